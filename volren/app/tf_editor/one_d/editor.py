"""The 1D transfer-function editor panel (after ParaView's colour map editor and 3D Slicer's volume
rendering module).

The panel owns no TF: it shows and edits `state.transfer_function` in place, and re-reads it on
every "tf" or "volume" change, because undo and opened files replace the object. Undo itself is
`TFHistory`'s, which records from the state; here only gestures are grouped (a drag is one
begin/end_interaction). A 2D TF is not edited here: the panel says so and offers to start a 1D
one. Errors (a bad file) leave as `errorOccurred(title, one_line)` for the window to show.

The value axis spans the TF's range and the data's, so both the histogram and every control
point are in view; it stays put during a drag so the point under the mouse does not slide. That
span is also where points may go (the canvases' `limits`). The view can zoom in on a part of it
(a TF's detail is often a few per cent of a CT's range): the mouse wheel over the curve
or the colour bar zooms about the value under the cursor, "TF range" shows just the TF's range and
"Whole range" all of it again. Zoomed, the histogram is binned afresh over the view (after the
wheel rests: binning a big volume takes a moment), the points outside stay where they are, and a
drag or a typed number may still take a point anywhere in the limits.

The colour-map combo box ends with "Browse colour maps…", the searchable `PresetBrowser` of the
curated and ParaView's maps.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from PyQt5.QtCore import QPoint, Qt, QTimer, pyqtSignal
from PyQt5.QtGui import QIcon, QPixmap
from PyQt5.QtWidgets import (
    QAbstractSpinBox,
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFileDialog,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QSlider,
    QStackedWidget,
    QStyle,
    QToolButton,
    QVBoxLayout,
    QWidget,
)

from volren.app.core.colormap_presets import PRESET_NAMES, apply_preset
from volren.app.core.opacity_presets import OPACITY_PRESET_NAMES, preset_problem, preset_transfer_function
from volren.app.core.state import Change, ViewState
from volren.app.qt_subscription import subscribe_while_alive
from volren.app.tf_editor.one_d.background_histogram import BackgroundHistogram
from volren.app.tf_editor.one_d.color_bar import ColorBar
from volren.app.tf_editor.one_d.color_entry import ColorEntry
from volren.app.tf_editor.one_d.opacity_curve import OpacityCurve
from volren.app.tf_editor.one_d.point_canvas import ValueAxis
from volren.app.tf_editor.one_d.point_entry import PointEntry
from volren.app.tf_editor.one_d.preset_browser import PresetBrowser, swatch_image
from volren.errors import VolrenError
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TransferFunction
from volren.model.value_histogram import DEFAULT_BINS, Histogram, compute_histogram
from volren.model.volume import UniformVolume, Volume

TF_FILTER = "Transfer functions: volren or ParaView preset JSON (*.json);;All files (*)"
PRESET_PLACEHOLDER = "Colour map…"
#: The colour-map box's last entry: opens the preset browser.
BROWSE_ITEM = "Browse colour maps…"
TISSUE_PLACEHOLDER = "Tissue preset…"
#: The shift slider's step, a fraction of the data range, and its steps each way: half the range
#: each way in thousandths, so the whole slider spans the range once (one range each way in 200ths
#: moved a narrow preset off its tissue with a few pixels of drag). Page Up/Down move 10 steps.
SHIFT_STEP = 0.001
SHIFT_STEPS = 500
#: How long the view must rest (ms) before the histogram is binned afresh over a zoomed view.
REBIN_DELAY_MS = 150


def _decimals(scale: float) -> int:
    """Digits after the point that resolve about a thousandth of `scale` (a range or a length)."""
    if not math.isfinite(scale) or scale <= 0:
        return 3
    return int(min(max(3 - math.floor(math.log10(scale)), 1), 12))


def _preset_icon(name: str) -> QIcon:
    return QIcon(QPixmap.fromImage(swatch_image(name, 48, 12)))


class PresetBox(QComboBox):
    """The colour-map chooser: a placeholder, the curated preset names, then "Browse colour maps…".

    The swatches are drawn when the list first opens, not while the app starts.
    """

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setSizeAdjustPolicy(QComboBox.AdjustToMinimumContentsLengthWithIcon)
        self.setMinimumContentsLength(10)
        self.addItem(PRESET_PLACEHOLDER)
        self.addItems(PRESET_NAMES)
        self.addItem(BROWSE_ITEM)
        self.setItemData(self.count() - 1, "Search every colour map, ParaView's included", Qt.ToolTipRole)
        self._have_icons = False

    def showPopup(self) -> None:
        if not self._have_icons:
            self._have_icons = True
            for index, name in enumerate(PRESET_NAMES, start=1):
                self.setItemIcon(index, _preset_icon(name))
        super().showPopup()


def _one_line(exc: BaseException, path: Path) -> str:
    """The first line of an error, naming the file (io errors already start with it)."""
    text = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
    return text if str(path) in text else f"{path}: {text}"


class TransferFunction1DEditor(QWidget):
    """Histogram, opacity curve, colour bar, presets, value range and file buttons for a 1D TF."""

    #: (title, one-line message) of a failure (a file that cannot be read or written).
    errorOccurred = pyqtSignal(str, str)

    def __init__(self, state: ViewState, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._state = state
        self._shown_tf: TransferFunction | None = None
        self._last_folder = ""
        self._histograms = BackgroundHistogram(self)
        #: (id of the channels, channel) -> a volume of that channel's values
        self._channel_volumes: dict[tuple[int, int], Volume] = {}
        self._shown_data: Volume | None = None
        self._histograms.ready.connect(self._histogram_ready)
        self._build()
        self._unsubscribe = subscribe_while_alive(state, self, "_on_state_change")
        self._set_volume()
        self.refresh()

    # ------------------------------------------------------------------ construction
    def _build(self) -> None:
        self.curve = OpacityCurve(self._state, self)
        self.color_bar = ColorBar(self._state, self)

        self.preset_box = PresetBox(self)
        self.preset_box.setToolTip("Replace the colours with a colour map over the current value range")
        self.preset_box.currentIndexChanged.connect(self._on_preset_chosen)
        self.tissue_box = QComboBox(self)
        self.tissue_box.setSizeAdjustPolicy(
            QComboBox.AdjustToMinimumContentsLength
        )  # names are long; the dock is narrow
        self.tissue_box.setMinimumContentsLength(10)
        self.tissue_box.addItem(TISSUE_PLACEHOLDER)
        self.tissue_box.addItems(OPACITY_PRESET_NAMES)
        self.tissue_box.setToolTip("Replace the transfer function with a CT (Hounsfield units) or MR preset")
        self.tissue_box.currentIndexChanged.connect(self._on_tissue_chosen)
        self.shift_slider = QSlider(Qt.Horizontal, self)
        self.shift_slider.setRange(-SHIFT_STEPS, SHIFT_STEPS)
        self.shift_slider.setPageStep(10)
        self.shift_slider.setToolTip(
            "Slide the whole transfer function (colours and opacity) along the value axis"
        )
        self.shift_slider.valueChanged.connect(self._on_shift_moved)
        self.shift_slider.sliderPressed.connect(self._state.begin_interaction)
        self.shift_slider.sliderReleased.connect(self._state.end_interaction)
        self.shift_label = QLabel("0", self)
        self.shift_label.setMinimumWidth(48)
        self._shift_applied = 0.0  # the offset the slider has applied to the TF shown
        self._shifted: tuple[TransferFunction, int] | None = None  # (TF, version) as the slider left it
        self._shifting = False
        self.zoom_tf_button = QToolButton(self)
        self.zoom_tf_button.setText("TF range")
        self.zoom_tf_button.setToolTip("Zoom the histogram and curve to the transfer function's range "
                                       "(the mouse wheel over them zooms about the cursor)")  # fmt: skip
        self.zoom_tf_button.clicked.connect(self.zoom_to_tf_range)
        self.zoom_all_button = QToolButton(self)
        self.zoom_all_button.setText("Whole range")
        self.zoom_all_button.setToolTip("Show the whole range again: the data's and the transfer function's")
        self.zoom_all_button.clicked.connect(self.reset_zoom)
        self._limits = ValueAxis(0.0, 1.0)  # where points may go: the TF's and the data's ranges
        self._zoom: ValueAxis | None = None  # the part of the limits shown, None: all of them
        self._zoom_histogram: tuple[object, ValueAxis, Histogram] | None = None  # (volume, view, bins)
        self._rebin_timer = QTimer(self)
        self._rebin_timer.setSingleShot(True)
        self._rebin_timer.setInterval(REBIN_DELAY_MS)
        self._rebin_timer.timeout.connect(self.update_histogram)
        for canvas in (self.curve, self.color_bar):
            canvas.zoomRequested.connect(self.zoom_about)
        self.preset_browser: PresetBrowser | None = None  # made when first opened

        self.log_check = QCheckBox("Log counts", self)
        self.log_check.setToolTip("Histogram heights as log(1 + count): rare values stay visible")
        self.log_check.setChecked(self.curve.log_counts)
        self.log_check.toggled.connect(self.curve.set_log_counts)

        self.min_spin = self._spin_box("Lowest value of the transfer function (its points are rescaled)")
        self.max_spin = self._spin_box("Highest value of the transfer function (its points are rescaled)")
        self._numbers_shown: tuple[float, float, float] | None = None  # (lo, hi, unit) in the spin boxes
        for spin in (self.min_spin, self.max_spin):  # typed in: show the TF's numbers again next time
            spin.valueChanged.connect(self._forget_numbers)
        self.min_spin.valueChanged.connect(self._on_min_changed)
        self.max_spin.valueChanged.connect(self._on_max_changed)
        self.reset_range_button = QToolButton(self)
        self.reset_range_button.setText("Data range")
        self.reset_range_button.setIcon(self.style().standardIcon(QStyle.SP_BrowserReload))
        self.reset_range_button.setToolTip("Reset to the data range: rescale the transfer function onto it")
        self.reset_range_button.clicked.connect(self.reset_to_data_range)
        self.unit_spin = self._spin_box(
            "Opacity unit distance: the thickness (world units) that the opacities above refer to"
        )
        self.unit_spin.setStepType(QAbstractSpinBox.AdaptiveDecimalStepType)
        self.unit_spin.valueChanged.connect(self._forget_numbers)
        self.unit_spin.valueChanged.connect(self._on_unit_changed)

        self.open_button = QPushButton("Open…", self)
        self.open_button.setToolTip(
            "Open a transfer function: volren JSON (1D or 2D) or a ParaView colour preset"
        )
        self.open_button.clicked.connect(self._open_clicked)
        self.save_button = QPushButton("Save…", self)
        self.save_button.setToolTip("Save the transfer function as volren JSON")
        self.save_button.clicked.connect(self._save_clicked)

        self.message_2d = QLabel(
            "The transfer function is 2D (value and gradient magnitude); edit it in the 2D editor, "
            "or replace it with a 1D one.",
            self,
        )
        self.message_2d.setWordWrap(True)
        self.use_1d_button = QPushButton("Use a 1D transfer function", self)
        self.use_1d_button.clicked.connect(self.use_1d_transfer_function)

        self.point_entry = PointEntry(self.curve, self)
        self.color_entry = ColorEntry(self.color_bar, self)
        self.pages = QStackedWidget(self)
        self.page_1d = QWidget(self.pages)
        one = QVBoxLayout(self.page_1d)
        one.setContentsMargins(0, 0, 0, 0)
        one.setSpacing(2)
        top = QHBoxLayout()
        top.addWidget(self.preset_box, 1)
        top.addWidget(self.tissue_box, 1)
        one.addLayout(top)
        shift = QHBoxLayout()
        shift.addWidget(QLabel("Shift", self.page_1d))
        shift.addWidget(self.shift_slider, 1)
        shift.addWidget(self.shift_label)
        one.addLayout(shift)
        view = QHBoxLayout()
        view.addWidget(QLabel("View", self.page_1d))
        view.addWidget(self.zoom_tf_button)
        view.addWidget(self.zoom_all_button)
        view.addStretch(1)
        one.addLayout(view)
        one.addWidget(self.curve, 1)
        one.addWidget(self.color_bar)
        one.addWidget(self.color_entry)
        one.addWidget(self.point_entry)
        value_range = QHBoxLayout()
        value_range.addWidget(QLabel("Range", self.page_1d))
        value_range.addWidget(self.min_spin, 1)
        value_range.addWidget(QLabel("to", self.page_1d))
        value_range.addWidget(self.max_spin, 1)
        value_range.addWidget(self.reset_range_button)
        one.addLayout(value_range)
        unit = QHBoxLayout()
        unit.addWidget(QLabel("Unit distance", self.page_1d))
        unit.addWidget(self.unit_spin, 1)
        one.addLayout(unit)
        self.page_2d = QWidget(self.pages)
        two = QVBoxLayout(self.page_2d)
        two.addWidget(self.message_2d)
        two.addWidget(self.use_1d_button)
        two.addStretch(1)
        self.pages.addWidget(self.page_1d)
        self.pages.addWidget(self.page_2d)

        files = QHBoxLayout()  # with the histogram's log switch: the View row has no room for it
        files.addWidget(self.log_check)
        files.addStretch(1)
        files.addWidget(self.open_button)
        files.addWidget(self.save_button)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(4, 4, 4, 4)
        layout.addWidget(self.pages, 1)
        layout.addLayout(files)

    def _spin_box(self, tip: str) -> QDoubleSpinBox:
        spin = QDoubleSpinBox(self)
        spin.setMinimumWidth(60)  # the hint fits the widest allowed value; the panel must fit ~300 px
        spin.setKeyboardTracking(False)  # apply on Enter, focus loss or a step, not per keystroke
        spin.setToolTip(tip)
        return spin

    # ------------------------------------------------------------------ following the state
    def _on_state_change(self, change: Change) -> None:
        if change.what == "volume":
            self._set_volume()
            self.refresh()
        elif change.what == "tf" or (change.what == "interaction" and not change.interactive):
            if self.data_volume() is not self._shown_data:  # another channel selected: its histogram
                self._set_volume()
            self.refresh()

    def data_volume(self) -> Volume | None:
        """The field the edited TF classifies: the volume's, or with channels the selected channel's
        (a volume of its values, made once per channel), whose histogram and range are shown."""
        volume, channels = self._state.volume, self._state.channels
        if channels is None or volume is None:
            self._channel_volumes.clear()
            return volume
        key = (id(channels), self._state.selected_channel)
        found = self._channel_volumes.get(key)
        if found is None:
            if any(k[0] != key[0] for k in self._channel_volumes):
                self._channel_volumes.clear()  # another volume's channels
            c = key[1]
            found = UniformVolume(channels.values[c], volume.spacing, volume.origin,  # type: ignore[union-attr]
                                  name=f"{volume.name} {channels.names[c]}")  # fmt: skip
            self._channel_volumes[key] = found
        return found

    def _set_volume(self) -> None:
        volume = self.data_volume()
        self._shown_data = volume
        self._zoom = None  # another data range: start from all of it
        self._zoom_histogram = None
        self._rebin_timer.stop()
        self.curve.set_histogram(None if volume is None else self._histograms.request(volume))
        self._refresh_tissue_presets(volume)

    def _histogram_ready(self, volume: Volume, histogram: Histogram) -> None:
        """A large volume's histogram, computed in the background (`BackgroundHistogram`), shown
        unless another volume or a zoomed view came meanwhile."""
        if volume is self.data_volume() and self._zoom is None:
            self.curve.set_histogram(histogram)

    def _refresh_tissue_presets(self, volume) -> None:
        """Presets that do not fit the data (CT ones on non-CT values) disabled, saying why."""
        model = self.tissue_box.model()
        for index, name in enumerate(OPACITY_PRESET_NAMES, start=1):
            problem = "Open a volume first" if volume is None else preset_problem(name, volume)
            item = model.item(index)
            item.setEnabled(problem is None)
            item.setToolTip(problem or "")

    def transfer_function(self) -> TransferFunction1D | None:
        """The state's TF when it is 1D (what this panel edits), else None."""
        tf = self._state.transfer_function
        return tf if isinstance(tf, TransferFunction1D) else None

    def refresh(self) -> None:
        """Show the state's TF as it is now (it may be another object than last time)."""
        tf = self._state.transfer_function
        volume = self.data_volume()
        replaced = tf is not self._shown_tf
        self._shown_tf = tf
        if not self._shifting and not self._left_by_slider(tf):  # edited otherwise: the slider starts again
            self._show_shift(0.0)
        self.shift_slider.setEnabled(volume is not None and volume.value_range[1] > volume.value_range[0])
        if replaced:
            self.curve.selected = self.color_bar.selected = None
        is_2d = tf is not None and tf.dims == 2
        self.pages.setCurrentWidget(self.page_2d if is_2d else self.page_1d)
        self.use_1d_button.setEnabled(volume is not None)
        self.page_1d.setEnabled(isinstance(tf, TransferFunction1D))
        self.save_button.setEnabled(tf is not None)
        self.reset_range_button.setEnabled(
            volume is not None and volume.value_range[1] > volume.value_range[0]
        )
        tf1 = self.transfer_function()
        if tf1 is not None:
            if replaced or not self._state.interacting:
                ranges = [tf1.value_range] + ([volume.value_range] if volume is not None else [])
                self._limits = ValueAxis.spanning(*ranges)
                self._set_view(None if self._zoom is None else self._zoom.within(self._limits))
            self._show_numbers(tf1)
        self.zoom_tf_button.setEnabled(tf1 is not None)
        self.curve.model_changed()
        self.color_bar.model_changed()
        self.point_entry.refresh()
        self.color_entry.refresh()

    def _forget_numbers(self) -> None:
        self._numbers_shown = None

    def _show_numbers(self, tf: TransferFunction1D) -> None:
        """The range and unit distance in their spin boxes; skipped when they are what is shown
        already (a point dragged inside the range changes neither, and setting the spin boxes'
        decimals and ranges relaid them out on every edit of the drag)."""
        shown = (*tf.value_range, tf.opacity_unit_distance)
        if shown == self._numbers_shown:
            return
        self._numbers_shown = shown
        lo, hi = tf.value_range
        span = hi - lo if hi > lo else max(abs(lo), 1.0)
        bound = 1e3 * max(abs(lo), abs(hi), span)
        decimals = _decimals(span)
        for spin, value in ((self.min_spin, lo), (self.max_spin, hi)):
            spin.blockSignals(True)
            spin.setDecimals(decimals)
            spin.setRange(-bound, bound)
            spin.setSingleStep(span / 100)
            spin.setValue(value)
            spin.blockSignals(False)
        unit = tf.opacity_unit_distance
        decimals = _decimals(unit)
        self.unit_spin.blockSignals(True)
        self.unit_spin.setDecimals(decimals)
        self.unit_spin.setRange(10.0**-decimals, 1e4 * max(unit, 1.0))
        self.unit_spin.setValue(unit)
        self.unit_spin.blockSignals(False)

    # ------------------------------------------------------------------ public operations
    def point_positions(self) -> list[QPoint]:
        """Opacity point centres in `self.curve`'s pixels (for scripted gestures)."""
        return self.curve.point_positions()

    def stop_positions(self) -> list[QPoint]:
        """Colour stop markers in `self.color_bar`'s pixels."""
        return self.color_bar.stop_positions()

    def apply_preset(self, name: str) -> None:
        """Replace the colours with the named colour map over the TF's range; opacity stays."""
        tf = self.transfer_function()
        if tf is not None:
            apply_preset(tf, name)

    # ------------------------------------------------------------------ the view (zoom)
    @property
    def view(self) -> ValueAxis:
        """The values the histogram, curve and colour bar show now."""
        return self.curve.axis

    def zoom_to(self, lo: float, hi: float) -> None:
        """Show [lo, hi] (the part inside the limits); all of the limits when that is all of them."""
        if math.isfinite(lo) and math.isfinite(hi) and hi > lo:
            self._set_view(ValueAxis(float(lo), float(hi)).within(self._limits))

    def zoom_to_tf_range(self) -> None:
        """Show just the TF's value range."""
        tf = self.transfer_function()
        if tf is not None:
            self.zoom_to(*tf.value_range)

    def zoom_about(self, center: float, factor: float) -> None:
        """Scale the view's span by `factor` about `center` (a wheel notch: `ZOOM_STEP`)."""
        if self.transfer_function() is not None and math.isfinite(center) and factor > 0:
            self._set_view(self.view.zoomed(center, factor, self._limits))

    def reset_zoom(self) -> None:
        """Show all of the limits again (the TF's and the data's ranges)."""
        self._set_view(None)

    def _set_view(self, zoom: ValueAxis | None) -> None:
        changed = zoom != self._zoom or self.curve.limits != self._limits
        self._zoom = zoom
        view = self._limits if zoom is None else zoom
        self.curve.set_axis(view, self._limits)
        self.color_bar.set_axis(view, self._limits)
        self.zoom_all_button.setEnabled(zoom is not None)
        if changed:
            self._show_histogram_for(view)

    def _show_histogram_for(self, view: ValueAxis) -> None:
        """The histogram for a new view: one that covers it at once, finer bins once it rests."""
        volume = self.data_volume()
        if volume is None:
            return
        if self._zoom is None:
            self._rebin_timer.stop()
            self.curve.set_histogram(self._histograms.request(volume))
            return
        shown = self.curve.histogram
        if shown is None or not shown.edges[0] <= view.lo or not view.hi <= shown.edges[-1]:
            self.curve.set_histogram(self._histograms.request(volume))  # coarse, but all there meanwhile
        self._rebin_timer.start()

    def update_histogram(self) -> None:
        """The histogram over the view: the volume's (cached) unzoomed, else binned over the view."""
        self._rebin_timer.stop()
        volume = self.data_volume()
        if volume is None:
            self.curve.set_histogram(None)
            return
        view = self._zoom
        if view is None:
            self.curve.set_histogram(self._histograms.request(volume))
            return
        cached = self._zoom_histogram
        if cached is None or cached[0] is not volume or cached[1] != view:
            histogram = compute_histogram(volume.values, DEFAULT_BINS, (view.lo, view.hi))
            cached = self._zoom_histogram = (volume, view, histogram)
        self.curve.set_histogram(cached[2])

    def open_preset_browser(self) -> PresetBrowser:
        """Show the colour-map browser (window-modal, not blocking); OK or a double-click applies
        the chosen map to the TF's colours over its range, Cancel changes nothing."""
        if self.preset_browser is None:
            self.preset_browser = PresetBrowser(self)
            self.preset_browser.accepted.connect(self._on_browser_accepted)
        self.preset_browser.reset()
        self.preset_browser.open()
        self.preset_browser.search.setFocus()
        return self.preset_browser

    def _on_browser_accepted(self) -> None:
        name = self.preset_browser.chosen() if self.preset_browser is not None else None
        if name is not None:
            self.apply_preset(name)

    def apply_tissue_preset(self, name: str) -> bool:
        """Replace the TF with the tissue preset `name` for this volume; False (and errorOccurred)
        when it does not fit the data."""
        volume = self._state.volume
        if volume is None:
            return False
        try:
            tf = preset_transfer_function(name, volume)
        except VolrenError as exc:
            self.errorOccurred.emit("Cannot apply the preset", str(exc))
            return False
        self._state.set_transfer_function(tf)
        return True

    def shift_step(self) -> float:
        """The value one step of the shift slider moves the TF: a thousandth of the data range."""
        volume = self.data_volume()
        if volume is None:
            return 0.0
        lo, hi = volume.value_range
        return (hi - lo) * SHIFT_STEP

    def shift_to(self, offset: float) -> None:
        """Slide the TF so that it lies `offset` from where it was when the slider was last at 0
        (the preset, or the TF as last edited otherwise): colours and opacity together."""
        tf = self.transfer_function()
        if tf is None or not math.isfinite(offset):
            return
        move = offset - self._shift_applied
        if move:
            lo, hi = tf.value_range
            self._shifting = True
            try:
                tf.rescale(lo + move, hi + move)  # a translation: the same span
            finally:
                self._shifting = False
        self._shifted = (tf, tf.version)
        self._show_shift(offset)

    def _left_by_slider(self, tf: TransferFunction | None) -> bool:
        """Whether `tf` is as the shift slider last left it (no edit since)."""
        return (
            tf is not None
            and self._shifted is not None
            and self._shifted[0] is tf
            and self._shifted[1] == tf.version
        )

    def _show_shift(self, offset: float) -> None:
        self._shift_applied = offset
        step = self.shift_step()
        self.shift_slider.blockSignals(True)
        self.shift_slider.setValue(round(offset / step) if step > 0 else 0)
        self.shift_slider.blockSignals(False)
        self.shift_label.setText(f"{offset:+.4g}" if offset else "0")

    def set_value_range(self, lo: float, hi: float) -> bool:
        """Rescale the TF's points onto [lo, hi]; refused (False) unless lo < hi."""
        tf = self.transfer_function()
        if tf is None or not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            self.refresh()  # put the boxes back
            return False
        if (lo, hi) != tf.value_range:
            tf.rescale(lo, hi)
        return True

    def reset_to_data_range(self) -> None:
        volume = self.data_volume()
        if volume is not None:
            self.set_value_range(*volume.value_range)

    def use_1d_transfer_function(self) -> None:
        """Replace the TF (a 2D one) with the 1D TF it replaced for this volume (the user's work),
        or the volume's default 1D TF."""
        volume = self._state.volume
        if volume is None:
            return
        from volren.api import default_transfer_function

        previous = self._state.replaced_transfer_function(1)
        self._state.set_transfer_function(
            previous if previous is not None else default_transfer_function(volume)
        )

    def open_file(self, path: str | Path) -> bool:
        """Put the TF in `path` into the state; False (and errorOccurred) if it cannot be read.

        volren JSON (1D or 2D) is used as it is. A ParaView preset is a colour map: its colours
        are spread over the current TF's range (or the data's) and the opacity is kept, unless
        the preset brings its own opacity ("Points"), which is spread the same way.
        """
        from volren.io.json_text import read_json
        from volren.io.paraview_presets import is_preset_data
        from volren.io.tf_io import tf_from_data

        path = Path(path)
        try:
            data = read_json(path)
            tf = self._from_preset(data, path) if is_preset_data(data) else tf_from_data(data, path)
        except (VolrenError, OSError, ValueError, TypeError, KeyError) as exc:
            self.errorOccurred.emit("Cannot open the transfer function", _one_line(exc, path))
            return False
        self._last_folder = str(path.parent)
        self._state.set_transfer_function(tf)
        return True

    def _from_preset(self, data: Any, path: Path) -> TransferFunction1D:
        from volren.io.paraview_presets import preset_to_tf, select_preset

        preset = select_preset(data, None, path)
        imported = preset_to_tf(preset, path)
        current, volume = self.transfer_function(), self.data_volume()
        colors = imported.color_points
        p0, p1 = colors[0, 0], colors[-1, 0]
        if current is not None:
            lo, hi = current.value_range
        elif volume is not None:
            lo, hi = volume.value_range
        else:
            lo, hi = p0, p1
        scale = (hi - lo) / (p1 - p0) if p1 > p0 else 0.0

        def spread(x: np.ndarray) -> np.ndarray:
            return lo + (x - p0) * scale

        colors[:, 0] = spread(colors[:, 0])
        if current is not None and "Points" not in preset:
            return TransferFunction1D(
                colors, current.opacity_points, current.opacity_unit_distance, current.extra
            )
        opacity = imported.opacity_points
        opacity[:, 0] = spread(opacity[:, 0])
        if current is not None:
            unit = current.opacity_unit_distance
        else:
            unit = volume.characteristic_length if volume is not None else 1.0
        return TransferFunction1D(colors, opacity, unit, imported.extra)

    def save_file(self, path: str | Path) -> bool:
        """Write the state's TF as volren JSON (".json" added when there is no suffix)."""
        from volren.io import save_transfer_function

        tf = self._state.transfer_function
        if tf is None:
            return False
        path = Path(path)
        if not path.suffix:
            path = path.with_suffix(".json")
        try:
            save_transfer_function(tf, path)
        except (VolrenError, OSError) as exc:
            self.errorOccurred.emit("Cannot save the transfer function", _one_line(exc, path))
            return False
        self._last_folder = str(path.parent)
        return True

    # ------------------------------------------------------------------ dialogs (tests replace these)
    def get_open_path(self) -> str | None:
        path, _ = QFileDialog.getOpenFileName(self, "Open transfer function", self._last_folder, TF_FILTER)
        return path or None

    def get_save_path(self) -> str | None:
        start = str(Path(self._last_folder or ".") / "transfer_function.json")
        path, _ = QFileDialog.getSaveFileName(self, "Save transfer function", start, TF_FILTER)
        return path or None

    def detach(self) -> None:
        """Stop following the state (the panel is being thrown away)."""
        self._unsubscribe()

    # ------------------------------------------------------------------ slots
    def _on_preset_chosen(self, index: int) -> None:
        if index <= 0:
            return
        if index == self.preset_box.count() - 1:
            self.open_preset_browser()
        else:
            self.apply_preset(self.preset_box.itemText(index))
        self.preset_box.blockSignals(True)
        self.preset_box.setCurrentIndex(0)  # a menu of actions: choosing the same map again works
        self.preset_box.blockSignals(False)

    def _on_tissue_chosen(self, index: int) -> None:
        if index <= 0:
            return
        self.apply_tissue_preset(self.tissue_box.itemText(index))
        self.tissue_box.blockSignals(True)
        self.tissue_box.setCurrentIndex(0)  # a menu of actions, as the colour maps
        self.tissue_box.blockSignals(False)

    def _on_shift_moved(self, steps: int) -> None:
        self.shift_to(steps * self.shift_step())

    def _on_min_changed(self, value: float) -> None:
        tf = self.transfer_function()
        if tf is not None:
            self.set_value_range(value, tf.value_range[1])

    def _on_max_changed(self, value: float) -> None:
        tf = self.transfer_function()
        if tf is not None:
            self.set_value_range(tf.value_range[0], value)

    def _on_unit_changed(self, value: float) -> None:
        tf = self.transfer_function()
        if tf is not None and value > 0 and value != tf.opacity_unit_distance:
            tf.set_opacity_unit_distance(value)

    def _open_clicked(self) -> None:
        path = self.get_open_path()
        if path:
            self.open_file(path)

    def _save_clicked(self) -> None:
        path = self.get_save_path()
        if path:
            self.save_file(path)
