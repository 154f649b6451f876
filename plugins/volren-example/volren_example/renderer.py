"""`example`: ray marching through a uniform grid in plain numpy, the smallest conformant renderer.

Why it exists: it is the template a plugin author copies. It uses only volren's public contract
(docs/renderer-contract.md): `RendererBase` keeps the state and refuses what the capabilities do
not claim, and this class only turns a camera into an image. It is correct and slow: every ray
is marched at once, one sample depth at a time, with numpy arrays over all rays.

How: each pixel ray is clipped to the grid's box and to the near and far planes, then cut into
segments of the step length (the last one shorter); each segment is sampled at its midpoint,
trilinearly. Composite: segment opacity 1 - (1 - a)^(length / unit distance), composited front to
back. Maximum, minimum and average project the sampled values and draw (c(v) a(v), a(v)). A
sample in a cell with a NaN corner is transparent (trilinear interpolation gives NaN there).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

from volren.model import BlendMode, Camera, UniformVolume
from volren.renderers.base import (
    Accuracy,
    Capabilities,
    KindSupport,
    OptionSpec,
    ProgressCallback,
    QualityLevel,
    RendererBase,
)

#: The contract's opacity clamp.
MAX_OPACITY = 1.0 - 1e-6
#: Sample depths between two progress calls.
PROGRESS_EVERY = 16


class ExampleRenderer(RendererBase):
    """Numpy ray marching through uniform grids: composite, maximum, minimum, average."""

    name: ClassVar[str] = "example"
    capabilities: ClassVar[Capabilities] = Capabilities(
        kinds={
            "uniform": KindSupport(
                blend_modes=frozenset(BlendMode),
                # measured with `volren check-renderer example`: RMSE up to 0.042 (maximum projection:
                # midpoint samples miss the grid points), the point 0.02 px off
                accuracy=Accuracy(rmse=0.05, position_px=0.1),
            )
        },
        backend="cpu",
        summary="plugin template: numpy ray marching with midpoint samples (slow, correct)",
        quality=(QualityLevel("step 2", step=2.0), QualityLevel("step 1", step=1.0),
                 QualityLevel("step 0.5 (default)", step=0.5), QualityLevel("step 0.25", step=0.25)),
    )  # fmt: skip
    #: None. An option is declared here once, e.g. OptionSpec("table_size", 256, "int", "entries", low=16,
    #: high=4096); RendererBase parses and checks settings.options against it and keeps the values in self.opts.
    options: ClassVar[tuple[OptionSpec, ...]] = ()

    def _volume_changed(self) -> None:
        volume = self.volume
        assert isinstance(volume, UniformVolume)
        self._values = np.asarray(volume.values, dtype=np.float64)  # (nz, ny, nx)

    # ------------------------------------------------------------------------- geometry
    def _ray_segments(
        self, camera: Camera, width: int, height: int
    ) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        """Origins and directions (N, 3) of the pixel rays, and where each enters and leaves the
        grid's box between the near and far planes (t0 >= t1 for a ray that misses)."""
        origins, directions = camera.pixel_rays(width, height)
        origins, directions = origins.reshape(-1, 3), directions.reshape(-1, 3)
        bounds = np.asarray(self.volume.bounds, dtype=np.float64)  # type: ignore[union-attr]
        lo, hi = bounds[0::2], bounds[1::2]
        with np.errstate(divide="ignore", invalid="ignore"):
            ta, tb = (lo - origins) / directions, (hi - origins) / directions
        inside = (origins >= lo) & (origins <= hi)
        flat = directions == 0  # a ray parallel to a slab is inside it everywhere or nowhere
        t_in = np.where(flat, np.where(inside, -np.inf, np.inf), np.minimum(ta, tb)).max(axis=1)
        t_out = np.where(flat, np.where(inside, np.inf, -np.inf), np.maximum(ta, tb)).min(axis=1)
        near, far = camera.clipping_range
        t_far = (far - near) / (directions @ camera.direction)
        return origins, directions, np.maximum(t_in, 0.0), np.minimum(t_out, t_far)

    def _sample(self, points: NDArray) -> NDArray:
        """Trilinear interpolation at world points (N, 3); NaN where a corner is NaN."""
        volume = self.volume
        index = (points - np.asarray(volume.origin)) / np.asarray(volume.spacing)  # type: ignore[union-attr]
        dims = np.asarray(volume.dimensions)  # type: ignore[union-attr]
        base = np.clip(np.floor(index), 0, dims - 2).astype(np.intp)
        f = np.clip(index - base, 0.0, 1.0)
        i, j, k = base[:, 0], base[:, 1], base[:, 2]
        fx, fy, fz = f[:, 0], f[:, 1], f[:, 2]
        v = self._values
        out = np.zeros(len(points))
        for dx, wx in ((0, 1 - fx), (1, fx)):
            for dy, wy in ((0, 1 - fy), (1, fy)):
                for dz, wz in ((0, 1 - fz), (1, fz)):
                    out += wx * wy * wz * v[k + dz, j + dy, i + dx]
        return out

    # --------------------------------------------------------------------------- render
    def _render(
        self, camera: Camera, width: int, height: int, progress: ProgressCallback | None
    ) -> tuple[NDArray[np.float32], Mapping[str, float]]:
        origins, directions, t0, t1 = self._ray_segments(camera, width, height)
        length = np.maximum(t1 - t0, 0.0)
        h = self.settings.step * self.volume.characteristic_length  # type: ignore[union-attr]
        counts = np.ceil(length / h).astype(np.int64)
        depth = int(counts.max()) if counts.size else 0
        composite = self.settings.blend_mode is BlendMode.COMPOSITE
        rgba = np.zeros((len(origins), 4))
        transmittance = np.ones(len(origins))
        projected = _Projection(self.settings.blend_mode, len(origins))
        for n in range(depth):
            rays = np.nonzero(counts > n)[0]
            if composite:
                rays = rays[transmittance[rays] > 1e-9]  # early termination: nothing shows through
            seg_start = n * h
            seg_len = np.minimum(h, length[rays] - seg_start)
            t_mid = t0[rays] + seg_start + 0.5 * seg_len
            values = self._sample(origins[rays] + t_mid[:, None] * directions[rays])
            if composite:
                self._composite(rgba, transmittance, rays, values, seg_len)
            else:
                projected.add(rays, values, seg_len)
            if progress is not None and n % PROGRESS_EVERY == PROGRESS_EVERY - 1:
                progress((n + 1) / depth)
        if not composite:
            rgba = projected.rgba(self.transfer_function)
        if progress is not None:
            progress(1.0)
        image = rgba.reshape(height, width, 4).astype(np.float32)
        return image, {"samples": float(counts.sum()), "rays": float(len(origins))}

    def _composite(
        self, rgba: NDArray, transmittance: NDArray, rays: NDArray, values: NDArray, lengths: NDArray
    ) -> None:
        """Front-to-back over: C += T alpha c, T *= 1 - alpha, for one sample depth."""
        rgb, a = self.transfer_function.sample(values)  # type: ignore[union-attr]
        alpha = np.where(np.isnan(values), 0.0, self._segment_opacity(a, lengths))
        weight = transmittance[rays] * alpha
        rgba[rays, :3] += weight[:, None] * np.nan_to_num(rgb)
        rgba[rays, 3] += weight
        transmittance[rays] *= 1.0 - alpha

    def _segment_opacity(self, a: NDArray, lengths: NDArray) -> NDArray:
        """The opacity of a segment: the TF's opacity corrected from its unit distance to the length."""
        unit = self.transfer_function.opacity_unit_distance  # type: ignore[union-attr]
        return 1.0 - (1.0 - np.minimum(np.nan_to_num(a), MAX_OPACITY)) ** (lengths / unit)


class _Projection:
    """Maximum, minimum or length-weighted average of the sampled values along each ray."""

    def __init__(self, mode: BlendMode, rays: int) -> None:
        self.mode = mode
        start = {BlendMode.MAXIMUM: -np.inf, BlendMode.MINIMUM: np.inf}.get(mode, 0.0)
        self.value = np.full(rays, start)
        self.weight = np.zeros(rays)

    def add(self, rays: NDArray, values: NDArray, lengths: NDArray) -> None:
        keep = ~np.isnan(values)
        rays, values, lengths = rays[keep], values[keep], lengths[keep]
        if self.mode is BlendMode.MAXIMUM:
            np.maximum.at(self.value, rays, values)
        elif self.mode is BlendMode.MINIMUM:
            np.minimum.at(self.value, rays, values)
        else:
            np.add.at(self.value, rays, values * lengths)
        np.add.at(self.weight, rays, lengths)

    def rgba(self, tf) -> NDArray:
        hit = self.weight > 0
        value = np.where(hit, self.value, 0.0)
        if self.mode is BlendMode.AVERAGE:
            value = np.where(hit, value / np.where(hit, self.weight, 1.0), 0.0)
        rgb, a = tf.sample(value)
        a = np.where(hit, a, 0.0)
        return np.concatenate([rgb * a[:, None], a[:, None]], axis=1)
