"""`ViewState`: what the app shows, as a plain observable object (no Qt).

Widgets never own the volume, the transfer function or the camera; they read them from one
`ViewState` and change them through its setters. Every change is announced to the subscribers as
a `Change`, so the viewport, the renderer chooser, the frame scheduler and (later) the
transfer-function editors all stay in step without knowing about each other.

A volume with labels (a segmentation, Real-Time Volume Graphics chapter 16) is drawn with a TF per
label whose base is the state's 1D TF, the one the 1D editor edits (`drawn_transfer_function`); its
style edits are announced as TF changes. A label selected for editing (`edit_label`) has the 1D
editor edit its own TF (`transfer_function` is then that TF; `base_transfer_function` stays the
base); an unstyled label gets its own TF, a copy of the base, on its first edit.

A volume with channels (Max 1995, section 2: several media whose extinctions and emissions add) is
drawn with a `ChannelTransferFunction`; `transfer_function` is then the selected channel's 1D TF
(`select_channel`), edited in place by the 1D editor like any 1D TF.

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
from volren.model.channels import ChannelSet, ChannelTransferFunction
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
        self._quiet_channels = False
        self._channel_tf: ChannelTransferFunction | None = None  # while the volume has channels
        self._channel_unhook: Callable[[], None] | None = None
        self._channel = 0  # the channel whose TF `transfer_function` is
        self._edit_label: int | None = None  # the label whose TF the 1D editor edits (None: the base)
        #: the edited label's own TF, or a copy of the base until its first edit
        self._label_edit_tf: TransferFunction1D | None = None
        self._label_edit_unhook: Callable[[], None] | None = None
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
        """The TF the editors edit: the selected label's own TF (`edit_label`) where labels are
        drawn, else the volume's TF (with channels, the selected channel's: `select_channel`)."""
        if self._label_edit_tf is not None and self.labels_drawn:
            return self._label_edit_tf
        return self._tf

    @property
    def base_transfer_function(self) -> TransferFunction | None:
        """The volume's TF: the base of the TF per label, whichever label's TF is edited."""
        return self._tf

    @property
    def edited_label(self) -> int | None:
        """The label whose own TF the 1D editor edits (None: the base TF)."""
        return self._edit_label if self._label_tf is not None else None

    @property
    def channels(self) -> ChannelSet | None:
        """The shown volume's channels (several fields on its grid), or None."""
        return getattr(self._volume, "channels", None)

    @property
    def channel_transfer_function(self) -> ChannelTransferFunction | None:
        """The TF per channel (a 1D TF, weight and visibility each) while the volume has channels."""
        return self._channel_tf if self.channels is not None else None

    @property
    def selected_channel(self) -> int:
        """The channel whose TF `transfer_function` is (with channels)."""
        return self._channel

    @property
    def channels_drawn(self) -> bool:
        """Whether frames mix the channels: the volume has channels and the TF is 1D."""
        return self.channel_transfer_function is not None and self._tf is not None and self._tf.dims == 1

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
    def drawn_transfer_function(
        self,
    ) -> TransferFunction | LabelTransferFunction | ChannelTransferFunction | None:
        """What frames are drawn with: the TF per label where labels are drawn, the TF per channel
        where channels are, else the TF."""
        if self.labels_drawn:
            return self._label_tf
        if self.channels_drawn:
            return self._channel_tf
        return self._tf

    def label_settings(self, renderer: str, settings: RenderSettings) -> RenderSettings:
        """`settings` as `renderer` draws this view with them: pre-integration off where labels are
        drawn and the renderer does not pre-integrate them (`volren.quality.label_settings`: a
        pre-integration table is made for one TF, RTVG section 4.5); likewise where channels are
        mixed (`volren.quality.channel_settings`)."""
        labels, channels = self.labels_drawn, self.channels_drawn
        if not (labels or channels) or self._volume is None or not settings.preintegration:
            return settings
        from volren.quality import channel_settings, label_settings
        from volren.renderers.registry import registry

        try:
            capabilities = registry.capabilities(renderer)
        except Exception:  # noqa: BLE001 - a renderer that does not import is refused where it is used
            return settings
        adjust = label_settings if labels else channel_settings
        return adjust(capabilities, self._volume.kind, settings)

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
        self._edit_label = None
        tf = self._hook_channels(volume, tf)
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
        channels = getattr(volume, "channels", None)
        if channels is None or self._channel_tf is None or self._channel_tf.count != channels.count:
            tf = self._hook_channels(volume, self._channel_tf)  # else the same channels' TFs go on
            if channels is not None and (self._tf is None or self._tf.dims == 1):
                self._hook_tf(tf)
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
        if self._label_edit_tf is not None and self.labels_drawn and isinstance(tf, TransferFunction1D):
            self._set_own_label_tf(tf)  # the edited label's TF replaced (a preset, a file)
            return
        self.set_base_transfer_function(tf)

    def set_base_transfer_function(self, tf: TransferFunction) -> None:
        """Use another TF object as the volume's TF (the base of the labels' TFs; with channels, the
        selected channel's TF), whichever label's TF is edited: what undo puts back."""
        if self._tf is not None and self._tf is not tf:
            self._replaced[self._tf.dims] = self._tf
        self._hook_tf(tf)
        if self._label_tf is not None and isinstance(tf, TransferFunction1D):
            self._quiet_labels = True  # announced once, below
            try:
                self._label_tf.set_base(tf)
            finally:
                self._quiet_labels = False
            self._bind_label_edit()  # an unstyled label's copy was of the old base
        if self._channel_tf is not None and isinstance(tf, TransferFunction1D):
            self._quiet_channels = True
            try:
                self._channel_tf.set_tf(self._channel, tf)
            finally:
                self._quiet_channels = False
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
        if self._edit_label not in labels.present:
            self._edit_label = None
        self._bind_label_edit()

    # ------------------------------------------------------------------ a label's own TF
    def edit_label(self, label: int | None) -> None:
        """Have the 1D editor edit `label`'s own TF (None: the base TF): the label's own TF where it
        has one, else a copy of the base that becomes its own on the first edit (RTVG chapter 16: a
        TF per object). Nothing happens without labels."""
        labels = self.labels
        if self._label_tf is None or labels is None or label not in labels.present:
            label = None
        if label == self._edit_label:
            return
        self._edit_label = label
        self._bind_label_edit()
        self._emit("tf")

    def _bind_label_edit(self) -> None:
        """Follow the edited label's TF: its own, or a fresh copy of the base."""
        if self._label_edit_unhook is not None:
            self._label_edit_unhook()
            self._label_edit_unhook = None
        self._label_edit_tf = None
        label, label_tf = self._edit_label, self._label_tf
        if label is None or label_tf is None:
            self._edit_label = None
            return
        tf = label_tf.style(label).tf or label_tf.base.copy()
        self._label_edit_tf = tf
        self._label_edit_unhook = tf.on_change(self._label_tf_edited)

    def _label_tf_edited(self, tf: object) -> None:
        """An edit of the edited label's TF in place: the first one makes it the label's own."""
        label_tf, label = self._label_tf, self._edit_label
        if label_tf is None or label is None or not isinstance(tf, TransferFunction1D):
            return
        style = label_tf.style(label)
        if style.tf is not tf:
            label_tf.set_style(label, replace(style, tf=tf))  # announced by its hook
        else:
            self._emit("tf")  # the label TF's `state` follows its own TFs' versions

    def _set_own_label_tf(self, tf: TransferFunction1D) -> None:
        label_tf, label = self._label_tf, self._edit_label
        assert label_tf is not None and label is not None
        self._quiet_labels = True  # announced once, below, with the editor's TF already the new one
        try:
            label_tf.set_style(label, replace(label_tf.style(label), tf=tf))
        finally:
            self._quiet_labels = False
        self._bind_label_edit()
        self._emit("tf")

    # ------------------------------------------------------------------ channels
    def _hook_channels(self, volume: Volume, tf: object) -> TransferFunction:
        """Draw `volume`'s channels (if any) with `tf` when it is a TF per channel for them, else
        with their default look (`channel_io.default_channel_tf`); returns the TF the 1D editor
        edits: the first shown channel's (or `tf` itself without channels)."""
        if self._channel_unhook is not None:
            self._channel_unhook()
            self._channel_unhook = None
        self._channel_tf = None
        channels = getattr(volume, "channels", None)
        if channels is None:
            if isinstance(tf, ChannelTransferFunction):
                return tf.tfs[0]
            return tf  # type: ignore[return-value]
        from volren.io.channel_io import default_channel_tf

        if not isinstance(tf, ChannelTransferFunction) or tf.count != channels.count:
            tf = default_channel_tf(channels)
        self._channel_tf = tf
        self._channel = next((c for c, shown in enumerate(tf.visible) if shown), 0)
        self._channel_unhook = tf.on_change(self._channels_edited)
        return tf.tfs[self._channel]

    def _channels_edited(self, ctf: object) -> None:
        """A weight, a visibility or a channel's TF changed; a replaced TF of the selected channel is
        the one the editor edits from now on."""
        assert isinstance(ctf, ChannelTransferFunction)
        if self._tf is not None and self._tf.dims == 1 and ctf.tfs[self._channel] is not self._tf:
            self._hook_tf(ctf.tfs[self._channel])
        if not self._quiet_channels:
            self._emit("tf")

    def select_channel(self, channel: int) -> None:
        """Have the 1D editor edit channel `channel`'s TF (its histogram shown)."""
        ctf = self.channel_transfer_function
        if ctf is None:
            return
        if not 0 <= channel < ctf.count:
            raise VolrenError(f"channel {channel} is not one of 0..{ctf.count - 1}")
        if channel == self._channel:
            return
        self._channel = channel
        if self._tf is None or self._tf.dims == 1:
            self._hook_tf(ctf.tfs[channel])
        self._emit("tf")

    def set_channel_transfer_function(self, ctf: ChannelTransferFunction) -> None:
        """Draw the channels with `ctf` (what undo puts back); the selected channel stays selected."""
        channels = self.channels
        if channels is None or self._volume is None:
            return
        if ctf.count != channels.count:
            raise VolrenError(f"the transfer function has {ctf.count} channels, the volume {channels.count}")
        if (
            self.channels_drawn
            and self._channel_tf is not None
            and ctf.to_dict() == self._channel_tf.to_dict()
        ):
            return
        channel = self._channel
        self._hook_channels(self._volume, ctf)
        self._channel = min(channel, ctf.count - 1)
        if self._tf is not None and self._tf.dims != 1:  # back from a 2D TF: it is remembered
            self._replaced[self._tf.dims] = self._tf
        self._hook_tf(ctf.tfs[self._channel])
        self._emit("tf")

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
            if volume.channels is not None:
                raise VolrenError(
                    f"{volume.name}: a volume is drawn with labels or with channels, not both at once yet"
                )
        volume = replace(volume, labels=labels)
        self._edit_label = None
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
