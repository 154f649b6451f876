"""Segmented volumes: a label at every grid point and a transfer function per label.

The optical model with labels (Real-Time Volume Graphics, chapter 16: per-object transfer
functions, and the boundary filtering of section 16.5). A label is not a number to interpolate:
at a point x of a cell, label l has the weight w_l(x), the trilinear interpolant of the indicator
"the corner's label is l" over the cell's eight corners (the weights sum to 1). Each label has a
1D transfer function (its own, or the volume's recoloured and scaled), giving an extinction
tau_l(s) and a colour c_l(s) of the interpolated scalar s(x) as in DESIGN.md. Then

    tau(x) = sum_l w_l(x) tau_l(s(x)),     q(x) = sum_l w_l(x) c_l(s(x)) tau_l(s(x)),

which is again DESIGN.md's emission-absorption model, so every renderer integrates it as before. A
cell whose eight corners agree uses its label's TF alone (the fast path); between labels the
classified samples blend, so a sphere of one label inside another has a smooth surface (near
w = 1/2), not voxel stairs. A hidden label has tau = 0: it takes its share of the weight and adds
nothing.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any, ClassVar, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from volren.errors import VolrenError
from volren.model.file_version import check_format_version
from volren.model.transfer_function import MAX_OPACITY, TransferFunction1D
from volren.model.versioned import Versioned

#: The largest label value: label volumes are stored as uint16 (uint8 where every label fits).
MAX_LABEL = 65_535
LABEL_TF_FORMAT_VERSION = 1
#: The most label styles that draw differently (renderers keep a table per class and a 16-bit class per cell).
MAX_CLASSES = 32_000
#: Colours given to labels that bring none (a file without colours): twenty that stay apart on
#: screen (the categorical palette of matplotlib's tab20, darker and lighter pairs interleaved).
PALETTE: tuple[tuple[float, float, float], ...] = tuple(
    (int(h[0:2], 16) / 255.0, int(h[2:4], 16) / 255.0, int(h[4:6], 16) / 255.0)
    for h in (
        "1f77b4", "ff7f0e", "2ca02c", "d62728", "9467bd", "8c564b", "e377c2", "7f7f7f", "bcbd22", "17becf",
        "aec7e8", "ffbb78", "98df8a", "ff9896", "c5b0d5", "c49c94", "f7b6d2", "c7c7c7", "dbdb8d", "9edae5",
    )
)  # fmt: skip


def _label_array(values: ArrayLike, what: str) -> NDArray[np.uint8] | NDArray[np.uint16]:
    """`values` as uint8 or uint16 labels, refused (one line naming `what`) where they are not
    whole numbers in 0..MAX_LABEL."""
    arr = np.asarray(values)
    if arr.dtype == np.bool_:
        arr = arr.astype(np.uint8)
    if not (np.issubdtype(arr.dtype, np.integer) or np.issubdtype(arr.dtype, np.floating)):
        raise VolrenError(f"{what}: labels must be integers, got {arr.dtype}")
    if arr.size == 0:
        raise VolrenError(f"{what}: the label volume is empty")
    if np.issubdtype(arr.dtype, np.floating):
        if not np.all(np.isfinite(arr)) or not np.array_equal(arr, np.round(arr)):
            raise VolrenError(f"{what}: labels must be whole numbers (found fractions, NaN or Inf)")
    lo, hi = arr.min(), arr.max()
    if lo < 0 or hi > MAX_LABEL:
        raise VolrenError(f"{what}: labels must lie in 0..{MAX_LABEL}, found {int(lo)}..{int(hi)}")
    if hi <= 255:
        return np.ascontiguousarray(arr, dtype=np.uint8)
    return np.ascontiguousarray(arr, dtype=np.uint16)


def parse_label(value: object, what: str) -> int:
    """A label: a whole number in 0..MAX_LABEL (an int, or its digits as text); else one line naming `what`."""
    if isinstance(value, str) and value.strip().isdigit():
        value = int(value.strip())
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= MAX_LABEL:
        raise VolrenError(f"{what}: a label is a whole number in 0..{MAX_LABEL}, got {value!r}")
    return value


def _rgb(value: Any, what: str) -> tuple[float, float, float]:
    arr = np.asarray(value, dtype=np.float64).reshape(-1) if value is not None else np.zeros(0)
    if arr.size != 3 or not np.all(np.isfinite(arr)) or arr.min() < 0 or arr.max() > 1:
        raise VolrenError(f"{what}: a colour is three numbers in [0, 1], got {value!r}")
    return (float(arr[0]), float(arr[1]), float(arr[2]))


@dataclass(frozen=True, eq=False)
class LabelMap:
    """A label per grid point, on the intensity volume's grid (``values[k, j, i]``), with the names
    and colours its file gave (empty where none)."""

    values: NDArray[Any]
    names: Mapping[int, str] = field(default_factory=dict)
    colors: Mapping[int, tuple[float, float, float]] = field(default_factory=dict)
    name: str = "labels"

    def __post_init__(self) -> None:
        values = _label_array(self.values, self.name)
        if values.ndim != 3:
            raise VolrenError(f"{self.name}: a label volume needs 3D values, got shape {values.shape}")
        names = {int(k): str(v) for k, v in dict(self.names).items()}
        colors = {int(k): _rgb(v, f"{self.name}: label {k}") for k, v in dict(self.colors).items()}
        object.__setattr__(self, "values", values)
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "colors", colors)

    @cached_property
    def present(self) -> tuple[int, ...]:
        """The labels that occur, ascending."""
        counts = np.bincount(self.values.reshape(-1), minlength=1)
        return tuple(int(v) for v in np.flatnonzero(counts))

    @property
    def max_label(self) -> int:
        return self.present[-1]

    @cached_property
    def digest(self) -> str:
        """A hash of the labels (their shape and values): what caches of label tables key on."""
        h = hashlib.blake2b(str(self.values.shape).encode(), digest_size=16)
        h.update(self.values.tobytes())
        return h.hexdigest()

    @cached_property
    def boundary(self) -> NDArray[np.int64]:
        """`boundary_cells` of these labels, found once."""
        return boundary_cells(self.values)

    def label_name(self, label: int) -> str:
        return self.names.get(label, f"label {label}")

    def check_grid(self, shape: tuple[int, ...], what: str) -> None:
        """Refuse (one line) a label volume that is not on the grid of `what`, whose values have `shape`."""
        if tuple(self.values.shape) != tuple(shape):
            got, want = self.values.shape[::-1], tuple(shape)[::-1]
            raise VolrenError(
                f"{self.name}: the label volume is {'x'.join(map(str, got))} but {what} is "
                f"{'x'.join(map(str, want))}: labels must lie on the volume's grid"
            )


@dataclass(frozen=True)
class LabelStyle:
    """How one label is drawn: shown or hidden, and its transfer function, either its own `tf` or
    the volume's with `color` in place of the TF's colours and its opacity times `opacity`."""

    visible: bool = True
    color: tuple[float, float, float] | None = None
    opacity: float = 1.0
    tf: TransferFunction1D | None = None

    def __post_init__(self) -> None:
        if self.color is not None:
            object.__setattr__(self, "color", _rgb(self.color, "label colour"))
        scale = float(self.opacity)
        if not (math.isfinite(scale) and scale >= 0):
            raise VolrenError(f"a label's opacity scale must be a number >= 0, got {self.opacity!r}")
        object.__setattr__(self, "opacity", scale)

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"visible": self.visible, "opacity": self.opacity}
        if self.color is not None:
            out["color"] = list(self.color)
        if self.tf is not None:
            out["tf"] = self.tf.to_dict()
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], what: str) -> LabelStyle:
        if not isinstance(data, Mapping):
            raise VolrenError(f"{what}: a label's style is an object, got {type(data).__name__}")
        unknown = set(data) - {"visible", "opacity", "color", "tf", "name"}
        if unknown:
            raise VolrenError(f"{what}: unknown key(s) {', '.join(sorted(unknown))}")
        visible = data.get("visible", True)
        if not isinstance(visible, bool):
            raise VolrenError(f"{what}: 'visible' must be true or false, got {visible!r}")
        tf = TransferFunction1D.from_dict(data["tf"]) if data.get("tf") is not None else None
        color = _rgb(data["color"], what) if data.get("color") is not None else None
        opacity = data.get("opacity", 1.0)
        if isinstance(opacity, bool) or not isinstance(opacity, int | float):
            raise VolrenError(f"{what}: 'opacity' must be a number, got {opacity!r}")
        return cls(visible, color, float(opacity), tf)


class LabelClasses(NamedTuple):
    """The labels grouped by the TF they draw with: `lookup[label]` is the label's class (-1:
    hidden), `tfs[c]` class c's transfer function. Labels above len(lookup) - 1 are hidden."""

    lookup: NDArray[np.int32]
    tfs: tuple[TransferFunction1D, ...]


class LabelTransferFunction(Versioned):
    """A transfer function per label over the volume's `base` TF (RTVG chapter 16): labels without
    a style of their own draw with `default`."""

    #: Labels classify the volume's value: one dimension, as a 1D TF.
    dims: ClassVar[int] = 1

    def __init__(
        self,
        base: TransferFunction1D,
        styles: Mapping[int, LabelStyle] | None = None,
        default: LabelStyle | None = None,
    ) -> None:
        if not isinstance(base, TransferFunction1D):
            raise VolrenError(f"label transfer functions build on a 1D TF, got {type(base).__name__}")
        self._base = base
        self._styles: dict[int, LabelStyle] = {}
        for label, style in dict(styles or {}).items():
            self._styles[self._check_label(label)] = style
        self._default = default or LabelStyle()
        self._digest: tuple[tuple[int, ...], str] | None = None
        self._classes: tuple[tuple[int, ...], int, LabelClasses] | None = None
        super().__init__()

    @classmethod
    def for_labels(cls, base: TransferFunction1D, labels: LabelMap) -> LabelTransferFunction:
        """What a label volume shows with nothing else said: label 0 (the background of every
        segmentation format) in the volume's TF, each other label in its file's colour, else in
        `PALETTE`'s next colour, over the volume's opacity."""
        styles = {}
        for n, label in enumerate(label for label in labels.present if label != 0):
            styles[label] = LabelStyle(color=labels.colors.get(label, PALETTE[n % len(PALETTE)]))
        return cls(base, styles)

    @staticmethod
    def _check_label(label: Any) -> int:
        if isinstance(label, bool) or not isinstance(label, int | np.integer) or not 0 <= label <= MAX_LABEL:
            raise VolrenError(f"a label is a whole number in 0..{MAX_LABEL}, got {label!r}")
        return int(label)

    # ------------------------------------------------------------------------------ state
    @property
    def base(self) -> TransferFunction1D:
        return self._base

    @property
    def default(self) -> LabelStyle:
        return self._default

    @property
    def styles(self) -> dict[int, LabelStyle]:
        """Each label's own style (a copy)."""
        return dict(self._styles)

    def style(self, label: int) -> LabelStyle:
        return self._styles.get(label, self._default)

    @property
    def opacity_unit_distance(self) -> float:
        return self._base.opacity_unit_distance

    @property
    def value_range(self) -> tuple[float, float]:
        """The span of every TF a label may draw with."""
        ranges = [tf.value_range for tf in [self._base, *(s.tf for s in self._styles.values() if s.tf)]]
        return (min(r[0] for r in ranges), max(r[1] for r in ranges))

    # ------------------------------------------------------------------------------ edits
    def set_style(self, label: int, style: LabelStyle) -> None:
        self._styles[self._check_label(label)] = style
        self._changed()

    def set_styles(self, styles: Mapping[int, LabelStyle]) -> None:
        for label, style in styles.items():
            self._styles[self._check_label(label)] = style
        self._changed()

    def hide(self, labels: Iterable[int]) -> None:
        """Hide these labels, keeping the rest of their styles."""
        self.set_styles({label: replace(self.style(label), visible=False) for label in labels})

    def set_base(self, base: TransferFunction1D) -> None:
        self._base = base
        self._changed()

    def copy(self) -> LabelTransferFunction:
        return LabelTransferFunction(self._base.copy(), self._styles, self._default)

    def state(self) -> tuple[int, ...]:
        """The versions of this object, its base TF and every label's own TF: they change with every
        edit, including edits of those TFs in place, which leave this object's `version` as it was.
        Versions come from one process-wide counter, so equal states mean equal contents."""
        own = [style.tf.version for style in self._styles.values() if style.tf is not None]
        default = self._default.tf.version if self._default.tf is not None else 0
        return (self.version, self._base.version, default, *own)

    def digest(self) -> str:
        """A hash of everything that classifies (the base TF, every style and its TF): a key for
        tables and caches that holds across processes (`state` holds within one), computed again
        only when `state` changes."""
        state = self.state()
        if self._digest is None or self._digest[0] != state:
            text = json.dumps(self.to_dict(), sort_keys=True)
            self._digest = (state, hashlib.blake2b(text.encode(), digest_size=16).hexdigest())
        return self._digest[1]

    # ------------------------------------------------------------------------ classification
    def effective_tf(self, label: int) -> TransferFunction1D | None:
        """The TF label `label` draws with, None where it is hidden."""
        return _drawn_with(self.style(label), self._base)

    def classes(self, max_label: int) -> LabelClasses:
        """Labels 0..max_label grouped by the TF they draw with: labels with equal styles share a
        class (and a table in the renderers); unstyled labels share the default's. At most
        `MAX_CLASSES` classes (refused above, in one line). Kept while `state` stays."""
        state = self.state()
        if self._classes is None or self._classes[:2] != (state, max_label):
            self._classes = (state, max_label, self._grouped(max_label))
        return self._classes[2]

    def _grouped(self, max_label: int) -> LabelClasses:
        lookup = np.full(max_label + 1, -1, np.int32)
        tfs: list[TransferFunction1D] = []
        index: dict[tuple, int] = {}  # a style's fields -> class

        def class_of(style: LabelStyle) -> int:
            key = (style.visible, style.color, style.opacity, id(style.tf))
            if key not in index:
                tf = _drawn_with(style, self._base)
                index[key] = -1 if tf is None else len(tfs)
                if tf is not None:
                    tfs.append(tf)
            return index[key]

        default = class_of(self._default)
        lookup[:] = default
        for label, style in self._styles.items():
            if label <= max_label:
                lookup[label] = class_of(style)
        if len(tfs) > MAX_CLASSES:
            raise VolrenError(f"{len(tfs):,} different label styles: at most {MAX_CLASSES:,} are drawn")
        return LabelClasses(lookup, tuple(tfs))

    def extinction_emission(
        self, values: ArrayLike, weights: Mapping[int, ArrayLike]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(tau, q (..., 3)) at scalars `values` where label l has weight `weights[l]` (the model
        above, in float64): the oracle the renderers' label paths are checked against."""
        s = np.asarray(values, dtype=np.float64)
        tau = np.zeros(s.shape)
        q = np.zeros(s.shape + (3,))
        for label, w in weights.items():
            tf = self.effective_tf(label)
            if tf is None:
                continue
            rgb, alpha = tf.sample(s)
            t = -np.log1p(-np.minimum(alpha, MAX_OPACITY)) / tf.opacity_unit_distance
            w = np.asarray(w, dtype=np.float64)
            tau += w * t
            q += (w * t)[..., None] * rgb
        return tau, q

    # ------------------------------------------------------------------------- file format
    def to_dict(self) -> dict[str, Any]:
        return {
            "version": LABEL_TF_FORMAT_VERSION,
            "kind": "labels",
            "base": self._base.to_dict(),
            "default": self._default.to_dict(),
            "labels": {str(label): style.to_dict() for label, style in sorted(self._styles.items())},
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> LabelTransferFunction:
        check_format_version(data, "label transfer function", LABEL_TF_FORMAT_VERSION)
        if data.get("kind") != "labels":
            raise VolrenError(
                f"expected a label transfer function (kind 'labels'), got kind {data.get('kind')!r}"
            )
        if "base" not in data:
            raise VolrenError("missing 'base' transfer function")
        styles = {}
        for key, value in dict(data.get("labels", {})).items():
            try:
                label = int(key)
            except ValueError:
                raise VolrenError(f"label {key!r} is not a whole number") from None
            styles[cls._check_label(label)] = LabelStyle.from_dict(value, f"label {label}")
        default = LabelStyle.from_dict(data.get("default", {}), "default label style")
        return cls(TransferFunction1D.from_dict(data["base"]), styles, default)

    def __repr__(self) -> str:
        return f"LabelTransferFunction({len(self._styles)} styled labels over {self._base!r})"


def _drawn_with(style: LabelStyle, base: TransferFunction1D) -> TransferFunction1D | None:
    """The 1D TF a label with `style` draws with over the volume's `base` TF; None when hidden."""
    if not style.visible or style.opacity == 0.0:
        return None
    tf = style.tf or base
    if style.color is None and style.opacity == 1.0:
        return tf
    color = tf.color_points
    if style.color is not None:
        color = np.array([[color[0, 0], *style.color]])
    return TransferFunction1D(
        color, _scaled_opacity(tf.opacity_points, style.opacity), tf.opacity_unit_distance
    )


def _scaled_opacity(points: NDArray[np.float64], scale: float) -> NDArray[np.float64]:
    """Opacity points of min(scale a(s), 1): the scaled points, clipped, with a point added where a
    scaled segment crosses 1 (so the result is exactly min(scale a, 1) between them)."""
    x, a = points[:, 0], points[:, 1] * scale
    out = [(x[0], a[0])]
    for k in range(1, len(x)):
        if (a[k - 1] - 1.0) * (a[k] - 1.0) < 0.0:
            out.append((x[k - 1] + (1.0 - a[k - 1]) / (a[k] - a[k - 1]) * (x[k] - x[k - 1]), 1.0))
        out.append((x[k], a[k]))
    result = np.array(out)
    result[:, 1] = np.minimum(result[:, 1], 1.0)
    return result


def cell_label_weights(corners: ArrayLike, fx: ArrayLike, fy: ArrayLike, fz: ArrayLike) -> dict[int, NDArray]:
    """Each label's trilinear weight at cell-local points (fx, fy, fz) in [0, 1]^3 of cells whose
    corner labels are `corners` (..., 8) in the order (v000, v100, v010, v110, v001, v101, v011,
    v111), corner vXYZ at (X, Y, Z): the w_l of the model above, in float64 (for oracles)."""
    c = np.asarray(corners)
    fx, fy, fz = (np.asarray(f, dtype=np.float64) for f in (fx, fy, fz))
    corner_w = [
        (1 - fx) * (1 - fy) * (1 - fz), fx * (1 - fy) * (1 - fz), (1 - fx) * fy * (1 - fz), fx * fy * (1 - fz),
        (1 - fx) * (1 - fy) * fz, fx * (1 - fy) * fz, (1 - fx) * fy * fz, fx * fy * fz,
    ]  # fmt: skip
    out: dict[int, NDArray] = {}
    for label in np.unique(c):
        out[int(label)] = sum(np.where(c[..., n] == label, corner_w[n], 0.0) for n in range(8))  # type: ignore[assignment]
    return out


#: `cell_classes`' mark of a cell whose corners fall in more than one class.
MIXED = -2


def boundary_cells(labels: NDArray[Any]) -> NDArray[np.int64]:
    """Flat indices (into `labels`) of the first corners of the cells whose eight corners hold more
    than one label: the only cells where a style change can make corners of different classes meet
    or part (`cell_classes`). A few per cent of the cells of a segmentation."""
    first = labels[:-1, :-1, :-1]
    same = np.ones(first.shape, dtype=bool)
    for dz in (0, 1):
        for dy in (0, 1):
            for dx in (0, 1):
                if dz or dy or dx:
                    same &= (
                        labels[dz : dz + first.shape[0], dy : dy + first.shape[1], dx : dx + first.shape[2]]
                        == first
                    )
    return np.ravel_multi_index(np.nonzero(~same), labels.shape)


def cell_classes(
    labels: NDArray[Any], lookup: NDArray[np.int32], boundary: NDArray[np.int64] | None = None
) -> NDArray[np.int16]:
    """Per cell, at the index of its first corner ([k, j, i] of the cell [i, i + 1] x ...): the class
    (`LabelClasses.lookup`) its eight corners share, -1 where that is hidden, or `MIXED` where they
    differ (and at the last plane, row and column, where no cell starts). Why: a sample then reads
    one number to know that its cell takes the fast path, instead of eight labels; only samples in
    boundary cells read their corners. One element past the end is readable (32-bit gathers).
    `boundary`: the label map's `boundary_cells`, kept from one style to the next (`LabelMap.boundary`),
    so that a style change looks up every cell once and compares corners only there."""
    if boundary is None:
        boundary = boundary_cells(labels)
    table = lookup.astype(np.int16)
    out = np.full(labels.size + 1, MIXED, np.int16)
    cells = out[: labels.size].reshape(labels.shape)
    cells[:-1, :-1, :-1] = table[labels[:-1, :-1, :-1]]  # the label shared by every corner
    nz, ny, nx = labels.shape
    flat = labels.reshape(-1)
    first = table[flat[boundary]]
    same = np.ones(len(boundary), dtype=bool)
    for offset in (1, nx, nx + 1, nx * ny, nx * ny + 1, nx * ny + nx, nx * ny + nx + 1):
        same &= table[flat[boundary + offset]] == first
    out[boundary] = np.where(same, first, MIXED)
    return cells
