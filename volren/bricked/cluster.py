"""Sort-last rendering on a dask.distributed cluster: bricks rendered where their data is kept,
each worker compositing its contiguous runs, the client finishing the ordered composite.

How a frame goes:
1. Ownership (data locality): the brick grid is cut into k-d blocks (`visibility.kd_blocks`), a
   few per worker, and each block belongs to one worker for as long as the volume is drawn, so
   the chunks it reads stay in that worker's cache from frame to frame.
2. The client orders the visible bricks front to back for the camera. A k-d block's bricks come
   one after another in that order, so the order cuts into runs, one block each.
3. Each run is a task on its block's worker (`allow_other_workers`: when that worker is lost,
   the scheduler reruns the task elsewhere and the frame completes). The task draws its bricks
   with the worker's own renderer into one layer, composited front to back, and sends back only
   the layer's rectangle of pixels.
4. The client composites the runs' layers in run order as they all arrive, and reports progress
   in bricks as each run finishes.

Workers keep one renderer and one open source per (source, renderer) in a per-process cache
(`_worker_state`), so GL contexts, compiled shaders and chunk caches live across frames.
"""

from __future__ import annotations

import asyncio
import threading
import time
import uuid
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from volren.bricked.composite import over
from volren.bricked.layout import BrickLayout, Index3
from volren.bricked.sort_last import RunCost, brick_layout, check_draws_bricks, draw_run, visible_bricks
from volren.bricked.source import BrickSource, VolumeSource
from volren.bricked.visibility import front_to_back, kd_blocks
from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.settings import RenderSettings
from volren.model.transfer_function_2d import TransferFunction
from volren.model.volume import UniformVolume
from volren.quality import DEFAULT_LEVEL
from volren.renderers.base import ProgressCallback

#: Seconds the client waits for a scheduler to answer before a one-line error.
CONNECT_TIMEOUT_S = 10.0
#: Render bricks of this many cells per side for an in-memory volume (OME-Zarr: its chunk side).
VOLUME_BRICK = 64
#: k-d blocks per worker: a few, so that a lost worker's share spreads over the others, and
#: progress comes in steps.
BLOCKS_PER_WORKER = 4


# ------------------------------------------------------------------------------- sources
@dataclass(frozen=True)
class ZarrSpec:
    """A level of an OME-Zarr image, which every worker opens itself (a path all of them read)."""

    path: str
    level: int
    budget: int

    @property
    def key(self) -> tuple:
        return ("zarr", self.path, self.level, self.budget)

    def open(self, data: Any = None) -> BrickSource:
        from volren.bricked.zarr_source import ZarrSource
        from volren.io.ome_zarr_io import open_multiscale

        return ZarrSource(open_multiscale(self.path), self.level, self.budget)


@dataclass(frozen=True)
class VolumeSpec:
    """An in-memory volume, sent to every worker once (`Client.scatter`): tasks carry the
    scattered volume as an argument of their own (`data`), where dask resolves it."""

    volume: UniformVolume
    token: str = field(default_factory=lambda: uuid.uuid4().hex)

    @property
    def key(self) -> tuple:
        return ("volume", self.token)

    def __getstate__(self) -> dict:
        return {"volume": None, "token": self.token}  # the workers get the volume scattered, once

    def __setstate__(self, state: dict) -> None:
        object.__setattr__(self, "volume", state["volume"])
        object.__setattr__(self, "token", state["token"])

    def open(self, data: Any = None) -> BrickSource:
        return VolumeSource(data if data is not None else self.volume)


# ------------------------------------------------------------------------------- workers
_WORKER_STATE: dict[tuple, tuple[Any, BrickSource]] = {}


def _worker_state(spec: Any, renderer_name: str, data: Any) -> tuple[Any, BrickSource]:
    """This process's renderer and open source for (spec, renderer), made on first use."""
    key = (spec.key, renderer_name)
    state = _WORKER_STATE.get(key)
    if state is None:
        from volren.renderers.registry import registry

        state = (registry.create(renderer_name), spec.open(data))
        _WORKER_STATE[key] = state
    return state


@dataclass(frozen=True)
class RunLayer:
    """What a worker sends back for a run: the layer's rectangle and what the run cost."""

    rect: tuple[int, int, int, int]
    pixels: NDArray[np.float32]
    cost: RunCost
    worker: str


def render_run(spec: Any, data: Any, renderer_name: str, settings: RenderSettings, tf: TransferFunction,
               camera: Camera, width: int, height: int, brick: int, ghost: int, run: list[Index3]) -> RunLayer:  # fmt: skip
    """(On a worker) the bricks of `run`, front to back, composited into one layer; `data` is the
    scattered volume of a `VolumeSpec` (None for a `ZarrSpec`)."""
    renderer, source = _worker_state(spec, renderer_name, data)
    renderer.set_settings(settings)
    layout = brick_layout(source, brick)
    image = np.zeros((height, width, 4), dtype=np.float64)
    cost = RunCost()
    draw_run(renderer, source, layout, tf, camera, image, ghost, run, cost)
    rect = _union_rect([layout.region(layout.brick_at(i)).pixel_rect(camera, width, height) for i in run])
    x0, y0, x1, y1 = rect
    try:
        from distributed import get_worker

        worker = get_worker().address
    except (ImportError, ValueError):
        worker = "local"
    return RunLayer(rect, image[y0:y1, x0:x1].astype(np.float32), cost, worker)


def _union_rect(rects: list[tuple[int, int, int, int]]) -> tuple[int, int, int, int]:
    if not rects:
        return 0, 0, 0, 0
    a = np.array(rects)
    return int(a[:, 0].min()), int(a[:, 1].min()), int(a[:, 2].max()), int(a[:, 3].max())


# -------------------------------------------------------------------------------- client
def require_distributed() -> Any:
    try:
        import distributed
    except ImportError:
        raise VolrenError("rendering on a cluster needs dask.distributed, which is not installed: "
                          "pip install 'volren[cluster]'") from None  # fmt: skip
    return distributed


def parse_cluster(text: str) -> int:
    """Workers of `local` (as many as cores) or `local:N`."""
    head, _, count = text.partition(":")
    if head != "local":
        raise VolrenError(f"--cluster takes local or local:N (N worker processes), got {text!r}; "
                          "for a running cluster give --scheduler ADDRESS")  # fmt: skip
    if not count:
        import os

        return max(os.cpu_count() or 1, 1)
    if not count.isdigit() or not 1 <= int(count) <= 256:
        raise VolrenError(f"--cluster local:N needs N in 1..256 worker processes, got {count!r}")
    return int(count)


#: Worker processes render with one thread each: N workers use N cores, as the scaling
#: benchmark assumes (Mesa llvmpipe and numba would otherwise each take every core).
ONE_THREAD_ENV = {"LP_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}


def local_client(workers: int) -> Any:
    """A Client on a new LocalCluster of `workers` processes, one thread each."""
    distributed = require_distributed()
    cluster = distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                       dashboard_address=":0", env=dict(ONE_THREAD_ENV))  # fmt: skip
    return distributed.Client(cluster)


def connect(address: str, timeout: float | None = None) -> Any:
    """A Client on the scheduler at `address`; one line naming --scheduler, within about
    `timeout` s, when it cannot."""
    distributed = require_distributed()
    timeout = CONNECT_TIMEOUT_S if timeout is None else timeout
    if not address.strip():
        raise VolrenError(
            "--scheduler needs the ADDRESS of a running dask scheduler (e.g. tcp://host:8786), got ''"
        )
    connection_args = distributed.Security().get_connection_args("client")
    if address.startswith("tls://") and connection_args["ssl_context"] is None:
        raise VolrenError(f"--scheduler {address}: a TLS scheduler needs the client's certificate in dask's "
                          "configuration (distributed.comm.tls.ca-file, .client.cert and .client.key)")  # fmt: skip
    try:
        greet_scheduler(address, connection_args, timeout)
    except Exception as exc:  # noqa: BLE001 - whatever met the greeting (a closed port, garbage, a bad address), one line
        raise VolrenError(f"--scheduler: cannot reach the dask scheduler at {address} within {timeout:g} s "
                          f"({_connect_problem(exc)})") from None  # fmt: skip
    try:
        return distributed.Client(address, timeout=f"{timeout}s")
    except Exception as exc:  # noqa: BLE001 - a scheduler that answered and then refused (versions, TLS), one line
        reason = " ".join(str(exc).split())[:160] or "no reason given"
        raise VolrenError(
            f"--scheduler: the dask scheduler at {address} did not take this client ({reason})"
        ) from None


def greet_scheduler(address: str, connection_args: Mapping[str, Any], timeout: float) -> None:
    """Open a connection to `address`, exchange dask's greeting and hang up, all within `timeout` s.

    Why: distributed bounds making the connection but not waiting for the greeting after it, so a
    port where something else listens (a web server, a service that says nothing) would keep a
    Client waiting for ever. The greeting runs on an event loop of its own, in a thread, so that it
    works whether or not the caller runs one (a notebook does)."""
    from distributed.comm import connect as open_comm

    async def greet() -> None:
        comm = await asyncio.wait_for(open_comm(address, timeout=timeout, **connection_args), timeout)
        await comm.close()

    failures: list[BaseException] = []

    def run() -> None:
        try:
            asyncio.run(greet())
        except BaseException as exc:  # noqa: BLE001 - handed to the caller's thread
            failures.append(exc)

    thread = threading.Thread(target=run, name="volren-scheduler-greeting", daemon=True)
    thread.start()
    thread.join(timeout + 1.0)
    if thread.is_alive():
        raise TimeoutError
    if failures:
        raise failures[0]


def _connect_problem(exc: BaseException) -> str:
    """Why a scheduler could not be reached, in words (never an exception's class)."""
    if isinstance(exc, TimeoutError):
        return "no answer"
    if isinstance(exc, OSError | ValueError):
        return " ".join(str(exc).split())[:160] or "the connection failed"
    return "what answered is not a dask scheduler"


@dataclass(frozen=True)
class ClusterFrame:
    """What a distributed frame did and cost (ms)."""

    bricks: int
    drawn: int
    transparent: int
    runs: int
    workers: int
    total_ms: float
    composite_ms: float
    worker_ms: Mapping[str, float]


class ClusterRenderer:
    """Frames of one source with one renderer on a dask.distributed cluster (`client`)."""

    def __init__(self, client: Any, spec: ZarrSpec | VolumeSpec, renderer: str, brick: int = 64) -> None:
        from volren.renderers.registry import registry

        self.client = client
        self.renderer_name = renderer
        self._probe = registry.create(renderer)  # for capabilities and ghost voxels; draws nothing
        check_draws_bricks(self._probe)
        self.source: BrickSource = spec.open()
        self.spec = spec
        self._data = self._scatter()
        self.layout: BrickLayout = brick_layout(self.source, brick)
        self._owners: dict[int, str] = {}

    def _scatter(self) -> Any:
        """The in-memory volume on every running worker (None for a `ZarrSpec`), under a key of its own:
        a key from the volume's hash is shared by every renderer of equal data, so one renderer's
        release could forget what another still uses."""
        if not isinstance(self.spec, VolumeSpec):
            return None
        return self.client.scatter(self.spec.volume, broadcast=True, hash=False)

    def _block_owners(self, blocks: NDArray[np.intp]) -> dict[int, str]:
        """Which worker keeps each k-d block (kept from frame to frame while the workers stay)."""
        workers = sorted(self.client.scheduler_info()["workers"])
        if not workers:
            raise VolrenError("the dask cluster has no workers")
        n_blocks = int(blocks.max()) + 1
        if set(self._owners.values()) - set(workers) or len(self._owners) != n_blocks:
            self._owners = {b: workers[b * len(workers) // n_blocks] for b in range(n_blocks)}
        return self._owners

    def render(self, settings: RenderSettings, tf: TransferFunction, camera: Camera, width: int, height: int,
               progress: ProgressCallback | None = None) -> tuple[NDArray[np.float32], ClusterFrame]:  # fmt: skip
        distributed = require_distributed()
        start = time.perf_counter()
        self._probe.set_settings(settings)
        ghost = int(self._probe.ghost_voxels(self.layout.spacing, camera, width, height))
        visible = visible_bricks(self.source, self.layout, tf, ghost)
        n_workers = max(len(self.client.scheduler_info()["workers"]), 1)
        blocks = kd_blocks(self.layout, BLOCKS_PER_WORKER * n_workers)
        owners = self._block_owners(blocks)
        runs: list[list[Index3]] = []
        run_blocks: list[int] = []
        for index in front_to_back(self.layout, camera):
            if not visible[index]:
                continue
            block = int(blocks[index])
            if not run_blocks or run_blocks[-1] != block:
                runs.append([])
                run_blocks.append(block)
            runs[-1].append(index)
        layers: list[RunLayer | None] = [None] * len(runs)
        total_bricks = sum(len(r) for r in runs)
        done = 0
        for attempt in range(2):
            pending = [n for n in range(len(runs)) if layers[n] is None]
            futures = [
                self.client.submit(render_run, self.spec, self._data, self.renderer_name, settings, tf, camera, width,
                                   height, self.layout.brick, ghost, runs[n], workers=[owners[run_blocks[n]]],
                                   allow_other_workers=True, retries=2, pure=False)
                for n in pending
            ]  # fmt: skip
            index_of = {f.key: n for f, n in zip(futures, pending, strict=True)}
            try:
                for future in distributed.as_completed(futures):
                    n = index_of[future.key]
                    layers[n] = future.result()
                    done += len(runs[n])
                    if progress is not None:
                        progress(done / max(total_bricks, 1))
                break
            except VolrenError:
                raise
            except Exception as exc:  # noqa: BLE001 - a worker's failure, whatever it was, on one line
                for future in futures:
                    future.cancel()
                if attempt == 0 and self._data is not None:
                    # the workers that held the scattered volume may all be gone (a worker that joined after
                    # the scatter has none): send it again and redo the runs not yet drawn, once
                    self._data = self._scatter()
                    continue
                reason = " ".join(str(exc).split())[:200] or "a worker failed without a reason"
                raise VolrenError(f"the cluster could not render the frame: {reason}") from None
        if progress is not None and not runs:
            progress(1.0)
        t0 = time.perf_counter()
        image = np.zeros((height, width, 4), dtype=np.float64)
        worker_ms: dict[str, float] = {}
        drawn = 0
        for layer in layers:
            assert layer is not None
            x0, y0, x1, y1 = layer.rect
            over(image[y0:y1, x0:x1], layer.pixels, out=image[y0:y1, x0:x1])
            cost = layer.cost
            worker_ms[layer.worker] = (
                worker_ms.get(layer.worker, 0.0) + cost.read_ms + cost.render_ms + cost.composite_ms
            )
            drawn += cost.drawn
        composite_ms = (time.perf_counter() - t0) * 1000.0
        frame = ClusterFrame(self.layout.n_bricks, drawn, int(np.count_nonzero(~visible)), len(runs), n_workers,
                             (time.perf_counter() - start) * 1000.0, composite_ms, worker_ms)  # fmt: skip
        return image.astype(np.float32), frame

    def close(self) -> None:
        """Release the probe renderer and the workers' copies of the scattered volume."""
        self._probe.release()
        if self._data is not None:
            self._data.release()
            self._data = None


def _check_draws_bricks(renderer: str) -> None:
    """Before a worker starts (seconds): a renderer that cannot draw a brick alone has no share
    of a frame to give a worker."""
    from volren.renderers.registry import registry

    def draws_bricks(name: str) -> bool:
        support = registry.capabilities(name).kinds.get("uniform")
        return support is not None and support.regions

    if not draws_bricks(renderer):
        able = ", ".join(name for name in registry.available() if draws_bricks(name))
        raise VolrenError(f"renderer {renderer} does not draw bricks, which a cluster (--cluster, --scheduler) needs; "
                          f"these do: {able}")  # fmt: skip


def render_on_cluster(
    cluster: str | None,
    scheduler: str | None,
    volume: Any,
    renderer: str,
    settings: RenderSettings,
    tf: TransferFunction,
    camera: Camera,
    width: int,
    height: int,
    level: int | None = None,
    progress: ProgressCallback | None = None,
    quality: str = DEFAULT_LEVEL,
) -> tuple[NDArray[np.float32], ClusterFrame, str]:
    """One frame on a new LocalCluster (`cluster`: "local" or "local:N") or the running cluster
    at `scheduler`, of `volume`: a `ZarrInput` (its `level`, else the level `quality` draws:
    `zarr_source.level_at_quality`) or a `UniformVolume`. Returns the image, what the frame did,
    and what was drawn."""
    from volren.bricked.zarr_input import ZarrInput
    from volren.bricked.zarr_source import level_at_quality

    if isinstance(volume, ZarrInput):
        if level is None:
            level = level_at_quality(volume.image.levels, camera, width, height, quality)
        volume.check_level(level)
        spec: ZarrSpec | VolumeSpec = ZarrSpec(volume.path, level, volume.budget)
        brick = int(min(volume.image.levels[level].chunks))
        what = f"{volume.name} level {level}"
    elif isinstance(volume, UniformVolume):
        spec, brick, what = VolumeSpec(volume), VOLUME_BRICK, volume.name
    else:
        raise VolrenError("a cluster renders uniform volumes (bricks); this one is tetrahedral")
    _check_draws_bricks(renderer)
    client = (
        connect(scheduler)
        if scheduler is not None
        else local_client(parse_cluster("local" if cluster is None else cluster))
    )
    cluster_renderer = None
    try:
        cluster_renderer = ClusterRenderer(client, spec, renderer, brick)
        image, frame = cluster_renderer.render(settings, tf, camera, width, height, progress)
    finally:
        if cluster_renderer is not None:
            cluster_renderer.close()
        local = getattr(client, "cluster", None) if scheduler is None else None
        client.close()
        if local is not None:
            local.close()
    return image, frame, what
