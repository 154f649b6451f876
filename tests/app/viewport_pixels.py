"""What the viewport shows, read back as pixels: the painted image and where the frame sits in it."""

from __future__ import annotations

import numpy as np
from PyQt5.QtGui import QImage


def grab(viewport) -> np.ndarray:
    """The viewport as painted, (H, W, 3) uint8."""
    image = viewport.grab().toImage().convertToFormat(QImage.Format_RGB888)
    w, h = image.width(), image.height()
    assert (w, h) == (viewport.width(), viewport.height())
    bits = image.constBits()
    bits.setsize(image.byteCount())
    return np.frombuffer(bits, np.uint8).reshape(h, image.bytesPerLine())[:, : 3 * w].reshape(h, w, 3).copy()


def frame_rect(viewport) -> tuple[float, float, float, float]:
    """Where the frame is drawn (x, y, width, height): the largest rectangle of its aspect centred
    in the viewport."""
    frame = viewport.frame
    scale = min(viewport.width() / frame.width, viewport.height() / frame.height)
    w, h = frame.width * scale, frame.height * scale
    return ((viewport.width() - w) / 2.0, (viewport.height() - h) / 2.0, w, h)
