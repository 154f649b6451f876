"""Quality levels and the `auto` renderer, from measurements (DESIGN.md: `--quality`, `--renderer auto`).

Why data, not constants: which settings give which error at which speed differs per renderer and
per scene, and only the benchmark knows. Each renderer ships its own measured levels: a
`quality_levels.json` in the package of the module its entry point names (`volren.renderers`;
volren's built-ins beside their renderer, a plugin in its own package), written by the repository's
`python -m benchmarks.quality_levels RUNS.csv ...` from `volren bench run` results: per scene
class (`volren.model.scene_class`: the volume kind, and the TF's class), per level, the settings
chosen from the renderer's configurations (a `QualityLevel`) and what they measured (a
`Measurement`). Levels are defined against VTK's default (vtkSmartVolumeMapper on grids, the
unstructured ray caster on meshes) on the same scenes:

- `draft`: the fastest configuration whose error is at most 4x VTK's default's on every scene;
- `interactive`: at most 2x;
- `default`: at most VTK's default's error (the fastest such: DESIGN.md);
- `high`: at most a quarter of it;
- `exact`: the most accurate configuration measured.

A renderer whose most accurate configuration is beyond VTK's error on some scene has its bounds
scaled by that factor (`Measurement.meets` false). `auto` picks, for the scene's class, the
registered renderer whose configuration for the level takes the least time relative to VTK's
default measured in the same run (`Measurement.time_ratio`) over the scenes every candidate was
measured on, among those that can draw the scene (TF dimensions, shading, blend mode) and that meet
the level's bound (any, where none does); renderers without measurements take part only when no
measured one can draw the scene. Why ratios: the files of different renderers may come from
different machines and days, and a frame time means something only next to a peer's from the same
run. A scene class's levels fall back to its volume kind's where the class has none.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.scene_class import SceneClass
from volren.model.settings import RenderSettings
from volren.renderers.base import Capabilities, QualityLevel

LEVELS = ("draft", "interactive", "default", "high", "exact")
DEFAULT_LEVEL = "default"
AUTO = "auto"
#: The name of the file of measured levels a renderer ships in its package.
LEVELS_FILE = "quality_levels.json"
#: The version of that file's format.
FILE_VERSION = 2
#: Never chosen by `auto`: the float64 reference (minutes per frame) and the plugin template.
NOT_AUTO = frozenset({"reference", "example"})


@dataclass(frozen=True)
class Measurement:
    """One renderer's configuration for one level on one scene class, as measured."""

    level: QualityLevel  #: the configuration (its label the benchmark's name of it)
    ms: Mapping[str, float]  #: median frame time per scene ("dataset/tf"), 512x512
    peer_ms: Mapping[str, float]  #: VTK's default's frame time per scene, measured in the same run
    worst_error_ratio: float  #: largest RMSE / VTK default's RMSE over the scenes
    meets: bool = (
        True  #: within the level's own bound (False: the bound was scaled to what the renderer reaches)
    )

    def time_ratio(self, scenes: Iterable[str]) -> float:
        """The frame time over these scenes as a multiple of VTK's default's in the same runs (the
        summed times' ratio: each scene weighs as much as VTK takes on it); inf where a scene is missing."""
        scenes = list(scenes)
        if any(s not in self.ms or s not in self.peer_ms for s in scenes):
            return float("inf")
        peer = sum(self.peer_ms[s] for s in scenes)
        return sum(self.ms[s] for s in scenes) / peer if peer > 0 else float("inf")


@dataclass(frozen=True)
class QualityTable:
    """Measurements by scene class, renderer and level, with where each renderer's came from."""

    levels: Mapping[
        SceneClass, Mapping[str, Mapping[str, Measurement]]
    ]  #: class -> renderer -> level -> measurement
    sources: Mapping[str, str]  #: renderer -> the command and runs that made its file

    def measurement(self, renderer: str, scene: SceneClass, level: str) -> Measurement | None:
        """The measurement for a scene class, else for its volume kind."""
        check_level(level)
        found = self.levels.get(scene, {}).get(renderer, {}).get(level)
        if found is None and scene != scene.volume:
            found = self.levels.get(scene.volume, {}).get(renderer, {}).get(level)
        return found

    def measured(self, scene: SceneClass) -> list[str]:
        """The renderers with levels for this scene class or its volume kind."""
        names = dict.fromkeys(self.levels.get(scene, {}))
        names.update(dict.fromkeys(self.levels.get(scene.volume, {})))
        return list(names)

    def siblings(self, scene: SceneClass) -> list[SceneClass]:
        """The scene classes the table holds for this scene's volume kind: its TF classes, then the kind itself."""
        return sorted((s for s in self.levels if s.kind == scene.kind), key=lambda s: (s.tf is None, str(s)))

    def renderer_json(self, renderer: str) -> dict[str, Any]:
        """One renderer's levels as its `LEVELS_FILE` holds them."""
        per_class = {scene: per[renderer] for scene, per in self.levels.items() if renderer in per}
        peer = {s: ms for per in per_class.values() for m in per.values() for s, ms in m.peer_ms.items()}
        return {
            "version": FILE_VERSION,
            "renderer": renderer,
            "source": self.sources.get(renderer, ""),
            "peer_ms": dict(sorted(peer.items())),
            "levels": {str(scene): {level: {"label": m.level.label, "step": m.level.step,
                                            "preintegration": m.level.preintegration,
                                            "options": dict(m.level.options), "ms": dict(m.ms),
                                            "worst_error_ratio": m.worst_error_ratio, "meets": m.meets}
                                    for level, m in per.items()}
                       for scene, per in per_class.items()},
        }  # fmt: skip

    @classmethod
    def from_renderer_json(cls, renderer: str, data: Mapping[str, Any], where: str) -> QualityTable:
        """The table of one renderer's `LEVELS_FILE` (`renderer_json`)."""
        try:
            if data.get("version") != FILE_VERSION:
                raise ValueError(f"version {data.get('version')!r}, expected {FILE_VERSION}")
            peer = {str(s): float(v) for s, v in data["peer_ms"].items()}
            levels = {SceneClass.parse(scene): {renderer: {
                level: Measurement(QualityLevel(str(m["label"]), float(m["step"]), bool(m["preintegration"]),
                                                dict(m["options"])),
                                   {s: float(v) for s, v in m["ms"].items()}, {s: peer[s] for s in m["ms"]},
                                   float(m["worst_error_ratio"]), bool(m.get("meets", True)))
                for level, m in per.items()}}
                for scene, per in data["levels"].items()}  # fmt: skip
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise VolrenError(f"{where}: not a renderer's quality levels ({exc})") from None
        return cls(levels, {renderer: str(data.get("source", ""))})

    @classmethod
    def merged(cls, tables: Iterable[QualityTable]) -> QualityTable:
        """One table of several renderers' tables."""
        levels: dict[SceneClass, dict[str, Mapping[str, Measurement]]] = {}
        sources: dict[str, str] = {}
        for t in tables:
            for scene, per in t.levels.items():
                levels.setdefault(scene, {}).update(per)
            sources.update(t.sources)
        return cls(levels, sources)


def check_level(level: str) -> str:
    if level not in LEVELS:
        raise VolrenError(f"quality must be one of {', '.join(LEVELS)}, got {level!r}")
    return level


def read_levels(renderer: str, path: Path) -> QualityTable:
    """One renderer's measured levels from its `LEVELS_FILE`."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise VolrenError(f"{path}: cannot read: {exc.strerror or exc}") from None
    except json.JSONDecodeError as exc:
        raise VolrenError(f"{path}: not JSON ({exc.msg} at line {exc.lineno})") from None
    return QualityTable.from_renderer_json(renderer, data, str(path))


@lru_cache(maxsize=1)
def table() -> QualityTable:
    """Every registered renderer's measured levels (none for a renderer that ships no file: it keeps
    its defaults, and `auto` takes it only where no measured renderer draws the scene)."""
    from volren.renderers.registry import registry

    found = ((name, registry.data_file(name, LEVELS_FILE)) for name in registry.names())
    return QualityTable.merged(read_levels(name, path) for name, path in found if path is not None)


def _with_level(measurement: Measurement | None, settings: RenderSettings) -> RenderSettings:
    """`settings` with the measured level's step and pre-integration, its options under the
    caller's own (`--option` wins), or unchanged where nothing was measured."""
    if measurement is None:
        return settings
    level = measurement.level
    return settings.with_(step=level.step, preintegration=level.preintegration,
                          options={**level.options, **settings.options})  # fmt: skip


def at_level(renderer: str, scene: SceneClass, level: str | None, settings: RenderSettings,
             quality: QualityTable | None = None) -> RenderSettings | None:  # fmt: skip
    """`settings` with exactly `level`'s measured step, pre-integration and options for `renderer`
    on this scene class (options replaced, as the app's chooser does); None for no level (custom
    settings) or where nothing was measured."""
    found = (quality or table()).measurement(renderer, scene, level) if level is not None else None
    return found.level.replace(settings) if found is not None else None


def level_of(renderer: str, scene: SceneClass, settings: RenderSettings, quality: QualityTable | None = None,
             prefer: str | None = None) -> str | None:  # fmt: skip
    """The first level whose measured settings `settings` are for `renderer` on this scene class, else
    on another class of its volume kind (a TF edited into the other class keeps its level), or None
    (custom settings). `prefer` (the level the person chose) comes first: several levels can have
    the same settings (VTK's on meshes), and the first of them is not necessarily the one chosen."""
    quality = quality or table()
    scenes = [scene] + [s for s in quality.siblings(scene) if s != scene]
    pairs = [(s, level) for s in scenes for level in LEVELS]
    if prefer in LEVELS:
        pairs = [(s, prefer) for s in scenes] + pairs
    return next((level for s, level in pairs
                 if (m := quality.measurement(renderer, s, level)) is not None and m.level.matches(settings)),
                None)  # fmt: skip


def ranked(scene: SceneClass, level: str, names: Iterable[str], quality: QualityTable | None = None,
           speed_only: bool = False) -> list[str]:  # fmt: skip
    """The renderers among `names` measured at `level` on this scene class (never `NOT_AUTO`),
    fastest first by their time relative to VTK's default in the same runs over the scenes all of
    them were measured on (over all scenes where they share none); those that meet the level's
    bound first unless `speed_only` (the app's previews: speed whatever the error)."""
    quality = quality or table()
    check_level(level)
    wanted = set(names) - NOT_AUTO
    found = {
        n: m for n in quality.measured(scene) if n in wanted and (m := quality.measurement(n, scene, level))
    }
    if not found:
        return []
    common = set.intersection(*(set(m.ms) for m in found.values())) or set.union(
        *(set(m.ms) for m in found.values())
    )
    ratio = {n: m.time_ratio(common) for n, m in found.items()}
    return sorted(found, key=lambda n: (not speed_only and not found[n].meets, ratio[n]))


def choose_renderer(scene: SceneClass, level: str, tf_dim: int, settings: RenderSettings, names: Iterable[str],
                    quality: QualityTable | None = None,
                    can_draw: Callable[[str], bool] | None = None, cameras: Sequence[Camera] = (),
                    bounds: Sequence[float] | None = None, labels: bool = False,
                    channels: bool = False) -> tuple[str, str]:  # fmt: skip
    """(`auto`'s renderer, why) for a scene of this class, TF dimension and settings at `level`,
    among the registered `names`. Candidates are tried fastest first (`ranked`), so only the chosen
    renderer and the faster ones that cannot draw the scene are imported. `can_draw` replaces the
    capabilities test (the app has its own list). `cameras` (with the volume's `bounds`): the views
    to be drawn, every one of which the renderer must be able to draw
    (`Capabilities.camera_reason`: an eye inside the volume). `labels`: the scene is drawn by a
    label volume with a TF per label, so only renderers whose capabilities say `labels` take part,
    each checked with its level's settings as `resolve` gives them to it (`label_settings`).
    `channels`: several channels mixed, a TF each, so only renderers whose capabilities say
    `channels` take part, each checked at its level's settings without pre-integration
    (`channel_settings`)."""
    from volren.renderers.registry import registry

    quality = quality or table()
    names = [n for n in names if n not in NOT_AUTO]

    def drawable(name: str) -> bool:
        if can_draw is not None and not can_draw(name):
            return False
        try:
            capabilities = registry.capabilities(name)
        except VolrenError:  # a plugin that does not import: not a candidate (unless `can_draw` says so)
            return can_draw is not None
        if can_draw is None:
            level_settings = _with_level(quality.measurement(name, scene, level), settings)
            if labels:
                level_settings = label_settings(capabilities, scene.kind, level_settings)
            if channels:
                level_settings = channel_settings(capabilities, scene.kind, level_settings)
            if (
                capabilities.unsupported_reason(scene.kind, tf_dim, level_settings, labels, channels)
                is not None
            ):
                return False
        return bounds is None or all(
            capabilities.camera_reason(scene.kind, c, bounds) is None for c in cameras
        )

    measured = ranked(scene, level, names, quality)
    for name in measured:
        if drawable(name):
            tf = f" for a {scene.tf.value} TF" if scene.tf is not None else ""
            return name, f"the fastest measured at quality {level}{tf} that draws this scene"
    for name in names:
        if name not in measured and drawable(name):
            return name, f"no measured renderer draws this scene; {name} can"
    what = f"{scene.kind} scene" + (" with labels" if labels else " with channels" if channels else "")
    raise VolrenError(f"no registered renderer can draw this {what} (see `volren renderers`)")


def label_settings(capabilities: Capabilities, kind: str, settings: RenderSettings) -> RenderSettings:
    """The settings a renderer draws a label scene with: `settings` with pre-integration off where
    it draws labels but does not pre-integrate them (`KindSupport.labels_preintegration`). Why: a
    pre-integration table is built for one TF (RTVG section 4.5), and with a TF per label the
    renderer would need one per pair of labels meeting in a ray segment (section 16.5), which it
    does not build; the level's other settings (its step, its options) stay as measured. Where the
    renderer pre-integrates labels, or draws no labels (it is then refused for its own reason), as
    they are."""
    support = capabilities.kinds.get(kind)  # type: ignore[call-overload]
    if (
        support is not None
        and support.labels
        and not support.labels_preintegration
        and settings.preintegration
    ):
        return settings.with_(preintegration=False)
    return settings


def channel_settings(capabilities: Capabilities, kind: str, settings: RenderSettings) -> RenderSettings:
    """The settings a renderer mixes channels with: `settings` with pre-integration off where it
    mixes channels (`KindSupport.channels`). Why: a pre-integration table (RTVG section 4.5) is
    indexed by the scalar at a segment's two ends for one TF; with a TF per channel the segment's
    extinction is a sum over channels of integrals of each (Max 1995, section 2), which would need a
    table per channel and a sum of their exponents, which no renderer builds. The level's other
    settings stay as measured; a renderer that mixes no channels is refused for its own reason."""
    support = capabilities.kinds.get(kind)  # type: ignore[call-overload]
    if support is not None and support.channels and settings.preintegration:
        return settings.with_(preintegration=False)
    return settings


def resolve(scene: SceneClass, tf_dim: int, renderer: str, level: str | None, settings: RenderSettings,
            bricks: bool = False, cameras: Sequence[Camera] = (), bounds: Sequence[float] | None = None,
            labels: bool = False, channels: bool = False) -> tuple[str, RenderSettings, str | None]:  # fmt: skip
    """(renderer, settings, why): `auto` resolved at `level` (`default` when None), the level's
    measured settings applied (none when `level` is None; the caller's options win over the
    level's), and why `auto` chose its renderer (None when one was named). With `bricks`, `auto`
    chooses among the renderers that draw bricks (a bricked volume, a cluster); with `cameras` and
    the volume's `bounds`, among those that draw every one of those views. With `labels` (a label
    volume drawn with a TF per label, RTVG chapter 16), among those that draw labels; and the
    level's settings are applied with pre-integration off where the renderer draws labels but does
    not pre-integrate them (`label_settings`: no per-label pre-integration tables are built). With
    `channels` (several channels mixed, a TF each), among those that mix channels, with
    pre-integration off (`channel_settings`). The one place the CLI and the API turn a request into what is drawn."""
    from volren.renderers.registry import registry

    if level is not None:
        check_level(level)
    why = None
    if renderer == AUTO:
        names = registry.names()
        if bricks:
            names = [n for n in names if _draws_bricks(registry, n, scene.kind)]
        renderer, why = choose_renderer(scene, level or DEFAULT_LEVEL, tf_dim, settings, names, cameras=cameras,
                                        bounds=bounds, labels=labels, channels=channels)  # fmt: skip
    if level is not None:
        settings = _with_level(table().measurement(renderer, scene, level), settings)
        if labels or channels:
            try:
                capabilities = registry.capabilities(renderer)
            except VolrenError:  # an unknown renderer: refused, by name, where it is made
                capabilities = None
            if capabilities is not None and labels:
                settings = label_settings(capabilities, scene.kind, settings)
            if capabilities is not None and channels:
                settings = channel_settings(capabilities, scene.kind, settings)
    return renderer, settings, why


def _draws_bricks(registry, name: str, kind: str) -> bool:
    try:
        support = registry.capabilities(name).kinds.get(kind)
    except Exception:  # noqa: BLE001 - a plugin that fails to load draws nothing
        return False
    return bool(support is not None and support.regions)
