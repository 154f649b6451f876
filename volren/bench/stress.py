"""`volren bench stress`: the numerical stability suite.

Why: a renderer that is accurate on friendly data can still return NaN, Inf or colours brighter
than their opacity on the corners of its input (see `stress_cases`). This suite renders every
scene there with every registered renderer that can draw it (pre-integration and shading each
off and on where supported) and checks the pre-integration tables directly, then counts, per
image or table, the pixels (entries) that are NaN, Inf or out of range: a channel outside
[0, 1], or a premultiplied colour above its alpha by more than `COLOR_EPS`. Those counts must
be 0. Beside them it reports RMSE and max abs error against `reference` at the same camera and
shading (DESIGN.md's metric): a report, never a failure. A renderer that refuses a scene with a
VolrenError counts as rejected (its message is kept); any other exception is a failure.
"""

from __future__ import annotations

import csv
import fnmatch
import math
import time
import warnings
from collections.abc import Callable, Iterable, Sequence
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from volren.bench.stress_cases import (
    BELOW_ALPHA,
    PREMULTIPLIED,
    RULES,
    UNIT,
    Case,
    TableCase,
    scene_cases,
    table_cases,
)
from volren.errors import VolrenError
from volren.model.channels import ChannelTransferFunction
from volren.model.labels import LabelTransferFunction
from volren.model.settings import RenderSettings
from volren.renderers.registry import RendererRegistry
from volren.testing.metrics import image_error

#: How far a premultiplied colour channel may exceed its alpha (float32 and 8-bit rounding).
COLOR_EPS = 1e-4
REFERENCE = "reference"
#: Renderer-specific variants added to the full suite, per (renderer, volume kind): options, and
#: whether pre-integration is tried with them (the projected-tetrahedra mapper has none).
EXTRA_OPTIONS: dict[tuple[str, str], tuple[tuple[dict[str, Any], bool], ...]] = {
    ("slicer", "uniform"): (({"path": "slices"}, True),),
    ("vtk", "tet"): (({"mapper": "zsweep"}, True), ({"mapper": "projected"}, False)),
}
STATUSES = ("ok", "bad", "failed", "rejected")


# ------------------------------------------------------------------------------ checks
@dataclass(frozen=True)
class Counts:
    """Per image (or table): values checked, and how many are NaN, Inf or out of range."""

    values: int = 0
    nan: int = 0
    inf: int = 0
    out_of_range: int = 0
    #: The largest amount by which a finite value breaks its rule (0 when none does).
    excess: float = 0.0

    def __add__(self, other: Counts) -> Counts:
        return Counts(
            self.values + other.values,
            self.nan + other.nan,
            self.inf + other.inf,
            self.out_of_range + other.out_of_range,
            max(self.excess, other.excess),
        )

    @property
    def bad(self) -> int:
        return self.nan + self.inf + self.out_of_range


def check_rgba(rgba: NDArray, rule: str = PREMULTIPLIED, eps: float = COLOR_EPS) -> Counts:
    """Counts over the pixels (rows of RGBA) of `rgba` (..., 4); a pixel counts once, as NaN if
    any channel is NaN, else Inf if any is infinite, else out of range if it breaks `rule`:
    PREMULTIPLIED, every channel in [0, 1] and no colour channel above alpha + eps; UNIT, every
    channel in [0, 1]; BELOW_ALPHA, no colour channel above alpha + eps (for sums of stored parts,
    which may pass 1 by a rounding)."""
    if rule not in RULES:
        raise ValueError(f"unknown rule {rule!r}; choose from {', '.join(RULES)}")
    a = np.asarray(rgba, dtype=np.float64).reshape(-1, 4)
    nan = np.isnan(a).any(axis=1)
    inf = np.isinf(a).any(axis=1) & ~nan
    finite = ~(nan | inf)
    a = a[finite]
    over = np.zeros(len(a))
    out = np.zeros(len(a), dtype=bool)
    if rule != BELOW_ALPHA:
        over = np.maximum(-a.min(axis=1, initial=0.0), a.max(axis=1, initial=1.0) - 1.0)
        out |= over > 0
    if rule != UNIT:
        above = (a[:, :3] - a[:, 3:4]).max(axis=1, initial=0.0)
        out |= above > eps
        over = np.where(above > eps, np.maximum(over, above), over)
    excess = float(over[out].max()) if out.any() else 0.0
    return Counts(len(finite), int(nan.sum()), int(inf.sum()), int(out.sum()), excess)


def check_arrays(arrays: Iterable[tuple[NDArray, str]], eps: float = COLOR_EPS) -> Counts:
    total = Counts()
    for array, rule in arrays:
        total = total + check_rgba(array, rule, eps)
    return total


# -------------------------------------------------------------------------------- rows
@dataclass
class Row:
    """One line of the report: an image (suite "image") or one table function on one TF over all
    its parameter sets (suite "table", its error the max against the continuous integral)."""

    suite: str
    case: str
    renderer: str
    settings: str
    status: str = "ok"
    values: int = 0
    nan: int = 0
    inf: int = 0
    out_of_range: int = 0
    excess: float = 0.0
    rmse: float = math.nan
    max_abs: float = math.nan
    ms: float = math.nan
    message: str = ""

    @property
    def problem(self) -> bool:
        """NaN, Inf or out-of-range values, or a crash: what makes the suite fail."""
        return self.status in ("bad", "failed")

    def add_counts(self, counts: Counts) -> None:
        self.values += counts.values
        self.nan += counts.nan
        self.inf += counts.inf
        self.out_of_range += counts.out_of_range
        self.excess = max(self.excess, counts.excess)
        if counts.bad and self.status == "ok":
            self.status = "bad"


COLUMNS = tuple(f.name for f in fields(Row))


def _one_line(text: str, limit: int = 300) -> str:
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _failure(exc: BaseException) -> str:
    return _one_line(f"{type(exc).__name__}: {exc}")


# ---------------------------------------------------------------------------- images
@dataclass(frozen=True)
class Config:
    """One renderer with one setting."""

    renderer: str
    settings: RenderSettings

    @property
    def label(self) -> str:
        s = self.settings
        parts = ["pre" if s.preintegration else "post", "shade" if s.shade else "flat"]
        parts += [f"{k}={v}" for k, v in sorted(s.options.items())]
        return " ".join(parts)


def configs_for(registry: RendererRegistry, name: str, case: Case, quick: bool) -> list[Config]:
    """The settings `name` is run with on `case`: pre-integration and shading off and on where
    its capabilities offer them, plus EXTRA_OPTIONS in the full suite."""
    support = registry.capabilities(name).kinds.get(case.volume.kind)  # type: ignore[call-overload]
    if support is None or case.tf.dims not in support.tf_dims:
        return []
    pres = (False, True) if support.preintegration else (False,)
    shades = (False, True) if support.shading and name != REFERENCE else (False,)
    out = [Config(name, RenderSettings(preintegration=p, shade=s)) for p in pres for s in shades]
    if not quick:
        for options, with_pre in EXTRA_OPTIONS.get((name, case.volume.kind), ()):
            out += [
                Config(name, RenderSettings(preintegration=p, options=options))
                for p in pres
                if with_pre or not p
            ]
    caps = registry.capabilities(name)
    return [
        c
        for c in out
        if caps.unsupported_reason(case.volume.kind, case.tf.dims, c.settings, *_mixing(case)) is None
    ]


def _mixing(case: Case) -> tuple[bool, bool]:
    """(labels, channels): whether the case draws a label volume or mixes channels."""
    return isinstance(case.tf, LabelTransferFunction), isinstance(case.tf, ChannelTransferFunction)


@dataclass(frozen=True)
class ImageJob:
    case: Case
    config: Config


def image_jobs(
    cases: Sequence[Case],
    registry: RendererRegistry,
    renderers: Sequence[str] | None = None,
    quick: bool = False,
) -> tuple[list[ImageJob], list[str]]:
    """Per case: the reference (shading off, and on where another renderer shades), then every
    other (selected) renderer's configs. Also the notes on renderers that failed to load."""
    unknown = sorted(set(renderers or ()) - set(registry.names()))
    if unknown:
        raise VolrenError(f"unknown renderers {unknown}; registered: {', '.join(registry.names())}")
    notes, names = [], []
    for name in registry.names():
        if name == REFERENCE or (renderers is not None and name not in renderers):
            continue
        try:
            registry.get(name)
        except VolrenError as exc:
            notes.append(f"renderer {name!r} skipped: {exc}")
            continue
        names.append(name)
    registry.get(REFERENCE)  # no oracle, no suite: let the VolrenError say why
    jobs = []
    for case in cases:
        others = [c for name in names for c in configs_for(registry, name, case, quick)]
        shades = sorted({c.settings.shade for c in others} | {False})
        refs = [Config(REFERENCE, RenderSettings(shade=s)) for s in shades]
        refs = [
            c
            for c in refs
            if registry.capabilities(REFERENCE).unsupported_reason(
                case.volume.kind, case.tf.dims, c.settings, *_mixing(case)
            )
            is None
        ]
        jobs += [ImageJob(case, c) for c in (*refs, *others)]
    return jobs, notes


def render_image(registry: RendererRegistry, config: Config, case: Case, size: int) -> tuple[NDArray, float]:
    """The image and its render time in ms, from a fresh renderer released afterwards."""
    renderer = registry.create(config.renderer)
    try:
        renderer.set_volume(case.volume)
        renderer.set_transfer_function(case.tf)
        renderer.set_settings(config.settings)
        start = time.perf_counter()
        image = np.asarray(renderer.render(case.camera, size, size))
        ms = (time.perf_counter() - start) * 1e3
    finally:
        renderer.release()
    if image.shape != (size, size, 4):
        raise RuntimeError(f"renderer {config.renderer} returned shape {image.shape}, not {(size, size, 4)}")
    return image, ms


def run_image(
    job: ImageJob,
    registry: RendererRegistry,
    size: int,
    oracles: dict[tuple[str, bool], NDArray | str],
    eps: float,
) -> Row:
    """Render, count, and compare with the reference image of the same case and shading (kept
    in `oracles`, or the reason there is none)."""
    case, config = job.case, job.config
    row = Row("image", case.name, config.renderer, config.label)
    is_reference = config.renderer == REFERENCE
    key = (case.name, config.settings.shade)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            image, row.ms = render_image(registry, config, case, size)
        except VolrenError as exc:
            row.status, row.message = "rejected", _one_line(str(exc))
            if is_reference:
                oracles[key] = f"reference rejected the scene: {row.message}"
            return row
        except Exception as exc:  # the suite's job: report any crash and go on
            row.status, row.message = "failed", _failure(exc)
            if is_reference:
                oracles[key] = "reference failed"
            return row
    notes = sorted({_one_line(str(w.message), 160) for w in caught})
    row.add_counts(check_rgba(image, PREMULTIPLIED, eps))
    if is_reference:
        oracles[key] = image
    else:
        oracle = oracles.get(key, "no reference image")
        if isinstance(oracle, str):
            notes.insert(0, oracle)
        else:  # NaN and Inf are counted above; the error measures the rest
            err = image_error(np.nan_to_num(image), np.nan_to_num(oracle))
            row.rmse, row.max_abs = err.rmse, err.max_abs
    row.message = _one_line("; ".join(notes))
    return row


# ---------------------------------------------------------------------------- tables
def run_table(case: TableCase, eps: float) -> Row:
    """Every parameter set of one table function on one TF; one row, counts summed."""
    row = Row("table", case.tf_name, f"table: {case.function}", f"{len(case.runs)} parameter sets")
    broken: list[str] = []
    rejected: list[str] = []
    errors: list[float] = []
    start = time.perf_counter()
    warned: dict[str, str] = {}
    for label, compute in case.runs:
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                output = compute()
            for w in caught:
                warned.setdefault(_one_line(str(w.message), 120), label)
        except VolrenError as exc:
            rejected.append(f"{label}: {exc}")
            continue
        except Exception as exc:  # reported as a failure of this table
            row.status = "failed"
            broken.append(f"{label}: {_failure(exc)}")
            continue
        counts = check_arrays(output.arrays, eps)
        row.add_counts(counts)
        if counts.bad:
            broken.append(f"{label}: {counts.nan} NaN, {counts.inf} Inf, {counts.out_of_range} out of range")
        if output.error is not None:
            errors.append(output.error)
    row.ms = (time.perf_counter() - start) * 1e3
    if errors:
        row.max_abs = max(errors)
    if rejected and len(rejected) == len(case.runs):
        row.status = "rejected"
    notes = broken[:3] + ([f"{len(broken) - 3} more"] if len(broken) > 3 else [])
    if rejected:
        notes.append(f"{len(rejected)} rejected, e.g. {rejected[0]}")
    notes += [f"warning: {message} (first at {label})" for message, label in warned.items()]
    row.message = _one_line("; ".join(notes), 400)
    return row


# ------------------------------------------------------------------------------- suite
@dataclass
class Plan:
    """Everything one run will do, known up front so a progress bar can count it."""

    images: list[ImageJob] = field(default_factory=list)
    tables: list[TableCase] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.images) + len(self.tables)


def select(cases: Sequence[Case], patterns: Sequence[str] | None) -> list[Case]:
    """The cases whose name matches any glob (e.g. "tet-*", "*/spike")."""
    if not patterns:
        return list(cases)
    return [c for c in cases if any(fnmatch.fnmatchcase(c.name, p) for p in patterns)]


def plan(
    quick: bool = False,
    registry: RendererRegistry | None = None,
    renderers: Sequence[str] | None = None,
    patterns: Sequence[str] | None = None,
    images: bool = True,
    tables: bool = True,
) -> Plan:
    if registry is None:
        from volren.renderers.registry import registry as default

        registry = default
    out = Plan()
    if images:
        cases = select(scene_cases(quick), patterns)
        if patterns and not cases:
            raise VolrenError(f"no stress case matches {', '.join(patterns)}")
        out.images, out.notes = image_jobs(cases, registry, renderers, quick)
    if tables:
        out.tables = table_cases(quick)
    return out


def run(
    work: Plan,
    registry: RendererRegistry | None = None,
    size: int = 64,
    eps: float = COLOR_EPS,
    report: Callable[[Row], None] | None = None,
) -> list[Row]:
    """Run the plan's images, then its tables; `report` sees every row as it is made."""
    if registry is None:
        from volren.renderers.registry import registry as default

        registry = default
    rows = []
    oracles: dict[tuple[str, bool], NDArray | str] = {}
    for job in work.images:
        rows.append(run_image(job, registry, size, oracles, eps))
        if report:
            report(rows[-1])
    for case in work.tables:
        rows.append(run_table(case, eps))
        if report:
            report(rows[-1])
    return rows


# ------------------------------------------------------------------------------ report
@dataclass
class Summary:
    """One renderer (or table function) over every row."""

    renderer: str
    runs: int = 0
    counts: dict[str, int] = field(default_factory=lambda: dict.fromkeys(STATUSES, 0))
    nan: int = 0
    inf: int = 0
    out_of_range: int = 0
    worst_rmse: tuple[float, str] = (math.nan, "")
    worst_max: tuple[float, str] = (math.nan, "")


def _worse(current: tuple[float, str], value: float, where: str) -> tuple[float, str]:
    if math.isnan(value) or (not math.isnan(current[0]) and value <= current[0]):
        return current
    return (value, where)


def summarize(rows: Iterable[Row]) -> list[Summary]:
    out: dict[str, Summary] = {}
    for row in rows:
        s = out.setdefault(row.renderer, Summary(row.renderer))
        s.runs += 1
        s.counts[row.status] += 1
        s.nan += row.nan
        s.inf += row.inf
        s.out_of_range += row.out_of_range
        where = f"{row.case} ({row.settings})" if row.suite == "image" else row.case
        s.worst_rmse = _worse(s.worst_rmse, row.rmse, where)
        s.worst_max = _worse(s.worst_max, row.max_abs, where)
    return list(out.values())


def _num(value: float, spec: str) -> str:
    return "-" if math.isnan(value) else format(value, spec)


ROW_HEADER = (
    "| case | renderer | settings | status | NaN | Inf | out of range | by | RMSE | max abs | ms | notes |\n"
    "|---|---|---|---|---|---|---|---|---|---|---|---|"
)


def markdown_row(row: Row) -> str:
    message = row.message.replace("|", "/")
    return (
        f"| {row.case} | {row.renderer} | {row.settings} | {row.status} | {row.nan} | {row.inf} | "
        f"{row.out_of_range} | {_num(row.excess or math.nan, '.2g')} | {_num(row.rmse, '.5f')} | "
        f"{_num(row.max_abs, '.4f')} | {_num(row.ms, '.0f')} | {message} |"
    )


SUMMARY_HEADER = (
    "| renderer | runs | ok | rejected | failed | NaN | Inf | out of range | worst RMSE | at | worst max abs | at |\n"
    "|---|---|---|---|---|---|---|---|---|---|---|---|"
)


def summary_table(rows: Iterable[Row]) -> str:
    lines = [SUMMARY_HEADER]
    for s in summarize(rows):
        c = s.counts
        lines.append(
            f"| {s.renderer} | {s.runs} | {c['ok']} | {c['rejected']} | {c['failed']} | {s.nan} | {s.inf} | "
            f"{s.out_of_range} | {_num(s.worst_rmse[0], '.5f')} | {s.worst_rmse[1] or '-'} | "
            f"{_num(s.worst_max[0], '.4f')} | {s.worst_max[1] or '-'} |"
        )
    return "\n".join(lines)


def problems(rows: Iterable[Row]) -> list[Row]:
    return [r for r in rows if r.problem]


def markdown(
    rows: Sequence[Row],
    seconds: float,
    size: int,
    quick: bool,
    notes: Sequence[str] = (),
    eps: float = COLOR_EPS,
) -> str:
    """The stress.md fragment: summary, problems, rejections, then every row."""
    bad = problems(rows)
    rejected = [r for r in rows if r.status == "rejected"]
    parts = [
        f"Stress suite ({'quick' if quick else 'full'}): {len(rows)} runs, {size}x{size} images, "
        f"{seconds:.0f} s. NaN, Inf and out-of-range counts must be 0 (out of range: a channel outside "
        f"[0, 1] or a premultiplied colour above alpha + {eps:g}, by: the largest such excess); RMSE and max abs are against "
        "`reference` at the same camera and shading (tables: max abs against the continuous integral).",
        summary_table(rows),
    ]
    parts += [f"Note: {n}" for n in notes]
    parts.append(f"Problems ({len(bad)}):")
    if bad:
        parts.append("\n".join([ROW_HEADER, *map(markdown_row, bad)]))
    parts.append(f"Rejected ({len(rejected)}):")
    if rejected:
        parts.append("\n".join([ROW_HEADER, *map(markdown_row, rejected)]))
    parts += ["All runs:", "\n".join([ROW_HEADER, *map(markdown_row, rows)])]
    return "\n\n".join(parts) + "\n"


def write_csv(rows: Iterable[Row], path: Path) -> None:
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        for row in rows:
            writer.writerow(asdict(row))
