"""`python -m benchmarks.memory_budget [--size N] [--memory SIZE]`: whether `volren convert` and
`volren render` stay within `--memory` on a volume larger than it.

A procedural uint16 volume of N^3 samples (default 512^3 = 256 MiB) is written as raw data with a
NRRD header, a slab at a time; then each command runs in a child process and its peak resident
memory is read from the kernel (`os.wait4`'s rusage: the largest of the command's processes).
The fixed overhead (interpreter, imports, the GL context and shaders, caches) is the peak of the
same command on a 16^3 volume (in 8^3 bricks, rendered streamed too, at --memory 12KB); "working"
is the peak less that overhead, the part `--memory` bounds:

- convert N^3 raw NRRD --memory SIZE (streamed, a row of bricks at a time);
- render the pyramid at quality default (level 0, streamed within SIZE) at 256^2 with the slicer;
- render --level 1 --memory SIZE: a level whose values fit in SIZE but whose renderer copies do
  not (read whole before the budget counted them; streamed now).

`--volren DIR` runs the commands on another checkout's code (PYTHONPATH=DIR; its convert is given
no --memory, which it may not know): the numbers before a change. About a minute on two cores at
the defaults.

    .venv/bin/python -m benchmarks.memory_budget
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

MIB = 1 << 20
RENDER = ["--renderer", "slicer", "--size", "256", "--quality", "default"]


def write_nrrd(path: Path, n: int) -> None:
    """n^3 uint16 samples of a smooth field, x fastest, after a NRRD header, one z slice at a time."""
    axis = np.arange(n, dtype=np.float32)
    y, x = np.meshgrid(axis, axis, indexing="ij")
    plane = 2000 + 1500 * np.sin(0.05 * x) * np.cos(0.04 * y)
    with open(path, "wb") as f:
        f.write(f"NRRD0004\ntype: uint16\ndimension: 3\nsizes: {n} {n} {n}\nendian: little\nencoding: raw\n"
                "spacings: 1 1 1\n\n".encode())  # fmt: skip
        for k in range(n):
            f.write((plane + 4000 * k / n).astype("<u2").tobytes())


#: Runs its arguments as a child and prints the child's peak resident memory last. Why a process
#: between: Linux keeps the largest resident size a process ever had across exec (exec_mmap records
#: the old image's high-water mark), and a child started from a large process (a test worker that
#: holds gigabytes) starts as that process's image, so its own peak would read as the parent's.
#: This small process's children start from its image instead.
_MEASURE = """
import os, subprocess, sys
child = subprocess.Popen(sys.argv[1:])
_, status, usage = os.wait4(child.pid, 0)
print(f"{PEAK_TAG} {usage.ru_maxrss}", flush=True)
sys.exit(os.waitstatus_to_exitcode(status))
"""
PEAK_TAG = "volren-memory-budget-peak-KiB"


def peak(argv: list[str], code: str | None, cwd: Path) -> tuple[float, float, str]:
    """(peak resident MiB, seconds, last output line) of `volren ARGV` in a child process."""
    env = dict(os.environ, NUMBA_NUM_THREADS="1")
    if code:
        env["PYTHONPATH"] = code
    command = [
        sys.executable,
        "-c",
        _MEASURE.replace("PEAK_TAG", repr(PEAK_TAG)),
        sys.executable,
        "-c",
        "import sys; from volren.cli.main import main; sys.exit(main(sys.argv[1:]))",
        *argv,
    ]
    start = time.perf_counter()
    # run from the temporary folder: a checkout in the working folder would come first
    child = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env, cwd=cwd)
    seconds = time.perf_counter() - start
    lines = [line for line in child.stdout.decode(errors="replace").splitlines() if line.strip()]
    kib = [float(line.split()[1]) for line in lines if line.startswith(PEAK_TAG)]
    lines = [line for line in lines if not line.startswith(PEAK_TAG)]
    said = lines[-1] if lines else ""
    if child.returncode != 0:
        said = f"FAILED ({child.returncode}): {said}"
    return (kib[-1] if kib else float("nan")) / 1024, seconds, said


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=512, help="samples a side of the volume (default 512)")
    parser.add_argument("--memory", default="64MB", help="the budget given to every command (default 64MB)")
    parser.add_argument("--volren", metavar="DIR", help="run the commands on the volren package under DIR")
    args = parser.parse_args()
    from volren.io.ome_zarr_io import parse_memory

    budget = parse_memory(args.memory) / MIB
    with tempfile.TemporaryDirectory(prefix="volren-memory-") as folder:
        tmp = Path(folder)
        write_nrrd(tmp / "small.nrrd", 16)
        write_nrrd(tmp / "big.nrrd", args.size)
        volume = args.size**3 * 2 / MIB
        print(f"{args.size}^3 uint16 = {volume:.0f} MiB, --memory {args.memory} ({budget:.0f} MiB); peak resident "
              f"memory of each command (MiB){' with ' + args.volren if args.volren else ''}")  # fmt: skip
        print(
            f"{'command':<44} {'peak':>7} {'fixed':>7} {'working':>8} {'budget':>7} {'time s':>7}  what it said"
        )
        convert = ["convert", "{nrrd}", "{zarr}", "--force", "--chunks", "{chunks}"]
        convert += [] if args.volren else ["--memory", args.memory]
        rows = [
            ("convert raw NRRD" + (" (no --memory)" if args.volren else ""), convert),
            (
                "render, quality default",
                [
                    "render",
                    "{zarr}",
                    *RENDER,
                    "--memory",
                    "{memory}",
                    "--save-array",
                    str(tmp / "a.npy"),
                    "--force",
                ],
            ),  # fmt: skip
            (
                "render --level 1",
                [
                    "render",
                    "{zarr}",
                    *RENDER,
                    "--level",
                    "{level}",
                    "--memory",
                    "{memory}",
                    "--save-array",
                    str(tmp / "b.npy"),
                    "--force",
                ],
            ),  # fmt: skip
        ]
        for label, argv in rows:
            # the 16^3 pyramid in 8^3 bricks has two levels, both streamed at 12KB: the same code runs
            # (code before the renderer's copies were counted reads them whole: its fixed overhead is smaller)
            small = [a.format(nrrd=tmp / "small.nrrd", zarr=tmp / "small.zarr", memory="12KB", level=1, chunks=8)
                     for a in argv]  # fmt: skip
            big = [a.format(nrrd=tmp / "big.nrrd", zarr=tmp / "big.zarr", memory=args.memory, level=1, chunks=64)
                   for a in argv]  # fmt: skip
            fixed, _, said = peak(small, args.volren, tmp)
            if "FAILED" in said:
                raise SystemExit(f"the 16^3 run failed: {said}")
            top, seconds, said = peak(big, args.volren, tmp)
            print(
                f"{label:<44} {top:7.0f} {fixed:7.0f} {top - fixed:8.0f} {budget:7.0f} {seconds:7.1f}  {said[:110]}"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
