"""Render settings shared by every renderer (DESIGN.md's CLI flags map onto these fields)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field, fields, replace
from enum import StrEnum
from typing import Any

from volren.errors import VolrenError
from volren.model.clip_region import NO_CLIP, ClipRegion

#: Most samples a ray may take across a volume's diagonal at the chosen `step`. The renderers that
#: march (vtk, slicer, reference, plugins) silently draw a black image or run for hours far beyond
#: it (VTK and the slicer go blank near 700,000 samples); 100,000 is about a 512^3 grid at step
#: 0.009, the slicer's cap on slices, and still honoured by every renderer.
MAX_SAMPLES_PER_RAY = 100_000
#: Longest step, in characteristic lengths: past it every ray of any volume volren can hold takes
#: one sample or none, so a larger value is a typo (1e300), not a setting.
MAX_STEP = 1000.0


class BlendMode(StrEnum):
    """How samples along a ray combine."""

    COMPOSITE = "composite"  # emission-absorption, front to back
    MAXIMUM = "maximum"  # maximum intensity projection
    MINIMUM = "minimum"  # minimum intensity projection
    AVERAGE = "average"  # mean value along the ray

    @classmethod
    def parse(cls, value: str | BlendMode) -> BlendMode:
        aliases = {"max": "maximum", "mip": "maximum", "min": "minimum", "mean": "average"}
        text = str(value).lower()
        try:
            return cls(aliases.get(text, text))
        except ValueError:
            names = ", ".join(m.value for m in cls)
            raise VolrenError(f"unknown blend mode {value!r}; choose one of {names}") from None


@dataclass(frozen=True)
class RenderSettings:
    """Quality and appearance settings; renderer-specific extras go in `options`.

    `step` is the sample distance in units of the volume's characteristic length: the smallest
    voxel spacing for uniform grids (`UniformVolume.characteristic_length`), the mean tetrahedron
    edge for meshes. Shading parameters follow vtkVolumeProperty (and its defaults).
    """

    step: float = 0.5
    preintegration: bool = False
    shade: bool = False
    ambient: float = 0.1
    diffuse: float = 0.7
    specular: float = 0.2
    specular_power: float = 10.0
    blend_mode: BlendMode = BlendMode.COMPOSITE
    jitter: bool = False
    options: Mapping[str, Any] = field(default_factory=dict)
    #: The kept region (oblique planes and a crop box), rays clipped to it analytically; renderers
    #: whose capabilities say `clip_region` honour it, `render_frame` refuses the others.
    clip: ClipRegion = NO_CLIP

    def __post_init__(self) -> None:
        object.__setattr__(self, "blend_mode", BlendMode.parse(self.blend_mode))
        if not isinstance(self.options, Mapping) or not all(isinstance(k, str) for k in self.options):
            raise VolrenError(f"render setting options must map names to values, got {self.options!r:.80}")
        object.__setattr__(self, "options", dict(self.options))
        object.__setattr__(self, "clip", ClipRegion.from_dict(self.clip))
        for name in ("step", "ambient", "diffuse", "specular", "specular_power"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise VolrenError(f"render setting {name} must be a number, got {value!r}")
            if not is_finite(value) or value < 0 or (name == "step" and value == 0):
                bound = "positive" if name == "step" else ">= 0"
                raise VolrenError(f"render setting {name} must be finite and {bound}, got {value!r:.40}")
        if self.step > MAX_STEP:
            raise VolrenError(
                f"render setting step must be at most {MAX_STEP:g} (in voxel lengths), got {self.step!r}"
            )
        for name in ("preintegration", "shade", "jitter"):
            if not isinstance(getattr(self, name), bool):
                raise VolrenError(f"render setting {name} must be true or false, got {getattr(self, name)!r}")

    def with_(self, **changes: Any) -> RenderSettings:
        """A copy with some fields changed; unknown names are an error that lists the valid ones."""
        names = {f.name for f in fields(self)}
        unknown = set(changes) - names
        if unknown:
            raise VolrenError(f"unknown render settings {sorted(unknown)}; valid: {sorted(names)}")
        return replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        data = asdict(self)
        data["blend_mode"] = str(self.blend_mode)
        data["options"] = dict(self.options)
        if (
            not self.clip.planes and self.clip.box is None
        ):  # files without clipping stay as older versions wrote them
            del data["clip"]
        else:
            data["clip"] = self.clip.to_dict()
        return data

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> RenderSettings:
        if not isinstance(data, Mapping):
            raise VolrenError(f"render settings must be a JSON object, got {type(data).__name__}")
        return cls().with_(**dict(data))


def _round_up(x: float, digits: int = 3) -> float:
    """`x` rounded up to `digits` significant digits: a least step that, printed, is still enough."""
    unit = 10.0 ** (math.floor(math.log10(x)) - digits + 1)
    return math.ceil(x / unit) * unit


def is_finite(value: float) -> bool:
    """math.isfinite, False also for an integer too large for a float (10**400), which
    math.isfinite cannot convert."""
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def samples_per_ray(step: float, bounds: Sequence[float], unit: float) -> float:
    """How many samples of `step` (in units of `unit`, the volume's characteristic length) a ray
    along the diagonal of `bounds` (xmin, xmax, ymin, ymax, zmin, zmax) takes."""
    diagonal = math.hypot(*(bounds[2 * a + 1] - bounds[2 * a] for a in range(3)))
    if not unit > 0 or not step > 0:
        return 0.0  # a degenerate volume or step is refused elsewhere, with its own message
    return diagonal / unit / step


def check_step(step: float, bounds: Sequence[float], unit: float, name: str = "render setting step") -> None:
    """Refuse a step so small that a ray would take more than MAX_SAMPLES_PER_RAY samples: the
    renderers would otherwise draw a black image (or run for hours) and report success. `name` is
    what the caller calls the step (`--step` on the command line)."""
    samples = samples_per_ray(step, bounds, unit)
    if samples > MAX_SAMPLES_PER_RAY:
        least = _round_up(step * samples / MAX_SAMPLES_PER_RAY)
        raise VolrenError(
            f"{name} {step:g} would take about {samples:.3g} samples per ray across this volume; "
            f"at most {MAX_SAMPLES_PER_RAY:,} are allowed (a step of at least {least:.3g})"
        )
