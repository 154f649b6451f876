"""`python -m benchmarks.quality_levels RUNS.csv ...`: each renderer's quality levels
(`volren.quality`) from `bench run` results, written into the renderer's own package.

Each row of runs.csv is one configuration of one curve (`volren.bench.sweep`) on one scene
(dataset and TF) with its median frame time and RMSE. Per volume kind, a configuration counts
for a level when its RMSE is within the level's bound of VTK's default's RMSE on every scene both
were measured on; the level's choice is the fastest such configuration (total time over those
scenes); a renderer with no configuration within a bound has it scaled by its own default
configuration's error (its `meets` flag false), and `exact` is the most accurate configuration.
The curves of one registered renderer (VTK's mappers are the `vtk` renderer's) compete for that
renderer's levels. Later files win where two give the same configuration and scene. The same
choice is also made over the scenes of each TF class ("uniform/smooth", ...), given by the scenes'
own TFs and volumes (`scene_features`, `volren.model.tf_class`). A scene is a dataset and TF at
one image size: rows at other sizes than `MAIN_SIZE` are scenes of their own ("dataset/tf@128"), so
a level holds at every size measured. Each choice keeps VTK's default's frame time on each of its
scenes from the same run (every scene comes from one runs.csv), which `auto` ranks by.

Each renderer's levels go to `quality_levels.json` in the package its entry point names
(`registry.package_folder`: volren's built-ins beside their renderer, a plugin in its own
package, whose pyproject must ship it as package data), or under `--out FOLDER/NAME/`.

Two rules hold at `default` and above (`FAITHFUL_LEVELS`), whatever the runs measured:
- every pixel is sampled: no configuration that interpolates pixels between rays (an option
  `image_stride` above 1) is eligible, since a feature thinner than the stride between rays that
  agree is dropped, and a run's scenes cannot show that it never happens;
- fidelity: where the rows count the pixels off by more than 0.1 (`volren.testing.metrics`), a
  configuration is eligible only where it has no more such pixels than VTK's default on every
  scene, since RMSE averages a missing thin feature away.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
from collections import defaultdict
from collections.abc import Iterable, Mapping
from pathlib import Path

from benchmarks._cli import run
from benchmarks.quality_report import scene_pair
from volren.bench import sweep
from volren.bench.viewer_peers import VIEWER_PEERS
from volren.errors import VolrenError
from volren.model.scene_class import SceneClass
from volren.model.tf_class import TFClass, tf_sharpness, tf_visible_fraction
from volren.quality import LEVELS, LEVELS_FILE, Measurement, QualityTable
from volren.renderers.base import QualityLevel

#: Each level's bound on RMSE / VTK default's RMSE (None: the most accurate configuration).
BOUNDS: dict[str, float | None] = {
    "draft": 4.0,
    "interactive": 2.0,
    "default": 1.0,
    "high": 0.25,
    "exact": None,
}
#: The fraction of its bound a level is chosen within: `default` promises at most VTK's error and
#: is chosen at 0.9 of it, a margin for scenes no run measured.
MARGINS: dict[str, float] = {"default": 0.9}
#: The levels that must sample every pixel and keep VTK default's count of pixels off by more than 0.1.
FAITHFUL_LEVELS = ("default", "high", "exact")
#: The image size of the runs' main scenes, named without a size.
MAIN_SIZE = 512
#: VTK's default configuration per kind (curve, settings label), the reference for the bounds.
VTK_DEFAULT = {"uniform": ("vtk-smart", "default"), "tet": ("vtk-raycast", "linear")}
#: The built-in curves' configurations at each renderer's default settings.
OWN_DEFAULTS = {("slicer", "step 0.5, post"), ("tetra", "table 256x32"), *VTK_DEFAULT.values()}


def read_rows(paths: list[Path]) -> list[dict]:
    """The rows of every file, a later file's row replacing an earlier one for the same configuration and scene."""
    rows: dict[tuple, dict] = {}
    for path in paths:
        try:
            with path.open(newline="", encoding="utf-8") as f:
                for row in csv.DictReader(f):
                    rows[scene_of(row), row["renderer"], row["settings"]] = row
        except OSError as exc:
            raise VolrenError(f"{path}: cannot read: {exc.strerror or exc}") from None
        except (KeyError, csv.Error) as exc:
            raise VolrenError(f"{path}: not a `volren bench run` runs.csv ({exc})") from None
    return list(rows.values())


def scene_of(row: Mapping[str, str]) -> str:
    """A row's scene: "dataset/tf", with "@size" where the size is not `MAIN_SIZE`."""
    size = row.get("size") or str(MAIN_SIZE)
    return f"{row['dataset']}/{row['tf']}" + ("" if size == str(MAIN_SIZE) else f"@{size}")


def _configs(kind: str, curves: set[str]) -> dict[tuple[str, str], sweep.Config]:
    """(curve, label) -> Config of every configuration the sweeps define for these curves now; not
    the viewer peers' (PyVista, napari), which are no renderer of ours to choose levels for."""
    builtin = [c for c in curves if c in sweep.BUILTIN_CURVES and c not in VIEWER_PEERS]
    out = {(c.curve, c.label): c for c in sweep.configs(kind, curves=builtin)} if builtin else {}
    from volren.renderers.registry import registry

    for name in curves - set(sweep.BUILTIN_CURVES):
        if name in registry.names():
            out.update({(c.curve, c.label): c for c in sweep.quality_axis(name, kind)})
    return out


def derive(
    rows: list[dict], source: str, classes: Mapping[tuple[str, str], TFClass] | None = None
) -> QualityTable:
    """The quality table of these rows (see the module docstring): per volume kind over all its
    scenes, and per TF class (`volren.model.tf_class`) over the scenes `classes` gives that class
    ((dataset, tf) -> class)."""
    levels: dict[SceneClass, dict[str, dict[str, Measurement]]] = {}
    peer_ms = vtk_default_ms(rows)
    for kind in VTK_DEFAULT:
        kind_rows = [r for r in rows if r.get("kind") == kind and _number(r.get("rmse")) is not None]
        peer = {
            scene_of(r): (float(r["rmse"]), _number(r.get("off"))) for r in kind_rows if _is_vtk_default(r)
        }
        if not peer:
            continue
        known = _configs(kind, {r["renderer"] for r in kind_rows})
        found = _levels(kind_rows, peer, peer_ms, known)
        if found:
            levels[SceneClass(kind)] = found
        for cls in TFClass:
            scenes = {scene for scene in peer if (classes or {}).get(scene_pair(scene)) == cls}
            found = (
                _levels(kind_rows, {s: e for s, e in peer.items() if s in scenes}, peer_ms, known)
                if scenes
                else {}
            )
            if found:
                levels[SceneClass(kind, cls)] = found
    return QualityTable(levels, dict.fromkeys({n for per in levels.values() for n in per}, source))


def vtk_default_ms(rows: list[dict]) -> dict[str, float]:
    """Scene ("dataset/tf", `scene_of`) -> VTK's default configuration's frame time (`VTK_DEFAULT`, per volume kind): the
    peer of `auto`'s speed ratios. Not the `vtk` renderer's `default` level, which may be a faster
    VTK configuration within the same error."""
    return {scene_of(r): ms for r in rows if _is_vtk_default(r) and (ms := _number(r.get("ms"))) is not None}


def _is_vtk_default(row: Mapping[str, str]) -> bool:
    """Whether a runs.csv row is VTK's default configuration for its volume kind (`VTK_DEFAULT`)."""
    return VTK_DEFAULT.get(row.get("kind", "")) == (row["renderer"], row["settings"])


def _levels(kind_rows: list[dict], peer: Mapping[str, tuple[float, float | None]], peer_ms: Mapping[str, float],
            known: Mapping[tuple[str, str], sweep.Config]) -> dict[str, dict[str, Measurement]]:  # fmt: skip
    """renderer -> level -> measurement over the scenes of `peer` (scene -> VTK default's RMSE and
    count of pixels off, None where not counted; `peer_ms`: its frame time)."""
    # renderer -> (curve, label) -> scene -> (ms, rmse / peer's, whether no more pixels off than the peer)
    measured: dict[str, dict[tuple[str, str], dict[str, tuple[float, float, bool]]]] = defaultdict(
        lambda: defaultdict(dict))  # fmt: skip
    for r in kind_rows:
        config = known.get((r["renderer"], r["settings"]))
        scene = scene_of(r)
        ms = _number(r.get("ms"))
        if config is None or scene not in peer or ms is None or peer[scene][0] <= 0:
            continue
        peer_rmse, peer_off = peer[scene]
        off = _number(r.get("off"))
        faithful = peer_off is None or off is None or off <= peer_off
        measured[config.renderer][config.curve, config.label][scene] = (
            ms, float(r["rmse"]) / peer_rmse, faithful)  # fmt: skip
    out: dict[str, dict[str, Measurement]] = {}
    for renderer, configs in measured.items():
        scenes, complete = _covered(configs)
        if not complete:
            continue
        per_level = {}
        own = _own_default(complete)
        faithful = {key: per for key, per in complete.items() if _samples_every_pixel(known[key])}
        chosen = {"default": _choose(faithful or complete, scenes, BOUNDS["default"], own, fidelity=True,
                                     margin=MARGINS["default"])}  # fmt: skip
        ceiling = sum(complete[chosen["default"]][s][0] for s in scenes)
        for level in LEVELS:
            if level not in chosen:
                below = LEVELS.index(level) < LEVELS.index("default")
                pool = complete if below else (faithful or complete)
                chosen[level] = _choose(pool, scenes, BOUNDS[level], own, ceiling if below else math.inf,
                                        fidelity=not below, margin=MARGINS.get(level, 1.0))  # fmt: skip
        for level in LEVELS:
            key = chosen[level]
            config = known[key]
            per = complete[key]
            settings = config.settings()
            per_level[level] = Measurement(
                QualityLevel(f"{key[0]}: {key[1]}" if key[0] != renderer else key[1], settings.step,
                             settings.preintegration, dict(settings.options)),
                ms={s: per[s][0] for s in sorted(scenes)}, peer_ms={s: peer_ms[s] for s in sorted(scenes)},
                worst_error_ratio=max(per[s][1] for s in scenes),
                meets=(BOUNDS[level] is None or max(per[s][1] for s in scenes) <= BOUNDS[level])
                and (level not in FAITHFUL_LEVELS or all(per[s][2] for s in scenes)),
            )  # fmt: skip
        out[renderer] = per_level
    return out


def scene_features(
    scenes: Iterable[tuple[str, str]], shared: Path | None
) -> dict[tuple[str, str], tuple[float, float]]:
    """(dataset, tf) -> (`tf_sharpness`, `tf_visible_fraction`) of each scene `bench run` knows (the
    shared datasets when `shared` is given, and the bundled samples), from its TF and its volume's
    value range."""
    from volren.bench.datasets import hard_datasets, sample_datasets, shared_datasets

    datasets = {
        **(shared_datasets(shared) if shared is not None else {}),
        **sample_datasets(),
        **hard_datasets(),
    }
    out: dict[tuple[str, str], tuple[float, float]] = {}
    wanted = sorted(set(scenes))
    for name in sorted({d for d, _ in wanted}):
        dataset = datasets.get(name)
        if dataset is None:
            continue
        value_range = dataset.load().value_range
        for style, tf in dataset.transfer_functions():
            if (name, style) not in wanted:
                continue
            sharpness, visible = tf_sharpness(tf, value_range), tf_visible_fraction(tf, value_range)
            if sharpness is not None and visible is not None:
                out[name, style] = (sharpness, visible)
    return out


def _covered(configs: Mapping[tuple[str, str], Mapping[str, tuple]]) -> tuple[set[str], dict]:
    """(scenes, the configurations measured on all of them): every scene any configuration was
    measured on, so that a scene set added by a later run (the hard scenes, another size) binds
    every level; a configuration missing from some scene (a level added since a run) is left out.
    Where no configuration covers them all, the scenes every configuration shares."""
    scenes = set.union(*(set(per) for per in configs.values()))
    complete = {key: per for key, per in configs.items() if set(per) >= scenes}
    if not complete:
        scenes = set.intersection(*(set(per) for per in configs.values()))
        complete = {key: per for key, per in configs.items() if scenes}
    return scenes, complete


def _samples_every_pixel(config: sweep.Config) -> bool:
    """Whether a configuration casts a ray through every pixel (no image-space refinement)."""
    return int(config.settings().options.get("image_stride", 1)) <= 1


def _choose(configs: dict, scenes: set[str], bound: float | None, own: tuple[str, str] | None,
            ceiling_ms: float = math.inf, fidelity: bool = False, margin: float = 1.0) -> tuple[str, str]:  # fmt: skip
    """The fastest configuration within `margin` times `bound` on every scene (and, for the levels below
    `default`, no slower than the default level's choice, `ceiling_ms`; with `fidelity`, with no
    more pixels off than VTK's default on every scene where counted). A renderer with none gets
    the bound scaled by its own default configuration's error (`own`): its default stays its
    default and its drafts stay faster, instead of its slowest setting being the only one within.
    The most accurate configuration where nothing is within, and for no bound (`exact`)."""

    def total_ms(key) -> float:
        return sum(configs[key][s][0] for s in scenes)

    def worst(key) -> float:
        return max(configs[key][s][1] for s in scenes)

    def faithful(key) -> bool:
        return not fidelity or all(configs[key][s][2] for s in scenes)

    best = min(configs, key=lambda key: (not faithful(key), worst(key), total_ms(key)))
    if bound is None:
        return best
    within = [key for key in configs
              if worst(key) <= bound * margin and total_ms(key) <= ceiling_ms and faithful(key)]  # fmt: skip
    if not within and own in configs:
        within = [key for key in configs
                  if worst(key) <= bound * worst(own) and total_ms(key) <= ceiling_ms and faithful(key)]  # fmt: skip
    return min(within, key=total_ms) if within else best


def _own_default(keys) -> tuple[str, str] | None:
    """The configuration a renderer draws with no settings: its quality axis's '(default)' level,
    or the built-in sweeps' point at the default settings."""
    for key in keys:
        if "(default)" in key[1] or key in OWN_DEFAULTS:
            return key
    return None


def _number(text: str | None) -> float | None:
    try:
        value = float(text) if text not in (None, "") else None
    except ValueError:
        return None
    return value if value is not None and math.isfinite(value) else None


def write_levels(quality: QualityTable, out: Path | None) -> list[Path]:
    """Each renderer's levels into its own package (`registry.package_folder`), or `out`/NAME/; the
    paths written."""
    from volren.renderers.registry import registry

    written = []
    for name in sorted(quality.sources):
        folder = out / name if out is not None else registry.package_folder(name)
        if folder is None:
            raise VolrenError(f"renderer {name!r} has no package to hold its {LEVELS_FILE} (pass --out)")
        path = folder / LEVELS_FILE
        try:
            folder.mkdir(parents=True, exist_ok=True)
            path.write_text(json.dumps(quality.renderer_json(name), indent=1) + "\n", encoding="utf-8")
        except OSError as exc:
            raise VolrenError(f"{path}: cannot write: {exc.strerror or exc}") from None
        written.append(path)
    return written


def run_quality(args: argparse.Namespace) -> int:
    from benchmarks.quality_report import auto_scenes, by_class, classed, markdown, summary_line
    from volren.bench.datasets import shared_folder
    from volren.renderers.registry import registry

    paths = [Path(p) for p in args.runs]
    source = "python -m benchmarks.quality_levels " + " ".join(str(p) for p in paths)
    rows = read_rows(paths)
    features = scene_features(
        {(r["dataset"], r["tf"]) for r in rows}, shared_folder(args.shared, required=False)
    )
    classes = {scene: TFClass.of_features(*value) for scene, value in features.items()}
    for (dataset, tf), (sharpness, visible) in sorted(features.items()):
        print(f"TF class of {dataset}/{tf}: {classes[dataset, tf].value} (sharpness {sharpness:.3g}, "
              f"visible on {visible:.2g} of the range)")  # fmt: skip
    quality = derive(rows, source, classes)
    if not quality.levels:
        raise VolrenError(
            f"{', '.join(args.runs)}: no scene has VTK's default measured, which the levels are defined against"
        )
    written = write_levels(quality, Path(args.out) if args.out else None)
    for kind, renderers in quality.levels.items():
        for name, per in renderers.items():
            print(f"{str(kind):8s} {name:12s} " + " | ".join(f"{level}: {per[level].level.label} "
                  f"(x{per[level].worst_error_ratio:.2g} VTK's error, {per[level].time_ratio(per[level].ms):.2g}x "
                  "VTK's time)" for level in LEVELS))  # fmt: skip
    print("wrote " + ", ".join(str(p) for p in written))
    scenes = auto_scenes(quality, registry.names(), vtk_default_ms(rows))
    groups: dict[tuple[SceneClass, str, str], list] = {}
    for s in scenes:
        groups.setdefault((s.kind, s.level, f"{s.renderer} ({s.label})"), []).append(s)
    for (kind, level, choice), group in groups.items():
        print(f"auto at {level} on {kind}: {choice}, {summary_line(group)} VTK's default's RMSE")
    for kind in sorted({s.kind.kind for s in by_class(scenes)}):
        for level in LEVELS:
            print(
                f"auto at {level} on {kind} by TF class: {summary_line(classed(scenes, kind, level))} VTK's default's RMSE"
            )
    if args.markdown:
        command = (
            source + (f" --shared {args.shared}" if args.shared else "") + f" --markdown {args.markdown}"
        )
        text = markdown(scenes, {k: c.value for k, c in classes.items()}, features, command)
        try:
            Path(args.markdown).write_text(text, encoding="utf-8")
        except OSError as exc:
            raise VolrenError(f"{args.markdown}: cannot write: {exc.strerror or exc}") from None
        print(f"wrote {args.markdown}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.quality_levels", description=__doc__.splitlines()[0]
    )
    parser.add_argument(
        "runs", nargs="+", help="runs.csv files of `volren bench run` (a later file wins on overlaps)"
    )
    parser.add_argument(
        "--out",
        help="a folder to write NAME/quality_levels.json into per renderer (default: each "
        "renderer's own package, the files volren uses)",
    )
    parser.add_argument(
        "--shared",
        help="the folder with data/ and scenes/, whose scenes' TFs give the TF classes "
        "(default: $VOLREN_SHARED; without it only the bundled samples are classed)",
    )
    parser.add_argument(
        "--markdown",
        help="also write `auto` against VTK's default per level and scene there "
        "(BENCHMARKS.md's fragment docs/bench/quality.md)",
    )
    return run(run_quality, parser, argv)


if __name__ == "__main__":
    raise SystemExit(main())
