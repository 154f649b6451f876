"""`python -m benchmarks.defaults_fidelity`: what a render with no options gets right, against VTK's default, at every image size.

Why: a default fitted to a few large smooth scenes can drop what they do not hold (a vessel
thinner than the spacing between rays, a speck between samples) and still average well in RMSE.
Here `auto` at quality `default` (what `volren render` draws with no options) and VTK's default
(vtkSmartVolumeMapper on grids, the unstructured ray caster on meshes) are scored against
`reference` on the hard scenes (`volren.testing.hard_cases`) and any shared scene or sample, at
128^2 to 1024^2: RMSE, and the count of pixels off by more than 0.1 in any channel
(`volren.testing.metrics.OFF_THRESHOLD`). A row holds when both are at most VTK's.

    python -m benchmarks.defaults_fidelity [--shared DIR] [--datasets hard,bonsai] [--sizes 128,256,512,1024]
                                           [--out docs/bench/defaults_fidelity.md]

References are cached on disk (`volren.testing.reference_images`); the first run of a scene
renders them (minutes at 1024^2).
"""

from __future__ import annotations

import argparse
import datetime
import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from benchmarks._cli import int_list, run
from benchmarks.quality_levels import VTK_DEFAULT, _configs
from volren.api import prepared_renderer
from volren.bench.datasets import select, shared_folder
from volren.model import RenderSettings
from volren.model.scene_class import SceneClass
from volren.quality import resolve
from volren.renderers.base import render_frame
from volren.testing.metrics import OFF_THRESHOLD, ImageError, image_error
from volren.testing.reference_images import reference_image


@dataclass(frozen=True)
class Row:
    """One scene at one size: `auto`'s choice and both errors."""

    scene: str
    size: int
    choice: str
    ours: ImageError
    vtk: ImageError

    @property
    def holds(self) -> bool:
        return self.ours.rmse <= self.vtk.rmse and self.ours.off <= self.vtk.off

    def markdown(self) -> str:
        ratio = self.ours.rmse / self.vtk.rmse if self.vtk.rmse > 0 else float("inf")
        return (f"| {self.scene} | {self.size} | {self.choice} | {self.ours.rmse:.3g} | {self.vtk.rmse:.3g} "
                f"| {ratio:.2f} | {self.ours.off} | {self.vtk.off} | {'yes' if self.holds else '**no**'} |")  # fmt: skip


HEADER = ("| scene | size | auto's choice (no options) | our RMSE | VTK's RMSE | ours / VTK's "
          f"| our px off > {OFF_THRESHOLD:g} | VTK's px off | holds |",
          "|---|---:|---|---:|---:|---:|---:|---:|---|")  # fmt: skip


def describe(name: str, settings: RenderSettings) -> str:
    """`auto`'s choice in a few words: renderer, step, pre-integration, options."""
    text = f"{name}: step {settings.step:g}{', pre-integrated' if settings.preintegration else ''}"
    if settings.options:
        text += ", " + ", ".join(f"{k} {v}" for k, v in sorted(settings.options.items()))
    return text


def scene_rows(dataset, sizes: Iterable[int], styles: set[str] | None = None) -> Iterable[Row]:
    """Each TF of the dataset (of `styles`, when given) at each size: `auto` at `default` and VTK's
    default against `reference`."""
    volume = dataset.load()
    camera = dataset.camera(volume.bounds)
    curve, label = VTK_DEFAULT[dataset.kind]
    peer = _configs(dataset.kind, {curve})[(curve, label)]
    for style, tf in dataset.transfer_functions():
        if styles is not None and style not in styles:
            continue
        name, settings, _ = resolve(SceneClass.of(volume, tf), tf.dims, "auto", "default", RenderSettings(),
                                    cameras=(camera,), bounds=volume.bounds)  # fmt: skip
        for size in sizes:
            truth = reference_image(volume, tf, camera, size, size)
            errors = []
            for renderer, renderer_settings in ((name, settings), (peer.renderer, peer.settings())):
                with prepared_renderer(renderer, volume, tf, renderer_settings) as r:
                    errors.append(image_error(render_frame(r, camera, size, size)[0], truth))
            yield Row(f"{dataset.name}/{style}", size, describe(name, settings), *errors)


def measure(args: argparse.Namespace) -> int:
    shared = shared_folder(args.shared, required=False)
    datasets = select(args.datasets.split(","), shared)
    command = (f"python -m benchmarks.defaults_fidelity{' --shared ' + args.shared if args.shared else ''} "
               f"--datasets {args.datasets}{' --tfs ' + args.tfs if args.tfs else ''} "
               f"--sizes {','.join(map(str, args.sizes))}")  # fmt: skip
    lines = [f"Measured {datetime.date.today()} by `{command}`: per scene and image size, `auto` at quality "
             "`default` (a render with no options) and VTK's default against `reference` at the scene's view.",
             "", f"load average at the start: {' '.join(f'{v:.2f}' for v in os.getloadavg())}", "", *HEADER]  # fmt: skip
    for line in lines:
        print(line, flush=True)
    rows = []
    for dataset in datasets:
        for row in scene_rows(dataset, args.sizes, set(args.tfs.split(",")) if args.tfs else None):
            rows.append(row)
            lines.append(row.markdown())
            print(lines[-1], flush=True)
    held = sum(r.holds for r in rows)
    lines += ["", f"{held} of {len(rows)} rows hold (RMSE and pixels off both at most VTK's default's)."]
    print(lines[-1])
    if args.out:
        Path(args.out).write_text("\n".join(lines) + "\n", encoding="utf-8")
    return 0 if held == len(rows) or not args.strict else 1


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.defaults_fidelity", description=__doc__.split("\n")[0]
    )
    parser.add_argument("--shared", help="the folder with data/ and scenes/ (default: $VOLREN_SHARED)")
    parser.add_argument("--datasets", default="hard",
                        help="comma-separated datasets; `hard` is every hard scene (default hard)")  # fmt: skip
    parser.add_argument("--tfs", help="comma-separated TF styles to keep, e.g. spiky (default: all)")
    parser.add_argument("--sizes", type=int_list(16), default=[128, 256, 512, 1024],
                        help="image sides in pixels (default 128,256,512,1024)")  # fmt: skip
    parser.add_argument("--out", help="also write the table to this Markdown file (BENCHMARKS.md's fragment: "
                                      "docs/bench/defaults_fidelity.md)")  # fmt: skip
    parser.add_argument("--strict", action="store_true", help="exit 1 when a row does not hold")
    return run(measure, parser, argv)


if __name__ == "__main__":
    raise SystemExit(main())
