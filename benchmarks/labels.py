"""`python -m benchmarks.labels --shared ../shared`: what a label volume costs and how accurate it is,
on the shared segmentations (the PD25 brain template with its 16 subcortical labels, the frog's 15
tissues) and a procedural sphere in a sphere.

Why: a TF per label (Real-Time Volume Graphics, chapter 16) must cost little more than the volume
without labels, and hidden labels must cost nothing (`volren.model.labels`). Per scene, with the
renderer and settings a render with no options picks for the label scene (`auto`, quality
`default`): the unlabelled frame with the base TF at the same settings, the labelled frame (every
label shown in its file's colour over the base TF's opacity, so that the visible opacity is the
same), and the labelled frame with 90 % of the labels hidden (the background first), all three at
the step the label scene's error target chose (so that the ratio is the cost of labels per
sample, not of two steps), warm, median of `--frames` turning frames each, in turns. Then the
error of the unlabelled and the labelled frame, each at the settings a render with no options has,
against `reference` at `--error-size` (cached in $VOLREN_REFERENCE_CACHE).
"""

from __future__ import annotations

import argparse
import os
import statistics
from collections.abc import Iterator
from dataclasses import replace
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks._cli import run
from benchmarks.scene_table import ms_text, named_scene_table, parser, timed_frame
from volren.bench.datasets import shared_folder

FRAMES = 5
#: The share of a scene's labels hidden for the third frame.
HIDDEN_SHARE = 0.9


def _scenes(shared: Path | None) -> Iterator[tuple[str, Any, Any]]:
    """(name, labelled volume, base TF) per scene: the shared segmentations where `shared` has them,
    and the procedural one always."""
    from volren.io import load_transfer_function, load_volume
    from volren.io.label_info import load_label_info
    from volren.io.label_io import load_labels
    from volren.model import TransferFunction1D, UniformVolume
    from volren.model.labels import LabelMap

    if shared is not None and (shared / "data" / "labels").is_dir():
        folder = shared / "data" / "labels"
        pd25 = load_volume(folder / "pd25_t1t2s.vti")
        seg = load_labels(folder / "pd25_subcortical.vti", pd25)
        info = load_label_info(folder / "pd25_subcortical.labels.json")
        pd25 = replace(pd25, labels=replace(seg, names=info.names, colors=info.colors))
        for style in ("smooth", "opaque"):
            yield f"pd25/{style}", pd25, load_transfer_function(shared / "scenes" / f"pd25-{style}.json")
        frog = load_volume(folder / "frogtissue.mhd")
        info = load_label_info(folder / "frogtissue.labels.json")
        labels = LabelMap(frog.values, info.names, info.colors, "frogtissue")
        frog = replace(frog, labels=labels)
        # the label numbers as the scalar: every tissue drawn at one opacity, the background clear
        yield (
            "frog/tissues",
            frog,
            TransferFunction1D([[0.0, 1, 1, 1]], [[0.0, 0.0], [0.5, 0.05], [29.0, 0.05]]),
        )
    n = 96
    z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(np.float32)
    r = np.sqrt((x - n / 2) ** 2 + (y - n / 2) ** 2 + (z - n / 2) ** 2)
    labels = np.where(r < n / 5, 2, np.where(r < n / 2.5, 1, 0)).astype(np.uint8)
    field = np.exp(-((r / (n / 3)) ** 2))
    volume = UniformVolume(field, name="spheres", labels=LabelMap(labels, {1: "shell", 2: "core"}))
    yield "spheres/ramp", volume, TransferFunction1D.ramp(0.0, 1.0, 0.3, (1.0, 0.9, 0.8))


def _row(name: str, volume: Any, base: Any, size: int, frames: int, error_size: int) -> str:
    from volren.api import prepared_renderer
    from volren.model import Camera, RenderSettings
    from volren.model.labels import LabelTransferFunction
    from volren.model.scene_class import SceneClass
    from volren.quality import resolve
    from volren.testing.metrics import image_error
    from volren.testing.reference_images import reference_image

    labelled = LabelTransferFunction.for_labels(base, volume.labels)
    present = volume.labels.present
    hidden = LabelTransferFunction.for_labels(base, volume.labels)
    hidden.hide(present[: int(round(HIDDEN_SHARE * len(present)))])
    nothing = LabelTransferFunction.for_labels(base, volume.labels)
    nothing.hide(present)

    def view(turn: float) -> Any:
        return Camera.orbit(volume.bounds, 30.0 + turn, 20.0)

    renderer_name, settings, _ = resolve(SceneClass.of(volume, base), 1, "auto", "default", RenderSettings(),
                                         cameras=(view(0.0),), bounds=volume.bounds, labels=True)  # fmt: skip
    tfs = {"plain": base, "labels": labelled, "hidden": hidden, "nothing": nothing}
    times: dict[str, list[float]] = {key: [] for key in tfs}
    edited: dict[str, list[float]] = {key: [] for key in tfs}
    samples: dict[str, float] = {}
    errors = {}
    with prepared_renderer(renderer_name, volume, base, settings) as renderer:
        camera = view(0.0)
        for key in ("plain", "labels"):  # at the settings a render with no options has (its step search too)
            renderer.set_transfer_function(tfs[key])
            image = renderer.render(camera, error_size, error_size)
            truth = reference_image(
                volume, tfs[key], camera, error_size, error_size, replace(settings, options={})
            )
            errors[key] = image_error(image, truth).rmse
        renderer.set_transfer_function(labelled)
        renderer.render(camera, size, size)
        step = renderer.last_frame.counters.get("step", settings.step)
        # the four TFs timed at one step, the one the label scene's search chose: the cost of labels
        renderer.set_settings(settings.with_(step=step, options={**settings.options, "target_error": 0.0}))
        for tf in tfs.values():  # warm: tables, bricks
            renderer.set_transfer_function(tf)
            timed_frame(renderer, camera, size)
        for k in range(
            frames
        ):  # in turns: the frame after the TF changed (tables, bricks rebuilt), then the next
            for key, tf in tfs.items():
                renderer.set_transfer_function(tf)
                ms, _ = timed_frame(renderer, view(2.0 * k + 0.5), size)
                edited[key].append(ms)
                ms, _ = timed_frame(renderer, view(2.0 * (k + 1)), size)
                times[key].append(ms)
                samples[key] = renderer.last_frame.counters.get("samples", float("nan"))
    ms = {key: statistics.median(values) for key, values in times.items()}
    after = {key: statistics.median(values) for key, values in edited.items()}
    return (f"| {name} | {len(present)} | {renderer_name} {step:.3g} | {ms_text(ms['plain'])} | "
            f"{ms_text(ms['labels'])} | {ms['labels'] / ms['plain']:.2f} | {ms_text(ms['hidden'])} | "
            f"{ms['labels'] / ms['hidden']:.1f} | {ms_text(ms['nothing'])} | {ms['labels'] / ms['nothing']:.1f} | "
            f"{samples['plain'] / 1e6:.2f} / {samples['labels'] / 1e6:.2f} / "
            f"{samples['hidden'] / 1e6:.3f} | {ms_text(after['labels'])} / {ms_text(after['hidden'])} | "
            f"{errors['plain']:.4f} | {errors['labels']:.4f} |")  # fmt: skip


def measure(args: argparse.Namespace) -> int:
    shared = shared_folder(args.shared, required=False)
    intro = (f"Measured by `python -m benchmarks.labels --shared ../shared --size {args.size} --frames {args.frames}"
             f"`: {args.size}x{args.size}, the renderer and settings a render with no options picks for the label "
             f"scene, at the step its error target chose for the labels (*step*, in voxels), warm, median of "
             f"{args.frames} turning frames each, the four TFs in turns (each frame timed is the second after its TF "
             f"was set: *after an edit* is the first, which rebuilds the tables and bricks); {os.cpu_count()} "
             f"cores. *plain*: the base TF without labels; *labels*: every label in its colour over the base TF's "
             f"opacity; *90 % hidden*: the background and the first labels hidden; *all hidden*: every label hidden, no sample "
             f"taken, what the frame costs besides sampling (its rays, their walk through the empty bricks, the image): "
             f"*labels / all hidden* bounds what hiding labels can gain. RMSE against `reference` at {args.error_size}x"
             f"{args.error_size}, each at the settings a render with no options has.")  # fmt: skip
    header = ("| scene | labels | renderer, step | plain ms | labels ms | labels / plain | 90 % hidden ms | "
             "labels / hidden | all hidden ms | labels / all hidden | M samples (plain / labels / hidden) | "
             "after an edit ms (labels / hidden) | RMSE plain | RMSE labels |",
             "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")  # fmt: skip
    rows = ((name, partial(_row, name, volume, base, args.size, args.frames, args.error_size))
            for name, volume, base in _scenes(shared))  # fmt: skip
    return named_scene_table(args, intro, header, rows)


def main(argv: list[str] | None = None) -> int:
    cli = parser(
        "python -m benchmarks.labels", (__doc__ or "").split("\n")[0], FRAMES, "docs/bench/labels.md"
    )
    cli.add_argument(
        "--error-size", type=int, default=128, help="image side of the error columns (default 128)"
    )
    return run(measure, cli, argv)


if __name__ == "__main__":
    raise SystemExit(main())
