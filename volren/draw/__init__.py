"""From a scene to pixels, one way for every caller.

- `inputs`: what a frame is drawn from (a volume, a time series' step, an OME-Zarr image: a
  level read whole or streamed).
- `prepared`: a renderer made and fed (`prepare`, `prepared_renderer`).
- `frame`: one frame drawn whole, streamed brick by brick, or on a cluster.
- `drawing`: `resolve_scene` (`auto`, quality levels), `check_scene`, and `Drawing`, which
  prepares and draws (and, in a ``with`` block, keeps its renderer for the next frames).
"""

from volren.draw.drawing import Drawing, Watch, check_scene, draw, resolve_scene
from volren.draw.inputs import (
    DrawInput,
    FrameData,
    VolumeInput,
    ZarrImageInput,
    is_ome_zarr_path,
    open_ome_zarr,
)
from volren.draw.prepared import Preparation, prepare, prepared_renderer

__all__ = [
    "DrawInput",
    "Drawing",
    "FrameData",
    "Preparation",
    "VolumeInput",
    "Watch",
    "ZarrImageInput",
    "check_scene",
    "draw",
    "is_ome_zarr_path",
    "open_ome_zarr",
    "prepare",
    "prepared_renderer",
    "resolve_scene",
]
