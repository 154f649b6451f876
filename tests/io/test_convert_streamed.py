"""`volren convert` streams inputs whose values lie uncompressed on disk (raw NRRD, uncompressed
MetaImage) a row of bricks at a time, never reading them whole, into the same pyramid as reading
them whole makes; other inputs are read whole, saying so, and refused when --memory cannot hold them."""

from __future__ import annotations

import gzip
import json
import warnings

import numpy as np
import pytest

from volren.errors import VolrenError

zarr = pytest.importorskip("zarr", reason="volren[zarr] is part of the test set-up")

SHAPE = (13, 17, 20)  # z, y, x: odd and even sides, bricks of 8 cut at every edge


def field(dtype: str, shape=SHAPE) -> np.ndarray:
    z, y, x = np.meshgrid(*(np.arange(n) for n in shape), indexing="ij")
    values = 60 + 50 * np.sin(0.4 * x) * np.cos(0.3 * y) + 3 * z
    return values.astype(dtype)


def nrrd_header(values: np.ndarray, type_name: str, extra: str = "", encoding: str = "raw") -> bytes:
    nz, ny, nx = values.shape
    endian = "big" if values.dtype.byteorder == ">" else "little"
    return (f"NRRD0004\ntype: {type_name}\ndimension: 3\nsizes: {nx} {ny} {nz}\nendian: {endian}\n"
            f"encoding: {encoding}\n{extra}").encode()  # fmt: skip


def write_nrrd(path, values, type_name, extra=""):
    path.write_bytes(nrrd_header(values, type_name, extra) + b"\n" + values.tobytes())
    return path


def write_nhdr(folder, values, type_name):
    (folder / "d.raw").write_bytes(values.tobytes())
    header = nrrd_header(values, type_name, "data file: d.raw\nspacings: 0.5 2 1.25\n")
    (folder / "d.nhdr").write_bytes(header + b"\n")
    return folder / "d.nhdr"


def write_mhd(folder, values, element, local=False):
    nz, ny, nx = values.shape
    msb = "True" if values.dtype.byteorder == ">" else "False"
    header = (f"ObjectType = Image\nNDims = 3\nDimSize = {nx} {ny} {nz}\nElementType = {element}\n"
              f"ElementSpacing = 0.7 0.8 1.5\nOffset = -3 4.5 10\nElementByteOrderMSB = {msb}\n"
              f"ElementDataFile = {'LOCAL' if local else 'd.raw'}\n")  # fmt: skip
    path = folder / ("d.mha" if local else "d.mhd")
    if local:
        path.write_bytes(header.encode() + values.tobytes())
    else:
        path.write_text(header)
        (folder / "d.raw").write_bytes(values.tobytes())
    return path


INPUTS = {
    "nrrd uint16, spacings and origin": lambda d: write_nrrd(
        d / "a.nrrd", field("<u2"), "uint16", "spacings: 0.5 0.75 2\nspace origin: (1,-2,3.5)\n"),
    "nrrd big-endian int16, space directions": lambda d: write_nrrd(
        d / "b.nrrd", field(">i2") - 100, "short",
        "space: right-anterior-superior\nspace directions: (0.5,0,0) (0,0.25,0) (0,0,3)\n"),
    "nrrd float32 with NaN": lambda d: write_nrrd(d / "c.nrrd", np.where(field("<f4") > 100, np.nan, field("<f4")),
                                                  "float"),
    "nrrd int8 (kept as int16)": lambda d: write_nrrd(d / "e.nrrd", field("i1") - 100, "signed char"),
    "nrrd uint32 (kept as float64)": lambda d: write_nrrd(d / "f.nrrd", field("<u4") * 1000, "uint32"),
    "nhdr and raw": lambda d: write_nhdr(d, field("<u2"), "ushort"),
    "mhd and raw": lambda d: write_mhd(d, field("<u2"), "MET_USHORT"),
    "mha big-endian float64": lambda d: write_mhd(d, field(">f8"), "MET_DOUBLE", local=True),
}  # fmt: skip


def read_pyramid(path):
    group = zarr.open_group(str(path), mode="r")
    levels = len(group.attrs["multiscales"][0]["datasets"])
    return [group[str(k)][:] for k in range(levels)], dict(group.attrs)


@pytest.fixture
def no_whole_read(monkeypatch):
    """Any whole read of a volume file raises."""
    from volren import io
    from volren.io import volume_io

    def refused(*args, **kwargs):
        raise AssertionError("the input was read whole")

    monkeypatch.setattr(io, "load_volume", refused)
    monkeypatch.setattr(volume_io, "read_with_header", refused)


@pytest.mark.filterwarnings("default::volren.errors.VolrenWarning")  # the CLI prints it as one line
@pytest.mark.parametrize("name", INPUTS)
def test_a_streamed_input_gives_the_pyramid_read_whole_gives(tmp_path, name, capsys, monkeypatch):
    from volren.cli.main import main
    from volren.io import load_volume
    from volren.io.ome_zarr_io import save_ome_zarr

    source = INPUTS[name](tmp_path)
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        whole = load_volume(source)
    save_ome_zarr(whole, tmp_path / "whole.zarr", chunk=8)
    from volren import io
    from volren.io import volume_io

    monkeypatch.setattr(io, "load_volume", lambda *a, **k: pytest.fail("read whole"))
    monkeypatch.setattr(volume_io, "read_with_header", lambda *a, **k: pytest.fail("read whole"))
    assert main(["convert", str(source), str(tmp_path / "streamed.zarr"), "--chunks", "8"]) == 0
    expected, expected_attrs = read_pyramid(tmp_path / "whole.zarr")
    got, got_attrs = read_pyramid(tmp_path / "streamed.zarr")
    assert len(got) == len(expected) == 3
    for a, b in zip(got, expected, strict=True):
        assert a.dtype == b.dtype
        np.testing.assert_array_equal(a, b)
    assert got_attrs == expected_attrs  # placement, name and brick ranges
    nz, ny, nx = SHAPE
    said = capsys.readouterr()
    assert said.out.strip() == (f"{source}: {nx}x{ny}x{nz} {whole.values.dtype} -> {tmp_path / 'streamed.zarr'} "
                                "(3 levels, 8^3 bricks)")  # fmt: skip
    nonfinite = f"volren: warning: {source.name}: {whole.nonfinite_count:,} values are NaN or Inf; they render transparent\n"
    assert said.err == (nonfinite if whole.nonfinite_count else "")


#: Converts argv[1] (small) then argv[2] (big) into argv[3], argv[4] in a fresh interpreter, with any
#: whole read refused, and prints the traced peak of the big one: a process of its own, because the
#: traced peak of the test process depended on what earlier tests had left behind (11.9 MB after
#: the whole suite, under 8 MB alone). The small convert comes first, outside the count: the first
#: convert of a process also imports the writer's modules.
MEASURE_CONVERT = """
import sys, tracemalloc
from volren import io
from volren.io import volume_io
from volren.cli.main import main

def refused(*args, **kwargs):
    raise AssertionError("the input was read whole")

io.load_volume = volume_io.read_with_header = refused
small, big, small_out, big_out = sys.argv[1:5]
assert main(["convert", small, small_out, "--chunks", "8"]) == 0
tracemalloc.start()
assert main(["convert", big, big_out, "--chunks", "32"]) == 0
print(tracemalloc.get_traced_memory()[1])
"""


def test_a_raw_nrrd_converts_without_holding_the_volume(tmp_path):
    """32 MiB of values in 32^3 bricks: at most a row of bricks and a coarser brick's block means
    are held at once (about 4 MiB), never the volume."""
    import subprocess
    import sys

    n = 256
    values = np.broadcast_to(np.arange(n, dtype="<u2")[:, None, None] * 100, (n, n, n))
    with open(tmp_path / "big.nrrd", "wb") as f:
        f.write(nrrd_header(values[:1], "uint16").replace(b"sizes: 256 256 1", b"sizes: 256 256 256") + b"\n")
        for plane in values:
            f.write(np.ascontiguousarray(plane).tobytes())
    small = write_nrrd(tmp_path / "small.nrrd", np.ascontiguousarray(values[:16, :16, :16]), "uint16")
    done = subprocess.run([sys.executable, "-c", MEASURE_CONVERT, str(small), str(tmp_path / "big.nrrd"),
                           str(tmp_path / "small.zarr"), str(tmp_path / "big.zarr")],
                          capture_output=True, text=True, timeout=600)  # fmt: skip
    assert done.returncode == 0, done.stderr
    peak = int(done.stdout.split()[-1])
    assert peak < values.nbytes / 4
    np.testing.assert_array_equal(zarr.open_array(str(tmp_path / "big.zarr" / "1"), mode="r")[:, 0, 0],
                                  np.arange(n // 2, dtype=np.uint16) * 200 + 50)  # fmt: skip


def test_an_input_read_whole_says_so_and_is_refused_beyond_memory(tmp_path, capsys):
    from volren.cli.main import main

    values = field("<u2")
    path = tmp_path / "g.nrrd"
    path.write_bytes(nrrd_header(values, "uint16", encoding="gzip") + b"\n" + gzip.compress(values.tobytes()))
    assert main(["convert", str(path), str(tmp_path / "g.zarr"), "--chunks", "8"]) == 0
    assert capsys.readouterr().err == (f"volren: warning: {path}: read whole, 8.6 KiB of values (raw NRRD and "
                                       "uncompressed MetaImage are streamed instead)\n")  # fmt: skip
    assert main(["convert", str(path), str(tmp_path / "h.zarr"), "--memory", "20KB"]) == 1
    err = capsys.readouterr().err.splitlines()
    assert err[-1] == (f"volren: error: {path}: read whole it takes about 25.9 KiB, more than --memory 20.0 KiB; "
                       "write it as raw NRRD, which is streamed")  # fmt: skip
    assert not (tmp_path / "h.zarr").exists()


def test_a_memory_too_small_to_stream_is_one_line(tmp_path, capsys, no_whole_read):
    from volren.cli.main import main

    path = write_nrrd(tmp_path / "a.nrrd", field("<u2"), "uint16")
    assert main(["convert", str(path), str(tmp_path / "a.zarr"), "--memory", "1MB"]) == 1
    assert capsys.readouterr().err == (f"volren: error: {path}: --memory 1.0 MiB is too little to convert it in 64^3 "
                                       "bricks, which takes 20.0 MiB (a row of bricks, and the block means of a "
                                       "coarser brick); give more, or smaller --chunks\n")  # fmt: skip


def test_a_file_shorter_than_its_header_says_is_one_line(tmp_path, no_whole_read):
    from volren.io.mapped_input import open_mapped

    values = field("<u2")
    path = tmp_path / "cut.nrrd"
    path.write_bytes(nrrd_header(values, "uint16") + b"\n" + values.tobytes()[:-10])
    with pytest.raises(VolrenError, match="truncated"):
        open_mapped(path)


RAW_INPUTS = {  # name: (values, --raw-dtype, --raw-byte-order, the NRRD type of the same values)
    "uint16": (field("<u2"), "ushort", "little", "uint16"),
    "big-endian float32 with NaN": (
        np.where(field("f4") > 100, np.nan, field("f4")).astype(">f4"),
        "float32",
        "big",
        "float",
    ),
    "int8 (kept as int16)": (field("i1") - 100, "int8", "little", "signed char"),
}


@pytest.mark.filterwarnings("default::volren.errors.VolrenWarning")
@pytest.mark.parametrize("name", RAW_INPUTS)
def test_a_headerless_raw_input_streams_into_the_pyramid_of_its_nrrd(tmp_path, name, monkeypatch):
    from volren import io
    from volren.cli.main import main
    from volren.io import volume_io

    values, dtype, byte_order, nrrd_type = RAW_INPUTS[name]
    nrrd = write_nrrd(tmp_path / "d.nrrd", values, nrrd_type, "spacings: 0.5 0.75 2\n")
    raw = tmp_path / "d.raw"
    raw.write_bytes(values.tobytes())
    assert main(["convert", str(nrrd), str(tmp_path / "nrrd.zarr"), "--chunks", "8"]) == 0
    monkeypatch.setattr(io, "load_volume", lambda *a, **k: pytest.fail("read whole"))
    monkeypatch.setattr(volume_io, "read_with_header", lambda *a, **k: pytest.fail("read whole"))
    nz, ny, nx = SHAPE
    assert main(["convert", str(raw), str(tmp_path / "raw.zarr"), "--chunks", "8", "--raw-shape", f"{nx},{ny},{nz}",
                 "--raw-dtype", dtype, "--raw-byte-order", byte_order, "--raw-spacing", "0.5,0.75,2"]) == 0  # fmt: skip
    expected, expected_attrs = read_pyramid(tmp_path / "nrrd.zarr")
    got, got_attrs = read_pyramid(tmp_path / "raw.zarr")
    assert len(got) == len(expected) == 3
    for a, b in zip(got, expected, strict=True):
        assert a.dtype == b.dtype
        np.testing.assert_array_equal(a, b)
    assert json.dumps(got_attrs) == json.dumps(expected_attrs).replace(
        "d.nrrd", "d.raw"
    )  # placement and brick ranges


def test_a_headerless_raw_input_of_the_wrong_size_is_one_line(tmp_path, capsys, no_whole_read):
    from volren.cli.main import main

    raw = tmp_path / "d.raw"
    raw.write_bytes(field("<u2").tobytes()[:-2])
    nz, ny, nx = SHAPE
    assert main(["convert", str(raw), str(tmp_path / "d.zarr"), "--raw-shape", f"{nx},{ny},{nz}",
                 "--raw-dtype", "uint16"]) == 1  # fmt: skip
    assert capsys.readouterr().err == (f"volren: error: {raw}: dimensions do not match the data: shape {nx}x{ny}x{nz} "
                                       f"of uint16 needs {values_bytes(SHAPE, 2):,} bytes after a 0-byte header, the "
                                       f"file holds {values_bytes(SHAPE, 2) - 2:,}\n")  # fmt: skip
    assert not (tmp_path / "d.zarr").exists()


def values_bytes(shape, itemsize: int) -> int:
    return int(np.prod(shape)) * itemsize
