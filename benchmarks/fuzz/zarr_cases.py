"""Malformed OME-Zarr images, the flags that choose how one is read, and a server that fails.

The seed is a small image that `volren convert` would write (two levels of 4^3 bricks, volren's
brick ranges). Its metadata (.zattrs, a level's .zarray) is changed one thing at a time, its
chunk files are cut, garbled or all removed, and it is read over HTTP from a local server
(`http_server`) that answers with an error status, a redirect loop or a body cut short. An
argument ``{http:MODE}`` stands for the server's address for this case's folder in that mode;
`with_server` fills it in when the case runs.
"""

from __future__ import annotations

import json
import re
import tempfile
from collections.abc import Callable, Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

from benchmarks.fuzz.cases import Case, Expect, render_argv
from benchmarks.fuzz.json_cases import _document_cases, _dump
from benchmarks.fuzz.seeds import SPACING, grid_values

IMAGE = "img.zarr"
GROUP = "ome-zarr"
HTTP_GROUP = "ome-zarr-http"
_PLACEHOLDER = re.compile(r"\{http:([a-z0-9-]+)\}")


def seed_files() -> dict[str, bytes]:
    """The seed image's files, by path under the case folder (img.zarr/...)."""
    from volren.io.ome_zarr_io import save_ome_zarr
    from volren.model.volume import UniformVolume

    volume = UniformVolume(grid_values(), SPACING, (1.0, -2.0, 0.5), name="fuzz")
    with tempfile.TemporaryDirectory() as tmp:
        save_ome_zarr(volume, Path(tmp) / IMAGE, chunk=4, levels=2)
        return {
            p.relative_to(tmp).as_posix(): p.read_bytes() for p in sorted(Path(tmp).rglob("*")) if p.is_file()
        }


def _is_chunk(rel: str) -> bool:
    return not Path(rel).name.startswith(".") and Path(rel).name != "zarr.json"


def _edited(files: dict[str, bytes], rel: str, edit: Callable[[Any], Any]) -> dict[str, bytes]:
    """`files` with the JSON document `rel` changed by `edit` (which returns the new document)."""
    return {**files, rel: _dump(edit(json.loads(files[rel])))}


def _case(what: str, files: dict[str, bytes], expect: Expect = "error", *flags: str) -> Case:
    return Case(f"{GROUP}/{what}", GROUP, files, render_argv(IMAGE, *flags), expect, (IMAGE, *flags))


def _dataset(doc: dict, index: int = 0) -> dict:
    return doc["multiscales"][0]["datasets"][index]


def _set_in(doc: dict, change: Callable[[dict], None]) -> dict:
    change(doc)
    return doc


def metadata_cases(files: dict[str, bytes]) -> Iterator[Case]:
    """The image's group attributes and level 0's array metadata, one fault at a time: each must be refused."""
    attrs, array = f"{IMAGE}/.zattrs", f"{IMAGE}/0/.zarray"
    faults: dict[str, Callable[[dict], None]] = {
        "transforms-as-strings": lambda d: _dataset(d).update(
            coordinateTransformations=["scale", "translation"]
        ),
        "transforms-as-string": lambda d: _dataset(d).update(coordinateTransformations="scale"),
        "scale-as-string": lambda d: _dataset(d)["coordinateTransformations"][0].update(scale="1,1,1"),
        "scale-short": lambda d: _dataset(d)["coordinateTransformations"][0].update(scale=[1, 1]),
        "scale-zero": lambda d: _dataset(d)["coordinateTransformations"][0].update(scale=[0, 1, 1]),
        "scale-true": lambda d: _dataset(d)["coordinateTransformations"][0].update(scale=[True, 1, 1]),
        "translation-nan": lambda d: _dataset(d)["coordinateTransformations"][1].update(
            translation=[float("nan"), 0, 0]
        ),
        "range-short": lambda d: d["volren"]["brick_ranges"][0].__setitem__(0, [5]),
        "range-empty": lambda d: d["volren"]["brick_ranges"][0].__setitem__(0, []),
        "range-reversed": lambda d: d["volren"]["brick_ranges"][0].__setitem__(0, [9, 1]),
        "range-strings": lambda d: d["volren"]["brick_ranges"][0].__setitem__(0, ["a", "b"]),
        "range-number": lambda d: d["volren"]["brick_ranges"][0].__setitem__(0, 7),
        "ranges-one-level": lambda d: d["volren"].update(brick_ranges=d["volren"]["brick_ranges"][:1]),
        "datasets-as-string": lambda d: d["multiscales"][0].update(datasets="0"),
        "datasets-empty": lambda d: d["multiscales"][0].update(datasets=[]),
        "dataset-as-string": lambda d: d["multiscales"][0]["datasets"].__setitem__(0, "0"),
        "dataset-without-path": lambda d: _dataset(d).pop("path"),
        "dataset-path-absent": lambda d: _dataset(d).update(path="9"),
        "axes-as-string": lambda d: d["multiscales"][0].update(axes="zyx"),
        "axes-four": lambda d: d["multiscales"][0].update(axes=["t", "z", "y", "x"]),
        "multiscales-empty": lambda d: d.update(multiscales=[]),
        "multiscales-of-strings": lambda d: d.update(multiscales=["a"]),
    }
    for what, fault in faults.items():
        yield _case(f"zattrs-{what}", _edited(files, attrs, lambda d, f=fault: _set_in(d, f)))
    array_faults: dict[str, Callable[[dict], None]] = {
        "chunks-zero": lambda d: d.update(chunks=[0, 4, 4]),
        "chunks-negative": lambda d: d.update(chunks=[-4, 4, 4]),
        "chunks-short": lambda d: d.update(chunks=[4, 4]),
        "shape-zero": lambda d: d.update(shape=[0, 7, 8]),
        "shape-larger": lambda d: d.update(shape=[60, 70, 80]),
        "dtype-unknown": lambda d: d.update(dtype="<x9"),
        "compressor-unknown": lambda d: d.update(compressor={"id": "nosuch"}),
    }
    for what, fault in array_faults.items():
        yield _case(f"zarray-{what}", _edited(files, array, lambda d, f=fault: _set_in(d, f)))
    for rel in (attrs, array):
        for what, text in (("empty", b""), ("not-json", b"this is not json"), ("cut", files[rel][:20])):
            yield _case(f"{Path(rel).name.lstrip('.')}-text-{what}", {**files, rel: text})


def chunk_cases(files: dict[str, bytes]) -> Iterator[Case]:
    """Chunk files garbled, cut, emptied, one missing (legal: it reads as the fill value), and all
    of them missing (the image would draw as nothing: refused or said)."""
    chunks = [rel for rel in files if _is_chunk(rel)]
    first = chunks[0]
    for what, content in (("garbage", b"this is not a compressed chunk"), ("empty", b""),
                          ("cut", files[first][: len(files[first]) // 2])):  # fmt: skip
        yield _case(f"chunk-{what}", {**files, first: content})
    yield _case("chunk-missing", {rel: data for rel, data in files.items() if rel != first}, "any")
    no_chunks = {rel: data for rel, data in files.items() if not _is_chunk(rel)}
    yield _case("no-chunk-files", no_chunks)
    yield _case(
        "no-chunk-files-no-ranges",
        _edited(no_chunks, f"{IMAGE}/.zattrs", lambda d: _set_in(d, lambda x: x.pop("volren"))),
    )


def flag_cases(files: dict[str, bytes]) -> Iterator[Case]:
    """The flags that choose how an OME-Zarr image is read (and on which cluster), given values
    that do not apply: each refused in one line naming it."""
    for flags in (("--memory", "1"), ("--memory", "100"), ("--memory", "0"), ("--memory", "abc"), ("--level", "-1"),
                  ("--level", "2"), ("--scalars", "density"), ("--cluster", ""), ("--cluster", "remote"),
                  ("--scheduler", ""), ("--scheduler", "tls://127.0.0.1:9")):  # fmt: skip
        yield _case(f"flag{flags[0]}={flags[1] or 'empty'}", files, "error", *flags)


def sweep_cases(files: dict[str, bytes]) -> Iterator[Case]:
    """Every value of the group attributes replaced by values of the wrong kind, and every key
    dropped (the first two brick ranges of a level only: the others are alike): no crash, no
    traceback, one line."""
    rel = f"{IMAGE}/.zattrs"
    later_range = re.compile(r"brick_ranges\.\d+\.([2-9]|\d\d)")
    for case in _document_cases(GROUP, json.loads(files[rel]), rel, render_argv(IMAGE), files, set()):
        if not later_range.search(case.name):
            yield replace(case, name=case.name.replace(f"{GROUP}/", f"{GROUP}/sweep-", 1), names=(IMAGE,))


def http_cases(files: dict[str, bytes]) -> Iterator[Case]:
    """The image read over HTTP from a server that serves it well, or fails every request or every chunk."""
    for mode in ("ok", "500", "403", "loop", "short", "chunks-500", "chunks-short"):
        expect: Expect = "render" if mode == "ok" else "error"
        yield Case(
            f"{HTTP_GROUP}/{mode}",
            HTTP_GROUP,
            files,
            render_argv(f"{{http:{mode}}}/{IMAGE}"),
            expect,
            (IMAGE,),
        )


def zarr_cases() -> list[Case]:
    """Every OME-Zarr case, in a fixed order."""
    files = seed_files()
    return [_case("valid", files, "render"), *metadata_cases(files), *chunk_cases(files), *flag_cases(files),
            *http_cases(files), *sweep_cases(files)]  # fmt: skip


def written_by_hand(case: Case) -> bool:
    """An OME-Zarr case other than the sweep's: each a fault of its own, all in the quick subset."""
    return case.group in (GROUP, HTTP_GROUP) and "/sweep-" not in case.name


def needs_server(case: Case) -> bool:
    return any(_PLACEHOLDER.search(arg) for arg in case.argv)


def with_server(case: Case, base: str, folder: Path) -> Case:
    """`case` with each ``{http:MODE}`` replaced by the address at which the server `base` (serving
    the folder above `folder`) serves `folder` in that mode."""
    argv = tuple(_PLACEHOLDER.sub(lambda m: f"{base}/{m.group(1)}/{folder.name}", arg) for arg in case.argv)
    return replace(case, argv=argv)
