"""`python -m benchmarks.packet_probe`: how fast one ray-marching loop runs on one core of this machine,
in numba and in C, scalar and in packets of 8 rays; the ceiling a CPU kernel of volren can reach here.

Why: the kernels issue asks for packet kernels at least half as fast as a C packet loop on the same
machine, and for vectorization verified from the generated code. The loop is the inner loop of a
post-classified ray caster without skipping (trilinear sample of a float32 grid, linear lookup in
a 256-entry RGBA TF, front-to-back compositing, each ray stopping at opacity 0.99), the same in
every variant, so the rates compare:

- numba, one ray at a time (`_scalar`);
- numba, 8 rays in lock step, the lanes' work written as a loop over the packet (`_packet`): whether
  LLVM turns it into vector gathers is read from numba's assembly (`vgather` instructions);
- C (`packet_probe.c`, built with the system's C compiler at -O3 -march=native), one ray at a time
  and 8 rays per AVX2 register with hardware gathers.

Each variant draws the same rays; their images agree to float32 rounding (printed). Beside them,
volren's own `raycast` march on the same field and TF (512x512, perspective, step 0.5, no skipping,
one thread): its samples per second, for the same kind of work with its sample placement, clipping
and cut faces.
"""

from __future__ import annotations

import argparse
import ctypes
import shutil
import subprocess
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from numba import float32, int32, njit, uint32
from numpy.typing import NDArray

from benchmarks.machine_speed import machine_line

#: numba's fast-math flags of volren's march kernels.
FAST = {"contract", "nsz", "arcp", "afn"}
#: Rays per packet: one AVX2 register of float32.
LANES = 8
#: Opacity at which a ray stops.
TERM = 0.99
SOURCE = Path(__file__).with_name("packet_probe.c")


@njit(fastmath=FAST, nogil=True, cache=True)
def _scalar(vol, tf, lo, scale, ox, oy, oz, d, nsteps, out):  # pragma: no cover - numba
    """Each ray marched to its end or to opacity TERM; the samples taken."""
    nz, ny, nx = vol.shape
    n = tf.shape[0]
    taken = 0
    for q in range(ox.shape[0]):
        r = g = b = a = float32(0.0)
        for k in range(nsteps):
            x = ox[q] + k * d[0]
            y = oy[q] + k * d[1]
            z = oz[q] + k * d[2]
            if x < 0 or y < 0 or z < 0 or x >= nx - 1 or y >= ny - 1 or z >= nz - 1:
                continue
            i, j, kk = int32(x), int32(y), int32(z)
            fx, fy, fz = x - i, y - j, z - kk
            x00 = vol[kk, j, i] + fx * (vol[kk, j, i + 1] - vol[kk, j, i])
            x10 = vol[kk, j + 1, i] + fx * (vol[kk, j + 1, i + 1] - vol[kk, j + 1, i])
            x01 = vol[kk + 1, j, i] + fx * (vol[kk + 1, j, i + 1] - vol[kk + 1, j, i])
            x11 = vol[kk + 1, j + 1, i] + fx * (vol[kk + 1, j + 1, i + 1] - vol[kk + 1, j + 1, i])
            y0 = x00 + fy * (x10 - x00)
            s = y0 + fz * (x01 + fy * (x11 - x01) - y0)
            taken += 1
            fi = min(max((s - lo) * scale, float32(0.0)), float32(n - 1))
            i0 = min(int32(fi), n - 2)
            w = fi - i0
            ca = tf[i0, 3] + w * (tf[i0 + 1, 3] - tf[i0, 3])
            if ca <= 0.0:
                continue
            tr = (float32(1.0) - a) * ca
            r += tr * (tf[i0, 0] + w * (tf[i0 + 1, 0] - tf[i0, 0]))
            g += tr * (tf[i0, 1] + w * (tf[i0 + 1, 1] - tf[i0, 1]))
            b += tr * (tf[i0, 2] + w * (tf[i0 + 1, 2] - tf[i0, 2]))
            a += tr
            if a >= TERM:
                break
        out[q, 0], out[q, 1], out[q, 2], out[q, 3] = r, g, b, a
    return taken


@njit(fastmath=FAST, nogil=True, cache=True)
def _packet(vol, tf, lo, scale, ox, oy, oz, d, nsteps, out):  # pragma: no cover - numba
    """As `_scalar`, LANES rays in lock step: each step a branch-free loop over the lanes (a lane
    outside the grid or opaque adds nothing), the packet stopping when every lane is opaque."""
    nz, ny, nx = vol.shape
    flat = vol.ravel()
    sy, sz = nx, nx * ny
    n = tf.shape[0]
    channels = [np.ascontiguousarray(tf[:, c]) for c in range(4)]
    tr_, tg_, tb_, ta_ = channels[0], channels[1], channels[2], channels[3]
    px, py, pz = np.empty(LANES, np.float32), np.empty(LANES, np.float32), np.empty(LANES, np.float32)
    r_, g_, b_, a_ = (np.empty(LANES, np.float32), np.empty(LANES, np.float32), np.empty(LANES, np.float32),
                      np.empty(LANES, np.float32))  # fmt: skip
    taken = 0
    for q0 in range(0, ox.shape[0] - LANES + 1, LANES):
        for lane in range(LANES):
            px[lane], py[lane], pz[lane] = ox[q0 + lane], oy[q0 + lane], oz[q0 + lane]
            r_[lane] = g_[lane] = b_[lane] = a_[lane] = 0.0
        for _ in range(nsteps):
            alive = 0
            live = 0
            for lane in range(LANES):
                x, y, z = px[lane], py[lane], pz[lane]
                px[lane], py[lane], pz[lane] = x + d[0], y + d[1], z + d[2]
                going = a_[lane] < TERM
                inside = (x >= 0) & (y >= 0) & (z >= 0) & (x < nx - 1) & (y < ny - 1) & (z < nz - 1) & going
                x = x if inside else float32(0.0)  # a lane outside reads voxel (0, 0, 0) and adds nothing
                y = y if inside else float32(0.0)
                z = z if inside else float32(0.0)
                i, j, kk = int32(x), int32(y), int32(z)
                fx, fy, fz = x - i, y - j, z - kk
                base = uint32(i + j * sy + kk * sz)
                v000, v001 = flat[base], flat[base + uint32(1)]
                v010, v011 = flat[base + uint32(sy)], flat[base + uint32(sy + 1)]
                v100, v101 = flat[base + uint32(sz)], flat[base + uint32(sz + 1)]
                v110, v111 = flat[base + uint32(sz + sy)], flat[base + uint32(sz + sy + 1)]
                x00 = v000 + fx * (v001 - v000)
                x10 = v010 + fx * (v011 - v010)
                x01 = v100 + fx * (v101 - v100)
                x11 = v110 + fx * (v111 - v110)
                y0 = x00 + fy * (x10 - x00)
                s = y0 + fz * (x01 + fy * (x11 - x01) - y0)
                fi = min(max((s - lo) * scale, float32(0.0)), float32(n - 1))
                i0 = min(int32(fi), int32(n - 2))
                w = fi - i0
                u0, u1 = uint32(i0), uint32(i0 + 1)
                ca = ta_[u0] + w * (ta_[u1] - ta_[u0])
                tr = (float32(1.0) - a_[lane]) * ca if inside else float32(0.0)
                r_[lane] += tr * (tr_[u0] + w * (tr_[u1] - tr_[u0]))
                g_[lane] += tr * (tg_[u0] + w * (tg_[u1] - tg_[u0]))
                b_[lane] += tr * (tb_[u0] + w * (tb_[u1] - tb_[u0]))
                a_[lane] += tr
                live += int32(inside)
                alive += int32(going)
            taken += live
            if alive == 0:
                break
        for lane in range(LANES):
            out[q0 + lane, 0], out[q0 + lane, 1] = r_[lane], g_[lane]
            out[q0 + lane, 2], out[q0 + lane, 3] = b_[lane], a_[lane]
    return taken


class Scene:
    """A smooth noisy float32 field of n^3, a TF visible over its upper half, parallel rays through it."""

    def __init__(self, n: int = 192, rays_per_side: int = 256) -> None:
        rng = np.random.default_rng(0)
        z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(np.float32) / n
        field = np.sin(7 * x) * np.cos(5 * y) * np.sin(3 * z + 1) * 0.5 + 0.5 + 0.05 * rng.random((n, n, n))
        self.vol = np.ascontiguousarray(field, dtype=np.float32)
        ramp = np.linspace(0.0, 1.0, 256)
        self.tf = np.stack([ramp, 1 - ramp, np.full(256, 0.5), np.clip((ramp - 0.55) * 0.05, 0, 1)], axis=1)
        self.tf = np.ascontiguousarray(self.tf, dtype=np.float32)
        gy, gx = np.mgrid[0:rays_per_side, 0:rays_per_side]
        self.ox = np.ascontiguousarray(gx.ravel() * (n - 1) / rays_per_side, dtype=np.float32)
        self.oy = np.ascontiguousarray(gy.ravel() * (n - 1) / rays_per_side, dtype=np.float32)
        self.oz = np.zeros(rays_per_side**2, np.float32)
        d = np.array([0.3, 0.2, 1.0])
        self.d = (d / np.linalg.norm(d) * 0.5).astype(np.float32)  # half a voxel a step
        self.nsteps = int(n / self.d[2]) + 2

    def args(self, out: NDArray[np.float32]) -> tuple:
        return (self.vol, self.tf, np.float32(0.0), np.float32(255.0), self.ox, self.oy, self.oz, self.d,
                self.nsteps, out)  # fmt: skip


def assembly_of(kernel: Callable) -> str:
    """numba's assembly of `kernel` for the signatures it was called with, compiled afresh: numba
    does not inspect code it loaded from its cache."""
    fresh = njit(fastmath=FAST, nogil=True)(kernel.py_func)  # type: ignore[attr-defined]
    for signature in kernel.signatures:  # type: ignore[attr-defined]
        fresh.compile(signature)
    return "".join(fresh.inspect_asm().values())


def gathers_in(kernel: Callable) -> int:
    """How many vector gather instructions numba's assembly of `kernel` holds."""
    text = assembly_of(kernel)
    return text.count("vgather") + text.count("vpgather")


def build_c(folder: Path) -> ctypes.CDLL | None:
    """packet_probe.c as a shared library, or None where there is no C compiler."""
    compiler = shutil.which("cc") or shutil.which("gcc")
    if compiler is None:
        return None
    library = folder / "packet_probe.so"
    subprocess.run([compiler, "-O3", "-march=native", "-ffp-contract=fast", "-shared", "-fPIC", "-o", str(library),
                    str(SOURCE)], check=True)  # fmt: skip
    lib = ctypes.CDLL(str(library))
    pointer = ctypes.POINTER(ctypes.c_float)
    for fn in (lib.march_scalar, lib.march_avx2):
        fn.restype = ctypes.c_long
        fn.argtypes = [pointer, *[ctypes.c_int] * 3, pointer, ctypes.c_int, ctypes.c_float, ctypes.c_float,
                       *[pointer] * 3, ctypes.c_int, *[ctypes.c_float] * 3, ctypes.c_int, pointer]  # fmt: skip
    return lib


def c_variant(fn: Callable, scene: Scene) -> Callable[[NDArray[np.float32]], int]:
    def run(out: NDArray[np.float32]) -> int:
        def p(a: NDArray) -> ctypes._Pointer:
            return a.ctypes.data_as(ctypes.POINTER(ctypes.c_float))

        n = scene.vol.shape[0]
        return int(fn(p(scene.vol), n, n, n, p(scene.tf), 256, 0.0, 255.0, p(scene.ox), p(scene.oy), p(scene.oz),
                      scene.ox.size, *map(float, scene.d), scene.nsteps, p(out)))  # fmt: skip

    return run


def variants(scene: Scene, lib: ctypes.CDLL | None) -> dict[str, Callable[[NDArray[np.float32]], int]]:
    found: dict[str, Callable[[NDArray[np.float32]], int]] = {
        "numba, one ray": lambda out: int(_scalar(*scene.args(out))),
        f"numba, {LANES}-ray packets": lambda out: int(_packet(*scene.args(out))),
    }
    if lib is not None:
        found["C, one ray"] = c_variant(lib.march_scalar, scene)
        if lib.has_avx2():
            found[f"C, {LANES}-ray AVX2 packets"] = c_variant(lib.march_avx2, scene)
    return found


def measure(scene: Scene, lib: ctypes.CDLL | None, repeats: int) -> list[tuple[str, int, float, NDArray]]:
    """(variant, samples, best seconds of `repeats`, image) per variant; the variants take turns, one
    run each per round, so that a change in the machine's speed reaches them all alike."""
    runs = variants(scene, lib)
    images = {name: np.zeros((scene.ox.size, 4), np.float32) for name in runs}
    samples = {name: run(images[name]) for name, run in runs.items()}  # compiled, warm
    best = dict.fromkeys(runs, float("inf"))
    for _ in range(repeats):
        for name, run in runs.items():
            start = time.perf_counter()
            run(images[name])
            best[name] = min(best[name], time.perf_counter() - start)
    return [(name, samples[name], best[name], images[name]) for name in runs]


def raycast_rate(scene: Scene, repeats: int, numba_kernels: bool = False) -> tuple[int, float]:
    """(samples, best seconds) of volren's raycast on the scene's field and TF: one thread, no
    skipping; its C march where it builds, or numba's."""
    from contextlib import nullcontext

    import numba

    import volren
    from volren.model.transfer_function import TransferFunction1D
    from volren.model.volume import UniformVolume
    from volren.renderers.raycast.march_native import numba_only

    values = np.linspace(0.0, 1.0, scene.tf.shape[0])
    tf = TransferFunction1D(
        np.column_stack([values, scene.tf[:, :3]]), np.column_stack([values, scene.tf[:, 3]])
    )
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        kernels = numba_only() if numba_kernels else nullcontext()
        drawing = volren.drawing(UniformVolume(scene.vol), tf, renderer="raycast", size=(512, 512), azimuth=30,
                                 elevation=20, step=0.5, options={"empty_space_skipping": False, "target_error": 0.0})  # fmt: skip
        with kernels, drawing:
            drawing.frame()
            best = float("inf")
            for _ in range(repeats):
                start = time.perf_counter()
                _, stats, *_ = drawing.frame()
                best = min(best, time.perf_counter() - start)
    finally:
        numba.set_num_threads(threads)
    return int(stats.counters["samples"]), best


def bonsai_floor(shared: Path, rate_per_core: float, repeats: int) -> str:
    """A line: bonsai's smooth TF at 512x512 with no options (raycast, every core): its samples, its
    warm frame, and the time its samples alone would take at `rate_per_core` on every core."""
    import os

    import volren

    drawing = volren.drawing(shared / "data/uniform/bonsai.vti", shared / "scenes/bonsai-smooth.json",
                             renderer="raycast", size=(512, 512), azimuth=30, elevation=20)  # fmt: skip
    with drawing:
        drawing.frame()
        times = []
        for _ in range(repeats):
            start = time.perf_counter()
            _, stats, *_ = drawing.frame()
            times.append(time.perf_counter() - start)
    samples, cores = stats.counters["samples"], os.cpu_count() or 1
    floor_ms = samples / (rate_per_core * cores) * 1e3
    return (f"bonsai smooth, 512x512, no options (raycast, {cores} cores): {samples / 1e6:.2f} M samples, "
            f"warm frame {float(np.median(times)) * 1e3:.0f} ms; those samples alone at the fastest loop's "
            f"rate on every core: {floor_ms:.0f} ms")  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.packet_probe", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("--size", type=int, default=192, help="grid edge in voxels (default 192)")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument(
        "--shared", type=Path, help="the shared data folder: also time bonsai's default frame"
    )
    args = parser.parse_args(argv)
    scene = Scene(args.size)
    with tempfile.TemporaryDirectory() as folder:
        lib = build_c(Path(folder))
        rows = measure(scene, lib, args.repeats)
    print(machine_line())
    print(f"{args.size}^3 float32, {scene.ox.size} rays, one thread; numba's packet loop: "
          f"{gathers_in(_packet)} vector gathers in its assembly")  # fmt: skip
    if lib is None:
        print("no C compiler found: the C rows are left out")
    marches = {"volren raycast, C march": raycast_rate(scene, args.repeats),
               "volren raycast, numba march": raycast_rate(scene, args.repeats, numba_kernels=True)}  # fmt: skip
    top = max(samples / seconds for _, samples, seconds, _ in rows)
    first = rows[0][3]
    print("\n| loop | samples | ms | M samples/s | of the fastest | largest difference from numba, one ray |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, samples, seconds, image in rows:
        rate = samples / seconds
        print(f"| {name} | {samples} | {seconds * 1e3:.1f} | {rate / 1e6:.1f} | {rate / top:.2f} | "
              f"{float(np.abs(image - first).max()):.1e} |")  # fmt: skip
    for name, (ray_samples, ray_seconds) in marches.items():
        rate = ray_samples / ray_seconds
        print(f"| {name}, 512x512, no skipping | {ray_samples} | {ray_seconds * 1e3:.1f} | {rate / 1e6:.1f} | "
              f"{rate / top:.2f} | (other rays) |")  # fmt: skip
    if args.shared is not None:
        print("\n" + bonsai_floor(args.shared, top, args.repeats))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
