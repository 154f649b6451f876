"""summary.md of `volren bench run`: per dataset, how our best renderer's time compares with VTK's
best at equal error, with the time/error plots beside the tables.

Per scene (dataset and TF), VTK's mappers are pooled and their Pareto front taken; for each point
on it, the fastest of our settings (`slicer`, `tetra`) with equal or lower RMSE is found. The time
ratio (ours over VTK's, below 1: ours is faster) is stated at VTK's most accurate setting, which is
the comparison that matters for quality, and as a range over the whole front. What a PyVista or
a napari user gets (the viewer peers, `volren.bench.viewer_peers`) is compared the same way, each
at its one setting, in a table of its own: pooling it with VTK's settings would change what "VTK's
best" means.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import cast

from volren.bench.pareto import Match, Row, equal_error, group, pareto_front
from volren.bench.viewer_peers import VIEWER_PEERS

#: How a refused configuration's reason starts (`run_bench.Progress.refused`): listed apart from
#: the skipped ones, as a renderer declining a scene it does not draw is no failure.
REFUSED = "refused: "


@dataclass(frozen=True)
class RunInfo:
    """How the rows were measured, for the summary's first paragraph."""

    size: int
    frames: int
    turn: float
    seconds: float
    skipped: Sequence[str] = field(default_factory=tuple)


@dataclass(frozen=True)
class SceneComparison:
    dataset: str
    tf: str
    front: list[Match]  # VTK's Pareto front, fastest first, each with our fastest match
    viewers: list[Match] = field(default_factory=list)  # each viewer peer's row with our fastest match

    @property
    def at_best(self) -> Match | None:
        """The match at VTK's most accurate setting (the front's last point)."""
        return self.front[-1] if self.front else None

    @property
    def ratios(self) -> list[float]:
        return [m.ratio for m in self.front if m.ratio is not None]


def is_vtk(row: Row) -> bool:
    return str(row["renderer"]).startswith("vtk-")


def is_viewer(row: Row) -> bool:
    return str(row["renderer"]) in VIEWER_PEERS


def compare(rows: Iterable[Row]) -> list[SceneComparison]:
    """One comparison per scene, in the order the rows came."""
    out = []
    for key, scene in group(rows, lambda r: (r["dataset"], r["tf"])).items():
        dataset, tf = cast(tuple[str, str], key)  # the pair made just above
        ours = [r for r in scene if not (is_vtk(r) or is_viewer(r))]
        front = pareto_front(r for r in scene if is_vtk(r))
        viewers = equal_error((r for r in scene if is_viewer(r)), ours)
        out.append(SceneComparison(str(dataset), str(tf), equal_error(front, ours), viewers))
    return out


def _ratio(value: float | None) -> str:
    if value is None:
        return "-"
    return f"{value:.2f} ({1 / value:.1f}x faster)" if value < 1 else f"{value:.2f} ({value:.1f}x slower)"


def _range(values: list[float], total: int) -> str:
    if not values:
        return f"none of {total} reached"
    return f"{min(values):.2f}-{max(values):.2f} ({len(values)} of {total} reached)"


def _setting(row: Row | None) -> str:
    return "none reaches it" if row is None else f"{row['renderer']} {row['settings']}"


def _cells(row: Row | None) -> str:
    return "- | -" if row is None else f"{row['ms']:.1f} | {row['rmse']:.5f}"


TABLE_HEAD = (
    "| TF | VTK's most accurate | ms | RMSE | our fastest at equal or lower RMSE | ms | RMSE | time ratio | "
    "ratio over VTK's Pareto front |\n|---|---|---|---|---|---|---|---|---|"
)


VIEWER_HEAD = (
    "| TF | viewer (its defaults) | ms | RMSE | our fastest at equal or lower RMSE | ms | RMSE | time ratio |\n"
    "|---|---|---|---|---|---|---|---|"
)


def viewer_table(scenes: list[SceneComparison]) -> list[str]:
    """What a PyVista or napari user gets against our fastest setting at that error (none: no rows)."""
    lines = [
        f"| {s.tf} | {_setting(m.peer)} | {_cells(m.peer)} | {_setting(m.ours)} | {_cells(m.ours)} | "
        f"{_ratio(m.ratio)} |"
        for s in scenes
        for m in s.viewers
    ]
    return ["What a PyVista or napari user gets:", "", VIEWER_HEAD, *lines, ""] if lines else []


def dataset_section(dataset: str, kind: str, scenes: list[SceneComparison]) -> list[str]:
    lines = [f"## {dataset} ({kind})", "", f"![{dataset}: time against error]({dataset}.png)", "", TABLE_HEAD]
    for s in scenes:
        m = s.at_best
        if m is None:
            lines.append(f"| {s.tf} | no VTK rows | - | - | - | - | - | - | - |")
            continue
        lines.append(
            f"| {s.tf} | {_setting(m.peer)} | {_cells(m.peer)} | {_setting(m.ours)} | {_cells(m.ours)} | "
            f"{_ratio(m.ratio)} | {_range(s.ratios, len(s.front))} |"
        )
    ratios = {s.tf: s.at_best.ratio for s in scenes if s.at_best is not None}
    best = [r for r in ratios.values() if r is not None]
    if best:
        per_tf = ", ".join(f"{tf} {'-' if r is None else f'{r:.2f}'}" for tf, r in ratios.items())
        span = f"{min(best):.2f}" if len(best) == 1 else f"{min(best):.2f}-{max(best):.2f}"
        missing = "; -: none of ours reaches VTK's best error" if len(best) < len(ratios) else ""
        lines += [
            "",
            f"At VTK's best error our best renderer takes {span} of VTK's time ({per_tf}; below 1: ours is "
            f"faster{missing}).",
        ]
    elif ratios:
        lines += ["", "None of our settings reaches the error of VTK's most accurate setting here."]
    else:
        lines += ["", "No VTK rows here (VTK was not run, or does not draw such a scene: see Refused)."]
    return lines + [""] + viewer_table(scenes)


def markdown(rows: list[Row], info: RunInfo) -> str:
    """The whole summary: how it was measured, one line per scene, then a section per dataset."""
    scenes = compare(rows)
    kinds = {r["dataset"]: r["kind"] for r in rows}
    lines = [
        "# Run time against error (`volren bench run`)",
        "",
        f"{len(rows)} runs at {info.size}x{info.size} in {info.seconds / 60:.1f} min. Time: median of "
        f"{info.frames} frames after a warm-up frame, the camera turning {info.turn:g} degrees of azimuth per "
        "frame around the scene's view (VTK's ZSweep: one cold frame). Error: RMSE over the premultiplied RGBA "
        "pixels against `reference` at the scene's view. Time ratio: the fastest of our renderers (slicer, "
        "tetra) whose RMSE is at most that of a VTK setting, over that setting's time (below 1: ours is "
        "faster), at VTK's most accurate setting and over VTK's Pareto front (all of VTK's mappers pooled); "
        "what a PyVista or napari user gets (`pyvista`, `vispy`: the tools' defaults) in a table of its own per "
        "dataset. Every run is in runs.csv.",
        "",
        "| dataset | TF | time ratio at VTK's best error | over VTK's Pareto front |",
        "|---|---|---|---|",
    ]
    for s in scenes:
        best = s.at_best.ratio if s.at_best is not None else None
        lines.append(f"| {s.dataset} | {s.tf} | {_ratio(best)} | {_range(s.ratios, len(s.front))} |")
    lines.append("")
    for dataset, group_scenes in group(scenes, lambda s: s.dataset).items():
        lines += dataset_section(str(dataset), str(kinds[dataset]), group_scenes)
    refused = [s for s in info.skipped if f": {REFUSED}" in s]
    failed = [s for s in info.skipped if s not in refused]
    if failed:
        lines += ["## Skipped", "", *(f"- {s}" for s in failed), ""]
    if refused:
        lines += ["## Refused", "", "Renderers that do not draw such a scene (their capabilities); not failures.", "",
                  *(f"- {s.replace(REFUSED, '', 1)}" for s in refused), ""]  # fmt: skip
    return "\n".join(lines)
