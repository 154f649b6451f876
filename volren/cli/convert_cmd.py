"""`volren convert INPUT OUT.zarr`: any volume volren reads, as a bricked OME-Zarr pyramid.

The pyramid's levels are 2x2x2 block means down to one brick (or --levels of them), each brick's
value range stored beside NGFF's metadata (`volren.io.ome_zarr_io`), so that renderers can skip
bricks a TF leaves transparent without reading them. A progress bar counts the bricks written.

Memory: an input whose values lie uncompressed in its file (raw NRRD, uncompressed MetaImage,
headerless raw data) is streamed, a row of bricks at a time (`volren.io.mapped_input`), and each
coarser level is made brick by brick from the one below as written, so a volume larger than memory
converts. Any other
input is read whole, which one line says with its size; with --memory it is refused when reading
it whole would take more.
"""

from __future__ import annotations

import argparse

from volren.cli.raw_flags import add_raw_arguments, check_raw_flags, raw_load_arguments
from volren.errors import VolrenError


def _positive(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a number above 0, got {text!r}")
    return value


def _chunk_side(text: str) -> int:
    """--chunks: a brick side the pyramid writer takes, refused as a usage error before the load."""
    from volren.model.pyramid import MAX_CHUNK, MIN_CHUNK

    try:
        value = int(text)
    except ValueError:
        value = 0
    if not MIN_CHUNK <= value <= MAX_CHUNK:
        raise argparse.ArgumentTypeError(f"expected {MIN_CHUNK} to {MAX_CHUNK} samples a side, got {text!r}")
    return value


def add_parser(sub) -> None:
    from volren.model.pyramid import DEFAULT_CHUNK

    p = sub.add_parser("convert", help="write a volume as a bricked multiresolution OME-Zarr image")
    p.add_argument("input", help="volume file or DICOM folder (a uniform grid)")
    p.add_argument("output", help="the OME-Zarr folder to write, e.g. volume.zarr")
    p.add_argument("--chunks", type=_chunk_side, default=DEFAULT_CHUNK, metavar="N",
                   help=f"bricks of N^3 samples (default {DEFAULT_CHUNK})")  # fmt: skip
    p.add_argument("--levels", type=_positive, metavar="N",
                   help="levels of the pyramid (default: down to one brick)")  # fmt: skip
    p.add_argument("--scalars", help="the array to convert (as volren render --scalars)")
    p.add_argument("--force", action="store_true", help="replace OUTPUT if it exists")
    add_raw_arguments(p)
    p.add_argument("--memory", metavar="SIZE",
                   help="the most the conversion's data may take in memory, e.g. 2GB (default: no limit): raw NRRD, "
                        "uncompressed MetaImage and headerless raw inputs are streamed within it, others are read "
                        "whole (about 3x their values) or refused. The command's fixed overhead comes on top (interpreter, "
                        "libraries: about 170 MiB): its peak is about that plus SIZE")  # fmt: skip
    p.set_defaults(run=run)


#: At its peak, reading a volume whole holds its values about this many times: the reader's array,
#: the copy it hands over from the reading process, and the model's (measured: a 256^3 uint16 NRRD,
#: 32 MiB, peaked 92 MiB above the command's 170 MiB start).
WHOLE_READ_COPIES = 3


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from volren.io.ome_zarr_io import parse_memory, require_zarr
    from volren.io.safe_write import check_output, refuse_overwriting_inputs

    check_raw_flags(args, "convert")
    require_zarr()  # before a long load
    output = Path(args.output)
    if output.suffix.lower() != ".zarr":
        raise VolrenError(f"{output}: an OME-Zarr image is a folder named *.zarr")
    refuse_overwriting_inputs(
        [("OUTPUT", output)], [("input", args.input)], kind="folder"
    )  # even with --force
    if output.exists() and not args.force:
        raise VolrenError(f"{output}: exists; add --force to replace it")
    check_output(output, "OUTPUT", kind="folder")  # the folder a link leads to, too: before the load
    memory = parse_memory(args.memory) if args.memory is not None else None
    mapped = _mapped_input(args)
    if mapped is not None:
        shape, dtype, levels = _convert_streamed(args, mapped, output, memory)
    else:
        shape, dtype, levels = _convert_whole(args, output, memory)
    nz, ny, nx = shape
    print(f"{args.input}: {nx}x{ny}x{nz} {dtype} -> {output} ({levels} levels, {args.chunks}^3 bricks)")
    return 0


def _mapped_input(args: argparse.Namespace):
    """The input as a `MappedVolume` when it can be streamed (None: it is read whole)."""
    from pathlib import Path

    from volren.io.mapped_input import open_mapped, open_raw
    from volren.io.ome_zarr_io import is_ome_zarr

    path = Path(args.input)
    if args.scalars is not None or is_ome_zarr(args.input) or not path.is_file() or path.stat().st_size == 0:
        return None  # the whole read's checks and messages apply
    if args.raw_shape:
        return open_raw(path, **raw_load_arguments(args))
    return open_mapped(path)


def _convert_streamed(args: argparse.Namespace, mapped, output, memory: int | None):
    """Write the pyramid from the input's file, a row of bricks at a time."""
    import warnings

    from volren.cli.progress import progress_bar
    from volren.errors import VolrenWarning
    from volren.io.mapped_input import BrickRows
    from volren.io.ome_zarr_io import human_size, write_pyramid
    from volren.io.safe_write import output_target

    needed = _streaming_bytes(mapped, args.chunks)
    if memory is not None and needed > memory:
        raise VolrenError(f"{args.input}: --memory {human_size(memory)} is too little to convert it in {args.chunks}^3 "
                          f"bricks, which takes {human_size(needed)} (a row of bricks, and the block means of a "
                          "coarser brick); give more, or smaller --chunks")  # fmt: skip
    _check_levels(args, mapped.shape)
    values = BrickRows(mapped, args.chunks)
    with progress_bar(f"{output.name}") as progress:
        levels = write_pyramid(values, mapped.spacing, mapped.origin, mapped.name,
                               output_target(output, "OUTPUT", "folder"), args.chunks, args.levels, progress)  # fmt: skip
    if values.nonfinite:
        warnings.warn(f"{mapped.name}: {values.nonfinite:,} values are NaN or Inf; they render transparent",
                      VolrenWarning, stacklevel=2)  # fmt: skip
    return mapped.shape, mapped.dtype, levels


def _check_levels(args: argparse.Namespace, shape: tuple[int, ...]) -> None:
    """Refuse a --levels the input's (z, y, x) `shape` cannot have, before a brick is written."""
    from volren.model.pyramid import max_levels

    most = max_levels(shape)
    if args.levels is not None and args.levels > most:
        nz, ny, nx = shape
        raise VolrenError(f"{args.input}: --levels {args.levels} is too many: its {nx}x{ny}x{nz} grid has at most "
                          f"{most} levels (each halves it, down to 2 samples an axis)")  # fmt: skip


def _streaming_bytes(mapped, chunk: int) -> int:
    """What streaming `mapped` into bricks of `chunk`^3 holds at once: a row of bricks of level 0,
    and for a coarser brick the block of the level below and its float64 means."""
    below = (2 * chunk) ** 3
    return mapped.row_bytes(chunk) + below * (mapped.dtype.itemsize + 8)


def _convert_whole(args: argparse.Namespace, output, memory: int | None):
    """Read the input whole (its format cannot be read a part at a time), then write the pyramid."""
    import sys

    from volren import io
    from volren.cli.progress import progress_bar
    from volren.io.ome_zarr_io import human_size, save_ome_zarr
    from volren.io.safe_write import output_target
    from volren.model.volume import UniformVolume

    size = None if args.raw_shape else _values_bytes(args.input)
    if size is not None:
        print(f"volren: warning: {args.input}: read whole, {human_size(size)} of values (raw NRRD and "
              "uncompressed MetaImage are streamed instead)", file=sys.stderr)  # fmt: skip
        if memory is not None and size * WHOLE_READ_COPIES > memory:
            raise VolrenError(f"{args.input}: read whole it takes about {human_size(size * WHOLE_READ_COPIES)}, more "
                              f"than --memory {human_size(memory)}; write it as raw NRRD, which is streamed")  # fmt: skip
    volume = io.load_volume(args.input, scalars=args.scalars, **raw_load_arguments(args))
    if not isinstance(volume, UniformVolume):
        raise VolrenError(f"{args.input}: a tetrahedral mesh has no bricks; OME-Zarr holds uniform grids")
    _check_levels(args, volume.values.shape)
    with progress_bar(f"{output.name}") as progress:
        levels = save_ome_zarr(
            volume, output_target(output, "OUTPUT", "folder"), args.chunks, args.levels, progress
        )
    return volume.values.shape, volume.values.dtype, levels


def _values_bytes(path_text: str) -> int | None:
    """The bytes of the values a file's header declares (None: a folder, an OME-Zarr image, or a
    file whose header says nothing of them; the load's own checks then speak)."""
    from pathlib import Path

    from volren.io.formats import find_format
    from volren.io.ome_zarr_io import is_ome_zarr

    path = Path(path_text)
    if is_ome_zarr(path_text) or not path.is_file() or path.stat().st_size == 0:
        return None
    fmt = find_format(path)
    layout = fmt.inspect(path).layout if fmt is not None else None
    return layout.memory_bytes if layout is not None else None
