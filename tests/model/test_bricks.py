"""BrickGrid: per-brick min/max, TF classification, conservativeness, NaN bricks, errors."""

from __future__ import annotations

import gc
import weakref

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from volren.errors import VolrenError
from volren.model.bricks import FEW_REGIONS, BrickGrid, BrickStats, _meets, opaque_regions
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume


# ----------------------------------------------------------------------------- oracles
def brute_minmax(values: np.ndarray, brick: int):
    """Loop over bricks; brick covering cells [a, b) reads voxels [a, b] (finite ones only)."""
    nz, ny, nx = values.shape

    def ranges(n):
        cells = max(n - 1, 1)
        return [(a, min(a + brick, n - 1)) for a in range(0, cells, brick)]

    rk, rj, ri = ranges(nz), ranges(ny), ranges(nx)
    vmin = np.full((len(rk), len(rj), len(ri)), np.inf)
    vmax = np.full_like(vmin, -np.inf)
    bad = np.zeros(vmin.shape, dtype=bool)
    for bk, (k0, k1) in enumerate(rk):
        for bj, (j0, j1) in enumerate(rj):
            for bi, (i0, i1) in enumerate(ri):
                block = values[k0 : k1 + 1, j0 : j1 + 1, i0 : i1 + 1].astype(np.float64)
                good = block[np.isfinite(block)]
                bad[bk, bj, bi] = good.size < block.size
                if good.size:
                    vmin[bk, bj, bi] = good.min()
                    vmax[bk, bj, bi] = good.max()
    return vmin, vmax, bad


def brute_max_opacity(tf: TransferFunction1D, lo: float, hi: float, n: int = 2001) -> float:
    """Dense sampling of [lo, hi] plus the exact control points inside it."""
    _, alpha = tf.sample(np.linspace(lo, hi, n))
    pts = tf.opacity_points
    inside = pts[(pts[:, 0] >= lo) & (pts[:, 0] <= hi), 1]
    return float(max(alpha.max(), inside.max(initial=0.0)))


def trilinear(values: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Trilinear interpolation at index-space points p (n, 3) given as (x, y, z)."""
    nz, ny, nx = values.shape
    v = values.astype(np.float64)
    idx = []
    frac = []
    for axis, n in enumerate((nx, ny, nz)):
        c = np.clip(np.floor(p[:, axis]).astype(int), 0, max(n - 2, 0))
        idx.append(c)
        frac.append(p[:, axis] - c)
    i, j, k = idx
    fx, fy, fz = frac
    out = np.zeros(len(p))
    for dk in (0, 1):
        for dj in (0, 1):
            for di in (0, 1):
                w = (fx if di else 1 - fx) * (fy if dj else 1 - fy) * (fz if dk else 1 - fz)
                out += w * v[k + dk, j + dj, i + di]
    return out


def check_against_brute(values: np.ndarray, brick: int) -> BrickGrid:
    grid = BrickGrid.from_array(values, brick)
    vmin, vmax, bad = brute_minmax(values, brick)
    np.testing.assert_array_equal(grid.vmin, vmin)
    np.testing.assert_array_equal(grid.vmax, vmax)
    np.testing.assert_array_equal(grid.has_nonfinite, bad)
    return grid


# ----------------------------------------------------------------------------- min / max
@pytest.mark.parametrize("dtype", [np.uint8, np.int16, np.float32, np.float64])
@pytest.mark.parametrize("shape", [(17, 9, 33), (5, 12, 8), (2, 2, 2), (16, 16, 16), (4, 7, 13)])
@pytest.mark.parametrize("brick", [1, 3, 4, 16])
def test_minmax_matches_brute_force_including_shared_boundary(dtype, shape, brick):
    """Per-brick min/max equal a loop over bricks reading the shared boundary voxel layer."""
    rng = np.random.default_rng(hash((shape, brick)) % 2**32)
    info = np.iinfo(dtype) if np.issubdtype(dtype, np.integer) else None
    lo, hi = (info.min, info.max) if info else (-1000.0, 1000.0)
    values = rng.uniform(lo, hi, size=shape).astype(dtype)
    grid = check_against_brute(values, brick)
    assert grid.shape == tuple(-(-max(n - 1, 1) // brick) for n in shape)


def test_boundary_voxel_belongs_to_both_bricks():
    """A spike on the shared voxel plane shows up in the max of the bricks on both sides."""
    values = np.zeros((3, 3, 9), dtype=np.float32)
    values[:, :, 4] = 7.0  # voxel 4 closes brick [0, 4) and opens brick [4, 8)
    grid = BrickGrid.from_array(values, 4)
    assert grid.shape == (1, 1, 2)
    np.testing.assert_array_equal(grid.vmax[0, 0], [7.0, 7.0])
    values[:, :, 4] = 0.0
    values[:, :, 5] = 7.0
    grid = BrickGrid.from_array(values, 4)
    np.testing.assert_array_equal(grid.vmax[0, 0], [0.0, 7.0])


@pytest.mark.parametrize("shape", [(1, 6, 7), (5, 1, 9), (1, 1, 1), (1, 1, 20)])
def test_one_voxel_thick_volumes(shape):
    """Axes with a single sample give flat bricks whose min/max read that one layer."""
    values = np.random.default_rng(1).normal(size=shape)
    grid = check_against_brute(values, 4)
    lo, hi = grid.brick_bounds()
    for axis, n in enumerate(shape[::-1]):
        if n == 1:
            assert np.all(lo[..., axis] == hi[..., axis])
    assert grid.stats(np.ones(grid.shape, bool)).n_cells == int(np.prod([max(n - 1, 1) for n in shape]))


def test_two_by_two_by_two_volume_is_one_brick():
    """A 2x2x2 volume (one cell) is one brick whose range is all eight voxels."""
    values = np.arange(8, dtype=np.int16).reshape(2, 2, 2) - 3
    volume = UniformVolume(values, spacing=(1, 2, 3), origin=(10, 20, 30))
    grid = BrickGrid.from_volume(volume, 16)
    assert grid.shape == (1, 1, 1) and grid.n_bricks == 1
    assert (grid.vmin[0, 0, 0], grid.vmax[0, 0, 0]) == (-3.0, 4.0)
    lo, hi = grid.brick_bounds()
    np.testing.assert_array_equal(lo[0, 0, 0], [10, 20, 30])
    np.testing.assert_array_equal(hi[0, 0, 0], [11, 22, 33])


def test_brick_bounds_tile_the_volume_bounds():
    """Brick boxes are origin + spacing * cell index and tile the volume's bounding box."""
    volume = UniformVolume(np.zeros((6, 11, 20), np.float32), spacing=(0.5, 2.0, 1.5), origin=(-1, 0, 3))
    grid = BrickGrid.from_volume(volume, 4)
    lo, hi = grid.brick_bounds()
    assert lo.shape == hi.shape == grid.shape + (3,)
    np.testing.assert_allclose(lo[0, 0, 0], volume.origin)
    np.testing.assert_allclose(hi[-1, -1, -1], volume.bounds[1::2])
    np.testing.assert_allclose(lo[0, 0, 1:, 0], hi[0, 0, :-1, 0])  # neighbours share faces
    np.testing.assert_allclose(lo[0, 0, 1, 0], -1 + 0.5 * 4)
    assert int(grid.cell_counts().sum()) == 19 * 10 * 5


# ----------------------------------------------------------------------------- NaN bricks
def test_nonfinite_voxels_are_ignored_and_flagged():
    """NaN/Inf are left out of min/max; all-NaN bricks are empty and never visible."""
    values = np.random.default_rng(3).uniform(0, 1, size=(9, 9, 9))
    values[:5, :5, :5] = np.nan  # brick (0,0,0) with brick=4 reads voxels 0..4: all NaN
    values[8, 8, 8] = np.inf
    values[0, 8, 8] = -np.inf
    grid = check_against_brute(values, 4)
    assert grid.empty[0, 0, 0] and grid.has_nonfinite[0, 0, 0]
    assert grid.vmin[0, 0, 0] == np.inf and grid.vmax[0, 0, 0] == -np.inf
    assert grid.has_nonfinite[1, 1, 1] and np.isfinite(grid.vmax[1, 1, 1]) and grid.vmax[1, 1, 1] <= 1
    # Brick (0,0,1) shares voxels 4 of x with the NaN block but has finite ones too.
    assert grid.has_nonfinite[0, 0, 1] and not grid.empty[0, 0, 1]
    everything = TransferFunction1D.constant(1.0)
    vis = grid.visible(everything, threshold=-1.0)
    assert not vis[0, 0, 0]
    assert vis.sum() == grid.n_bricks - 1
    assert grid.max_opacity(everything)[0, 0, 0] == 0.0


def test_partly_nan_brick_uses_finite_voxels():
    """A brick with some NaN is classified by its finite voxels only."""
    values = np.full((3, 3, 3), np.nan)
    values[1, 1, 1] = 5.0
    grid = BrickGrid.from_array(values, 2)
    assert (grid.vmin.item(), grid.vmax.item(), grid.has_nonfinite.item()) == (5.0, 5.0, True)
    assert grid.visible(TransferFunction1D.ramp(4.0, 6.0)).item()
    assert not grid.visible(TransferFunction1D.ramp(5.0, 6.0)).item()  # opacity 0 at exactly 5


# ----------------------------------------------------------------------------- classification
def step_tf():
    return TransferFunction1D([[0, 1, 1, 1]], [[0, 0], [10, 0], [10, 0.7], [20, 0.7], [20, 0], [30, 0]])


def spike_tf():
    return TransferFunction1D([[0, 1, 1, 1]], [[0, 0], [49.9, 0], [50, 0.9], [50.1, 0], [100, 0.2]])


TFS = {
    "step": step_tf,
    "spike": spike_tf,
    "constant": lambda: TransferFunction1D.constant(0.3),
    "zero": lambda: TransferFunction1D([[0, 1, 1, 1]], [[0, 0], [50, 0], [100, 0]]),
    "ramp": lambda: TransferFunction1D.ramp(40, 60, 0.5),
    "single-point": lambda: TransferFunction1D([[0, 1, 1, 1]], [[25, 0.4]]),
}


def intervals():
    """Brick value intervals that hit every structure of the TFs above: ends, steps, spikes."""
    edges = [
        -5.0,
        0.0,
        5.0,
        9.99,
        10.0,
        10.01,
        15.0,
        20.0,
        25.0,
        30.0,
        40.0,
        49.9,
        49.95,
        50.0,
        50.05,
        60.0,
        120.0,
    ]
    lo, hi = np.meshgrid(edges, edges, indexing="ij")
    keep = lo <= hi
    return lo[keep], hi[keep]


@pytest.mark.parametrize("name", sorted(TFS))
@pytest.mark.parametrize("threshold", [0.0, 0.2, 0.5, 0.95])
def test_visible_matches_dense_evaluation(name, threshold):
    """`visible` equals a dense evaluation of the TF over [min, max] plus its control points."""
    tf = TFS[name]()
    lo, hi = intervals()
    grid = BrickGrid(
        lo.reshape(1, 1, -1), hi.reshape(1, 1, -1), np.zeros((1, 1, lo.size), bool), 1, (lo.size + 1, 2, 2)
    )
    expected = np.array([brute_max_opacity(tf, a, b) for a, b in zip(lo, hi)])
    np.testing.assert_allclose(grid.max_opacity(tf).ravel(), expected, atol=1e-12)
    np.testing.assert_array_equal(grid.visible(tf, threshold).ravel(), expected > threshold)


@settings(max_examples=200, deadline=None)
@given(
    xs=st.lists(st.sampled_from([-1.0, 0.0, 0.5, 1.0, 2.0, 2.0, 3.0]), min_size=1, max_size=9),
    alphas=st.lists(st.sampled_from([0.0, 0.0, 0.25, 1.0]), min_size=9, max_size=9),
    pad=st.sampled_from([0.0, 0.25]),
)
def test_opaque_regions_classify_as_the_table_of_maxima(xs, alphas, pad):
    """At threshold 0, the regions' comparisons (the fast path) and the table of maxima agree on
    every brick range built from the TF's own points, between them and beyond them, including
    steps (repeated x) and zero points that split two segments."""
    xs = sorted(xs)
    tf = TransferFunction1D([[0, 1, 1, 1]], np.column_stack([xs, alphas[: len(xs)]]))
    edges = sorted({*xs, *(x + d for x in xs for d in (-0.5, -1e-9, 1e-9, 0.5)), -9.0, 9.0})
    lo, hi = np.meshgrid(edges, edges, indexing="ij")
    keep = lo <= hi
    lo, hi = lo[keep], hi[keep]
    grid = BrickGrid(
        lo.reshape(1, 1, -1), hi.reshape(1, 1, -1), np.zeros((1, 1, lo.size), bool), 1, (lo.size + 1, 2, 2)
    )
    expected = (grid.max_opacity(tf, pad) > 0.0).ravel()
    np.testing.assert_array_equal(grid.visible(tf, 0.0, pad).ravel(), expected)


def test_many_opaque_regions_take_the_table_and_agree():
    """A comb of more spikes than FEW_REGIONS is classified through the table of maxima, and the
    regions, though not used for it, give the same answer."""
    spikes = FEW_REGIONS + 3
    points = [[0.0, 0.0]] + [
        [x, a] for k in range(spikes) for x, a in ((10 * k + 4, 0), (10 * k + 5, 1), (10 * k + 6, 0))
    ]
    tf = TransferFunction1D([[0, 1, 1, 1]], points)
    regions = opaque_regions(tf)
    assert len(regions) == spikes and regions[0] == (4.0, False, 6.0, False)
    lo = np.arange(0.0, 10.0 * spikes, 0.5)
    hi = lo + 0.75
    grid = BrickGrid(
        lo.reshape(1, 1, -1), hi.reshape(1, 1, -1), np.zeros((1, 1, lo.size), bool), 1, (lo.size + 1, 2, 2)
    )
    visible = grid.visible(tf).ravel()
    np.testing.assert_array_equal(visible, _meets(regions, lo, hi))
    assert visible.any() and not visible.all()


def test_spike_inside_a_brick_is_found():
    """A TF spike narrower than the brick's range marks it visible; a zero TF marks nothing."""
    values = np.linspace(0, 100, 9 * 9 * 9).reshape(9, 9, 9)
    grid = BrickGrid.from_array(values, 8)
    assert grid.visible(spike_tf(), 0.5).item()
    assert not grid.visible(TFS["zero"]()).any()
    assert grid.visible(TFS["constant"]()).all()
    assert not grid.visible(TFS["constant"](), threshold=0.3).any()


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 2**32 - 1),
    shape=st.tuples(st.integers(2, 12), st.integers(2, 12), st.integers(2, 12)),
    brick=st.integers(1, 6),
    xs=st.lists(st.floats(-0.2, 1.2), min_size=1, max_size=8),
    alphas=st.lists(st.sampled_from([0.0, 0.0, 0.1, 0.5, 1.0]), min_size=8, max_size=8),
    threshold=st.sampled_from([0.0, 0.05, 0.3]),
)
def test_every_opaque_trilinear_sample_lies_in_a_visible_brick(seed, shape, brick, xs, alphas, threshold):
    """Conservativeness: any interpolated sample with opacity > threshold is in a visible brick."""
    rng = np.random.default_rng(seed)
    values = rng.uniform(0, 1, size=shape).astype(np.float32)
    values[rng.uniform(size=shape) < 0.3] = 0.0  # plenty of empty space
    tf = TransferFunction1D([[0, 1, 1, 1]], np.column_stack([xs, alphas[: len(xs)]]))
    grid = BrickGrid.from_array(values, brick)
    visible = grid.visible(tf, threshold)
    nz, ny, nx = shape
    p = rng.uniform(0, 1, size=(4000, 3)) * [nx - 1, ny - 1, nz - 1]
    # Include points exactly on brick faces and voxels.
    p[:500] = np.round(p[:500])
    _, alpha = tf.sample(trilinear(values, p))
    opaque = alpha > threshold
    cell = np.minimum(np.floor(p).astype(int), [nx - 2, ny - 2, nz - 2])
    b = cell // brick
    # A point on a face between bricks is read by both, so it must be visible in each.
    for q in np.flatnonzero(opaque):
        owners = [
            visible[bk, bj, bi]
            for bk in {b[q, 2], (int(np.ceil(p[q, 2])) - 1) // brick if p[q, 2] > 0 else 0}
            for bj in {b[q, 1], (int(np.ceil(p[q, 1])) - 1) // brick if p[q, 1] > 0 else 0}
            for bi in {b[q, 0], (int(np.ceil(p[q, 0])) - 1) // brick if p[q, 0] > 0 else 0}
        ]
        assert all(owners), (p[q], alpha[q])
    # And every brick's stated range holds its samples.
    v = trilinear(values, p)
    assert np.all(v >= grid.vmin[b[:, 2], b[:, 1], b[:, 0]] - 1e-6)
    assert np.all(v <= grid.vmax[b[:, 2], b[:, 1], b[:, 0]] + 1e-6)


# ----------------------------------------------------------------------------- re-classification
def test_reclassification_keeps_no_reference_to_the_volume():
    """The grid holds only small per-brick arrays; a TF edit re-classifies without the volume."""
    values = np.zeros((33, 33, 33), np.float32)
    values[20:, 20:, 20:] = 100.0
    volume = UniformVolume(values)
    grid = BrickGrid.from_volume(volume, 8)
    for arr in (grid.vmin, grid.vmax, grid.has_nonfinite):
        assert not np.shares_memory(arr, volume.values)
    assert grid.nbytes < volume.values.nbytes / 100
    ref = weakref.ref(volume.values)
    del volume, values
    gc.collect()
    assert ref() is None  # nothing in the grid keeps the volume alive

    tf = TransferFunction1D.ramp(50, 100)
    mask, stats = grid.classify(tf)
    assert stats == BrickStats(n_bricks=64, n_visible=8, n_cells=32**3, n_skipped_cells=32**3 - 8 * 8**3)
    assert stats.skipped_fraction == pytest.approx(1 - 1 / 8)
    assert "8/64 bricks visible" in str(stats)
    np.testing.assert_array_equal(np.argwhere(mask), np.argwhere(np.ones((2, 2, 2))) + 2)
    tf.set_opacity_points([[0, 0.5], [1, 0.0]])  # now only value 0 is opaque
    mask2, stats2 = grid.classify(tf)
    assert stats2.n_visible == 64 - 1  # every brick but the all-100 corner reads some zero
    assert not mask2[3, 3, 3]
    assert grid.classify(tf, threshold=0.6)[1].n_visible == 0


def test_grid_arrays_are_read_only():
    """Renderers cannot corrupt the cached min/max by accident."""
    grid = BrickGrid.from_array(np.zeros((3, 3, 3)), 1)
    with pytest.raises(ValueError):
        grid.vmin[0, 0, 0] = 1.0
    assert "bricks" in repr(grid)


@pytest.mark.parametrize("shape", [(17, 9, 33), (5, 12, 8), (2, 2, 2), (4, 7, 13)])
@pytest.mark.parametrize("brick", [1, 3, 4])
@pytest.mark.parametrize("reach", [1, 2])
def test_reach_covers_exactly_the_cells_within_reach(shape, brick, reach):
    """With a reach of r cells, a brick over cells [a, b) covers voxels [a - r, b + r] (clipped to
    the grid, non-finite voxels skipped): exactly, not a whole neighbouring brick."""
    rng = np.random.default_rng(sum(shape) * 10 + brick + reach)
    values = rng.normal(size=shape).astype(np.float32)
    values[rng.random(shape) < 0.1] = np.nan
    grid = BrickGrid.from_volume(UniformVolume(values), brick, reach=reach)
    nz, ny, nx = shape

    def ranges(n):
        return [(max(a - reach, 0), min(a + brick + reach, n - 1)) for a in range(0, max(n - 1, 1), brick)]

    for bk, (k0, k1) in enumerate(ranges(nz)):
        for bj, (j0, j1) in enumerate(ranges(ny)):
            for bi, (i0, i1) in enumerate(ranges(nx)):
                block = values[k0 : k1 + 1, j0 : j1 + 1, i0 : i1 + 1]
                good = block[np.isfinite(block)]
                if good.size:
                    assert grid.vmin[bk, bj, bi] == good.min() and grid.vmax[bk, bj, bi] == good.max()
                else:
                    assert grid.empty[bk, bj, bi]
    whole_bricks = BrickGrid.from_volume(UniformVolume(values), brick).dilated(-(-reach // brick))
    assert (grid.vmin >= whole_bricks.vmin).all() and (grid.vmax <= whole_bricks.vmax).all()


@pytest.mark.parametrize("reach", [-1, 1.5, True])
def test_bad_reach(reach):
    with pytest.raises(VolrenError, match="reach"):
        BrickGrid.from_volume(UniformVolume(np.zeros((4, 4, 4))), 2, reach=reach)


# ----------------------------------------------------------------------------- errors
@pytest.mark.parametrize("brick", [0, -3, 2.5, True])
def test_bad_brick_size(brick):
    """Brick sizes that are not positive integers are rejected with a clear message."""
    with pytest.raises(VolrenError, match="brick size"):
        BrickGrid.from_array(np.zeros((4, 4, 4)), brick)


@pytest.mark.parametrize("shape", [(0, 4, 4), (4, 0, 0), (4, 4)])
def test_empty_or_non_3d_volume(shape):
    """Empty or non-3D arrays are rejected with a clear message."""
    with pytest.raises(VolrenError, match="empty|3D"):
        BrickGrid.from_array(np.zeros(shape), 4)


def test_bad_volume_kind_and_mask():
    """Non-uniform volumes, non-numeric data and wrong-shaped masks are rejected."""
    with pytest.raises(VolrenError, match="uniform volume"):
        BrickGrid.from_volume(np.zeros((4, 4, 4)), 4)  # type: ignore[arg-type]
    with pytest.raises(VolrenError, match="not numeric"):
        BrickGrid.from_array(np.full((2, 2, 2), "a"), 1)
    grid = BrickGrid.from_array(np.zeros((5, 5, 5)), 2)
    with pytest.raises(VolrenError, match="mask has shape"):
        grid.stats(np.ones((1, 1, 1), bool))
    with pytest.raises(VolrenError, match="threshold"):
        grid.visible(TransferFunction1D.constant(1.0), threshold=float("nan"))


def test_a_2d_tf_of_one_1d_widget_bounds_bricks_as_its_1d_tf():
    """A 1d widget over the whole gradient axis is its 1D TF at every gradient: same bound."""
    from volren.model.transfer_function_2d import TFWidget, TransferFunction2D

    values = np.random.default_rng(5).random((9, 9, 9))
    grid = BrickGrid.from_array(values, 4)
    tf = TransferFunction1D([[0, 1, 1, 1]], [[0.2, 0.0], [0.5, 0.8], [0.55, 0.1], [0.9, 0.0]])
    tf2 = TransferFunction2D((0.0, 1.0), (0.0, 3.0), [TFWidget.from_1d(tf, (0.0, 3.0))])
    np.testing.assert_allclose(
        grid.max_opacity(tf2, pad=0.01), grid.max_opacity(tf, pad=0.01), atol=1e-15, rtol=0
    )
    assert grid.max_opacity(tf).max() > 0.5
