"""`python -m benchmarks.golden_images save|compare RENDERER FILE.npz`: one renderer's images of the
hard scenes, saved before a refactor and compared to the bit after it.

Why: a refactor of a kernel (parameter bundles, a shared helper replacing a copy) must not change
a single pixel, and the tests' tolerances would let a small change through. The scenes are the
hard cases (`volren.testing.hard_cases`: thin tubes and sheets, specks, noise, steps, anisotropy,
tetrahedral struts and sheets) at draft, default and high, shaded, MIP, without pre-integration
and in parallel projection, 72x60 pixels. A renderer's refusal (its one-line error) is part of
its behaviour and is compared too. Run `save` on the commit before the change and `compare` after
it; the exit status is 1 when any image differs.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterator
from typing import Any

import numpy as np

from benchmarks._cli import run
from volren.errors import VolrenError

SIZE = (72, 60)


def variants() -> Iterator[tuple[str, dict[str, Any]]]:
    """(name, keyword arguments of `volren.render`) of every variant drawn of each scene."""
    for quality in ("draft", "default", "high"):
        yield f"q={quality}", {"quality": quality}
    yield "shade", {"quality": "default", "shade": True}
    yield "shade-high", {"quality": "high", "shade": True}
    yield "mip", {"quality": "default", "blend_mode": "maximum"}
    yield "nopreint", {"quality": "default", "preintegration": False}
    yield "parallel", {"quality": "default", "parallel": True}


def images(renderer: str) -> dict[str, np.ndarray]:
    """Every scene and variant: the image, or the refusal's text as bytes."""
    import volren
    from volren.testing.hard_cases import CASES

    out: dict[str, np.ndarray] = {}
    for name, case in CASES.items():
        volume, tf = case.build(), case.tf()
        for variant, kwargs in variants():
            key = f"{name}/{variant}"
            try:
                image = volren.render(volume, tf, renderer=renderer, size=SIZE, azimuth=case.azimuth,
                                      elevation=case.elevation, zoom=case.zoom, **kwargs)  # fmt: skip
                out[key] = np.asarray(image)
            except VolrenError as exc:
                out[key] = np.frombuffer(str(exc).encode(), dtype=np.uint8)
    return out


def differences(saved: dict[str, np.ndarray], drawn: dict[str, np.ndarray]) -> list[str]:
    """One line per image that is missing, refused differently or not equal to the bit."""
    lines = []
    for key in sorted(set(saved) | set(drawn)):
        a, b = saved.get(key), drawn.get(key)
        if a is None or b is None or a.shape != b.shape or a.dtype != b.dtype:
            lines.append(f"{key}: missing, or its shape or refusal changed")
        elif not np.array_equal(a, b):
            diff = np.abs(a.astype(np.float64) - b.astype(np.float64))
            lines.append(f"{key}: max |diff| {diff.max():.3g}")
    return lines


def measure(args: argparse.Namespace) -> int:
    drawn = images(args.renderer)
    if args.mode == "save":
        np.savez_compressed(args.file, **drawn)
        print(f"saved {len(drawn)} images of {args.renderer} to {args.file}")
        return 0
    try:
        with np.load(args.file) as stored:
            saved = {key: stored[key] for key in stored.files}
    except (OSError, ValueError) as exc:
        raise VolrenError(f"{args.file}: cannot read saved images: {exc}") from None
    lines = differences(saved, drawn)
    print("\n".join([*lines, f"{args.renderer}: {len(drawn)} images, {len(lines)} differ"]))
    return 1 if lines else 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.golden_images", description=__doc__.split("\n")[0]
    )
    parser.add_argument("mode", choices=("save", "compare"))
    parser.add_argument("renderer", help="a registered renderer (volren renderers)")
    parser.add_argument("file", help="the .npz file to write (save) or read (compare)")
    return run(measure, parser, argv)


if __name__ == "__main__":
    sys.exit(main())
