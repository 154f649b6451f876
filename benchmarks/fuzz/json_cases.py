"""Malformed transfer-function and scene files, and bad values of every `volren render` flag.

Each JSON case starts from a valid document and changes one thing: a key dropped, a value of
the wrong type, NaN, a list too short, too long or nested too deep, bytes that are not JSON.
"""

from __future__ import annotations

import copy
import json
from collections.abc import Iterator
from typing import Any

from benchmarks.fuzz.cases import Case, Expect, render_argv
from benchmarks.fuzz.seeds import seeds

_VOLUME = "v.vti"

TF_1D: dict[str, Any] = {
    "version": 1,
    "kind": "1d",
    "color": [[0, 0.1, 0.1, 0.3], [800, 0.9, 0.5, 0.2], [2200, 1, 1, 0.9]],
    "opacity": [[0, 0], [700, 0.05], [1600, 0.8], [2200, 1]],
    "opacity_unit_distance": 1.0,
}

TF_2D: dict[str, Any] = {
    "version": 1,
    "kind": "2d",
    "value_range": [0, 2200],
    "gradient_range": [0, 800],
    "widgets": [
        {
            "type": "gaussian",
            "center": [1500, 300],
            "width": [300, 200],
            "color": [1, 0.8, 0.6],
            "opacity": 0.8,
        },
        {
            "type": "triangle",
            "value": 700,
            "half_width": 200,
            "gradient_max": 600,
            "color": [0.2, 0.4, 1],
            "opacity": 0.3,
        },
        {
            "type": "box",
            "value_range": [100, 400],
            "gradient_range": [0, 400],
            "color": [0, 1, 0],
            "opacity": 0.1,
        },
    ],  # fmt: skip
}

#: Replacement values of the wrong kind, tried in place of every value of a document.
WRONG = (None, True, "abc", -1, 0, 1e308, float("nan"), float("inf"), [], {}, [[]], [1], "1e999")


def _volume_files() -> dict[str, bytes]:
    seed = next(s for s in seeds() if s.name == "vti-raw")
    return dict(seed.files)


def _paths(doc: Any, prefix: tuple = ()) -> Iterator[tuple]:
    """Every path (tuple of keys and indices) to a value in `doc`."""
    yield prefix
    if isinstance(doc, dict):
        for k, v in doc.items():
            yield from _paths(v, (*prefix, k))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            yield from _paths(v, (*prefix, i))


def _set(doc: Any, path: tuple, value: Any, drop: bool = False) -> Any:
    out = copy.deepcopy(doc)
    if not path:
        return value
    parent = out
    for key in path[:-1]:
        parent = parent[key]
    if drop:
        del parent[path[-1]]
    else:
        parent[path[-1]] = value
    return out


def _dump(doc: Any) -> bytes:
    return json.dumps(doc, allow_nan=True).encode()


def _label(path: tuple) -> str:
    return ".".join(str(p) for p in path) or "root"


def _document_cases(group: str, doc: dict, file: str, argv: tuple[str, ...], files: dict[str, bytes],
                    refused_at: set[str]) -> Iterator[Case]:  # fmt: skip
    """One case per (value, wrong value) and per dropped key. A wrong value of a key in
    `refused_at` (its label's first part) must be an error."""
    for path in _paths(doc):
        if not path:
            continue
        label = _label(path)
        for wrong in WRONG:
            if not isinstance(path[-1], int) or wrong in (None, "abc", float("nan"), -1, 1e308):
                expect: Expect = (
                    "error" if str(path[0]) in refused_at and not _harmless(path, wrong) else "any"
                )
                yield Case(f"{group}/{label}={json.dumps(wrong)}", group, {**files, file: _dump(_set(doc, path, wrong))},
                           argv, expect, (file,))  # fmt: skip
        if isinstance(path[-1], str):
            yield Case(f"{group}/{label}-dropped", group, {**files, file: _dump(_set(doc, path, None, drop=True))},
                       argv, "any", (file,))  # fmt: skip


def _harmless(path: tuple, wrong: Any) -> bool:
    """Values that are legal where they stand: a data value or an angle of -1, 0 or 1e308 (fmod
    of a double is exact), an opacity of 0, a flag turned on, an empty settings object (defaults),
    a widget placed or sized anywhere on the value and gradient axes (it then misses the data)."""
    if path[0] == "transfer_function":  # a scene's inline TF: the TF's own rules
        path = path[1:]
    if not path or isinstance(wrong, bool) and wrong is not True:
        return False
    number = isinstance(wrong, int | float) and not isinstance(wrong, bool)
    key = path[-1] if not isinstance(path[-1], int) else path[-2]
    if number and wrong in (0, -1, 1e308):
        if path[0] in ("color", "opacity") and len(path) == 3 and path[2] == 0:
            return True  # a data value
        if path[0] in ("color", "opacity") and len(path) == 3 and wrong == 0:
            return True  # a colour or opacity of 0
        if key in ("azimuth", "elevation"):
            return True
        if path[0] in ("value_range", "gradient_range") and wrong != 0:
            return True  # the table's range: wide, or below zero on the value axis
        if (
            path[0] == "widgets"
            and key in ("center", "value", "value_range", "gradient_range")
            and wrong != 0
        ):
            return True  # a widget anywhere
        if path[0] == "widgets" and key in ("width", "half_width", "gradient_max") and wrong == 1e308:
            return True  # a widget that covers everything
        if path[0] == "widgets" and key == "value" and wrong == 0:
            return True
        if path[0] == "widgets" and key == "opacity" and wrong == 0:
            return True
        if key == "opacity_unit_distance" and wrong == 1e308:
            return True  # nearly transparent, as asked
    if wrong is True and key in ("parallel", "shade", "preintegration", "jitter"):
        return True
    if wrong == {} and key in ("camera", "settings", "options"):
        return True  # the defaults
    if wrong is None and key == "scalars":
        return True  # the first point array, as when it is left out
    return False


def _raw_text_cases(group: str, file: str, argv: tuple[str, ...], files: dict[str, bytes]) -> Iterator[Case]:
    texts = {
        "empty": b"",
        "not-json": b"this is not json",
        "truncated": _dump(TF_1D)[:40],
        "nested-100000": b"[" * 100_000 + b"]" * 100_000,
        "nested-dict-deep": b'{"a":' * 5000 + b"1" + b"}" * 5000,
        "array-top": b"[1, 2, 3]",
        "number-top": b"42",
        "null-top": b"null",
        "utf16": json.dumps(TF_1D).encode("utf-16"),
        "bom": b"\xef\xbb\xbf" + _dump(TF_1D),
        "latin1-garbage": bytes(range(128, 256)),
        "huge-number": b'{"version": 1, "kind": "1d", "color": [[1e999999, 0, 0, 0]], "opacity": [[0, 0]]}',
        "duplicate-keys": b'{"version": 1, "version": 99, "kind": "1d", "color": [[0,0,0,0]], "opacity": [[0,0]]}',
        "nul-bytes": b"\0" * 100,
        "long-string": b'{"kind": "' + b"x" * 1_000_000 + b'"}',
    }
    for label, text in texts.items():
        expect: Expect = "any" if label in ("bom",) else "error"
        yield Case(f"{group}/text-{label}", group, {**files, file: text}, argv, expect, (file,))


def tf_cases() -> list[Case]:
    files = _volume_files()
    out: list[Case] = []
    for kind, doc in (("tf1d", TF_1D), ("tf2d", TF_2D)):
        argv = render_argv(
            _VOLUME, "--tf", "tf.json", *(("--renderer", "reference") if kind == "tf2d" else ())
        )
        refused = {
            "version",
            "kind",
            "color",
            "opacity",
            "value_range",
            "gradient_range",
            "widgets",
            "opacity_unit_distance",
        }
        out += _document_cases(kind, doc, "tf.json", argv, files, refused)
        out += _raw_text_cases(kind, "tf.json", argv, files)
    many = {**TF_1D, "opacity": [[i, (i % 7) / 7] for i in range(200_000)]}
    argv = render_argv(_VOLUME, "--tf", "tf.json")
    out.append(
        Case("tf1d/points-200000", "tf1d", {**files, "tf.json": _dump(many)}, argv, "error", ("tf.json",))
    )
    widgets = {**TF_2D, "widgets": [TF_2D["widgets"][0]] * 5000}
    out.append(
        Case("tf2d/widgets-5000", "tf2d", {**files, "tf.json": _dump(widgets)}, argv, "error", ("tf.json",))
    )
    unsorted = {**TF_1D, "opacity": [[1600, 0.8], [0, 0], [700, 0.05]]}
    out.append(
        Case("tf1d/unsorted", "tf1d", {**files, "tf.json": _dump(unsorted)}, argv, "any", ("tf.json",))
    )
    miss = {**TF_1D, "color": [[1e6, 1, 1, 1], [2e6, 1, 1, 1]], "opacity": [[1e6, 1], [2e6, 1]]}
    out.append(
        Case("tf1d/range-misses-data", "tf1d", {**files, "tf.json": _dump(miss)}, argv, "any", ("tf.json",))
    )
    preset = [{"Name": "x", "ColorSpace": "Lab", "RGBPoints": [0, 0, 0, 0, 1, "a", 1, 1]}]
    out.append(
        Case(
            "tf1d/paraview-preset-bad",
            "tf1d",
            {**files, "tf.json": _dump(preset)},
            argv,
            "error",
            ("tf.json",),
        )
    )
    for space in ("Bogus", None, 5):
        preset = [{"Name": "x", "ColorSpace": space, "RGBPoints": [0, 0, 0, 0, 1, 1, 1, 1]}]
        out.append(Case(f"tf1d/paraview-colorspace-{space}", "tf1d", {**files, "tf.json": _dump(preset)}, argv, "any", ("tf.json",)))  # fmt: skip
    return out


def scene_document() -> dict[str, Any]:
    return {
        "version": 1,
        "volume": {"path": _VOLUME, "scalars": None},
        "transfer_function": TF_1D,
        "camera": {"azimuth": 30.0, "elevation": 20.0, "zoom": 1.0, "parallel": False},
        "settings": {
            "step": 0.5,
            "shade": True,
            "blend_mode": "composite",
            "preintegration": False,
            "options": {},
        },
        "renderer": "vtk",
        "size": [24, 24],
    }


def scene_cases() -> list[Case]:
    files = _volume_files()
    argv = ("render", "--scene", "scene.json", "-o", "out.png", "--save-array", "out.npy")
    refused = {"version", "volume", "transfer_function", "camera", "settings", "renderer", "size"}
    doc = scene_document()
    out = list(_document_cases("scene", doc, "scene.json", argv, files, refused))
    out += _raw_text_cases("scene", "scene.json", argv, files)
    out.append(
        Case("scene/valid", "scene", {**files, "scene.json": _dump(doc)}, argv, "render", ("scene.json",))
    )
    for label, path in (("missing-volume", "nope.vti"), ("volume-is-folder", "."), ("volume-is-scene", "scene.json"),
                        ("volume-absolute-missing", "/nonexistent/v.vti")):  # fmt: skip
        changed = {**doc, "volume": {"path": path}}
        out.append(
            Case(
                f"scene/{label}",
                "scene",
                {**files, "scene.json": _dump(changed)},
                argv,
                "error",
                ("scene.json",),
            )
        )
    tf_missing = {**doc, "transfer_function": "nope.json"}
    out.append(
        Case(
            "scene/tf-path-missing",
            "scene",
            {**files, "scene.json": _dump(tf_missing)},
            argv,
            "error",
            ("scene.json",),
        )
    )
    tf_self = {**doc, "transfer_function": "scene.json"}
    out.append(
        Case(
            "scene/tf-path-is-scene",
            "scene",
            {**files, "scene.json": _dump(tf_self)},
            argv,
            "error",
            ("scene.json",),
        )
    )
    big = {**doc, "size": [100000, 100000]}
    out.append(
        Case("scene/size-huge", "scene", {**files, "scene.json": _dump(big)}, argv, "error", ("scene.json",))
    )
    out.append(Case("scene/output-is-volume", "scene", {**files, "scene.json": _dump(doc)},
                    ("render", "--scene", "scene.json", "-o", _VOLUME), "error", (_VOLUME, "-o")))  # fmt: skip
    return out


#: (flag, bad values, whether every value must be refused)
_FLAGS: tuple[tuple[str, tuple[str, ...], bool], ...] = (
    ("--size", ("0", "-5", "nan", "1e9", "100000", "10x", "x10", "abc", "3x0", ""), True),
    ("--azimuth", ("nan", "inf", "-inf", "abc", "1e308"), False),
    ("--elevation", ("nan", "inf", "90", "-90", "abc"), False),
    ("--zoom", ("0", "-1", "nan", "inf", "1e-300", "1e300", "abc"), False),
    ("--step", ("0", "-1", "nan", "inf", "1e-9", "1e-300", "1e300", "abc"), False),
    ("--renderer", ("nosuch", "", "VTK", "../vtk", "vtk;ls"), True),
    ("--blend", ("nosuch", "", "MAXIMUM"), True),
    ("--option", ("novalue", "=1", "mapper=nosuch", "mapper=", "jitter=abc", "x" * 5000 + "=1"), False),
    ("--scalars", ("nosuch", "", "density\0"), False),
    ("--tf", ("nope.json", ".", "v.vti", "/dev/null"), True),
    ("--scene", ("nope.json", "."), True),
    ("-o", ("", ".", "nofolder/out.png", "out.txt", "/proc/out.png", "out"), False),
    ("--save-array", ("", ".", "nofolder/a.npy", "v.vti"), False),
)

#: How a message names the renderer at fault when no --renderer is given (`auto` chose it).
_DEFAULT_RENDERER = "(chosen by --renderer auto)"

_STRICT_VALUES = {"0", "-1", "nan", "inf", "-inf", "abc", "", "-5", "1e-300", "1e300", "1e9", "100000"}


def flag_cases() -> list[Case]:
    """Each flag of `volren render` with values it must refuse or cope with; the volume is valid."""
    files = _volume_files()
    out: list[Case] = []
    for flag, values, always in _FLAGS:
        for value in values:
            argv = list(render_argv(_VOLUME))
            if flag in ("-o", "--save-array"):
                index = argv.index(flag)
                argv[index + 1] = value
            elif flag == "--size":
                argv[argv.index("--size") + 1] = value
            else:
                argv += [flag, value]
            strict = always or (value in _STRICT_VALUES and flag in ("--zoom", "--step"))
            strict = strict or (
                value in ("nan", "inf", "-inf", "abc") and flag in ("--azimuth", "--elevation")
            )
            parts = (value, *value.split("=")) if value and len(value) < 100 else ()
            names = tuple(n for n in (flag, _VOLUME, _DEFAULT_RENDERER, *parts) if n)
            out.append(Case(f"flags/{flag.strip('-')}={value[:20] or 'empty'}", "flags", files, tuple(argv),
                            "error" if strict else "any", names))  # fmt: skip
    for combo, expect in (
        (("--parallel", "--zoom", "0.001"), "any"),
        (("--blend", "maximum", "--preintegration"), "any"),
        (("--renderer", "reference", "--step", "1e-6"), "error"),
        (("--renderer", "slicer", "--step", "1e-6"), "error"),
        (("--renderer", "tetra"), "error"),
        (("--raw-shape", "8,7,6"), "error"),
        (("--transparent", "--size", "1"), "any"),
        (("--size", "1x1"), "any"),
    ):
        out.append(Case(f"flags/combo-{'_'.join(a.strip('-') for a in combo)}", "flags", files,
                        render_argv(_VOLUME, *combo), expect, (_VOLUME, _DEFAULT_RENDERER, *combo)))  # fmt: skip
    return out
