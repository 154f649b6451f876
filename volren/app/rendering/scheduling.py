"""When to render, and at what cost: state changes -> frame requests.

Interactive changes (a drag in progress) get an immediate preview frame with at most a quarter of
the pixels (half of each side, scaled up for display; fewer when the renderer is slow, so that a
preview stays within about 80 ms) and cheaper settings (`preview_settings`: the `interactive`
quality level, and cheap TF tables while a TF is dragged), and restart a short settle timer; when no
input has come for `settle_ms` (a gesture resting before its release), or at once when the
gesture ends, one full-quality frame follows, and none again for the same request. Every other change (a new volume,
another renderer, a reset view) asks for a full-quality frame at once. A full-quality frame
measured slower than REFINE_AFTER_MS comes after a coarse frame of the whole view at the preview
settings (progressive refinement: something sharp at once, the exact frame when it is ready).

This is the only place that builds requests, so other panels (TF editors) get the same policy
just by changing the `ViewState` inside `state.begin_interaction()` / `end_interaction()`.
"""

from __future__ import annotations

from collections.abc import Callable

from PyQt5.QtCore import QObject, QTimer

from volren.app.core.frame_sizes import FrameCost, adaptive_preview_scale, preview_size
from volren.app.core.preview_settings import preview_choice, still_settings
from volren.app.core.state import Change, ViewState
from volren.app.rendering.render_service import Frame, RenderRequest, RenderService, tf_key
from volren.model.clip_region import NO_CLIP
from volren.model.scene_class import SceneClass
from volren.model.settings import RenderSettings
from volren.renderers.base import Capabilities
from volren.renderers.registry import RendererRegistry

#: Input quiet for this long means the gesture stopped: render at full quality.
SETTLE_MS = 150
#: Largest side scale of preview frames (0.5: a quarter of the pixels).
PREVIEW_SCALE = 0.5
#: A still frame measured slower than this (ms) comes after a coarse frame of the whole view at the
#: preview settings (progressive refinement), when that costs at most half as much.
REFINE_AFTER_MS = 400.0
#: ... and when the coarse frame itself comes soon: the screen already shows the gesture's last
#: preview, so a coarse frame of seconds only delays the still frame (a 2D TF on bonsai: 8 s of
#: coarse frame before a 14 s still frame, release to full frame 19.5 s).
COARSE_MAX_MS = 250.0
#: What a preview frame may cost; slower renderers get coarser previews. 80 ms (12.5 fps, above the
#: 10 fps a drag needs): at 50 ms objectorder's bonsai previews were 3 % of the pixels at 17 fps.
PREVIEW_BUDGET_MS = 80.0


class FrameScheduler(QObject):
    """Subscribes to a `ViewState` and submits frames to a `RenderService`."""

    def __init__(
        self,
        state: ViewState,
        service: RenderService,
        viewport_size: Callable[[], tuple[int, int]],
        parent: QObject | None = None,
        settle_ms: int = SETTLE_MS,
        preview_scale: float = PREVIEW_SCALE,
        registry: RendererRegistry | None = None,
    ) -> None:
        super().__init__(parent)
        self._state = state
        self._service = service
        self._viewport_size = viewport_size
        self._registry = registry  # the renderers previews may use (None: the state's only)
        self._failed_previewers: set[str] = set()  # renderers whose previews raised: not asked again
        service.renderFailed.connect(self._on_failed)
        self.preview_scale = preview_scale
        self.preview_budget_ms = PREVIEW_BUDGET_MS
        # per renderer, settings (repr: options are a dict) and whether the frame had a new TF
        self._costs: dict[tuple[str, str, int, bool], FrameCost] = {}
        self._tf_dragged = False  # the gesture in progress drags the TF
        self._preview: tuple[tuple, tuple[str, RenderSettings]] | None = None  # (inputs, preview) last made
        self._warmed: tuple[str, int] | None = None  # (renderer, id(volume)) last warmed up for previews
        self._cost_keys: tuple[RenderSettings | None, str] | None = None  # (settings, its repr) last asked
        self._tf_dims = 1  # of the TF last seen: a change of dimension may change renderer or settings
        self._labels_drawn = False  # labels opened or closed: the renderer control may change renderer first
        self._pending_final: tuple[int, tuple] | None = (
            None  # (coarse frame's serial, the still frame's request)
        )
        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.setInterval(settle_ms)
        self._timer.timeout.connect(self.request_full)
        #: a full frame asked for once the state's other listeners have run (`_on_change`)
        self._after_listeners = QTimer(self)
        self._after_listeners.setSingleShot(True)
        self._after_listeners.setInterval(0)
        self._after_listeners.timeout.connect(self.request_full)
        self._requested_any = False
        self._last_full: tuple | None = (
            None  # what the newest full frame asked for, while nothing else was asked
        )
        self._unsubscribe = state.subscribe(self._on_change)

    def _on_change(self, change: Change) -> None:
        tf = self._state.transfer_function
        dims = tf.dims if tf is not None else self._tf_dims
        labels = self._state.labels_drawn or self._state.channels_drawn
        if (dims != self._tf_dims or labels != self._labels_drawn) and not change.interactive:
            # a 1D TF turned 2D (or back), or labels came or went: the renderer control may move to
            # another renderer (one that draws labels) or drop pre-integration in the listeners after
            # this one; a frame asked for now would go to a renderer that refuses it (an error box for
            # a state that lasts microseconds)
            self._tf_dims, self._labels_drawn = dims, labels
            self._timer.stop()
            self._after_listeners.start()
            return
        if change.what == "interaction":  # a gesture ended (a release): full quality at once
            self._tf_dragged = False
            self.request_full()
        elif change.interactive:
            self._tf_dragged = change.what == "tf"
            self.request_preview()
            self._timer.start()
        else:
            self._timer.stop()
            self.request_full()

    def viewport_resized(self) -> None:
        """A resize is like a gesture: preview now, full quality when the resizing stops."""
        if not self._requested_any:
            self.request_full()
            return
        self.request_preview()
        self._timer.start()

    def note_frame(self, frame: Frame) -> None:
        """Remember what the renderer's frames cost, to size the next previews (not a frame that
        paid a set-up: a preview renderer's first frame of bonsai took 0.7 s, ten times the next,
        and kept the previews at a tenth of the pixels)."""
        if not frame.setup:
            key = (*self._cost_key(frame.renderer, frame.settings), frame.tf_changed)
            self._costs.setdefault(key, FrameCost()).note(frame.width * frame.height, frame.ms)
        self._refine(frame)
        if frame.full and frame.serial == self._service.latest_serial:
            self._warm_previewer()

    def _warm_previewer(self) -> None:
        """The view is still: set the previews' renderer up now, if it is another than the still
        frames' and has not seen this volume, so that the next gesture's first preview comes at
        once instead of after its set-up (shearwarp's first bonsai preview took 0.7 s)."""
        s = self._state
        renderer, settings = self.preview(tf_dragged=False)
        volume, settings = s.frame_inputs(renderer, settings)
        tf = s.drawn_transfer_function
        if volume is None or tf is None:
            return
        key = (renderer, id(volume))
        if renderer != s.renderer and key != self._warmed:
            self._warmed = key
            self._service.warm(renderer, volume, tf, settings)

    def preview(self, tf_dragged: bool | None = None) -> tuple[str, RenderSettings]:
        """(renderer, settings) the next preview draws with (`preview_choice`); kept while the
        inputs stay the same objects, since a drag asks for it at the mouse's rate."""
        s = self._state
        kind = SceneClass.of(s.volume, s.transfer_function) if s.volume is not None else SceneClass("uniform")
        dims = s.transfer_function.dims if s.transfer_function is not None else 1
        dragged = self._tf_dragged if tf_dragged is None else tf_dragged
        names = [n for n in self._registry.names() if n not in self._failed_previewers] \
            if self._registry is not None else [s.renderer]  # fmt: skip
        refused = self._refusing_the_view(names)
        # the kind (with the TF's class) and the renderers refusing this view compared by value
        inputs = (s.renderer, kind, s.settings, dragged, dims, refused, s.crop is not None, s.labels_drawn,
                  s.channels_drawn)  # fmt: skip
        if self._preview is None or any(
            a is not b and not (isinstance(a, str | frozenset | bool) and a == b)
            for a, b in zip(self._preview[0], inputs, strict=True)
        ):
            usable = [n for n in names if n not in refused or n == s.renderer]
            if s.crop is not None and s.clips():  # previews clip too: a crop drag prepares nothing again
                usable = [n for n in usable if s.clips(n)]
            if s.labels_drawn:  # previews by label too (RTVG chapter 16), not of the unlabelled volume
                usable = [n for n in usable if n == s.renderer or self._draws_labels(n)]
            if s.channels_drawn:  # previews mix the channels too
                usable = [n for n in usable if n == s.renderer or self._draws_labels(n, "channels")]
            self._preview = (
                inputs,
                preview_choice(s.renderer, kind, dims, s.settings, usable, self._capabilities, dragged),
            )
        return self._preview[1]

    def _refusing_the_view(self, names: list[str]) -> frozenset[str]:
        """The renderers among `names` that cannot draw the current view (an eye inside the volume,
        a clipping plane through it: `Capabilities.camera_reason`); they preview again once the
        camera is back where they can."""
        s = self._state
        volume, camera = s.volume, s.camera  # what a clipping renderer is given
        if volume is None or camera is None:
            return frozenset()
        refused = set()
        for name in names:
            caps = self._capabilities(name)
            if caps is not None and caps.camera_reason(volume.kind, camera, volume.bounds) is not None:
                refused.add(name)
        return frozenset(refused)

    def _on_failed(self, request: RenderRequest, _message: str) -> None:
        """A preview renderer that raised previews no more, unless it only refused the view (the
        still frames' renderer's own failures are the renderer control's to report)."""
        if request.renderer == self._state.renderer:
            return
        caps = self._capabilities(request.renderer)
        if (
            caps is None
            or caps.camera_reason(request.volume.kind, request.camera, request.volume.bounds) is None
        ):
            self._failed_previewers.add(request.renderer)
        self._preview = None  # chosen again, without it
        self._last_full = None
        self.request_full()

    def _draws_labels(self, name: str, what: str = "labels") -> bool:
        """Whether renderer `name` draws the shown volume's labels (`KindSupport.labels`; `what`
        "channels": mixes its channels, `KindSupport.channels`)."""
        caps, volume = self._capabilities(name), self._state.volume
        support = caps.kinds.get(volume.kind) if caps is not None and volume is not None else None  # type: ignore[call-overload]
        return bool(support is not None and getattr(support, what))

    def _capabilities(self, name: str) -> Capabilities | None:
        if self._registry is None:
            return None
        try:
            return self._registry.capabilities(name)
        except Exception:  # noqa: BLE001 - a plugin that does not import draws no previews
            return None

    def _cost_key(self, renderer: str, settings: RenderSettings | None) -> tuple[str, str, int]:
        """Frame costs are kept per renderer, settings (by repr: options are a dict) and TF
        dimension, whatever is clipped (a clip plane's drag must not start the cost model again at every step)."""
        if self._cost_keys is None or self._cost_keys[0] is not settings:
            unclipped = settings.with_(clip=NO_CLIP) if settings is not None else None
            self._cost_keys = (settings, repr(unclipped))
        tf = self._state.transfer_function  # a 2D TF's frames read gradients: 2-7x dearer than a 1D TF's
        return renderer, self._cost_keys[1], tf.dims if tf is not None else 1

    def _cost(self, frame: tuple[str, RenderSettings], tf_changed: bool) -> FrameCost | None:
        """What frames of (renderer, settings) cost, with a new TF each or not, as the frame asked
        for will (those of the other kind until it has some). Why apart: a frame with a new TF also
        pays for what the renderer keeps per TF (raycast's step choice, 0.1 s on bonsai), and
        rotation previews sized from the TF edits' frames were 17 % of the pixels at 18 fps."""
        key = self._cost_key(*frame)
        found = self._costs.get((*key, tf_changed)) or self._costs.get((*key, not tf_changed))
        return found or self._cost_at_other_settings(key)

    def _cost_at_other_settings(self, key: tuple[str, str, int]) -> FrameCost | None:
        """The renderer's frames at other settings of the same TF dimension: its still frames, when
        it draws previews too and has drawn none yet at their settings. Why: a still frame costs at
        least what a preview does per pixel, so the first previews fit the budget (raycast's first 2D
        previews, sized at a quarter of the pixels for want of a cost, took 2-3 s each on bonsai)."""
        renderer, _, dims = key
        return next(
            (cost for (name, _, d, _), cost in self._costs.items() if name == renderer and d == dims), None
        )

    def current_preview_scale(self, preview: tuple[str, RenderSettings] | None = None) -> float:
        """The side scale of the next preview, from what frames of its renderer and settings cost
        (during a TF drag, frames with a new TF each)."""
        width, height = self._viewport_size()
        cost = self._cost(preview or self.preview(), self._tf_dragged)
        model = cost.model() if cost is not None else None
        if model is None:
            return self.preview_scale
        fixed, per_pixel = model
        return adaptive_preview_scale(per_pixel, width * height, self.preview_budget_ms, self.preview_scale,
                                      fixed_ms=fixed)  # fmt: skip

    def request_preview(self) -> int | None:
        return self._request(full=False)

    def request_full(self) -> int | None:
        self._timer.stop()
        return self._request(full=True)

    def _request(self, full: bool) -> int | None:
        s = self._state
        width, height = self._viewport_size()
        if s.volume is None or s.transfer_function is None or s.camera is None or width < 1 or height < 1:
            return None
        tf = s.drawn_transfer_function
        assert tf is not None
        renderer, settings = s.renderer, s.settings
        if full:
            settings = still_settings(settings, self._capabilities(renderer))
            # a gesture that rested before it ended asks twice for the same full frame: once when input
            # went quiet, again on release; the second would redraw what is already on screen
            key = (
                s.renderer,
                id(s.volume),
                s.crop,
                tf_key(tf),
                s.settings,
                s.camera,
                width,
                height,
                s.background,
            )
            if key == self._last_full:
                return None  # and a refinement under way for it still ends in its still frame
            self._last_full = key
        else:
            self._last_full = None  # a preview replaces what is on screen: the next full frame is needed
            preview = renderer, settings = self.preview()
            width, height = preview_size(width, height, self.current_preview_scale(preview))
        self._requested_any = True
        self._pending_final = None  # this request replaces a refinement under way
        volume, settings = s.frame_inputs(renderer, settings)
        assert volume is not None
        request = (
            renderer,
            volume,
            tf,
            settings,
            s.camera,
            width,
            height,
            full,
            s.background,
        )
        if full:
            coarse = self.preview(tf_dragged=False)
            if coarse != (renderer, settings) and self._worth_refining(
                width * height, (renderer, settings), coarse
            ):
                # progressive refinement: the whole view at the preview's renderer and settings first
                coarse_volume, coarse_settings = s.frame_inputs(*coarse)
                serial = self._service.submit(
                    coarse[0], coarse_volume, tf, coarse_settings, *request[4:7], False, s.background
                )
                self._pending_final = (serial, request)
                return serial
        return self._service.submit(*request)

    def _worth_refining(self, pixels: int, still_frame: tuple[str, RenderSettings],
                        coarse_frame: tuple[str, RenderSettings]) -> bool:  # fmt: skip
        """Whether a still frame is slow enough (REFINE_AFTER_MS, as measured for its settings) and
        the coarse one cheap enough (at most half of it, and at most COARSE_MAX_MS) to show the
        coarse one first."""
        still_ms = self._predicted_ms(still_frame, pixels)
        if still_ms is None:
            return False
        cheap_ms = self._predicted_ms(coarse_frame, pixels) or 0.0
        return still_ms > REFINE_AFTER_MS and cheap_ms <= min(0.5 * still_ms, COARSE_MAX_MS)

    def _predicted_ms(self, frame: tuple[str, RenderSettings], pixels: int) -> float | None:
        """What a frame of `pixels` by (renderer, settings) costs, from that pair's frames (None: none yet)."""
        cost = self._cost(frame, False)
        model = cost.model() if cost is not None else None
        return model[0] + model[1] * pixels if model is not None else None

    def _refine(self, frame: Frame) -> None:
        """The coarse frame of a refinement is shown: ask for the still frame it stands in for."""
        if self._pending_final is not None and frame.serial == self._pending_final[0]:
            request, self._pending_final = self._pending_final[1], None
            self._service.submit(*request)

    def detach(self) -> None:
        """Stop listening (the window is closing)."""
        self._timer.stop()
        self._after_listeners.stop()
        self._unsubscribe()
