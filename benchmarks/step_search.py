"""`python -m benchmarks.step_search --shared ../shared`: what raycast's step search costs against the
frame it serves, scene by scene.

Why: raycast chooses its step for the `target_error` of a quality level by a search over a sample
of rays (`volren.renderers.raycast.step_choice`) at the first frame of every TF. In the app a TF
edit's full frame pays it; the kernels issue asks for a search of at most 5 % of a frame. Each
scene is drawn at 512x512 with no options (the search and the frame timed by the renderer's own
counters), then its TF's opacity unit distance is changed by 1 % (a new TF: the search runs again,
its kernels warm, the step cache in a new folder) and drawn again: that frame's `step_choice_ms`
against its time.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

from volren.bench.datasets import SCENES, shared_folder

#: The shared grids' datasets (raycast draws grids).
GRIDS = ("bonsai", "engine", "aneurism", "ironProt")
STYLES = ("smooth", "spiky", "opaque")


def search_share(
    path: Path, tf_path: Path, scalars: str | None, repeats: int
) -> tuple[float, float, float] | None:
    """(frame ms, search ms, chosen step) of frames with a new TF each, medians of `repeats`; None where
    the level chosen for the scene sets no error target (no search)."""
    import numpy as np

    import volren
    from volren.model.transfer_function import TransferFunction1D

    drawing = volren.drawing(path, tf=tf_path, renderer="raycast", size=(512, 512), azimuth=30, elevation=20,
                             scalars=scalars)  # fmt: skip
    frames, searches = [], []
    with drawing:
        drawing.frame()
        tf = drawing.scene.transfer_function
        assert isinstance(tf, TransferFunction1D)
        for k in range(repeats):
            changed = TransferFunction1D(tf.color_points, tf.opacity_points,
                                         opacity_unit_distance=tf.opacity_unit_distance * (1.01 + 0.01 * k))  # fmt: skip
            drawing.set_transfer_function(changed)
            _, stats, *_ = drawing.frame()
            if "step_choice_ms" not in stats.counters:
                return None
            frames.append(stats.ms)
            searches.append(stats.counters["step_choice_ms"])
    return float(np.median(frames)), float(np.median(searches)), float(stats.counters["step"])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.step_search", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("--shared", help="the folder with data/ and scenes/ (default: $VOLREN_SHARED)")
    parser.add_argument("--repeats", type=int, default=3, help="new TFs per scene (default 3)")
    args = parser.parse_args(argv)
    shared = shared_folder(args.shared)
    os.environ["VOLREN_STEP_CACHE"] = tempfile.mkdtemp(prefix="volren-steps-")  # every search runs
    print("| scene | frame ms | search ms | search / frame | step |")
    print("|---|---:|---:|---:|---:|")
    for name in GRIDS:
        rel, scalars = SCENES[name][0], SCENES[name][1]
        for style in STYLES:
            found = search_share(shared / "data" / rel, shared / "scenes" / f"{name}-{style}.json", scalars,
                                 args.repeats)  # fmt: skip
            if found is None:
                print(f"| {name} {style} | | no search: the level sets no error target | | |", flush=True)
                continue
            frame_ms, search_ms, step = found
            print(f"| {name} {style} | {frame_ms:.0f} | {search_ms:.0f} | {search_ms / frame_ms:.2f} | {step:.3f} |",
                  flush=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
