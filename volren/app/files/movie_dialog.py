"""The Export Movie dialog: where to (MP4 or GIF), frame size, frames, speed and how far to orbit.

`ask_movie` is looked up on this module at call time, so tests (and headless runs) can replace
the modal dialog. The dialog opens with `MovieFields`: the ones of the last movie, which
`MovieActions` keeps for the session and in the app's settings.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path

from PyQt5.QtWidgets import (
    QCheckBox,
    QDialog,
    QDialogButtonBox,
    QDoubleSpinBox,
    QFileDialog,
    QFormLayout,
    QLabel,
    QWidget,
)

from volren.app.files.dialog_fields import clamped_spin, path_row, run_modal, size_row
from volren.io.movie_io import MOVIE_SUFFIXES
from volren.model.animation import DEFAULT_FPS, DEFAULT_FRAMES, MAX_FPS, MAX_FRAMES, Animation
from volren.renderers.base import MAX_IMAGE_SIDE

MOVIE_FILTER = "Movies (*.mp4 *.gif);;MP4 video (*.mp4);;GIF animation (*.gif)"
#: The orbit's range in the dialog, degrees (ten turns either way).
MAX_ORBIT = 3600.0


@dataclass(frozen=True)
class MovieFields:
    """What the dialog holds besides the file: offered again the next time it opens."""

    width: int
    height: int
    frames: int = DEFAULT_FRAMES
    fps: float = DEFAULT_FPS
    orbit: float = 360.0
    lossless: bool = False

    def to_json(self) -> str:
        return json.dumps(asdict(self))

    @classmethod
    def from_json(cls, text: object) -> MovieFields | None:
        """The fields stored by `to_json`; None for anything else (an older or hand-edited store),
        as the dialog's defaults are better than an error about a preference."""
        try:
            data = json.loads(text)  # type: ignore[arg-type]
            fields = cls(**data)
        except (TypeError, ValueError):
            return None
        ints = (fields.width, fields.height, fields.frames)
        numbers = (fields.fps, fields.orbit)
        if not all(type(v) is int for v in ints) or not all(
            type(v) in (int, float) and math.isfinite(v) for v in numbers
        ):
            return None
        return fields if isinstance(fields.lossless, bool) else None


@dataclass(frozen=True)
class MovieChoice:
    """What the movie dialog asked for."""

    path: str
    width: int
    height: int
    animation: Animation
    lossless: bool = False

    def fields(self) -> MovieFields:
        """The dialog's fields that made this choice."""
        a = self.animation
        return MovieFields(self.width, self.height, a.frames, a.fps, a.orbit_degrees, self.lossless)


def movie_path(path: str) -> str:
    """`path`, with ".mp4" added when its suffix is not a movie's (what the file will hold)."""
    return path if Path(path).suffix.lower() in MOVIE_SUFFIXES else path + ".mp4"


class MovieDialog(QDialog):
    """File, frame size, number of frames, frames per second, the orbit's angle and lossless,
    starting from `fields`, with the movie's length shown as they change."""

    def __init__(self, parent: QWidget | None, path: str, fields: MovieFields) -> None:
        super().__init__(parent)
        self.setWindowTitle("Export movie")
        self.path_edit, file_row = path_row(self, path, self._browse)
        self.width_box, self.height_box = (
            clamped_spin(self, 1, MAX_IMAGE_SIDE, v) for v in (fields.width, fields.height)
        )
        self.frames_box = clamped_spin(self, 1, MAX_FRAMES, fields.frames)
        self.fps_box = QDoubleSpinBox(self)
        self.fps_box.setRange(1.0, MAX_FPS)
        self.fps_box.setDecimals(1)
        self.fps_box.setValue(fields.fps)
        self.orbit_box = QDoubleSpinBox(self)
        self.orbit_box.setRange(-MAX_ORBIT, MAX_ORBIT)
        self.orbit_box.setDecimals(1)
        self.orbit_box.setSuffix("°")
        self.orbit_box.setValue(fields.orbit)
        self.orbit_box.setToolTip("How far the camera turns about the view's up axis; whole turns loop")
        self.lossless = QCheckBox("Lossless (exact frames; larger, and not every player takes it)", self)
        self.lossless.setChecked(fields.lossless)
        self.length_label = QLabel(self)
        for box in (self.frames_box, self.fps_box):
            box.valueChanged.connect(self._update_length)
        self.path_edit.textChanged.connect(self._path_changed)

        self.buttons = QDialogButtonBox(QDialogButtonBox.Save | QDialogButtonBox.Cancel, self)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)

        form = QFormLayout(self)
        form.addRow("File:", file_row)
        form.addRow("Frame size:", size_row(self, self.width_box, self.height_box))
        form.addRow("Frames:", self.frames_box)
        form.addRow("Frames per second:", self.fps_box)
        form.addRow("Orbit:", self.orbit_box)
        form.addRow("", self.lossless)
        form.addRow("Length:", self.length_label)
        form.addRow(self.buttons)
        self._path_changed(path)
        self._update_length()

    def _update_length(self) -> None:
        self.length_label.setText(f"{self.frames_box.value() / self.fps_box.value():.1f} s")

    def _path_changed(self, text: str) -> None:
        self.buttons.button(QDialogButtonBox.Save).setEnabled(bool(text.strip()))
        is_mp4 = movie_path(text.strip()).lower().endswith(".mp4")
        self.lossless.setEnabled(is_mp4)
        self.lossless.setToolTip("" if is_mp4 else "A GIF has 256 colours a frame: it cannot be lossless")

    def _browse(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self, "Export movie", self.path_edit.text(), MOVIE_FILTER)
        if path:
            self.path_edit.setText(movie_path(path))

    def choice(self) -> MovieChoice:
        path = movie_path(self.path_edit.text().strip())
        animation = Animation(frames=self.frames_box.value(), fps=self.fps_box.value(),
                              orbit_degrees=self.orbit_box.value())  # fmt: skip
        lossless = self.lossless.isChecked() and path.lower().endswith(".mp4")
        return MovieChoice(path, self.width_box.value(), self.height_box.value(), animation, lossless)


def ask_movie(parent: QWidget | None, path: str, fields: MovieFields) -> MovieChoice | None:
    """Run the movie dialog; None when cancelled. Looked up at call time so tests can patch it."""
    return run_modal(MovieDialog(parent, path, fields), MovieDialog.choice)
