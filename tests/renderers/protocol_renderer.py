"""A renderer that follows the Protocol without subclassing RendererBase: every caller must work
with it (the CLI, the app, the bench), because they rely only on the Protocol."""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar

import numpy as np

from volren.errors import VolrenError
from volren.model.volume import UniformVolume
from volren.renderers.base import (
    Capabilities,
    FrameStats,
    KindSupport,
    OptionSpec,
    QualityLevel,
    option_help_of,
    parse_options,
)


class PlainRenderer:
    """Draws the TF colour at the middle of the value range, half opaque, over the whole image."""

    name: ClassVar[str] = "plain"
    capabilities: ClassVar[Capabilities] = Capabilities(
        kinds={"uniform": KindSupport()},
        quality=(QualityLevel("coarse", step=1.0), QualityLevel("fine", step=0.25)),
    )
    options: ClassVar[tuple[OptionSpec, ...]] = (
        OptionSpec("alpha", 0.5, "float", "the opacity drawn", low=0.0, high=1.0),
    )
    option_help: ClassVar[Mapping[str, str]] = option_help_of(options)

    def __init__(self) -> None:
        self.last_frame: FrameStats | None = None
        self._volume = self._tf = None
        self._alpha = 0.5
        self._released = False

    def _alive(self) -> None:
        if self._released:
            raise VolrenError("renderer plain was released")

    def set_volume(self, volume) -> None:
        self._alive()
        if not isinstance(volume, UniformVolume):
            raise VolrenError("renderer plain does not render tet volumes (only uniform)")
        self._volume = volume

    def set_transfer_function(self, tf) -> None:
        self._alive()
        if tf.dims != 1:
            raise VolrenError("renderer plain does not support 2D transfer functions")
        self._tf = tf

    def set_settings(self, settings) -> None:
        self._alive()
        self._alpha = parse_options(self.name, self.options, settings.options)["alpha"]

    def render(self, camera, width, height, progress=None):
        self._alive()
        lo, hi = self._volume.value_range
        rgb, _ = self._tf.sample(np.array([(lo + hi) / 2]))
        image = np.empty((height, width, 4), np.float32)
        image[..., :3] = rgb[0] * self._alpha
        image[..., 3] = self._alpha
        if progress is not None:
            progress(1.0)
        self.last_frame = FrameStats(1.0, width, height, {"samples": float(width * height)})
        return image

    def release(self) -> None:
        self._released = True
