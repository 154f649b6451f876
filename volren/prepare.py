"""Compile the renderers' kernels ahead of their first use, so that a first frame does not wait.

Why: the CPU renderers' kernels are numba functions cached on disk (``cache=True``) per argument
types, and a fresh install has no cache: the first `tetra` frame waited 37-46 s and the first
`reference` frame 54 s while numba compiled. `scripts/setup.sh` runs `volren prepare` once per
change of the sources, which draws a tiny scene with every registered renderer in every
combination its capabilities claim and at every level of its quality axis (TF dimensions,
pre-integration, shading, blend modes, the levels' options, label volumes and channels; both
projections; every kept scalar type of a uniform grid), so that every specialization a real scene
needs is compiled and cached (and the OpenGL drivers' shader caches are warm). numba checks each
cached function against its source file's time stamp, and packages whose kernels span modules drop
stale caches themselves (`volren.numba_cache`), so an edit recompiles only what changed.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace

import numpy as np

from volren.errors import VolrenError
from volren.model import Camera, RenderSettings, TransferFunction1D, UniformVolume, Volume
from volren.model.channels import ChannelTransferFunction
from volren.model.labels import LabelTransferFunction
from volren.model.transfer_function_2d import TransferFunction
from volren.model.volume import KEPT_DTYPES
from volren.renderers.base import KindSupport
from volren.testing.checks import contract_combinations, kit_tf_2d
from volren.testing.scenes import lattice_volume

#: A frame to draw: (TF, settings, camera, optional: a refusal passes it over).
Frame = tuple[
    TransferFunction | LabelTransferFunction | ChannelTransferFunction, RenderSettings, Camera, bool
]

#: Side of the images drawn (small: only the compilation matters).
SIZE = 12


@dataclass(frozen=True)
class Prepared:
    """One renderer's preparation: how long it took, how many frames, and the error that stopped it."""

    name: str
    seconds: float
    frames: int
    error: str | None = None


def _volumes(kind: str) -> Iterator[Volume]:
    """Small volumes of `kind`: a uniform grid in every kept scalar type, or a tetrahedral lattice."""
    if kind == "tet":
        yield lattice_volume("tet", lambda x, y, z: x + 0.5 * y - 0.3 * z, (4, 4, 3), name="prepare")
        return
    z, y, x = np.mgrid[0:5, 0:6, 0:7]
    ramp = (x * 7 + y * 3 + z * 5).astype(np.float64)
    for dtype in KEPT_DTYPES:
        yield UniformVolume(
            ramp.astype(dtype), spacing=(1.0, 0.9, 1.1), name=f"prepare {np.dtype(dtype).name}"
        )


def _scenes(name: str) -> Iterator[tuple[Volume, list[Frame]]]:
    """Per small volume, the (TF, settings, camera, optional) of every combination `name`'s
    capabilities claim, then of every level of its quality axis with a 1D TF (and a 2D one where
    claimed): a level's options (adaptive image refinement, an error target) reach kernels the
    default settings never do, and `volren render`'s default level is one of them (with them
    compiled at the first frame, a fresh install's first refined tetra frame took 2.0 s instead of
    0.7). A level is optional: one that does not apply to this kind of volume is passed over."""
    from volren.renderers.registry import registry

    capabilities = registry.capabilities(name)
    for kind, support in capabilities.kinds.items():
        for volume in _volumes(kind):
            lo, hi = volume.value_range
            tf1 = TransferFunction1D([[lo, 0.2, 0.4, 0.9], [hi, 1.0, 0.6, 0.1]], [[lo, 0.0], [hi, 0.8]])
            tf2 = kit_tf_2d()
            cameras = [Camera.orbit(volume.bounds, 30, 20, parallel=parallel) for parallel in (False, True)]
            claimed: list[Frame] = [(tf1 if dims == 1 else tf2, settings, camera, False)
                       for dims, settings, is_claimed in contract_combinations(support) if is_claimed
                       for camera in cameras]  # fmt: skip
            tfs = (tf1, tf2) if 2 in support.tf_dims else (tf1,)  # a 2D TF runs kernels of its own
            levels: list[Frame] = [
                (tf, level.apply(), camera, True)
                for level in capabilities.quality
                for tf in tfs
                for camera in cameras
            ]
            yield volume, claimed + levels
            if isinstance(volume, UniformVolume):
                yield from _mixed_scenes(volume, support, tf1, cameras)


#: The types a label volume is kept in (`volren.model.labels`): each compiles kernels of its own.
LABEL_DTYPES = (np.uint8, np.uint16)


def _mixed_scenes(volume: UniformVolume, support: KindSupport, tf: TransferFunction1D, cameras: list[Camera]
                  ) -> Iterator[tuple[Volume, list[Frame]]]:  # fmt: skip
    """The label volumes (in each kept label type) and the two channels on `volume`'s grid that
    `support` claims, drawn composite and post-classified (the contract's only label and channel
    settings, renderer-contract.md section 2): their kernels are the march's own, not the plain ones.
    Optional: a renderer may refuse some of them at render time (vtk: labels above 255)."""
    from volren.model.channels import ChannelSet
    from volren.model.labels import LabelMap, LabelStyle

    post = RenderSettings(preintegration=False)
    values = volume.values
    if support.labels:
        label_tf = LabelTransferFunction(
            tf, {2: LabelStyle(color=(0.1, 0.9, 0.2)), 3: LabelStyle(visible=False)}
        )
        for dtype in LABEL_DTYPES:
            labels = (np.indices(values.shape).sum(axis=0) % 4).astype(dtype)
            if dtype == np.uint16:
                labels[0, 0, 0] = 300  # past 8 bits: kept as uint16
            labelled = replace(
                volume, labels=LabelMap(labels), name=f"{volume.name} labels {np.dtype(dtype).name}"
            )
            yield labelled, [(label_tf, post, camera, True) for camera in cameras]
    if support.channels:
        channels = ChannelSet(np.stack([values, values[::-1]]), name=f"{volume.name} channels")
        channel_tf = ChannelTransferFunction([tf, tf.copy()], [1.0, 0.5])
        yield replace(volume, channels=channels), [(channel_tf, post, camera, True) for camera in cameras]


def prepare_renderer(name: str) -> Prepared:
    """Draw every claimed combination and quality level with renderer `name` (one renderer per volume, as the app keeps
    one); an error stops it and is reported in one line. A renderer that drew with C kernels
    (`volren.kernels.native`) draws everything a second time with them off, so that the numba kernels they stand
    in for are compiled too (a grid they cannot take, and ``VOLREN_NATIVE=0``, draw with those)."""
    from volren.kernels import native

    start = time.perf_counter()
    frames = 0
    try:
        before = native.handed_out()
        frames += _draw_scenes(name, numba_only=False)
        if native.handed_out() > before:
            frames += _draw_scenes(name, numba_only=True)
    except VolrenError as exc:
        return Prepared(name, time.perf_counter() - start, frames, str(exc))
    except Exception as exc:  # noqa: BLE001 - a plugin's failure is reported, never fatal to set-up
        return Prepared(
            name, time.perf_counter() - start, frames, f"{type(exc).__name__}: {' '.join(str(exc).split())}"
        )
    return Prepared(name, time.perf_counter() - start, frames)


def _draw_scenes(name: str, numba_only: bool) -> int:
    """How many frames `prepare_renderer`'s scenes drew with `name`, with the C kernels off where `numba_only`."""
    from volren.renderers.registry import registry

    before = os.environ.get("VOLREN_NATIVE")
    if numba_only:
        os.environ["VOLREN_NATIVE"] = "0"
    frames = 0
    try:
        for volume, frames_of_volume in _scenes(name):
            renderer = registry.create(name)
            try:
                renderer.set_volume(volume)
                for tf, settings, camera, optional in frames_of_volume:
                    try:
                        renderer.set_transfer_function(tf)
                        renderer.set_settings(settings)
                        renderer.render(camera, SIZE, SIZE)
                    except VolrenError:
                        if not optional:
                            raise
                        continue
                    frames += 1
            finally:
                renderer.release()
    finally:
        if before is None:
            os.environ.pop("VOLREN_NATIVE", None)
        else:
            os.environ["VOLREN_NATIVE"] = before
    return frames


def default_jobs() -> int:
    """The processes `prepare` runs at once by default: one per core this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


def prepare(names: list[str] | None = None, on_done: Callable[[Prepared], None] | None = None,
            jobs: int = 1) -> list[Prepared]:  # fmt: skip
    """`prepare_renderer` for `names` (default: every registered renderer), in order of `names`; `on_done`
    is called as each finishes. With jobs > 1, that many renderers at once, each in its own process:
    numba compiles on one core, so on a 2-core machine set-up's compilation takes about half as long
    (renderers registered at run time, which a worker process does not know, are prepared in this one)."""
    from volren.renderers.registry import registry

    names = list(names) if names is not None else registry.names()
    if jobs <= 1 or len(names) <= 1:
        out = []
        for name in names:
            result = prepare_renderer(name)
            out.append(result)
            if on_done is not None:
                on_done(result)
        return out
    return _prepare_in_processes(names, on_done, min(jobs, len(names)))


def _prepare_in_processes(names: list[str], on_done: Callable[[Prepared], None] | None, jobs: int,
                          work: Callable[[str], Prepared] = prepare_renderer) -> list[Prepared]:  # fmt: skip
    """`prepare` in `jobs` fresh (spawned: no forked threads of numba, OpenGL or Qt) worker processes, each
    running `work` per name; a worker that dies (a crash in a driver or a kernel) is reported for the
    renderers it leaves unprepared, not fatal."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    from volren.renderers.registry import registry

    start = time.perf_counter()
    results: dict[str, Prepared] = {}

    def finished(result: Prepared) -> None:
        results[result.name] = result
        if on_done is not None:
            on_done(result)

    here = [name for name in names if registry.registered_in_process(name)]
    elsewhere = [name for name in names if name not in here]
    with ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("spawn")) as pool:
        futures = {pool.submit(work, name): name for name in elsewhere}
        for name in here:  # while the workers compile
            finished(work(name))
        for future in as_completed(futures):
            name = futures[future]
            try:
                result = future.result()
            except Exception as exc:  # noqa: BLE001 - a dead worker is reported, never fatal to set-up
                detail = " ".join(str(exc).split()) or type(exc).__name__
                result = Prepared(name, time.perf_counter() - start, 0, f"worker process failed: {detail}")
            finished(result)
    return [results[name] for name in names]
