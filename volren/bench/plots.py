"""Time against error plots of `volren bench run`: one PNG per dataset, one panel per TF.

Log-log axes (both quantities span decades); every setting of a renderer is a faint marker and
its Pareto front a line through bold markers, so the reader sees at once which renderer gives the
least error for a time budget. Our renderers are drawn solid, VTK's mappers dashed, what a PyVista
or napari user gets (one setting each) dotted. Figures are
made with matplotlib's object API (no pyplot state), which renders with Agg and needs no display.
matplotlib is the `bench` extra and loads only when a plot is drawn (`require_matplotlib`).
"""

from __future__ import annotations

from pathlib import Path

from volren.bench.pareto import Row, group, pareto_front
from volren.bench.sweep import BUILTIN_CURVES
from volren.bench.viewer_peers import VIEWER_PEERS
from volren.extras import require

#: RMSE below this is drawn at it: a log axis has no zero (an exact match is possible on a sample).
RMSE_FLOOR = 1e-6
_ORDER = list(BUILTIN_CURVES)
_COLORS = dict(zip(_ORDER, ["C0", "C2", "C1", "C3", "C4", "C5", "C0", "C1", "C4", "C5"], strict=True))
_MARKERS = dict(zip(_ORDER, ["o", "^", "s", "D", "p", "d", "o", "s", "v", "P"], strict=True))
#: Colours and markers of other renderers (plugins), in the order they first appear.
_OTHER_STYLES = [("C6", "X"), ("C7", "*"), ("C8", "h"), ("C9", "<"), ("C5", ">")]


def require_matplotlib() -> None:
    """A one-line VolrenError naming the `bench` extra when matplotlib is missing."""
    require("bench", "volren bench run (its plots)")


def _order(curve: str) -> tuple[int, str]:
    return (_ORDER.index(curve), "") if curve in _ORDER else (len(_ORDER), curve)


def _style(curve: str, others: list[str]) -> tuple[str, str]:
    if curve in _COLORS:
        return _COLORS[curve], _MARKERS[curve]
    if curve not in others:
        others.append(curve)
    return _OTHER_STYLES[others.index(curve) % len(_OTHER_STYLES)]


def plot_dataset(rows: list[Row], dataset: str, path: Path) -> Path:
    """Write `path` (PNG): a panel per TF of `dataset`'s rows, ms against RMSE per renderer."""
    require_matplotlib()
    from matplotlib.figure import Figure
    from matplotlib.ticker import FuncFormatter, NullFormatter

    scenes = group((r for r in rows if r["dataset"] == dataset), lambda r: r["tf"])
    figure = Figure(figsize=(4.6 * len(scenes) + 1.6, 4.2), layout="constrained")
    axes = figure.subplots(1, len(scenes), squeeze=False)[0]
    legend: dict[str, object] = {}  # one legend for all panels, outside them: it never hides a point
    others: list[str] = []
    for ax, (tf, scene) in zip(axes, scenes.items(), strict=True):
        curves = group(sorted(scene, key=lambda r: _order(str(r["renderer"]))), lambda r: r["renderer"])
        for curve, points in curves.items():
            color, marker = _style(str(curve), others)
            style = "--" if str(curve).startswith("vtk-") else ":" if curve in VIEWER_PEERS else "-"
            ax.scatter(
                [p["ms"] for p in points],
                [max(p["rmse"], RMSE_FLOOR) for p in points],
                s=18,
                color=color,
                marker=marker,
                alpha=0.3,
                linewidths=0,
            )
            front = pareto_front(points)
            (legend[str(curve)],) = ax.plot(
                [p["ms"] for p in front],
                [max(p["rmse"], RMSE_FLOOR) for p in front],
                style,
                color=color,
                marker=marker,
                markersize=6,
                linewidth=1.8,
            )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))  # 10, 100, not 10^1
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("ms per frame (median, camera turning)")
        ax.set_ylabel("RMSE against reference")
        ax.set_title(f"{dataset}, {tf}")
        ax.grid(True, which="both", alpha=0.25)
    names = sorted(legend, key=_order)
    figure.legend(
        [legend[c] for c in names],
        names,
        loc="outside right upper",
        fontsize="small",
        title="renderer\n(dots: settings,\nline: Pareto front)",
        title_fontsize="small",
    )
    figure.savefig(path, dpi=100)
    return path


def plot_all(rows: list[Row], folder: Path) -> list[Path]:
    """One `<dataset>.png` per dataset in `folder`."""
    return [plot_dataset(rows, str(d), folder / f"{d}.png") for d in group(rows, lambda r: r["dataset"])]
