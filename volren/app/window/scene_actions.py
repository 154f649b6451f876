"""File > Save Scene: what is shown, written as a scene JSON that File > Open reads back.

A scene refers to its volume by path, so this part remembers which file (and scalars) the shown
volume came from (`remember_volume_file`, told by the opening part). A volume made in memory has
no file: it is written beside the scene first, as `<scene>.volume.vti` (or .vtu). A step of a time
series is saved with its series (the .pvd or folder opened) and the step's number, so the scene
reopens the series at that step. A volume with labels (Real-Time Volume Graphics, chapter 16)
names its label file too (one made in memory is written beside the scene, `<scene>.labels.vti`),
and the TF saved is the TF per label, whose base is the 1D TF shown.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from PyQt5.QtGui import QKeySequence
from PyQt5.QtWidgets import QAction, QFileDialog, QMainWindow

from volren.app.core.loading import PathArg, one_line_error, view_scene
from volren.app.core.state import ViewState
from volren.app.files.recent_files import RecentFiles
from volren.app.files.screenshot import check_writable
from volren.app.rendering.viewport import Viewport
from volren.app.window.time_control import TimeControl
from volren.errors import VolrenError

SCENE_FILTER = "Scenes (*.json);;All files (*)"


class SceneActions:
    """The Save Scene action, its dialog, and `save(path)`."""

    def __init__(
        self,
        window: QMainWindow,
        state: ViewState,
        viewport: Viewport,
        recent: RecentFiles,
        report_error: Callable[[str, str], None],
        time: TimeControl | None = None,
    ) -> None:
        """`time`: the time toolbar, whose series and step a scene saved on a time series names."""
        self._window = window
        self._state = state
        self._viewport = viewport
        self._recent = recent
        self._report_error = report_error
        self._time = time
        self._volume_path: str | None = None
        self._volume_scalars: str | None = None
        self.save_action = QAction(
            "Save &Scene…", window, shortcut=QKeySequence("Ctrl+S"), triggered=self._save_dialog
        )
        self.save_action.setToolTip("Save the volume's path, the transfer function, camera and settings")

    @property
    def volume_path(self) -> str | None:
        """The file (or DICOM folder) the shown volume was read from; None for one made in memory."""
        return self._volume_path

    def remember_volume_file(self, path: str | None, scalars: str | None) -> None:
        """The shown volume came from `path` (None: made in memory), with these scalars."""
        self._volume_path, self._volume_scalars = path, scalars

    def save(self, path: PathArg) -> bool:
        """Write what is shown as a scene JSON that Open reads back; reports and returns False on
        failure."""
        s = self._state
        if s.volume is None or s.transfer_function is None or s.camera is None:
            self._report_error("Cannot save the scene", "nothing to save: open a volume first")
            return False
        from volren import io

        try:
            check_writable(path)  # before a volume is written beside it
            volume_path = self._volume_path or self._write_volume_beside(Path(path))
            label_tf = s.label_transfer_function
            labels_path = None
            if label_tf is not None:
                labels_path = s.labels_path or self._write_labels_beside(Path(path))
            drawn = s.drawn_transfer_function  # a TF per label or per channel where they are drawn
            assert drawn is not None
            scene = view_scene(
                volume_path,
                drawn,
                s.camera,
                s.label_settings(s.renderer, s.settings),  # as drawn: `volren render` draws them so
                s.renderer,
                self._viewport.pixel_size(),
                scalars=self._volume_scalars,
                crop=s.crop,
                background=s.background,
                time_series=self._series_step(),
                labels_path=labels_path,
                channels=_channel_pick(s),
            )
            io.save_scene(scene, path)
        except (VolrenError, OSError) as exc:
            self._report_error("Cannot save the scene", one_line_error(exc, path))
            return False
        self._recent.add(path)
        self._window.statusBar().showMessage(f"Saved scene {path}", 5000)
        return True

    def _series_step(self) -> tuple[str, int] | None:
        """The time series shown (the .pvd or folder opened) and the step on screen; None without one."""
        time = self._time
        if time is None or time.series is None or time.shown_step is None:
            return None
        return str(time.series.source), time.shown_step

    def _write_volume_beside(self, scene_path: Path) -> str:
        from volren import io

        volume = self._state.volume
        assert volume is not None
        target = scene_path.with_name(
            f"{scene_path.stem}.volume.{'vti' if volume.kind == 'uniform' else 'vtu'}"
        )
        io.save_volume(volume, target)
        self._volume_path, self._volume_scalars = str(target.absolute()), None
        return self._volume_path

    def _write_labels_beside(self, scene_path: Path) -> str:
        """Labels made in memory, written beside the scene as `<scene>.labels.vti`."""
        from volren import io
        from volren.model.volume import UniformVolume

        volume, labels = self._state.volume, self._state.labels
        assert isinstance(volume, UniformVolume) and labels is not None
        target = scene_path.with_name(f"{scene_path.stem}.labels.vti")
        grid = UniformVolume(labels.values, spacing=volume.spacing, origin=volume.origin, name=labels.name)
        io.save_volume(grid, target)
        self._state.labels_path = str(target.absolute())
        return self._state.labels_path

    def suggested_path(self) -> str:
        """Where Save Scene proposes to write: named after the volume, in the folder the person
        last opened or saved in (not next to the data, which may be read-only or shared)."""
        name = Path(self._volume_path).with_suffix(".json").name if self._volume_path else "scene.json"
        folder = self._recent.folder() or (str(Path(self._volume_path).parent) if self._volume_path else "")
        return str(Path(folder) / name) if folder else name

    def _save_dialog(self) -> None:
        if self._state.volume is None:
            self._report_error("Cannot save the scene", "nothing to save: open a volume first")
            return
        path, _ = QFileDialog.getSaveFileName(self._window, "Save scene", self.suggested_path(), SCENE_FILTER)
        if path:
            self.save(path if Path(path).suffix else path + ".json")


def _channel_pick(state: ViewState) -> bool | tuple[int, ...] | None:
    """The channels of the file shown, as a scene names them: True for every one, else the file's
    channel numbers (`PickedChannels.indices`); None without channels."""
    channels = state.channels
    if channels is None:
        return None
    indices = tuple(getattr(channels, "indices", range(channels.count)))
    return True if indices == tuple(range(channels.count)) else indices
