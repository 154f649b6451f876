"""The main window: wires the state, the viewport, the render thread, the loader and the menus.

The window holds no scene data of its own. It owns one `ViewState`; the viewport edits it, the
`FrameScheduler` turns its changes into requests for the `RenderService`, and finished frames come
back to the viewport and the status bar. Later panels (TF editors) plug in by observing and editing
`window.state` and adding dock widgets.

Failures never end the app: a file that fails to load leaves what was shown; a renderer that
raises is reported in one line and the previous working renderer takes over again.

The File menu: open (dialog, drag and drop, Open Recent), a load runs in the background with its
stage in the status bar and can be cancelled (the Cancel button or Esc) or superseded by the next
open; Save Scene writes the view as a scene JSON (`loading.view_scene`) that Open reads back; Save
Screenshot renders a full-quality frame at a chosen size in the background (`screenshot`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from PyQt5.QtCore import QSettings, Qt, pyqtSignal
from PyQt5.QtGui import QCloseEvent, QDragEnterEvent, QDragMoveEvent, QDropEvent, QKeySequence
from PyQt5.QtWidgets import (
    QAction,
    QFileDialog,
    QLabel,
    QMainWindow,
    QProgressBar,
    QProgressDialog,
    QToolBar,
    QToolButton,
    QWidget,
)

from volren.app.core.loading import LoadedInput, PathArg, load_input, one_line_error, view_scene
from volren.app.core.renderer_choice import RendererOption, pick_renderer, renderer_options
from volren.app.core.state import Change, ViewState, default_camera
from volren.app.files import screenshot_dialog as dialogs
from volren.app.files.load_task import Loader, LoadFunction
from volren.app.files.recent_files import RecentFiles, RecentFilesMenu
from volren.app.files.screenshot import ScreenshotJob, Screenshotter, check_writable
from volren.app.rendering.render_service import (
    Frame,
    RendererFactory,
    RenderRequest,
    RenderService,
    _registry_factory,
)
from volren.app.rendering.renderer_chooser import RendererChooser
from volren.app.rendering.scheduling import FrameScheduler
from volren.app.rendering.viewport import Viewport
from volren.app.window.docks import Docks
from volren.errors import VolrenError
from volren.renderers.registry import RendererRegistry
from volren.renderers.registry import registry as default_registry

OPEN_FILTER = (
    "Volumes and scenes (*.vti *.vtk *.vtu *.vtr *.mha *.mhd *.nrrd *.nhdr *.nii *.nii.gz *.slc *.dcm *.raw *.json);;"
    "All files (*)"
)
SCENE_FILTER = "Scenes (*.json);;All files (*)"


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
    #: A load finished: True when something new is shown (False: failed or cancelled).
    loadFinished = pyqtSignal(bool)
    #: A screenshot was written (its path).
    screenshotSaved = pyqtSignal(str)

    def __init__(
        self,
        state: ViewState | None = None,
        parent: QWidget | None = None,
        *,
        registry: RendererRegistry = default_registry,
        renderer_factory: RendererFactory = _registry_factory,
        load: LoadFunction = load_input,
        settings: QSettings | None = None,
    ) -> None:
        """`settings` keeps the recent files (default: the app's QSettings; tests pass their own)."""
        super().__init__(parent)
        self.state = state or ViewState()
        self.registry = registry
        #: False in headless runs (--screenshot): errors are only emitted, never shown modally.
        self.show_error_dialogs = True
        self._last_good_renderer: str | None = None
        self._failure_key: tuple[Any, ...] | None = None
        self._closed = False
        self._shown_tf_dims = 1
        #: The file the shown volume came from, and its scalars (what Save Scene refers to).
        self._volume_path: str | None = None
        self._volume_scalars: str | None = None
        self._screenshot_path = "volren.png"
        self._screenshot_progress: QProgressDialog | None = None

        self.viewport = Viewport(self.state, self)
        self.setCentralWidget(self.viewport)
        self.service = RenderService(self, renderer_factory)
        self.scheduler = FrameScheduler(self.state, self.service, self.viewport.pixel_size, self)
        self.loader = Loader(self, load)
        self.screenshotter = Screenshotter(renderer_factory, self)
        self.recent = RecentFiles(settings, parent=self)

        self._build_actions()
        self._build_file_actions()
        self._build_menus_and_toolbar()
        self._build_status_bar()
        self.docks = Docks(self)
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
        self.loader.stageChanged.connect(self._on_load_stage)
        self.loader.cancelled.connect(self._on_load_cancelled)
        self.recent_menu.fileChosen.connect(self.open_input)
        self.screenshotter.busyChanged.connect(self._on_screenshot_busy)
        self.screenshotter.progressed.connect(self._on_screenshot_progress)
        self.screenshotter.saved.connect(self._on_screenshot_saved)
        self.screenshotter.failed.connect(
            lambda message: self.report_error("Cannot save the screenshot", message)
        )
        self.chooser.rendererChosen.connect(self.state.set_renderer)
        self._unsubscribe = self.state.subscribe(self._on_state_change)
        self._refresh_renderers()

    # ------------------------------------------------------------------ construction
    def _build_actions(self) -> None:
        self.open_action = QAction("&Open…", self, shortcut=QKeySequence.Open, triggered=self._open_dialog)
        self.open_action.setToolTip(
            "Open a volume, a scene or a transfer function (or drop a file on the window)"
        )
        self.open_folder_action = QAction("Open &DICOM folder…", self, triggered=self._open_folder_dialog)
        self.quit_action = QAction("&Quit", self, shortcut=QKeySequence.Quit, triggered=self.close)
        self.reset_action = QAction(
            "&Reset view", self, shortcut=QKeySequence("R"), triggered=self.reset_view
        )
        self.reset_action.setToolTip("Reset the camera (azimuth 30, elevation 20, zoom 1)  [R]")

    def _build_file_actions(self) -> None:
        """Recent files, saving scenes and screenshots, cancelling a load."""
        self.recent_menu = RecentFilesMenu(self.recent, self)
        self.save_scene_action = QAction(
            "Save &Scene…", self, shortcut=QKeySequence("Ctrl+S"), triggered=self._save_scene_dialog
        )
        self.save_scene_action.setToolTip(
            "Save the volume's path, the transfer function, camera and settings"
        )
        self.screenshot_action = QAction(
            "Save Screens&hot…",
            self,
            shortcut=QKeySequence("Ctrl+Shift+S"),
            triggered=self._screenshot_dialog,
        )
        self.screenshot_action.setToolTip("Render the view at a chosen resolution and save it as PNG")
        self.cancel_action = QAction(
            "Cancel", self, shortcut=QKeySequence(Qt.Key_Escape), triggered=self.cancel_load
        )
        self.cancel_action.setToolTip("Stop loading and keep what is shown  [Esc]")
        self.cancel_action.setEnabled(False)
        self.addAction(self.cancel_action)  # its Esc shortcut works without a menu entry

    def _build_menus_and_toolbar(self) -> None:
        file_menu = self.menuBar().addMenu("&File")
        file_menu.addAction(self.open_action)
        file_menu.addAction(self.open_folder_action)
        file_menu.addMenu(self.recent_menu)
        file_menu.addSeparator()
        file_menu.addAction(self.save_scene_action)
        file_menu.addAction(self.screenshot_action)
        file_menu.addSeparator()
        file_menu.addAction(self.quit_action)
        self.view_menu = self.menuBar().addMenu("&View")
        self.view_menu.addAction(self.reset_action)

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
        self.stage_label = QLabel("", self)  # "Reading bonsai.vti…", "Preparing mesh…"
        self.busy_bar = QProgressBar(self)
        self.busy_bar.setRange(0, 0)  # busy indicator until a stage reports how far it is
        self.busy_bar.setMaximumWidth(120)
        self.busy_bar.setTextVisible(False)
        self.cancel_button = QToolButton(self)
        self.cancel_button.setDefaultAction(self.cancel_action)
        for widget in (self.stage_label, self.busy_bar, self.cancel_button):
            widget.hide()
            self.statusBar().addPermanentWidget(widget)
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
        """Load `path` (default: the bundled sample) in the background, then show it; a load still
        running is abandoned (its result never shows).

        `renderer` is an explicit request (the command line): if it cannot draw the volume that is
        an error; a scene's renderer that cannot is replaced quietly.
        """
        label = Path(path).name if path is not None else "sample"
        self.statusBar().showMessage(f"Opening {label}…")
        if self.state.volume is None:
            self.viewport.placeholder = f"Opening {label}…"
            self.viewport.update()
        self.loader.start(path, tf, scalars, context={"path": path, "renderer": renderer})

    def cancel_load(self) -> bool:
        """Abandon the running load (Esc, the status bar's Cancel): what is shown stays."""
        return self.loader.cancel()

    def _on_busy(self, busy: bool) -> None:
        self.busy_bar.setRange(0, 0)
        self.stage_label.setText("")
        for widget in (self.stage_label, self.busy_bar, self.cancel_button):
            widget.setVisible(busy)
        self.cancel_action.setEnabled(busy)

    def _on_load_stage(self, text: str, fraction: float | None) -> None:
        self.stage_label.setText(text)
        if fraction is None:
            self.busy_bar.setRange(0, 0)
        else:
            self.busy_bar.setRange(0, 100)
            self.busy_bar.setValue(round(100 * min(max(fraction, 0.0), 1.0)))

    def _on_load_cancelled(self, _context: dict[str, Any]) -> None:
        self._show_no_volume_placeholder()
        self.statusBar().showMessage("Loading cancelled", 5000)
        self.loadFinished.emit(False)

    def _show_no_volume_placeholder(self) -> None:
        if self.state.volume is None:
            self.viewport.placeholder = "No volume (File > Open, or drop a file here)"
            self.viewport.update()

    def _on_loaded(self, loaded: LoadedInput, context: dict[str, Any]) -> None:
        self.statusBar().clearMessage()
        opened = context.get("path") if context else None
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
        else:
            self.apply_loaded(loaded, context.get("renderer") if context else None)
        if opened is not None:
            self.recent.add(opened)
        self.loadFinished.emit(True)

    def _on_load_failed(self, message: str, context: dict[str, Any]) -> None:
        self._show_no_volume_placeholder()
        self.report_error("Cannot open", message)
        self.loadFinished.emit(False)

    def apply_loaded(self, loaded: LoadedInput, requested_renderer: str | None = None) -> None:
        """Show a loaded volume (with its TF, camera, settings), choosing a renderer that can draw it."""
        volume = loaded.volume
        assert volume is not None and loaded.transfer_function is not None
        settings = loaded.settings or self.state.settings
        options, notes = renderer_options(
            volume.kind, settings, self.registry, loaded.transfer_function.dims
        )
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
        self._volume_path, self._volume_scalars = loaded.volume_path, loaded.scalars
        self.state.load(
            volume, loaded.transfer_function, camera, settings, loaded.source, renderer=chosen or wanted
        )
        self._apply_view_extras(loaded)
        if notes:
            self.statusBar().showMessage("; ".join(notes), 15000)

    def _apply_view_extras(self, loaded: LoadedInput) -> None:
        """A scene's crop box and background (state.load just cleared the crop of the old volume)."""
        if loaded.background is not None:
            self.state.set_background(loaded.background)
        if loaded.crop is not None:
            try:
                self.state.set_crop(loaded.crop)
            except VolrenError as exc:
                self.report_error("Cannot crop", f"{loaded.source}: {exc}")

    @property
    def volume_path(self) -> str | None:
        """The file (or DICOM folder) the shown volume was read from; None for one made in memory."""
        return self._volume_path

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
            self.statusBar().showMessage(
                f"{_renderer_message(self.state.renderer, reason)}; using {chosen}", 15000
            )
            self.state.set_renderer(chosen)

    def _options(self) -> tuple[list[RendererOption], list[str]]:
        volume, tf = self.state.volume, self.state.transfer_function
        dims = tf.dims if tf is not None else 1
        return renderer_options(volume.kind if volume else None, self.state.settings, self.registry, dims)

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
        self.frame_label.setText(
            f"{frame.renderer}  |  {frame.width} x {frame.height}{quality}  |  {frame.ms:.1f} ms"
        )
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

    # ------------------------------------------------------------------ scenes
    def save_scene(self, path: PathArg) -> bool:
        """Write what is shown as a scene JSON that Open reads back; reports and returns False on
        failure. A volume made in memory (no file) is written beside it first, as
        `<scene>.volume.vti` (or .vtu), so the scene still names a file."""
        s = self.state
        if s.volume is None or s.transfer_function is None or s.camera is None:
            self.report_error("Cannot save the scene", "nothing to save: open a volume first")
            return False
        from volren import io

        try:
            check_writable(path)  # before a volume is written beside it
            volume_path = self._volume_path or self._write_volume_beside(Path(path))
            scene = view_scene(
                volume_path,
                s.transfer_function,
                s.camera,
                s.settings,
                s.renderer,
                self.viewport.pixel_size(),
                scalars=self._volume_scalars,
                crop=s.crop,
                background=s.background,
            )
            io.save_scene(scene, path)
        except (VolrenError, OSError) as exc:
            self.report_error("Cannot save the scene", one_line_error(exc, path))
            return False
        self.recent.add(path)
        self.statusBar().showMessage(f"Saved scene {path}", 5000)
        return True

    def _write_volume_beside(self, scene_path: Path) -> str:
        from volren import io

        volume = self.state.volume
        assert volume is not None
        target = scene_path.with_name(
            f"{scene_path.stem}.volume.{'vti' if volume.kind == 'uniform' else 'vtu'}"
        )
        io.save_volume(volume, target)
        self._volume_path, self._volume_scalars = str(target.absolute()), None
        return self._volume_path

    # ------------------------------------------------------------------ screenshots
    def save_screenshot(self, path: PathArg, whole_window: bool = False) -> bool:
        """Write the viewport (or the whole window) as shown, as PNG; reports and returns False on
        failure. `render_screenshot` renders at a chosen size instead."""
        pixmap = (self if whole_window else self.viewport).grab()
        if not pixmap.save(str(path), "PNG"):
            self.report_error("Cannot save the screenshot", f"{path}: cannot write a PNG file there")
            return False
        self.statusBar().showMessage(f"Saved {path}", 5000)
        self.screenshotSaved.emit(str(path))
        return True

    def render_screenshot(self, path: PathArg, width: int, height: int) -> bool:
        """Render a full-quality `width` x `height` frame of the view with the current renderer in
        the background and write it as PNG (`screenshotSaved` or a reported error follow); False
        when it cannot even start (nothing shown, a folder that cannot be written)."""
        try:
            check_writable(path)
            job = ScreenshotJob.of_view(self.state, path, width, height)
        except VolrenError as exc:
            self.report_error("Cannot save the screenshot", str(exc))
            return False
        self._close_screenshot_progress()
        progress = QProgressDialog(
            f"Rendering {job.width} x {job.height} with {job.renderer}…", "Cancel", 0, 0, self
        )
        progress.setWindowTitle("Save screenshot")
        progress.setMinimumDuration(400)
        progress.setAutoClose(False)
        progress.setAutoReset(False)
        progress.canceled.connect(self.screenshotter.cancel)
        self._screenshot_progress = progress
        self.screenshotter.start(job)
        return True

    def _on_screenshot_progress(self, fraction: float) -> None:
        if self._screenshot_progress is not None:
            self._screenshot_progress.setRange(0, 100)
            self._screenshot_progress.setValue(round(100 * min(max(fraction, 0.0), 1.0)))

    def _on_screenshot_busy(self, busy: bool) -> None:
        if not busy:
            self._close_screenshot_progress()

    def _close_screenshot_progress(self) -> None:
        progress, self._screenshot_progress = self._screenshot_progress, None
        if progress is not None:
            progress.canceled.disconnect()  # closing it would say "canceled"
            progress.close()
            progress.deleteLater()

    def _on_screenshot_saved(self, path: str) -> None:
        self.statusBar().showMessage(f"Saved {path}", 5000)
        self.screenshotSaved.emit(path)

    # ------------------------------------------------------------------ dialogs
    def _open_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(
            self, "Open volume, scene or transfer function", "", OPEN_FILTER
        )
        if path:
            self.open_input(path)

    def _open_folder_dialog(self) -> None:
        path = QFileDialog.getExistingDirectory(self, "Open DICOM folder")
        if path:
            self.open_input(path)

    def _save_scene_dialog(self) -> None:
        if self.state.volume is None:
            self.report_error("Cannot save the scene", "nothing to save: open a volume first")
            return
        start = str(Path(self._volume_path).with_suffix(".json")) if self._volume_path else "scene.json"
        path, _ = QFileDialog.getSaveFileName(self, "Save scene", start, SCENE_FILTER)
        if path:
            self.save_scene(path if Path(path).suffix else path + ".json")

    def _screenshot_dialog(self) -> None:
        choice = dialogs.ask_screenshot(self, self._screenshot_path, self.viewport.pixel_size())
        if choice is None:
            return
        self._screenshot_path = choice.path
        if choice.whole_window:
            self.save_screenshot(choice.path, whole_window=True)
        else:
            self.render_screenshot(choice.path, choice.width, choice.height)

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
        self.docks.detach()
        self.scheduler.detach()
        self.service.shutdown()
        self._close_screenshot_progress()
        self.screenshotter.shutdown()
        self.loader.shutdown(5000)

    def closeEvent(self, event: QCloseEvent) -> None:
        self.shutdown()
        super().closeEvent(event)
