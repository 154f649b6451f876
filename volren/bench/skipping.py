"""What each skipping technique saves and what it changes in the image (`volren bench skip`).

For every scene (a volume, a TF, the scene's camera) and renderer, the same frames are drawn with
every skipping technique on, with each one off alone and with all off. A row gives the median ms
per frame, the renderer's work counters, and the image difference against the all-on and the
all-off image of the same renderer (max abs and RMSE, DESIGN.md's metric). Two more rows measure
skipping of other kinds: `shading` (lighting on: what "lighting off" saves; that image differs by
design) and `tf edit` (a TF edit before every frame, so tables and textures are rebuilt: what
reusing them while only the camera moves saves; its image must not change).

Techniques and their switches:
- slicer (march path): `empty_space_skipping` (bricks whose value range maps to zero opacity are
  jumped over: exact) and `early_termination` at `termination_alpha` (a ray stops with opacity >=
  alpha, so the rest could add at most 1 - alpha to any premultiplied channel).
- tetra: early termination (off: `termination_alpha` = 1, which no ray reaches) and skipping cells
  whose value range maps to zero opacity (off: `skip_transparent` = false): with it, a ray walks
  only the visible cells, leaves them at a transparent one and re-enters at the next visible cell's
  face, so `cell_steps` and `cells_integrated` both drop. The skip is exact to the optical model, not to the
  image with those cells integrated: the 3D pre-integration table interpolates between its 256 value
  bins, so a segment in a cell just beside an opacity spike or ramp gets a little opacity from the
  table (measured at 512x512: 1e-4 max abs on the smooth TFs, up to 6.6e-3 on the spiky ones; on
  spx spiky the pixels that differ are closer to `reference` with the skip).
- shearwarp (plugin): `empty_space_skipping` (runs of cells whose value range, widened by the
  slab's shear, maps to zero opacity are not visited: exact) and `early_termination` at its
  `termination_alpha` (0.995; VolPack's skip links jump over opaque intermediate pixels).
- objectorder (plugin): `octree_skipping` (min-max octree nodes whose value range maps to zero
  opacity are not entered: exact) and `hidden_volume_removal` (nodes whose footprint the
  hierarchical occlusion map shows finished are skipped whole: within 1 - its termination_alpha
  0.999); `cells` counts the leaf cells processed.
- raycast: `empty_space_skipping` (bricks of 4 cells whose value range, widened by the cells a
  pre-integrated segment reaches, maps to zero opacity are not sampled, and a ray leaves a box of
  them in one jump: exact) and early termination at `termination_alpha` 0.999 (off: 1).
- vtk: VTK's mappers skip on their own (the GPU ray caster stops a ray at opacity 1 - 1/255, a
  shader constant) with no switch, so vtk gets the all-on row only, as the peer, plus its lighting
  (grids) and TF-edit rows.

Timing: the configurations of one renderer are alive together and drawn interleaved (frame k of
each in turn), so load from other processes falls on all alike: a warm-up frame each at the scene's
view (compilation, uploads, tables), then `frames` timed frames while the camera turns `turn`
degrees of azimuth per frame (the same views in every row; 0 keeps the view fixed); ms is their
median. The counters and the compared image come from one more frame at the scene's view (in the
TF-edit row, right after an edit; that row edits its own copy of the TF).
"""

from __future__ import annotations

import csv
import json
import statistics
import time
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import ExitStack
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.settings import RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import Volume
from volren.renderers.base import Renderer
from volren.testing.metrics import image_error

#: The termination opacity of slicer and tetra by default; early termination changes a pixel by at
#: most 1 - alpha per channel.
ALPHA = 0.999
#: Renderers whose default termination opacity is another (their option `termination_alpha`).
TERMINATION_ALPHA = {"shearwarp": 0.995}
#: Float32 rounding allowed on top of a bound (the slicer composites in float32 on the GPU).
ROUNDING = 1e-5
RENDERERS = ("slicer", "tetra", "vtk", "shearwarp", "objectorder", "raycast")


@dataclass(frozen=True)
class Variant:
    """One configuration of a renderer; `kind` says what its image difference means."""

    key: str
    label: str
    options: Mapping[str, Any] = field(default_factory=dict)
    kind: str = "skip"  # skip: same image within `bound`; shading: a different image; reuse: same image
    shade: bool = False
    tf_edit: bool = False
    terminates: bool = True


def _two_switches(
    skip: tuple[str, str, Mapping[str, Any]], stop: tuple[str, str, Mapping[str, Any]]
) -> tuple[Variant, ...]:
    """The rows of a renderer with a skipping switch and an early-termination switch, each given as
    (variant key, label, options that turn it off): all on, each off alone, all off, shading, TF edit."""
    (skip_key, skip_label, skip_off), (stop_key, stop_label, stop_off) = skip, stop
    return (
        Variant("all_on", "all on"),
        Variant(skip_key, skip_label, skip_off),
        Variant(stop_key, stop_label, stop_off, terminates=False),
        Variant("all_off", "all off", {**skip_off, **stop_off}, terminates=False),
        Variant("shading", "all on, shading on", kind="shading", shade=True),
        Variant("tf_edit", "all on, TF edited every frame", kind="reuse", tf_edit=True),
    )


_EARLY_TERMINATION_OFF = ("no_early_termination", "early termination off", {"early_termination": False})

VARIANTS: dict[str, tuple[Variant, ...]] = {
    "slicer": _two_switches(
        ("no_empty_space", "empty-space skipping off", {"empty_space_skipping": False}),
        _EARLY_TERMINATION_OFF,
    ),
    "tetra": _two_switches(
        ("no_transparent_skip", "transparent cells integrated", {"skip_transparent": False}),
        ("no_early_termination", "early termination off", {"termination_alpha": 1.0}),
    ),
    "shearwarp": _two_switches(
        ("no_empty_space", "run-length skipping off", {"empty_space_skipping": False}), _EARLY_TERMINATION_OFF
    ),
    "objectorder": _two_switches(
        ("no_octree_skipping", "octree skipping off", {"octree_skipping": False}),
        ("no_hidden_volume_removal", "hidden volume removal off", {"hidden_volume_removal": False}),
    ),
    "raycast": _two_switches(
        ("no_empty_space", "empty-space skipping off", {"empty_space_skipping": False}),
        ("no_early_termination", "early termination off", {"termination_alpha": 1.0}),
    ),
    "vtk": (
        Variant("all_on", "VTK's own skipping (no switch)"),
        Variant("shading", "shading on", kind="shading", shade=True),
        Variant("tf_edit", "TF edited every frame", kind="reuse", tf_edit=True),
    ),
}
#: The technique each "off alone" row measures: variant key -> (technique, counter it saves).
TECHNIQUES = {
    ("slicer", "no_empty_space"): ("empty-space skipping", "samples"),
    ("slicer", "no_early_termination"): ("early termination", "samples"),
    ("slicer", "all_off"): ("all skipping", "samples"),
    ("tetra", "no_transparent_skip"): ("transparent cells skipped", "cells_integrated"),
    ("tetra", "no_early_termination"): ("early termination", "cell_steps"),
    ("tetra", "all_off"): ("all skipping", "cells_integrated"),
    ("shearwarp", "no_empty_space"): ("run-length skipping", "samples"),
    ("shearwarp", "no_early_termination"): ("early termination", "samples"),
    ("shearwarp", "all_off"): ("all skipping", "samples"),
    ("objectorder", "no_octree_skipping"): ("octree skipping", "cells"),
    ("objectorder", "no_hidden_volume_removal"): ("hidden volume removal", "cells"),
    ("objectorder", "all_off"): ("all skipping", "cells"),
    ("raycast", "no_empty_space"): ("empty-space skipping", "samples"),
    ("raycast", "no_early_termination"): ("early termination", "samples"),
    ("raycast", "all_off"): ("all skipping", "samples"),
}
WORK_COUNTERS = (
    "samples",
    "brick_steps",
    "rays_terminated",
    "bricks_empty",
    "cell_steps",
    "cells_integrated",
    "cells_transparent",
    "rays_hit",
    "empty_pixels_skipped",
    "pixels_terminated",
    "cells",
    "cells_occluded",
    "nodes",
)
COLUMNS = (
    "dataset",
    "tf",
    "renderer",
    "variant",
    "label",
    "kind",
    "size",
    "frames",
    "turn_deg",
    "ms",
    "ms_min",
    "ms_max",
    *WORK_COUNTERS,
    "uploaded_tables_per_frame",
    "uploaded_brick_mask_per_frame",
    "max_abs_vs_all_on",
    "rmse_vs_all_on",
    "max_abs_vs_all_off",
    "rmse_vs_all_off",
    "bound_vs_all_on",
    "bound_vs_all_off",
)


@dataclass(frozen=True)
class Scene:
    """A volume with its TF and view, named for the table."""

    dataset: str
    style: str
    volume: Volume
    tf: TransferFunction1D
    camera: Camera


def scene_kind(dataset: str, samples: bool = False) -> str:
    """The volume kind of a shared dataset (or bundled sample) before it is loaded."""
    from volren.bench.datasets import SCENES
    from volren.samples import SAMPLES

    if samples:
        return "tet" if SAMPLES[dataset][0].endswith(".vtu") else "uniform"
    return "tet" if SCENES[dataset][0].startswith("tets/") else "uniform"


def shared_scenes(shared: Path, datasets: Iterable[str], styles: Sequence[str]) -> Iterator[Scene]:
    """The scenes of ../shared/scenes, each dataset loaded once, when its turn comes."""
    from volren.bench.datasets import SCENES
    from volren.io import load_volume

    for dataset in datasets:
        path, scalars, azimuth, elevation, zoom = SCENES[dataset]
        volume = load_volume(shared / "data" / path, scalars=scalars)
        camera = Camera.orbit(volume.bounds, azimuth, elevation, zoom)
        for style in styles:
            tf = TransferFunction1D.from_dict(
                json.loads((shared / "scenes" / f"{dataset}-{style}.json").read_text())
            )
            yield Scene(dataset, style, volume, tf, camera)


def sample_scenes(names: Iterable[str]) -> Iterator[Scene]:
    """The bundled samples (volren.samples) with their own TFs, seen like the shared scenes."""
    from volren.samples import sample_transfer_functions, sample_volumes

    volumes, tfs = sample_volumes(), sample_transfer_functions()
    for name in names:
        volume = volumes[name]
        yield Scene(name, "sample", volume, tfs[name], Camera.orbit(volume.bounds, 30, 20, 1.0))


#: --quick: two small scenes where early termination and empty space both matter.
QUICK_SHARED = (("ironProt", "spx"), ("opaque",))
QUICK_SAMPLES = ("phantom_ct", "hollow_cylinder")


def plan(
    shared: Path,
    samples: bool,
    datasets: str | None,
    styles: str | None,
    quick: bool,
) -> tuple[list[str], Iterator[Scene]]:
    """(volume kind of every scene, the scenes, loaded lazily) for the command line's choices."""
    from volren.bench.datasets import SCENES, STYLES
    from volren.samples import SAMPLES

    if samples:
        names = datasets.split(",") if datasets else list(QUICK_SAMPLES if quick else SAMPLES)
        unknown = [n for n in names if n not in SAMPLES]
        if unknown or not names:
            raise VolrenError(f"unknown samples {unknown}; choose from {', '.join(SAMPLES)}")
        return [scene_kind(n, True) for n in names], sample_scenes(names)
    if not (shared / "data").is_dir() or not (shared / "scenes").is_dir():
        raise VolrenError(f"{shared}: no data/ and scenes/ folders there (give --shared, or --samples)")
    names = datasets.split(",") if datasets else list(QUICK_SHARED[0] if quick else SCENES)
    chosen = styles.split(",") if styles else list(QUICK_SHARED[1] if quick else STYLES)
    unknown = [n for n in names if n not in SCENES]
    if unknown or not names:
        raise VolrenError(f"unknown datasets {unknown}; choose from {', '.join(SCENES)}")
    missing = [
        f"{n}-{s}.json" for n in names for s in chosen if not (shared / "scenes" / f"{n}-{s}.json").exists()
    ]
    if missing or not chosen:
        raise VolrenError(
            f"no such scene files in {shared / 'scenes'}: {', '.join(missing) or 'no styles given'}"
        )
    return [scene_kind(n) for n in names for _ in chosen], shared_scenes(shared, names, chosen)


def renderers_for(kind: str, names: Iterable[str]) -> list[str]:
    """The benchmarked renderers, of `names`, that draw volumes of this kind."""
    from volren.renderers.registry import registry

    return [n for n in names if kind in registry.capabilities(n).volume_kinds]


def variants_for(name: str, kind: str, base: RenderSettings) -> list[Variant]:
    """The variants of a renderer it can draw on this kind of volume (vtk has no shading on meshes)."""
    from volren.renderers.registry import registry

    caps = registry.capabilities(name)
    return [v for v in VARIANTS[name] if caps.unsupported_reason(kind, 1, base.with_(shade=v.shade)) is None]


def _make(
    name: str, variant: Variant, volume: Volume, tf: TransferFunction1D, base: RenderSettings
) -> Renderer:
    from volren.renderers.registry import registry

    renderer = registry.create(name)
    try:
        renderer.set_volume(volume)
        renderer.set_transfer_function(tf)
        renderer.set_settings(base.with_(shade=variant.shade, options={**base.options, **variant.options}))
    except BaseException:
        renderer.release()
        raise
    return renderer


def _bound(name: str, a: Variant, b: Variant) -> float:
    """How much skipping may change a pixel of renderer `name` between two configurations (NaN: a
    different image)."""
    if "shading" in (a.kind, b.kind):
        return float("nan")
    alpha = TERMINATION_ALPHA.get(name, ALPHA)
    return (1.0 - alpha if a.terminates != b.terminates else 0.0) + ROUNDING


@dataclass
class Measured:
    """One configuration's frames: timed ms, uploads per timed frame, the scene-view image and counters."""

    times: list[float] = field(default_factory=list)
    uploads: dict[str, float] = field(default_factory=dict)
    image: NDArray[np.float32] | None = None
    counters: dict[str, float] = field(default_factory=dict)


Entry = tuple[Variant, Renderer, TransferFunction1D]


def measure(
    entries: Sequence[Entry], scene: Scene, size: int, frames: int, turn: float
) -> dict[str, Measured]:
    """Time the configurations interleaved: frame k of each in turn (the order rotated every frame),
    so load from elsewhere on the machine falls on all of them alike."""

    def edit(variant: Variant, tf: TransferFunction1D) -> None:
        if variant.tf_edit:  # an edit that keeps the values: only the version changes
            tf.set_opacity_points(tf.opacity_points)

    out = {variant.key: Measured() for variant, _, _ in entries}
    for _, renderer, _ in entries:
        renderer.render(scene.camera, size, size)
    for k in range(1, frames + 1):
        camera = (
            scene.camera.azimuth(turn * k).reset_clipping_range(scene.volume.bounds) if turn else scene.camera
        )
        for i in range(len(entries)):
            variant, renderer, tf = entries[(i + k) % len(entries)]
            got = out[variant.key]
            edit(variant, tf)
            start = time.perf_counter()
            renderer.render(camera, size, size)
            got.times.append((time.perf_counter() - start) * 1000.0)
            for name, count in renderer.last_frame.counters.items():
                if name.startswith("uploaded_"):
                    got.uploads[name] = got.uploads.get(name, 0.0) + count / frames
    for variant, renderer, tf in entries:
        edit(variant, tf)
        got = out[variant.key]
        got.image = renderer.render(scene.camera, size, size)
        got.counters = dict(renderer.last_frame.counters)
    return out


def run_scene(
    scene: Scene,
    renderers: Sequence[str],
    size: int,
    frames: int,
    turn: float,
    base: RenderSettings,
    report: Callable[[dict], None] | None = None,
) -> list[dict]:
    """Every variant of every renderer on one scene; rows as dicts with COLUMNS' keys."""
    rows = []
    for name in renderers:
        variants = variants_for(name, scene.volume.kind, base)
        with ExitStack() as stack:
            entries = []
            for variant in variants:
                tf = scene.tf.copy() if variant.tf_edit else scene.tf  # edits reach no other renderer
                entries.append(
                    (variant, stack.enter_context(_make(name, variant, scene.volume, tf, base)), tf)
                )
            measured = measure(entries, scene, size, frames, turn)
        refs = [v for v in variants if v.key in ("all_on", "all_off")]
        for variant in variants:
            got = measured[variant.key]
            row: dict[str, Any] = {
                "dataset": scene.dataset,
                "tf": scene.style,
                "renderer": name,
                "variant": variant.key,
                "label": variant.label,
                "kind": variant.kind,
                "size": size,
                "frames": frames,
                "turn_deg": turn,
                "ms": round(statistics.median(got.times), 3),
                "ms_min": round(min(got.times), 3),
                "ms_max": round(max(got.times), 3),
                "uploaded_tables_per_frame": got.uploads.get("uploaded_tables", ""),
                "uploaded_brick_mask_per_frame": got.uploads.get("uploaded_brick_mask", ""),
            }
            row.update({c: got.counters[c] for c in WORK_COUNTERS if c in got.counters})
            for ref in refs:
                err = image_error(got.image, measured[ref.key].image)
                row[f"max_abs_vs_{ref.key}"] = err.max_abs
                row[f"rmse_vs_{ref.key}"] = err.rmse
                row[f"bound_vs_{ref.key}"] = _bound(name, variant, ref)
            rows.append(row)
            if report is not None:
                report(row)
    return rows


def run(
    scenes: Iterable[Scene],
    renderers: Sequence[str],
    size: int = 512,
    frames: int = 5,
    turn: float = 1.0,
    base: RenderSettings | None = None,
    report: Callable[[dict], None] | None = None,
) -> list[dict]:
    base = base or RenderSettings()
    rows = []
    for scene in scenes:
        rows += run_scene(
            scene, renderers_for(scene.volume.kind, renderers), size, frames, turn, base, report
        )
    return rows


def row_count(kinds: Iterable[str], renderers: Sequence[str], base: RenderSettings) -> int:
    """Rows a run over scenes of these volume kinds prints (for the progress bar)."""
    return sum(len(variants_for(n, kind, base)) for kind in kinds for n in renderers_for(kind, renderers))


def intro(size: int, frames: int, turn: float, base: RenderSettings, command: str) -> str:
    """skip.md's first paragraph: how the numbers were taken."""
    import os

    import numba

    view = (
        f"while the camera turns {turn:g} degrees of azimuth per frame"
        if turn
        else "at the scene's fixed view"
    )
    return (
        f"`{command}`: {size}x{size} pixels, step {base.step:g}, pre-integration "
        f"{'on' if base.preintegration else 'off'}, slicer path march, {os.cpu_count()} CPU cores, numba "
        f"{numba.get_num_threads()} threads. ms is the median of {frames} frames after a warm-up frame, "
        f"{view}, one renderer's configurations drawn interleaved (frame k of each in turn, so that load "
        "from other processes falls on all alike); work counters and images are those of one more frame "
        "at the scene's view. Image "
        "differences are DESIGN.md's max abs / RMSE over premultiplied RGBA against the same renderer's "
        "all-on and all-off images; skipping must be exact, early termination within 1 - termination_alpha "
        f"= {1 - ALPHA:.0e} (shearwarp: {1 - TERMINATION_ALPHA['shearwarp']:.0e}; plus {ROUNDING:.0e} float "
        "rounding). shearwarp's run-length skipping is exact. tetra's transparent-cell skip is exact to "
        "the optical model but not to the image with those cells integrated: its 3D pre-integration table "
        "interpolates between value bins and so gives cells just beside an opacity spike a little opacity. "
        "vtk has no switch for its own skipping: its row is the peer's time."
    )


# ------------------------------------------------------------------------------------ output
def write_csv(rows: Sequence[dict], path: Path) -> None:
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS, restval="")
        writer.writeheader()
        writer.writerows(rows)


def _count(value: Any) -> str:
    if value == "" or value is None:
        return "-"
    value = float(value)
    for scale, unit in ((1e6, " M"), (1e3, " k")):
        if value >= scale:
            return f"{value / scale:.2f}{unit}"
    return f"{value:.0f}"


def work_text(row: dict) -> str:
    """The renderer's work counters in a few words."""
    parts = []
    names = {
        "samples": "samples",
        "brick_steps": "brick jumps",
        "rays_terminated": "rays stopped",
        "cell_steps": "cell steps",
        "cells_integrated": "integrated",
    }
    for key, name in names.items():
        if row.get(key, "") != "":
            parts.append(f"{name} {_count(row[key])}")
    for key, name in (("uploaded_tables_per_frame", "tables"), ("uploaded_brick_mask_per_frame", "masks")):
        if row.get(key, "") not in ("", 0, 0.0):
            parts.append(f"{name} {row[key]:g}/frame")
    return ", ".join(parts) or "-"


def _diff(row: dict, other: str) -> str:
    if row.get(f"max_abs_vs_{other}", "") == "":
        return "-"
    return f"{row[f'max_abs_vs_{other}']:.2e} / {row[f'rmse_vs_{other}']:.1e}"


HEADER = (
    "| dataset | TF | renderer | configuration | ms | work (at the scene's view) | vs all on: max / RMSE "
    "| vs all off: max / RMSE |\n|---|---|---|---|---|---|---|---|"
)


def markdown_row(row: dict) -> str:
    return (
        f"| {row['dataset']} | {row['tf']} | {row['renderer']} | {row['label']} | {row['ms']:.1f} | "
        f"{work_text(row)} | {_diff(row, 'all_on')} | {_diff(row, 'all_off')} |"
    )


def _saved(on: float, off: float) -> float:
    return 100.0 * (1.0 - on / off) if off > 0 else float("nan")


def _spread(values: list[float]) -> str:
    values = [v for v in values if v == v]
    if not values:
        return "-"
    median, low, high = (round(v) for v in (statistics.median(values), min(values), max(values)))
    return f"{median} ({low} to {high})"


SUMMARY_HEADER = (
    "| renderer | technique | counter | work saved %: median (range) | time saved %: median (range) "
    "| image change: worst max abs / RMSE | allowed | scenes |\n|---|---|---|---|---|---|---|---|"
)


def summary_rows(rows: Sequence[dict]) -> list[str]:
    """Per renderer and technique, over the scenes: what switching it on saves against having it
    off (work counter and time), and the largest image change it causes; then each renderer's
    all-on time against vtk's on the same scenes."""
    scenes: dict[tuple, dict[str, dict]] = {}
    for row in rows:
        scenes.setdefault((row["dataset"], row["tf"], row["renderer"]), {})[row["variant"]] = row
    out = []
    techniques = [(r, v, t, c) for (r, v), (t, c) in TECHNIQUES.items()]
    techniques += [(r, "shading", "lighting off", "") for r in RENDERERS]
    techniques += [(r, "tf_edit", "tables reused", "") for r in RENDERERS]
    for renderer, key, technique, counter in techniques:
        pairs = [(s["all_on"], s[key]) for (_, _, r), s in scenes.items() if r == renderer and key in s]
        if not pairs:
            continue
        work = [
            _saved(float(on[counter]), float(off[counter])) for on, off in pairs if on.get(counter, "") != ""
        ]
        times = [_saved(on["ms"], off["ms"]) for on, off in pairs]
        worst = max(pairs, key=lambda p: p[1]["max_abs_vs_all_on"])[1]
        bound = worst["bound_vs_all_on"]
        allowed = "different image" if bound != bound else f"{bound:.1e}"
        if bound == bound and worst["max_abs_vs_all_on"] > bound:
            allowed += " (exceeded)"
        out.append(
            f"| {renderer} | {technique} | {counter or '-'} | {_spread(work)} | {_spread(times)} | "
            f"{worst['max_abs_vs_all_on']:.2e} / {worst['rmse_vs_all_on']:.1e} | {allowed} | {len(pairs)} |"
        )
    for renderer in ("slicer", "tetra"):
        pairs = [
            (s["all_on"], scenes[d, t, "vtk"]["all_on"])
            for (d, t, r), s in scenes.items()
            if r == renderer and "all_on" in scenes.get((d, t, "vtk"), {})
        ]
        if pairs:
            times = [_saved(on["ms"], peer["ms"]) for on, peer in pairs]
            spread = _spread(times)
            out.append(
                f"| {renderer} | all on, against vtk's time | - | - | {spread} | - | - | {len(pairs)} |"
            )
    return out


def markdown(rows: Sequence[dict], intro: str) -> str:
    """skip.md: what was run, the summary, then every row."""
    return "\n".join(
        [
            intro,
            "",
            "Summary over the scenes (saved = 1 - all on / technique off; for lighting: 1 - unshaded / "
            "shaded; for tables: 1 - camera-only frame / frame after a TF edit; against vtk: 1 - all on / "
            "vtk; the image change is that row's against all on):",
            "",
            SUMMARY_HEADER,
            *summary_rows(rows),
            "",
            "Every row:",
            "",
            HEADER,
            *(markdown_row(r) for r in rows),
            "",
        ]
    )
