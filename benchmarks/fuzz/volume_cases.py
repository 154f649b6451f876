"""Malformed volume files: every header field of every format given values it must not take
quietly, bytes cut, flipped and appended, and the mesh faults (indices past the points, -1,
bogus cell types, NaN points, duplicated and inverted cells).

Mutations rewrite the seeds' text headers line by line (NRRD, MetaImage, legacy VTK, SLC), their
XML attributes (VTK XML), their binary fields (NIfTI, DICOM) and their bytes; the expectation of
each case says whether a render would be accepting a bad header in silence.
"""

from __future__ import annotations

import gzip
import random
import re
import struct
from collections.abc import Callable, Iterator

import numpy as np

from benchmarks.fuzz.cases import BAD_NUMBERS, Case, Expect, render_argv
from benchmarks.fuzz.seeds import SHAPE, SPACING, Seed, grid_values, legacy_mesh_text, mesh, rle, seeds

TOKEN_BAD = ("0", "-1", "nan", "inf", "99999", "4294967296", "x")


def _case(seed: Seed, what: str, files: dict[str, bytes], expect: Expect = "any", *flags: str) -> Case:
    return Case(f"{seed.name}/{what}", seed.name.split("-")[0], files, render_argv(seed.target, *seed.flags, *flags),
                expect)  # fmt: skip


# ------------------------------------------------------------------------ what a field must refuse


def expectation(key: str, bad: str) -> Expect:
    """Whether a header `key` set to `bad` must be refused: sizes and types always, spacings
    when not a positive finite number, origins when not finite."""
    k = key.lower().replace("_", " ").strip()
    if any(w in k for w in ("dimsize", "sizes", "dimensions", "ndims", "dimension", "elementtype", "type:")):
        return "error"
    if k in ("type",) or k.startswith("type"):
        return "error"
    if any(w in k for w in ("spacing", "space directions", "elementsize", "pixdim")):
        return "error" if bad in ("0", "nan", "inf", "-inf", "abc", "", "x", "1,5") else "any"
    if any(w in k for w in ("origin", "offset", "position")):
        return "error" if bad in ("nan", "inf", "-inf", "abc", "x", "1,5") else "any"
    return "any"


# ------------------------------------------------------------------------------ text headers

_LEGACY_KEYWORDS = (
    "DIMENSIONS", "SPACING", "ASPECT_RATIO", "ORIGIN", "POINT_DATA", "CELL_DATA", "SCALARS", "LOOKUP_TABLE",
    "POINTS", "CELLS", "CELL_TYPES", "OFFSETS", "CONNECTIVITY", "DATASET", "BINARY", "ASCII",
)  # fmt: skip


def _header_lines(seed: Seed, data: bytes) -> list[tuple[int, str, str]]:
    """(byte offset of the line, key part, value part) of each header line the seed's format has."""
    out = []
    pos = 0
    for number, line in enumerate(data.split(b"\n")):
        start = pos
        pos += len(line) + 1
        try:
            text = line.decode("ascii")
        except UnicodeDecodeError:
            continue
        if not text.isprintable():
            continue
        if seed.name.startswith(("nrrd", "nhdr")):
            if not text:
                break  # the blank line ends an attached header
            m = re.match(r"^([^:#]+:=?\s*)(.*)$", text)
        elif seed.name.startswith(("mhd", "mha")):
            m = re.match(r"^(\w+\s*=\s*)(.*)$", text)
        elif seed.name.startswith("legacy"):
            m = re.match(rf"^((?:{'|'.join(_LEGACY_KEYWORDS)})\s*)(.*)$", text)
            if number == 0:
                m = re.match(r"^(# vtk DataFile Version\s*)(.*)$", text)
        elif seed.name.startswith("slc"):
            m = re.match(r"^()(.*)$", text) if number < 4 else None
        else:
            m = None
        if m:
            out.append((start, m.group(1), m.group(2)))
    return out


def _replace_line(data: bytes, start: int, key: str, old: str, new: str | None) -> bytes:
    end = start + len((key + old).encode())
    if new is None:  # drop the line
        return data[:start] + data[end + 1 :]
    return data[:start] + (key + new).encode() + data[end:]


def text_field_cases(seed: Seed, file: str, full: bool) -> Iterator[Case]:
    """Each header line's value replaced (whole, and token by token), dropped and doubled."""
    data = seed.files[file]
    for number, (start, key, value) in enumerate(_header_lines(seed, data)):
        label = re.sub(r"[^A-Za-z0-9]+", "_", key.strip(" :=")) or f"line{number}"
        values = BAD_NUMBERS if full else BAD_NUMBERS[:6]
        for bad in values:
            files = {**seed.files, file: _replace_line(data, start, key, value, bad)}
            yield _case(seed, f"{label}={bad or 'empty'}", files, expectation(key, bad))
        tokens = value.split()
        if len(tokens) > 1:
            for i in range(len(tokens)):
                for bad in TOKEN_BAD if full else TOKEN_BAD[:3]:
                    new = " ".join(bad if n == i else t for n, t in enumerate(tokens))
                    files = {**seed.files, file: _replace_line(data, start, key, value, new)}
                    yield _case(seed, f"{label}[{i}]={bad}", files, expectation(key, bad))
            files = {**seed.files, file: _replace_line(data, start, key, value, " ".join(tokens[:-1]))}
            yield _case(seed, f"{label}-one-value-short", files, expectation(key, "abc"))
            files = {**seed.files, file: _replace_line(data, start, key, value, value + " 7")}
            yield _case(seed, f"{label}-one-value-more", files)
        yield _case(
            seed, f"{label}-dropped", {**seed.files, file: _replace_line(data, start, key, value, None)}
        )
        doubled = data[:start] + (key + value).encode() + b"\n" + data[start:]
        yield _case(seed, f"{label}-twice", {**seed.files, file: doubled})


# --------------------------------------------------------------------------------- XML attributes


def xml_attribute_cases(seed: Seed, full: bool) -> Iterator[Case]:
    """Every attribute of the XML part given bad values; the appended data left as it is."""
    file = seed.target
    data = seed.files[file]
    cut = data.find(b"<AppendedData")
    head = data if cut < 0 else data[:cut]
    seen: dict[str, int] = {}
    for m in re.finditer(rb'(\w+)="([^"]*)"', head):
        name = m.group(1).decode()
        seen[name] = seen.get(name, 0) + 1
        if name in ("version", "RangeMin", "RangeMax") or (not full and seen[name] > 1):
            continue
        label = f"{name}{seen[name] if seen[name] > 1 else ''}"
        for bad in (
            (*BAD_NUMBERS[:6], "String", "UInt64", "-1 -1 -1 -1 -1 -1", "99999999 99999999")
            if full
            else ("-1", "nan", "abc")
        ):
            new = data[: m.start(2)] + bad.encode() + data[m.end(2) :]
            yield _case(seed, f"{label}={bad or 'empty'}", {file: new}, _xml_expectation(name, bad))


def _xml_expectation(name: str, bad: str) -> Expect:
    if name in ("WholeExtent", "Extent", "NumberOfComponents", "NumberOfPoints", "NumberOfCells"):
        return "error" if bad not in ("0",) else "any"
    if name == "type" and bad not in ("UInt64",):
        return "error"
    if name == "Spacing" or name == "Origin":
        return expectation(name, bad)
    return "any"


# -------------------------------------------------------------------------------------- bytes


def byte_cases(seed: Seed, rng: random.Random) -> Iterator[Case]:
    """Cut, flipped, zeroed, extended and replaced bytes of the seed's main file."""
    file = next((f for f in seed.files if not f.endswith(".raw") or seed.name == "raw"), seed.target)
    if seed.name == "dicom":
        file = sorted(seed.files)[len(seed.files) // 2]
    data = seed.files[file]
    n = len(data)
    for fraction in (0.02, 0.1, 0.3, 0.5, 0.7, 0.9, 0.99):
        cut = max(1, int(n * fraction))
        yield _case(
            seed, f"cut-{fraction:g}", {**seed.files, file: data[:cut]}, "error" if fraction < 0.95 else "any"
        )
    yield _case(seed, "cut-last-byte", {**seed.files, file: data[:-1]})
    yield _case(seed, "empty", {**seed.files, file: b""}, "error")
    yield _case(
        seed, "garbage-appended", {**seed.files, file: data + bytes(rng.getrandbits(8) for _ in range(999))}
    )
    yield _case(
        seed, "zeros-in-middle", {**seed.files, file: data[: n // 2] + bytes(64) + data[n // 2 + 64 :]}
    )
    yield _case(seed, "random-same-length", {**seed.files, file: bytes(rng.getrandbits(8) for _ in range(n))})
    for trial in range(4):
        flipped = bytearray(data)
        for _ in range(1 + 3 * trial):
            flipped[rng.randrange(n)] ^= 1 << rng.randrange(8)
        yield _case(seed, f"bit-flips-{trial}", {**seed.files, file: bytes(flipped)})
    header_end = min(n, 300)
    for trial in range(3):
        flipped = bytearray(data)
        flipped[rng.randrange(header_end)] = rng.choice(b"0-9 \n\t\0\xff:=.e")
        yield _case(seed, f"header-byte-{trial}", {**seed.files, file: bytes(flipped)})


# -------------------------------------------------------------------------------------- NIfTI

_NIFTI_FIELDS: tuple[tuple[str, int, str, tuple[float, ...]], ...] = (
    ("sizeof_hdr", 0, "<i", (0, -1, 540, 2**31 - 1)),
    ("dim0", 40, "<h", (0, -1, 8, 99)),
    ("dim1", 42, "<h", (0, -1, 32767)),
    ("dim2", 44, "<h", (0, -1)),
    ("dim3", 46, "<h", (0, -1, 32767)),
    ("dim4", 48, "<h", (0, -1, 3, 32767)),
    ("dim5", 50, "<h", (5, 32767)),
    ("datatype", 70, "<h", (0, 1, 3, 32, 128, 2304, 999, -1)),
    ("bitpix", 72, "<h", (0, 7, 64, -1)),
    ("pixdim0", 76, "<f", (float("nan"), 0.0, -1.0, 5.0)),
    ("pixdim1", 80, "<f", (float("nan"), float("inf"), 0.0, -1.0, 1e30)),
    ("pixdim3", 88, "<f", (float("nan"), 0.0, -1.0)),
    ("vox_offset", 108, "<f", (float("nan"), float("inf"), -352.0, 0.0, 100.0, 1e12, 353.5)),
    ("scl_slope", 112, "<f", (float("nan"), float("inf"), 0.0, 1e38)),
    ("scl_inter", 116, "<f", (float("nan"), float("-inf"), 1e38)),
    ("qform_code", 252, "<h", (1, 99, -1)),
    ("sform_code", 254, "<h", (1, 99)),
    ("quatern_b", 256, "<f", (float("nan"), 2.0)),
    ("qoffset_x", 268, "<f", (float("nan"), float("inf"))),
    ("srow_x0", 280, "<f", (float("nan"), 0.0)),
    ("srow_z3", 324, "<f", (float("inf"),)),
)

_NIFTI_REFUSED = {"dim0", "dim1", "dim2", "dim3", "datatype", "bitpix", "vox_offset", "sizeof_hdr"}


def _nifti_expect(name: str, value: float) -> Expect:
    if name in _NIFTI_REFUSED:
        return "error" if not (name == "vox_offset" and value == 353.5) else "any"
    if name in ("pixdim1", "pixdim3"):
        return "error" if not np.isfinite(value) or value == 0 else "any"
    if name in ("scl_slope", "scl_inter", "quatern_b", "qoffset_x", "srow_x0", "srow_z3"):
        return "error" if not np.isfinite(value) else "any"
    return "any"


def nifti_cases(seed: Seed) -> Iterator[Case]:
    file = seed.target
    raw = seed.files[file]
    data = gzip.decompress(raw) if file.endswith(".gz") else raw
    for name, offset, fmt, values in _NIFTI_FIELDS:
        for value in values:
            out = bytearray(data)
            struct.pack_into(fmt, out, offset, int(value) if fmt != "<f" else value)
            if name == "sform_code" and value == 1:  # an sform of zeros, then of NaN
                struct.pack_into("<12f", out, 280, *([float("nan")] * 12))
            body = gzip.compress(bytes(out), mtime=0) if file.endswith(".gz") else bytes(out)
            expect = _nifti_expect(name, value) if name != "sform_code" or value != 1 else "error"
            if name in ("dim0",) and value == 5:
                expect = "any"
            yield _case(seed, f"{name}={value:g}", {file: body}, expect)
    out = bytearray(data)
    out[344:348] = b"ni1\0"
    body = gzip.compress(bytes(out), mtime=0) if file.endswith(".gz") else bytes(out)
    yield _case(seed, "magic=ni1-without-img", {file: body}, "error")
    if file.endswith(".gz"):
        yield _case(seed, "gzip-lying", {file: raw[:10] + bytes(len(raw) - 10)}, "error")
        yield _case(seed, "not-gzipped", {file: data}, "any")


# -------------------------------------------------------------------------------------- DICOM


def _elements(data: bytes) -> Iterator[tuple[int, int, str, int, int]]:
    """(group, element, VR, value start, value end) of an explicit-VR little-endian file."""
    pos = 132
    while pos + 8 <= len(data):
        group, elem = struct.unpack_from("<HH", data, pos)
        vr = data[pos + 4 : pos + 6].decode("latin-1")
        if vr in ("OB", "OW", "OF", "SQ", "UT", "UN"):
            (length,) = struct.unpack_from("<I", data, pos + 8)
            start = pos + 12
        else:
            (length,) = struct.unpack_from("<H", data, pos + 6)
            start = pos + 8
        yield group, elem, vr, start, start + length
        pos = start + length


def set_element(data: bytes, tag: tuple[int, int], value: bytes, length: int | None = None) -> bytes:
    """The file with element `tag`'s value replaced (its length field set to `length` or the
    value's length)."""
    for group, elem, vr, start, end in _elements(data):
        if (group, elem) == tag:
            size = len(value) if length is None else length
            long_vr = vr in ("OB", "OW", "OF", "SQ", "UT", "UN")
            head = start - (4 if long_vr else 2)
            field = struct.pack("<I" if long_vr else "<H", size & (0xFFFFFFFF if long_vr else 0xFFFF))
            return data[:head] + field + value + data[end:]
    raise KeyError(tag)  # pragma: no cover - the seeds have every element mutated


_US = struct.Struct("<H")
_DICOM_FIELDS: tuple[tuple[str, tuple[int, int], tuple[bytes, ...]], ...] = (
    ("rows", (0x28, 0x10), (_US.pack(0), _US.pack(65535), _US.pack(3))),
    ("columns", (0x28, 0x11), (_US.pack(0), _US.pack(65535), _US.pack(9))),
    ("bits_allocated", (0x28, 0x100), (_US.pack(12), _US.pack(0), _US.pack(8), _US.pack(32), _US.pack(1))),
    ("bits_stored", (0x28, 0x101), (_US.pack(0), _US.pack(40))),
    ("pixel_representation", (0x28, 0x103), (_US.pack(7),)),
    ("samples_per_pixel", (0x28, 0x02), (_US.pack(3), _US.pack(0))),
    ("pixel_spacing", (0x28, 0x30), (b"nan\\nan ", b"0\\0 ", b"-1\\1 ", b"abc\\def ", b"1 ")),
    ("slice_thickness", (0x18, 0x50), (b"nan ", b"0 ", b"abc ")),
    ("position", (0x20, 0x32), (b"nan\\0\\0 ", b"inf\\inf\\inf ", b"1\\2 ", b"")),
    ("orientation", (0x20, 0x37), (b"0\\0\\0\\0\\0\\0 ", b"nan\\0\\0\\0\\1\\0 ", b"1\\0\\0\\1\\0\\0 ")),
    ("rescale_slope", (0x28, 0x1053), (b"nan ", b"0 ", b"inf ", b"1e300 ")),
    ("rescale_intercept", (0x28, 0x1052), (b"nan ", b"-inf ")),
    ("transfer_syntax", (0x2, 0x10), (b"1.2.840.10008.1.2.2\0", b"1.2.840.10008.1.2.4.50", b"garbage\0")),
)

_DICOM_REFUSED = {"rows", "columns", "bits_allocated", "samples_per_pixel"}


def dicom_cases(seed: Seed) -> Iterator[Case]:
    names = sorted(seed.files)
    middle = names[len(names) // 2]
    for label, tag, values in _DICOM_FIELDS:
        for i, value in enumerate(values):
            for scope in ("all", "one"):
                files = {
                    f: set_element(d, tag, value) if scope == "all" or f == middle else d
                    for f, d in seed.files.items()
                }
                expect: Expect = (
                    "error"
                    if label in _DICOM_REFUSED and not (label == "bits_allocated" and i == 2)
                    else "any"
                )
                if label == "position" and scope == "one":
                    expect = "any"
                yield _case(seed, f"{label}[{i}]-{scope}", files, expect)
    pixels_tag = (0x7FE0, 0x10)
    data = seed.files[middle]
    *_, (g, e, vr, start, end) = list(_elements(data))
    pixel_bytes = data[start:end]
    short = set_element(data, pixels_tag, pixel_bytes[: len(pixel_bytes) // 2])
    yield _case(seed, "pixel-data-short", {**seed.files, middle: short}, "error")
    yield _case(seed, "pixel-data-length-lies", {**seed.files, middle: set_element(data, pixels_tag, pixel_bytes, 2 * len(pixel_bytes))}, "error")  # fmt: skip
    yield _case(
        seed,
        "pixel-data-odd",
        {**seed.files, middle: set_element(data, pixels_tag, pixel_bytes[:-1])},
        "error",
    )
    yield _case(seed, "pixel-data-missing", {**seed.files, middle: data[: start - 12]}, "error")
    yield _case(seed, "slice-empty", {**seed.files, middle: b""}, "error")
    yield _case(seed, "slice-garbage", {**seed.files, middle: bytes(range(256)) * 4}, "error")
    yield _case(seed, "slice-duplicated", {**seed.files, "series/zz.dcm": data}, "error")
    yield _case(seed, "slice-missing", {f: d for f, d in seed.files.items() if f != middle}, "any")
    yield _case(seed, "one-slice", {names[0]: seed.files[names[0]]}, "any")
    yield _case(seed, "folder-empty", {"series/readme.txt": b"no slices here"}, "error")
    yield Case("dicom/one-file-named", "dicom", seed.files, render_argv(names[0]), "render")


# ---------------------------------------------------------------------------------------- SLC


def _slc_file(
    blocks: list[bytes], flag: int = 1, sizes: list[str] | None = None, icon: str = "2 2", bits: int = 8
) -> bytes:
    """An SLC file of the seed's size whose slices are `blocks`, each after its 'size X' when
    `sizes` is given (the blocks' own lengths by default, for flag 1)."""
    nx, ny, nz = SHAPE
    head = f"11111\n{nx} {ny} {nz} {bits}\n{SPACING[0]} {SPACING[1]} {SPACING[2]}\n1 6 0 {flag}\n{icon} X"
    out = bytearray(head.encode()) + bytes(12)
    if sizes is None and flag == 1:
        sizes = [str(len(b)) for b in blocks]
    for k, block in enumerate(blocks):
        out += (f"{sizes[k]} X".encode() if sizes else b"") + block
    return bytes(out)


def slc_cases() -> Iterator[Case]:
    """What vtkSLCReader trusted: the compression flag, the run lengths (no bounds on the slice or
    the compressed block), the compressed and icon sizes, the bits per voxel."""
    planes = [np.ascontiguousarray(p).tobytes() for p in (grid_values() // 8).clip(0, 255).astype(np.uint8)]
    coded = [rle(p) for p in planes]
    plane = len(planes[0])

    def case(what: str, content: bytes) -> Case:
        return Case(f"slc/{what}", "slc", {"v.slc": content}, render_argv("v.slc"), "error")

    def with_slice(block: bytes, k: int = 2) -> list[bytes]:
        return [block if n == k else c for n, c in enumerate(coded)]

    yield case("flag-rle-on-raw-slices", _slc_file(planes, 1, sizes=[]))
    yield case("flag-raw-on-rle-slices", _slc_file(coded, 0, sizes=[str(len(c)) for c in coded]))
    yield case("run-longer-than-slice", _slc_file(with_slice(bytes([0x7F, 9, 0]))))
    yield case(
        "literal-run-past-block", _slc_file(with_slice(bytes([0x80 | plane]) + planes[2][:20] + b"\0"))
    )
    yield case("repeat-run-without-value", _slc_file(with_slice(bytes([5]))))
    yield case("runs-short-of-slice", _slc_file(with_slice(rle(planes[2][: plane // 2]))))
    yield case("no-end-marker", _slc_file(with_slice(coded[2][:-1])))
    yield case("size-past-end", _slc_file(coded, 1, sizes=[*(str(len(c)) for c in coded[:-1]), "99999"]))
    yield case(
        "size-negative",
        _slc_file(coded, 1, sizes=[str(len(c)) if k != 2 else "-5" for k, c in enumerate(coded)]),
    )
    yield case(
        "size-short",
        _slc_file(coded, 1, sizes=[str(len(c) - (3 if k == 2 else 0)) for k, c in enumerate(coded)]),
    )
    yield case(
        "size-long",
        _slc_file(coded, 1, sizes=[str(len(c) + (5 if k == 2 else 0)) for k, c in enumerate(coded)]),
    )
    yield case(
        "size-huge",
        _slc_file(coded, 1, sizes=[str(len(c)) if k != 2 else "9" * 20 for k, c in enumerate(coded)]),
    )
    yield case("icon-huge", _slc_file(coded, 1, icon="99999 99999"))
    yield case("icon-negative", _slc_file(coded, 1, icon="-2 2"))
    yield case("bits-16", _slc_file(coded, 1, bits=16))
    yield case("slice-missing", _slc_file(coded[:-1], 1))


# --------------------------------------------------------------------------------------- meshes


def _mesh_text(points=None, tets=None, values=None, edit: Callable[[str], str] | None = None) -> bytes:
    p, t, v = mesh()
    text = legacy_mesh_text(
        p if points is None else points, t if tets is None else tets, v if values is None else values
    )
    return (edit(text) if edit else text).encode()


def mesh_cases() -> Iterator[Case]:
    """Faults of tetrahedral meshes, written as legacy ASCII files (what hand-written meshes are)."""
    points, tets, values = mesh()
    n = len(points)

    def case(what: str, content: bytes, expect: Expect = "any") -> Case:
        return Case(f"mesh/{what}", "mesh", {"m.vtk": content}, render_argv("m.vtk"), expect)

    def with_index(value: int, where: int = 7) -> np.ndarray:
        bad = tets.copy()
        bad[where, 2] = value
        return bad

    for label, value in (("past-end", n), ("far-past-end", 10**6), ("minus-one", -1), ("int32-wrap", 2**32 + 1),
                         ("int64-min", -(2**63))):  # fmt: skip
        yield case(f"index-{label}", _mesh_text(tets=with_index(value)), "error")
    yield case("cell-size-3", _mesh_text(edit=lambda s: s.replace("\n4 ", "\n3 ", 1)), "error")
    yield case("cell-size-0", _mesh_text(edit=lambda s: s.replace("\n4 ", "\n0 ", 1)), "error")
    yield case("cell-size-huge", _mesh_text(edit=lambda s: s.replace("\n4 ", "\n2000000000 ", 1)), "error")
    yield case("cell-size-negative", _mesh_text(edit=lambda s: s.replace("\n4 ", "\n-4 ", 1)), "error")
    for ctype in ("0", "255", "-1", "7", "42", "12", "1"):
        yield case(
            f"cell-type-{ctype}",
            _mesh_text(edit=lambda s, c=ctype: s.replace("CELL_TYPES 40\n10", f"CELL_TYPES 40\n{c}")),
        )
    yield case("all-cell-types-vertex", _mesh_text(edit=lambda s: s.replace("\n10", "\n1")), "error")
    yield case(
        "cells-count-short", _mesh_text(edit=lambda s: s.replace("CELLS 40 200", "CELLS 41 205")), "error"
    )
    yield case("cells-count-zero", _mesh_text(edit=lambda s: s.replace("CELLS 40 200", "CELLS 0 0")), "error")
    yield case(
        "cell-types-count", _mesh_text(edit=lambda s: s.replace("CELL_TYPES 40", "CELL_TYPES 39")), "error"
    )
    yield case(
        "points-count-more",
        _mesh_text(edit=lambda s: s.replace(f"POINTS {n} float", f"POINTS {n + 5} float")),
        "error",
    )
    yield case(
        "points-count-less",
        _mesh_text(edit=lambda s: s.replace(f"POINTS {n} float", f"POINTS {n - 5} float")),
        "error",
    )
    yield case(
        "point-data-count",
        _mesh_text(edit=lambda s: s.replace(f"POINT_DATA {n}", f"POINT_DATA {n - 1}")),
        "error",
    )
    for label, value in (("nan", np.nan), ("inf", np.inf), ("huge", 1e300)):
        bad = points.copy()
        bad[4, 1] = value
        yield case(f"point-{label}", _mesh_text(points=bad), "error" if label != "huge" else "any")
        vals = values.astype(np.float64)
        vals[4] = value
        yield case(f"value-{label}", _mesh_text(values=vals), "any")
    yield case("all-values-nan", _mesh_text(values=np.full_like(values, np.nan)), "any")
    yield case("all-points-equal", _mesh_text(points=np.zeros_like(points)), "error")
    yield case("flat-mesh", _mesh_text(points=points * np.array([1.0, 1.0, 0.0])), "error")
    yield case("duplicated-tets", _mesh_text(tets=np.vstack([tets, tets])), "any")
    yield case("duplicated-tets-permuted", _mesh_text(tets=np.vstack([tets, tets[:, ::-1]])), "any")
    yield case("inverted-tets", _mesh_text(tets=tets[:, [1, 0, 2, 3]]), "any")
    yield case("repeated-vertex", _mesh_text(tets=np.where(np.arange(4) == 3, tets[:, :1], tets)), "error")
    yield case("no-cells", _mesh_text(edit=lambda s: s.split("CELLS")[0] + "POINT_DATA 27\nSCALARS pressure float 1\nLOOKUP_TABLE default\n" + "1\n" * 27), "error")  # fmt: skip
    yield case("no-point-data", _mesh_text(edit=lambda s: s.split("POINT_DATA")[0]), "error")
    yield case("cell-data-only", _mesh_text(edit=lambda s: s.replace(f"POINT_DATA {n}", "CELL_DATA 40").split("LOOKUP_TABLE default")[0] + "LOOKUP_TABLE default\n" + "2\n" * 40), "any")  # fmt: skip
    yield case(
        "value-type-string",
        _mesh_text(edit=lambda s: s.replace("SCALARS pressure float", "SCALARS pressure string")),
    )
    yield case("value-components-0", _mesh_text(edit=lambda s: s.replace("SCALARS pressure float 1", "SCALARS pressure float 0")), "error")  # fmt: skip
    yield case("value-components-9", _mesh_text(edit=lambda s: s.replace("SCALARS pressure float 1", "SCALARS pressure float 9")), "error")  # fmt: skip


def vtu_text_cases(seed: Seed) -> Iterator[Case]:
    """The ASCII .vtu's connectivity, offsets and types given indices past the points and -1."""
    text = seed.files[seed.target].decode()
    for array, label, new in (
        ("connectivity", "past-end", "27"), ("connectivity", "minus-one", "-1"), ("connectivity", "huge", "9223372036854775807"),
        ("offsets", "decreasing", "2"), ("offsets", "zero", "0"), ("offsets", "huge", "99999999"),
        ("types", "bogus", "255"), ("types", "zero", "0"), ("types", "negative", "-3"),
    ):  # fmt: skip
        m = re.search(rf'Name="{array}"[^>]*>\s*(-?\d+)\s+(-?\d+)', text)
        if not m:
            continue
        changed = text[: m.start(2)] + new + text[m.end(2) :]
        expect: Expect = "error" if array != "types" or label != "bogus" else "any"
        yield _case(seed, f"{array}-{label}", {seed.target: changed.encode()}, expect)


# --------------------------------------------------------------------------------- raw flags


def raw_cases(seed: Seed) -> Iterator[Case]:
    data = seed.files[seed.target]

    def case(what: str, flags: tuple[str, ...], expect: Expect, content: bytes = data) -> Case:
        return Case(f"raw/{what}", "raw", {"v.raw": content}, render_argv("v.raw", *flags), expect,
                    ("v.raw", "--raw-shape", "--raw-dtype", "--raw-spacing", "--raw-byte-order"))  # fmt: skip

    for shape in (
        "8,7",
        "8,7,6,1",
        "0,7,6",
        "-8,7,6",
        "8,7,nan",
        "4294967296,1,1",
        "99999,99999,99999",
        "8.5,7,6",
        "x",
    ):
        yield case(f"shape={shape}", ("--raw-shape", shape, "--raw-dtype", "int16"), "error")
    for dtype in (
        "int17",
        "complex64",
        "object",
        "U8",
        "float16",
        "bool",
        "datetime64",
        "V2",
        "int8",
        "uint32",
    ):
        expect: Expect = "any" if dtype in ("float16", "int8", "uint32") else "error"
        yield case(f"dtype={dtype}", ("--raw-shape", "8,7,6", "--raw-dtype", dtype), expect)
    for spacing in ("0,1,1", "nan,1,1", "inf,1,1", "-1,1,1", "1,1", "a,b,c"):
        expect = "any" if spacing == "-1,1,1" else "error"
        yield case(
            f"spacing={spacing}",
            ("--raw-shape", "8,7,6", "--raw-dtype", "int16", "--raw-spacing", spacing),
            expect,
        )
    yield case("no-dtype-two-bytes", ("--raw-shape", "8,7,6"), "error")
    yield case("no-shape", (), "error")
    yield case(
        "float-nan-data",
        ("--raw-shape", "8,7,6", "--raw-dtype", "float64"),
        "any",
        np.full(336, np.nan).tobytes(),
    )
    yield case(
        "float-inf-data",
        ("--raw-shape", "8,7,6", "--raw-dtype", "float64"),
        "any",
        np.full(336, np.inf).tobytes(),
    )
    yield case(
        "float-huge-data",
        ("--raw-shape", "8,7,6", "--raw-dtype", "float64"),
        "any",
        np.full(336, 1e308).tobytes(),
    )
    yield case("float32-denormal", ("--raw-shape", "8,7,6", "--raw-dtype", "float32"), "any", np.full(336 * 2, 1e-42, np.float32).tobytes())  # fmt: skip
    yield case("constant", ("--raw-shape", "8,7,6", "--raw-dtype", "int16"), "any", bytes(len(data)))


# ---------------------------------------------------------------------------------- the corpus


def volume_cases(seed_value: int = 0) -> list[Case]:
    """Every volume case, in a fixed order (`seed_value` drives the byte-level randomness)."""
    rng = random.Random(seed_value)
    out: list[Case] = []
    for seed in seeds():
        out.append(Case(f"{seed.name}/valid", seed.name.split("-")[0], seed.files, render_argv(seed.target, *seed.flags), "render"))  # fmt: skip
        out += byte_cases(seed, rng)
        name = seed.name
        if name.startswith(("nrrd", "nhdr", "mhd", "mha", "legacy", "slc")):
            header_file = next(
                f for f in seed.files if f.endswith((".nrrd", ".nhdr", ".mhd", ".mha", ".vtk", ".slc"))
            )
            full = name in (
                "nrrd-raw",
                "nhdr",
                "mhd",
                "mha-zlib",
                "legacy-binary",
                "legacy-mesh-30",
                "slc-rle",
            )
            out += text_field_cases(seed, header_file, full)
        if name.startswith(("vti", "vtu")):
            out += xml_attribute_cases(seed, full=name in ("vti-raw", "vti-zlib", "vtu-binary"))
        if name.startswith("nii"):
            out += nifti_cases(seed)
        if name == "dicom":
            out += dicom_cases(seed)
        if name == "vtu-ascii":
            out += vtu_text_cases(seed)
        if name == "raw":
            out += raw_cases(seed)
        if name == "slc-raw":
            out += slc_cases()
    out += mesh_cases()
    return out
