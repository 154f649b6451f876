"""`ViewState`: what the app shows, as a plain observable object (no Qt).

Widgets never own the volume, the transfer function or the camera; they read them from one
`ViewState` and change them through its setters. Every change is announced to the subscribers as
a `Change`, so the viewport, the renderer chooser, the frame scheduler and (later) the
transfer-function editors all stay in step without knowing about each other.

A volume with labels (a segmentation, Real-Time Volume Graphics chapter 16) is drawn with a TF per
label whose base is the state's 1D TF, the one the 1D editor edits (`drawn_transfer_function`); its
style edits are announced as TF changes.

Changes made while an interaction is in progress (a mouse drag in the viewport, later a drag in a
TF editor) are flagged `interactive`: the frame scheduler answers them with cheap preview frames
and renders one full-quality frame once the input stops.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, replace
from typing import Literal

from volren.app.core.crop_handles import shown_box
from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.crop import Box, check_box, covers, crop_volume
from volren.model.labels import LabelMap, LabelStyle, LabelTransferFunction
from volren.model.settings import RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TransferFunction
from volren.model.volume import UniformVolume, Volume

#: The parts of the state a `Change` can name.
What = Literal["volume", "tf", "camera", "settings", "renderer", "background", "crop", "interaction"]

#: The scene camera convention (DESIGN.md): azimuth 30, elevation 20, zoom 1 after the reset.
DEFAULT_VIEW = (30.0, 20.0, 1.0)
#: Dark grey: volumes fading to transparent stay distinguishable from the window background.
DEFAULT_BACKGROUND = (0.1, 0.1, 0.12)


@dataclass(frozen=True)
class Change:
    """One announcement: which part changed, and whether it came from an ongoing interaction.

    `what == "interaction"` with `interactive == False` says an interaction just ended;
    `what == "volume"` with `same_scene` says another time step of the same data came (TF,
    camera, settings, renderer and crop kept): the data changed, the user's work did not.
    """

    what: What
    interactive: bool = False
    same_scene: bool = False


Listener = Callable[[Change], None]


def default_camera(volume: Volume, aspect: float = 1.0, parallel: bool = False) -> Camera:
    """The camera the scenes use (Camera.orbit with 30/20/1), fitted to the viewport's aspect."""
    azimuth, elevation, zoom = DEFAULT_VIEW
    return Camera.orbit(volume.bounds, azimuth, elevation, zoom, parallel, aspect)


def renderer_clips(renderer: str, kind: str) -> bool:
    """Whether the registered `renderer` clips volumes of `kind` to planes and a box
    (`KindSupport.clip_region`); False for one that does not import."""
    from volren.renderers.registry import registry

    try:
        support = registry.capabilities(renderer).kinds.get(kind)  # type: ignore[call-overload]
    except Exception:  # noqa: BLE001 - a plugin that does not import clips nothing
        return False
    return bool(support is not None and support.clip_region)


class ViewState:
    """Volume, transfer function (1D or 2D), camera, settings, renderer name, background and crop
    box of one view."""

    def __init__(self, renderer: str = "vtk", settings: RenderSettings | None = None) -> None:
        self._volume: Volume | None = None
        self._tf: TransferFunction | None = None
        self._crop: Box | None = None
        self._cropped: tuple[Volume, Box, Volume] | None = None
        self._camera: Camera | None = None
        self._settings = settings or RenderSettings()
        self._renderer = renderer
        self._background: tuple[float, float, float] = DEFAULT_BACKGROUND
        self._listeners: list[Listener] = []
        self._tf_unhook: Callable[[], None] | None = None
        self._label_tf: LabelTransferFunction | None = None  # over the 1D TF, while the volume has labels
        self._label_unhook: Callable[[], None] | None = None
        self._quiet_labels = False
        self._replaced: dict[int, TransferFunction] = {}  # by dimension: the last TF replaced by another
        self._interaction_depth = 0
        #: What is loaded, for titles and messages (a file name or "sample ...").
        self.source = ""
        #: The file the volume's labels came from (for a scene saved later); None: none, or made in memory.
        self.labels_path: str | None = None
        #: The quality level the person chose (or the app opened at), None for custom settings:
        #: kept beside the settings because several levels can have equal settings, and the one
        #: chosen is the one to show and to carry to another renderer (`volren.quality.level_of`).
        self.quality_level: str | None = None

    # ------------------------------------------------------------------ observation
    def subscribe(self, listener: Listener) -> Callable[[], None]:
        """Call `listener(change)` after every change; returns a function that unsubscribes."""
        listeners = self._listeners
        listeners.append(listener)

        def unsubscribe() -> None:
            # Holds the list, not the state: widgets unsubscribe from Qt's `destroyed`, which can
            # come after Python has torn the state down (at exit).
            if listener in listeners:
                listeners.remove(listener)

        return unsubscribe

    def _emit(self, what: What, interactive: bool | None = None, same_scene: bool = False) -> None:
        change = Change(what, self.interacting if interactive is None else interactive, same_scene)
        for listener in list(self._listeners):
            listener(change)

    # ------------------------------------------------------------------ interaction
    @property
    def interacting(self) -> bool:
        return self._interaction_depth > 0

    def begin_interaction(self) -> None:
        """Changes from now until `end_interaction` are previews of a gesture in progress."""
        self._interaction_depth += 1

    def end_interaction(self) -> None:
        if self._interaction_depth == 0:
            return
        self._interaction_depth -= 1
        if self._interaction_depth == 0:
            self._emit("interaction", interactive=False)

    @contextmanager
    def interaction(self) -> Iterator[None]:
        """A one-shot interactive change (a wheel step): preview now, full quality once input stops."""
        self._interaction_depth += 1
        try:
            yield
        finally:
            self._interaction_depth -= 1

    # ------------------------------------------------------------------ properties
    @property
    def volume(self) -> Volume | None:
        return self._volume

    @property
    def transfer_function(self) -> TransferFunction | None:
        return self._tf

    @property
    def labels(self) -> LabelMap | None:
        """The shown volume's label map (a segmentation on its grid), or None."""
        return getattr(self._volume, "labels", None)

    @property
    def label_transfer_function(self) -> LabelTransferFunction | None:
        """The TF per label (RTVG chapter 16) whose `base` is the state's 1D TF, while the volume has
        labels; None without labels."""
        return self._label_tf if self.labels is not None else None

    @property
    def labels_drawn(self) -> bool:
        """Whether frames are drawn by label: labels are shown and the TF is 1D (a label
        classifies the value with a 1D TF per label; with a 2D TF the labels are not drawn)."""
        return self.label_transfer_function is not None and self._tf is not None and self._tf.dims == 1

    @property
    def drawn_transfer_function(self) -> TransferFunction | LabelTransferFunction | None:
        """What frames are drawn with: the TF per label where labels are drawn, else the TF."""
        return self._label_tf if self.labels_drawn else self._tf

    def label_settings(self, renderer: str, settings: RenderSettings) -> RenderSettings:
        """`settings` as `renderer` draws this view with them: pre-integration off where labels are
        drawn and the renderer does not pre-integrate them (`volren.quality.label_settings`: a
        pre-integration table is made for one TF, RTVG section 4.5)."""
        if not self.labels_drawn or self._volume is None or not settings.preintegration:
            return settings
        from volren.quality import label_settings
        from volren.renderers.registry import registry

        try:
            capabilities = registry.capabilities(renderer)
        except Exception:  # noqa: BLE001 - a renderer that does not import is refused where it is used
            return settings
        return label_settings(capabilities, self._volume.kind, settings)

    @property
    def crop(self) -> Box | None:
        """The axis-aligned crop box in world units (xmin, xmax, ...), or None: no cropping."""
        return self._crop

    @property
    def render_volume(self) -> Volume | None:
        """The volume cut to the crop box (made once per box, a copy of its samples): what is shown,
        for picking and for the bounds of a renderer that does not clip (`shown_bounds`), and what
        such a renderer draws (`frame_inputs`). The Dataset panel counts a grid's cut without it.
        The cut keeps the labels' cut with it."""
        volume, box = self._volume, self._crop
        if volume is None or box is None:
            return volume
        if self._cropped is not None and self._cropped[0] is volume and self._cropped[1] == box:
            return self._cropped[2]
        cropped = crop_volume(volume, box)  # the labels and channels cut with the values
        self._cropped = (volume, box, cropped)
        return cropped

    @property
    def shown_bounds(self) -> Box | None:
        """The bounds of what is drawn (None: nothing is): the crop box cut to the volume's bounds
        where the renderer clips, else the bounds of the cut volume (`render_volume`)."""
        volume = self._volume
        if volume is None or self._crop is None:
            return None if volume is None else volume.bounds
        if self.clips():
            return shown_box(self._crop, volume.bounds)
        shown = self.render_volume
        assert shown is not None
        return shown.bounds

    def clips(self, renderer: str | None = None) -> bool:
        """Whether `renderer` (default: the state's) clips the shown volume's kind to planes and a
        box (`renderer_clips`)."""
        return self._volume is not None and renderer_clips(renderer or self._renderer, self._volume.kind)

    def with_crop(self, settings: RenderSettings) -> RenderSettings:
        """`settings` with the crop box as their clip box (the oblique planes kept)."""
        if self._crop is None or settings.clip.box == self._crop:
            return settings
        return settings.with_(clip=settings.clip.with_box(self._crop))

    def frame_inputs(self, renderer: str, settings: RenderSettings) -> tuple[Volume | None, RenderSettings]:
        """(volume, settings) that `renderer` draws this view with, from `settings` (its still or
        preview settings): a renderer that clips gets the whole volume and the crop box as a clip
        box, so a moved face changes two numbers per ray and nothing it prepared (Real-Time Volume
        Graphics, section 15.1); another gets the volume cut to the box (`render_volume`). With
        labels drawn, the settings are those `label_settings` gives."""
        settings = self.label_settings(renderer, settings)
        if self._crop is None:
            return self._volume, settings
        if self.clips(renderer):
            return self._volume, self.with_crop(settings)
        return self.render_volume, settings

    @property
    def camera(self) -> Camera | None:
        return self._camera

    @property
    def settings(self) -> RenderSettings:
        return self._settings

    @property
    def renderer(self) -> str:
        return self._renderer

    @property
    def background(self) -> tuple[float, float, float]:
        return self._background

    # ------------------------------------------------------------------ setters
    def load(
        self,
        volume: Volume,
        tf: TransferFunction,
        camera: Camera,
        settings: RenderSettings | None = None,
        source: str = "",
        renderer: str | None = None,
        crop: Box | None = None,
        background: tuple[float, float, float] | None = None,
        label_tf: LabelTransferFunction | None = None,
        labels_path: str | None = None,
    ) -> None:
        """Replace the whole scene at once (one "volume" change, so one new frame).

        A volume with labels (read from `labels_path`) is drawn with `label_tf` (a scene's), its
        base replaced by `tf`, or else with `LabelTransferFunction.for_labels` over `tf`.

        The renderer, the crop box and the background change in the same step, so no frame is
        drawn of a mix of old and new (the new volume uncropped, then cropped). The old crop box
        is cleared: it belongs to the old volume's bounds. A `crop` that leaves nothing to draw
        raises a VolrenError before anything changes.
        """
        cropped = None
        if crop is not None:
            crop = check_box(crop)
            if covers(crop, volume.bounds):
                crop = None
            elif not renderer_clips(renderer or self._renderer, volume.kind):
                cropped = (volume, crop, crop_volume(volume, crop))
        self._volume = volume
        self._crop = crop
        self._cropped = cropped
        if background is not None:
            self._background = (float(background[0]), float(background[1]), float(background[2]))
        self._replaced = {}  # the old volume's TFs do not fit the new one
        self._hook_tf(tf)
        self._hook_labels(volume, label_tf)
        self.labels_path = labels_path if self._label_tf is not None else None
        self._camera = camera
        if settings is not None:
            self._settings = settings
        if renderer is not None:
            self._renderer = renderer
        self.source = source
        self._emit("volume", interactive=False)

    def show_step(self, volume: Volume, source: str = "") -> None:
        """Another time step of the data shown: the volume is replaced and everything else (TF,
        camera, settings, renderer, the crop box where it still cuts the new volume) stays; so do
        the labels' styles where the step has labels too."""
        if getattr(volume, "labels", None) is None or self._label_tf is None:
            self._hook_labels(volume, None)  # else the same segmentation's styles go on
        self._volume = volume
        self._cropped = None
        if self._crop is not None and not self.clips():
            try:
                self._cropped = (volume, self._crop, crop_volume(volume, self._crop))
            except VolrenError:  # the step's bounds moved away from the box: show it whole
                self._crop = None
        if source:
            self.source = source
        self._emit("volume", interactive=False, same_scene=True)

    def set_transfer_function(self, tf: TransferFunction) -> None:
        """Use another TF object; in-place edits of the current one are announced as well. The
        one replaced is remembered by its dimension (`replaced_transfer_function`)."""
        if self._tf is not None and self._tf is not tf:
            self._replaced[self._tf.dims] = self._tf
        self._hook_tf(tf)
        if self._label_tf is not None and isinstance(tf, TransferFunction1D):
            self._quiet_labels = True  # announced once, below
            try:
                self._label_tf.set_base(tf)
            finally:
                self._quiet_labels = False
        self._emit("tf")

    def replaced_transfer_function(self, dims: int) -> TransferFunction | None:
        """The last TF of dimension `dims` that another replaced for this volume (switching 1D to
        2D and back returns to the user's TF instead of a default), or None."""
        return self._replaced.get(dims)

    def _hook_tf(self, tf: TransferFunction) -> None:
        if self._tf_unhook is not None:
            self._tf_unhook()
        self._tf = tf
        self._tf_unhook = tf.on_change(lambda _tf: self._emit("tf"))

    def _hook_labels(self, volume: Volume, label_tf: LabelTransferFunction | None) -> None:
        """Draw `volume`'s labels (if any) with `label_tf` over the 1D TF, or their default look
        (`for_labels`); every style edit is announced as a TF change."""
        if self._label_unhook is not None:
            self._label_unhook()
            self._label_unhook = None
        self._label_tf = None
        labels = getattr(volume, "labels", None)
        if labels is None:
            self.labels_path = None
            return
        base = self._tf if isinstance(self._tf, TransferFunction1D) else None
        if label_tf is None:
            label_tf = LabelTransferFunction.for_labels(base or _grey(volume), labels)
        elif base is not None:
            label_tf = LabelTransferFunction(base, label_tf.styles, label_tf.default)
        self._label_tf = label_tf
        self._label_unhook = label_tf.on_change(lambda _tf: None if self._quiet_labels else self._emit("tf"))

    def set_labels(self, labels: LabelMap | None, label_tf: LabelTransferFunction | None = None,
                   path: str | None = None) -> None:  # fmt: skip
        """Show the volume with `labels` (a segmentation on its grid, read from `path`), drawn with
        `label_tf` or `LabelTransferFunction.for_labels` over the 1D TF; None removes them. The TF,
        camera, settings, renderer and crop stay (one "volume" change of the same scene)."""
        volume = self._volume
        if not isinstance(volume, UniformVolume):
            raise VolrenError("labels are for uniform grids: open a uniform volume first")
        if labels is not None:
            labels.check_grid(volume.values.shape, volume.name)
        volume = replace(volume, labels=labels)
        self._hook_labels(volume, label_tf)
        self.labels_path = path if labels is not None else None
        self._volume = volume
        self._cropped = None
        self._emit("volume", interactive=False, same_scene=True)

    def set_label_styles(self, styles: Mapping[int, LabelStyle], default: LabelStyle | None = None) -> None:
        """Draw the labels with exactly these styles (the others with `default`) over the 1D TF: what
        undo puts back. Nothing happens without labels."""
        if self._label_tf is None:
            return
        label_tf = LabelTransferFunction(self._label_tf.base, styles, default)
        if label_tf.to_dict() == self._label_tf.to_dict():
            return
        volume = self._volume
        assert volume is not None
        self._hook_labels(volume, label_tf)
        self._emit("tf")

    def set_camera(self, camera: Camera) -> None:
        self._camera = camera
        self._emit("camera")

    def set_settings(self, settings: RenderSettings) -> None:
        self._settings = settings
        self._emit("settings")

    def set_renderer(self, name: str, option_names: Collection[str] | None = None,
                     settings: RenderSettings | None = None) -> None:  # fmt: skip
        """Switch renderer; with `option_names` (the new renderer's options), renderer options it
        does not have are dropped first (a quality level's options belong to the renderer it was
        chosen for, and a renderer refuses options it does not know); with `settings`, those
        settings come with it in the same change (the same quality level for the new renderer)."""
        if name == self._renderer:
            return
        if settings is not None:
            self._settings = settings
        if option_names is not None and any(key not in option_names for key in self._settings.options):
            kept = {k: v for k, v in self._settings.options.items() if k in option_names}
            self._settings = self._settings.with_(options=kept)
        self._renderer = name
        self._emit("renderer", interactive=False)

    def set_crop(self, box: Box | None) -> None:
        """Crop to `box` (world units), or None for the whole volume; a box covering the whole
        volume is stored as None. A box that leaves nothing to draw raises a VolrenError."""
        if box is not None:
            box = check_box(box)
            if self._volume is not None:
                if covers(box, self._volume.bounds):
                    box = None
                elif not self.clips():  # cut now: errors surface here, not in the render thread
                    self._cropped = (self._volume, box, crop_volume(self._volume, box))
        if box == self._crop:
            return
        self._crop = box
        self._emit("crop")

    def set_background(self, rgb: tuple[float, float, float]) -> None:
        self._background = (float(rgb[0]), float(rgb[1]), float(rgb[2]))
        self._emit("background")

    def reset_camera(self, aspect: float = 1.0) -> None:
        """Back to the scene camera (30/20/1), keeping the projection type."""
        if self._volume is None:
            return
        parallel = self._camera.parallel if self._camera is not None else False
        self._camera = default_camera(self._volume, aspect, parallel)
        self._emit("camera", interactive=False)


def _grey(volume: Volume) -> TransferFunction1D:
    """A TF for labels shown while the TF is 2D (they are drawn once a 1D TF is back, over it)."""
    from volren.model.default_tf import default_transfer_function

    return default_transfer_function(volume)
