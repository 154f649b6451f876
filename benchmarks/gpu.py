"""`python -m benchmarks.gpu`: our OpenGL renderers on a machine with a real GPU.

`bench run` measures everything on the machine at hand; on a GPU machine the question is narrower:
how fast are `slicer` and `tetra`'s GL walk there, at what error. The scenes, cameras, turning
frames and error metric are `bench run`'s; the error is measured at 512x512 against the cached
`reference` image, the time at every size asked for (the tetra goal is oxygen post at 1024x1024).

A GPU machine may lack VTK and PyVista (the wheels are large), so the scenes can travel as arrays:
`export` writes each shared dataset as .npz, its TFs and the reference images (the cache is keyed
by content, and the arrays are the loaded ones, so the keys match); `run --arrays DIR` reads them
with numpy alone. With PyVista there, `run --shared DIR` loads the files themselves.
"""

from __future__ import annotations

import argparse
import csv
import json
import shutil
import statistics
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from volren.api import prepared_renderer
from volren.bench.datasets import Dataset, shared_datasets
from volren.bench.run_bench import turn_offsets
from volren.model.settings import RenderSettings
from volren.model.volume import TetVolume, UniformVolume, Volume
from volren.testing.metrics import image_error
from volren.testing.reference_images import reference_image, reference_settings, scene_key

#: The error is measured at this size (the reference images the CPU run already has).
ERROR_SIZE = 512
SIZES = (512, 1024)
FRAMES = 11
TURN = 2.0
COLUMNS = (
    "dataset",
    "tf",
    "renderer",
    "settings",
    "size",
    "ms",
    "gpu_ms",
    "gpu_bin_ms",
    "gpu_walk_ms",
    "rmse",
    "max_abs",
    "cell_steps",
    "samples",
)


@dataclass(frozen=True)
class GLConfig:
    renderer: str
    label: str
    settings: RenderSettings


def configs(kind: str) -> list[GLConfig]:
    """The GL configurations measured on a volume of this kind."""
    if kind == "tet":
        return [
            GLConfig(
                "tetra",
                f"gl, table 256x32{', no termination' if alpha == 1.0 else ''}",
                RenderSettings(
                    options={
                        "backend": "gl",
                        "table_size": 256,
                        "table_lengths": 32,
                        "termination_alpha": alpha,
                    }
                ),
            )
            for alpha in (0.999, 1.0)
        ]
    out = []
    for step in (1.0, 0.5, 0.25):
        out.append(GLConfig("slicer", f"step {step:g}, post", RenderSettings(step=step)))
        out.append(
            GLConfig(
                "slicer",
                f"step {step:g}, pre 512",
                RenderSettings(step=step, preintegration=True, options={"table_size": 512}),
            )
        )
    return out


class ArrayDataset(Dataset):
    """A shared dataset exported by `export`: the loaded arrays in an .npz file."""

    def load(self) -> Volume:
        with np.load(self.path) as data:
            if self.kind == "tet":
                return TetVolume(data["points"], data["tets"], data["values"], name=self.name)
            return UniformVolume(
                data["values"],
                tuple(data["spacing"].tolist()),
                tuple(data["origin"].tolist()),
                name=self.name,
            )


def export(shared: Path, folder: Path, names: list[str] | None = None) -> None:
    """Each shared dataset as .npz, its TFs, and the reference images at ERROR_SIZE (rendered now
    where the cache lacks them) under folder/reference."""
    folder.mkdir(parents=True, exist_ok=True)
    index = []
    for name, dataset in shared_datasets(shared).items():
        if names and name not in names:
            continue
        print(f"exporting {name}", flush=True)
        volume = dataset.load()
        if isinstance(volume, TetVolume):
            np.savez_compressed(
                folder / f"{name}.npz", points=volume.points, tets=volume.tets, values=volume.values
            )
        else:
            assert isinstance(volume, UniformVolume)
            np.savez_compressed(
                folder / f"{name}.npz",
                values=volume.values,
                spacing=np.asarray(volume.spacing),
                origin=np.asarray(volume.origin),
            )
        styles, references = [], {}
        for style, tf in dataset.transfer_functions():
            shutil.copy(dict(dataset.tf_paths)[style], folder / f"{name}-{style}.json")
            camera = dataset.camera(volume.bounds)
            key = scene_key(volume, tf, camera, ERROR_SIZE, ERROR_SIZE, reference_settings(RenderSettings()))
            references[key] = reference_image(volume, tf, camera, ERROR_SIZE, ERROR_SIZE)
            styles.append(style)
        np.savez_compressed(folder / f"{name}-reference.npz", **references)
        index.append(
            {
                "name": name,
                "kind": dataset.kind,
                "azimuth": dataset.azimuth,
                "elevation": dataset.elevation,
                "zoom": dataset.zoom,
                "styles": styles,
            }
        )
    (folder / "datasets.json").write_text(json.dumps(index, indent=1))


def exported(folder: Path) -> list[Dataset]:
    """The datasets `export` wrote; their reference images go into folder/reference, the cache's layout."""
    index = json.loads((folder / "datasets.json").read_text())
    (folder / "reference").mkdir(exist_ok=True)
    for d in index:
        with np.load(folder / f"{d['name']}-reference.npz") as references:
            for key in references.files:
                np.save(folder / "reference" / f"{key}.npy", references[key])
    return [
        ArrayDataset(
            d["name"],
            d["kind"],
            folder / f"{d['name']}.npz",
            None,
            tuple((s, folder / f"{d['name']}-{s}.json") for s in d["styles"]),
            d["azimuth"],
            d["elevation"],
            d["zoom"],
        )
        for d in index
    ]


def measure(
    datasets: list[Dataset], sizes: tuple[int, ...], frames: int, reference_folder: Path | None
) -> Iterator[dict]:
    """One row per dataset, TF, configuration and size."""
    for dataset in datasets:
        volume = dataset.load()
        for style, tf in dataset.transfer_functions():
            reference = reference_image(
                volume, tf, dataset.camera(volume.bounds), ERROR_SIZE, ERROR_SIZE, folder=reference_folder
            )
            for config in configs(dataset.kind):
                with prepared_renderer(config.renderer, volume, tf, config.settings) as renderer:
                    for size in sizes:
                        renderer.render(dataset.camera(volume.bounds), size, size)  # warm-up
                        times, image, counters = [], None, {}
                        gpu: dict[str, list[float]] = {k: [] for k in ("gpu_ms", "gpu_bin_ms", "gpu_walk_ms")}
                        for offset in turn_offsets(frames, TURN):
                            start = time.perf_counter()
                            frame = renderer.render(dataset.camera(volume.bounds, offset), size, size)
                            times.append((time.perf_counter() - start) * 1000.0)
                            for k, values in gpu.items():
                                values.append(renderer.last_frame.counters.get(k, float("nan")))
                            if offset == 0.0:
                                image, counters = frame, dict(renderer.last_frame.counters)
                        err = image_error(image, reference) if size == ERROR_SIZE else None
                        yield {
                            "dataset": dataset.name, "tf": style, "renderer": config.renderer,
                            "settings": config.label, "size": size, "ms": statistics.median(times),
                            **{k: statistics.median(v) for k, v in gpu.items()}, "rmse": err.rmse if err else None,
                            "max_abs": err.max_abs if err else None, "cell_steps": counters.get("cell_steps"),
                            "samples": counters.get("samples"),
                        }  # fmt: skip


def markdown(rows: list[dict], device: str, frames: int = FRAMES) -> str:
    """The GPU section of BENCHMARKS.md: one line per scene and configuration, the sizes side by side."""
    sizes = sorted({r["size"] for r in rows})
    lines = [
        f"Device: {device}. Medians of {frames} frames while the camera turns, after a warm-up. `ms`: the whole",
        "`render()` call, with the read-back of float32 RGBA into numpy (16 MB at 1024x1024); `GPU`: the GL",
        "timer queries around the passes (tetra: entry lists + walk). RMSE against `reference` at "
        f"{ERROR_SIZE}x{ERROR_SIZE}; work: cell steps (tetra) or samples (slicer) at {ERROR_SIZE}x{ERROR_SIZE}.",
        "",
        "| dataset | TF | renderer | settings | "
        + " | ".join(f"ms {n} | GPU ms {n}" for n in sizes)
        + " | RMSE | work |",
        "|---|---|---|---|" + "---|---|" * len(sizes) + "---|---|",
    ]
    groups: dict[tuple, dict[int, dict]] = {}
    for r in rows:
        groups.setdefault((r["dataset"], r["tf"], r["renderer"], r["settings"]), {})[r["size"]] = r
    for (dataset, tf, renderer, settings), by_size in groups.items():
        cells = []
        for n in sizes:
            r = by_size.get(n)
            gpu = r["gpu_ms"] if r is not None else float("nan")
            cells.append(
                ("" if r is None else f"{r['ms']:.1f}") + " | " + ("" if gpu != gpu else f"{gpu:.1f}")
            )
        first = by_size.get(ERROR_SIZE) or next(iter(by_size.values()))
        work = first["cell_steps"] if first["cell_steps"] is not None else first["samples"]
        rmse = "" if first["rmse"] is None else f"{first['rmse']:.5f}"
        lines.append(
            f"| {dataset} | {tf} | {renderer} | {settings} | "
            + " | ".join(cells)
            + f" | {rmse} | {'' if work is None else format(work, '.3g')} |"
        )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.gpu", description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    e = sub.add_parser("export", help="write the shared datasets, TFs and reference images as arrays")
    e.add_argument("--shared", type=Path, required=True)
    e.add_argument("--to", type=Path, required=True)
    e.add_argument("--datasets", default="", help="comma-separated names (default: all)")
    r = sub.add_parser("run", help="measure slicer and the tetra GL walk")
    source = r.add_mutually_exclusive_group(required=True)
    source.add_argument("--arrays", type=Path, nargs="+", help="folders written by export")
    source.add_argument("--shared", type=Path, help="the shared folder (needs PyVista)")
    r.add_argument("--out", type=Path, required=True)
    r.add_argument("--sizes", default=",".join(map(str, SIZES)))
    r.add_argument("--frames", type=int, default=FRAMES)
    args = parser.parse_args(argv)
    if args.command == "export":
        export(args.shared, args.to, [n for n in args.datasets.split(",") if n] or None)
        return 0
    if args.arrays is not None:
        parts = [(exported(folder), folder / "reference") for folder in args.arrays]
    else:
        parts = [(list(shared_datasets(args.shared).values()), None)]
    from volren.renderers.tetra.gl_walk import GLWalk

    walk = GLWalk()
    device = walk.renderer_name
    walk.release()
    sizes = tuple(int(s) for s in args.sizes.split(","))
    args.out.mkdir(parents=True, exist_ok=True)
    rows = []
    with open(args.out / "gpu.csv", "w", newline="") as stream:
        writer = csv.DictWriter(stream, COLUMNS)
        writer.writeheader()
        for datasets, references in parts:
            for row in measure(datasets, sizes, args.frames, references):
                rows.append(row)
                writer.writerow(row)
                stream.flush()
                print(
                    " ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in row.items()),
                    flush=True,
                )
    (args.out / "gpu.md").write_text(markdown(rows, device, args.frames))
    return 0


if __name__ == "__main__":
    sys.exit(main())
