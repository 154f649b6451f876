"""`volren bench run`'s measurement: every configuration of the sweep on every scene, timed and scored.

Timing: one warm-up frame at the scene's view (shader compilation, uploads, tables, numba), then
`frames` timed frames while the camera turns in azimuth steps of `turn` degrees around that view
(-2, 0, +2, ... for three frames), so no renderer can reuse the last frame's per-view work; the
time is their median. Error: DESIGN.md's RMSE and max abs, and the count of pixels off by more
than 0.1 (`off`), of the timed frame at the scene's own view (offset 0 is always among the turns)
against `reference` at that view, from the on-disk reference cache
(`volren.testing.reference_images`), so each scene needs one reference image per size, ever.
Curves in `sweep.ONE_FRAME_CURVES` (VTK's ZSweep) time one frame at the scene's view, with no
warm-up: at 30-80 s a frame, a warm-up and a median would cost minutes per scene.

Label and channel scenes (`volren.bench.mixed_datasets`) are drawn by the renderers whose
capabilities say they draw them; the others are reported refused (`Progress.refused`), not failed.

Rows are dicts with `COLUMNS` as keys, written to CSV as they come.
"""

from __future__ import annotations

import csv
import statistics
import time
from collections.abc import Callable, Iterable, Iterator
from typing import IO, Any

import numpy as np
from numpy.typing import NDArray

from volren.api import prepared_renderer
from volren.bench.datasets import Dataset, HardDataset
from volren.bench.mixed_datasets import MixedDataset
from volren.bench.summary import REFUSED
from volren.bench.sweep import Config
from volren.bench.viewer_peers import open_peer
from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.channels import ChannelTransferFunction
from volren.model.labels import LabelTransferFunction
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import Volume
from volren.renderers.base import Renderer, render_frame
from volren.renderers.registry import registry
from volren.testing.metrics import image_error
from volren.testing.reference_images import reference_image

COLUMNS = (
    "dataset", "kind", "tf", "renderer", "settings", "step", "preintegration", "table_size", "table_lengths",
    "jitter", "skipping", "size", "frames", "ms", "rmse", "max_abs", "psnr", "samples", "cell_steps", "off",
)  # fmt: skip
TURN_DEGREES = 2.0


def turn_offsets(frames: int, turn: float) -> list[float]:
    """Azimuth offsets of the timed frames: consecutive steps of `turn`, 0 at index frames // 2."""
    return [(k - frames // 2) * turn for k in range(frames)]


def time_turning(
    renderer: Renderer,
    camera_at: Callable[[float], Camera],
    size: int,
    frames: int,
    turn: float,
    warmup: bool = True,
) -> tuple[float, NDArray[np.float32], dict[str, float]]:
    """(median ms of the turning frames, the image at offset 0, that frame's counters)."""
    if warmup:
        renderer.render(camera_at(0.0), size, size)
    times, image, counters = [], None, {}
    for offset in turn_offsets(frames, turn):
        camera = camera_at(offset)
        start = time.perf_counter()
        frame, stats = render_frame(renderer, camera, size, size)
        times.append((time.perf_counter() - start) * 1000.0)
        if offset == 0.0:
            image, counters = frame, dict(stats.counters)
    assert image is not None  # offset 0 is always among the turns
    return statistics.median(times), image, counters


def measure(
    config: Config,
    volume: Volume,
    tf: TransferFunction1D | LabelTransferFunction | ChannelTransferFunction,
    camera_at: Callable[[float], Camera],
    reference: NDArray[np.float32],
    size: int,
    frames: int,
    turn: float,
) -> dict:
    """One row: the configuration timed while turning and scored against the reference image."""
    if config.one_frame:
        frames = 1
    drawer: Any
    if config.viewer:  # drawn as a PyVista or napari user draws it, not by a registered renderer
        if not isinstance(tf, TransferFunction1D):
            raise VolrenError(f"{config.curve}: {refusal(config, 'uniform', tf)}")
        drawer = open_peer(config.curve, volume, tf)
    else:
        drawer = prepared_renderer(config.renderer, volume, tf, config.settings())
    with drawer as renderer:
        ms, image, counters = time_turning(
            renderer, camera_at, size, frames, turn, warmup=not config.one_frame
        )
    err = image_error(image, reference)
    return {
        "renderer": config.curve,
        "settings": config.label,
        "step": config.step,
        "preintegration": config.preintegration,
        "table_size": config.table_size,
        "table_lengths": config.table_lengths,
        "jitter": config.jitter,
        "skipping": config.skipping,
        "size": size,
        "frames": frames,
        "ms": ms,
        "rmse": err.rmse,
        "max_abs": err.max_abs,
        "psnr": err.psnr,
        "samples": counters.get("samples"),
        "cell_steps": counters.get("cell_steps"),
        "off": err.off,
    }


def refusal(config: Config, kind: str, tf: Any) -> str | None:
    """Why the configuration's renderer declines to draw a label or channel scene (its
    `Capabilities`: a TF per label or per channel, pre-integrated or not), or None. A viewer peer
    draws one field with one 1D TF, as its users do."""
    labels, channels = isinstance(tf, LabelTransferFunction), isinstance(tf, ChannelTransferFunction)
    if not (labels or channels):
        return None
    if config.viewer:
        return f"{config.curve} draws one field with one 1D TF, as its users draw it"
    try:
        capabilities = registry.capabilities(config.renderer)
    except VolrenError:
        return None  # an unknown renderer: measuring it says why
    reason = capabilities.unsupported_reason(kind, 1, config.settings(), labels=labels, channels=channels)
    return f"{config.renderer} {reason}" if reason else None


class Progress:
    """What the run reports as it goes (the CLI draws a bar from it)."""

    def status(self, text: str) -> None:
        """Now doing `text` (loading, rendering a reference, ...)."""

    def row(self, row: dict) -> None:
        """One configuration finished."""

    def skipped(self, what: str, reason: str) -> None:
        """One configuration could not run."""

    def refused(self, what: str, reason: str) -> None:
        """One configuration's renderer declines the scene (`refusal`): not a failure. Reported as
        skipped with `REFUSED` before the reason unless overridden."""
        self.skipped(what, REFUSED + reason)


#: What `run` measures: a shared dataset or sample, a hard procedural scene, a label or channel scene.
AnyDataset = Dataset | HardDataset | MixedDataset


def run(
    datasets: Iterable[AnyDataset],
    sweep: Callable[[str], list[Config]],
    size: int,
    frames: int,
    turn: float = TURN_DEGREES,
    styles: Iterable[str] | None = None,
    progress: Progress | None = None,
) -> Iterator[dict]:
    """Rows for every dataset, TF style (all, or those in `styles`) and configuration of `sweep(kind)`.

    A configuration a renderer refuses (VolrenError: no OpenGL, a mapper this VTK lacks) is
    reported to `progress.skipped` and left out, so one missing renderer cannot sink a long run.
    """
    progress = progress or Progress()
    wanted = set(styles) if styles is not None else None
    for dataset in datasets:
        configs = sweep(dataset.kind)
        if configs:
            yield from _dataset_rows(dataset, configs, size, frames, turn, wanted, progress)


def _dataset_rows(
    dataset: AnyDataset,
    configs: list[Config],
    size: int,
    frames: int,
    turn: float,
    wanted: set[str] | None,
    progress: Progress,
) -> Iterator[dict]:
    """The rows of one dataset (its volume is freed when this generator ends)."""
    progress.status(f"loading {dataset.name}")
    volume = dataset.load()

    def camera_at(offset: float) -> Camera:
        return dataset.camera(volume.bounds, offset)

    for style, tf in dataset.transfer_functions():
        if wanted is not None and style not in wanted:
            continue
        progress.status(f"reference {dataset.name} {style}")
        reference = reference_image(volume, tf, camera_at(0.0), size, size)
        for config in configs:
            what = f"{dataset.name} {style} {config.curve} {config.label}"
            progress.status(what)
            reason = refusal(config, dataset.kind, tf)
            if reason is not None:
                progress.refused(what, reason)
                continue
            try:
                row = measure(config, volume, tf, camera_at, reference, size, frames, turn)
            except VolrenError as exc:
                progress.skipped(what, str(exc))
                continue
            row = {"dataset": dataset.name, "kind": dataset.kind, "tf": style, **row}
            progress.row(row)
            yield row


def _cell(value: object) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "on" if value else "off"
    if isinstance(value, float):
        if value.is_integer() and abs(value) < 1e15:
            return str(int(value))  # counters and steps: 143193, 2
        return f"{value:.6g}"
    return str(value)


class CsvWriter:
    """runs.csv, one row per configuration, flushed as each comes (a long run leaves what it did)."""

    def __init__(self, stream: IO[str]) -> None:
        self._stream = stream
        self._writer = csv.writer(stream)
        self._writer.writerow(COLUMNS)

    def write(self, row: dict) -> None:
        self._writer.writerow([_cell(row.get(c)) for c in COLUMNS])
        self._stream.flush()
