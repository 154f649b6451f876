"""The renderer in use: what the chooser offers, switching when the current one cannot draw, and
the status-bar label that says what it drew.

Why one place: the renderer has to stay usable through every change that can rule it out (a new
volume, a 2D TF in `vtk`, a setting, a render that fails), and each case says why in the same
words. A renderer that raises is reported in one line and the previous working renderer takes
over again; the same failure of the same scene is said once.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from PyQt5 import sip
from PyQt5.QtCore import QTimer
from PyQt5.QtWidgets import QLabel, QStatusBar, QWidget

from volren.app.core.renderer_choice import RendererOption, pick_renderer, renderer_options
from volren.app.core.state import Change, ViewState
from volren.app.rendering.render_service import Frame, RenderRequest
from volren.app.rendering.renderer_chooser import RendererChooser
from volren.app.rendering.viewport import Viewport
from volren.errors import VolrenError
from volren.model.scene_class import SceneClass
from volren.model.settings import RenderSettings
from volren.model.transfer_function_2d import TransferFunction
from volren.model.volume import Volume
from volren.quality import AUTO, DEFAULT_LEVEL, at_level, choose_renderer, level_of
from volren.renderers.registry import RendererRegistry

#: A set-up (new renderer or volume) longer than this without a frame is shown as "preparing".
PREPARING_AFTER_S = 0.3


def renderer_message(name: str, reason: str | None) -> str:
    """Why `name` cannot draw, as one phrase starting with "renderer"."""
    reason = reason or "is not registered"
    return reason if reason.startswith("renderer") else f"renderer {name} {reason}"


class RendererControl:
    """Owns the chooser and the frame label; keeps `state.renderer` one that can draw."""

    def __init__(
        self,
        state: ViewState,
        registry: RendererRegistry,
        viewport: Viewport,
        status_bar: QStatusBar,
        report_error: Callable[[str, str], None],
        parent: QWidget,
    ) -> None:
        self._state = state
        self._registry = registry
        self._viewport = viewport
        self._status_bar = status_bar
        self._report_error = report_error
        self._last_good_renderer: str | None = None
        self._failure_key: tuple[Any, ...] | None = None
        self._shown_tf_dims = 1
        self._preparing: tuple[int, str] | None = None  # (serial, renderer) set up with no frame yet
        #: The renderer follows `auto`'s measured choice for each volume shown (another file, a
        #: dropped one, a series, another array), until the person picks one in the chooser.
        self.auto = True
        self.chooser = RendererChooser(parent)
        self.chooser.rendererChosen.connect(self._picked)
        #: "vtk  |  800 x 600  |  12.3 ms", or how far a slow frame is.
        self.frame_label = QLabel("", parent)

    def _picked(self, name: str) -> None:
        """The person chose a renderer: it stays for later volumes wherever it can draw them."""
        self.auto = False
        self.switch(name)

    def switch(self, name: str) -> None:
        """Make `name` the renderer, dropping renderer options it does not have; settings at a
        quality level move to the same level for the new renderer (its own measured settings)."""
        try:
            option_names = self._registry.get(name).option_help
        except VolrenError:
            option_names = None
        state, settings = self._state, None
        if state.volume is not None:
            kind = SceneClass.of(state.volume, state.transfer_function)
            level = level_of(state.renderer, kind, state.settings, prefer=state.quality_level)
            settings = at_level(name, kind, level, state.settings)
        state.set_renderer(name, option_names, settings)

    # ------------------------------------------------------------------ options
    def options(self) -> list[RendererOption]:
        """Every registered renderer, with why it cannot draw what is shown (None: it can)."""
        return self._options()[0]

    def _options(self) -> tuple[list[RendererOption], list[str]]:
        volume, tf = self._state.volume, self._state.transfer_function
        dims = tf.dims if tf is not None else 1
        return renderer_options(volume.kind if volume else None, self._state.settings, self._registry, dims,
                                labels=self._state.labels_drawn, channels=self._state.channels_drawn)  # fmt: skip

    def refresh(self) -> None:
        """List the renderers again (after a change, or plugins registered later)."""
        options, notes = self._options()
        self.chooser.set_options(options, self._state.renderer)
        if notes:
            self._status_bar.showMessage("; ".join(notes), 15000)

    def choose_for(
        self,
        volume: Volume,
        tf: TransferFunction,
        settings: RenderSettings,
        wanted: str,
        requested: str | None,
    ) -> tuple[str, list[str]]:
        """The renderer for a volume about to be shown, and notes for the status bar.

        `requested` is an explicit request (the command line): if it cannot draw the volume that
        is an error; another `wanted` one (a scene's) that cannot is replaced quietly; "auto" is
        the fastest measured renderer that can (`volren.quality`). A new scene also clears the
        memory of the last failure, so it is reported again.
        """
        labels = getattr(volume, "labels", None) is not None and tf.dims == 1
        channels = getattr(volume, "channels", None) is not None and tf.dims == 1
        options, notes = renderer_options(volume.kind, settings, self._registry, tf.dims, labels=labels,
                                          channels=channels)  # fmt: skip
        self.auto = wanted == AUTO
        if wanted == AUTO:  # the fastest measured renderer that draws this (volren.quality)
            drawable = {o.name for o in options if o.reason is None}
            try:
                wanted, why = choose_renderer(SceneClass.of(volume, tf), DEFAULT_LEVEL, tf.dims, settings, list(drawable),
                                              can_draw=drawable.__contains__)  # fmt: skip
                notes.append(f"renderer {wanted}: {why} (auto)")
            except VolrenError as exc:
                self._report_error("Renderer unavailable", str(exc))
                return next(iter(sorted(drawable)), "vtk"), notes
        chosen = pick_renderer(options, wanted, self._measured(volume, tf, settings))
        if chosen != wanted:
            reason = next((o.reason for o in options if o.name == wanted), None)
            text = renderer_message(wanted, reason)
            text += f"; using {chosen}" if chosen else f"; no renderer can draw {volume.kind} volumes"
            if requested is not None or chosen is None:
                self._report_error("Renderer unavailable", text)
            else:
                notes.append(text)
        self._failure_key = None
        return chosen or wanted, notes

    @staticmethod
    def _measured(
        volume: Volume, tf: TransferFunction, settings: RenderSettings
    ) -> Callable[[list[str]], str | None]:
        """`auto`'s measured choice among the usable renderers for this scene (None: none measured)."""

        def fastest(usable: list[str]) -> str | None:
            try:
                return choose_renderer(SceneClass.of(volume, tf), DEFAULT_LEVEL, tf.dims, settings, usable,
                                       can_draw=set(usable).__contains__)[0]  # fmt: skip
            except VolrenError:
                return None

        return fastest

    # ------------------------------------------------------------------ state
    def on_state_change(self, change: Change) -> None:
        if change.what == "volume":
            self._tf_dims_changed()
            self.refresh()
            if change.same_scene:  # labels opened or closed (or a time step): the renderer may not draw them
                self._keep_a_usable_renderer()
        elif change.what == "settings" or (change.what == "tf" and self._tf_dims_changed()):
            self.refresh()
            self._keep_a_usable_renderer()
        elif change.what == "renderer":
            self.chooser.set_current(self._state.renderer)

    def _tf_dims_changed(self) -> bool:
        tf = self._state.transfer_function
        dims = tf.dims if tf is not None else 1
        changed, self._shown_tf_dims = dims != self._shown_tf_dims, dims
        return changed

    def _keep_a_usable_renderer(self) -> None:
        """After a TF or settings change the current renderer may no longer apply (a 2D TF in
        `vtk`): switch to one that can, and say why in the status bar."""
        state = self._state
        if state.volume is None:
            return
        volume, tf = state.volume, state.transfer_function
        assert tf is not None
        options = self.options()
        chosen = pick_renderer(options, state.renderer, self._measured(volume, tf, state.settings))
        plain = None
        if chosen is None:  # a level's setting no renderer has for this TF (pre-integration of a 2D TF)
            plain = state.settings.with_(preintegration=False)
            plain_options = renderer_options(volume.kind, plain, self._registry, tf.dims,
                                             labels=state.labels_drawn, channels=state.channels_drawn)[0]  # fmt: skip
            chosen = pick_renderer(plain_options, state.renderer, self._measured(volume, tf, plain))
        if chosen is None:
            return
        if chosen != state.renderer:
            reason = next((o.reason for o in options if o.name == state.renderer), None)
            self._status_bar.showMessage(f"{renderer_message(state.renderer, reason)}; using {chosen}", 15000)
            self.switch(chosen)
        if plain is not None and self._registry.capabilities(chosen).unsupported_reason(
                volume.kind, tf.dims, state.settings) is not None:  # fmt: skip
            state.set_settings(state.settings.with_(preintegration=False))

    # ------------------------------------------------------------------ frames
    def frame_shown(self, frame: Frame) -> None:
        """The renderer drew: it is the one to fall back to, and its numbers go in the label."""
        self._preparing = None
        if frame.renderer == self._state.renderer:  # not a preview by the fastest renderer
            self._last_good_renderer = frame.renderer
            self._failure_key = None
        cheaper = frame.settings is not None and frame.settings != self._state.settings
        quality = "" if frame.full else (", preview at lower quality" if cheaper else ", preview")
        if (
            frame.full
            and self._state.labels_drawn
            and self._state.settings.preintegration
            and frame.settings is not None
            and not frame.settings.preintegration
        ):  # `ViewState.label_settings`: no pre-integration tables per label
            quality = ", labels without pre-integration"
        self.frame_label.setText(
            f"{frame.renderer} ({self._level_drawn(frame)})  |  {frame.width} x {frame.height}{quality}  |  "
            f"{frame.ms:.1f} ms"
        )

    def _level_drawn(self, frame: Frame) -> str:
        """The quality level a frame was drawn at (the chosen one where levels have equal
        settings), or "custom"."""
        state = self._state
        if frame.settings is None or state.volume is None:
            return "custom"
        kind = SceneClass.of(state.volume, state.transfer_function)
        if frame.full and frame.renderer == state.renderer:  # the state's settings (image refinement off)
            return level_of(state.renderer, kind, state.settings, prefer=state.quality_level) or "custom"
        return level_of(frame.renderer, kind, frame.settings) or "custom"

    def preparing(self, serial: int, renderer: str) -> None:
        """A new renderer or volume is being set up: after PREPARING_AFTER_S without a frame or
        progress, the label says so (a set-up that long would otherwise look like a frozen view)."""
        self._preparing = (serial, renderer)
        QTimer.singleShot(int(PREPARING_AFTER_S * 1000), lambda: self._show_preparing(serial))

    def _show_preparing(self, serial: int) -> None:
        if sip.isdeleted(self.frame_label):  # the window closed before the timer fired
            return
        if self._preparing is not None and self._preparing[0] == serial:
            self.frame_label.setText(f"{self._preparing[1]}  |  preparing the renderer…")

    def frame_progressed(self, _serial: int, renderer: str, fraction: float) -> None:
        """Slow renderers (reference) report how far the newest frame is."""
        self._preparing = None
        self.frame_label.setText(f"{renderer}  |  rendering {100 * fraction:.0f}%")

    def _fallback(self, request: RenderRequest, usable: set[str]) -> str | None:
        """The renderer to switch to after `request` failed: the last one that drew, where it can
        draw this view, else (when the failed one cannot draw this view at all: an eye inside the
        volume) the fastest measured one that can; None when there is none."""
        volume, camera = request.volume, request.camera

        def refuses_view(name: str) -> bool:
            try:
                return (
                    self._registry.capabilities(name).camera_reason(volume.kind, camera, volume.bounds)
                    is not None
                )
            except VolrenError:
                return True

        last = self._last_good_renderer
        if last in usable and not refuses_view(last):
            return last
        if not refuses_view(request.renderer):
            return None
        try:
            chosen, _ = choose_renderer(SceneClass.of(volume, request.tf), DEFAULT_LEVEL, request.tf.dims, request.settings,
                                        sorted(usable), can_draw=usable.__contains__, cameras=(camera,),
                                        bounds=volume.bounds)  # fmt: skip
        except VolrenError:
            return None
        return chosen

    def render_failed(self, request: RenderRequest, message: str) -> None:
        """Back to the last renderer that drew, if it can; report once per renderer and scene."""
        self._preparing = None
        name = request.renderer
        if name != self._state.renderer:
            return  # the person switched away already
        text = message if message.startswith(f"renderer {name}") else f"renderer {name} failed: {message}"
        usable = {o.name for o in self.options() if o.enabled} - {name}
        fallback = self._fallback(request, usable)
        if fallback is not None:
            back = "back " if fallback == self._last_good_renderer else ""
            text += f"; switched {back}to {fallback}"
            self.switch(fallback)  # re-renders behind the message box
        else:
            self.frame_label.setText(f"{name}  |  render failed")
            if self._viewport.frame is None:
                self._viewport.placeholder = "Rendering failed"
                self._viewport.update()
        key = (name, id(request.volume), request.settings)
        if fallback is None and key == self._failure_key:
            self._status_bar.showMessage(text, 15000)  # already said once for this scene
            return
        self._failure_key = key
        self._report_error("Rendering failed", text)
