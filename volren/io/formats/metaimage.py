"""MetaImage (.mhd header + data file, or .mha with the data inside).

VTK's MetaImage reader aborts the process (std::bad_alloc) on an absurd DimSize and, on short
data, reports an error but still returns a full-size array; MetaIO also prints straight to
std::cerr. So the header is parsed here and the data size checked before the reader runs.
"""

from __future__ import annotations

from pathlib import Path

from volren.errors import file_error
from volren.io.formats.base import FileFormat, Inspection, quote, read_head
from volren.io.formats.geometry import check_declared, parse_numbers
from volren.io.limits import DataLayout, product

_TYPE_SIZES = {
    "MET_CHAR": 1, "MET_UCHAR": 1, "MET_SHORT": 2, "MET_USHORT": 2, "MET_INT": 4, "MET_UINT": 4,
    "MET_LONG": 4, "MET_ULONG": 4, "MET_LONG_LONG": 8, "MET_ULONG_LONG": 8, "MET_FLOAT": 4,
    "MET_DOUBLE": 8,
}  # fmt: skip


def _header(path: Path) -> tuple[dict[str, str], int]:
    """Header fields (keys lower-cased) and the byte offset just after ElementDataFile."""
    head = read_head(path)
    fields: dict[str, str] = {}
    offset = 0
    for raw in head.splitlines(keepends=True):
        offset += len(raw)
        line = raw.decode("latin-1").strip()
        if not line:
            continue
        key, sep, value = line.partition("=")
        if not sep or not key.strip().replace("_", "").isalnum():
            raise file_error(path, f"not a MetaImage header: line {quote(line)} is not 'Key = Value'")
        fields[key.strip().lower()] = value.strip()
        if key.strip().lower() == "elementdatafile":
            return fields, offset
    if "dimsize" not in fields:
        raise file_error(path, "not a MetaImage header: it has no DimSize")
    raise file_error(path, "truncated: the MetaImage header ends before its ElementDataFile line")


def inspect(path: Path) -> Inspection:
    fields, header_end = _header(path)
    try:
        dims = tuple(int(v) for v in fields.get("dimsize", "").split())
        ndims = int(fields.get("ndims", len(dims)))
        channels = int(fields.get("elementnumberofchannels", "1"))
        header_size = int(fields.get("headersize", "0"))
    except ValueError:
        raise file_error(
            path,
            "malformed MetaImage header: DimSize, NDims, HeaderSize and "
            "ElementNumberOfChannels must be integers",
        ) from None
    if not dims or len(dims) != ndims:
        raise file_error(
            path, f"malformed MetaImage header: NDims = {ndims} but DimSize = {fields.get('dimsize')!r}"
        )
    if min(dims) <= 0:
        raise file_error(path, f"malformed MetaImage header: DimSize {dims} must be positive")
    if not 2 <= ndims <= 3:
        raise file_error(path, f"NDims = {ndims}: volren reads 2D and 3D MetaImage files")
    if not 1 <= channels <= 64:
        raise file_error(path, f"ElementNumberOfChannels = {channels} must be between 1 and 64")
    spacing = parse_numbers(path, "ElementSpacing", fields.get("elementspacing") or fields.get("elementsize"))
    origin_key = next((k for k in ("offset", "origin", "position") if k in fields), "offset")
    origin = parse_numbers(path, origin_key.capitalize(), fields.get(origin_key))
    facts = check_declared(path, spacing, origin, "ElementSpacing", origin_key.capitalize())
    element = fields.get("elementtype", "").upper()
    if element not in _TYPE_SIZES:
        raise file_error(path, f"unsupported MetaImage ElementType {fields.get('elementtype')!r}")
    nbytes = product(dims) * channels * _TYPE_SIZES[element]
    type_name = element[4:].lower()
    layout = DataLayout(dims, type_name, nbytes)
    compressed = _flag(path, fields, "CompressedData", False)
    binary = _flag(path, fields, "BinaryData", True)
    data_name = fields.get("elementdatafile", "")
    if data_name.upper().startswith("LIST") or "%" in data_name:
        raise file_error(
            path, f"ElementDataFile = {data_name}: volren does not read MetaImage slice lists or patterns"
        )
    data_file, start = (path, header_end) if data_name.upper() == "LOCAL" else (path.parent / data_name, 0)
    if compressed:
        _check_compressed(path, fields, start, data_file, nbytes)
    if compressed or not binary or header_size < 0:
        return Inspection("metaimage", path, layout, facts)  # sizes on disk unknown: VTK reports these
    layout = DataLayout(dims, type_name, nbytes, data_file, start + header_size, nbytes)
    return Inspection("metaimage", path, layout, facts)


def _flag(path: Path, fields: dict[str, str], key: str, default: bool) -> bool:
    """A True/False field. MetaIO reads any word starting with T, t or 1 as true, so a value
    that is neither word is refused rather than read one way here and the other way by VTK."""
    value = fields.get(key.lower())
    if value is None:
        return default
    if value.lower() not in ("true", "false"):
        raise file_error(path, f"{key} = {quote(value)} must be True or False")
    return value.lower() == "true"


#: zlib's deflate expands at most 1032 times; more declared data than that cannot be in the file.
_MAX_DEFLATE_RATIO = 1032


def _check_compressed(path: Path, fields: dict[str, str], offset: int, data_file: Path, nbytes: int) -> None:
    """What MetaIO trusts in compressed data: CompressedDataSize, and that the bytes are zlib."""
    if not data_file.is_file():
        raise file_error(path, f"the data file {data_file.name!r} named in the header is missing")
    available = data_file.stat().st_size - offset
    declared = fields.get("compresseddatasize")
    if declared is not None:
        if not declared.isdigit() or not 0 < int(declared) <= available:
            raise file_error(
                path, f"CompressedDataSize = {declared!r} but {max(available, 0):,} bytes of data follow"
            )
        available = int(declared)
    if nbytes > _MAX_DEFLATE_RATIO * max(available, 0):
        raise file_error(
            path, f"truncated or wrong DimSize: {available:,} compressed bytes cannot hold {nbytes:,} bytes"
        )
    with open(data_file, "rb") as f:
        f.seek(offset)
        magic = f.read(2)
    if len(magic) < 2 or magic[0] & 0x0F != 8 or (magic[0] << 8 | magic[1]) % 31:
        raise file_error(path, "CompressedData = True but the data is not zlib-compressed")


METAIMAGE = FileFormat("MetaImage", (".mhd", ".mha"), inspect)
