"""The largest ray step whose image error stays within a target, estimated from a sample of rays.

Why: how fine a step an image needs depends on the data and the TF, not only on the TF's class
(at step 1 bonsai's smooth TF is within a third of VTK's default's error, ironProt's and
aneurism's are 3-4x beyond it), so one step per class is too fine for some scenes. As in adaptive
step control for ODEs, the error is estimated a posteriori: the rays of a ~64x64 image of the
frame's view are marched at a much finer step, which stands in for the exact image
(post-classified and pre-integrated sampling both converge to it as the step shrinks), and at
candidate steps found by bisection between the coarsest and the finest; the coarsest found within
the target is used. The RMSE over those rays estimates DESIGN.md's RMSE over the frame's pixels
(each ray is a sample of the same image plane).

The target is relative to the image's root mean square (a normalised RMSE), so that it asks the
same of a volume that fills the view and of one that covers a tenth of it: VTK's default makes
0.4-1.0 % on the shared smooth scenes, and 0.8e-3 absolute was a third of its error on one
and 1.05x on another.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

#: Candidate steps: the coarsest times 2^(-k/8), k = 0..24 (three octaves, 9 % apart).
CANDIDATES = 25
#: The fine march's step is the coarsest candidate's over this (half the finest candidate's).
FINE = 16
#: About this many rays are sampled.
SAMPLE_RAYS = 4096


def sample_size(width: int, height: int, rays: int = SAMPLE_RAYS) -> tuple[int, int]:
    """The size of the image whose every pixel's ray is sampled: about `rays` pixels, the frame's
    aspect. Why a size of its own and not a subset of the frame's pixels: the estimate must not
    depend on the first frame's size (the app warms a renderer up with an 8x8 frame)."""
    aspect = width / height
    return max(1, round(math.sqrt(rays * aspect))), max(1, round(math.sqrt(rays / aspect)))


def candidate_steps(coarsest: float) -> list[float]:
    return [coarsest * 2.0 ** (-k / 8.0) for k in range(CANDIDATES)]


def largest_step_within(
    march: Callable[[float], NDArray], coarsest: float, target: float
) -> tuple[float, float]:
    """(step, its estimated relative RMSE): a candidate step whose rays differ from the fine
    march's by at most `target` times the fine rays' root mean square while the next coarser
    candidate's do not, found by bisection (the error grows with the step), or the finest candidate
    when none is within. `march(h)` gives the sampled rays' premultiplied RGBA at step h."""
    fine = np.asarray(march(coarsest / FINE), dtype=np.float64)
    scale = float(np.sqrt(np.mean(fine**2)))
    steps = candidate_steps(coarsest)

    def error(k: int) -> float:
        rmse = float(np.sqrt(np.mean((np.asarray(march(steps[k]), dtype=np.float64) - fine) ** 2)))
        return rmse / scale if scale > 0.0 else 0.0

    best = error(0)
    if best <= target:
        return steps[0], best
    coarse, within = 0, len(steps) - 1  # the error exceeds the target at `coarse`, and at `within`?
    best = error(within)
    if best > target:
        return steps[within], best
    while within - coarse > 1:
        middle = (coarse + within) // 2
        e = error(middle)
        if e <= target:
            within, best = middle, e
        else:
            coarse = middle
    return steps[within], best
