"""The shear-warp plugin under a clip region (`RenderSettings.clip`: oblique planes and a crop box):
each intermediate ray keeps an interval of slices (`Factorization.region_limits`), its cut segments
sampled at the cut and corrected to their kept part, so the composited image is the closed form of
every intermediate ray (what is left is the final warp's, the same as for an uncut volume), and
moving a plane redoes none of what serves the TF, the volume and the step."""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest
from volren_shearwarp import ShearWarpRenderer
from volren_shearwarp.factorization import Factorization, factorize

from volren.model import Camera, RenderSettings, TransferFunction1D, UniformVolume
from volren.model.clip_region import ClipPlane, ClipRegion
from volren.testing import image_error, oracles
from volren.testing.render_helpers import SMOOTH_TF, clipped_constant_box, field, render_checked
from volren.testing.scenes import lattice_volume

draw = partial(render_checked, ShearWarpRenderer)
RGB, OPACITY, UNIT = (0.4, 0.7, 0.2), 0.3, 0.8
CONSTANT_TF = TransferFunction1D.constant(OPACITY, RGB, opacity_unit_distance=UNIT)


def _region(bounds: tuple[float, ...]) -> ClipRegion:
    """Two oblique planes (a wedge) and a crop box that takes a slab off the top."""
    lo, hi = np.asarray(bounds[0::2]), np.asarray(bounds[1::2])
    centre = (lo + hi) / 2
    planes = (
        ClipPlane(tuple(centre), (-1.0, 0.3, 0.4)),
        ClipPlane(tuple(centre - 0.2 * (hi - lo)), (0.3, 1.0, 0.2)),
    )
    return ClipRegion(planes, (lo[0], hi[0], lo[1], hi[1], lo[2], centre[2] + 1.0))


def _intermediate_rays(fac: Factorization, volume: UniformVolume, rows: np.ndarray):
    """(entry, exit) world points per intermediate pixel of the kept part of its ray (float64: the
    line through its points on the front and back slices, cut by the box and every half-space
    row), and whether it keeps anything."""
    perm = list(fac.perm)
    q, p = np.mgrid[0 : fac.height, 0 : fac.width].astype(np.float64)

    def world(k: int) -> np.ndarray:
        index = np.empty(q.shape + (3,))
        index[..., perm[0]] = fac.alpha_a[k] + fac.beta_a[k] * p
        index[..., perm[1]] = fac.alpha_b[k] + fac.beta_b[k] * q
        index[..., perm[2]] = k
        return np.asarray(volume.origin) + index * np.asarray(volume.spacing)

    front, back = world(int(fac.order[0])), world(int(fac.order[-1]))
    d = back - front
    lo, hi = np.asarray(volume.bounds[0::2]), np.asarray(volume.bounds[1::2])
    inside = (front >= lo) & (front <= hi)
    with np.errstate(divide="ignore", invalid="ignore"):
        ta, tb = (lo - front) / d, (hi - front) / d
    s0 = np.maximum(np.where(d == 0, np.where(inside, -np.inf, np.inf), np.minimum(ta, tb)).max(-1), 0.0)
    s1 = np.minimum(np.where(d == 0, np.where(inside, np.inf, -np.inf), np.maximum(ta, tb)).min(-1), 1.0)
    for a, b, c, e in rows:
        f, g = front @ (a, b, c) + e, d @ (a, b, c)
        with np.errstate(divide="ignore", invalid="ignore"):
            cross = -f / g
        s0 = np.where(g > 0, np.maximum(s0, cross), s0)
        s1 = np.where(g < 0, np.minimum(s1, cross), np.where((g == 0) & (f < 0), -np.inf, s1))
    return front + s0[..., None] * d, front + s1[..., None] * d, s1 > s0


def _factorization(renderer: ShearWarpRenderer, camera: Camera, size: tuple[int, int]) -> Factorization:
    """The renderer's factorization of its last frame (oversampling given in its options)."""
    volume = renderer.volume
    assert isinstance(volume, UniformVolume)
    opts = renderer.opts
    return factorize(camera, volume, *size, opts["oversampling"], min_scale=opts["pixels_per_voxel"])


@pytest.mark.parametrize(("settings", "stride"), [
    ({}, 1), ({"preintegration": False}, 1), ({"step": 0.25}, 1), ({"step": 1.5, "preintegration": False}, 2),
    ({"step": 2.0}, 3), ({"jitter": True}, 1), ({"options": {"lookup": "bilinear", "early_termination": False}}, 1),
])  # fmt: skip
def test_the_composited_cut_is_each_intermediate_rays_closed_form(settings, stride):
    """A constant box cut by a wedge and a crop box, parallel: the image is, to float32 precision, the
    final warp of the intermediate image whose pixels are 1 - (1 - a)^(L / d_u), L each intermediate
    ray's length in the kept region; so the cut is flat (no staircase of slices), also with
    sub-planes, skipped slices (steps 1.5 and 2: every second and third of 6 slices, a short last
    slab) and jittered samples, and the
    distance to the closed form of the output rays is the warp's, as for an uncut box."""
    volume = UniformVolume(
        np.full((6, 7, 8), 1.0, np.float32), spacing=(0.9, 1.1, 1.0), origin=(0.5, -1.0, 2.0)
    )
    camera = Camera.orbit(volume.bounds, 35, -20, zoom=1.3, parallel=True)
    region = _region(volume.bounds)
    size = (40, 36)
    settings = dict(settings)
    options = {"oversampling": 1.5, **settings.pop("options", {})}
    image, renderer = draw(volume, CONSTANT_TF, camera, size, clip=region, options=options, **settings)
    assert renderer.last_frame.counters["slice_stride"] == stride
    fac = _factorization(renderer, camera, size)
    entry, exit_, hit = _intermediate_rays(fac, volume, region.half_spaces())
    lengths = np.where(hit, np.linalg.norm(exit_ - entry, axis=-1), 0.0)
    exact = oracles.homogeneous_image(lengths, RGB, OPACITY, UNIT).astype(np.float32)
    warped = ShearWarpRenderer._warp(np.ascontiguousarray(exact), fac, *size, renderer.opts)
    uncut = oracles.homogeneous_image(
        oracles.box_path_lengths(camera, *size, volume.bounds), RGB, OPACITY, UNIT
    )
    closed = oracles.homogeneous_image(
        oracles.box_path_lengths(camera, *size, volume.bounds, region.half_spaces()), RGB, OPACITY, UNIT
    )
    assert image_error(closed, uncut).rmse > 0.03  # the cut shows
    assert np.abs(image - warped).max() < 1e-5
    assert image_error(image, closed).rmse < 0.01


@pytest.mark.parametrize("parallel", [True, False])
def test_the_near_and_far_planes_and_a_clip_region_cut_together(parallel):
    """A camera whose near or far plane cuts the box, and a clip region: both narrow each ray, to the
    closed form of the output rays up to the warp's blur of the kinks and slivers they leave, which
    falls with the intermediate pixels per output pixel (RMSE up to 0.0082 at 1, 0.0036 at 2, 0.0015
    at 4: four intermediate pixels per output pixel here)."""
    volume, tf, cases = clipped_constant_box(parallel)
    region = _region(volume.bounds)
    for near, far, clipped, _ in cases:
        image, renderer = draw(volume, tf, clipped, (40, 40), clip=region, options={"oversampling": 4.0})
        lengths = oracles.box_path_lengths(clipped, 40, 40, volume.bounds, region.half_spaces())
        expected = oracles.homogeneous_image(lengths, (0.4, 0.7, 0.2), 0.15, 0.7)
        assert renderer.last_frame.counters["clipped"] == 1.0
        assert image_error(image, expected).rmse < 0.002, (near, far)


def test_a_maximum_projection_of_a_ramp_peaks_exactly_on_the_cut():
    """s = x + 0.5 y is linear along every intermediate ray, so its maximum over the kept part lies at
    one of the kept interval's ends: the image is the warp of those values' colours, to float32
    precision, except beside pixels whose ray grazes the kept region."""
    volume = lattice_volume(
        "uniform", lambda x, y, z: x + 0.5 * y, (9, 8, 7), (0.8, 1.0, 1.2), (-1.0, 0.5, 2.0)
    )
    region = _region(volume.bounds)
    tf = TransferFunction1D([[-2, 0, 0, 0], [12, 1, 1, 1]], [[-2, 0.2], [12, 1.0]], 1.0)
    camera = Camera.orbit(volume.bounds, 35, 25, zoom=1.2, parallel=True)
    size = (36, 36)
    image, renderer = draw(
        volume, tf, camera, size, blend_mode="maximum", clip=region, options={"oversampling": 1.0}
    )
    fac = _factorization(renderer, camera, size)
    entry, exit_, hit = _intermediate_rays(fac, volume, region.half_spaces())
    peak = np.maximum(entry[..., 0] + 0.5 * entry[..., 1], exit_[..., 0] + 0.5 * exit_[..., 1])
    exact = np.where(hit[..., None], oracles.projection_rgba(tf, np.where(hit, peak, 0.0)), 0.0)
    warped = ShearWarpRenderer._warp(np.ascontiguousarray(exact, dtype=np.float32), fac, *size, renderer.opts)
    assert hit.sum() > 200 and (~hit).sum() > 200
    assert np.abs(image - warped).max() < 1e-4


def test_moving_a_plane_keeps_the_stride_the_tables_and_the_runs():
    """A drag moves a plane every frame: the slice stride of a draft step (its segments' length, so
    its tables), the table pool and the runs of visible blocks serve the TF, the volume and the step,
    and are what an uncut frame uses, neither rebuilt nor redone."""
    volume = field((16, 18, 20))
    renderer = ShearWarpRenderer()
    renderer.set_volume(volume)
    renderer.set_transfer_function(SMOOTH_TF)
    camera = Camera.orbit(volume.bounds, 20, 10)
    renderer.set_settings(RenderSettings(step=1.0))
    uncut = renderer.render(camera, 32, 32)
    counters = renderer.last_frame.counters
    assert counters["slice_stride"] == 2.0 and counters["clipped"] == 0.0
    pools = {kind: (pool, len(pool.slots)) for kind, pool in renderer._pools.items()}
    copy = renderer.classified.copies[next(iter(renderer.classified.copies))]
    runs = dict(copy.runs)
    images = []
    for x in (4.0, 9.0, 15.0):
        clip = ClipRegion((ClipPlane((x, 0.0, 0.0), (1.0, 0.2, 0.0)),))
        renderer.set_settings(RenderSettings(step=1.0, clip=clip))
        images.append(renderer.render(camera, 32, 32))
        frame = renderer.last_frame.counters
        assert frame["clipped"] == 1.0 and frame["slice_stride"] == counters["slice_stride"]
        assert frame["table_lengths"] == counters["table_lengths"]
        assert renderer._pools.keys() == pools.keys()
        assert all(
            renderer._pools[kind] is pool and len(pool.slots) == n for kind, (pool, n) in pools.items()
        )
        assert dict(copy.runs) == runs and all(copy.runs[r] is runs[r] for r in runs)
    assert image_error(images[0], images[-1]).rmse > 0.01 and image_error(images[0], uncut).rmse > 0.01
