"""The main window: wires the state, the viewport, the render thread, the window's parts and the
menus.

The window holds no scene data of its own. It owns one `ViewState`; the viewport edits it, the
`FrameScheduler` turns its changes into requests for the `RenderService`, and finished frames come
back to the viewport and the status bar. Each concept of the window is a part of its own, built
here with what it needs and placed in the menus, toolbar and status bar here:

- `files` (`FileActions`): opening files in the background, Open Recent, cancelling a load;
- `scenes` (`SceneActions`): Save Scene;
- `labels` (`LabelActions`): Open Labels, Close Labels;
- `screenshots` (`ScreenshotActions`): Save Screenshot;
- `movies` (`MovieActions`): Export Movie;
- `renderers` (`RendererControl`): the chooser, keeping a usable renderer, the frame label;
- `docks` (`Docks`): the TF editors and settings panels;
- `drops` (`FileDrops`): files dropped on the window open like File > Open.

Failures never end the app: every part reports through `report_error` (one line, in the status
bar and a message box) and goes on with what it had.
"""

from __future__ import annotations

from PyQt5.QtCore import QSettings, Qt, pyqtSignal
from PyQt5.QtGui import QCloseEvent, QKeySequence, QResizeEvent
from PyQt5.QtWidgets import QAction, QLabel, QMainWindow, QMessageBox, QToolBar, QWidget

from volren.app.core.loading import load_input
from volren.app.core.state import Change, ViewState
from volren.app.core.view_directions import (
    ANATOMICAL_SIDES,
    VIEW_DIRECTIONS,
    ViewDirection,
    anatomical_view,
    look_along,
)
from volren.app.files.load_task import LoadFunction
from volren.app.files.recent_files import RecentFiles, app_settings
from volren.app.rendering.render_service import Frame, RendererFactory, RenderService, _registry_factory
from volren.app.rendering.scheduling import FrameScheduler
from volren.app.rendering.viewport import Viewport
from volren.app.window.docks import Docks
from volren.app.window.file_actions import FileActions
from volren.app.window.file_drops import FileDrops
from volren.app.window.label_actions import LabelActions
from volren.app.window.movie_actions import MovieActions
from volren.app.window.quality_control import QualityControl
from volren.app.window.renderer_control import RendererControl
from volren.app.window.scene_actions import SceneActions
from volren.app.window.screenshot_actions import ScreenshotActions
from volren.app.window.time_control import TimeControl
from volren.renderers.registry import RendererRegistry
from volren.renderers.registry import registry as default_registry

#: Why the A/P/L/R/S/I views are disabled.
NO_PATIENT_ORIENTATION = ("The data says nothing of how the patient lies (DICOM, or NRRD in an LPS or RAS space, "
                          "axial, coronal or sagittal)")  # fmt: skip


class MainWindow(QMainWindow):
    """The volren desktop app's window."""

    #: A full-quality frame for the current state is on screen (what --screenshot waits for).
    fullFrameShown = pyqtSignal(object)
    #: Any frame was shown.
    frameShown = pyqtSignal(object)
    #: (title, one-line message) of every error reported to the person.
    errorReported = pyqtSignal(str, str)

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
        """`settings` keeps the recent files and the dialogs' last choices (default: the app's
        QSettings; tests pass their own)."""
        super().__init__(parent)
        self.state = state or ViewState()
        self.registry = registry
        #: False in headless runs (--screenshot): errors are only emitted, never shown modally.
        self.show_error_dialogs = True
        self._closed = False

        self.viewport = Viewport(self.state, self)
        self.setCentralWidget(self.viewport)
        self.service = RenderService(self, renderer_factory)
        self.scheduler = FrameScheduler(
            self.state, self.service, self.viewport.pixel_size, self, registry=registry
        )
        status_bar = self.statusBar()
        settings = settings if settings is not None else app_settings()
        recent = RecentFiles(settings, parent=self)
        self.renderers = RendererControl(
            self.state, registry, self.viewport, status_bar, self.report_error, self
        )
        self.quality = QualityControl(self.state, self)
        self.time = TimeControl(self, self.state, self.report_error)
        self.addToolBar(Qt.BottomToolBarArea, self.time)
        self.scenes = SceneActions(self, self.state, self.viewport, recent, self.report_error, self.time)
        self.screenshots = ScreenshotActions(self, self.state, self.viewport, renderer_factory, self.report_error,
                                             recent.folder)  # fmt: skip
        self.movies = MovieActions(self, self.state, self.viewport, renderer_factory, self.report_error, recent.folder,
                                   settings)  # fmt: skip
        self.files = FileActions(
            self,
            self.state,
            self.viewport,
            self.renderers,
            self.scenes,
            recent,
            load,
            self.report_error,
            self.time,
        )
        self.addAction(self.files.cancel_action)  # its Esc shortcut works without a menu entry
        self.labels = LabelActions(self, self.state, self.report_error, recent.folder)

        self._build_view_actions()
        self._build_menus_and_toolbar()
        for widget in self.files.status_widgets:
            status_bar.addPermanentWidget(widget)
        status_bar.addPermanentWidget(self.renderers.frame_label)
        self.docks = Docks(self)
        self.docks.clipping.plane_list.currentRowChanged.connect(lambda _row: self._show_clip_handles())
        self.drops = FileDrops(self)
        self.drops.dropped.connect(self.files.open_input)
        self.installEventFilter(self.drops)
        self.setAcceptDrops(True)
        self.setWindowTitle("volren")

        self.viewport.resized.connect(self.scheduler.viewport_resized)
        self.viewport.resetRequested.connect(self.reset_view)
        self.service.frameReady.connect(self._on_frame)
        self.service.renderFailed.connect(self.renderers.render_failed)
        self.service.progressed.connect(self.renderers.frame_progressed)
        self.service.preparing.connect(self.renderers.preparing)
        self._unsubscribe = self.state.subscribe(self._on_state_change)
        self.renderers.refresh()

    # ------------------------------------------------------------------ construction
    def _build_view_actions(self) -> None:
        self.quit_action = QAction("&Quit", self, shortcut=QKeySequence.Quit, triggered=self.close)
        self.reset_action = QAction(
            "&Reset view", self, shortcut=QKeySequence("R"), triggered=self.reset_view
        )
        self.reset_action.setToolTip("Reset the camera (azimuth 30, elevation 20, zoom 1)  [R]")
        #: View > View direction and the toolbar's "+X" ... "-Z": ParaView's view-direction buttons.
        self.view_direction_actions = {
            view.name: self._view_direction_action(view) for view in VIEW_DIRECTIONS
        }
        #: View > View direction > A, P, L, R, S, I: where the data says how the patient lies.
        self.anatomical_actions = {letter: self._anatomical_action(letter) for letter in ANATOMICAL_SIDES}
        #: View > Outline, Orientation axes, Colour legend: the viewport's overlays, by `OverlaySettings` name.
        overlays = (("outline", "Outline"), ("axes", "Orientation axes"), ("legend", "Colour legend"))
        self.overlay_actions = {name: self._overlay_action(name, text) for name, text in overlays}

    def _view_direction_action(self, view: ViewDirection) -> QAction:
        action = QAction(view.name, self, triggered=lambda _checked=False, v=view: self.look_along(v))
        action.setToolTip(view.description)
        action.setEnabled(False)  # until a volume is loaded
        return action

    def _anatomical_action(self, letter: str) -> QAction:
        action = QAction(f"{letter} ({ANATOMICAL_SIDES[letter]})", self,
                         triggered=lambda _checked=False, x=letter: self.look_from_patient_side(x))  # fmt: skip
        action.setEnabled(False)  # until a volume with a patient orientation is loaded
        action.setToolTip(NO_PATIENT_ORIENTATION)
        return action

    def look_from_patient_side(self, letter: str) -> None:
        """Turn the camera to look from the patient's `letter` side (A, P, L, R, S or I)."""
        volume = self.state.volume
        if volume is not None and getattr(volume, "patient_axes", None) is not None:
            self.look_along(anatomical_view(letter, volume.patient_axes))

    def _overlay_action(self, name: str, text: str) -> QAction:
        action = QAction(text, self, checkable=True)
        action.setChecked(getattr(self.viewport.overlays, name))
        action.toggled.connect(lambda on, n=name: self.viewport.set_overlay(n, on))
        return action

    def _build_menus_and_toolbar(self) -> None:
        file_menu = self.menuBar().addMenu("&File")
        file_menu.addAction(self.files.open_action)
        file_menu.addAction(self.files.open_folder_action)
        file_menu.addMenu(self.files.recent_menu)
        file_menu.addSeparator()
        file_menu.addAction(self.labels.open_action)
        file_menu.addAction(self.labels.close_action)
        file_menu.addSeparator()
        file_menu.addAction(self.scenes.save_action)
        file_menu.addAction(self.screenshots.action)
        file_menu.addAction(self.movies.action)
        file_menu.addSeparator()
        file_menu.addAction(self.quit_action)
        self.view_menu = self.menuBar().addMenu("&View")
        self.view_menu.addAction(self.reset_action)
        self.view_direction_menu = self.view_menu.addMenu("View &direction")
        self.view_direction_menu.addActions(list(self.view_direction_actions.values()))
        self.view_direction_menu.addSeparator()
        self.view_direction_menu.addActions(list(self.anatomical_actions.values()))
        self.view_menu.addSeparator()
        self.view_menu.addActions(list(self.overlay_actions.values()))
        #: View > Edit crop box: the crop box's face handles over the frame, dragged to crop.
        self.crop_handles_action = self.view_menu.addAction("Edit crop box")
        self.crop_handles_action.setCheckable(True)
        self.crop_handles_action.setChecked(self.viewport.crop_handles)
        self.crop_handles_action.setToolTip(
            "Show the crop box with a handle on each face; drag a handle to crop"
        )
        self.crop_handles_action.toggled.connect(self.viewport.set_crop_handles)
        #: View > Edit clip plane: the selected clip plane's handles over the frame (`_show_clip_handles`).
        self.clip_handles_action = self.view_menu.addAction("Edit clip plane")
        self.clip_handles_action.setCheckable(True)
        self.clip_handles_action.setToolTip(
            "Show the clip plane selected in the Clip planes panel with a handle at its centre (drag: move "
            "it along its normal) and one at its normal's tip (drag: turn it; Shift: to the nearest axis)"
        )
        self.clip_handles_action.toggled.connect(lambda _on: self._show_clip_handles())

        self.toolbar = QToolBar("Main", self)
        self.toolbar.setObjectName("main-toolbar")
        self.toolbar.setMovable(False)
        self.toolbar.addAction(self.files.open_action)
        self.toolbar.addAction(self.reset_action)
        self.toolbar.addSeparator()
        self.toolbar.addActions(list(self.view_direction_actions.values()))
        self.toolbar.addSeparator()
        self.toolbar.addWidget(QLabel(" Renderer: ", self.toolbar))
        self.toolbar.addWidget(self.renderers.chooser)
        self.toolbar.addWidget(QLabel(" Quality: ", self.toolbar))
        self.toolbar.addWidget(self.quality.chooser)
        self.addToolBar(self.toolbar)

    # ------------------------------------------------------------------ errors
    def report_error(self, title: str, message: str) -> None:
        """Show a one-line error; the app goes on with what it had. (`QMessageBox.critical` is
        looked up at call time, so tests and headless runs can replace it.)"""
        self.statusBar().showMessage(message, 15000)
        self.errorReported.emit(title, message)
        if self.show_error_dialogs:
            QMessageBox.critical(self, title, message)

    # ------------------------------------------------------------------ view
    def _on_state_change(self, change: Change) -> None:
        if change.what == "volume":
            self.setWindowTitle(f"volren - {self.state.source}" if self.state.source else "volren")
            for action in self.view_direction_actions.values():
                action.setEnabled(self.state.volume is not None)
            axes = getattr(self.state.volume, "patient_axes", None)
            for letter, action in self.anatomical_actions.items():
                action.setEnabled(axes is not None)
                action.setToolTip(
                    anatomical_view(letter, axes).description if axes else NO_PATIENT_ORIENTATION
                )
        self.renderers.on_state_change(change)
        self.quality.on_state_change(change)

    def _show_clip_handles(self) -> None:
        """The selected clip plane's handles in the view while View > Edit clip plane is on."""
        on = self.clip_handles_action.isChecked()
        self.viewport.set_clip_handles(self.docks.clipping.selected() if on else None)

    def reset_view(self) -> None:
        self.state.reset_camera(self.viewport.aspect())

    def look_along(self, view: ViewDirection) -> None:
        """Turn the camera to look along `view` at the drawn (cropped) volume's centre, same distance."""
        bounds, camera = self.state.shown_bounds, self.state.camera
        if bounds is not None and camera is not None:
            self.state.set_camera(look_along(camera, view, bounds))

    def _on_frame(self, frame: Frame) -> None:
        self.viewport.show_frame(frame)
        self.scheduler.note_frame(frame)
        self.renderers.frame_shown(frame)
        self.frameShown.emit(frame)
        if frame.full and frame.serial == self.service.latest_serial:
            self.fullFrameShown.emit(frame)

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
        self.screenshots.shutdown()
        self.movies.shutdown()
        self.time.shutdown()
        self.files.shutdown(5000)
        self.labels.shutdown(5000)

    def resizeEvent(self, event: QResizeEvent) -> None:
        super().resizeEvent(event)
        if hasattr(self, "docks"):
            self.docks.keep_viewport_share()

    def closeEvent(self, event: QCloseEvent) -> None:
        if not self._may_discard_running_jobs():
            event.ignore()
            return
        self.shutdown()
        super().closeEvent(event)

    def _may_discard_running_jobs(self) -> bool:
        """Closing stops a movie or screenshot still rendering, and it is not written: ask first
        (a headless run has nobody to ask, and closes)."""
        running = [what for what, jobs in (("a movie", self.movies.exporter), ("a screenshot", self.screenshots.screenshotter))
                   if jobs.busy]  # fmt: skip
        if not running or not self.show_error_dialogs or self._closed:
            return True
        answer = QMessageBox.question(self, "volren", f"{running[0].capitalize()} is still being rendered. Quit anyway "
                                      "and discard it?", QMessageBox.Yes | QMessageBox.No, QMessageBox.No)  # fmt: skip
        return answer == QMessageBox.Yes
