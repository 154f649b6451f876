"""Multi-channel volumes from files: which channels a file's array (or an OME-Zarr image's ``c``
axis) gives, and the `ChannelSet` they become.

A channel pick is True (every channel), or a list of the file's channel numbers (drawn in that
order); None or False reads the field as before (a vector array's magnitude). The channels keep
the file's numbers (`PickedChannels.indices`), so that a per-channel TF or weight names channel 2
of the file whichever channels were picked, and the file's display hints (OME-Zarr's
``omero.channels`` ``active``) as `PickedChannels.active`: which channels are shown at first.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from volren.errors import VolrenError
from volren.model.channels import MAX_CHANNELS, ChannelSet, ChannelTransferFunction
from volren.model.volume import UniformVolume

#: What asks for channels: True (all), the file's channel numbers, or None/False (none).
ChannelPick = bool | Sequence[int] | None


@dataclass(frozen=True, eq=False)
class PickedChannels(ChannelSet):
    """A `ChannelSet` read from a file: each channel's number in the file, and whether the file
    shows it at first (OME-Zarr's ``active``)."""

    indices: tuple[int, ...] = ()
    active: tuple[bool, ...] = ()

    def __post_init__(self) -> None:
        super().__post_init__()
        indices = tuple(int(i) for i in self.indices) or tuple(range(self.count))
        active = tuple(bool(a) for a in self.active) or (True,) * self.count
        if len(indices) != self.count or len(active) != self.count:
            raise VolrenError(f"{self.name}: {self.count} channels need as many numbers and active flags")
        object.__setattr__(self, "indices", indices)
        object.__setattr__(self, "active", active)


def wants_pick(pick: object) -> bool:
    """Whether `pick` asks for channels (True or a list; None and False do not)."""
    return pick is not None and pick is not False


def check_pick(pick: object, count: int, what: str) -> tuple[int, ...]:
    """The channel numbers `pick` names among `count` channels (True: all), checked: whole numbers
    in range, none twice, at most `MAX_CHANNELS`; errors are one line starting with `what`."""
    if pick is True:
        chosen = tuple(range(count))
    elif isinstance(pick, str | bytes) or not isinstance(pick, Sequence | np.ndarray):
        raise VolrenError(f"{what}: give True (every channel) or a list of channel numbers, got {pick!r:.60}")
    else:
        chosen = ()
        for c in pick:
            if isinstance(c, bool) or not isinstance(c, int | np.integer) or not 0 <= c < count:
                raise VolrenError(f"{what}: channel {c!r:.20} is not one of 0..{count - 1}")
            chosen += (int(c),)
        if not chosen:
            raise VolrenError(f"{what}: give at least one channel")
        if len(set(chosen)) != len(chosen):
            raise VolrenError(f"{what}: a channel is named twice in {list(chosen)}")
    if len(chosen) > MAX_CHANNELS:
        raise VolrenError(f"{what}: {len(chosen)} channels; at most {MAX_CHANNELS} are drawn at once "
                          "(pick some, e.g. 0,1,2)")  # fmt: skip
    return chosen


def first_shown(channels: ChannelSet) -> int:
    """The channel a multi-channel volume's `values` are: the first shown one (else the first)."""
    active = getattr(channels, "active", ())
    return next((c for c, shown in enumerate(active) if shown), 0)


def channel_volume(volume: UniformVolume, channels: ChannelSet) -> UniformVolume:
    """`volume` holding `channels`, its `values` the first shown channel: a view of the channels'
    array, not a copy."""
    return UniformVolume(
        channels.values[first_shown(channels)],
        volume.spacing,
        volume.origin,
        name=volume.name,
        notes=volume.notes,
        scalars=volume.scalars,
        arrays=volume.arrays,
        patient_axes=volume.patient_axes,
        channels=channels,
    )


def share_values(volume: Any) -> Any:
    """`volume` with its `values` made a view of its channels again. Why: a volume read in a child
    process (`volren.io.isolation`) comes back pickled, and pickling writes a view as its own array;
    this drops that second copy. The values are the same numbers (same shape and type), so the
    volume's checked fields stay true."""
    channels = getattr(volume, "channels", None)
    if channels is None or not isinstance(volume, UniformVolume):
        return volume
    shared = channels.values[first_shown(channels)]
    if shared.shape == volume.values.shape and shared.dtype == volume.values.dtype:
        object.__setattr__(volume, "values", shared)
    return volume


def default_channel_tf(channels: ChannelSet) -> ChannelTransferFunction:
    """The look a multi-channel volume has with nothing else said (`ChannelTransferFunction.for_channels`),
    with the channels the file marks inactive hidden."""
    tf = ChannelTransferFunction.for_channels(channels)
    for c, shown in enumerate(getattr(channels, "active", ())):
        if not shown:
            tf.set_visible(c, False)
    return tf


def nonfinite_notes(channels: ChannelSet, name: str) -> list[str]:
    """A note per channel with NaN or Inf values: kept, drawn transparent in that channel."""
    if not np.issubdtype(channels.values.dtype, np.floating):
        return []
    notes = []
    for c in range(channels.count):
        bad = int(channels.values[c].size - np.count_nonzero(np.isfinite(channels.values[c])))
        if bad:
            notes.append(f"{name}: channel {channels.names[c]!r} has {bad:,} NaN or Inf values; they render "
                         "transparent in that channel")  # fmt: skip
    return notes
