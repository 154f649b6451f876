"""Turning what a VTK reader printed into one line a person can act on.

VTK readers rarely raise: they print, and return an empty or half-filled dataset. Some of what
they call warnings mean the data is wrong ("Error reading binary data!" from the legacy reader is
a warning), so those count as errors here.
"""

from __future__ import annotations

import re

from volren.io._pv import MessageLog, VtkMessage

# Warnings that mean the data is incomplete or wrong.
_BAD_WARNING = re.compile(r"error|fail|premature|truncat|not all meta ?data|cannot|unable|could ?n.t", re.I)

# (pattern in VTK's text, the problem to report), most telling first: the first pattern that
# matches any message wins. {0} is VTK's own text, {1}... the pattern's groups.
_PROBLEMS: tuple[tuple[re.Pattern[str], str], ...] = tuple(
    (re.compile(p, re.I), problem)
    for p, problem in (
        (r"Zlib error|uncompress|inflate", "corrupt: its compressed data cannot be decompressed ({0})"),
        (r"Error parsing XML in stream at line (\d+), column (\d+).*?: (.*)",
         "truncated or not well-formed XML (line {1}, column {2}: {3})"),
        (r"Cannot read \w+ data array \"([^\"]*)\"",
         "truncated or corrupt: data array '{1}' is shorter than its header says"),
        (r"Error reading extent .* from piece",
         "the data does not match the extent the header declares ({0})"),
        (r"Unable to allocate|bad_alloc", "too large for this machine's memory ({0})"),
        (r"Unrecognized file type|Premature EOF reading first line",
         "not a legacy VTK file ({0})"),
        (r"Bad NIfTI header", "not a NIfTI file (VTK: bad header)"),
        (r"is not a nrrd file", "not a NRRD file"),
        (r"magic number", "not an SLC file ({0})"),
        (r"MetaImage cannot parse file", "not a MetaImage file ({0})"),
        (r"MetaImage cannot read data", "truncated or corrupt: MetaImage could not read all the data"),
        (r"reading binary|Premature EOF|truncated|not read completely|File operation failed|"
         r"Couldn't read gzip|Unable to read compressed slice|Error reading|Not all meta data",
         "truncated or corrupt ({0})"),
    )
)  # fmt: skip


def _clean(text: str, path: str = "") -> str:
    if path:  # the path is already at the start of the message
        text = text.replace(path, "")
    text = re.sub(r"\s*for file:?\s*$", "", text)
    text = re.sub(r"\(0x[0-9a-f]+\)", "", text)
    return " ".join(text.split())[:240]


def serious(log: MessageLog) -> list[VtkMessage]:
    """Errors, and warnings that mean the data is wrong, in the order VTK printed them."""
    return [
        m for m in log.messages if m.kind == "error" or (m.kind == "warning" and _BAD_WARNING.search(m.text))
    ]


def problem(log: MessageLog, path: object = "") -> str | None:
    """The problem to report for a read of `path`, or None when VTK said nothing alarming."""
    bad = serious(log)
    if not bad:
        return None
    for pattern, template in _PROBLEMS:
        for message in bad:
            m = pattern.search(message.text)
            if m:
                text = _clean(message.text, str(path))
                return template.format(text, *(_clean(g or "", str(path)) for g in m.groups()))
    return f"VTK could not read it: {_clean(bad[0].text, str(path))}"


def detail(log: MessageLog) -> str:
    """Everything VTK printed, for debugging (not for users)."""
    return " | ".join(f"{m.kind}: {m.text}" for m in log.messages)
