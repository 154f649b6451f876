"""Multi-channel volumes: several co-registered scalar fields on one grid, a transfer function each,
mixed in one ray march.

The optical model with channels (DESIGN.md's emission-absorption with several absorbing and
emitting media, Max 1995, section 2; VTK's independent components): at a point x, channel c has
its trilinear value s_c(x) and its own 1D transfer function, which gives it an extinction
tau_c(s_c) and a colour c_c(s_c) as in DESIGN.md; a weight w_c >= 0 scales its density. Then

    tau(x) = sum_c w_c tau_c(s_c(x)),     q(x) = sum_c w_c c_c(s_c(x)) tau_c(s_c(x)):

the media's densities add and so do their emissions, and the rest of the model is unchanged, so
a constant two-channel field has exactly the single-channel integral of the summed extinction.
A hidden channel (or weight 0) adds nothing. Where the channels of a fluorescence image overlap,
their colours mix by their extinctions: what napari's separately blended layers cannot show.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.model.file_version import check_format_version
from volren.model.transfer_function import MAX_OPACITY, TransferFunction1D
from volren.model.versioned import Versioned

CHANNEL_TF_FORMAT_VERSION = 1
#: The most channels drawn at once (a table each per sample): OME-Zarr images hold more, picked with --channels.
MAX_CHANNELS = 16
#: Channel colours where the file gives none: green, magenta, cyan, yellow, then red, blue, ...
#: (the order fluorescence viewers use for two to four channels, distinct for colour-blind readers).
CHANNEL_COLORS: tuple[tuple[float, float, float], ...] = (
    (0.0, 1.0, 0.0), (1.0, 0.0, 1.0), (0.0, 1.0, 1.0), (1.0, 1.0, 0.0),
    (1.0, 0.0, 0.0), (0.0, 0.0, 1.0), (1.0, 0.5, 0.0), (0.5, 0.0, 1.0),
)  # fmt: skip
#: The opacity a channel's default ramp reaches at the top of its window.
DEFAULT_PEAK_OPACITY = 0.2


@dataclass(frozen=True, eq=False)
class ChannelSet:
    """Several scalar fields on one grid: ``values[c, k, j, i]``, with each channel's name, colour
    and display window where the file gives them (None where not)."""

    values: NDArray[Any]
    names: tuple[str, ...] = ()
    colors: tuple[tuple[float, float, float] | None, ...] = ()
    windows: tuple[tuple[float, float] | None, ...] = ()
    name: str = "channels"
    value_ranges: tuple[tuple[float, float], ...] = field(init=False)

    def __post_init__(self) -> None:
        values = np.asarray(self.values)
        if values.ndim != 4:
            raise VolrenError(
                f"{self.name}: channels need 4D values (channel, z, y, x), got shape {values.shape}"
            )
        count = values.shape[0]
        if not 1 <= count <= MAX_CHANNELS:
            raise VolrenError(f"{self.name}: 1 to {MAX_CHANNELS} channels are drawn at once, got {count}")
        if not (np.issubdtype(values.dtype, np.integer) or np.issubdtype(values.dtype, np.floating)):
            raise VolrenError(f"{self.name}: channel values must be numbers, got {values.dtype}")
        values = np.ascontiguousarray(values)
        names = tuple(self.names) or tuple(f"channel {c}" for c in range(count))
        colors = tuple(self.colors) or (None,) * count
        windows = tuple(self.windows) or (None,) * count
        for what, given in (("names", names), ("colors", colors), ("windows", windows)):
            if len(given) != count:
                raise VolrenError(f"{self.name}: {len(given)} {what} for {count} channels")
        ranges = []
        for c in range(count):
            channel = values[c]
            finite = channel[np.isfinite(channel)] if np.issubdtype(values.dtype, np.floating) else channel
            ranges.append((float(finite.min()), float(finite.max())) if finite.size else (0.0, 0.0))
        for key, value in (("values", values), ("names", names), ("colors", colors), ("windows", windows),
                           ("value_ranges", tuple(ranges))):  # fmt: skip
            object.__setattr__(self, key, value)

    @property
    def count(self) -> int:
        return int(self.values.shape[0])

    @property
    def shape(self) -> tuple[int, int, int]:
        """The grid's (nz, ny, nx)."""
        return tuple(self.values.shape[1:])  # type: ignore[return-value]

    def window(self, c: int) -> tuple[float, float]:
        """Channel c's display window: the file's, else its value range."""
        return self.windows[c] or self.value_ranges[c]

    @cached_property
    def digest(self) -> str:
        """A hash of the channels' values: what caches of channel tables key on."""
        h = hashlib.blake2b(str(self.values.shape).encode() + str(self.values.dtype).encode(), digest_size=16)
        h.update(self.values.tobytes())
        return h.hexdigest()


class ChannelTransferFunction(Versioned):
    """A 1D transfer function per channel, a weight each (its density's scale) and whether it is
    shown: the channels mixed in one optical model (module docstring)."""

    dims: ClassVar[int] = 1

    def __init__(
        self,
        tfs: Sequence[TransferFunction1D],
        weights: Sequence[float] | None = None,
        visible: Sequence[bool] | None = None,
    ) -> None:
        tfs = list(tfs)
        if not tfs or len(tfs) > MAX_CHANNELS:
            raise VolrenError(f"a channel transfer function has 1 to {MAX_CHANNELS} channels, got {len(tfs)}")
        for c, tf in enumerate(tfs):
            if not isinstance(tf, TransferFunction1D):
                raise VolrenError(
                    f"channel {c}: a channel's transfer function is 1D, got {type(tf).__name__}"
                )
        self._tfs = tfs
        self._weights = [self._check_weight(w, c) for c, w in enumerate(weights or [1.0] * len(tfs))]
        self._visible = [bool(v) for v in (visible or [True] * len(tfs))]
        if len(self._weights) != len(tfs) or len(self._visible) != len(tfs):
            raise VolrenError(f"{len(tfs)} channels need as many weights and visibility flags")
        super().__init__()

    @classmethod
    def for_channels(cls, channels: ChannelSet) -> ChannelTransferFunction:
        """What a multi-channel volume shows with nothing else said: each channel an opacity ramp
        over its window (0 at its bottom, `DEFAULT_PEAK_OPACITY` at its top) in its file's colour,
        else the next of `CHANNEL_COLORS`."""
        tfs = []
        for c in range(channels.count):
            lo, hi = channels.window(c)
            color = channels.colors[c] or CHANNEL_COLORS[c % len(CHANNEL_COLORS)]
            tfs.append(TransferFunction1D.ramp(lo, hi if hi > lo else lo + 1.0, DEFAULT_PEAK_OPACITY, color))
        return cls(tfs)

    @staticmethod
    def _check_weight(value: Any, c: int) -> float:
        if (
            isinstance(value, bool)
            or not isinstance(value, int | float)
            or not (math.isfinite(value) and value >= 0)
        ):
            raise VolrenError(f"channel {c}: a weight is a number >= 0, got {value!r}")
        return float(value)

    # ------------------------------------------------------------------------------ state
    @property
    def count(self) -> int:
        return len(self._tfs)

    @property
    def tfs(self) -> list[TransferFunction1D]:
        return list(self._tfs)

    @property
    def weights(self) -> list[float]:
        return list(self._weights)

    @property
    def visible(self) -> list[bool]:
        return list(self._visible)

    def drawn_weight(self, c: int) -> float:
        """Channel c's weight as drawn: 0 where it is hidden."""
        return self._weights[c] if self._visible[c] else 0.0

    @property
    def opacity_unit_distance(self) -> float:
        return self._tfs[0].opacity_unit_distance

    @property
    def value_range(self) -> tuple[float, float]:
        ranges = [tf.value_range for tf in self._tfs]
        return (min(r[0] for r in ranges), max(r[1] for r in ranges))

    # ------------------------------------------------------------------------------ edits
    def set_tf(self, c: int, tf: TransferFunction1D) -> None:
        self._tfs[c] = tf
        self._changed()

    def set_weight(self, c: int, weight: float) -> None:
        self._weights[c] = self._check_weight(weight, c)
        self._changed()

    def set_visible(self, c: int, visible: bool) -> None:
        self._visible[c] = bool(visible)
        self._changed()

    def copy(self) -> ChannelTransferFunction:
        return ChannelTransferFunction([tf.copy() for tf in self._tfs], self._weights, self._visible)

    def digest(self) -> str:
        """A hash of every channel's TF, weight and visibility (edits of a TF in place included)."""
        text = json.dumps(self.to_dict(), sort_keys=True)
        return hashlib.blake2b(text.encode(), digest_size=16).hexdigest()

    # ------------------------------------------------------------------------ classification
    def extinction_emission(self, values: Sequence[Any]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(tau, q (..., 3)) where channel c has the scalars `values[c]` (the model above, in
        float64): the oracle the renderers' channel paths are checked against."""
        tau: NDArray[np.float64] = np.zeros(np.shape(values[0]))
        q: NDArray[np.float64] = np.zeros(tau.shape + (3,))
        for c, tf in enumerate(self._tfs):
            w = self.drawn_weight(c)
            if w == 0.0:
                continue
            rgb, alpha = tf.sample(values[c])
            t = w * (-np.log1p(-np.minimum(alpha, MAX_OPACITY)) / tf.opacity_unit_distance)
            tau += t
            q += t[..., None] * rgb
        return tau, q

    # ------------------------------------------------------------------------- file format
    def to_dict(self) -> dict[str, Any]:
        return {
            "version": CHANNEL_TF_FORMAT_VERSION,
            "kind": "channels",
            "channels": [
                {"tf": tf.to_dict(), "weight": w, "visible": v}
                for tf, w, v in zip(self._tfs, self._weights, self._visible, strict=True)
            ],
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> ChannelTransferFunction:
        check_format_version(data, "channel transfer function", CHANNEL_TF_FORMAT_VERSION)
        if data.get("kind") != "channels":
            raise VolrenError(
                f"expected a channel transfer function (kind 'channels'), got {data.get('kind')!r}"
            )
        entries = data.get("channels")
        if not isinstance(entries, list) or not entries:
            raise VolrenError("'channels' must be a list of {tf, weight, visible}")
        tfs, weights, visible = [], [], []
        for c, entry in enumerate(entries):
            if not isinstance(entry, Mapping) or "tf" not in entry:
                raise VolrenError(f"channel {c}: an object with a 'tf' (and 'weight', 'visible')")
            unknown = set(entry) - {"tf", "weight", "visible"}
            if unknown:
                raise VolrenError(f"channel {c}: unknown key(s) {', '.join(sorted(unknown))}")
            tfs.append(TransferFunction1D.from_dict(entry["tf"]))
            weights.append(entry.get("weight", 1.0))
            shown = entry.get("visible", True)
            if not isinstance(shown, bool):
                raise VolrenError(f"channel {c}: 'visible' must be true or false, got {shown!r}")
            visible.append(shown)
        return cls(tfs, weights, visible)

    def __repr__(self) -> str:
        return f"ChannelTransferFunction({self.count} channels)"
