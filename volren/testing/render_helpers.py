"""Shared set-up for renderer tests: one smooth test field, the transfer functions the renderer
suites compare on, and a render call that checks what the contract promises of every image.

Why one place: the ray caster and the plugins' renderers are tested against the same samples
(docs/renderer-contract.md), so their suites must draw the same field through the same TFs; a
copy per suite would let them drift apart unnoticed.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

from volren.model import Camera, RenderSettings, TransferFunction1D, UniformVolume
from volren.renderers.base import Renderer
from volren.testing import oracles
from volren.testing.checks import clipped_camera
from volren.testing.metrics import image_error

R = TypeVar("R", bound=Renderer)

#: Smooth colour and opacity over the whole range of `field`: every sample contributes.
SMOOTH_TF = TransferFunction1D([[-2, 0.2, 0.3, 1.0], [4, 1.0, 0.8, 0.1]], [[-1, 0.0], [4, 0.6]], 1.5)
#: Opacity zero below 1.37 and above 2.23: much of `field` is transparent (breakpoints off the data),
#: so empty-space skipping has something to skip.
SHELL_TF = TransferFunction1D(
    [[-2, 1, 0.5, 0.2], [4, 0.3, 0.6, 1.0]], [[1.37, 0.0], [1.61, 0.7], [2.23, 0.0]], 1.0
)


def field(
    shape: Sequence[int] = (14, 16, 18), spacing: tuple[float, float, float] = (1.0, 1.0, 1.0)
) -> UniformVolume:
    """A smooth, nowhere-constant scalar field (z, y, x order `shape`) with values in about [-2, 4]."""
    z, y, x = np.mgrid[0 : shape[0], 0 : shape[1], 0 : shape[2]]
    values = np.sin(x / 3.0) + np.cos(y / 4.0) + z / 8.0
    return UniformVolume(values.astype(np.float32), spacing=spacing)


def assert_valid_image(image: NDArray) -> None:
    """The contract's image: float32, finite, in [0, 1], colour premultiplied (rgb <= alpha)."""
    assert image.dtype == np.float32 and np.all(np.isfinite(image))
    assert image.min() >= 0 and image.max() <= 1 and np.all(image[..., :3] <= image[..., 3:4] + 1e-6)


def render_checked(
    make_renderer: Callable[[], R],
    volume: UniformVolume,
    tf: TransferFunction1D,
    camera: Camera,
    size: tuple[int, int] = (40, 32),
    **settings: Any,
) -> tuple[NDArray[np.float32], R]:
    """Render `volume` with a fresh renderer and `RenderSettings(**settings)`; check the image
    (`assert_valid_image`) and return it with the renderer (for its counters and last frame)."""
    renderer = make_renderer()
    renderer.set_volume(volume)
    renderer.set_transfer_function(tf)
    renderer.set_settings(RenderSettings(**settings))
    image = renderer.render(camera, *size)
    assert_valid_image(image)
    return image, renderer


#: Clipping planes cutting `clipped_constant_box`: near only, far only, both (fractions of its depth).
CLIPPING_PLANES = ((0.3, None), (None, 0.6), (0.2, 0.65))

ClipCase = tuple[float | None, float | None, Camera, NDArray[np.float64]]


def clipped_constant_box(
    parallel: bool, size: int = 40
) -> tuple[UniformVolume, TransferFunction1D, list[ClipCase]]:
    """A constant box and TF whose image has a closed form (1 - (1 - a)^(L / d_u), L the path
    length), and for each of `CLIPPING_PLANES` (near, far, the camera they cut, its closed-form
    `size` x `size` image); each image differs from the uncut one, so the planes matter."""
    volume = UniformVolume(
        np.full((6, 7, 8), 1.0, np.float32), spacing=(0.9, 1.1, 1.0), origin=(0.5, -1.0, 2.0)
    )
    tf = TransferFunction1D.constant(0.15, (0.4, 0.7, 0.2), opacity_unit_distance=0.7)
    camera = Camera.orbit(volume.bounds, 35, -20, zoom=1.3, parallel=parallel)

    def closed_form(view: Camera) -> NDArray[np.float64]:
        lengths = oracles.box_path_lengths(view, size, size, volume.bounds)
        return oracles.homogeneous_image(lengths, (0.4, 0.7, 0.2), 0.15, 0.7)

    whole = closed_form(camera)
    cases: list[ClipCase] = []
    for near, far in CLIPPING_PLANES:
        clipped = clipped_camera(camera, volume.bounds, near, far)
        expected = closed_form(clipped)
        assert image_error(expected, whole).rmse > 0.03  # the planes matter
        cases.append((near, far, clipped, expected))
    return volume, tf, cases


def ramp_maximum_on_cut(
    camera: Camera,
    width: int,
    height: int,
    bounds: Sequence[float],
    half_spaces: NDArray[np.float64],
    tf: TransferFunction1D,
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """(expected image, pixels to compare) of a maximum projection of s = x + y / 2 over each
    ray's kept part (`oracles.pixel_kept_intervals`): s is linear along a ray, so its maximum
    lies at an end of the kept interval; the pixels compared leave out those at the edge of the
    kept region (`oracles.at_an_edge`). Asserts that both hit and missed rays are many."""
    origins, directions, t0, t1, _ = oracles.pixel_kept_intervals(camera, width, height, bounds, half_spaces)
    hit = t1 > t0 + 1e-6
    ends = [origins + t[..., None] * directions for t in (t0, t1)]
    peak = np.maximum(*(p[..., 0] + 0.5 * p[..., 1] for p in ends))
    expected = np.where(hit[..., None], oracles.projection_rgba(tf, np.where(hit, peak, 0.0)), 0.0)
    assert hit.sum() > 200 and (~hit).sum() > 200
    return expected, ~oracles.at_an_edge(hit)
