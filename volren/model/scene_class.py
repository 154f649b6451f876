"""What a scene is, for choosing settings: its volume kind and its 1D TF's class (`tf_class`).

The measured quality levels are looked up by it (`volren.quality`), a TF class's levels first and
the volume kind's, over every TF, where the class has none.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from volren.model.tf_class import TFClass


@dataclass(frozen=True)
class SceneClass:
    """A volume kind ("uniform" grids, "tet" meshes) with its TF's class (None: any TF, or one
    without a class). Written "uniform/smooth" or "uniform" in the measured levels' files."""

    kind: str
    tf: TFClass | None = None

    @classmethod
    def of(cls, volume: Any, tf: object) -> SceneClass:
        """The class of a volume (its `kind` and `value_range`) drawn with `tf`."""
        return cls(volume.kind, TFClass.of(tf, volume.value_range))

    @classmethod
    def parse(cls, text: str) -> SceneClass:
        """The class `str` wrote ("uniform/smooth" or "uniform"); ValueError for an unknown TF class."""
        kind, _, tf = text.partition("/")
        return cls(kind, TFClass(tf) if tf else None)

    @property
    def volume(self) -> SceneClass:
        """The class of any TF on this volume kind (the fallback where a TF class was not measured)."""
        return SceneClass(self.kind)

    def __str__(self) -> str:
        return f"{self.kind}/{self.tf.value}" if self.tf is not None else self.kind
