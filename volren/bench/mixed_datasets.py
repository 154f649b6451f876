"""The label and multi-channel scenes of `volren bench run` (``--datasets labels``, ``channels``, or
by name; not in the default run): a segmentation drawn with a TF per label (Real-Time Volume
Graphics, chapter 16) and channels mixed in one optical model (Max 1995, section 2: their
extinctions and emissions add).

Shared (where shared/data has them, as `benchmarks/labels.py` and `channels.py` measure them): the PD25
brain template with its 16 subcortical labels over the template's smooth TF, the frog's 15 tissues,
the stroke MRI's T1, T2 and FLAIR, and VTK's vase of four identical components at weight 1/4 each
(which is the one component). Procedural, with closed forms along their centre lines:

- ``spheres-labels``: a constant field, a core (label 2) in a shell (label 1) in a hidden background
  (label 0), each radius half a voxel past the last labelled point, so that along a grid line
  through the centre the filtered label boundary (`volren.model.labels`: a label's weight is the
  trilinear interpolant, a ramp across the boundary cell) integrates to exactly the radius: optical
  depth 2 (tau_shell (R2 - R1) + tau_core R1) (`spheres_axis_alpha`).
- ``slab-channels``: the conformance kit's two constant channels (`volren.testing.channel_scenes`),
  one medium of the summed extinction (`channel_slab_rgba`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from volren.model.camera import Camera
from volren.model.labels import LabelMap, LabelStyle, LabelTransferFunction
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume

#: The names that stand for every label scene and every channel scene in --datasets.
LABELS_GROUP = "labels"
CHANNELS_GROUP = "channels"

#: The spheres: points a side (odd: the centre is a grid point), the radii (half a voxel past the
#: last labelled point along a grid line), the base TF's constant opacity and unit distance, and
#: the labels' colours and opacity scales.
SPHERES_POINTS = 49
SPHERES_RADII = (8.5, 20.5)
SPHERES_OPACITY = 0.05
SPHERES_UNIT = 4.0
SPHERES_STYLES = {1: ((0.2, 0.6, 1.0), 1.0), 2: ((1.0, 0.35, 0.1), 3.0)}


def spheres() -> tuple[UniformVolume, LabelTransferFunction]:
    """The core in a shell (see the module docstring), unit spacing, label 0 hidden."""
    n = SPHERES_POINTS
    c = (n - 1) / 2.0
    z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(np.float64)
    r = np.sqrt((x - c) ** 2 + (y - c) ** 2 + (z - c) ** 2)
    core, shell = SPHERES_RADII
    labels = np.where(r < core, 2, np.where(r < shell, 1, 0)).astype(np.uint8)
    volume = UniformVolume(np.full((n, n, n), 0.5), name="spheres",
                           labels=LabelMap(labels, {1: "shell", 2: "core"}, name="spheres"))  # fmt: skip
    base = TransferFunction1D.constant(SPHERES_OPACITY, (0.9, 0.9, 0.9), SPHERES_UNIT)
    styles = {0: LabelStyle(visible=False)}
    styles.update(
        {k: LabelStyle(color=colour, opacity=scale) for k, (colour, scale) in SPHERES_STYLES.items()}
    )
    return volume, LabelTransferFunction(base, styles)


def spheres_extinctions() -> dict[int, float]:
    """Each shown label's extinction per unit length (its opacity scale times the base opacity, per
    unit distance)."""
    return {
        k: -math.log1p(-min(SPHERES_OPACITY * s, 1.0)) / SPHERES_UNIT for k, (_, s) in SPHERES_STYLES.items()
    }


def spheres_axis_alpha() -> float:
    """The opacity along a grid line through the centre: optical depth 2 (tau_1 (R2 - R1) + tau_2 R1)."""
    tau = spheres_extinctions()
    core, shell = SPHERES_RADII
    return -math.expm1(-2.0 * (tau[1] * (shell - core) + tau[2] * core))


@dataclass(eq=False)
class MixedDataset:
    """A label or channel scene as a `volren.bench.datasets.Dataset`: built on `load`, one TF (its
    style ``labels`` or ``channels``, made with the volume: a TF per label needs the labels), seen
    from azimuth 30 and elevation 20."""

    name: str
    build: Callable[[], tuple[Any, Any]]
    style: str = LABELS_GROUP
    kind: str = "uniform"
    azimuth: float = 30.0
    elevation: float = 20.0
    zoom: float = 1.0
    _tf: Any = field(default=None, init=False, repr=False)

    @property
    def styles(self) -> tuple[str, ...]:
        return (self.style,)

    def load(self) -> UniformVolume:
        volume, self._tf = self.build()
        return volume

    def transfer_functions(self) -> Iterator[tuple[str, Any]]:
        yield self.style, self._tf if self._tf is not None else self.build()[1]

    def camera(self, bounds, turn: float = 0.0) -> Camera:
        return Camera.orbit(bounds, self.azimuth + turn, self.elevation, self.zoom)


def _pd25(shared: Path) -> tuple[UniformVolume, LabelTransferFunction]:
    from volren.io import load_transfer_function, load_volume
    from volren.io.label_info import load_label_info
    from volren.io.label_io import load_labels

    folder = shared / "data" / "labels"
    volume = load_volume(folder / "pd25_t1t2s.vti")
    assert isinstance(volume, UniformVolume)
    info = load_label_info(folder / "pd25_subcortical.labels.json")
    seg = load_labels(folder / "pd25_subcortical.vti", volume)
    labels = replace(seg, names=info.names, colors=info.colors)
    base = load_transfer_function(shared / "scenes" / "pd25-smooth.json")
    assert isinstance(base, TransferFunction1D)
    return replace(volume, labels=labels), LabelTransferFunction.for_labels(base, labels)


def _frog(shared: Path) -> tuple[UniformVolume, LabelTransferFunction]:
    """The label numbers as the scalar too: every tissue at one opacity, the background clear."""
    from volren.io import load_volume
    from volren.io.label_info import load_label_info

    folder = shared / "data" / "labels"
    frog = load_volume(folder / "frogtissue.mhd")
    assert isinstance(frog, UniformVolume)
    info = load_label_info(folder / "frogtissue.labels.json")
    labels = LabelMap(frog.values, info.names, info.colors, "frogtissue")
    base = TransferFunction1D([[0.0, 1, 1, 1]], [[0.0, 0.0], [0.5, 0.05], [29.0, 0.05]])
    return replace(frog, labels=labels), LabelTransferFunction.for_labels(base, labels)


def _channels(path: Path, weight: float | None = None) -> tuple[UniformVolume, Any]:
    """Every component of `path`'s array as a channel, each its default ramp; all at `weight` when
    given (else the file's defaults)."""
    from volren.io import load_volume
    from volren.io.channel_io import default_channel_tf
    from volren.model.channels import ChannelTransferFunction

    volume = load_volume(path, channels=True)
    assert isinstance(volume, UniformVolume) and volume.channels is not None
    tf = default_channel_tf(volume.channels)
    if weight is not None:
        tf = ChannelTransferFunction([tf.tfs[0]] * volume.channels.count, [weight] * volume.channels.count)
    return volume, tf


def _slab() -> tuple[UniformVolume, Any]:
    from volren.testing.channel_scenes import channel_slab

    return channel_slab()


def label_datasets(shared: Path | None) -> dict[str, MixedDataset]:
    """The label scenes: the shared ones whose files are there, and the procedural spheres."""
    out = {}
    folder = shared / "data" / "labels" if shared is not None else None
    if shared is not None and folder is not None:
        if (folder / "pd25_subcortical.vti").is_file() and (shared / "scenes" / "pd25-smooth.json").is_file():
            out["pd25-labels"] = MixedDataset("pd25-labels", lambda: _pd25(shared))
        if (folder / "frogtissue.mhd").is_file():
            out["frog-labels"] = MixedDataset("frog-labels", lambda: _frog(shared))
    out["spheres-labels"] = MixedDataset("spheres-labels", spheres)
    return out


def channel_datasets(shared: Path | None) -> dict[str, MixedDataset]:
    """The channel scenes: the shared ones whose files are there, and the procedural slab."""
    out = {}
    if shared is not None:
        folder = shared / "data" / "multichannel"
        stroke, vase = folder / "stroke_t1_t2_flair.vti", folder / "vase_4comp.vti"
        if stroke.is_file():
            out["stroke-channels"] = MixedDataset(
                "stroke-channels", lambda: _channels(stroke), CHANNELS_GROUP
            )
        if vase.is_file():
            out["vase-channels"] = MixedDataset(
                "vase-channels", lambda: _channels(vase, 0.25), CHANNELS_GROUP
            )
    out["slab-channels"] = MixedDataset("slab-channels", _slab, CHANNELS_GROUP)
    return out
