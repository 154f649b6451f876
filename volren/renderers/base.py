"""The renderer contract: what every renderer (built-in or plugin) provides.

The whole contract, in prose, is `docs/renderer-contract.md` in the repository: the optical
model, units, camera, output, capabilities, options, progress and cancellation, threads,
`release()` and counters. `volren check-renderer NAME` (the kit in `volren.testing`) checks it.

A renderer holds a volume, a transfer function and settings, and turns a camera into an image:
``render(camera, width, height)`` returns a float32 (H, W, 4) array of premultiplied linear RGBA
composited over black, row 0 at the top. Renderers never see files or PyVista objects, only
`volren.model` objects.

Third parties implement `Renderer` (most simply by subclassing `RendererBase`) and register the
class under the entry-point group ``volren.renderers``. Callers go through `render_frame`, which
checks what a renderer returns, so a renderer that follows the Protocol without subclassing
`RendererBase` works everywhere.
"""

from __future__ import annotations

import math
import threading
import time
from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, ClassVar, Literal, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.channels import ChannelTransferFunction
from volren.model.labels import LabelTransferFunction
from volren.model.option_rule import OptionRule
from volren.model.progress import ProgressCallback
from volren.model.region import Region
from volren.model.settings import BlendMode, RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TransferFunction, TransferFunction2D
from volren.model.volume import Volume, VolumeKind

MAX_IMAGE_SIDE = 16384
#: How far outside the bounds, as a fraction of their largest side, an eye still counts as inside.
EYE_INSIDE_MARGIN = 1e-6


def eye_inside_bounds(camera: Camera, bounds: Sequence[float]) -> bool:
    """Whether a perspective camera's eye lies inside `bounds` (xmin, xmax, ymin, ymax, zmin, zmax),
    faces included, within `EYE_INSIDE_MARGIN`: where rays start inside the volume."""
    if camera.parallel:
        return False
    lo = np.asarray(bounds[0::2], dtype=np.float64)
    hi = np.asarray(bounds[1::2], dtype=np.float64)
    margin = EYE_INSIDE_MARGIN * float(np.max(hi - lo))
    eye = np.asarray(camera.position, dtype=np.float64)
    return bool(np.all(eye >= lo - margin) and np.all(eye <= hi + margin))


def clipping_planes_cut(camera: Camera, bounds: Sequence[float]) -> bool:
    """Whether the camera's near or far plane passes through the box `bounds` (an eye inside it
    included), beyond `EYE_INSIDE_MARGIN` of the depth range of its corners."""
    d0, d1 = camera.depth_range(bounds)
    margin = EYE_INSIDE_MARGIN * max(d1 - d0, float(np.max(np.subtract(bounds[1::2], bounds[0::2]))))
    near, far = camera.clipping_range
    return bool(d0 + margin < near < d1 - margin or d0 + margin < far < d1 - margin)


OptionKind = Literal["bool", "int", "float", "str", "choice"]
OPTION_KINDS: tuple[OptionKind, ...] = ("bool", "int", "float", "str", "choice")
#: The longest shown form of a refused value in an error message.
SHOWN_VALUE_CHARS = 60


@dataclass(frozen=True)
class OptionSpec:
    """One renderer option, declared once: parsing, validation, the error messages and the help
    text (`option_help`, the CLI's `volren renderers`) all come from it.

    `kind` is what a given value must be: bool (true/false only), int (not a bool, not 2.0), float
    (an int or a float, finite, returned as float), str, or choice (one of `choices`, of the same
    type). `low` and `high` bound ints and floats (inclusive; `low_exclusive` makes low open);
    `words` are strings accepted as they are besides the kind's values ('auto': chosen per frame);
    `rule` adds a test the range cannot say. A default of None means "chosen by the renderer"
    (by volume kind, say) and is never a value a caller may give.
    """

    name: str
    default: Any
    kind: OptionKind
    help: str
    low: float | None = None
    high: float | None = None
    low_exclusive: bool = False
    choices: tuple[Any, ...] = ()
    words: tuple[str, ...] = ()
    rule: OptionRule | None = None

    def __post_init__(self) -> None:
        if self.kind not in OPTION_KINDS:
            raise VolrenError(
                f"option {self.name}: kind must be one of {', '.join(OPTION_KINDS)}, got {self.kind!r}"
            )
        if (self.kind == "choice") != bool(self.choices):
            raise VolrenError(f"option {self.name}: choices go with kind 'choice' and only with it")
        if self.low_exclusive and self.kind != "float":
            raise VolrenError(f"option {self.name}: only a float option has an exclusive low bound")
        if self.default is not None and not self._accepts(self.default):
            raise VolrenError(f"option {self.name}: the default {self.default!r} is not {self.allowed()}")

    def _accepts(self, value: Any) -> bool:
        """Whether `value` parses to itself."""
        try:
            return bool(self.parse(value, "") == value)
        except VolrenError:
            return False

    def allowed(self) -> str:
        """The values this option accepts, in words: "an integer in 16..4096"."""
        text = self.rule.allowed if self.rule is not None else self._kind_text()
        return " or ".join([*(repr(w) for w in self.words), text])

    def _kind_text(self) -> str:
        if self.kind == "bool":
            return "true or false"
        if self.kind == "str":
            return "a string"
        if self.kind == "choice":
            return "one of " + ", ".join(repr(c) for c in self.choices)
        return ("an integer" if self.kind == "int" else "a number") + self._range_text()

    def _range_text(self) -> str:
        """ " in 16..4096", " in (0, 1]", " >= 0", or "" for no bounds."""
        lo, hi = self.low, self.high
        if lo is not None and hi is not None:
            if self.kind == "int":
                return f" in {lo}..{hi}"
            return f" in {'(' if self.low_exclusive else '['}{lo:g}, {hi:g}]"
        if lo is not None:
            return f" {'>' if self.low_exclusive else '>='} {lo:g}"
        return "" if hi is None else f" <= {hi:g}"

    def parse(self, value: Any, renderer: str) -> Any:
        """`value` as this option's kind (an int given to a float option becomes a float), or a
        one-line VolrenError naming the renderer and the option and saying what is allowed."""
        if isinstance(value, str) and value in self.words:
            return value
        parsed = self._parse_kind(value)
        if parsed is _REFUSED or (self.rule is not None and not self.rule.test(parsed)):
            where = f"renderer {renderer}: " if renderer else ""
            raise VolrenError(f"{where}option {self.name} must be {self.allowed()}, got {_shown(value)}")
        return parsed

    def _parse_kind(self, value: Any) -> Any:
        if self.kind == "bool":
            return value if isinstance(value, bool) else _REFUSED
        if self.kind == "str":
            return value if isinstance(value, str) else _REFUSED
        if self.kind == "choice":
            return value if any(type(value) is type(c) and value == c for c in self.choices) else _REFUSED
        number = int | float if self.kind == "float" else int
        if isinstance(value, bool) or not isinstance(value, number) or not self._in_range(value):
            return _REFUSED
        if self.kind == "int":
            return value
        try:
            as_float = float(value)
        except OverflowError:  # an int beyond the float range
            return _REFUSED
        return as_float if math.isfinite(as_float) else _REFUSED

    def _in_range(self, value: float) -> bool:
        """Exact comparison (ints of any size against float bounds); NaN is in no range."""
        if value != value:
            return False
        if self.low is not None and (value <= self.low if self.low_exclusive else value < self.low):
            return False
        return self.high is None or value <= self.high

    def describe(self) -> str:
        """The help line: what it does, what it accepts, its default."""
        default = "" if self.default is None else f"; default {_shown_default(self.default)}"
        return f"{self.help} [{self.allowed()}{default}]"


#: What `OptionSpec._parse_kind` returns for a value of the wrong kind or out of range.
_REFUSED = object()


def _shown(value: Any) -> str:
    """A refused value as an error message shows it: repr, cut short (a huge int has its digits
    counted, since Python refuses to write ints of over 4300 digits)."""
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 128:
        return f"an integer of about {int(value.bit_length() * math.log10(2)) + 1} digits"
    text = repr(value)
    return text if len(text) <= SHOWN_VALUE_CHARS else text[: SHOWN_VALUE_CHARS - 3] + "..."


def _shown_default(value: Any) -> str:
    """A default as the CLI's `--option KEY=VALUE` takes it (JSON): true, 256, auto."""
    if isinstance(value, bool):
        return "true" if value else "false"
    return f"{value:g}" if isinstance(value, float) else str(value)


def option_help_of(specs: Sequence[OptionSpec]) -> dict[str, str]:
    """The `option_help` mapping derived from a renderer's option specs: name -> help line."""
    return {spec.name: spec.describe() for spec in specs}


def parse_options(renderer: str, specs: Sequence[OptionSpec], options: Mapping[str, Any]) -> dict[str, Any]:
    """Every declared option: the given value parsed (`OptionSpec.parse`) or the default; an
    option not declared is a one-line VolrenError listing the valid ones."""
    known = {spec.name: spec for spec in specs}
    unknown = [key for key in options if key not in known]
    if unknown:
        valid = ", ".join(sorted(known)) or "none"
        raise VolrenError(f"renderer {renderer} has no option(s) {sorted(map(str, unknown))}; valid: {valid}")
    return {name: spec.parse(options[name], renderer) if name in options else spec.default
            for name, spec in known.items()}  # fmt: skip


@dataclass(frozen=True)
class Accuracy:
    """How close a renderer's images come to the exact ones at its default quality, as it claims.

    The conformance kit holds the renderer to these numbers and never widens them: `rmse` bounds
    DESIGN.md's error metric (RMSE over pixels and the four RGBA channels) against the kit's closed
    forms; `position_px` bounds how far, in pixels, a small feature may land from where the camera
    contract puts it.
    """

    rmse: float = 0.01
    position_px: float = 0.25

    def __post_init__(self) -> None:
        for name in ("rmse", "position_px"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value >= 0):
                raise VolrenError(f"accuracy {name} must be a finite number >= 0, got {value!r}")


@dataclass(frozen=True)
class QualityLevel:
    """One setting on a renderer's quality axis: what it changes from the caller's settings."""

    label: str
    step: float | None = None
    preintegration: bool | None = None
    options: Mapping[str, Any] = field(default_factory=dict)

    def apply(self, settings: RenderSettings | None = None) -> RenderSettings:
        """`settings` (default: the defaults) with this level's changes."""
        settings = settings or RenderSettings()
        changes: dict[str, Any] = {}
        if self.step is not None:
            changes["step"] = self.step
        if self.preintegration is not None:
            changes["preintegration"] = self.preintegration
        if self.options:
            changes["options"] = {**settings.options, **self.options}
        return settings.with_(**changes)

    def replace(self, settings: RenderSettings) -> RenderSettings:
        """`settings` with this level's step and pre-integration and exactly its options (a level
        picked in the app's chooser replaces the options of the one before)."""
        return self.apply(settings.with_(options={}))

    def matches(self, settings: RenderSettings) -> bool:
        """Whether `settings` are at this level: its step and pre-integration where it sets them,
        and exactly its options."""
        return ((self.step is None or settings.step == self.step)
                and (self.preintegration is None or settings.preintegration == self.preintegration)
                and dict(settings.options) == dict(self.options))  # fmt: skip


@dataclass(frozen=True)
class KindSupport:
    """What a renderer can do with one kind of volume, and how accurately at default quality."""

    tf_dims: frozenset[int] = frozenset({1})
    preintegration: bool = False
    shading: bool = False
    blend_modes: frozenset[BlendMode] = frozenset({BlendMode.COMPOSITE})
    #: The blend modes available with a 2D TF (where 2 is in tf_dims): maximum / minimum /
    #: average project the value alone, which leaves no gradient to look a 2D TF up with.
    blend_modes_2d: frozenset[BlendMode] = frozenset({BlendMode.COMPOSITE})
    #: Pre-integration of 2D TFs (a 4D table over value and gradient pairs: nobody has one yet).
    preintegration_2d: bool = False
    #: What the renderer promises on this kind at default settings (checked by the kit).
    accuracy: Accuracy = field(default_factory=Accuracy)
    #: Draws a brick's share of a whole volume (`set_region`, composite blending), so that layers
    #: composited front to back equal the whole render (the kit's `bricks` check).
    regions: bool = False
    #: Draws perspective views whose eye lies inside the volume's bounds (a fly-through, an
    #: endoscopic view; the kit's `eye_inside` check). False: such a frame is refused with a one-line
    #: VolrenError before the renderer runs, and `auto` passes the renderer over for such a view.
    eye_inside: bool = True
    #: Honours near and far planes that cut the volume (a camera zoomed into it, planes placed by
    #: hand; the kit's `clip` check). False: such a frame is refused like an eye inside.
    clipping: bool = True
    #: Honours `RenderSettings.clip` (oblique planes and a crop box), each ray clipped to the kept
    #: region analytically (the kit's `clip_region` check). False: a clipped scene is refused with a
    #: one-line VolrenError, and `auto` passes the renderer over for it.
    clip_region: bool = False
    #: Draws the cut faces opaque when the clip region asks for it (`ClipRegion.cap`; the kit's
    #: `clip_cap` check). False: such a scene is refused and passed over as above.
    clip_cap: bool = False
    #: Draws a volume's label map with a `LabelTransferFunction` (a TF per label, blended across
    #: label boundaries: `volren.model.labels`; the kit's `labels` check). False: such a scene is
    #: refused with a one-line VolrenError, and `auto` passes the renderer over for it.
    labels: bool = False
    #: Pre-integrates label scenes too; False: a label scene with pre-integration on is refused.
    labels_preintegration: bool = False
    #: Mixes a volume's channels with a `ChannelTransferFunction` (a TF per channel, their
    #: extinctions and emissions added: `volren.model.channels`; the kit's `channels` check).
    #: False: refused and passed over as labels are. Post-classified (no pre-integration) only.
    channels: bool = False


@dataclass(frozen=True)
class Capabilities:
    """The volume kinds a renderer accepts and, per kind, what it supports."""

    kinds: Mapping[VolumeKind, KindSupport]
    backend: str = "cpu"
    summary: str = ""
    #: The quality axis, fast to accurate, that `volren bench run` sweeps (empty: defaults only).
    quality: tuple[QualityLevel, ...] = ()
    #: Options that make a new transfer function cheap to apply (a smaller pre-integration
    #: table), added by the app to its preview frames while a TF is dragged; the still frame after
    #: the drag uses the user's settings. Empty: TF changes are cheap already.
    tf_drag_options: Mapping[str, Any] = field(default_factory=dict)
    #: Options the app sets on every still frame (the frame after a gesture, a screenshot, a
    #: movie): image-space refinement off, so a still frame samples every pixel and never
    #: interpolates across a feature thinner than the refinement's stride (previews may).
    still_frame_options: Mapping[str, Any] = field(default_factory=dict)

    @property
    def volume_kinds(self) -> frozenset[str]:
        return frozenset(self.kinds)

    def unsupported_reason(
        self,
        volume_kind: str,
        tf_dim: int = 1,
        settings: RenderSettings | None = None,
        labels: bool = False,
        channels: bool = False,
    ) -> str | None:
        """Why this renderer cannot draw such a scene (`labels`: drawn by a label map with a TF per
        label; `channels`: several channels mixed, a TF each), or None when it can."""
        support = self.kinds.get(volume_kind)  # type: ignore[call-overload]
        if support is None:
            kinds = ", ".join(sorted(self.kinds)) or "none"
            return f"does not render {volume_kind} volumes (only {kinds})"
        if tf_dim not in support.tf_dims:
            return f"does not support {tf_dim}D transfer functions on {volume_kind} volumes"
        if labels and not support.labels:
            return f"does not draw label volumes (a transfer function per label) on {volume_kind} volumes"
        if labels and settings is not None and settings.preintegration and not support.labels_preintegration:
            return f"has no pre-integration with label volumes on {volume_kind} volumes"
        if channels and not support.channels:
            return f"does not mix channels (a transfer function per channel) on {volume_kind} volumes"
        if channels and settings is not None and settings.preintegration:
            return f"has no pre-integration of several channels on {volume_kind} volumes"
        if settings is not None:
            if settings.preintegration and not support.preintegration:
                return f"has no pre-integration for {volume_kind} volumes"
            if settings.preintegration and tf_dim == 2 and not support.preintegration_2d:
                return f"has no pre-integration of 2D transfer functions on {volume_kind} volumes"
            if settings.shade and not support.shading:
                return f"has no shading for {volume_kind} volumes"
            if not settings.clip.is_empty and not support.clip_region:
                return f"does not clip {volume_kind} volumes to planes or a crop box"
            if settings.clip.caps and not support.clip_cap:
                return f"does not draw cut faces (clip caps) on {volume_kind} volumes"
            if settings.blend_mode not in support.blend_modes:
                modes = ", ".join(sorted(str(m) for m in support.blend_modes))
                return f"has no {settings.blend_mode} blend mode for {volume_kind} volumes (only {modes})"
            if tf_dim == 2 and settings.blend_mode not in support.blend_modes_2d:
                modes = ", ".join(sorted(str(m) for m in support.blend_modes_2d & support.blend_modes))
                return (
                    f"has no {settings.blend_mode} blend mode with 2D transfer functions on {volume_kind} "
                    f"volumes (only {modes})"
                )
        return None

    def camera_reason(self, volume_kind: str, camera: Camera, bounds: Sequence[float]) -> str | None:
        """Why this renderer cannot draw a volume with these `bounds` from `camera`, or None."""
        support = self.kinds.get(volume_kind)  # type: ignore[call-overload]
        if support is None:
            return None
        if not support.eye_inside and eye_inside_bounds(camera, bounds):
            return (
                f"cannot draw a perspective view from inside the {volume_kind} volume's bounds: move the camera "
                "out, use a parallel projection or another renderer"
            )
        if not support.clipping and clipping_planes_cut(camera, bounds):
            return (
                f"cannot draw a view whose near or far plane cuts the {volume_kind} volume: move the camera "
                "back, widen the clipping range or use another renderer"
            )
        return None

    def describe(self) -> str:
        parts = []
        for kind, s in sorted(self.kinds.items()):
            extras = [f"{'/'.join(str(d) for d in sorted(s.tf_dims))}D TF"]
            if s.preintegration:
                extras.append("pre-integration")
            if s.shading:
                extras.append("shading")
            if s.regions:
                extras.append("bricks")
            if s.clip_region:
                extras.append("clip planes" + (" and cut faces" if s.clip_cap else ""))
            if s.labels:
                extras.append("labels")
            if s.channels:
                extras.append("channels")
            extras.append("blend " + "/".join(sorted(str(m) for m in s.blend_modes)))
            modes_2d = s.blend_modes_2d & s.blend_modes
            if 2 in s.tf_dims and modes_2d != s.blend_modes:
                extras.append("2D TF blend " + ("/".join(sorted(str(m) for m in modes_2d)) or "none"))
            parts.append(f"{kind} ({', '.join(extras)})")
        return "; ".join(parts)


@dataclass(frozen=True)
class FrameStats:
    """What the last frame cost: time, and renderer-specific work counters."""

    ms: float
    width: int
    height: int
    counters: Mapping[str, float] = field(default_factory=dict)


@runtime_checkable
class Renderer(Protocol):
    """The structural contract a renderer class satisfies (docs/renderer-contract.md).

    Everything callers use is here: `volren render`, the app and the bench need nothing else.
    `last_frame` is None until the first frame and then describes the latest one.
    """

    name: ClassVar[str]
    capabilities: ClassVar[Capabilities]
    options: ClassVar[tuple[OptionSpec, ...]]
    option_help: ClassVar[Mapping[str, str]]
    last_frame: FrameStats | None

    def set_volume(self, volume: Volume) -> None: ...

    def set_transfer_function(
        self, tf: TransferFunction | LabelTransferFunction | ChannelTransferFunction
    ) -> None: ...

    def set_settings(self, settings: RenderSettings) -> None: ...

    def render(
        self, camera: Camera, width: int, height: int, progress: ProgressCallback | None = None
    ) -> NDArray[np.float32]: ...

    def release(self) -> None: ...


#: One renderer at a time works in a process (a frame, or the set-up after a new volume, TF or
#: settings). The kernels release the interpreter's lock (numba `nogil`), so the app's GUI thread
#: runs while a frame is drawn; but numba's `workqueue` threading layer (used where neither TBB nor
#: OpenMP loads) aborts the process when two threads launch parallel kernels at once (the app's
#: render thread and a screenshot or movie job), and two frames at once gain nothing on shared cores.
_ONE_AT_A_TIME = threading.RLock()


class RendererBase(ABC):
    """State keeping, validation and timing shared by renderers; subclasses implement `_render`.

    Subclasses may override the `_volume_changed`, `_tf_changed` and `_settings_changed` hooks to
    invalidate only what an edit affects.
    """

    name: ClassVar[str] = ""
    capabilities: ClassVar[Capabilities]

    #: The renderer's options (RenderSettings.options), declared once; `set_settings` parses them
    #: and `opts` holds the parsed values.
    options: ClassVar[tuple[OptionSpec, ...]] = ()
    #: Derived from `options` for every subclass: name -> help line.
    option_help: ClassVar[Mapping[str, str]] = {}

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "option_help" in vars(cls):
            raise VolrenError(f"renderer class {cls.__name__} sets option_help: declare `options` (OptionSpec) "
                              "instead, option_help is derived from them")  # fmt: skip
        cls.option_help = MappingProxyType(option_help_of(cls.options))

    def __init__(self) -> None:
        self._volume: Volume | None = None
        self._tf: TransferFunction | LabelTransferFunction | ChannelTransferFunction | None = None
        self._settings = RenderSettings()
        self._opts = self._parse_options(self._settings.options)
        self._region: Region | None = None
        self._released = False
        self.last_frame: FrameStats | None = None

    # ------------------------------------------------------------------------- state
    @property
    def volume(self) -> Volume | None:
        return self._volume

    @property
    def transfer_function(self) -> TransferFunction | LabelTransferFunction | ChannelTransferFunction | None:
        return self._tf

    @property
    def settings(self) -> RenderSettings:
        return self._settings

    @property
    def region(self) -> Region | None:
        return self._region

    @property
    def opts(self) -> Mapping[str, Any]:
        """The current settings' options, parsed: every declared option, defaults filled in."""
        return self._opts

    def set_volume(self, volume: Volume) -> None:
        self._check_alive()
        reason = self.capabilities.unsupported_reason(volume.kind)
        if reason:
            raise VolrenError(f"renderer {self.name} {reason}")
        self._volume = volume
        with _ONE_AT_A_TIME:
            self._volume_changed()

    def set_transfer_function(
        self, tf: TransferFunction | LabelTransferFunction | ChannelTransferFunction
    ) -> None:
        """Use `tf` (a TransferFunction1D or TransferFunction2D, or a LabelTransferFunction where the
        capabilities say `labels`); a TF this renderer cannot draw (on the current volume's kind, or
        on any kind before a volume is set) is refused."""
        self._check_alive()
        if not isinstance(
            tf, TransferFunction1D | TransferFunction2D | LabelTransferFunction | ChannelTransferFunction
        ):
            raise VolrenError(
                f"renderer {self.name} needs a TransferFunction1D or TransferFunction2D, got {type(tf).__name__}"
            )
        labels, channels = isinstance(tf, LabelTransferFunction), isinstance(tf, ChannelTransferFunction)
        if self._volume is not None:
            reason = self.capabilities.unsupported_reason(
                self._volume.kind, tf.dims, labels=labels, channels=channels
            )
        elif not any(tf.dims in support.tf_dims for support in self.capabilities.kinds.values()):
            reason = f"does not support {tf.dims}D transfer functions"
        elif labels and not any(support.labels for support in self.capabilities.kinds.values()):
            reason = "does not draw label volumes (a transfer function per label)"
        elif channels and not any(support.channels for support in self.capabilities.kinds.values()):
            reason = "does not mix channels (a transfer function per channel)"
        else:
            reason = None
        if reason:
            raise VolrenError(f"renderer {self.name} {reason}")
        self._tf = tf
        with _ONE_AT_A_TIME:
            self._tf_changed()

    def set_settings(self, settings: RenderSettings) -> None:
        self._check_alive()
        opts = self._parse_options(settings.options)
        self._settings, self._opts = settings, opts
        with _ONE_AT_A_TIME:
            self._settings_changed()

    def set_region(self, region: Region | None) -> None:
        """Draw only `region`'s share of the whole volume (the volume is then the brick's
        sub-volume with ghost voxels); None draws the volume whole again. Offered where the
        capabilities say `regions`."""
        self._check_alive()
        if region is not None:
            if not isinstance(region, Region):
                raise VolrenError(f"renderer {self.name} needs a Region, got {type(region).__name__}")
            if not any(support.regions for support in self.capabilities.kinds.values()):
                raise VolrenError(f"renderer {self.name} does not draw bricks (regions)")
        self._region = region
        with _ONE_AT_A_TIME:
            self._region_changed()

    def _whole_value_range(self) -> tuple[float, float]:
        """The value range that normalisations and thresholds use: the whole volume's while a
        region is set, so that every brick computes them alike; else the volume's own."""
        if self._region is not None:
            return self._region.value_range
        return self._volume.value_range  # type: ignore[union-attr]

    def ghost_voxels(
        self, spacing: tuple[float, float, float], camera: Camera, width: int, height: int
    ) -> int:
        """How many voxels beyond a region's box, per face, a frame with these settings reads from
        a volume of this voxel `spacing`: the caller cuts sub-volumes with at least this many. One
        covers trilinear values and central-difference gradients at points inside the box."""
        return 1

    def _parse_options(self, options: Mapping[str, Any]) -> Mapping[str, Any]:
        """`options` parsed against `self.options` (`parse_options`), read-only. A renderer with a
        rule across options (two valid values it cannot draw together) extends this."""
        return MappingProxyType(parse_options(self.name, self.options, options))

    def _volume_changed(self) -> None:
        """Hook: the volume was replaced."""

    def _tf_changed(self) -> None:
        """Hook: the transfer function was replaced (edits bump tf.version instead)."""

    def _settings_changed(self) -> None:
        """Hook: the settings were replaced."""

    def _region_changed(self) -> None:
        """Hook: the region was set or cleared."""

    # ------------------------------------------------------------------------ render
    def render(
        self, camera: Camera, width: int, height: int, progress: ProgressCallback | None = None
    ) -> NDArray[np.float32]:
        """Render one frame: float32 (H, W, 4) premultiplied RGBA over black, row 0 at the top."""
        self._check_alive()
        width, height = int(width), int(height)
        if not (1 <= width <= MAX_IMAGE_SIDE and 1 <= height <= MAX_IMAGE_SIDE):
            raise VolrenError(f"image size must lie in 1..{MAX_IMAGE_SIDE} per side, got {width}x{height}")
        if self._volume is None:
            raise VolrenError(f"renderer {self.name}: no volume set")
        if self._tf is None:
            raise VolrenError(f"renderer {self.name}: no transfer function set")
        labels, channels = (
            isinstance(self._tf, LabelTransferFunction),
            isinstance(self._tf, ChannelTransferFunction),
        )
        reason = self.capabilities.unsupported_reason(
            self._volume.kind, self._tf.dims, self._settings, labels, channels
        )
        if labels and getattr(self._volume, "labels", None) is None:
            reason = (
                f"was given a transfer function per label, but the volume {self._volume.name!r} has no labels"
            )
        given = getattr(self._volume, "channels", None)
        if isinstance(self._tf, ChannelTransferFunction) and (given is None or given.count != self._tf.count):
            have = "no channels" if given is None else f"{given.count} channels"
            reason = (
                f"was given a transfer function for {self._tf.count} channels, but the volume "
                f"{self._volume.name!r} has {have}"
            )
        reason = reason or self.capabilities.camera_reason(self._volume.kind, camera, self._volume.bounds)
        if reason:
            raise VolrenError(f"renderer {self.name} {reason}")
        if self._region is not None:
            self._check_region(self._region)
        with _ONE_AT_A_TIME:
            start = time.perf_counter()
            image, counters = self._render(camera, width, height, progress)
            ms = (time.perf_counter() - start) * 1000.0
        if image.shape != (height, width, 4) or image.dtype != np.float32:
            raise RuntimeError(
                f"renderer {self.name} returned {image.dtype} {image.shape}, expected float32 {(height, width, 4)}"
            )
        self.last_frame = FrameStats(ms, width, height, dict(counters))
        return image

    def _check_region(self, region: Region) -> None:
        """A region needs a uniform sub-volume covering its owner box (within the whole box), and
        composite blending (maximum, minimum and average layers do not composite by "over")."""
        volume = self._volume
        support = self.capabilities.kinds.get(volume.kind)  # type: ignore[union-attr]
        if support is None or not support.regions:
            raise VolrenError(f"renderer {self.name} does not draw bricks (regions) of {volume.kind} volumes")  # type: ignore[union-attr]
        if self._settings.blend_mode != BlendMode.COMPOSITE:
            raise VolrenError(
                f"renderer {self.name}: bricks composite only with the composite blend mode, not {self._settings.blend_mode}"
            )
        bounds = np.asarray(volume.bounds, dtype=np.float64)  # type: ignore[union-attr]
        lo, hi = region.box
        slack = 1e-6 * max(float(np.ptp(np.asarray(region.whole_bounds).reshape(3, 2), axis=1).max()), 1.0)
        if np.any(lo < bounds[0::2] - slack) or np.any(hi > bounds[1::2] + slack):
            raise VolrenError(
                f"renderer {self.name}: the region's box {tuple(lo)}..{tuple(hi)} is not inside the sub-volume's "
                f"bounds {tuple(bounds)}"
            )

    @abstractmethod
    def _render(
        self, camera: Camera, width: int, height: int, progress: ProgressCallback | None
    ) -> tuple[NDArray[np.float32], Mapping[str, float]]:
        """Draw a frame; return the image and work counters (e.g. samples taken)."""

    def release(self) -> None:
        """Free every GPU/VTK resource; the renderer cannot render afterwards."""
        self._released = True

    def _check_alive(self) -> None:
        if self._released:
            raise VolrenError(f"renderer {self.name} was released")

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.release()


def render_frame(
    renderer: Renderer,
    camera: Camera,
    width: int,
    height: int,
    progress: ProgressCallback | None = None,
    label: str | None = None,
) -> tuple[NDArray[np.float32], FrameStats]:
    """One frame through the Protocol, checked: the image (float32 (H, W, 4)) and its FrameStats.

    Why: callers may hold any renderer that follows the Protocol, so what comes back is checked
    here once instead of trusted; a renderer that breaks the contract is a one-line VolrenError.
    """
    name = label or getattr(renderer, "name", "") or type(renderer).__name__
    image = renderer.render(camera, width, height, progress)
    if not isinstance(image, np.ndarray) or image.shape != (height, width, 4) or image.dtype != np.float32:
        got = f"{image.dtype} {image.shape}" if isinstance(image, np.ndarray) else type(image).__name__
        raise VolrenError(f"renderer {name} returned {got}, expected float32 {(height, width, 4)}")
    stats = getattr(renderer, "last_frame", None)
    if not isinstance(stats, FrameStats) or (stats.width, stats.height) != (width, height):
        raise VolrenError(
            f"renderer {name} did not describe its frame in last_frame (a FrameStats of {width}x{height})"
        )
    return image, stats
