"""What the bytes of a headerless raw file are: shape, sample type, byte order, spacing, header.

Why a dialog: a `.raw` file says nothing about itself, so the Open dialog listed it but could not
open it. As `volren render --raw-shape ...` does on the command line, the user says what
it holds; the dialog proposes a cube that fits the file's size, shows how many bytes the answer
needs against what the file holds, and accepts only an answer that matches exactly.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from PyQt5.QtWidgets import (
    QComboBox,
    QDialog,
    QDialogButtonBox,
    QDoubleSpinBox,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QSpinBox,
    QWidget,
)

#: Sample types offered, smallest first (the guess tries them in this order).
DTYPES = ("uint8", "int8", "uint16", "int16", "uint32", "int32", "float32", "float64")
MAX_SIDE = 65536


def guess_shape(n_bytes: int) -> tuple[str, tuple[int, int, int]] | None:
    """(dtype, cube shape) whose size is exactly `n_bytes`, trying the smallest sample type first."""
    for name in ("uint8", "uint16", "float32", "float64"):
        size = np.dtype(name).itemsize
        if n_bytes % size:
            continue
        side = round((n_bytes // size) ** (1 / 3))
        for n in (side - 1, side, side + 1):
            if n > 0 and n**3 * size == n_bytes:
                return name, (n, n, n)
    return None


class RawDialog(QDialog):
    """Asks for the layout of the raw file `path`; `parameters()` gives `load_volume`'s keywords."""

    def __init__(self, path: str | Path, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.path = Path(path)
        self.file_bytes = self.path.stat().st_size
        self.setWindowTitle(f"Open raw data: {self.path.name}")
        self.shape = [self._spin(1, MAX_SIDE) for _ in range(3)]
        self.dtype = QComboBox(self)
        self.dtype.addItems(DTYPES)
        self.byte_order = QComboBox(self)
        self.byte_order.addItems(["little", "big"])
        self.spacing = [QDoubleSpinBox(self) for _ in range(3)]
        for box in self.spacing:
            box.setDecimals(6)
            box.setRange(1e-6, 1e6)
            box.setValue(1.0)
        self.header = self._spin(0, 2**31 - 1)
        self.header.setValue(0)
        self.check = QLabel(self)
        self.buttons = QDialogButtonBox(QDialogButtonBox.Ok | QDialogButtonBox.Cancel, self)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        guess = guess_shape(self.file_bytes)
        if guess is not None:
            self.dtype.setCurrentText(guess[0])
            for box, n in zip(self.shape, guess[1], strict=True):
                box.setValue(n)
        form = QFormLayout(self)
        form.addRow("Shape (x, y, z)", self._row(self.shape))
        form.addRow("Sample type", self.dtype)
        form.addRow("Byte order", self.byte_order)
        form.addRow("Spacing (x, y, z)", self._row(self.spacing))
        form.addRow("Header bytes", self.header)
        form.addRow(self.check)
        form.addRow(self.buttons)
        for box in (*self.shape, self.header):
            box.valueChanged.connect(self._update)
        self.dtype.currentTextChanged.connect(self._update)
        self._update()

    def _spin(self, lo: int, hi: int) -> QSpinBox:
        box = QSpinBox(self)
        box.setRange(lo, hi)
        return box

    def _row(self, boxes: list) -> QWidget:
        row = QWidget(self)
        layout = QHBoxLayout(row)
        layout.setContentsMargins(0, 0, 0, 0)
        for box in boxes:
            layout.addWidget(box)
        return row

    def needed_bytes(self) -> int:
        nx, ny, nz = (box.value() for box in self.shape)
        return nx * ny * nz * np.dtype(self.dtype.currentText()).itemsize + self.header.value()

    def _update(self) -> None:
        needed = self.needed_bytes()
        fits = needed == self.file_bytes
        self.check.setText(
            f"{needed:,} bytes needed; the file holds {self.file_bytes:,}" + ("" if fits else " (no match)")
        )
        self.buttons.button(QDialogButtonBox.Ok).setEnabled(fits)

    def parameters(self) -> dict[str, Any]:
        """`volren.io.load_volume`'s keywords for this file."""
        return {
            "shape": tuple(box.value() for box in self.shape),
            "dtype": self.dtype.currentText(),
            "byte_order": self.byte_order.currentText(),
            "spacing": tuple(box.value() for box in self.spacing),
            "header_bytes": self.header.value(),
        }
