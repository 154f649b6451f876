"""File > Open Labels and Close Labels: a segmentation drawn over the volume shown.

A label volume (Real-Time Volume Graphics, chapter 16: an object id per voxel, on the volume's
grid) is read off the GUI thread like a volume (`files.load_task.Loader`), with the names and
colours of its labels from a sidecar ``NAME.labels.json`` beside it (`volren.io.label_info`) or a
3D Slicer ``.seg.nrrd`` header. The volume shown then carries the labels and is drawn with a TF
per label over the 1D TF (`ViewState.set_labels`); opening another volume drops them.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from PyQt5.QtCore import QObject
from PyQt5.QtWidgets import QAction, QFileDialog, QMainWindow

from volren.app.core.loading import PathArg
from volren.app.core.state import Change, ViewState
from volren.app.files.load_task import Loader
from volren.draw.labelled import labelled
from volren.io.label_info import load_label_info
from volren.io.label_io import load_labels
from volren.model.default_tf import default_transfer_function
from volren.model.labels import LabelMap, LabelTransferFunction
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume

LABEL_FILTER = (
    "Label volumes (*.seg.nrrd *.nrrd *.nhdr *.nii *.nii.gz *.vti *.vtk *.mha *.mhd);;All files (*)"
)
#: File endings that are one suffix: `NAME.labels.json` is named after NAME without them.
_DOUBLE_SUFFIXES = (".seg.nrrd", ".nii.gz")


def sidecar_path(path: PathArg) -> Path:
    """Where a label volume's names and colours are: ``NAME.labels.json`` beside it."""
    path = Path(path)
    name = path.name
    for suffix in _DOUBLE_SUFFIXES:
        if name.lower().endswith(suffix):
            return path.with_name(name[: -len(suffix)] + ".labels.json")
    return path.with_name(path.stem + ".labels.json")


def read_labels(
    path: PathArg, volume: UniformVolume, tf: TransferFunction1D
) -> tuple[LabelMap, LabelTransferFunction]:
    """The label map in `path` on `volume`'s grid, and its TF per label over `tf` (the sidecar's
    styles over `LabelTransferFunction.for_labels`); every error is one line naming a file."""
    label_map = load_labels(Path(path), volume)
    sidecar = sidecar_path(path)
    info = load_label_info(sidecar) if sidecar.is_file() else None
    shown, label_tf = labelled(volume, tf, labels=label_map, info=info)
    assert shown.labels is not None
    return shown.labels, label_tf


def _load(path: PathArg, inputs: Any, _scalars: object = None) -> tuple[LabelMap, LabelTransferFunction]:
    """`read_labels` as the `Loader` calls it: (path, (volume, tf), scalars)."""
    volume, tf = inputs
    return read_labels(path, volume, tf)


class LabelActions(QObject):
    """Open Labels (in the background, cancelled by the next) and Close Labels."""

    def __init__(self, window: QMainWindow, state: ViewState, report_error: Callable[[str, str], None],
                 folder: Callable[[], str] = lambda: "") -> None:  # fmt: skip
        """`folder`: where the file dialog opens (the folder last used)."""
        super().__init__(window)
        self._window = window
        self._state = state
        self._report_error = report_error
        self._folder = folder
        self.loader = Loader(self, _load)  # type: ignore[arg-type]  # its results are passed on as they are
        self.loader.loaded.connect(self._on_loaded)
        self.loader.failed.connect(lambda message, _context: report_error("Cannot open labels", message))
        self.open_action = QAction("Open &Labels…", window)
        self.open_action.triggered.connect(self._open_dialog)
        self.open_action.setToolTip("Draw a segmentation of the volume shown, a transfer function per label")
        self.close_action = QAction("Close La&bels", window)
        self.close_action.triggered.connect(self.close_labels)
        self.close_action.setToolTip("Draw the volume without its labels")
        self._unsubscribe = state.subscribe(self._on_change)
        self._on_change(Change("volume"))

    def _on_change(self, change: Change) -> None:
        if change.what != "volume":
            return
        volume = self._state.volume  # labels or channels, not both at once yet
        self.open_action.setEnabled(isinstance(volume, UniformVolume) and volume.channels is None)
        self.close_action.setEnabled(self._state.labels is not None)

    def open_labels(self, path: PathArg) -> bool:
        """Read the segmentation in `path` in the background; it is shown when read. False (and a
        one-line error) when no uniform volume is shown."""
        volume, tf = self._state.volume, self._state.base_transfer_function
        if not isinstance(volume, UniformVolume):
            self._report_error("Cannot open labels", f"{path}: labels need a uniform volume: open one first")
            return False
        if volume.channels is not None:
            self._report_error("Cannot open labels", f"{path}: a volume is drawn with labels or with channels, "
                               "not both at once yet")  # fmt: skip
            return False
        base = tf.copy() if isinstance(tf, TransferFunction1D) else default_transfer_function(volume)
        self._status(f"Reading labels {Path(path).name}…", 0)
        self.loader.start(path, (volume, base), context={"path": str(path), "volume": volume})  # type: ignore[arg-type]
        return True

    def _on_loaded(self, result: tuple[LabelMap, LabelTransferFunction], context: dict[str, Any]) -> None:
        label_map, label_tf = result
        if context["volume"] is not self._state.volume:  # another volume came meanwhile
            return
        path = str(Path(context["path"]).absolute())
        self._state.set_labels(label_map, label_tf, path)
        count = len([label for label in label_map.present if label != 0])
        self._status(f"{count} labels from {Path(path).name}", 5000)

    def _status(self, text: str, ms: int) -> None:
        bar = self._window.statusBar()
        if bar is not None:
            bar.showMessage(text, ms)

    def close_labels(self) -> None:
        """Draw the volume without labels."""
        if self._state.labels is not None:
            self._state.set_labels(None)

    def _open_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(
            self._window, "Open a label volume", self._folder(), LABEL_FILTER
        )
        if path:
            self.open_labels(path)

    def shutdown(self, timeout_ms: int = 5000) -> None:
        self._unsubscribe()
        self.loader.shutdown(timeout_ms)
