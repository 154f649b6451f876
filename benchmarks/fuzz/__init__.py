"""The fuzz suite: a deterministic corpus of malformed inputs run through `volren`.

`corpus()` generates the cases (volume files of every format, meshes, TF and scene JSON,
command-line flags, OME-Zarr images, `convert` and `movie`, output paths); `runner.run_cases` runs each in a child process with a time limit and
classifies the outcome (render, clean error, crash, hang, traceback, several lines, unnamed
culprit, bad pixels, nondeterministic image, bad header accepted in silence); `report` writes the
summary. `python -m benchmarks.fuzz` runs it all; CI runs `quick_corpus()`.
"""

from __future__ import annotations

from benchmarks.fuzz import command_cases as commands
from benchmarks.fuzz import output_cases as outputs
from benchmarks.fuzz.cases import Case
from benchmarks.fuzz.json_cases import flag_cases, scene_cases, tf_cases
from benchmarks.fuzz.volume_cases import volume_cases
from benchmarks.fuzz.zarr_cases import written_by_hand as zarr_by_hand
from benchmarks.fuzz.zarr_cases import zarr_cases

#: The families whose cases are written by hand, each a fault of its own, but for their sweeps.
BY_HAND = frozenset({outputs.GROUP, commands.CONVERT, commands.MOVIE, commands.FLAGS})


def corpus(seed: int = 0) -> list[Case]:
    """Every case, in a fixed order; `seed` drives the byte-level randomness."""
    return [*volume_cases(seed), *tf_cases(), *scene_cases(), *flag_cases(), *zarr_cases(), *outputs.output_cases(),
            *commands.command_cases()]  # fmt: skip


def written_by_hand(case: Case) -> bool:
    """A case of the OME-Zarr, output, convert, movie or cluster and memory flag families other
    than their sweeps': all in the quick subset."""
    return zarr_by_hand(case) or (case.group in BY_HAND and "/sweep-" not in case.name)


def quick_corpus(seed: int = 0, every: int = 12) -> list[Case]:
    """Every `every`-th case plus every valid seed, every case that once crashed or hung, and every
    case written by hand (`written_by_hand`: a couple of hundred, each a fault of its own)."""
    cases = corpus(seed)
    return [c for i, c in enumerate(cases)
            if i % every == 0 or c.expect == "render" or c.name in REGRESSIONS or written_by_hand(c)]  # fmt: skip


#: Cases that once crashed, hung or rendered uninitialized memory: always in the quick subset.
REGRESSIONS: frozenset[str] = frozenset({
    # vtkDICOMImageReader: SIGSEGV (RescaleSlope outside float's range), double free (a fractional
    # rescale in one slice), short or missing pixel data read from uninitialized memory
    "dicom/rescale_slope[2]-one", "dicom/rescale_slope[3]-all", "dicom/rescale_slope[3]-one",
    "dicom/rescale_intercept[1]-one", "dicom/pixel-data-short", "dicom/pixel-data-length-lies",
    "dicom/pixel-data-missing", "dicom/cut-0.5",
    # vtkSLCReader: runs written or read past their buffers, negative sizes, short slices
    "slc/run-longer-than-slice", "slc/literal-run-past-block", "slc/repeat-run-without-value",
    "slc/size-negative", "slc/icon-negative", "slc/runs-short-of-slice",
    # vtkNIFTIImageReader: vox_offset NaN/inf (an internal error), a cut .nii.gz read in silence
    "nii/vox_offset=nan", "nii-gz/vox_offset=inf", "nii-gz/cut-0.99",
})  # fmt: skip

__all__ = ["Case", "corpus", "quick_corpus"]
