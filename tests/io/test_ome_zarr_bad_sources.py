"""OME-Zarr images that a server, a disk or a writer got wrong, and flags that do not apply to
how an image is read: each a one-line error (or warning) naming the URL, file or flag, never a
traceback, an exception's class name, a hang, or a render of nothing in silence."""

from __future__ import annotations

import json
import re
import shutil
import warnings

import numpy as np
import pytest

from volren.cli.main import main
from volren.errors import VolrenError, VolrenWarning
from volren.model.volume import UniformVolume

zarr = pytest.importorskip("zarr", reason="volren[zarr] is part of the test set-up")
from benchmarks.fuzz.http_server import serving  # noqa: E402
from volren.io.ome_zarr_io import open_multiscale  # noqa: E402

#: What a message must not hold: an exception's class name (ValueError, ClientResponseError, ...).
CLASS_NAME = re.compile(r"\b[A-Z][a-zA-Z]*(Error|Exception)\b")


@pytest.fixture
def image(tmp_path):
    """`volren convert` of a small volume: two levels of 4^3 bricks (6x7x8 and 3x3x4), brick ranges stored."""
    from volren.io import save_volume

    values = (np.arange(6 * 7 * 8, dtype=np.int16).reshape(6, 7, 8) * 3 + 10).astype(np.int16)
    source = tmp_path / "cells.vti"
    save_volume(UniformVolume(values, spacing=(0.5, 0.75, 1.25), name="cells"), source)
    path = tmp_path / "cells.zarr"
    assert main(["convert", str(source), str(path), "--chunks", "4"]) == 0
    return path


@pytest.fixture
def render(capsys, tmp_path):
    """`volren render TARGET FLAGS` to an array in the test's folder: its status and its stderr lines."""

    def run(target, *flags: str) -> tuple[int, list[str]]:
        capsys.readouterr()
        out = tmp_path / "out.npy"
        code = main(["render", str(target), "--size", "12", *flags, "--save-array", str(out), "--force"])
        return code, capsys.readouterr().err.splitlines()

    return run


def edit_json(path, change) -> None:
    document = json.loads(path.read_text())
    change(document)
    path.write_text(json.dumps(document))


@pytest.mark.parametrize(("mode", "problem"), [
    ("500", "the server answered HTTP 500 Internal Server Error"),
    ("403", "the server answered HTTP 403 Forbidden"),
    ("loop", "the server redirected too many times (a redirect loop)"),
    ("short", "the server's answer was cut short"),
    ("chunks-500", "level '1', brick 0.0.0: cannot be read: the server answered HTTP 500 Internal Server Error"),
    ("chunks-short", "level '1', brick 0.0.0: cannot be read: the server's answer was cut short"),
])  # fmt: skip
def test_a_failing_server_is_one_line_naming_the_url(image, render, mode, problem):
    """Metadata or chunks refused (500, 403), redirected for ever, or cut short: the image's URL and
    what the server did, in words (the scene is set up on the coarsest level, level '1')."""
    with serving(image.parent) as base:
        url = f"{base}/{mode}/{image.name}"
        code, lines = render(url, "--renderer", "reference")
        assert (code, lines) == (1, [f"volren: error: {url}: {problem}"])
        ok, lines = render(f"{base}/ok/{image.name}", "--renderer", "reference")
    assert ok == 0 and lines == []


def open_error(path) -> str:
    with pytest.raises(VolrenError) as exc:
        open_multiscale(path)
    text = str(exc.value)
    assert "\n" not in text and not CLASS_NAME.search(text), text
    return text


@pytest.mark.parametrize(("file", "change", "problem"), [
    ("0/.zarray", lambda d: d.update(chunks=[0, 4, 4]),
     "level '0': its shape (6, 7, 8) and chunk shape (0, 4, 4) must have no empty side"),
    (".zattrs", lambda d: d["multiscales"][0]["datasets"][0].update(coordinateTransformations=["scale"]),
     "level '0': its coordinateTransformations must be a list of objects, got ['scale']"),
    (".zattrs", lambda d: d["multiscales"][0]["datasets"][1]["coordinateTransformations"][0].update(scale="1,1,1"),
     "level '1': its scale must be a list of 3 finite numbers, got '1,1,1'"),
    (".zattrs", lambda d: d["volren"]["brick_ranges"][0].__setitem__(3, [5]),
     "'volren.brick_ranges' of level '0': a brick range must be null or [min, max], got [5]"),
    (".zattrs", lambda d: d["volren"]["brick_ranges"][1].__setitem__(0, [9, 1]),
     "'volren.brick_ranges' of level '1': a brick range must be null or [min, max], got [9, 1]"),
    (".zattrs", lambda d: d["multiscales"][0].update(datasets=["0"]),
     "each of 'datasets' must be an object with a 'path', got '0'"),
    (".zattrs", lambda d: d["multiscales"][0].update(axes="zyx"), "'axes' must be a list of axes, got 'zyx'"),
])  # fmt: skip
def test_malformed_metadata_is_one_line_naming_the_image_and_the_part(image, file, change, problem):
    edit_json(image / file, change)
    assert open_error(image) == f"{image}: {problem}"


def test_metadata_that_is_not_json_is_one_line(image):
    (image / "0" / ".zarray").write_text('{"shape": [6, 7')
    assert open_error(image).startswith(f"{image}: level '0' cannot be opened: ")


def test_a_level_without_chunk_files_is_refused_when_volren_stored_its_values(image, tmp_path):
    """Its stored ranges say what its chunks held; an image of fill values alone (zarr writes no
    chunk of them) is no false alarm."""
    from volren.io.ome_zarr_io import save_ome_zarr

    for chunk in (image / "0").glob("[0-9]*"):
        chunk.unlink()
    assert open_error(image) == (f"{image}: level '0' has no chunk files, yet its stored brick ranges reach "
                                 f"{6 * 7 * 8 * 3 + 7}: its chunks are missing")  # fmt: skip
    zeros = tmp_path / "zeros.zarr"
    save_ome_zarr(UniformVolume(np.zeros((6, 7, 8), np.uint8)), zeros, chunk=4, levels=2)
    assert not list(zeros.glob("[0-9]/[0-9]*"))
    with warnings.catch_warnings():
        warnings.simplefilter("error", VolrenWarning)
        open_multiscale(zeros)


@pytest.mark.filterwarnings("default::volren.errors.VolrenWarning")  # the CLI prints it as one line
def test_an_image_without_chunk_files_renders_saying_so(image, render):
    """An image volren did not write (no stored ranges) and whose chunks are all absent reads as its
    fill value everywhere: it renders, with one warning line per empty level."""
    for chunk in image.glob("[0-9]/[0-9]*"):
        chunk.unlink()
    edit_json(image / ".zattrs", lambda d: d.pop("volren"))
    code, lines = render(image, "--renderer", "reference", "--level", "1")
    assert code == 0 and lines == [
        f"volren: warning: {image}: level '0' has no chunk files: every value reads as its fill value 0",
        f"volren: warning: {image}: level '1' has no chunk files: every value reads as its fill value 0",
    ]


@pytest.mark.filterwarnings("default::volren.errors.VolrenWarning")  # vtk's coarser level, said in one line
@pytest.mark.parametrize("renderer", ["reference", pytest.param("vtk", marks=pytest.mark.vtk)])
def test_too_little_memory_is_refused_alike_by_every_renderer(image, render, renderer):
    """--memory 100: less than a chunk (128 bytes) in the cache; a renderer that streams bricks
    (reference) would ignore it, one that reads a level whole (vtk) refused it in other words. A
    renderer that reads a level whole needs its own copies of the coarsest level besides (vtk: 4
    bytes a voxel, 36 voxels of 2 bytes)."""
    code, lines = render(image, "--renderer", renderer, "--memory", "100")
    assert (code, lines) == (1, [f"volren: error: {image}: --memory 100 bytes is too little; this image needs "
                                 "at least 171 bytes (its coarsest level read whole, and a chunk in the chunk "
                                 "cache)"])  # fmt: skip
    enough = 171 if renderer == "reference" else 36 * (2 + 4)
    assert render(image, "--renderer", renderer, "--memory", str(enough))[0] == 0
    if renderer == "vtk":
        assert render(image, "--renderer", renderer, "--memory", str(enough - 1)) == (1, [
            f"volren: error: {image}: --memory 215 bytes is too little for renderer vtk, which does not stream "
            "bricks: it takes 216 bytes to draw even the coarsest level"])  # fmt: skip


def test_level_and_memory_are_refused_where_no_ome_zarr_input_is_read(image, tmp_path, capsys, render):
    """A scene's own volume is read whole and raw data has no levels: --level or --memory would
    be ignored there."""
    scene = tmp_path / "scene.json"
    tf = {
        "version": 1,
        "kind": "1d",
        "color": [[0, 0, 0, 1], [1500, 1, 1, 1]],
        "opacity": [[0, 0], [1500, 0.5]],
    }
    scene.write_text(json.dumps({"version": 1, "volume": {"path": str(image)}, "transfer_function": tf,
                                 "renderer": "reference"}))  # fmt: skip
    for flags, flag in ((["--scene", str(scene), "--level", "1"], "--level"),
                        (["--scene", str(scene), "--memory", "1GB"], "--memory")):  # fmt: skip
        capsys.readouterr()
        assert main(["render", *flags, "--size", "12", "--save-array", str(tmp_path / "out.npy")]) == 1
        assert capsys.readouterr().err.splitlines() == [
            f"volren: error: {flag} applies to an OME-Zarr INPUT (a .zarr folder or URL), not to the scene's "
            "volume (give the image as INPUT)"]  # fmt: skip
    raw = tmp_path / "v.raw"
    raw.write_bytes(bytes(4 * 4 * 4))
    code, lines = render(raw, "--raw-shape", "4,4,4", "--level", "0")
    assert (code, lines) == (1, ["volren: error: --level applies to an OME-Zarr INPUT (a .zarr folder or URL), "
                                 "not to headerless raw data"])  # fmt: skip


def test_a_broken_chunk_names_it_without_a_class_name(image):
    from volren.io.ome_zarr_io import load_level

    (image / "0" / "0.0.1").write_bytes(b"not a chunk")
    with pytest.raises(
        VolrenError, match=rf"^{re.escape(str(image))}: level '0', brick 0.0.1: cannot be read: "
    ) as exc:
        load_level(image, 0)
    assert not CLASS_NAME.search(str(exc.value)), exc.value
    shutil.rmtree(image / "1")
    assert open_error(image) == f"{image}: level '1' is listed but missing"


@pytest.mark.parametrize(("index", "kind", "values"), [(0, "scale", [1e308, 1, 1]), (1, "scale", [1, 1e308, 1]),
                                                       (1, "translation", [0, 0, 1e308])])  # fmt: skip
def test_voxels_placed_beyond_any_camera_are_one_line_naming_the_level(image, render, index, kind, values):
    """A scale or translation of 1e308 put the bounds (or the camera) at infinity: errors that named
    neither the image nor the level, or an internal error."""
    edit_json(image / ".zattrs", lambda d: next(t for t in d["multiscales"][0]["datasets"][index]["coordinateTransformations"]
                                                if t["type"] == kind).update({kind: values}))  # fmt: skip
    code, lines = render(image, "--renderer", "reference")
    assert code == 1 and len(lines) == 1
    assert lines[0].startswith(f"volren: error: {image}: level '{index}': its scale ") and lines[0].endswith(
        " place voxels beyond +-1e+100"
    ), lines
