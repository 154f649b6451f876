"""One frame, drawn the one way its input asks: by a prepared renderer whole (`render_frame`, the
output checked), by a prepared renderer brick by brick from a streamed source
(`volren.bricked.sort_last`), or sort-last on a dask.distributed cluster (`volren.bricked.cluster`).

The only module that chooses between the three, so that `volren.render`, `volren render`,
`volren movie` and the app's exports draw the same input the same way.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from volren.draw.inputs import DrawInput, FrameData
from volren.model.camera import Camera
from volren.model.channels import ChannelTransferFunction
from volren.model.labels import LabelTransferFunction
from volren.model.settings import RenderSettings
from volren.model.transfer_function_2d import TransferFunction
from volren.quality import DEFAULT_LEVEL
from volren.renderers.base import FrameStats, ProgressCallback, Renderer, render_frame


class Drawn(NamedTuple):
    """A frame: float32 (H, W, 4) premultiplied RGBA over black (row 0 on top), what it did, and
    what was drawn (a level, bricks, workers: the note a command prints after its time)."""

    image: NDArray[np.float32]
    stats: FrameStats
    note: str


def draw_prepared(renderer: Renderer, data: FrameData, tf: TransferFunction | LabelTransferFunction | ChannelTransferFunction, camera: Camera, width: int, height: int,
                  progress: ProgressCallback | None = None, label: str | None = None) -> Drawn:  # fmt: skip
    """A frame of `data` by `renderer`, which holds `data.volume` (or, streamed, the scene's
    stand-in), `tf` and its settings."""
    if data.source is None:
        image, stats = render_frame(renderer, camera, width, height, progress, label=label)
        return Drawn(image, stats, data.note)
    from volren.bricked.sort_last import render_streamed

    assert not isinstance(
        tf, LabelTransferFunction | ChannelTransferFunction
    )  # read whole (`draw.labelled`, `draw.channels`)
    image, stats = render_streamed(renderer, data.source, tf, camera, width, height, progress)
    note = (
        data.note[:-1]
        + f": {stats.counters['bricks_drawn']:.0f} of {stats.counters['bricks']:.0f} bricks drawn)"
    )
    return Drawn(image, stats, note)


def draw_on_cluster(cluster: str | None, scheduler: str | None, source: DrawInput, renderer: str,
                    settings: RenderSettings, tf: TransferFunction, camera: Camera, width: int, height: int,
                    progress: ProgressCallback | None = None, quality: str = DEFAULT_LEVEL) -> Drawn:  # fmt: skip
    """A frame of `source` on a new LocalCluster (`cluster`: "local" or "local:N") or the running
    cluster at `scheduler`, brick by brick (`render_on_cluster`)."""
    from volren.bricked.cluster import render_on_cluster

    volume, level = source.on_cluster()
    image, frame, what = render_on_cluster(cluster, scheduler, volume, renderer, settings, tf, camera, width, height,
                                           level, progress, quality)  # fmt: skip
    counters: dict[str, Any] = {"bricks": frame.bricks, "bricks_drawn": frame.drawn,
                                "bricks_transparent": frame.transparent, "runs": frame.runs,
                                "workers": frame.workers, "composite_ms": frame.composite_ms}  # fmt: skip
    note = f" ({what} on {frame.workers} worker{'s' if frame.workers != 1 else ''}: {frame.drawn} of {frame.bricks} " \
           f"bricks drawn in {frame.runs} runs)"  # fmt: skip
    return Drawn(image, FrameStats(frame.total_ms, width, height, counters), note)
