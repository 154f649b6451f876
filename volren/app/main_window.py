"""The main window: wires the state, the viewport, the render thread, the loader and the menus.

The window holds no scene data of its own. It owns one `ViewState`; the viewport edits it, the
`FrameScheduler` turns its changes into requests for the `RenderService`, and finished frames come
back to the viewport and the status bar. Later panels (TF editors) plug in by observing and editing
`window.state` and adding dock widgets.

Failures never end the app: a file that fails to load leaves what was shown; a renderer that
raises is reported in one line and the previous working renderer takes over again.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from PyQt5.QtCore import pyqtSignal
from PyQt5.QtGui import QCloseEvent, QDragEnterEvent, QDragMoveEvent, QDropEvent, QKeySequence
from PyQt5.QtWidgets import QAction, QFileDialog, QLabel, QMainWindow, QProgressBar, QToolBar, QWidget

from volren.app import dialogs
from volren.app.load_task import Loader, LoadFunction
from volren.app.loading import LoadedInput, PathArg, load_input
from volren.app.render_service import Frame, RendererFactory, RenderRequest, RenderService, _registry_factory
from volren.app.renderer_box import RendererChooser
from volren.app.renderer_choice import RendererOption, pick_renderer, renderer_options
from volren.app.scheduling import FrameScheduler
from volren.app.state import Change, ViewState, default_camera
from volren.app.viewport import Viewport
from volren.renderers.registry import RendererRegistry
from volren.renderers.registry import registry as default_registry

OPEN_FILTER = (
    "Volumes and scenes (*.vti *.vtk *.vtu *.vtr *.mha *.mhd *.nrrd *.nhdr *.nii *.nii.gz *.slc *.dcm *.raw *.json);;"
    "All files (*)"
)


def _renderer_message(name: str, reason: str | None) -> str:
    reason = reason or "is not registered"
    return reason if reason.startswith("renderer") else f"renderer {name} {reason}"


class MainWindow(QMainWindow):
    """The volren desktop app's window."""

    #: A full-quality frame for the current state is on screen (what --screenshot waits for).
    fullFrameShown = pyqtSignal(object)
    #: Any frame was shown.
    frameShown = pyqtSignal(object)
    #: (title, one-line message) of every error reported to the person.
    errorReported = pyqtSignal(str, str)
    #: A load finished: True when something new is shown.
    loadFinished = pyqtSignal(bool)

    def __init__(
        self,
        state: ViewState | None = None,
        parent: QWidget | None = None,
        *,
        registry: RendererRegistry = default_registry,
        renderer_factory: RendererFactory = _registry_factory,
        load: LoadFunction = load_input,
    ) -> None:
        super().__init__(parent)
        self.state = state or ViewState()
        self._registry = registry
        #: False in headless runs (--screenshot): errors are only emitted, never shown modally.
        self.show_error_dialogs = True
        self._last_good_renderer: str | None = None
        self._failure_key: tuple[Any, ...] | None = None
        self._closed = False
        self._shown_tf_dims = 1

        self.viewport = Viewport(self.state, self)
        self.setCentralWidget(self.viewport)
        self.service = RenderService(self, renderer_factory)
        self.scheduler = FrameScheduler(self.state, self.service, self.viewport.pixel_size, self)
        self.loader = Loader(self, load)

        self._build_actions()
        self._build_menus_and_toolbar()
        self._build_status_bar()
        self.setAcceptDrops(True)
        self.setWindowTitle("volren")

        self.viewport.resized.connect(self.scheduler.viewport_resized)
        self.viewport.resetRequested.connect(self.reset_view)
        self.service.frameReady.connect(self._on_frame)
        self.service.renderFailed.connect(self._on_render_failed)
        self.service.progressed.connect(self._on_render_progress)
        self.loader.loaded.connect(self._on_loaded)
        self.loader.failed.connect(self._on_load_failed)
        self.loader.busyChanged.connect(self._on_busy)
        self.chooser.rendererChosen.connect(self.state.set_renderer)
        self._unsubscribe = self.state.subscribe(self._on_state_change)
        self._refresh_renderers()

    # ------------------------------------------------------------------ construction
    def _build_actions(self) -> None:
        self.open_action = QAction("&Open…", self, shortcut=QKeySequence.Open, triggered=self._open_dialog)
        self.open_action.setToolTip("Open a volume, a scene or a transfer function (or drop a file on the window)")
        self.open_folder_action = QAction("Open &DICOM folder…", self, triggered=self._open_folder_dialog)
        self.save_action = QAction(
            "&Save screenshot…", self, shortcut=QKeySequence("Ctrl+S"), triggered=self._save_dialog
        )
        self.quit_action = QAction("&Quit", self, shortcut=QKeySequence.Quit, triggered=self.close)
        self.reset_action = QAction("&Reset view", self, shortcut=QKeySequence("R"), triggered=self.reset_view)
        self.reset_action.setToolTip("Reset the camera (azimuth 30, elevation 20, zoom 1)  [R]")

    def _build_menus_and_toolbar(self) -> None:
        file_menu = self.menuBar().addMenu("&File")
        for action in (self.open_action, self.open_folder_action, self.save_action):
            file_menu.addAction(action)
        file_menu.addSeparator()
        file_menu.addAction(self.quit_action)
        view_menu = self.menuBar().addMenu("&View")
        view_menu.addAction(self.reset_action)

        self.toolbar = QToolBar("Main", self)
        self.toolbar.setObjectName("main-toolbar")
        self.toolbar.setMovable(False)
        self.toolbar.addAction(self.open_action)
        self.toolbar.addAction(self.reset_action)
        self.toolbar.addSeparator()
        self.toolbar.addWidget(QLabel(" Renderer: ", self.toolbar))
        self.chooser = RendererChooser(self.toolbar)
        self.toolbar.addWidget(self.chooser)
        self.addToolBar(self.toolbar)

    def _build_status_bar(self) -> None:
        self.frame_label = QLabel("", self)
        self.busy_bar = QProgressBar(self)
        self.busy_bar.setRange(0, 0)  # busy indicator: readers report no progress
        self.busy_bar.setMaximumWidth(120)
        self.busy_bar.setTextVisible(False)
        self.busy_bar.hide()
        self.statusBar().addPermanentWidget(self.busy_bar)
        self.statusBar().addPermanentWidget(self.frame_label)

    # ------------------------------------------------------------------ errors
    def report_error(self, title: str, message: str) -> None:
        """Show a one-line error; the app goes on with what it had."""
        self.statusBar().showMessage(message, 15000)
        self.errorReported.emit(title, message)
        if self.show_error_dialogs:
            dialogs.show_error(self, title, message)

    # ------------------------------------------------------------------ loading
    def open_input(
        self,
        path: PathArg | None = None,
        tf: PathArg | None = None,
        scalars: str | None = None,
        renderer: str | None = None,
    ) -> None:
        """Load `path` (default: the bundled sample) in the background, then show it.

        `renderer` is an explicit request (the command line): if it cannot draw the volume that is
        an error; a scene's renderer that cannot is replaced quietly.
        """
        label = Path(path).name if path is not None else "sample"
        self.statusBar().showMessage(f"Opening {label}…")
        if self.state.volume is None:
            self.viewport.placeholder = f"Opening {label}…"
            self.viewport.update()
        self.loader.start(path, tf, scalars, context={"path": path, "renderer": renderer})

    def _on_busy(self, busy: bool) -> None:
        self.busy_bar.setVisible(busy)

    def _on_loaded(self, loaded: LoadedInput, context: dict[str, Any]) -> None:
        self.statusBar().clearMessage()
        if loaded.volume is None:
            if self.state.volume is None or loaded.transfer_function is None:
                self.report_error(
                    "Cannot apply the transfer function",
                    f"{loaded.source}: a transfer function needs a volume; open a volume first",
                )
                self.loadFinished.emit(False)
                return
            self.state.set_transfer_function(loaded.transfer_function)
            self.statusBar().showMessage(f"Transfer function from {loaded.source}", 5000)
            self.loadFinished.emit(True)
            return
        self.apply_loaded(loaded, context.get("renderer") if context else None)
        self.loadFinished.emit(True)

    def _on_load_failed(self, message: str, context: dict[str, Any]) -> None:
        if self.state.volume is None:
            self.viewport.placeholder = "No volume (File > Open, or drop a file here)"
            self.viewport.update()
        self.report_error("Cannot open", message)
        self.loadFinished.emit(False)

    def apply_loaded(self, loaded: LoadedInput, requested_renderer: str | None = None) -> None:
        """Show a loaded volume (with its TF, camera, settings), choosing a renderer that can draw it."""
        volume = loaded.volume
        assert volume is not None and loaded.transfer_function is not None
        settings = loaded.settings or self.state.settings
        options, notes = renderer_options(volume.kind, settings, self._registry, loaded.transfer_function.dims)
        wanted = requested_renderer or loaded.renderer or self.state.renderer
        chosen = pick_renderer(options, wanted)
        if chosen != wanted:
            reason = next((o.reason for o in options if o.name == wanted), None)
            text = _renderer_message(wanted, reason)
            text += f"; using {chosen}" if chosen else f"; no renderer can draw {volume.kind} volumes"
            if requested_renderer is not None or chosen is None:
                self.report_error("Renderer unavailable", text)
            else:
                notes.append(text)
        aspect = self.viewport.aspect()
        camera = loaded.resolve_camera(aspect) or default_camera(volume, aspect)
        self._failure_key = None
        self.state.load(volume, loaded.transfer_function, camera, settings, loaded.source, renderer=chosen or wanted)
        if notes:
            self.statusBar().showMessage("; ".join(notes), 15000)

    # ------------------------------------------------------------------ state
    def _on_state_change(self, change: Change) -> None:
        if change.what == "volume":
            self._tf_dims_changed()
            self.setWindowTitle(f"volren - {self.state.source}" if self.state.source else "volren")
            self._refresh_renderers()
        elif change.what == "settings" or (change.what == "tf" and self._tf_dims_changed()):
            self._refresh_renderers()
            self._keep_a_usable_renderer()
        elif change.what == "renderer":
            self.chooser.set_current(self.state.renderer)

    def _tf_dims_changed(self) -> bool:
        tf = self.state.transfer_function
        dims = tf.dims if tf is not None else 1
        changed, self._shown_tf_dims = dims != self._shown_tf_dims, dims
        return changed

    def _keep_a_usable_renderer(self) -> None:
        """After a TF or settings change the current renderer may no longer apply (a 2D TF in
        `vtk`): switch to one that can, and say why in the status bar."""
        if self.state.volume is None:
            return
        options = self.renderer_options()
        chosen = pick_renderer(options, self.state.renderer)
        if chosen is not None and chosen != self.state.renderer:
            reason = next((o.reason for o in options if o.name == self.state.renderer), None)
            self.statusBar().showMessage(f"{_renderer_message(self.state.renderer, reason)}; using {chosen}", 15000)
            self.state.set_renderer(chosen)

    def _options(self) -> tuple[list[RendererOption], list[str]]:
        volume, tf = self.state.volume, self.state.transfer_function
        dims = tf.dims if tf is not None else 1
        return renderer_options(volume.kind if volume else None, self.state.settings, self._registry, dims)

    def renderer_options(self) -> list[RendererOption]:
        return self._options()[0]

    def _refresh_renderers(self) -> None:
        options, notes = self._options()
        self.chooser.set_options(options, self.state.renderer)
        if notes:
            self.statusBar().showMessage("; ".join(notes), 15000)

    def reset_view(self) -> None:
        self.state.reset_camera(self.viewport.aspect())

    # ------------------------------------------------------------------ frames
    def _on_frame(self, frame: Frame) -> None:
        self.viewport.show_frame(frame)
        self.scheduler.note_frame(frame)
        self._last_good_renderer = frame.renderer
        self._failure_key = None
        quality = "" if frame.full else ", preview"
        self.frame_label.setText(f"{frame.renderer}  |  {frame.width} x {frame.height}{quality}  |  {frame.ms:.1f} ms")
        self.frameShown.emit(frame)
        if frame.full and frame.serial == self.service.latest_serial:
            self.fullFrameShown.emit(frame)

    def _on_render_progress(self, _serial: int, renderer: str, fraction: float) -> None:
        """Slow renderers (reference) report how far the newest frame is."""
        self.frame_label.setText(f"{renderer}  |  rendering {100 * fraction:.0f}%")

    def _on_render_failed(self, request: RenderRequest, message: str) -> None:
        name = request.renderer
        if name != self.state.renderer:
            return  # the person switched away already
        text = message if message.startswith(f"renderer {name}") else f"renderer {name} failed: {message}"
        fallback = self._last_good_renderer
        usable = {o.name for o in self.renderer_options() if o.enabled}
        if fallback == name or fallback not in usable:
            fallback = None
        if fallback is not None:
            text += f"; switched back to {fallback}"
            self.state.set_renderer(fallback)  # re-renders behind the message box
        else:
            self.frame_label.setText(f"{name}  |  render failed")
            if self.viewport.frame is None:
                self.viewport.placeholder = "Rendering failed"
                self.viewport.update()
        key = (name, id(request.volume), request.settings)
        if fallback is None and key == self._failure_key:
            self.statusBar().showMessage(text, 15000)  # already said once for this scene
            return
        self._failure_key = key
        self.report_error("Rendering failed", text)

    # ------------------------------------------------------------------ screenshots
    def save_screenshot(self, path: PathArg, whole_window: bool = False) -> bool:
        """Write the viewport (or the whole window) as PNG; reports and returns False on failure."""
        pixmap = (self if whole_window else self.viewport).grab()
        if not pixmap.save(str(path), "PNG"):
            self.report_error("Cannot save the screenshot", f"{path}: cannot write a PNG file there")
            return False
        self.statusBar().showMessage(f"Saved {path}", 5000)
        return True

    # ------------------------------------------------------------------ dialogs
    def _open_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Open volume, scene or transfer function", "", OPEN_FILTER)
        if path:
            self.open_input(path)

    def _open_folder_dialog(self) -> None:
        path = QFileDialog.getExistingDirectory(self, "Open DICOM folder")
        if path:
            self.open_input(path)

    def _save_dialog(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self, "Save screenshot", "volren.png", "PNG images (*.png)")
        if path:
            if Path(path).suffix.lower() != ".png":
                path += ".png"
            self.save_screenshot(path)

    # ------------------------------------------------------------------ drag and drop
    @staticmethod
    def _dropped_path(event: QDragEnterEvent | QDragMoveEvent | QDropEvent) -> str | None:
        mime = event.mimeData()
        if mime is None or not mime.hasUrls():
            return None
        for url in mime.urls():
            if url.isLocalFile():
                return url.toLocalFile()
        return None

    def dragEnterEvent(self, event: QDragEnterEvent) -> None:
        if self._dropped_path(event):
            event.acceptProposedAction()
        else:
            event.ignore()

    def dragMoveEvent(self, event: QDragMoveEvent) -> None:
        if self._dropped_path(event):
            event.acceptProposedAction()
        else:
            event.ignore()

    def dropEvent(self, event: QDropEvent) -> None:
        path = self._dropped_path(event)
        if path is None:
            event.ignore()
            return
        event.acceptProposedAction()
        self.open_input(path)

    # ------------------------------------------------------------------ shutdown
    def shutdown(self) -> None:
        """Stop rendering and release the renderer (in its thread); safe to call twice."""
        if self._closed:
            return
        self._closed = True
        self._unsubscribe()
        self.scheduler.detach()
        self.service.shutdown()
        self.loader.wait(5000)

    def closeEvent(self, event: QCloseEvent) -> None:
        self.shutdown()
        super().closeEvent(event)
