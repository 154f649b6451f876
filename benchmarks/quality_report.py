"""What `--renderer auto` gives at each quality level against VTK's default, scene by scene.

Why: issue-style goals ("with no options, at least as accurate as VTK's default and N times faster
on every shared scene") are about what a user gets, which is `auto`'s choice at the level asked
for; the table (`volren.quality`) holds each choice's measured frame times per scene and its worst
RMSE against VTK's default's, so the comparison needs no new runs. `python -m benchmarks.quality_levels`
prints it and, with `--markdown`, writes it as the BENCHMARKS.md fragment `quality.md`.
"""

from __future__ import annotations

import statistics
from collections.abc import Mapping
from dataclasses import dataclass

from volren.model.scene_class import SceneClass
from volren.model.settings import RenderSettings
from volren.quality import LEVELS, QualityTable, choose_renderer


def scene_pair(scene: str) -> tuple[str, str]:
    """(dataset, tf) of a scene, whatever its size."""
    dataset, tf = scene.split("@", 1)[0].split("/", 1)
    return dataset, tf


@dataclass(frozen=True)
class AutoScene:
    """`auto`'s choice on one scene at one level, against VTK's default there."""

    kind: SceneClass  #: the scene class the choice was made for (the volume kind alone, or with a TF class)
    level: str
    scene: str  #: "dataset/tf"
    renderer: str
    label: str  #: the chosen configuration
    ms: float
    vtk_ms: float
    worst_error_ratio: float  #: the choice's largest RMSE / VTK default's RMSE over its scenes

    @property
    def speed(self) -> float:
        """VTK default's frame time over the choice's (above 1: faster than VTK)."""
        return self.vtk_ms / self.ms


def auto_scenes(quality: QualityTable, registered: list[str], vtk_ms: Mapping[str, float]) -> list[AutoScene]:
    """`auto`'s choice on every scene with VTK's default's frame time in `vtk_ms` ("dataset/tf" ->
    ms, `benchmarks.quality_levels.vtk_default_ms`), per scene class and level."""
    out = []
    for kind in quality.levels:
        for level in LEVELS:
            name, _ = choose_renderer(kind, level, 1, RenderSettings(), registered, quality)
            choice = quality.measurement(name, kind, level)
            assert choice is not None
            out += [AutoScene(kind, level, scene, name, choice.level.label, choice.ms[scene], vtk_ms[scene],
                              choice.worst_error_ratio) for scene in sorted(set(choice.ms) & set(vtk_ms))]  # fmt: skip
    return out


def by_class(scenes: list[AutoScene]) -> list[AutoScene]:
    """The rows of the TF-class kinds ("uniform/smooth", ...): what `auto` does, each scene under its class."""
    return [s for s in scenes if s.kind.tf is not None]


def classed(scenes: list[AutoScene], kind: str, level: str) -> list[AutoScene]:
    """The `by_class` rows of one volume kind ("uniform") at one level: every scene under its TF's class."""
    return [s for s in by_class(scenes) if s.kind.kind == kind and s.level == level]


def summary_line(rows: list[AutoScene]) -> str:
    """'1.4-11.3x (median 2.9x) over 5 scenes, RMSE up to 0.73x'."""
    speeds = sorted(r.speed for r in rows)
    worst = max(r.worst_error_ratio for r in rows)
    scenes = f"{len(speeds)} scene" + ("s" if len(speeds) != 1 else "")
    return f"{speeds[0]:.1f}-{speeds[-1]:.1f}x (median {statistics.median(speeds):.1f}x) over {scenes}, RMSE up to {worst:.2g}x"


def markdown(scenes: list[AutoScene], classes: Mapping[tuple[str, str], str],
             features: Mapping[tuple[str, str], tuple[float, float]], command: str) -> str:  # fmt: skip
    """The BENCHMARKS.md fragment: per volume kind and level, `auto` by TF class and with one
    choice for all scenes; then every scene at `default`."""
    lines = [
        f"From `{command}`. Each ratio is VTK's default's frame time over `auto`'s at the level (512x512, warm frames "
        "with the camera turning, both from the same `bench run`); *RMSE up to*: the chosen configuration's largest "
        "RMSE over its scenes, as a multiple of VTK's default's on the same scene. *By TF class*: each scene drawn with "
        "the choice for its TF's class (what `auto` does); *one choice*: the kind's single choice for every scene.",
        "",
        "| volumes | level | by TF class | one choice |",
        "|---|---|---|---|",
    ]
    for kind in sorted({s.kind.kind for s in scenes}):
        for level in LEVELS:
            rows = classed(scenes, kind, level)
            whole = [s for s in scenes if s.kind == SceneClass(kind) and s.level == level]
            lines.append(f"| {kind} | {level} | {summary_line(rows) if rows else '-'} | "
                         f"{summary_line(whole) if whole else '-'} |")  # fmt: skip
    lines += ["", "At `default` (what a render with no options gets), scene by scene:", "",
              "| scene | TF class (sharpness, visible fraction) | auto's choice | ms | VTK's default ms | faster than VTK |",
              "|---|---|---|---:|---:|---:|"]  # fmt: skip
    for s in sorted(by_class(scenes), key=lambda s: (s.kind.kind, s.scene)):
        if s.level != "default":
            continue
        key = scene_pair(s.scene)
        cls = classes.get(key, "-")
        feature = features.get(key)
        shown = f" ({feature[0]:.3g}, {feature[1]:.2g})" if feature is not None else ""
        lines.append(f"| {s.scene} | {cls}{shown} | {s.renderer}: {s.label} | "
                     f"{s.ms:.0f} | {s.vtk_ms:.0f} | {s.speed:.1f}x |")  # fmt: skip
    return "\n".join(lines) + "\n"
