"""The largest ray step whose image error stays within a target, estimated from a sample of rays.

Why: how fine a step an image needs depends on the data and the TF, not only on the TF's class
(at step 1 bonsai's smooth TF is within a third of VTK's default's error, ironProt's and
aneurism's are 3-4x beyond it), so one step per class is too fine for some scenes. As in adaptive
step control for ODEs, the error is estimated a posteriori: a sample of the frame's rays is
marched at a much finer step, which stands in for the exact image (post-classified and
pre-integrated sampling both converge to it as the step shrinks), and at the candidate steps from
the coarsest down; the first whose RMSE against the fine rays is within the target is used. The
RMSE over a uniform sample of pixels estimates DESIGN.md's RMSE over all of them.

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

#: Candidate steps: the coarsest times 2^(-k/4), k = 0..8 (down to a quarter of it).
CANDIDATES = 9
#: The fine march's step is the coarsest candidate's over this (half the finest candidate's).
FINE = 8
#: About this many rays are sampled.
SAMPLE_RAYS = 4096


def sample_pixels(width: int, height: int, rays: int = SAMPLE_RAYS) -> NDArray[np.int64]:
    """Row-major indices of about `rays` pixels on a regular grid. Its spacing is odd so that the
    sample holds both phases of interleaved depth offsets (an even spacing meets one only)."""
    spacing = max(1, int(math.sqrt(width * height / rays)))
    spacing += 1 - spacing % 2
    first = spacing // 2
    ys, xs = np.mgrid[min(first, height - 1) : height : spacing, min(first, width - 1) : width : spacing]
    return np.ascontiguousarray((ys * width + xs).ravel(), dtype=np.int64)


def candidate_steps(coarsest: float) -> list[float]:
    return [coarsest * 2.0 ** (-k / 4.0) for k in range(CANDIDATES)]


def largest_step_within(march: Callable[[float], NDArray], coarsest: float, target: float) -> tuple[float, float]:
    """(step, its estimated relative RMSE): the largest candidate step whose rays differ from the
    fine march's by at most `target` times the fine rays' root mean square, or the finest candidate
    when none does. `march(h)` gives the sampled rays' premultiplied RGBA at step h."""
    fine = np.asarray(march(coarsest / FINE), dtype=np.float64)
    scale = float(np.sqrt(np.mean(fine**2)))
    error = math.inf
    for h in candidate_steps(coarsest):
        rmse = float(np.sqrt(np.mean((np.asarray(march(h), dtype=np.float64) - fine) ** 2)))
        error = rmse / scale if scale > 0.0 else 0.0
        if error <= target:
            return h, error
    return h, error
