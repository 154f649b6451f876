"""Opening files: File > Open, Open DICOM folder, Open Recent, and showing what was loaded.

A load runs in the background (`files.load_task.Loader`) with its stage in the status bar, and can
be cancelled (the Cancel button or Esc) or superseded by the next open. A file that fails to load
leaves what was shown. A transfer-function file is applied to the volume already shown; a volume
or a scene replaces the scene, with a renderer that can draw it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

from PyQt5.QtCore import QObject, Qt, pyqtSignal
from PyQt5.QtGui import QKeySequence
from PyQt5.QtWidgets import QAction, QFileDialog, QLabel, QMainWindow, QProgressBar, QToolButton, QWidget

from volren.app.core.loading import LoadedInput, PathArg
from volren.app.core.state import ViewState, default_camera
from volren.app.files.level_refiner import LevelRefiner
from volren.app.files.load_task import Loader, LoadFunction
from volren.app.files.raw_dialog import RawDialog
from volren.app.files.recent_files import RecentFiles, RecentFilesMenu
from volren.app.rendering.viewport import Viewport
from volren.app.window.renderer_control import RendererControl
from volren.app.window.scene_actions import SceneActions
from volren.app.window.time_control import TimeControl
from volren.errors import VolrenError
from volren.io.ome_zarr_io import MAX_IN_MEMORY_BYTES, is_ome_zarr
from volren.io.series_io import TimeSeries, is_series, load_series
from volren.model.scene_class import SceneClass
from volren.model.transfer_function_2d import TransferFunction
from volren.quality import AUTO, DEFAULT_LEVEL, at_level, level_of

OPEN_FILTER = (
    "Volumes, time series and scenes (*.vti *.vtk *.vtu *.mha *.mhd *.nrrd *.nhdr *.nii *.nii.gz *.slc *.dcm *.raw "
    "*.pvd *.json);;"
    "All files (*)"
)


#: The level the app opens at: the command line's `default`, the level that keeps every thin
#: structure (at most VTK's error and pixels off on every measured scene, `docs/bench/quality.md`).
#: Gestures are previewed at `interactive` (`preview_settings`); still frames never refine in image
#: space (`still_settings`), and at that a bonsai still frame at 947x896 cost no more at `default`
#: than at `interactive` (raycast 1.8 s against 2.0 s on this 2-core machine under load).
APP_LEVEL = DEFAULT_LEVEL


class FileActions(QObject):
    """The open actions, the recent-files menu, the load's status-bar widgets and `open_input`."""

    #: A load finished: True when something new is shown (False: failed or cancelled).
    loadFinished = pyqtSignal(bool)

    def __init__(
        self,
        window: QMainWindow,
        state: ViewState,
        viewport: Viewport,
        renderers: RendererControl,
        scenes: SceneActions,
        recent: RecentFiles,
        load: LoadFunction,
        report_error: Callable[[str, str], None],
        time: TimeControl | None = None,
    ) -> None:
        """`time`: the time toolbar, given a series when one is opened (a .pvd, a folder of volumes)."""
        super().__init__(window)
        self._window = window
        self._state = state
        self._viewport = viewport
        self._renderers = renderers
        self._scenes = scenes
        self._report_error = report_error
        #: The TF each field of a file had when another was chosen (`show_array`), for the session.
        self._tf_by_field: dict[tuple[str, str], TransferFunction] = {}
        self.recent = recent
        self._time = time
        #: The most an OME-Zarr image's levels may take in memory (`volren view --memory`): the app
        #: refines up to the finest level within it.
        self.zarr_memory = MAX_IN_MEMORY_BYTES
        self._scalars: str | None = None  # what the shown volume was opened with
        if time is not None:
            time.stepShown.connect(lambda _index, path: scenes.remember_volume_file(path, self._scalars))
        self.refiner = LevelRefiner(parent=self)
        self.refiner.levelReady.connect(self._on_level_ready)
        self.refiner.failed.connect(lambda message: report_error("Cannot refine the image", message))
        self.loader = Loader(window, load)
        self.loader.loaded.connect(self._on_loaded)
        self.loader.failed.connect(self._on_load_failed)
        self.loader.busyChanged.connect(self._on_busy)
        self.loader.stageChanged.connect(self._on_load_stage)
        self.loader.cancelled.connect(self._on_load_cancelled)
        self._build_actions()
        self._build_status_widgets()

    def _build_actions(self) -> None:
        window = self._window
        self.open_action = QAction("&Open…", window, shortcut=QKeySequence.Open, triggered=self._open_dialog)
        self.open_action.setToolTip(
            "Open a volume, a scene or a transfer function (or drop a file on the window)"
        )
        self.open_folder_action = QAction("Open &Folder…", window, triggered=self._open_folder_dialog)
        self.open_folder_action.setToolTip(
            "Open a DICOM series, or a folder of volume files as a time series"
        )
        self.recent_menu = RecentFilesMenu(self.recent, window)
        self.recent_menu.fileChosen.connect(self.open_input)
        self.cancel_action = QAction(
            "Cancel", window, shortcut=QKeySequence(Qt.Key_Escape), triggered=self.cancel
        )
        self.cancel_action.setToolTip("Stop loading and keep what is shown  [Esc]")
        self.cancel_action.setEnabled(False)

    def _build_status_widgets(self) -> None:
        window = self._window
        self.stage_label = QLabel("", window)  # "Reading bonsai.vti…", "Preparing mesh…"
        self.busy_bar = QProgressBar(window)
        self.busy_bar.setRange(0, 0)  # busy indicator until a stage reports how far it is
        self.busy_bar.setMaximumWidth(120)
        self.busy_bar.setTextVisible(False)
        self.cancel_button = QToolButton(window)
        self.cancel_button.setDefaultAction(self.cancel_action)
        for widget in self.status_widgets:
            widget.hide()

    @property
    def status_widgets(self) -> tuple[QWidget, ...]:
        """What the status bar shows while a load runs, left to right."""
        return (self.stage_label, self.busy_bar, self.cancel_button)

    # ------------------------------------------------------------------ opening
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
        series = None
        if path is not None and is_series(path):
            try:
                series = load_series(path)
            except VolrenError as exc:
                self._report_error("Cannot open", str(exc))
                return
        raw, refine = None, None
        if path is not None and series is None and is_ome_zarr(path):
            try:
                raw, refine = self._coarse_first(path, renderer)
            except VolrenError as exc:
                self._report_error("Cannot open", str(exc))
                return
        if path is not None and Path(path).suffix.lower() == ".raw" and Path(path).is_file():
            raw = self.ask_raw_layout(path)  # a headerless file: the user says what it holds
            if raw is None:
                return
        label = Path(path).name if path is not None else "sample"
        self._window.statusBar().showMessage(f"Opening {label}…")
        if self._state.volume is None:
            self._viewport.placeholder = f"Opening {label}…"
            self._viewport.update()
        context = {"path": path, "renderer": renderer, "series": series, "step": 0, "refine": refine}
        self.loader.start(series.steps[0] if series else path, tf, scalars, context=context, raw=raw)

    def _coarse_first(
        self, path: PathArg, renderer: str | None
    ) -> tuple[dict[str, int] | None, tuple[str, list[int]] | None]:
        """For an OME-Zarr image: read the coarsest level now and the finer ones after
        (`LevelRefiner`), down to the finest that the renderer drawing it takes within `zarr_memory`,
        its copies counted as `volren render` counts them (`renderer` when requested, else the one
        shown, or `auto`: not chosen yet, so counted as the one that copies most); (reader options,
        refinement)."""
        from volren.bricked.zarr_input import finest_level_read_whole, renderer_copy_bytes
        from volren.io.ome_zarr_io import human_size, level_bytes, open_multiscale

        following_auto = self._state.volume is None or self._renderers.auto
        drawing = renderer or (AUTO if following_auto else self._state.renderer)
        image = open_multiscale(path)
        finest = finest_level_read_whole(image, self.zarr_memory, drawing)
        coarsest = len(image.levels) - 1
        if finest is None:
            drawn = human_size(level_bytes(image.levels[-1], renderer_copy_bytes(drawing)))
            raise VolrenError(f"{path}: even the coarsest level takes {drawn} drawn by renderer {drawing} (its values "
                              f"and the renderer's copies), more than the memory allowed "
                              f"({human_size(self.zarr_memory)})")  # fmt: skip
        if finest >= coarsest:
            return {"level": coarsest}, None  # one level to read
        return {"level": coarsest}, (str(path), list(range(coarsest - 1, finest - 1, -1)))

    def _on_level_ready(self, level: int, volume: object) -> None:
        """A finer level of the OME-Zarr image shown: put it on screen with the view as it is."""
        if self._state.volume is None:
            return
        left = len(self.refiner.pending)
        self._state.show_step(volume, source=f"{self._state.source.split(' (level')[0]} (level {level})")  # type: ignore[arg-type]
        more = f"; {left} finer level{'s' if left != 1 else ''} coming" if left else ""
        self._window.statusBar().showMessage(f"Showing level {level} of the image{more}", 5000)

    def show_array(self, choice: str) -> bool:
        """Show another field of the file on screen (the Dataset panel's chooser): the file is read
        again in the background with `choice` as its scalars, and the camera, crop, settings and
        renderer stay. Each field keeps its own TF for the session (as ParaView keeps a colour map
        per array): switching back brings back the TF edited for it. False when nothing can be
        reloaded (a volume made in memory)."""
        path, volume, tf = self._scenes.volume_path, self._state.volume, self._state.transfer_function
        if path is None or volume is None or tf is None:
            self._report_error("Cannot show another array", "only a volume read from a file has other arrays")
            return False
        self._tf_by_field[(path, volume.scalars)] = tf
        self._window.statusBar().showMessage(f"Reading {choice} from {Path(path).name}…")
        series = self._time.series if self._time is not None else None
        step = self._time.shown_step if self._time is not None else None
        context = {"path": path, "keep_view": True, "series": series, "step": step or 0}
        self.loader.start(path, None, choice, context=context)
        return True

    def _keeping_the_view(self, loaded: LoadedInput) -> LoadedInput:
        """Another field of the shown file: the view as it is, the TF this field had, if any."""
        state, volume = self._state, loaded.volume
        assert volume is not None
        tf = self._tf_by_field.get((loaded.volume_path, volume.scalars)) or loaded.transfer_function
        renderer = None if self._renderers.auto else state.renderer  # `auto` chooses again for the new field
        settings = (
            None if self._level_shown() is not None else state.settings
        )  # the level, for the renderer drawing
        return replace(loaded, camera=state.camera, settings=settings, renderer=renderer,
                       transfer_function=tf, crop=state.crop, background=state.background)  # fmt: skip

    def ask_raw_layout(self, path: PathArg) -> dict[str, Any] | None:
        """The layout of a headerless raw file from `RawDialog` (None: cancelled). Without dialogs
        (a scripted screenshot) there is nobody to ask: a one-line error says what to do."""
        if not getattr(self._window, "show_error_dialogs", True):
            self._window.report_error("Cannot open", f"{path}: headerless raw data needs its shape and sample type: "
                                      "open it in the window, or use volren render --raw-shape NX,NY,NZ --raw-dtype T")  # fmt: skip
            return None
        dialog = RawDialog(path, self._window)
        return dialog.parameters() if dialog.exec() == RawDialog.Accepted else None

    def cancel(self) -> bool:
        """Abandon the running load (Esc, the status bar's Cancel): what is shown stays."""
        return self.loader.cancel()

    def apply_loaded(self, loaded: LoadedInput, requested_renderer: str | None = None) -> None:
        """Show a loaded volume (with its TF, camera, settings), choosing a renderer that can draw it."""
        state, volume = self._state, loaded.volume
        assert volume is not None and loaded.transfer_function is not None
        settings = loaded.settings or state.settings
        # `auto` unless something names a renderer or the person picked one (kept where it can draw)
        following_auto = state.volume is None or self._renderers.auto
        wanted = requested_renderer or loaded.renderer or (AUTO if following_auto else state.renderer)
        renderer, notes = self._renderers.choose_for(
            volume, loaded.transfer_function, settings, wanted, requested_renderer
        )
        if loaded.settings is None:
            level = self._level_shown()
            kind = SceneClass.of(volume, loaded.transfer_function)
            settings = (at_level(renderer, kind, level, settings) if level is not None else None) or settings
            state.quality_level = level
        else:  # a scene's own settings, as they are: whichever level they are
            state.quality_level = None
        aspect = self._viewport.aspect()
        camera = loaded.resolve_camera(aspect) or default_camera(volume, aspect)
        self._scenes.remember_volume_file(loaded.volume_path, loaded.scalars)
        try:
            state.load(volume, loaded.transfer_function, camera, settings, loaded.source, renderer=renderer,
                       crop=loaded.crop, background=loaded.background, label_tf=loaded.label_tf,
                       labels_path=loaded.labels_path)  # fmt: skip
        except VolrenError as exc:  # the crop box leaves nothing of this volume: show it whole
            self._report_error("Cannot crop", f"{loaded.source}: {exc}")
            state.load(volume, loaded.transfer_function, camera, settings, loaded.source, renderer=renderer,
                       background=loaded.background, label_tf=loaded.label_tf,
                       labels_path=loaded.labels_path)  # fmt: skip
        if notes:
            self._window.statusBar().showMessage("; ".join(notes), 15000)

    def _level_shown(self) -> str | None:
        """The quality level the next volume opens at: APP_LEVEL for the first, else the level
        shown now (None: custom settings, kept as they are)."""
        state = self._state
        if state.volume is None:
            return APP_LEVEL
        kind = SceneClass.of(state.volume, state.transfer_function)
        return level_of(state.renderer, kind, state.settings, prefer=state.quality_level)

    # ------------------------------------------------------------------ the loader's answers
    def _on_busy(self, busy: bool) -> None:
        self.busy_bar.setRange(0, 0)
        self.stage_label.setText("")
        for widget in self.status_widgets:
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
        self._window.statusBar().showMessage("Loading cancelled", 5000)
        self.loadFinished.emit(False)

    def _show_no_volume_placeholder(self) -> None:
        if self._state.volume is None:
            self._viewport.placeholder = "No volume (File > Open, or drop a file here)"
            self._viewport.update()

    def _on_loaded(self, loaded: LoadedInput, context: dict[str, Any]) -> None:
        self._window.statusBar().clearMessage()
        opened = context.get("path") if context else None
        if loaded.volume is None:
            if self._state.volume is None or loaded.transfer_function is None:
                self._report_error(
                    "Cannot apply the transfer function",
                    f"{loaded.source}: a transfer function needs a volume; open a volume first",
                )
                self.loadFinished.emit(False)
                return
            self._state.set_transfer_function(loaded.transfer_function)
            self._window.statusBar().showMessage(f"Transfer function from {loaded.source}", 5000)
        else:
            context = context or {}
            if context.get("keep_view") and self._state.volume is not None:
                loaded = self._keeping_the_view(loaded)
            self.apply_loaded(loaded, context.get("renderer"))
            self._scalars = loaded.scalars
            refine = context.get("refine")
            if refine:
                self.refiner.start(*refine)
            elif not context.get("keep_view"):
                self.refiner.cancel()
            if self._time is not None:
                series, step = _series_shown(loaded, context)
                self._time.set_series(series, loaded.volume, loaded.scalars, step)
        if opened is not None and not (context or {}).get("keep_view"):
            self.recent.add(opened)
        self.loadFinished.emit(True)

    def _on_load_failed(self, message: str, context: dict[str, Any]) -> None:
        self._show_no_volume_placeholder()
        self._report_error("Cannot open", message)
        self.loadFinished.emit(False)

    # ------------------------------------------------------------------ dialogs
    def _open_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self._window, "Open volume, scene or transfer function",
                                              self.recent.folder(), OPEN_FILTER)  # fmt: skip
        if path:
            self.open_input(path)

    def _open_folder_dialog(self) -> None:
        path = QFileDialog.getExistingDirectory(self._window, "Open a DICOM folder or a time series folder",
                                                self.recent.folder())  # fmt: skip
        if path:
            self.open_input(path)

    def shutdown(self, timeout_ms: int = 5000) -> None:
        """Stop the running load at its next stage and wait for it (and for a level being read)."""
        self.refiner.shutdown(timeout_ms)
        self.loader.shutdown(timeout_ms)


def _series_shown(loaded: LoadedInput, context: dict[str, Any]) -> tuple[TimeSeries | None, int]:
    """The time series a load shows and its step: the one opened, or the one its scene was saved on."""
    if context.get("series") is not None:
        return context["series"], context.get("step", 0)
    return loaded.series, loaded.step
