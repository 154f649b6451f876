"""Property test of the parsers written in Python: whatever a file says, reading it gives a
result or a VolrenError (one line for the user), never another exception (the rule of pydicom's
fuzz harness).

The inputs are structured: documents shaped like the real ones (TF JSON of both kinds, ParaView
presets, scenes with cameras, settings and movies, raw layouts, OME-Zarr multiscales metadata)
with a few of their parts replaced by the values that break parsers (integers beyond float64, NaN
and Inf, booleans, text, empty or nested containers), and NRRD and MetaImage headers whose fields
are drawn from good and bad values. Few examples each, so that the whole file stays fast; the
seed varies from run to run.
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from volren.errors import VolrenError

SETTINGS = settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
#: An integer beyond float64's range, which JSON allows: the first thing the test found.
HUGE = 10**400
TF = {"version": 1, "color": [[0, 1, 1, 1]], "opacity": [[0, 1]]}


def survives(call, *args, **kwargs):
    """The call's result, or None when it raised a one-line VolrenError; any other exception
    fails the test."""
    try:
        return call(*args, **kwargs)
    except VolrenError as exc:
        assert "\n" not in str(exc), str(exc)
        return None


@pytest.fixture(scope="module")
def folder():
    with tempfile.TemporaryDirectory() as name:
        yield Path(name)


# ----------------------------------------------------------------------- documents, mutated

#: Values that break parsers: beyond float64 and int64, NaN and Inf, subnormals, booleans, text,
#: nothing, empty containers.
odd = st.one_of(
    st.sampled_from([10**400, -(10**400), 2**63, 1e308, -1e308, 1e-320, float("nan"), float("inf"),
                     -float("inf"), True, False, None, "", "1", "0.5", "x", [], {}, 0, -1]),
    st.floats(allow_nan=True, allow_infinity=True), st.integers(), st.text(max_size=4),
)  # fmt: skip
anything = st.recursive(
    odd,
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=3), inner, max_size=3),
    max_leaves=8,
)


def _paths(node, path=()):
    """Every place in a JSON document (its containers too), as tuples of keys and indices."""
    yield path
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    for key, child in items:
        yield from _paths(child, (*path, key))


def _replaced(node, path, new):
    if not path:
        return new
    copy = dict(node) if isinstance(node, dict) else list(node)
    copy[path[0]] = _replaced(node[path[0]], path[1:], new)
    return copy


@st.composite
def mutated(draw, valid: st.SearchStrategy):
    """A valid document with up to three of its values (or whole parts) replaced by odd values or
    arbitrary JSON: how hand-edited and generated files go wrong."""
    document = draw(valid)
    for _ in range(draw(st.integers(0, 3))):
        path = draw(st.sampled_from(list(_paths(document))))
        document = _replaced(document, path, draw(st.one_of(odd, anything)))
    return document


def documents(valid: st.SearchStrategy) -> st.SearchStrategy:
    return st.one_of(mutated(valid), anything)


unit = st.floats(0.0, 1.0)
value = st.floats(-100.0, 100.0)
ranges = st.tuples(value, value).map(lambda p: [min(p), max(p) + 1.0])


def nodes(width: int) -> st.SearchStrategy:
    """[x, v, ...] rows: x a data value, the rest in [0, 1]."""
    return st.lists(st.tuples(value, *[unit] * (width - 1)).map(list), min_size=1, max_size=5)


def flat_nodes(width: int) -> st.SearchStrategy:
    """ParaView's flat node lists: x not decreasing, then width - 1 values in [0, 1] each."""
    return nodes(width).map(lambda rows: [v for row in sorted(rows) for v in row])


tf_1d = st.fixed_dictionaries(
    {"version": st.just(1), "kind": st.just("1d"), "color": nodes(4), "opacity": nodes(2)},
    optional={"opacity_unit_distance": st.floats(0.01, 10.0), "name": st.text(max_size=3)},
)
widget_shapes = st.one_of(
    st.fixed_dictionaries({"type": st.just("gaussian"), "center": st.tuples(value, unit).map(list),
                           "width": st.tuples(unit, unit).map(lambda w: [w[0] + 0.1, w[1] + 0.1])}),
    st.fixed_dictionaries({"type": st.just("triangle"), "value": value, "half_width": st.floats(0.1, 5.0),
                           "gradient_max": st.floats(0.1, 5.0)}),
    st.fixed_dictionaries({"type": st.just("box"), "value_range": ranges, "gradient_range": st.just([0.0, 1.0])}),
)  # fmt: skip
looks = st.fixed_dictionaries({"color": st.lists(unit, min_size=3, max_size=3), "opacity": unit})
widget = st.tuples(widget_shapes, looks).map(lambda parts: {**parts[0], **parts[1]})
tf_2d = st.fixed_dictionaries(
    {"version": st.just(1), "kind": st.just("2d"), "value_range": ranges, "gradient_range": st.just([0.0, 2.0]),
     "widgets": st.lists(widget, max_size=3)},
    optional={"opacity_unit_distance": st.floats(0.01, 10.0)},
)  # fmt: skip
#: ParaView's colour spaces but Lab/CIEDE2000 (VTK takes 0.1 s a segment there: too slow here).
color_spaces = st.sampled_from(["RGB", "HSV", "Lab", "CIELAB", "Diverging", "Step"])
preset = st.fixed_dictionaries(
    {"Name": st.text(max_size=3), "ColorSpace": color_spaces, "RGBPoints": flat_nodes(4)},
    optional={"Points": flat_nodes(4), "UseLogScale": st.booleans(), "HSVWrap": st.booleans(),
              "NanColor": st.just([1, 1, 0])},
)  # fmt: skip
camera = st.one_of(
    st.fixed_dictionaries({}, optional={"azimuth": value, "elevation": value, "zoom": st.floats(0.5, 2.0),
                                        "parallel": st.booleans()}),
    st.fixed_dictionaries(
        {"position": st.just([0.0, 0.0, 5.0]), "focal_point": st.just([0.0, 0.0, 0.0])},
        optional={"view_up": st.just([0.0, 1.0, 0.0]), "view_angle": st.floats(10.0, 60.0), "parallel": st.booleans(),
                  "parallel_scale": st.floats(0.1, 3.0), "clipping_range": st.just([0.1, 100.0])},
    ),
)  # fmt: skip
render_settings = st.fixed_dictionaries(
    {},
    optional={"step": st.floats(0.1, 2.0), "preintegration": st.booleans(), "shade": st.booleans(), "ambient": unit,
              "specular_power": st.floats(1.0, 50.0), "blend_mode": st.sampled_from(["composite", "mip"]),
              "jitter": st.booleans(), "options": st.dictionaries(st.text(max_size=3), st.integers(), max_size=2)},
)  # fmt: skip
keyframe = st.fixed_dictionaries({"time": unit}, optional={"camera": camera, "transfer_function": tf_1d})
movie = st.fixed_dictionaries(
    {},
    optional={"frames": st.integers(1, 50), "fps": st.floats(1.0, 60.0), "orbit": value,
              "keyframes": st.lists(keyframe, max_size=3)},
)  # fmt: skip
scene = st.fixed_dictionaries(
    {"version": st.just(1), "transfer_function": st.one_of(tf_1d, tf_2d)},
    optional={"volume": st.fixed_dictionaries({"path": st.just("v.vti")}, optional={"scalars": st.text(max_size=3)}),
              "camera": camera, "settings": render_settings, "renderer": st.sampled_from(["auto", "vtk"]),
              "size": st.tuples(st.integers(1, 64), st.integers(1, 64)).map(list), "movie": movie},
)  # fmt: skip


@SETTINGS
@given(document=documents(st.one_of(tf_1d, tf_2d)))
@example(document={**TF, "color": [[0, 1, 1, HUGE]]})
@example(document={**TF, "opacity_unit_distance": HUGE})
@example(document={"kind": "2d", "value_range": [0, HUGE], "gradient_range": [0, 1], "widgets": []})
def test_transfer_function_json(folder, document):
    from volren.io.tf_io import load_transfer_function, save_transfer_function

    path = folder / "tf.json"
    path.write_text(json.dumps(document))
    tf = survives(load_transfer_function, path)
    if tf is None:
        return
    try:
        save_transfer_function(tf, path)
    except VolrenError:  # unknown keys are kept, and JSON cannot hold a NaN among them: one line
        return
    assert load_transfer_function(path) == tf  # what was read, written, reads the same


@SETTINGS
@given(document=documents(st.one_of(preset, st.lists(preset, min_size=1, max_size=2))),
       name=st.one_of(st.none(), st.text(max_size=2)))  # fmt: skip
def test_paraview_presets(folder, document, name):
    from volren.io.tf_io import load_transfer_function

    path = folder / "preset.json"
    path.write_text(json.dumps(document))
    survives(load_transfer_function, path, name)


@SETTINGS
@given(document=documents(scene))
@example(
    document={
        "version": 1,
        "transfer_function": TF,
        "camera": {"position": [HUGE, 0, 5], "focal_point": [0, 0, 0]},
    }
)
@example(document={"version": 1, "transfer_function": TF, "camera": {"azimuth": HUGE}})
@example(document={"version": 1, "transfer_function": TF, "movie": {"orbit": HUGE}})
def test_scene_json(folder, document):
    from volren.io.scene_io import load_scene
    from volren.model.animation import Animation

    path = folder / "scene.json"
    path.write_text(json.dumps(document))
    loaded = survives(load_scene, path, load_volume=False)
    if loaded is not None and "movie" in loaded.extra:
        survives(Animation.from_dict, loaded.extra["movie"])


RAW_ARGUMENTS = {
    "shape": st.just([4, 4, 4]), "dtype": st.sampled_from(["uint8", "uchar", "i1", np.uint8]),
    "byte_order": st.sampled_from(["little", "big", "native"]), "spacing": st.just([1.0, 2.0, 3.0]),
    "origin": st.just([0.0, 0.0, 0.0]), "header_bytes": st.just(0)}  # fmt: skip


@SETTINGS
@given(document=mutated(st.fixed_dictionaries(RAW_ARGUMENTS)))
@example(document={"shape": [4, 4, float("inf")]})
@example(document={"shape": [4, 4, 4], "spacing": [HUGE, 1, 1]})
@example(document={"shape": [4, 4, 4], "byte_order": []})
@example(document={"spacing": 7})
def test_load_raw_arguments(folder, document):
    from volren.io import load_volume

    path = folder / "w.raw"
    path.write_bytes(bytes(64))
    arguments = document if isinstance(document, dict) else {}  # a mutated root: no arguments
    survives(load_volume, path, **{key: v for key, v in arguments.items() if key in RAW_ARGUMENTS})


# ---------------------------------------------------------------------------- volume headers


def words(choices: list[str], most: int = 4, joined: str = " ") -> st.SearchStrategy:
    return st.lists(st.sampled_from(choices), max_size=most).map(joined.join)


def vector(choices: list[str]) -> st.SearchStrategy:
    return words(choices, joined=",").map(lambda text: f"({text})")


sizes = st.lists(st.integers(-1, 5), max_size=4).map(lambda s: " ".join(map(str, s)))
nrrd_fields = st.fixed_dictionaries(
    {"type": st.sampled_from(["uchar", "short", "unsigned short", "int", "float", "double", "int64", "block", "x"]),
     "sizes": sizes, "encoding": st.sampled_from(["raw", "ascii", "gzip", "bzip2", "hex", "?"])},
    optional={"dimension": st.integers(0, 5).map(str), "endian": st.sampled_from(["little", "big", "middle"]),
              "space": st.sampled_from(["left-anterior-superior", "RAS", "3D-right-handed", "x"]),
              "space directions": st.lists(st.one_of(st.just("none"), vector(["0", "1", "-2", "nan", "1e400", "x"])),
                                           max_size=4).map(" ".join),
              "spacings": words(["1", "0", "-1", "nan", "1e400", "a"]),
              "space origin": vector(["0", "2", "inf", "b"]),
              "kinds": words(["domain", "space", "vector", "3-color", "none", "bogus"]),
              "byte skip": st.sampled_from(["0", "-1", "4", "x"]), "line skip": st.sampled_from(["0", "1", "-1", "x"]),
              "data file": st.sampled_from(["d.raw", "LIST", "missing.raw", "d%d.raw 0 1 1"])},
)  # fmt: skip
mhd_fields = st.fixed_dictionaries(
    {"DimSize": sizes,
     "ElementType": st.sampled_from(["MET_UCHAR", "MET_SHORT", "MET_FLOAT", "MET_LONG_LONG", "MET_STRING", "x"]),
     "ElementDataFile": st.sampled_from(["LOCAL", "d.raw", "missing.raw", "LIST", "d%d.raw 0 1 1"])},
    optional={"NDims": st.integers(0, 5).map(str),
              "ElementSpacing": st.sampled_from(["1 1 1", "0 1 1", "nan 1 1", "1", "a b c"]),
              "Offset": st.sampled_from(["0 0 0", "1e400 0 0", "x"]),
              "HeaderSize": st.sampled_from(["0", "-1", "8", "x"]),
              "ElementNumberOfChannels": st.sampled_from(["1", "3", "0", "100"]),
              "BinaryData": st.sampled_from(["True", "False", "x"]), "CompressedData": st.sampled_from(["True", "False"]),
              "CompressedDataSize": st.sampled_from(["10", "-5", "x"]),
              "ElementByteOrderMSB": st.sampled_from(["True", "False"]),
              "TransformMatrix": st.sampled_from(["1 0 0 0 1 0 0 0 1", "0 0 0 0 0 0 0 0 0"])},
)  # fmt: skip


def read_header_and_own_data(path: Path) -> None:
    """What loading does before any VTK reader sees the file: the format's header checks, the size
    checks, and the format's own reader (NRRD's ASCII data)."""
    from volren.io.formats import find_format
    from volren.io.limits import check_layout

    fmt = find_format(path)
    inspection = fmt.inspect(path)
    if inspection.layout is not None:
        check_layout(path, inspection.layout)
    if fmt.read is not None:
        fmt.read(path, inspection)


@SETTINGS
@given(
    fields=nrrd_fields, data=st.binary(max_size=40), numbers=words(["1", "2.5", "-3", "x", "1e400"], most=30)
)
def test_nrrd_headers(folder, fields, data, numbers):
    header = "NRRD0004\n" + "".join(f"{key}: {text}\n" for key, text in fields.items())
    body = numbers.encode() if fields["encoding"] == "ascii" else data
    (folder / "d.raw").write_bytes(body)
    (folder / "h.nrrd").write_bytes(header.encode() + b"\n" + body)
    survives(read_header_and_own_data, folder / "h.nrrd")


@SETTINGS
@given(fields=mhd_fields, data=st.binary(max_size=40))
def test_metaimage_headers(folder, fields, data):
    header = "".join(f"{key} = {text}\n" for key, text in fields.items() if key != "ElementDataFile")
    header += f"ElementDataFile = {fields['ElementDataFile']}\n"
    (folder / "d.raw").write_bytes(data)
    (folder / "h.mhd").write_bytes(header.encode() + data)
    survives(read_header_and_own_data, folder / "h.mhd")


# ------------------------------------------------------------------------------------ raw flags

flag_triples = st.one_of(words(["2", "3", "0", "-1", "1e400", "9" * 400, "nan", "x", ""], joined=","),
                         st.text(max_size=6))  # fmt: skip
raw_dtypes = st.sampled_from(["uint8", "uchar", "MET_SHORT", "float", "float16", "complex64", "U3", "object", "bool",
                              "V2", ">i2", "quad"])  # fmt: skip


@SETTINGS
@given(shape=st.one_of(st.none(), flag_triples), dtype=st.one_of(st.none(), raw_dtypes, st.text(max_size=5)),
       byte_order=st.sampled_from([None, "little", "big"]), spacing=st.one_of(st.none(), flag_triples),
       size=st.integers(0, 80))  # fmt: skip
@example(shape="9" * 400 + ",4,4", dtype=None, byte_order=None, spacing=None, size=64)
def test_raw_flags(folder, shape, dtype, byte_order, spacing, size):
    from volren.cli.raw_flags import check_raw_flags, raw_load_arguments
    from volren.io import load_volume

    path = folder / "v.raw"
    path.write_bytes(bytes(range(size)))
    args = argparse.Namespace(input=str(path), raw_shape=shape, raw_dtype=dtype, raw_byte_order=byte_order,
                              raw_spacing=spacing)  # fmt: skip

    def load() -> None:
        check_raw_flags(args, "render")
        arguments = raw_load_arguments(args)
        if arguments:
            load_volume(path, **arguments)

    survives(load)


# --------------------------------------------------------------------------- OME-Zarr metadata


@pytest.fixture(scope="module")
def ome_zarr(folder):
    """A real two-level OME-Zarr image (arrays 4^3 and 2^3) and its metadata as volren wrote it,
    which each example rewrites."""
    pytest.importorskip("zarr")
    from volren.io.ome_zarr_io import save_ome_zarr
    from volren.model.volume import UniformVolume

    path = folder / "image.zarr"
    save_ome_zarr(UniformVolume(np.arange(64, dtype=np.float32).reshape(4, 4, 4)), path, chunk=2, levels=2)
    return path, json.loads((path / ".zattrs").read_text())


@SETTINGS
@given(data=st.data())
def test_ome_zarr_multiscales_metadata(ome_zarr, data):
    from volren.io.ome_zarr_io import open_multiscale

    path, written = ome_zarr
    as_v05 = {"ome": {"version": "0.5", "multiscales": written["multiscales"]}}
    attributes = data.draw(documents(st.sampled_from([written, as_v05])))
    (path / ".zattrs").write_text(json.dumps(attributes))
    survives(open_multiscale, path)


@pytest.mark.parametrize("place", [("multiscales", 0, "datasets", 0, "coordinateTransformations", 0, "scale", 2),
                                   ("volren", "brick_ranges", 1, 0, 1)])  # fmt: skip
def test_ome_zarr_integers_beyond_float64(ome_zarr, place):
    from volren.io.ome_zarr_io import open_multiscale

    path, written = ome_zarr
    (path / ".zattrs").write_text(json.dumps(_replaced(written, place, HUGE)))
    with pytest.raises(VolrenError, match="finite|must be null or"):
        open_multiscale(path)
