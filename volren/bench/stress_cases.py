"""The scenes and tables `volren bench stress` (`volren.bench.stress`) renders and checks.

Why generated, not loaded: the suite must reach the corners real data rarely does (uint8 to
float64, ranges of 1e-30 and 1e300, a float32 range of a few ulps, constant values, spacing of
1e-6 and 1e6, NaN and Inf samples, zero-volume, inverted and sliver tetrahedra, duplicated
points) and extreme transfer functions (opacity 0 and 1 everywhere, an opacity spike far
narrower than the value change across one voxel, a jump, control points outside the data).
Label volumes (every label 0..65535 at once, styles for labels the volume does not hold, nine in
ten hidden) and channels (one NaN in a slab, Inf at points) are cases too. Everything is small
(a 24 x 20 x 16 grid, a 41^3 one for the labels, a 5^3 box of 750 tetrahedra) and seeded, so a
run is quick and repeatable.
"""

from __future__ import annotations

import zlib
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from itertools import permutations

import numpy as np
from numpy.typing import NDArray

from volren.model.camera import Camera
from volren.model.channels import ChannelSet, ChannelTransferFunction
from volren.model.labels import MAX_LABEL, LabelMap, LabelStyle, LabelTransferFunction
from volren.model.preintegration import LightingTables
from volren.model.tet_repair import signed_volumes
from volren.model.transfer_function import MIN_UNIT_DISTANCE, TransferFunction1D
from volren.model.transfer_function_2d import TFWidget, TransferFunction, TransferFunction2D
from volren.model.volume import TetVolume, UniformVolume, Volume

#: (nz, ny, nx) of the uniform grids: unequal sides catch axis mix-ups.
GRID_SHAPE = (16, 20, 24)
#: Cubes per side of the tetrahedralized box (6 tetrahedra each).
BOX_CELLS = 5


def seed_of(text: str) -> int:
    """A stable seed per name (Python's hash() is salted per process)."""
    return zlib.crc32(text.encode())


# ------------------------------------------------------------------------------ fields
def blob(x: NDArray, y: NDArray, z: NDArray) -> NDArray[np.float64]:
    """A smooth field over [0, 1]^3 with both flat and steep parts, scaled to exactly [0, 1]."""
    r2 = (x - 0.5) ** 2 + (y - 0.45) ** 2 + (z - 0.55) ** 2
    f = 0.6 * np.exp(-8.0 * r2) + 0.2 * (1.0 + np.sin(6.0 * x + 3.0 * y) * np.cos(5.0 * z))
    return (f - f.min()) / (f.max() - f.min())


def grid_field(shape: tuple[int, int, int] = GRID_SHAPE) -> NDArray[np.float64]:
    """`blob` on a (nz, ny, nx) grid spanning [0, 1]^3."""
    z, y, x = (np.linspace(0.0, 1.0, n) for n in shape)
    return blob(x[None, None, :], y[None, :, None], z[:, None, None])


# ------------------------------------------------------------------------------- tetrahedra
def kuhn_box(cells: int = BOX_CELLS, z_planes: NDArray | None = None) -> tuple[NDArray, NDArray]:
    """(points, tets) of [0, 1]^3 cut into cubes of 6 positively oriented tetrahedra each (Kuhn's
    subdivision along the main diagonal, conforming across cubes). `z_planes` replaces the
    evenly spaced z coordinates (e.g. two planes 1e-9 apart make a layer of slivers)."""
    xs = np.linspace(0.0, 1.0, cells + 1)
    zs = xs if z_planes is None else np.asarray(z_planes, dtype=np.float64)
    nx, nz = len(xs), len(zs)
    k, j, i = np.meshgrid(np.arange(nz), np.arange(nx), np.arange(nx), indexing="ij")
    points = np.stack([xs[i.ravel()], xs[j.ravel()], zs[k.ravel()]], axis=1)

    def index(i: NDArray, j: NDArray, k: NDArray) -> NDArray:
        return (k * nx + j) * nx + i

    ci, cj, ck = (
        a.ravel() for a in np.meshgrid(np.arange(nx - 1), np.arange(nx - 1), np.arange(nz - 1), indexing="ij")
    )
    tets = []
    for order in permutations(range(3)):
        corner = [ci.copy(), cj.copy(), ck.copy()]
        path = [index(*corner)]
        for axis in order:
            corner[axis] = corner[axis] + 1
            path.append(index(*corner))
        tets.append(np.stack(path, axis=1))
    tets = np.concatenate(tets).astype(np.int64)
    negative = signed_volumes(points, tets) < 0
    tets[negative, 2], tets[negative, 3] = tets[negative, 3].copy(), tets[negative, 2].copy()
    return points, tets


def point_field(points: NDArray) -> NDArray[np.float64]:
    lo, hi = points.min(axis=0), points.max(axis=0)
    u = (points - lo) / np.where(hi > lo, hi - lo, 1.0)
    return blob(u[:, 0], u[:, 1], u[:, 2])


def with_flat_tets(points: NDArray, tets: NDArray, rng: np.random.Generator) -> NDArray:
    """`tets` plus zero-volume cells: repeated vertices, the four corners of a cube face, and four
    points on one grid line."""
    picks = tets[rng.choice(len(tets), 24, replace=False)]
    repeated = picks.copy()
    repeated[:, 1] = repeated[:, 0]
    n = BOX_CELLS + 1
    face = np.array([[0, 1, n + 1, n], [n * n, n * n + 1, 2 * n * n + 1, 2 * n * n]]) + rng.integers(0, 3)
    line = np.array([[0, 1, 2, 3], [n, n + 1, n + 2, n + 3]])
    return np.concatenate([tets, repeated, face, line])


def with_inverted(tets: NDArray, rng: np.random.Generator, fraction: float = 0.4) -> NDArray:
    out = tets.copy()
    flip = rng.random(len(tets)) < fraction
    out[flip, 2], out[flip, 3] = tets[flip, 3], tets[flip, 2]
    return out


def with_duplicated_points(
    points: NDArray, tets: NDArray, rng: np.random.Generator
) -> tuple[NDArray, NDArray]:
    """Every point twice; each tetrahedron picks either copy per vertex, so neighbouring cells
    rarely share a face by index although they share it in space."""
    twice = np.concatenate([points, points])
    pick = rng.integers(0, 2, size=tets.shape) * len(points)
    return twice, tets + pick


# ------------------------------------------------------------------------------------- TFs
def tf_span(lo: float, hi: float) -> tuple[float, float]:
    """The TF's x range for data in [lo, hi]: the data's, or a unit around a constant."""
    if hi > lo:
        return lo, hi
    half = max(abs(lo) * 1e-3, 0.5)
    return lo - half, hi + half


def _at(lo: float, hi: float, t: float) -> float:
    return lo + (hi - lo) * t


def tf_random(lo: float, hi: float, unit: float, seed: int) -> TransferFunction1D:
    """8 random colour and opacity points, some coincident, opacities including 0 and 1."""
    rng = np.random.default_rng(seed)
    ts = np.sort(rng.random(8))
    ts[3] = ts[2]
    opacity = rng.random(8)
    opacity[[1, 5]] = (0.0, 1.0)
    colors = rng.random((8, 3))
    return TransferFunction1D(
        [[_at(lo, hi, t), *c] for t, c in zip(ts, colors)],
        [[_at(lo, hi, t), a] for t, a in zip(ts, opacity)],
        unit,
    )


def tf_zero(lo: float, hi: float, unit: float, seed: int) -> TransferFunction1D:
    return TransferFunction1D([[lo, 1, 0, 0], [hi, 0, 0, 1]], [[lo, 0.0], [hi, 0.0]], unit)


def tf_one(lo: float, hi: float, unit: float, seed: int) -> TransferFunction1D:
    return TransferFunction1D([[lo, 1, 0.2, 0], [hi, 0, 0.8, 1]], [[lo, 1.0], [hi, 1.0]], unit)


def tf_spike(lo: float, hi: float, unit: float, seed: int) -> TransferFunction1D:
    """An opaque spike 1e-4 of the range wide at the middle, on a faint ramp."""
    mid, w = _at(lo, hi, 0.5), 0.5e-4 * (hi - lo)
    return TransferFunction1D(
        [[lo, 0.2, 0.2, 1], [mid, 1, 1, 0], [hi, 1, 0, 0]],
        [[lo, 0.0], [mid - w, 0.02], [mid, 1.0], [mid + w, 0.02], [hi, 0.05]],
        unit,
    )


def tf_step(lo: float, hi: float, unit: float, seed: int) -> TransferFunction1D:
    """Opacity and colour jump at the middle (two control points at one value)."""
    mid = _at(lo, hi, 0.5)
    return TransferFunction1D(
        [[lo, 0, 0, 1], [mid, 0, 0, 1], [mid, 1, 0.5, 0], [hi, 1, 0.5, 0]],
        [[lo, 0.0], [mid, 0.0], [mid, 0.9], [hi, 0.9]],
        unit,
    )


def tf_outside(lo: float, hi: float, unit: float, seed: int) -> TransferFunction1D:
    """Every control point above the data: the data sees the TF's constant lower end."""
    span = hi - lo
    return TransferFunction1D(
        [[hi + span, 0.3, 0.9, 0.1], [hi + 2 * span, 1, 0, 0]], [[hi + span, 0.3], [hi + 2 * span, 1.0]], unit
    )


def tf_faint(lo: float, hi: float, unit: float, seed: int) -> TransferFunction1D:
    """Opacities of 1e-7 to 1e-4: tiny alphas, where float32 loses digits first."""
    return TransferFunction1D([[lo, 1, 1, 1], [hi, 1, 0.5, 0]], [[lo, 1e-7], [hi, 1e-4]], unit)


TF1D_BUILDERS: dict[str, Callable[[float, float, float, int], TransferFunction1D]] = {
    "random": tf_random,
    "zero": tf_zero,
    "one": tf_one,
    "spike": tf_spike,
    "step": tf_step,
    "outside": tf_outside,
    "faint": tf_faint,
}


def tf_2d(lo: float, hi: float, unit: float, gmax: float) -> TransferFunction2D:
    """An opaque box over everything at low gradient, a narrow gaussian, and a triangle whose
    apex sits at gradient 0 (where constant data lives)."""
    mid = _at(lo, hi, 0.5)
    widgets = [
        TFWidget.box((lo, hi), (0.0, 0.05 * gmax), (0.9, 0.3, 0.1), 1.0),
        TFWidget.gaussian((mid, 0.5 * gmax), (1e-3 * (hi - lo), 0.05 * gmax), (0.1, 0.9, 0.3), 0.8),
        TFWidget.triangle(mid, 0.1 * (hi - lo), gmax, (0.2, 0.3, 1.0), 0.6),
    ]
    return TransferFunction2D((lo, hi), (0.0, gmax), widgets, unit)


def tf_labels(volume: UniformVolume, base: TransferFunction1D, name: str) -> LabelTransferFunction:
    """A TF per label over `base`: "labels", each label in its palette colour (label 0 as `base`);
    "labels-absent", styles given for labels the volume does not hold (past its largest, and a
    gap), the labels it holds unstyled; "labels-hidden", all but every tenth label hidden."""
    assert volume.labels is not None
    present = volume.labels.present
    if name == "labels-absent":
        missing = sorted(set(range(0, present[-1] + 3, 7)) - set(present))[:50] + [MAX_LABEL]
        return LabelTransferFunction(
            base, {label: LabelStyle(color=(1.0, 0.2, 0.1), opacity=3.0) for label in missing}
        )
    tf = LabelTransferFunction.for_labels(base, volume.labels)
    if name == "labels-hidden":
        tf.hide(label for n, label in enumerate(present) if n % 10)
    return tf


def make_tf(
    name: str, volume: Volume, seed: int
) -> TransferFunction | LabelTransferFunction | ChannelTransferFunction:
    """TF `name` (a TF1D_BUILDERS key, "2d", "labels...": a TF per label over "random", or
    "channels": each channel's default ramp, the second at weight 3) over the volume's value range,
    its unit distance the volume's characteristic length (so a voxel of opacity a has about that
    opacity)."""
    lo, hi = tf_span(*volume.value_range)
    unit = max(volume.characteristic_length, MIN_UNIT_DISTANCE)
    if name == "2d":
        assert isinstance(volume, UniformVolume)
        return tf_2d(lo, hi, unit, (hi - lo) / volume.mean_spacing)
    if name.startswith("labels"):
        assert isinstance(volume, UniformVolume)
        return tf_labels(volume, tf_random(lo, hi, unit, seed), name)
    if name == "channels":
        assert isinstance(volume, UniformVolume) and volume.channels is not None
        channels = ChannelTransferFunction.for_channels(volume.channels)
        channels.set_weight(1, 3.0)
        return channels
    return TF1D_BUILDERS[name](lo, hi, unit, seed)


# ----------------------------------------------------------------------------------- volumes
def _uniform(
    values: NDArray, spacing: float | tuple[float, float, float] = 1.0, name: str = ""
) -> UniformVolume:
    return UniformVolume(values, spacing=spacing, name=name)


def uniform_volumes() -> dict[str, Callable[[], UniformVolume]]:
    """Name -> builder of each uniform data case."""
    f = grid_field()
    rng = np.random.default_rng(seed_of("nonfinite"))

    def nonfinite() -> UniformVolume:
        v = f.astype(np.float32)
        u = rng.random(v.shape)
        v[u < 0.03] = np.nan
        v[(u >= 0.03) & (u < 0.04)] = np.inf
        v[(u >= 0.04) & (u < 0.05)] = -np.inf
        return _uniform(v, name="nonfinite")

    def many_labels() -> UniformVolume:
        # every label 0..65535 somewhere, most of them once: the most a label volume holds
        shape = (41, 41, 41)
        field = grid_field(shape).astype(np.float32)
        labels = (np.arange(field.size) % (MAX_LABEL + 1)).reshape(shape)
        return UniformVolume(field, name="labels-65535", labels=LabelMap(labels))

    def channels_nan() -> UniformVolume:
        # two channels, the second NaN in a slab and Inf at scattered points
        second = (1.0 - f).astype(np.float32)
        second[:, :, 5:9] = np.nan
        second[np.random.default_rng(seed_of("channels-nan")).random(second.shape) < 0.02] = np.inf
        stack = np.stack([f.astype(np.float32), second])
        return UniformVolume(stack[0], name="channels-nan", channels=ChannelSet(stack))

    return {
        "labels-65535": many_labels,
        "channels-nan": channels_nan,
        "f32-blob": lambda: _uniform(f.astype(np.float32), name="f32-blob"),
        "u8-full": lambda: _uniform(np.round(255 * f).astype(np.uint8), name="u8-full"),
        "u8-binary": lambda: _uniform(np.where(f > 0.5, 255, 0).astype(np.uint8), name="u8-binary"),
        "i16-full": lambda: _uniform((np.round(65535 * f) - 32768).astype(np.int16), name="i16-full"),
        "f32-ulps": lambda: _uniform((1.0 + 1e-5 * f).astype(np.float32), name="f32-ulps"),
        "f32-1e-30": lambda: _uniform((1e-30 * f).astype(np.float32), name="f32-1e-30"),
        "f64-1e300": lambda: _uniform((f - 0.5) * 2e300, name="f64-1e300"),
        "f64-offset": lambda: _uniform(1e8 + 1e-6 * f, name="f64-offset"),
        "constant": lambda: _uniform(np.full(GRID_SHAPE, 7.0, np.float32), name="constant"),
        "nonfinite": nonfinite,
        "spacing-1e-6": lambda: _uniform(f.astype(np.float32), 1e-6, "spacing-1e-6"),
        "spacing-1e6": lambda: _uniform(f.astype(np.float32), 1e6, "spacing-1e6"),
        "spacing-aniso": lambda: _uniform(f.astype(np.float32), (1e-2, 1.0, 30.0), "spacing-aniso"),
        "grid-2": lambda: _uniform(grid_field((2, 2, 2)).astype(np.float32), name="grid-2"),
    }


def _tet(points: NDArray, tets: NDArray, values: NDArray, name: str) -> TetVolume:
    return TetVolume(points, tets, values, name=name)


def tet_volumes() -> dict[str, Callable[[], TetVolume]]:
    """Name -> builder of each tetrahedral data case."""
    points, tets = kuhn_box()
    f = point_field(points)
    rng = np.random.default_rng(seed_of("tets"))

    def sliver() -> TetVolume:
        zs = np.array([0.0, 0.2, 0.4, 0.4 + 1e-7, 0.6, 0.6 + 1e-13, 0.8, 1.0])
        p, t = kuhn_box(BOX_CELLS, zs)
        return _tet(p, t, point_field(p), "tet-sliver")

    def duplicated() -> TetVolume:
        p, t = with_duplicated_points(points, tets, rng)
        return _tet(p, t, np.concatenate([f, f]), "tet-duplicated")

    single = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    some_nan = f.copy()
    some_nan[rng.choice(len(f), 12, replace=False)] = np.nan
    return {
        "tet-box": lambda: _tet(points, tets, f, "tet-box"),
        "tet-flat": lambda: _tet(points, with_flat_tets(points, tets, rng), f, "tet-flat"),
        "tet-inverted": lambda: _tet(points, with_inverted(tets, rng), f, "tet-inverted"),
        "tet-sliver": sliver,
        "tet-duplicated": duplicated,
        "tet-single": lambda: _tet(
            single, np.array([[0, 1, 2, 3]]), np.array([0.0, 1.0, 0.5, 0.25]), "tet-single"
        ),
        "tet-u8": lambda: _tet(points, tets, np.round(255 * f).astype(np.uint8), "tet-u8"),
        "tet-i16": lambda: _tet(points, tets, (np.round(65535 * f) - 32768).astype(np.int16), "tet-i16"),
        "tet-f64-1e300": lambda: _tet(points, tets, (f - 0.5) * 2e300, "tet-f64-1e300"),
        "tet-f32-ulps": lambda: _tet(points, tets, (1.0 + 1e-5 * f).astype(np.float32), "tet-f32-ulps"),
        "tet-constant": lambda: _tet(points, tets, np.full(len(points), -3.0), "tet-constant"),
        "tet-nonfinite": lambda: _tet(points, tets, some_nan, "tet-nonfinite"),
        "tet-scale-1e-6": lambda: _tet(points * 1e-6, tets, f, "tet-scale-1e-6"),
        "tet-scale-1e6": lambda: _tet(points * 1e6, tets, f, "tet-scale-1e6"),
    }


# -------------------------------------------------------------------------------------- cases
@dataclass(frozen=True)
class Case:
    """One scene: a volume, a TF and a camera, rendered by every renderer that can draw it."""

    name: str
    data: str
    tf_name: str
    camera_name: str
    volume: Volume
    tf: TransferFunction | LabelTransferFunction | ChannelTransferFunction
    camera: Camera


#: (data, TFs, camera) of the full suite; the quick subset is QUICK_SCENES.
_ALL_TFS = tuple(TF1D_BUILDERS)
FULL_SCENES: tuple[tuple[str, tuple[str, ...], str], ...] = (
    ("labels-65535", ("labels", "labels-absent", "labels-hidden"), "orbit"),
    ("channels-nan", ("channels",), "orbit"),
    ("f32-blob", (*_ALL_TFS, "2d"), "orbit"),
    ("f32-blob", ("random", "one"), "axis"),
    ("u8-full", ("random", "spike"), "orbit"),
    ("u8-binary", ("random", "step", "2d"), "orbit"),
    ("i16-full", ("random", "spike"), "orbit"),
    ("f32-ulps", ("random", "spike"), "orbit"),
    ("f32-1e-30", ("random", "spike"), "orbit"),
    ("f64-1e300", ("random", "spike"), "orbit"),
    ("f64-offset", ("random", "spike"), "orbit"),
    ("constant", ("random", "spike", "one", "zero", "2d"), "orbit"),
    ("nonfinite", ("random", "one"), "orbit"),
    ("spacing-1e-6", ("random", "spike"), "orbit"),
    ("spacing-1e6", ("random", "spike"), "orbit"),
    ("spacing-aniso", ("random",), "orbit"),
    ("grid-2", ("random", "one"), "orbit"),
    ("tet-box", _ALL_TFS, "orbit"),
    ("tet-box", ("random", "one"), "axis"),
    ("tet-flat", ("random", "one"), "orbit"),
    ("tet-inverted", ("random", "one"), "orbit"),
    ("tet-sliver", ("random", "one"), "orbit"),
    ("tet-sliver", ("random",), "axis"),
    ("tet-duplicated", ("random", "one"), "orbit"),
    ("tet-single", ("random", "spike"), "orbit"),
    ("tet-u8", ("random", "spike"), "orbit"),
    ("tet-i16", ("random", "spike"), "orbit"),
    ("tet-f64-1e300", ("random", "spike"), "orbit"),
    ("tet-f32-ulps", ("random", "spike"), "orbit"),
    ("tet-constant", ("random", "spike", "one"), "orbit"),
    ("tet-nonfinite", ("random", "one"), "orbit"),
    ("tet-scale-1e-6", ("random", "spike"), "orbit"),
    ("tet-scale-1e6", ("random", "spike"), "orbit"),
)
QUICK_SCENES: tuple[tuple[str, tuple[str, ...], str], ...] = (
    ("labels-65535", ("labels-absent",), "orbit"),
    ("channels-nan", ("channels",), "orbit"),
    ("f32-blob", ("spike", "one", "zero"), "orbit"),
    ("i16-full", ("random",), "orbit"),
    ("f64-1e300", ("random",), "orbit"),
    ("constant", ("spike",), "orbit"),
    ("spacing-1e-6", ("random",), "orbit"),
    ("tet-flat", ("random",), "orbit"),
    ("tet-duplicated", ("spike",), "axis"),
    ("tet-constant", ("one",), "orbit"),
)


def make_camera(name: str, volume: Volume) -> Camera:
    """ "orbit": DESIGN.md's orbit at azimuth 30, elevation 20; "axis": straight down -z in
    parallel projection, so rays run along grid lines and through tetrahedron edges."""
    if name == "axis":
        return Camera.orbit(volume.bounds, 0.0, 0.0, 1.0, True)
    return Camera.orbit(volume.bounds, 30.0, 20.0, 1.0)


def scene_cases(quick: bool = False) -> list[Case]:
    """Every scene of the full suite, or of the quick subset."""
    builders = {**uniform_volumes(), **tet_volumes()}
    out = []
    for data, tfs, camera_name in QUICK_SCENES if quick else FULL_SCENES:
        volume = builders[data]()
        camera = make_camera(camera_name, volume)
        for tf_name in tfs:
            tf = make_tf(tf_name, volume, seed_of(f"{data}/{tf_name}"))
            suffix = "" if camera_name == "orbit" else f"@{camera_name}"
            out.append(Case(f"{data}/{tf_name}{suffix}", data, tf_name, camera_name, volume, tf, camera))
    return out


# ------------------------------------------------------------------------------------ tables
@dataclass(frozen=True)
class TableTF:
    """A named 1D TF for the table checks."""

    name: str
    tf: TransferFunction1D


def table_tfs(quick: bool = False) -> list[TableTF]:
    """The 1D TFs over [0, 1] plus a single-point TF and one with the smallest unit distance
    allowed (an extinction of 1.4e31 per unit length)."""
    names = ("random", "one", "spike") if quick else tuple(TF1D_BUILDERS)
    out = [TableTF(n, TF1D_BUILDERS[n](0.0, 1.0, 0.5, seed_of(f"table/{n}"))) for n in names]
    out.append(TableTF("single-point", TransferFunction1D([[0.3, 0.2, 0.4, 0.6]], [[0.3, 0.7]], 1.0)))
    if not quick:
        out.append(TableTF("unit-1e-30", tf_random(0.0, 1.0, MIN_UNIT_DISTANCE, seed_of("table/unit"))))
    return out


#: Value ranges of the tables: the TF's own, a point, huge, and a few ulps of 1e8.
TABLE_RANGES: tuple[tuple[float, float] | None, ...] = (None, (0.5, 0.5), (-1e300, 1e300), (1e8, 1e8 + 1e-6))
#: Segment lengths of 2D tables and of the layers of 3D tables.
TABLE_STEPS = (1e-300, 1e-12, 0.5, 1e12, 1e300)
TABLE_LENGTHS = (0.0, 1e-300, 1e-12, 0.5, 1e12, 1e300)
TABLE_SIZES = (2, 3, 64)
QUICK_TABLE_SIZES = (2, 64)


#: What a checked RGBA array must satisfy (`volren.bench.stress.check_rgba`).
PREMULTIPLIED, UNIT, BELOW_ALPHA = "premultiplied", "unit", "below-alpha"
RULES = (PREMULTIPLIED, UNIT, BELOW_ALPHA)


@dataclass(frozen=True)
class TableOutput:
    """What one table computation gives the checks: (N, 4) arrays, each with the rule it must
    satisfy, and the max error against the continuous integral at random entries where that was
    measured."""

    arrays: tuple[tuple[NDArray, str], ...]
    error: float | None = None


@dataclass(frozen=True)
class TableCase:
    """One table function on one TF, over a list of parameter sets (each a label and a thunk)."""

    function: str
    tf_name: str
    runs: tuple[tuple[str, Callable[[], TableOutput]], ...]


def _flat(table: NDArray) -> NDArray[np.float64]:
    return np.asarray(table, dtype=np.float64).reshape(-1, 4)


def _lighting_arrays(tables: LightingTables) -> tuple[tuple[NDArray, str], ...]:
    """front (Df, opacity) and (Db, opacity), (Sb, Sb, Sb, opacity): every stored part of the
    split is a premultiplied colour of the segment's opacity; so is their sum Df + Db (which may
    pass 1 by a float32 rounding, so only its bound by the opacity is checked)."""
    front, back = _flat(tables.front), _flat(tables.back)
    alpha = front[:, 3:4]
    whole = np.concatenate([front[:, :3] + back[:, :3], alpha], axis=1)
    specular = np.concatenate([np.repeat(back[:, 3:4], 3, axis=1), alpha], axis=1)
    diffuse_back = np.concatenate([back[:, :3], alpha], axis=1)
    return (
        (front, PREMULTIPLIED),
        (diffuse_back, PREMULTIPLIED),
        (specular, PREMULTIPLIED),
        (whole, BELOW_ALPHA),
    )


def _oracle_error(tf: TransferFunction1D, table: NDArray, n: int, length: float, seed: int) -> float:
    """Max abs RGBA difference of 16 random entries of a table over the TF's range from the
    continuous integral (`volren.renderers.reference.segment_rgba`)."""
    from volren.renderers.reference import segment_rgba

    rng = np.random.default_rng(seed)
    idx = rng.integers(0, n, size=(16, 2))
    lo, hi = tf.value_range
    values = lo + (hi - lo) * idx / (n - 1)
    truth = segment_rgba(tf, values[:, 0], values[:, 1], length)
    return float(np.abs(np.asarray(table, np.float64)[idx[:, 0], idx[:, 1]] - truth).max())


def _range_label(r: tuple[float, float] | None) -> str:
    return "tf" if r is None else f"[{r[0]:.16g}, {r[1]:.16g}]"


def _thunks(params: list[tuple[tuple[str, ...], tuple]], fn: Callable[..., TableOutput]) -> tuple:
    """(label, thunk) per parameter set: `fn` applied to the set's arguments when called."""
    return tuple((" ".join(key), partial(fn, *args)) for key, args in params)


def tf_table_cases(entry: TableTF, sizes: tuple[int, ...]) -> list[TableCase]:
    """Every table function on one TF, over sizes, value ranges and segment lengths."""
    from volren.model.preintegration import (
        LengthAxis,
        correct_for_length,
        interpolate_in_length,
        lighting_tables,
        preintegrate,
        preintegrate_approximate,
    )

    tf, seed = entry.tf, seed_of(f"oracle/{entry.name}")

    def exact_2d(n: int, r: tuple[float, float] | None, step: float) -> TableOutput:
        table = preintegrate(tf, n, step, value_range=r, cache=None)
        error = _oracle_error(tf, table, n, step, seed) if (n, r, step) == (64, None, 0.5) else None
        return TableOutput(((_flat(table), PREMULTIPLIED),), error)

    def exact_3d(n: int, r: tuple[float, float] | None) -> TableOutput:
        table = preintegrate(tf, n, lengths=TABLE_LENGTHS, value_range=r, cache=None)
        error = None
        if (n, r) == (64, None):
            error = max(_oracle_error(tf, table[k], n, TABLE_LENGTHS[k], seed) for k in (2, 3))
        return TableOutput(((_flat(table), PREMULTIPLIED),), error)

    def lighting(n: int, r: tuple[float, float] | None, step: float | None) -> TableOutput:
        if step is None:
            return TableOutput(
                _lighting_arrays(lighting_tables(tf, n, lengths=TABLE_LENGTHS, value_range=r, cache=None))
            )
        return TableOutput(_lighting_arrays(lighting_tables(tf, n, step, value_range=r, cache=None)))

    def approximate(n: int, r: tuple[float, float] | None, step: float) -> TableOutput:
        # Engel's table drops attenuation inside a segment: its colour may exceed its alpha.
        return TableOutput(((_flat(preintegrate_approximate(tf, n, step, value_range=r)), UNIT),))

    def corrected() -> TableOutput:
        table = _flat(preintegrate(tf, 64, 0.5, cache=None))
        ratios = (0.0, 1e-300, 1e-12, 1.0, 1e12, 1e300)
        return TableOutput(tuple((correct_for_length(table, q), PREMULTIPLIED) for q in ratios))

    def interpolated(n: int) -> TableOutput:
        axis = LengthAxis(2.0, 8)
        table = preintegrate(tf, n, lengths=axis.lengths, cache=None)
        front, back = np.random.default_rng(seed).integers(0, n, size=(2, 256))
        queries = (0.0, 1e-300, 1e-12, 0.1, 0.25, 1.3, 2.0, 2.5, 1e12, 1e300)
        return TableOutput(
            tuple((interpolate_in_length(table, axis, front, back, q), PREMULTIPLIED) for q in queries)
        )

    grid = [(n, r) for n in sizes for r in TABLE_RANGES]
    steps = [
        ((f"n={n}", f"range={_range_label(r)}", f"L={s:g}"), (n, r, s)) for n, r in grid for s in TABLE_STEPS
    ]
    layers = [((f"n={n}", f"range={_range_label(r)}", "3D"), (n, r)) for n, r in grid]
    runs = {
        "preintegrate 2D": _thunks(steps, exact_2d),
        "preintegrate 3D": _thunks(layers, exact_3d),
        "lighting 2D": _thunks(steps, lighting),
        "lighting 3D": _thunks([(key, (n, r, None)) for key, (n, r) in layers], lighting),
        "approximate": _thunks(steps, approximate),
        "correct_for_length": _thunks([(("n=64", "L=0.5", "ratios 0..1e300"), ())], corrected),
        "interpolate_in_length": _thunks([((f"n={n}", "L 0..1e300"), (n,)) for n in sizes], interpolated),
    }
    return [TableCase(function, entry.name, items) for function, items in runs.items()]


def table_cases(quick: bool = False) -> list[TableCase]:
    """`tf_table_cases` for every table TF."""
    sizes = QUICK_TABLE_SIZES if quick else TABLE_SIZES
    return [case for entry in table_tfs(quick) for case in tf_table_cases(entry, sizes)]
