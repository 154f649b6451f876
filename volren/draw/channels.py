"""A scene with a multi-channel volume: the volume with its `ChannelSet` and the TF made a
`ChannelTransferFunction` (Max 1995, section 2: several media whose extinctions and emissions add;
VTK's independent components), the one way `volren.render`, `volren render` and scene files put
channel picks, per-channel TFs, weights and hidden channels together.

The order, each step over the one before: the channels' default look (each an opacity ramp over its
window in its file's or the palette's colour, the file's inactive channels hidden:
`channel_io.default_channel_tf`), or the `ChannelTransferFunction` given, or a 1D TF given for
every channel; then the per-channel TFs; then the weights; then the hidden channels.

Channels are named by their number in the file (`PickedChannels.indices`): ``--channels 0,2
--channel-tf 2=x.json`` draws the file's channel 2 with x.json. A volume made in memory numbers
its channels 0, 1, ... in its `ChannelSet`'s order.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sized
from dataclasses import dataclass
from typing import Any

import numpy as np

from volren.errors import VolrenError
from volren.io.channel_io import PickedChannels, channel_volume, check_pick, default_channel_tf, wants_pick
from volren.io.label_info import one_d_tf
from volren.model.channels import ChannelSet, ChannelTransferFunction
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume, Volume


@dataclass(frozen=True)
class ChannelArgs:
    """How the caller names each channel input in errors (the API's arguments, or the CLI's flags)."""

    channels: str = "channels"
    tfs: str = "channel_tfs"
    weights: str = "channel_weights"
    hidden: str = "hidden_channels"


API_ARGS = ChannelArgs()
CLI_ARGS = ChannelArgs("--channels", "--channel-tf", "--channel-weight", "--hide-channels")


def _given(value: object) -> bool:
    """Whether an optional collection was given: not None and not empty."""
    if value is None:
        return False
    return len(value) > 0 if isinstance(value, Sized) else True


def wants_channels(volume: Volume, tf: object, channels: object = None, tfs: object = None, weights: object = None,
                   hidden: object = ()) -> bool:  # fmt: skip
    """Whether anything asks for a multi-channel scene: a channel pick or input, a
    `ChannelTransferFunction`, or a volume that has channels."""
    given = wants_pick(channels) or _given(tfs) or _given(weights) or _given(hidden)
    return given or isinstance(tf, ChannelTransferFunction) or getattr(volume, "channels", None) is not None


def file_channel(channels: ChannelSet, key: object, what: str) -> int:
    """The slot (0..count-1) of the file's channel `key` among the channels drawn."""
    indices = getattr(channels, "indices", tuple(range(channels.count)))
    if isinstance(key, str) and key.strip().isdigit():
        key = int(key)
    if isinstance(key, bool) or not isinstance(key, int | np.integer):
        raise VolrenError(f"{what}: a channel is a whole number, got {key!r:.20}")
    if int(key) not in indices:
        raise VolrenError(f"{what}: channel {key} is not drawn (the channels drawn: "
                          f"{', '.join(str(i) for i in indices)})")  # fmt: skip
    return indices.index(int(key))


def picked_volume(volume: UniformVolume, pick: object, what: str) -> UniformVolume:
    """A volume in memory with channels, `pick` (True, or its channels' numbers) kept, in that order."""
    assert volume.channels is not None
    have = volume.channels
    indices = getattr(have, "indices", tuple(range(have.count)))
    if pick is True:
        return volume
    slots = [file_channel(have, c, what) for c in check_pick(pick, max(indices) + 1, what)]
    if slots == list(range(have.count)):
        return volume
    active = getattr(have, "active", (True,) * have.count)
    kept = PickedChannels(have.values[slots], tuple(have.names[s] for s in slots),
                          tuple(have.colors[s] for s in slots), tuple(have.windows[s] for s in slots),
                          name=have.name, indices=tuple(indices[s] for s in slots),
                          active=tuple(active[s] for s in slots))  # fmt: skip
    return channel_volume(volume, kept)


def channelled(
    volume: Volume,
    tf: TransferFunction1D | ChannelTransferFunction | None,
    tfs: Mapping[Any, Any] | None = None,
    weights: Mapping[Any, Any] | None = None,
    hidden: Iterable[Any] = (),
    names: ChannelArgs = API_ARGS,
) -> tuple[UniformVolume, ChannelTransferFunction]:
    """(the volume, the TF per channel) of a volume with channels: `tf` None for the default look,
    a `ChannelTransferFunction` (one per drawn channel), or a 1D TF for every channel; `tfs`
    {channel: a 1D TF, TF file or TF dict}; `weights` {channel: weight >= 0}; `hidden`: channels not
    drawn. Channels are the file's numbers. Errors are one line naming the argument as `names` says."""
    asked = names.tfs if _given(tfs) else names.weights if _given(weights) else names.hidden
    if not isinstance(volume, UniformVolume) or volume.channels is None:
        what = "a tetrahedral mesh" if not isinstance(volume, UniformVolume) else "one field"
        raise VolrenError(f"{asked if _given(tfs) or _given(weights) or _given(hidden) else names.channels}: "
                          f"needs a multi-channel volume; {volume.name} is {what} (give {names.channels})")  # fmt: skip
    channels = volume.channels
    if isinstance(hidden, str | bytes) or not isinstance(hidden, Iterable):
        raise VolrenError(f"{names.hidden}: give the channels as a list of whole numbers, got {hidden!r:.60}")
    for given, name in ((tfs, names.tfs), (weights, names.weights)):
        if given is not None and not isinstance(given, Mapping):
            raise VolrenError(f"{name}: give {{channel: value}}, got a {type(given).__name__}")
    if isinstance(tf, ChannelTransferFunction):
        if tf.count != channels.count:
            raise VolrenError(f"{names.channels}: the transfer function has {tf.count} channels, the volume "
                              f"{volume.name} {channels.count}")  # fmt: skip
        ctf = tf.copy()
    elif isinstance(tf, TransferFunction1D):
        ctf = ChannelTransferFunction([tf.copy() for _ in range(channels.count)])
    elif tf is None:
        ctf = default_channel_tf(channels)
    else:
        raise VolrenError(f"{names.channels}: channels draw with a 1D transfer function each; got a 2D one")
    for key, value in dict(tfs or {}).items():
        slot = file_channel(channels, key, names.tfs)
        try:
            ctf.set_tf(slot, one_d_tf(value, f"{names.tfs}: channel {key}"))
        except VolrenError as exc:
            text = str(exc).replace("a label's", "a channel's")
            raise VolrenError(text if text.startswith(names.tfs) else f"{names.tfs}: {text}") from None
    for key, value in dict(weights or {}).items():
        slot = file_channel(channels, key, names.weights)
        if (
            isinstance(value, bool)
            or not isinstance(value, int | float)
            or not (math.isfinite(value) and value >= 0)
        ):
            raise VolrenError(f"{names.weights}: channel {key}: a weight is a number >= 0, got {value!r:.20}")
        ctf.set_weight(slot, float(value))
    for key in tuple(hidden):
        ctf.set_visible(file_channel(channels, key, names.hidden), False)
    return volume, ctf
