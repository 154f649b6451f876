"""`python -m benchmarks.readers`: volren's readers against VTK's, for speed and equality.

Why: volren reads most formats with VTK's own readers after checking every header field they
read, in a child process (`volren.io.isolation`); DICOM with pydicom and SLC with its own few
lines. This measures what that choice costs and shows it reads the same numbers: for the shared
real datasets, and for bonsai (256^3) written in every other format, the median time of

- `vtk`: PyVista's `pv.read` (VTK's reader) and the point array as numpy, in this process;
- `checked`: volren's header checks and reader, in this process (`read_with_header`);
- `volren`: `volren.io.load_volume` as users call it (checks, reader, child process);
- `pynrrd` and `nibabel`: the format's own Python reader, where installed;

and the largest difference of volren's values from VTK's and from the values written (where the
script wrote the file). VTK's NRRD reader returns unfilled memory for ASCII data, which volren
parses itself, so that row's VTK difference is garbage by design. VTK's DICOM reader returns the rows bottom-up and the slices in reverse
(here, where the slices' z rises with their number); volren's follow the world axes, so that
comparison flips both first.
"""

from __future__ import annotations

import argparse
import gzip
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from benchmarks._cli import run
from benchmarks.preint import median_seconds
from volren.bench.datasets import shared_folder


@dataclass
class Case:
    """A file to read, the values it holds where known, and how VTK's rows relate to volren's."""

    label: str
    path: Path
    truth: NDArray | None = None
    vtk_rows_flipped: bool = False


#: The formats bonsai is written in, in order.
WRITTEN = ("legacy .vtk", "MetaImage .mha", "MetaImage .mha zlib", "NRRD raw", "NRRD gzip", "NRRD ascii",
           "NIfTI .nii", "NIfTI .nii.gz", "SLC (RLE)", "DICOM (256 slices)")  # fmt: skip


def _median_ms(read: Callable[[], NDArray], repeats: int) -> tuple[float, NDArray]:
    """Median ms of `repeats` reads after a warm one (imports, page cache, numba), and the values read."""
    seconds, values = median_seconds(read, repeats)
    return seconds * 1000.0, values


def _vtk_values(path: Path, flipped: bool) -> NDArray:
    import pyvista as pv

    data = pv.read(path)
    if isinstance(data, pv.MultiBlock):
        data = data[0]
    name = data.point_data.active_scalars_name or data.point_data.keys()[0]  # volren's choice too
    values = np.asarray(data.point_data[name])
    if isinstance(data, pv.ImageData) and values.ndim == 1:
        nx, ny, nz = data.dimensions
        values = values.reshape(nz, ny, nx)
        if flipped:
            values = values[::-1, ::-1, :]
    return values


def _volren_values(path: Path, in_process: bool) -> NDArray:
    from volren.io.volume_io import load_volume, read_with_header

    volume = read_with_header(path) if in_process else load_volume(path)
    return np.asarray(volume.values)


def _pynrrd(path: Path) -> NDArray:
    import nrrd  # pynrrd

    values, _ = nrrd.read(str(path))
    return np.ascontiguousarray(values.T)


def _nibabel(path: Path) -> NDArray:
    import nibabel

    return np.ascontiguousarray(np.asarray(nibabel.load(str(path)).dataobj).T)


def _installed(module: str) -> bool:
    try:
        __import__(module)
    except ImportError:
        return False
    return True


def _difference(a: NDArray, b: NDArray | None) -> str:
    if b is None:
        return "-"
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    if a.size != b.size:
        return f"sizes differ ({a.size} vs {b.size})"
    return f"{np.abs(a.reshape(-1) - b.reshape(-1)).max():g}"


def _written_cases(folder: Path, values: NDArray[np.uint8]) -> list[Case]:
    """bonsai's values written as legacy VTK, MetaImage, NRRD (raw, gzip), NIfTI, DICOM and SLC."""
    import pyvista as pv
    import vtk

    from benchmarks.fuzz.seeds import slc_bytes
    from volren.testing.dicom_series import write_series

    nz, ny, nx = values.shape
    image = pv.ImageData(dimensions=(nx, ny, nz))
    image.point_data["values"] = values.reshape(-1)
    image.save(folder / "bonsai.vtk", binary=True)
    for name, compress in (("bonsai.mha", False), ("bonsai-zlib.mha", True)):
        writer = vtk.vtkMetaImageWriter()
        writer.SetInputData(image)
        writer.SetFileName(str(folder / name))
        writer.SetCompression(compress)
        writer.Write()
    header = (
        f"NRRD0004\ntype: uint8\ndimension: 3\nsizes: {nx} {ny} {nz}\nspacings: 1 1 1\n"
        "kinds: domain domain domain\nencoding: {}\n\n"
    )
    raw = values.tobytes()
    (folder / "bonsai.nrrd").write_bytes(header.format("raw").encode() + raw)
    (folder / "bonsai-gzip.nrrd").write_bytes(header.format("gzip").encode() + gzip.compress(raw, 6, mtime=0))
    text = "\n".join(" ".join(map(str, row)) for row in values.reshape(-1, nx)).encode()
    (folder / "bonsai-ascii.nrrd").write_bytes(header.format("ascii").encode() + text + b"\n")
    image.save(folder / "bonsai.nii")
    image.save(folder / "bonsai.nii.gz")
    (folder / "bonsai.slc").write_bytes(slc_bytes(values, compressed=True))
    write_series(folder / "bonsai-dicom", values.astype(np.int16), (1.0, 1.0, 1.0), (0.0, 0.0, 0.0))
    names = ("bonsai.vtk", "bonsai.mha", "bonsai-zlib.mha", "bonsai.nrrd", "bonsai-gzip.nrrd", "bonsai-ascii.nrrd", "bonsai.nii",
             "bonsai.nii.gz", "bonsai.slc", "bonsai-dicom")  # fmt: skip
    return [Case(f"bonsai as {label}", folder / name, values, name == "bonsai-dicom")
            for label, name in zip(WRITTEN, names, strict=True)]  # fmt: skip


def _shared_cases(data: Path) -> list[Case]:
    names = ("uniform/bonsai.vti", "uniform/engine.vti", "uniform/aneurism.vti", "uniform/ironProt.vtk",
             "uniform/HeadMRVolume.mhd", "uniform/neghip.slc", "tets/spx.vtk", "tets/post_small_tets.vtk",
             "tets/bluntfin_tets.vtu", "tets/oxygen_post_tets.vtu")  # fmt: skip
    return [Case(name, data / name) for name in names if (data / name).exists()]


def measure(args: argparse.Namespace) -> int:
    data = shared_folder(args.shared) / "data"  # type: ignore[operator]
    extra = {"pynrrd": ("nrrd", (".nrrd",), _pynrrd), "nibabel": ("nibabel", (".nii", ".nii.gz"), _nibabel)}
    extra = {k: v for k, v in extra.items() if _installed(v[0])}
    print(f"# volren's readers against VTK's (median of {args.repeats}, ms)\n")
    print("| file | vtk | checked | volren | volren / vtk | " + "".join(f"{k} | " for k in extra)
          + "max diff volren-vtk | max diff volren-written |")  # fmt: skip
    print("|---|" + "---:|" * (4 + len(extra)) + "---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        from volren.io.volume_io import load_volume

        bonsai = np.asarray(load_volume(data / "uniform/bonsai.vti").values, np.uint8)
        cases = _shared_cases(data)
        if not args.only or any(args.only in f"bonsai as {label}" for label in WRITTEN):
            cases += _written_cases(Path(tmp), bonsai)
        for case in cases:
            if args.only and args.only not in case.label:
                continue
            path, flipped = case.path, case.vtk_rows_flipped
            vtk_ms, vtk_values = _median_ms(partial(_vtk_values, path, flipped), args.repeats)
            checked_ms, _ = _median_ms(partial(_volren_values, path, True), args.repeats)
            volren_ms, values = _median_ms(partial(_volren_values, path, False), args.repeats)
            cells = []
            for _, suffixes, reader in extra.values():
                hit = any(path.name.endswith(s) for s in suffixes)
                cells.append(f"{_median_ms(partial(reader, path), args.repeats)[0]:.1f}" if hit else "-")
            print(f"| {case.label} | {vtk_ms:.1f} | {checked_ms:.1f} | {volren_ms:.1f} | {volren_ms / vtk_ms:.2f} | "
                  + "".join(f"{c} | " for c in cells)
                  + f"{_difference(values, vtk_values)} | {_difference(values, case.truth)} |",
                  flush=True)  # fmt: skip
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.readers", description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=5, help="timed reads per reader and file (median)")
    parser.add_argument("--shared", help="the shared folder with data/ (default: $VOLREN_SHARED)")
    parser.add_argument("--only", help="files whose label contains this text")
    return run(measure, parser, argv)


if __name__ == "__main__":
    raise SystemExit(main())
