"""Time series: a ParaView `.pvd` collection, a folder of volume files, or an OME-Zarr image's t
axis, as a list of steps.

A `.pvd` names its steps' files (relative to itself) with their times; a folder's volume files
are its steps in natural order ("step_2" before "step_10"), at times 0, 1, 2, ...; an OME-Zarr
image's t axis gives steps ``image.zarr#t=N`` at the times its scale and translation say (local
images; over a URL, name a time point). A folder of DICOM slices is one volume, not a series, and
so is a folder with fewer than two volume files. Only the list is read here: each step is a volume
file (or time point) that `load_volume` reads when needed.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass
from pathlib import Path

from volren.errors import VolrenError, file_error
from volren.io.formats import DICOM, FORMATS, suffix_of

#: More steps than this is a listing gone wrong, not a simulation to step through by hand.
MAX_STEPS = 100_000
#: The suffixes of one-file volumes (DICOM slices make a volume together, not a step each).
STEP_SUFFIXES = frozenset(s for f in FORMATS if f is not DICOM for s in f.suffixes)


@dataclass(frozen=True)
class TimeSeries:
    """The steps of a time series: their files and times (increasing)."""

    source: Path
    steps: tuple[Path, ...]
    times: tuple[float, ...]

    def __len__(self) -> int:
        return len(self.steps)

    def label(self, index: int) -> str:
        """How step `index` is named to people: its place, its time and its file."""
        return f"step {index + 1} of {len(self)} (t = {self.times[index]:g}, {self.steps[index].name})"


def _natural_key(path: Path) -> list[object]:
    return [int(part) if part.isdigit() else part.lower() for part in re.split(r"(\d+)", path.name)]


def _folder_steps(folder: Path) -> list[Path]:
    return sorted(
        (p for p in folder.iterdir() if p.is_file() and suffix_of(p) in STEP_SUFFIXES), key=_natural_key
    )


def _zarr_times(path: Path) -> tuple[float, ...] | None:
    """The times of an OME-Zarr image's time points (None: not an OME-Zarr image, or one that
    cannot be opened: reading it says why)."""
    from volren.io.ome_zarr_io import is_ome_zarr, open_multiscale, split_time_point

    if not is_ome_zarr(path) or split_time_point(path)[1] is not None:
        return None
    try:
        return open_multiscale(path, channels_ok=True, times_ok=True).times
    except VolrenError:
        return None


def is_series(path: str | Path) -> bool:
    """Whether `path` is a time series: a .pvd file, a folder with two or more volume files, or an
    OME-Zarr image whose t axis holds two or more time points."""
    path = Path(path)
    zarr_times = _zarr_times(path)
    if zarr_times is not None:
        return len(zarr_times) >= 2
    if path.is_file():
        return path.suffix.lower() == ".pvd"
    if path.is_dir():
        try:
            return len(_folder_steps(path)) >= 2
        except OSError:
            return False
    return False


def _read_pvd(path: Path) -> tuple[list[Path], list[float]]:
    try:
        root = ElementTree.parse(path).getroot()
    except (ElementTree.ParseError, OSError, UnicodeDecodeError) as exc:
        raise file_error(path, f"not a readable .pvd collection: {' '.join(str(exc).split())}") from None
    if root.tag != "VTKFile" or root.get("type") != "Collection":
        raise file_error(path, 'not a ParaView data collection (expected <VTKFile type="Collection">)')
    entries = root.findall("./Collection/DataSet")
    if not entries:
        raise file_error(path, "the collection lists no data sets")
    if len(entries) > MAX_STEPS:
        raise file_error(path, f"the collection lists {len(entries):,} data sets; at most {MAX_STEPS:,}")
    if any(entry.get("part", "0") != "0" for entry in entries):
        raise file_error(
            path, "the collection has several parts per time step; volren reads one volume per step"
        )
    steps, times = [], []
    for index, entry in enumerate(entries):
        name = entry.get("file")
        if not name:
            raise file_error(path, f"data set {index} has no 'file'")
        try:
            time = float(entry.get("timestep", index))
        except ValueError:
            raise file_error(
                path, f"data set {index}: timestep {entry.get('timestep')!r} is not a number"
            ) from None
        if not math.isfinite(time):
            raise file_error(path, f"data set {index}: timestep {entry.get('timestep')!r} is not finite")
        steps.append((path.parent / name).resolve())
        times.append(time)
    order = sorted(range(len(steps)), key=lambda i: times[i])  # a stable sort: equal times keep file order
    return [steps[i] for i in order], [times[i] for i in order]


def load_series(path: str | Path) -> TimeSeries:
    """The steps of the .pvd or folder at `path`; one-line errors name the file and the problem
    (every step's file must exist; reading it is `load_volume`'s job, step by step)."""
    path = Path(path)
    if not path.exists():
        raise file_error(path, "no such file or folder")
    zarr_times = _zarr_times(path)
    if zarr_times is not None:
        return _zarr_series(path, zarr_times)
    if path.is_dir():
        steps = _folder_steps(path)
        if len(steps) < 2:
            raise file_error(
                path,
                f"a time series folder needs two or more volume files ({', '.join(sorted(STEP_SUFFIXES))})",
            )
        if len(steps) > MAX_STEPS:
            raise file_error(path, f"{len(steps):,} volume files; a time series has at most {MAX_STEPS:,}")
        times = [float(i) for i in range(len(steps))]
    elif path.suffix.lower() == ".pvd":
        steps, times = _read_pvd(path)
        missing = [step for step in steps if not step.is_file()]
        if missing:
            raise file_error(
                path, f"{len(missing)} of its {len(steps)} files are missing, e.g. {missing[0].name}"
            )
    else:
        raise VolrenError(f"{path}: not a time series (a .pvd file, or a folder of volume files)")
    return TimeSeries(path, tuple(steps), tuple(times))


def _zarr_series(path: Path, times: tuple[float, ...]) -> TimeSeries:
    """An OME-Zarr image's time points as steps named ``image.zarr#t=N`` (`load_volume` reads one;
    the image's t axis is never read whole)."""
    from volren.io.ome_zarr_io import time_point_path

    if len(times) < 2:
        raise file_error(path, "an OME-Zarr time series needs a t axis of two or more time points")
    if len(times) > MAX_STEPS:
        raise file_error(path, f"{len(times):,} time points; a time series has at most {MAX_STEPS:,}")
    return TimeSeries(path, tuple(Path(time_point_path(path, k)) for k in range(len(times))), times)
