"""`volren convert INPUT OUT.zarr`: any volume volren reads, as a bricked OME-Zarr pyramid.

The pyramid's levels are 2x2x2 block means down to one brick (or --levels of them), each brick's
value range stored beside NGFF's metadata (`volren.io.ome_zarr_io`), so that renderers can skip
bricks a TF leaves transparent without reading them. A progress bar counts the bricks written.
"""

from __future__ import annotations

import argparse

from volren.errors import VolrenError


def _positive(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a number above 0, got {text!r}")
    return value


def add_parser(sub) -> None:
    from volren.model.pyramid import DEFAULT_CHUNK

    p = sub.add_parser("convert", help="write a volume as a bricked multiresolution OME-Zarr image")
    p.add_argument("input", help="volume file or DICOM folder (a uniform grid)")
    p.add_argument("output", help="the OME-Zarr folder to write, e.g. volume.zarr")
    p.add_argument("--chunks", type=_positive, default=DEFAULT_CHUNK, metavar="N",
                   help=f"bricks of N^3 samples (default {DEFAULT_CHUNK})")  # fmt: skip
    p.add_argument("--levels", type=_positive, metavar="N",
                   help="levels of the pyramid (default: down to one brick)")  # fmt: skip
    p.add_argument("--scalars", help="the array to convert (as volren render --scalars)")
    p.add_argument("--force", action="store_true", help="replace OUTPUT if it exists")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from volren import io
    from volren.cli.progress import progress_bar
    from volren.io.ome_zarr_io import require_zarr, save_ome_zarr
    from volren.io.safe_write import output_target, refuse_overwriting_inputs
    from volren.model.volume import UniformVolume

    require_zarr()  # before a long load
    output = Path(args.output)
    if output.suffix.lower() != ".zarr":
        raise VolrenError(f"{output}: an OME-Zarr image is a folder named *.zarr")
    refuse_overwriting_inputs([("OUTPUT", output)], [("input", args.input)], kind="folder")  # even with --force
    if output.exists() and not args.force:
        raise VolrenError(f"{output}: exists; add --force to replace it")
    volume = io.load_volume(args.input, scalars=args.scalars)
    if not isinstance(volume, UniformVolume):
        raise VolrenError(f"{args.input}: a tetrahedral mesh has no bricks; OME-Zarr holds uniform grids")
    with progress_bar(f"{output.name}") as progress:
        levels = save_ome_zarr(volume, output_target(output, "OUTPUT", "folder"), args.chunks, args.levels, progress)
    nx, ny, nz = volume.dimensions
    print(f"{args.input}: {nx}x{ny}x{nz} {volume.values.dtype} -> {output} ({levels} levels, "
          f"{args.chunks}^3 bricks)")  # fmt: skip
    return 0
