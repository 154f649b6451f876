"""The quality settings `volren bench run` sweeps, per renderer and volume kind.

A configuration is one point of a renderer's time/error curve. Each renderer sweeps the knob that
trades time for error most directly (the step for `slicer` and VTK's stepped mappers, the table
size for `tetra`, whose rays step cell to cell) and, at one middle setting, turns the other knobs
one at a time (pre-integration, table size, jitter, skipping, `tetra`'s adaptive image refinement),
so that the sweep stays linear in the number of knobs instead of their product. VTK's mappers are
peers: each one is a curve. So is what a PyVista or a napari user gets (`pyvista`, `vispy`:
`volren.bench.viewer_peers`), on grids, at the tool's defaults: one configuration each.

`curve` names the renderer as plotted and compared: `slicer`, `tetra` (ours), `vtk-<mapper>` or
a viewer peer.
Any other registered renderer (a plugin) is swept along the quality axis it declares in its
capabilities (`Capabilities.quality`, fast to accurate; its defaults when it declares none), as the
curve of its own name.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

from volren.bench.viewer_peers import VIEWER_PEERS
from volren.errors import VolrenError
from volren.model.settings import RenderSettings
from volren.renderers.base import QualityLevel

#: Every curve a sweep can hold, by volume kind, in plotting order.
CURVES: dict[str, tuple[str, ...]] = {
    "uniform": ("slicer", "vtk-smart", "vtk-gpu", "vtk-fixed_point", *VIEWER_PEERS),
    "tet": ("tetra", "vtk-raycast", "vtk-projected", "vtk-zsweep"),
}
#: Every built-in curve, in plotting order; any other name is a registered renderer's own axis.
BUILTIN_CURVES: tuple[str, ...] = tuple(c for kind in CURVES.values() for c in kind)
#: Curves that time one cold frame only: VTK's ZSweep takes 30-80 s per 512x512 frame.
ONE_FRAME_CURVES = frozenset({"vtk-zsweep"})

FULL_STEPS = (2.0, 1.0, 0.5, 0.25)
QUICK_STEPS = (2.0, 0.5)
#: The step at which the other knobs are turned one at a time.
MIDDLE_STEP = 0.5
SLICER_TABLE = 512
TETRA_TABLE = 256
TETRA_LENGTHS = 32
#: `tetra`'s adaptive refinement settings swept (image stride, refine tolerance): from close to the
#: image with a ray per pixel to coarse; tolerance 1 splits only at silhouettes. 8/0.05 and 16/0.03 lie
#: between 8/0.02 (RMSE at most 0.58x VTK's default's on the shared scenes) and 16/0.05 (up to 1.47x,
#: spx spiky), where the `default` quality level is chosen.
TETRA_REFINEMENT = ((8, 0.02), (8, 0.05), (16, 0.03), (16, 0.05), (16, 0.1), (32, 0.2), (64, 0.4), (64, 1.0))
QUICK_TETRA_REFINEMENT = ((16, 0.1),)
#: The tables (size, lengths) each refinement setting is swept with: besides the default, two
#: lighter ones, also swept at a ray per pixel (where their own error shows: far below refinement's
#: on smooth TFs, and for 256x8 also on spiky ones). A smaller table is cheaper to build and to read
#: (the 256x32 one is 50 MB, and its reads are most of a refined frame's walk).
TETRA_REFINEMENT_TABLES = ((TETRA_TABLE, TETRA_LENGTHS), (TETRA_TABLE, 8), (128, 8))


@dataclass(frozen=True)
class Config:
    """One renderer with one set of quality settings; None marks a knob the renderer lacks."""

    curve: str
    step: float | None = None
    preintegration: bool | None = None
    table_size: int | None = None
    table_lengths: int | None = None
    jitter: bool | None = None
    skipping: bool | None = None
    image_stride: int | None = None
    refine_tolerance: float | None = None
    #: A level of a registered renderer's own quality axis (plugins); it replaces the knobs above.
    quality_label: str | None = None
    quality: QualityLevel | None = field(default=None, compare=False)

    @property
    def viewer(self) -> bool:
        """Whether a viewer peer draws it (`volren.bench.viewer_peers`), not a registered renderer."""
        return self.curve in VIEWER_PEERS

    @property
    def ours(self) -> bool:
        return not (self.curve.startswith("vtk-") or self.viewer)

    @property
    def renderer(self) -> str:
        """The registry name of the renderer that draws this configuration (a viewer peer: its name)."""
        return "vtk" if self.curve.startswith("vtk-") else self.curve

    @property
    def one_frame(self) -> bool:
        return self.curve in ONE_FRAME_CURVES

    @property
    def label(self) -> str:
        """The settings as short text, e.g. 'step 0.5, pre 512, jitter, no skipping'."""
        if self.quality_label is not None:
            return self.quality_label
        parts = []
        if self.step is not None:
            parts.append(f"step {self.step:g}")
        if self.preintegration:
            parts.append(f"pre {self.table_size}" if self.table_size else "pre")
        elif self.preintegration is not None:
            parts.append("post" if self.ours else "linear")
        elif self.table_size is not None:
            parts.append(f"table {self.table_size}x{self.table_lengths}")
        if self.jitter:
            parts.append("jitter")
        if self.skipping is False:
            parts.append("no skipping")
        if self.image_stride is not None:
            parts.append(f"refine {self.image_stride}/{self.refine_tolerance:g}")
        return ", ".join(parts) or "default"

    def settings(self) -> RenderSettings:
        """The RenderSettings that make the renderer draw this configuration."""
        if self.quality is not None:
            return self.quality.apply()
        options: dict[str, object] = {}
        if self.curve == "slicer":
            options.update(
                table_size=self.table_size or SLICER_TABLE,
                empty_space_skipping=bool(self.skipping),
                early_termination=bool(self.skipping),
            )
        elif self.curve == "tetra":
            options.update(
                table_size=self.table_size,
                table_lengths=self.table_lengths,
                termination_alpha=0.999 if self.skipping else 1.0,
            )
            if self.image_stride is not None:
                options.update(image_stride=self.image_stride, refine_tolerance=self.refine_tolerance)
        else:
            options["mapper"] = self.curve.removeprefix("vtk-")
        return RenderSettings(
            step=self.step if self.step is not None else RenderSettings().step,
            preintegration=bool(self.preintegration),
            jitter=bool(self.jitter),
            options=options,
        )


def _slicer(steps: Iterable[float], tables: Iterable[int]) -> list[Config]:
    out = [
        Config("slicer", step, pre, SLICER_TABLE if pre else None, jitter=False, skipping=True)
        for step in steps
        for pre in (False, True)
    ]
    out += [Config("slicer", MIDDLE_STEP, True, n, jitter=False, skipping=True) for n in tables]
    for pre in (False, True):
        table = SLICER_TABLE if pre else None
        out.append(Config("slicer", MIDDLE_STEP, pre, table, jitter=True, skipping=True))
        out.append(Config("slicer", MIDDLE_STEP, pre, table, jitter=False, skipping=False))
    return out


def _vtk_uniform(steps: Iterable[float]) -> list[Config]:
    steps = list(steps)
    out = [Config("vtk-smart")]
    out += [Config("vtk-gpu", step, jitter=False) for step in steps]
    out.append(Config("vtk-gpu", MIDDLE_STEP, jitter=True))
    out += [Config("vtk-fixed_point", step) for step in steps]
    return out


def _tetra(
    tables: Iterable[int],
    short_lengths: bool,
    refinement: Iterable[tuple[int, float]],
    tables_refined: Iterable[tuple[int, int]],
) -> list[Config]:
    out = [Config("tetra", table_size=n, table_lengths=TETRA_LENGTHS, skipping=True) for n in tables]
    if short_lengths:  # every table the refinement runs with, at a ray per pixel too (its own error)
        out += [
            Config("tetra", table_size=size, table_lengths=lengths, skipping=True)
            for size, lengths in TETRA_REFINEMENT_TABLES
            if lengths != TETRA_LENGTHS
        ]
    out.append(Config("tetra", table_size=TETRA_TABLE, table_lengths=TETRA_LENGTHS, skipping=False))
    out += [
        Config(
            "tetra",
            table_size=size,
            table_lengths=lengths,
            skipping=True,
            image_stride=stride,
            refine_tolerance=tol,
        )
        for size, lengths in tables_refined
        for stride, tol in refinement
    ]
    return out


def _vtk_tets() -> list[Config]:
    return [
        Config("vtk-raycast", preintegration=False),
        Config("vtk-raycast", preintegration=True),
        Config("vtk-projected"),
        Config("vtk-zsweep", preintegration=False),
    ]


def configs(
    kind: str, quick: bool = False, steps: Iterable[float] | None = None, curves: Iterable[str] | None = None
) -> list[Config]:
    """The sweep for a volume of this kind: the full one, or a few points per curve with `quick`;
    `steps` replaces the step list, `curves` keeps only those curves."""
    if kind not in CURVES:
        raise VolrenError(f"no benchmark sweep for {kind} volumes")
    given_steps = list(steps) if steps is not None else None
    steps = given_steps or list(QUICK_STEPS if quick else FULL_STEPS)
    if kind == "uniform":
        out = _slicer(steps, (64,) if quick else (64, 2048)) + _vtk_uniform(steps)
        out += [Config(name) for name in VIEWER_PEERS]  # the tools' defaults: nothing to sweep
    else:
        tables = (32, TETRA_TABLE) if quick else (32, 64, 128, TETRA_TABLE, 512)
        refinement = QUICK_TETRA_REFINEMENT if quick else TETRA_REFINEMENT
        tables_refined = TETRA_REFINEMENT_TABLES[:1] if quick else TETRA_REFINEMENT_TABLES
        out = _tetra(tables, not quick, refinement, tables_refined) + _vtk_tets()
    if curves is not None:
        wanted = set(curves)
        out = [c for c in out if c.curve in wanted]
        out += [
            c for name in curves if name not in BUILTIN_CURVES for c in quality_axis(name, kind, given_steps)
        ]
    return _unique(out)


def quality_axis(name: str, kind: str, steps: Iterable[float] | None = None) -> list[Config]:
    """A registered renderer's declared quality axis on volumes of `kind` (none if it does not draw
    them); `steps`, when given, replaces the axis by those steps at the renderer's defaults."""
    from volren.renderers.registry import registry

    capabilities = registry.capabilities(name)
    if kind not in capabilities.kinds:
        return []
    if steps is not None:
        levels = tuple(QualityLevel(f"step {s:g}", step=s) for s in steps)
    else:
        levels = capabilities.quality or (QualityLevel("default"),)
    return [Config(name, step=level.step, preintegration=level.preintegration, quality_label=level.label,
                   quality=level) for level in levels]  # fmt: skip


def _unique(configs: list[Config]) -> list[Config]:
    """The configurations in order, each once (a swept step may equal the middle step)."""
    seen: set[Config] = set()
    out = []
    for c in configs:
        if c not in seen:
            seen.add(c)
            out.append(c)
    return out


def check_curves(names: Iterable[str]) -> list[str]:
    """The curve names (built-in curves, or any registered renderer), or an error listing the valid ones."""
    from volren.renderers.registry import registry

    names = list(names)
    registered = [n for n in registry.names() if n not in BUILTIN_CURVES]
    unknown = [n for n in names if n not in BUILTIN_CURVES and n not in registered]
    if unknown or not names:
        raise VolrenError(
            f"unknown renderers {unknown or names}; choose from {', '.join(BUILTIN_CURVES)} or a registered renderer "
            f"({', '.join(registered)})"
        )
    return names
