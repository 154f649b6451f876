"""Size checks made from a file's header before any VTK reader sees the file.

VTK's readers allocate what the header declares and then read: a header that declares more than
the machine has ends in std::bad_alloc, which aborts the whole process, and data shorter than
declared is read past its end or silently zero-filled. Checking both here turns them into
one-line errors.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

from volren.errors import file_error


def physical_memory() -> int:
    """Bytes of RAM in this machine (0 when the OS does not say)."""
    try:
        return int(os.sysconf("SC_PHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, ValueError, OSError):  # pragma: no cover - non-POSIX
        return 0


def human_bytes(n: float) -> str:
    """'1.5 GiB' style sizes for messages."""
    for unit in ("bytes", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if abs(n) < 1024 or unit == "PiB":
            return f"{n:,.0f} {unit}" if unit == "bytes" else f"{n:,.1f} {unit}"
        n /= 1024
    return f"{n:.1f} EiB"  # pragma: no cover


@dataclass(frozen=True)
class DataLayout:
    """What a header promises: how much memory the data needs and where its bytes lie.

    `data_bytes` is None when the size on disk cannot be known from the header (compressed or
    text encodings); then only the memory check applies.
    """

    shape: tuple[int, ...]
    type_name: str
    memory_bytes: int
    data_file: Path | None = None
    data_offset: int = 0
    data_bytes: int | None = None
    label: str | None = None

    def describe(self) -> str:
        """'256x256x128 uint8', or the label given for data that is not a grid."""
        return self.label or f"{'x'.join(str(n) for n in self.shape)} {self.type_name}"


def check_memory(path: Path | str, what: str, nbytes: int) -> None:
    """Refuse data that could not fit in this machine's memory."""
    ram = physical_memory()
    if ram and nbytes > ram:
        raise file_error(
            path,
            f"too large: the header declares {what} = {human_bytes(nbytes)}, more than this "
            f"machine's {human_bytes(ram)} of memory",
        )


def check_layout(path: Path | str, layout: DataLayout) -> None:
    """Memory first, then whether the data file holds all the bytes the header declares."""
    check_memory(path, layout.describe(), layout.memory_bytes)
    if layout.data_bytes is None or layout.data_file is None:
        return
    if not layout.data_file.is_file():
        raise file_error(path, f"the data file {layout.data_file.name!r} named in the header is missing")
    have = layout.data_file.stat().st_size - layout.data_offset
    if have < layout.data_bytes:
        where = "" if layout.data_file == Path(path) else f" in {layout.data_file.name}"
        raise file_error(
            path,
            f"truncated (or wrong dimensions): the header declares {layout.describe()} = "
            f"{layout.data_bytes:,} bytes of data but only {max(have, 0):,} bytes follow{where}",
        )


def product(values) -> int:
    return int(math.prod(int(v) for v in values))
