"""The scenes `volren bench run` measures: the shared datasets with their TFs, the bundled samples,
the hard procedural scenes (`volren.testing.hard_cases`: thin tubes and sheets, tiny objects,
noise, steps, anisotropic spacing; `--datasets hard` names them all), and the label and channel
scenes (`volren.bench.mixed_datasets`; `--datasets labels`, `--datasets channels`).

A shared dataset comes with one TF per style in the shared folder's scenes/ (`<dataset>-<style>.json`) and the
camera of shared/scenes/README.md (`SCENES`); a bundled sample (`volren.samples`)
comes with its own TF, style `sample`, seen from azimuth 30 and elevation 20 like the others.
Volumes load lazily, one dataset at a time, so a run holds one large mesh at most.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from volren.bench.mixed_datasets import (
    CHANNELS_GROUP,
    LABELS_GROUP,
    MixedDataset,
    channel_datasets,
    label_datasets,
)
from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TransferFunction
from volren.model.volume import Volume
from volren.samples import SAMPLES, sample_paths

#: dataset -> (file under shared/data, scalars, azimuth, elevation, zoom), from shared/scenes/README.md
SCENES = {
    "ironProt": ("uniform/ironProt.vtk", "scalars", 30, 20, 1.0),
    "bonsai": ("uniform/bonsai.vti", "ImageFile", 30, 20, 1.0),
    "engine": ("uniform/engine.vti", "ImageFile", 30, 20, 1.0),
    "aneurism": ("uniform/aneurism.vti", "ImageFile", 30, 20, 1.0),
    "spx": ("tets/spx.vtk", "scalars", 30, 20, 1.0),
    "bluntfin": ("tets/bluntfin_tets.vtu", "Density", 30, 20, 1.4),
    "oxygen": ("tets/oxygen_post_tets.vtu", "VelocityMagnitude", 30, 45, 1.3),
}
STYLES = ("smooth", "spiky", "opaque")

#: Where the shared datasets are when no --shared is given.
SHARED_ENV = "VOLREN_SHARED"


def shared_folder(flag: str | os.PathLike | None, required: bool = True) -> Path | None:
    """The folder with data/ and scenes/: the --shared flag, else $VOLREN_SHARED. Without either
    (or when it lacks those folders) a one-line error, or None when not `required`."""
    text = flag if flag is not None else os.environ.get(SHARED_ENV)
    if not text:
        if required:
            raise VolrenError(f"no shared data folder given (--shared DIR or ${SHARED_ENV})")
        return None
    shared = Path(text).expanduser()
    if not ((shared / "data").is_dir() and (shared / "scenes").is_dir()):
        if required or flag is not None:
            raise VolrenError(f"{shared}: no data/ and scenes/ folders there (--shared DIR or ${SHARED_ENV})")
        return None
    return shared


#: What --quick measures: one small grid and one small mesh, both bundled.
QUICK_DATASETS = ("marschner_lobb", "hollow_cylinder")
SAMPLE_CAMERA = (30.0, 20.0, 1.0)


@dataclass(frozen=True)
class Dataset:
    """A volume file, how to read it, its TFs by style and the scene's camera."""

    name: str
    kind: str
    path: Path
    scalars: str | None
    tf_paths: tuple[tuple[str, Path], ...]
    azimuth: float
    elevation: float
    zoom: float

    def load(self) -> Volume:
        from volren.io import load_volume

        return load_volume(self.path, scalars=self.scalars)

    @property
    def styles(self) -> tuple[str, ...]:
        """The TF styles, in `transfer_functions`' order."""
        return tuple(style for style, _ in self.tf_paths)

    def transfer_functions(self) -> Iterator[tuple[str, TransferFunction1D]]:
        for style, path in self.tf_paths:
            yield style, TransferFunction1D.from_dict(json.loads(path.read_text()))

    def camera(self, bounds, turn: float = 0.0) -> Camera:
        """The scene's camera, turned by `turn` degrees of azimuth (the timed frames turn)."""
        return Camera.orbit(bounds, self.azimuth + turn, self.elevation, self.zoom)


def shared_datasets(shared: Path) -> dict[str, Dataset]:
    """The datasets of shared/scenes/README.md whose file and at least one TF are present, their TFs
    in the README's order (smooth, spiky, opaque, then any others by name)."""
    out = {}
    for name, (rel, scalars, az, el, zoom) in SCENES.items():
        path = shared / "data" / rel
        found = [(p.stem.removeprefix(f"{name}-"), p) for p in (shared / "scenes").glob(f"{name}-*.json")]
        tfs = tuple(
            sorted(found, key=lambda sp: (STYLES.index(sp[0]) if sp[0] in STYLES else len(STYLES), sp[0]))
        )
        if path.exists() and tfs:
            kind = "tet" if rel.startswith("tets/") else "uniform"
            out[name] = Dataset(name, kind, path, scalars, tfs, az, el, zoom)
    return out


def sample_datasets() -> dict[str, Dataset]:
    out = {}
    for name in SAMPLES:
        volume_path, tf_path = sample_paths(name)
        kind = "tet" if volume_path.suffix == ".vtu" else "uniform"
        out[name] = Dataset(name, kind, volume_path, None, (("sample", tf_path),), *SAMPLE_CAMERA)
    return out


@dataclass(frozen=True)
class HardDataset:
    """A hard procedural scene (`volren.testing.hard_cases`) as a `Dataset`: built in memory, one TF
    (style `hard`), its own camera angles."""

    name: str
    kind: str
    styles: tuple[str, ...] = ("hard",)

    def _case(self):
        from volren.testing.hard_cases import CASES

        return CASES[self.name]

    def load(self) -> Volume:
        return self._case().build()

    def transfer_functions(self) -> Iterator[tuple[str, TransferFunction1D]]:
        yield "hard", self._case().tf()

    def camera(self, bounds, turn: float = 0.0) -> Camera:
        case = self._case()
        return Camera.orbit(bounds, case.azimuth + turn, case.elevation, case.zoom)


#: The name that stands for every hard scene in --datasets.
HARD_GROUP = "hard"


def hard_datasets() -> dict[str, HardDataset]:
    from volren.testing.hard_cases import CASES

    return {name: HardDataset(name, case.kind) for name, case in CASES.items()}


def select(
    names: Iterable[str] | None, shared: Path | None, quick: bool = False
) -> list[Dataset | HardDataset | MixedDataset]:
    """The datasets asked for by name (`hard`: every hard scene; `labels`, `channels`: every label or
    channel scene, `volren.bench.mixed_datasets`); by default every shared one and every sample
    (--quick: two samples)."""
    hard = hard_datasets()
    groups: dict[str, dict[str, Any]] = {HARD_GROUP: hard, LABELS_GROUP: label_datasets(shared),
                                         CHANNELS_GROUP: channel_datasets(shared)}  # fmt: skip
    grouped = {n for group in groups.values() for n in group}
    available = {**(shared_datasets(shared) if shared is not None else {}), **sample_datasets(),
                 **{n: d for group in groups.values() for n, d in group.items()}}  # fmt: skip
    if names is None:
        names = QUICK_DATASETS if quick else [n for n in available if n not in grouped]
    names = [n for name in names for n in (groups[name] if name in groups else [name])]
    unknown = [n for n in names if n not in available]
    if unknown:
        where = "" if shared is not None else " (no shared folder found: give --shared)"
        raise VolrenError(
            f"unknown datasets {unknown}; choose from {', '.join([*available, *groups])}{where}"
        )
    return [available[n] for n in names]


def scene_inputs(shared: Path, dataset: str, style: str) -> tuple[Volume, TransferFunction]:
    """The volume and TF of a shared scene (../shared/scenes/<dataset>-<style>.json)."""
    from volren import io

    path, scalars = SCENES[dataset][0], SCENES[dataset][1]
    volume = io.load_volume(shared / "data" / path, scalars=scalars)
    tf = io.load_transfer_function(shared / "scenes" / f"{dataset}-{style}.json")
    return volume, tf
