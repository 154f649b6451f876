"""The most any hidden volume removal could occlude: per scene, the non-transparent cells all of whose
rays are already opaque where they enter the cell, against what `objectorder`'s occlusion map occludes.

Why: Mora, Jessel and Caubet's Table 1 reports the ratio of occluded cells, and objectorder's target is
>= 70 % on the opaque TFs. Whether a scene can reach that depends on the data (how deep the visible surfaces are)
as much as on the occlusion test, so this measures the bound with the renderer's own rays and samples:

1. every pixel's ray (`patterns.ray_table`, the renderer's step and interleaved offsets) marched in
   float64 through its samples (trilinear, post-classified at the segment's length, as the renderer's
   default), to the position of the sample where its opacity first reaches the termination opacity;
2. every cell the octree's classification leaves visible (the renderer's `cells_visible`): the pixels
   whose centres its eight projected corners' box holds, each ray's entry into the cell (slab test);
   the cell is *occludable* when every ray that crosses it (the renderer's own slab test) is opaque
   before it enters, and *seen* when some ray crosses it at all.

Bound = occludable / seen. Parallel projection, 512x512, as `benchmarks.objectorder_table`.

    python -m benchmarks.occlusion_bound [DATASETS] [STYLES]
"""

from __future__ import annotations

import math
import os
import sys
from pathlib import Path

import numpy as np
from numba import njit, prange
from volren_objectorder import ObjectOrderRenderer
from volren_objectorder.bundles import Grid, Rays
from volren_objectorder.composite import _slab
from volren_objectorder.octree import MinMaxOctree, Reach
from volren_objectorder.patterns import ray_table, sample_t, screen_matrix

from benchmarks.machine_speed import machine_line
from benchmarks.objectorder_table import parallel_camera
from volren.bench.datasets import shared_datasets
from volren.kernels.sample_placement import pixel_phases, segment_length
from volren.model import RenderSettings, TransferFunction1D, UniformVolume

SIZE = 512
STEP = 0.5
TERMINATION = 0.999  # objectorder's default termination_alpha
LUT = 4096


@njit(cache=True)
def _trilinear(values, x, y, z):
    nz, ny, nx = values.shape
    x = min(max(x, 0.0), nx - 1.0)
    y = min(max(y, 0.0), ny - 1.0)
    z = min(max(z, 0.0), nz - 1.0)
    i = min(int(x), nx - 2)
    j = min(int(y), ny - 2)
    k = min(int(z), nz - 2)
    fx, fy, fz = x - i, y - j, z - k
    c00 = values[k, j, i] * (1 - fx) + values[k, j, i + 1] * fx
    c10 = values[k, j + 1, i] * (1 - fx) + values[k, j + 1, i + 1] * fx
    c01 = values[k + 1, j, i] * (1 - fx) + values[k + 1, j, i + 1] * fx
    c11 = values[k + 1, j + 1, i] * (1 - fx) + values[k + 1, j + 1, i + 1] * fx
    return (c00 * (1 - fy) + c10 * fy) * (1 - fz) + (c01 * (1 - fy) + c11 * fy) * fz


@njit(cache=True, parallel=True)
def saturation_depths(values, ro, rd, t0, count, first, last, h, alpha_lut, lo, scale, unit, term, out):
    """out[p] = where pixel p's ray reaches opacity `term` (its sample's position), inf if never."""
    shared = rd.shape[0] == 1
    for p in prange(count.shape[0]):
        q = p - p if shared else p  # one type with the loop index (0 would unify with it as a float)
        out[p] = math.inf
        a = 0.0
        for k in range(count[p]):
            t = sample_t(t0[p], first[p], h, count[p], last[p], k)
            s = _trilinear(values, ro[p, 0] + t * rd[q, 0], ro[p, 1] + t * rd[q, 1], ro[p, 2] + t * rd[q, 2])
            if not np.isfinite(s):
                continue
            x = min(max((s - lo) * scale, 0.0), alpha_lut.shape[0] - 1.0)
            i = min(int(x), alpha_lut.shape[0] - 2)
            opacity = alpha_lut[i] * (1 - (x - i)) + alpha_lut[i + 1] * (x - i)
            length = segment_length(first[p], last[p], h, count[p], k)
            alpha = 1.0 - (1.0 - min(opacity, 1.0 - 1e-12)) ** (length / unit)
            a += (1.0 - a) * alpha
            if a >= term:
                out[p] = t
                break


@njit(cache=True, parallel=True)
def cell_states(visible, M, rays, grid, t_sat, width, height, state):
    """state[z, y, x] for each visible cell (of the `Grid`'s cells) and the `Rays`: 0 not seen by
    any ray, 1 seen, 2 occludable."""
    nz, ny, nx = visible.shape
    ri = rays.inverse
    count = rays.n_samples
    for z in prange(nz):
        for y in range(ny):
            for x in range(nx):
                state[z, y, x] = 0
                if not visible[z, y, x]:
                    continue
                u0 = v0 = math.inf
                u1 = v1 = -math.inf
                for c in range(8):
                    px, py, pz = x + (c & 1), y + ((c >> 1) & 1), z + ((c >> 2) & 1)
                    w = M[2, 0] * px + M[2, 1] * py + M[2, 2] * pz + M[2, 3]
                    u = (M[0, 0] * px + M[0, 1] * py + M[0, 2] * pz + M[0, 3]) / w
                    v = (M[1, 0] * px + M[1, 1] * py + M[1, 2] * pz + M[1, 3]) / w
                    u0, u1, v0, v1 = min(u0, u), max(u1, u), min(v0, v), max(v1, v)
                seen = False
                open_ray = False
                for r in range(max(int(math.ceil(v0)), 0), min(int(math.floor(v1)), height - 1) + 1):
                    for col in range(max(int(math.ceil(u0)), 0), min(int(math.floor(u1)), width - 1) + 1):
                        p = r * width + col
                        if count[p] == 0:
                            continue
                        q = 0 if ri.shape[0] == 1 else p
                        tlo, thi = _slab(rays, grid, p, q, x, y, z, 1, 1, 1)  # the renderer's test
                        if thi > tlo:
                            seen = True
                            if tlo < t_sat[p]:
                                open_ray = True
                                break
                    if open_ray:
                        break
                if seen:
                    state[z, y, x] = 1 if open_ray else 2


def visible_cells(octree: MinMaxOctree, tf: TransferFunction1D) -> np.ndarray:
    """The cells the renderer's post-classified classification leaves visible, (z, y, x) booleans."""
    cls = octree.classify(tf, Reach())
    nz, ny, nx = octree.cell_shape
    bits = np.unpackbits(cls.leaves[..., None], axis=-1, bitorder="little")  # bit x + 2 y + 4 z
    lz, ly, lx = cls.leaves.shape
    cells = bits.reshape(lz, ly, lx, 2, 2, 2).transpose(0, 3, 1, 4, 2, 5).reshape(2 * lz, 2 * ly, 2 * lx)
    return np.ascontiguousarray(cells[:nz, :ny, :nx].astype(bool))


def bound(
    volume: UniformVolume, tf: TransferFunction1D, camera, termination: float = TERMINATION
) -> dict[str, float]:
    """The bound's counts for one view, and what the renderer's occlusion map achieved there, both
    with pixels finished at opacity `termination`."""
    h = STEP * volume.characteristic_length
    rays = ray_table(camera, volume, SIZE, SIZE, h, pixel_phases("interleaved", SIZE, SIZE, 0))
    lo, hi = volume.value_range
    tlo, thi = tf.value_range
    lo, hi = min(lo, tlo), max(hi, thi)
    if not hi > lo:
        hi = lo + 1.0
    _, alpha_lut = tf.sample(np.linspace(lo, hi, LUT))
    t_sat = np.empty(SIZE * SIZE)
    values = np.ascontiguousarray(volume.values, dtype=np.float64)
    saturation_depths(values, rays.origin, rays.direction, rays.t0, rays.count, rays.first, rays.last, h,
                      np.ascontiguousarray(alpha_lut, dtype=np.float64), lo, (LUT - 1) / (hi - lo),
                      tf.opacity_unit_distance, termination, t_sat)  # fmt: skip
    renderer = ObjectOrderRenderer()
    renderer.set_volume(volume)
    renderer.set_transfer_function(tf)
    renderer.set_settings(RenderSettings(step=STEP, options={"termination_alpha": termination}))
    renderer.render(camera, SIZE, SIZE)
    counters = renderer.last_frame.counters
    octree = renderer.octree
    assert octree is not None
    visible = visible_cells(octree, tf)
    state = np.empty(visible.shape, np.int8)
    inv_spacing = 1.0 / np.asarray(volume.spacing, dtype=np.float64)
    cell_states(visible, screen_matrix(camera, volume, SIZE, SIZE),
                Rays(rays.origin, rays.direction, rays.world_direction, rays.inverse, rays.t0, rays.count, rays.first,
                     rays.last),
                Grid(values, visible.shape[2], visible.shape[1], visible.shape[0], *map(float, inv_spacing)), t_sat,
                SIZE, SIZE, state)  # fmt: skip
    seen = int(np.count_nonzero(state > 0))
    occludable = int(np.count_nonzero(state == 2))
    return {"visible": float(visible.sum()), "renderer_visible": counters["cells_visible"], "seen": float(seen),
            "occludable": float(occludable), "bound": occludable / seen if seen else 0.0,
            "achieved": counters["occluded_ratio"], "saturated_rays": float(np.isfinite(t_sat).sum()),
            "rays": float((rays.count > 0).sum())}  # fmt: skip


def main() -> None:
    names = sys.argv[1].split(",") if len(sys.argv) > 1 else ["bonsai", "engine", "aneurism", "ironProt"]
    styles = sys.argv[2].split(",") if len(sys.argv) > 2 else ["opaque"]
    ds = shared_datasets(Path(os.environ.get("VOLREN_SHARED", "../shared")))
    print(machine_line())
    print(
        "| scene | visible cells | seen | occludable | bound | objectorder's occluded ratio | rays opaque |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|")
    for name in names:
        d = ds[name]
        volume = d.load()
        for style, tf in d.transfer_functions():
            if style not in styles:
                continue
            b = bound(volume, tf, parallel_camera(d, volume.bounds))
            assert b["visible"] == b["renderer_visible"], (b["visible"], b["renderer_visible"])
            print(f"| {name} {style} | {b['visible']:.0f} | {b['seen']:.0f} | {b['occludable']:.0f} | "
                  f"{100 * b['bound']:.1f} % | {100 * b['achieved']:.1f} % | "
                  f"{100 * b['saturated_rays'] / max(b['rays'], 1):.0f} % of {b['rays']:.0f} |", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
