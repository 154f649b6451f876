"""Quality levels and the `auto` renderer, from measurements (DESIGN.md: `--quality`, `--renderer auto`).

Why data, not constants: which settings give which error at which speed differs per renderer and
per volume kind, and only the benchmark knows. `volren bench quality RUNS.csv ...`
(`volren.bench.quality`) reads `volren bench run` results and writes `quality_levels.json` next to
this module: per volume kind, per renderer, per level, the settings chosen from the run's
configurations and what they measured. Levels are defined against VTK's default (vtkSmartVolumeMapper
on grids, the unstructured ray caster on meshes) on the same scenes:

- `draft`: the fastest configuration whose error is at most 4x VTK's default's on every scene;
- `interactive`: at most 2x;
- `default`: at most VTK's default's error (the fastest such: DESIGN.md);
- `high`: at most a quarter of it;
- `exact`: the most accurate configuration measured.

A renderer whose most accurate configuration is beyond VTK's error on some scene has its bounds
scaled by that factor (`LevelChoice.meets` false). `auto` picks, for the scene's kind, the
registered renderer whose configuration for the level was fastest over the scenes every candidate
was measured on, among those that can draw the scene (TF dimensions, shading, blend mode) and that
meet the level's bound (any, where none does); renderers without measurements take part only when
no measured one can draw the scene.

TF classes: a 1D TF is `smooth` or `sharp` (`tf_class`: how steeply its optical depth changes
across the data's value range), and a sharp one is a `band` TF when it is visible on a narrow part
of that range only (`BAND_TF`); a kind's levels may also be chosen over the scenes of one class
("uniform/smooth", "uniform/sharp", "uniform/band"). Why: what a level needs differs by class, and one
configuration for every scene pays the sharp TFs' price on the smooth ones. Measured on the shared
grids (2026-12-02): objectorder's post-classified step 0.5 is within VTK's default's RMSE on every
smooth TF but 1.64x over it on ironProt's opaque one, its pre-integrated step 0.5 within on every
sharp TF but 1.83x over on aneurism's smooth one; one configuration for all was step 0.25
pre-integrated, 2.9x the time of step 0.5 post-classified on bonsai's smooth TF. A scene's kind with
its class (`scene_kind`) is what callers pass; the table falls back to the kind's own levels where
it has none for the class.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.settings import RenderSettings
from volren.model.transfer_function import MAX_OPACITY, TransferFunction1D

LEVELS = ("draft", "interactive", "default", "high", "exact")
DEFAULT_LEVEL = "default"
AUTO = "auto"
#: The committed table (`volren bench quality` writes it).
TABLE_PATH = Path(__file__).with_name("quality_levels.json")
#: Never chosen by `auto`: the float64 reference (minutes per frame) and the plugin template.
NOT_AUTO = frozenset({"reference", "example"})


#: A 1D TF is `sharp` when its optical depth per opacity unit distance changes by at least this much across
#: the data's value range at its steepest (`tf_sharpness`). The shared scenes' TFs lie far either side:
#: smooth 0.3-5.2, spiky and opaque 235-1760 (`volren bench quality` prints each scene's; the bundled
#: samples' 2.1, 12 and 51), so the class does not hinge on the exact value; 30 is about the shared
#: scenes' geometric middle.
SHARP_TF = 30.0
#: A sharp 1D TF is a `band` TF when it is visible (opacity > 0) on less than this fraction of the
#: data's value range: narrow peaks of opacity around a few values (thin shells), not steps up to a
#: solid body. The shared scenes lie far either side: spiky 0.027-0.047; opaque 0.32-0.90, the
#: samples 0.20-1 (`volren bench quality` prints each scene's); 0.1 is about their geometric middle.
#: Why a class of its own: VTK's post-classified default misses most of a thin peak (its RMSE on
#: bonsai's spiky TF is 3.6x that on the opaque one), so coarser pre-integrated settings reach its
#: error there and not on the steps (shearwarp's pre-integrated oversampling 1, measured 2026-12-03:
#: within it on every spiky TF, up to 0.9x; 1.55-1.9x over it on three of the four opaque TFs and
#: 1.42x on phantom_ct's).
BAND_TF = 0.1
TF_CLASSES = ("smooth", "sharp", "band")


def tf_sharpness(tf: object, value_range: tuple[float, float]) -> float | None:
    """The steepest change of a 1D TF's optical depth, -ln(1 - a), over its opacity points, times the
    data's value span (inf for a step); None for a TF that is not 1D."""
    if not isinstance(tf, TransferFunction1D):
        return None
    points = tf.opacity_points
    span = float(value_range[1]) - float(value_range[0])
    if len(points) < 2 or not span > 0.0:
        return 0.0
    depth = -np.log1p(-np.minimum(np.clip(points[:, 1], 0.0, 1.0), MAX_OPACITY))
    rise = np.abs(np.diff(depth))
    run = np.diff(points[:, 0])
    steps = (run <= 0.0) & (rise > 0.0)
    if steps.any():
        return math.inf
    slopes = np.where(run > 0.0, rise / np.where(run > 0.0, run, 1.0), 0.0)
    return float(slopes.max()) * span


def tf_visible_fraction(tf: object, value_range: tuple[float, float]) -> float | None:
    """The fraction of the data's value range on which a 1D TF's opacity is positive (4097 evenly
    spaced values; 1 or 0 for constant data); None for a TF that is not 1D."""
    if not isinstance(tf, TransferFunction1D):
        return None
    lo, hi = float(value_range[0]), float(value_range[1])
    values = np.linspace(lo, hi, 4097) if hi > lo else np.array([lo])
    return float(np.mean(tf.sample(values)[1] > 0.0))


def tf_class(tf: object, value_range: tuple[float, float]) -> str | None:
    """`smooth`, `sharp` or `band` (SHARP_TF, BAND_TF) for a 1D TF over data spanning
    `value_range`; None for other TFs."""
    sharpness = tf_sharpness(tf, value_range)
    visible = tf_visible_fraction(tf, value_range)
    return features_class(sharpness, visible) if sharpness is not None and visible is not None else None


def features_class(sharpness: float, visible: float) -> str:
    """The TF class of a `tf_sharpness` and a `tf_visible_fraction`."""
    if sharpness < SHARP_TF:
        return "smooth"
    return "band" if visible < BAND_TF else "sharp"


def scene_kind(kind: str, tf: object, value_range: tuple[float, float]) -> str:
    """The volume kind with the TF's class ("uniform/smooth"), or the kind alone for a TF without one:
    what the table is looked up by."""
    cls = tf_class(tf, value_range)
    return f"{kind}/{cls}" if cls is not None else kind


def kind_of(volume: Any, tf: object) -> str:
    """`scene_kind` of a volume (its `kind` and `value_range`) drawn with `tf`."""
    return scene_kind(volume.kind, tf, volume.value_range)


def base_kind(kind: str) -> str:
    """The volume kind of a scene kind ("uniform/smooth" -> "uniform")."""
    return kind.split("/", 1)[0]


@dataclass(frozen=True)
class LevelChoice:
    """One renderer's configuration for one level on one volume kind, as measured."""

    label: str  #: the benchmark's name of the configuration
    step: float
    preintegration: bool
    options: Mapping[str, Any]
    ms: Mapping[str, float]  #: median frame time per scene ("dataset/tf"), 512x512
    worst_error_ratio: float  #: largest RMSE / VTK default's RMSE over the scenes
    meets: bool = True  #: within the level's own bound (False: the bound was scaled to what the renderer reaches)

    def apply(self, settings: RenderSettings) -> RenderSettings:
        """`settings` with this level's step, pre-integration and options (options merged, the
        caller's own winning)."""
        return settings.with_(step=self.step, preintegration=self.preintegration,
                              options={**self.options, **settings.options})  # fmt: skip

    def replace(self, settings: RenderSettings) -> RenderSettings:
        """`settings` with exactly this level's step, pre-integration and options (the app's
        chooser: a level picked there replaces the options of the one before)."""
        return settings.with_(step=self.step, preintegration=self.preintegration, options=dict(self.options))

    def matches(self, settings: RenderSettings) -> bool:
        """Whether `settings` are this level's (step, pre-integration and options all equal)."""
        return (settings.step == self.step and settings.preintegration == self.preintegration
                and dict(settings.options) == dict(self.options))  # fmt: skip


@dataclass(frozen=True)
class QualityTable:
    """Level choices by volume kind and renderer, with where they came from."""

    levels: Mapping[str, Mapping[str, Mapping[str, LevelChoice]]]  #: kind -> renderer -> level -> choice
    source: str  #: the command and runs that made it

    def choice(self, renderer: str, kind: str, level: str) -> LevelChoice | None:
        """The choice for a scene kind ("uniform/smooth"), else for its volume kind ("uniform")."""
        check_level(level)
        found = self.levels.get(kind, {}).get(renderer, {}).get(level)
        if found is None and kind != base_kind(kind):
            found = self.levels.get(base_kind(kind), {}).get(renderer, {}).get(level)
        return found

    def measured(self, kind: str) -> list[str]:
        """The renderers with levels for this scene kind or its volume kind."""
        names = dict.fromkeys(self.levels.get(kind, {}))
        names.update(dict.fromkeys(self.levels.get(base_kind(kind), {})))
        return list(names)

    def siblings(self, kind: str) -> list[str]:
        """The scene kinds the table holds for this scene's volume kind: its classes, then the kind itself."""
        base = base_kind(kind)
        return sorted((k for k in self.levels if base_kind(k) == base), key=lambda k: k == base)

    def to_json(self) -> dict[str, Any]:
        return {
            "version": 1,
            "source": self.source,
            "levels": {kind: {name: {level: {"label": c.label, "step": c.step, "preintegration": c.preintegration,
                                             "options": dict(c.options), "ms": dict(c.ms),
                                             "worst_error_ratio": c.worst_error_ratio, "meets": c.meets}
                                     for level, c in per.items()}
                              for name, per in renderers.items()}
                       for kind, renderers in self.levels.items()},
        }  # fmt: skip

    @classmethod
    def from_json(cls, data: Mapping[str, Any], where: str) -> QualityTable:
        try:
            if data.get("version") != 1:
                raise ValueError(f"version {data.get('version')!r}, expected 1")
            levels = {kind: {name: {level: LevelChoice(str(c["label"]), float(c["step"]), bool(c["preintegration"]),
                                                       dict(c["options"]), {k: float(v) for k, v in c["ms"].items()},
                                                       float(c["worst_error_ratio"]), bool(c.get("meets", True)))
                                    for level, c in per.items()}
                             for name, per in renderers.items()}
                      for kind, renderers in data["levels"].items()}  # fmt: skip
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise VolrenError(f"{where}: not a quality table ({exc})") from None
        return cls(levels, str(data.get("source", "")))


def check_level(level: str) -> str:
    if level not in LEVELS:
        raise VolrenError(f"quality must be one of {', '.join(LEVELS)}, got {level!r}")
    return level


@lru_cache(maxsize=1)
def table() -> QualityTable:
    """The committed table (an empty one where the file is missing: every renderer keeps its defaults)."""
    try:
        text = TABLE_PATH.read_text(encoding="utf-8")
    except FileNotFoundError:
        return QualityTable({}, "")
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise VolrenError(f"{TABLE_PATH}: not JSON ({exc.msg} at line {exc.lineno})") from None
    return QualityTable.from_json(data, str(TABLE_PATH))


def settings_for(renderer: str, kind: str, level: str, settings: RenderSettings,
                 quality: QualityTable | None = None) -> RenderSettings:  # fmt: skip
    """`settings` at `level` for `renderer` on `kind` volumes: the measured choice applied, or
    `settings` unchanged where the renderer has no measurements."""
    choice = (quality or table()).choice(renderer, kind, level)
    return choice.apply(settings) if choice is not None else settings


def level_of(renderer: str, kind: str, settings: RenderSettings, quality: QualityTable | None = None,
             prefer: str | None = None) -> str | None:  # fmt: skip
    """The first level whose measured settings `settings` are for `renderer` on this scene kind, else
    on another class of its volume kind (a TF edited into the other class keeps its level), or None
    (custom settings). `prefer` (the level the person chose) comes first: several levels can have
    the same settings (VTK's on meshes), and the first of them is not necessarily the one chosen."""
    quality = quality or table()
    kinds = [kind] + [k for k in quality.siblings(kind) if k != kind]
    pairs = [(k, level) for k in kinds for level in LEVELS]
    if prefer in LEVELS:
        pairs = [(k, prefer) for k in kinds] + pairs
    return next((level for k, level in pairs
                 if (c := quality.choice(renderer, k, level)) is not None and c.matches(settings)), None)  # fmt: skip


def at_level(renderer: str, kind: str, level: str | None, settings: RenderSettings) -> RenderSettings | None:
    """`settings` with exactly `level`'s measured step, pre-integration and options for `renderer`
    on `kind` volumes (options replaced, as the app's chooser does); None for no level (custom
    settings) or where nothing was measured."""
    choice = table().choice(renderer, kind, level) if level is not None else None
    return choice.replace(settings) if choice is not None else None


def choose_renderer(kind: str, level: str, tf_dim: int, settings: RenderSettings, names: Iterable[str],
                    quality: QualityTable | None = None,
                    can_draw: Callable[[str], bool] | None = None, cameras: Sequence[Camera] = (),
                    bounds: Sequence[float] | None = None) -> tuple[str, str]:  # fmt: skip
    """(`auto`'s renderer, why) for a scene of this kind, TF dimension and settings at `level`,
    among the registered `names`. Candidates are tried fastest first (those meeting the level's
    bound before the others), so only the chosen renderer and the faster ones that cannot draw
    the scene are imported. `can_draw` replaces the capabilities test (the app has its own list).
    `cameras` (with the volume's `bounds`): the views to be drawn, every one of which the
    renderer must be able to draw (`Capabilities.camera_reason`: an eye inside the volume)."""
    from volren.renderers.registry import registry

    quality = quality or table()
    check_level(level)
    names = [n for n in names if n not in NOT_AUTO]

    def drawable(name: str) -> bool:
        if can_draw is not None and not can_draw(name):
            return False
        try:
            capabilities = registry.capabilities(name)
        except VolrenError:  # a plugin that does not import: not a candidate (unless `can_draw` says so)
            return can_draw is not None
        if can_draw is None:
            level_settings = settings_for(name, kind, level, settings, quality)
            if capabilities.unsupported_reason(base_kind(kind), tf_dim, level_settings) is not None:
                return False
        return bounds is None or all(capabilities.camera_reason(base_kind(kind), c, bounds) is None for c in cameras)

    choices = _measured_choices(quality, kind, level, names)
    cost = _costs(choices)
    for name in sorted(choices, key=lambda n: (not choices[n].meets, cost[n])):
        if drawable(name):
            tf = f" for a {kind.split('/', 1)[1]} TF" if kind != base_kind(kind) else ""
            return name, f"the fastest measured at quality {level}{tf} that draws this scene"
    for name in names:
        if name not in choices and drawable(name):
            return name, f"no measured renderer draws this scene; {name} can"
    raise VolrenError(f"no registered renderer can draw this {base_kind(kind)} scene (see `volren renderers`)")


def _measured_choices(quality: QualityTable, kind: str, level: str, names: Iterable[str]) -> dict[str, LevelChoice]:
    """The level's choices of the renderers among `names` that have one, by name."""
    names = set(names)
    return {n: c for n in quality.measured(kind) if n in names and (c := quality.choice(n, kind, level))}


def _costs(choices: Mapping[str, LevelChoice]) -> dict[str, float]:
    """Each choice's summed frame time over the scenes all of them were measured on (over all
    scenes where they share none)."""
    if not choices:
        return {}
    common = set.intersection(*(set(c.ms) for c in choices.values())) or set.union(*(set(c.ms) for c in choices.values()))
    return {n: sum(c.ms.get(scene, float("inf")) for scene in common) for n, c in choices.items()}


def fastest_measured(kind: str, level: str, names: Iterable[str], can_draw: Callable[[str], bool],
                     quality: QualityTable | None = None) -> str | None:  # fmt: skip
    """The renderer among `names` measured fastest at `level` on `kind` volumes that `can_draw`,
    whatever its error (the app's previews: speed first); None when none is measured."""
    quality = quality or table()
    choices = _measured_choices(quality, kind, level, (n for n in names if n not in NOT_AUTO))
    cost = _costs(choices)
    return next((name for name in sorted(choices, key=cost.__getitem__) if can_draw(name)), None)


def resolve(kind: str, tf_dim: int, renderer: str, level: str | None, settings: RenderSettings,
            bricks: bool = False, cameras: Sequence[Camera] = (),
            bounds: Sequence[float] | None = None) -> tuple[str, RenderSettings, str | None]:  # fmt: skip
    """(renderer, settings, why): `auto` resolved at `level` (`default` when None), the level's
    measured settings applied (none when `level` is None), and why `auto` chose its renderer (None
    when one was named). With `bricks`, `auto` chooses among the renderers that draw bricks (a
    bricked volume, a cluster); with `cameras` and the volume's `bounds`, among those that draw
    every one of those views. The one place the CLI and the API turn a request into what is drawn."""
    from volren.renderers.registry import registry

    if level is not None:
        check_level(level)
    why = None
    if renderer == AUTO:
        names = registry.names()
        if bricks:
            names = [n for n in names if _draws_bricks(registry, n, kind)]
        renderer, why = choose_renderer(kind, level or DEFAULT_LEVEL, tf_dim, settings, names, cameras=cameras,
                                        bounds=bounds)  # fmt: skip
    if level is not None:
        settings = settings_for(renderer, kind, level, settings)
    return renderer, settings, why


def _draws_bricks(registry, name: str, kind: str) -> bool:
    try:
        support = registry.capabilities(name).kinds.get(base_kind(kind))
    except Exception:  # noqa: BLE001 - a plugin that fails to load draws nothing
        return False
    return bool(support is not None and support.regions)
