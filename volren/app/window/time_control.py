"""The time toolbar of a time series: a slider over the steps, the step's time and file, and Play.

It appears when a `.pvd` or a folder of volume files is opened and goes when something else is.
Moving the slider asks `SeriesSteps` for the step; the step is shown with `ViewState.show_step`
(TF, camera, settings, renderer and crop kept) when it is read, and the newest position wins, so
dragging the slider never queues a backlog. Play advances one step at a time, each once the one
before is on screen, at most `PLAY_FPS` steps a second, looping at the end.
"""

from __future__ import annotations

from collections.abc import Callable

from PyQt5.QtCore import Qt, QTimer, pyqtSignal
from PyQt5.QtWidgets import QLabel, QMainWindow, QSlider, QStyle, QToolBar, QToolButton

from volren.app.core.state import ViewState
from volren.app.files.series_steps import SeriesSteps, StepReader, read_step
from volren.io.series_io import TimeSeries
from volren.model.volume import Volume

#: Play's fastest pace, steps a second (slower when a step takes longer to read or render).
PLAY_FPS = 10


class TimeControl(QToolBar):
    """The toolbar; `set_series(series, volume)` shows it, `set_series(None)` hides it;
    `stepShown(index, file)` after each step put on screen."""

    stepShown = pyqtSignal(int, str)

    def __init__(self, window: QMainWindow, state: ViewState, report_error: Callable[[str, str], None],
                 read: StepReader = read_step) -> None:  # fmt: skip
        super().__init__("Time", window)
        self.setObjectName("time-toolbar")
        self._state = state
        self._report_error = report_error
        self._read = read
        self.steps: SeriesSteps | None = None
        self._shown: int | None = None
        self.slider = QSlider(Qt.Horizontal, self)
        self.slider.setMinimumWidth(160)
        self.slider.setToolTip("The time step shown (the steps beside it are read ahead)")
        self.slider.valueChanged.connect(self._on_slider)
        self.label = QLabel(self)
        self.play_button = QToolButton(self)
        self.play_button.setCheckable(True)
        self.play_button.setIcon(self.style().standardIcon(QStyle.SP_MediaPlay))
        self.play_button.setToolTip("Play the time steps (loops)")
        self.play_button.toggled.connect(self._on_play)
        self._timer = QTimer(self)
        self._timer.setInterval(round(1000 / PLAY_FPS))
        self._timer.timeout.connect(self._advance)
        self.addWidget(QLabel(" Time: ", self))
        self.addWidget(self.play_button)
        self.addWidget(self.slider)
        self.addWidget(self.label)
        self.hide()

    @property
    def series(self) -> TimeSeries | None:
        return self.steps.series if self.steps is not None else None

    @property
    def shown_step(self) -> int | None:
        """The step on screen (None without a series)."""
        return self._shown

    def set_series(self, series: TimeSeries | None, shown: Volume | None = None, scalars: str | None = None,
                   index: int = 0) -> None:  # fmt: skip
        """Step through `series`, whose step `index` (`shown`) is on screen; None: no series."""
        self.play_button.setChecked(False)
        if self.steps is not None:
            self.steps.shutdown()
            self.steps.deleteLater()
            self.steps = None
        self._shown = None
        if series is None:
            self.hide()
            return
        self.steps = SeriesSteps(series, scalars, self._read, self)
        self.steps.stepReady.connect(self._on_step_ready)
        self.steps.stepFailed.connect(self._on_step_failed)
        self.slider.blockSignals(True)
        self.slider.setRange(0, len(series) - 1)
        self.slider.setValue(index)
        self.slider.blockSignals(False)
        self._shown = index
        self.label.setText(series.label(index))
        if shown is not None:
            self.steps.keep(index, shown)
        self.show()

    def show_step(self, index: int) -> None:
        """Move to step `index` (as the slider does)."""
        self.slider.setValue(index)

    def _on_slider(self, index: int) -> None:
        if self.steps is not None:
            self.label.setText(f"{self.steps.series.label(index)}…")
            self.steps.request(index)

    def _on_step_ready(self, index: int, volume: object) -> None:
        if self.steps is None or index != self.slider.value():
            return
        self._shown = index
        self.label.setText(self.steps.series.label(index))
        path = self.steps.series.steps[index]
        self._state.show_step(volume, source=path.name)  # type: ignore[arg-type]
        self.stepShown.emit(index, str(path))

    def _on_step_failed(self, index: int, message: str) -> None:
        self.play_button.setChecked(False)
        if self.steps is not None and self._shown is not None:
            self.label.setText(self.steps.series.label(self._shown))
        self._report_error("Cannot show the time step", message)

    def _on_play(self, playing: bool) -> None:
        icon = QStyle.SP_MediaPause if playing else QStyle.SP_MediaPlay
        self.play_button.setIcon(self.style().standardIcon(icon))
        if playing:
            self._timer.start()
        else:
            self._timer.stop()

    def _advance(self) -> None:
        """The next step, once the one asked for last is on screen."""
        if self.steps is None or self._shown != self.slider.value():
            return
        self.slider.setValue((self.slider.value() + 1) % len(self.steps.series))

    def shutdown(self) -> None:
        self.play_button.setChecked(False)
        if self.steps is not None:
            self.steps.shutdown()
