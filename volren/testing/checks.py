"""The conformance checks: what `volren check-renderer` holds a renderer to.

Each check takes a `CheckContext` (a factory of fresh renderers, quick or full) and returns
`Measurement`s: a measured number beside its bound. Image bounds are the renderer's own declared
`Accuracy` for that volume kind at default settings, never widened here; contract rules that
admit no error (an empty TF draws nothing, cancelling lets the exception through) have bound 0.

Every image any check renders is also held to the output rules (float32 (H, W, 4), finite, in
[0, 1], rgb <= alpha), so a violation anywhere fails the check that saw it.
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.channels import ChannelTransferFunction
from volren.model.clip_region import ClipPlane, ClipRegion
from volren.model.labels import LabelTransferFunction
from volren.model.scene_class import SceneClass
from volren.model.settings import BlendMode, RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TFWidget, TransferFunction, TransferFunction2D
from volren.model.volume import UniformVolume, Volume
from volren.renderers.base import Accuracy, Capabilities, OptionSpec, Renderer, option_help_of, render_frame
from volren.testing import oracles
from volren.testing.channel_scenes import channel_scene, channel_slab, channel_slab_rgba
from volren.testing.label_scenes import label_scene, label_slab, label_slab_rgba
from volren.testing.metrics import image_error
from volren.testing.reference_images import reference_image
from volren.testing.scenes import axis_camera, column_camera, lattice_volume

#: The volume kinds the kit has scenes for.
KINDS = ("uniform", "tet")
#: How far a premultiplied channel may exceed alpha, or leave [0, 1]: float32 rounding.
OUTPUT_EPS = 1e-6

RendererFactory = Callable[[], Renderer]


class ContractError(Exception):
    """A renderer broke a rule of the contract; the message is one line."""


@dataclass(frozen=True)
class Measurement:
    """One measured number of one check beside its bound (`at_least`: the value must reach it)."""

    check: str
    case: str
    quantity: str
    value: float
    bound: float
    at_least: bool = False

    @property
    def passed(self) -> bool:
        if math.isnan(self.value):
            return False
        return self.value >= self.bound if self.at_least else self.value <= self.bound

    def line(self) -> str:
        relation = ">=" if self.at_least else "<="
        verdict = "PASS" if self.passed else "FAIL"
        return f"{verdict} {self.check} [{self.case}] {self.quantity} {self.value:.3g} (bound {relation} {self.bound:.3g})"


def _check_values(image: NDArray[np.float32]) -> str | None:
    """Why the values of an image (its shape and dtype checked by `render_frame`) break the output
    rules, or None."""
    if not np.all(np.isfinite(image)):
        return f"{np.count_nonzero(~np.isfinite(image))} non-finite values"
    if image.min() < -OUTPUT_EPS or image.max() > 1 + OUTPUT_EPS:
        return f"values outside [0, 1] (min {image.min():.3g}, max {image.max():.3g})"
    excess = float((image[..., :3] - image[..., 3:4]).max())
    if excess > OUTPUT_EPS:
        return f"colour exceeds alpha by {excess:.3g}: not premultiplied"
    return None


@dataclass
class CheckContext:
    """What a check works with: fresh renderers, and whether the run is quick (fewer cases; the image
    sizes stay, since an RMSE with silhouettes depends on the size)."""

    factory: RendererFactory
    quick: bool = False
    _renderers: list[Renderer] = field(default_factory=list)
    _inputs: dict[int, tuple[Any, Any, Any]] = field(default_factory=dict)

    def renderer(self) -> Renderer:
        """A new renderer, released when the check ends (`close`)."""
        renderer = self.factory()
        self._renderers.append(renderer)
        return renderer

    @property
    def capabilities(self) -> Capabilities:
        return type(self._probe()).capabilities

    def _probe(self) -> Renderer:
        return self._renderers[0] if self._renderers else self.renderer()

    def kinds(self) -> list[str]:
        return [k for k in KINDS if k in self.capabilities.kinds]

    def accuracy(self, kind: str) -> Accuracy:
        return self.capabilities.kinds[kind].accuracy  # type: ignore[index]

    def feed(
        self,
        renderer: Renderer,
        volume: Volume,
        tf: TransferFunction | LabelTransferFunction | ChannelTransferFunction,
        settings: RenderSettings,
    ) -> None:
        """Give the renderer what changed since its last frame (as the app does)."""
        last = self._inputs.get(id(renderer), (None, None, None))
        if last[2] != settings:
            renderer.set_settings(settings)
        if last[0] is not volume:
            renderer.set_volume(volume)
        if last[1] is not tf:
            renderer.set_transfer_function(tf)  # type: ignore[arg-type]  # a Protocol renderer may take labels
        self._inputs[id(renderer)] = (volume, tf, settings)

    def draw(
        self,
        renderer: Renderer,
        volume: Volume,
        tf: TransferFunction | LabelTransferFunction | ChannelTransferFunction,
        camera: Camera,
        width: int,
        height: int,
        settings: RenderSettings | None = None,
        progress: Callable[[float], None] | None = None,
    ) -> NDArray[np.float64]:
        """One frame, held to the output rules; float64 for the comparisons."""
        self.feed(renderer, volume, tf, settings or RenderSettings())
        image, _ = render_frame(renderer, camera, width, height, progress)
        problem = _check_values(image)
        if problem:
            raise ContractError(f"{volume.kind} {width}x{height}: {problem}")
        return image.astype(np.float64)

    def close(self) -> None:
        for renderer in self._renderers:
            try:
                renderer.release()
            except Exception:  # noqa: BLE001 - the release check reports release failures
                pass
        self._renderers.clear()


def _rmse(image: NDArray, expected: NDArray) -> float:
    return image_error(image, expected).rmse


def _box(kind: str, value: float = 1.0) -> Volume:
    return lattice_volume(kind, value, (5, 4, 4), (0.7, 1.1, 0.9), (-1.0, 0.5, 2.0))


# ---------------------------------------------------------------------------------- checks
def check_output(ctx: CheckContext) -> list[Measurement]:
    """Random volumes, a non-square image, every claimed blend mode: the output rules hold."""
    out = []
    rng = np.random.default_rng(7)
    for kind in ctx.kinds():
        volume = lattice_volume(
            kind, lambda x, y, z: rng.random(x.shape) * 8.0 - 2.0, (6, 5, 4), (0.8, 1.0, 1.3)
        )
        tf = TransferFunction1D([[-2, 0.1, 0.2, 1.0], [6, 1.0, 0.5, 0.0]], [[-1, 0.0], [6, 0.9]], 0.5)
        renderer = ctx.renderer()
        w, h = 37, 23
        modes = sorted(ctx.capabilities.kinds[kind].blend_modes)  # type: ignore[index]
        for mode in modes:
            ctx.draw(renderer, volume, tf, Camera.orbit(volume.bounds, 35, 25, aspect=w / h), w, h,
                     RenderSettings(blend_mode=mode))  # fmt: skip
        out.append(Measurement("output", f"{kind}, {len(modes)} blend modes", "rule violations", 0, 0))
    return out


def check_empty(ctx: CheckContext) -> list[Measurement]:
    """A TF with zero opacity everywhere draws exactly nothing."""
    out = []
    for kind in ctx.kinds():
        volume = lattice_volume(kind, lambda x, y, z: x + y, (5, 4, 4), (1.0, 0.8, 1.2))
        tf = TransferFunction1D([[0, 1, 1, 1]], [[0, 0.0], [10, 0.0]], 1.0)
        n = 32
        image = ctx.draw(ctx.renderer(), volume, tf, Camera.orbit(volume.bounds, 20, 30), n, n)
        out.append(Measurement("empty", kind, "max abs", float(np.abs(image).max()), 0.0))
    return out


def check_box(ctx: CheckContext) -> list[Measurement]:
    """A homogeneous box against 1 - (1 - a)^(L / d_u), perspective and parallel."""
    out = []
    tf = TransferFunction1D.constant(0.35, (0.9, 0.4, 0.2), opacity_unit_distance=0.8)
    for kind in ctx.kinds():
        volume = _box(kind)
        renderer = ctx.renderer()
        for parallel in (False, True):
            w, h = 48, 40
            camera = Camera.orbit(volume.bounds, 30, 20, zoom=1.3, parallel=parallel, aspect=w / h)
            image = ctx.draw(renderer, volume, tf, camera, w, h)
            expected = oracles.homogeneous_image(oracles.box_path_lengths(camera, w, h, volume.bounds),
                                                 (0.9, 0.4, 0.2), 0.35, 0.8)  # fmt: skip
            case = f"{kind}, {'parallel' if parallel else 'perspective'}"
            out.append(Measurement("box", case, "RMSE", _rmse(image, expected), ctx.accuracy(kind).rmse))
    return out


#: Clipping cases: (projection, near, far) as fractions of the box's depth range along the view
#: direction (0 at its nearest corner, 1 at its farthest); None leaves that plane well clear of it.
CLIP_CASES = (
    ("parallel, near", True, 0.35, None),
    ("parallel, far", True, None, 0.55),
    ("perspective, near", False, 0.4, None),
    ("perspective, near and far", False, 0.25, 0.7),
)
#: The cases a quick run keeps: one cut by each plane, in each projection.
CLIP_QUICK = ("parallel, far", "perspective, near and far")


def clipped_camera(camera: Camera, bounds: Sequence[float], near: float | None, far: float | None) -> Camera:
    """`camera` with its near / far planes at those fractions of the depth range of `bounds` (depth:
    distance from the eye along the view direction, vtkCamera's clipping range); None puts that
    plane a whole depth range in front of the box (near, never below half the eye's distance to the
    box) or behind it (far)."""
    corners = np.array(
        [[x, y, z] for x in bounds[0:2] for y in bounds[2:4] for z in bounds[4:6]], dtype=np.float64
    )
    depth = (corners - np.asarray(camera.position)) @ camera.direction
    d_lo, d_hi = float(depth.min()), float(depth.max())
    span = d_hi - d_lo
    lo = d_lo + near * span if near is not None else max(d_lo - span, 0.5 * d_lo)
    hi = d_lo + far * span if far is not None else d_hi + span
    return replace(camera, clipping_range=(lo, hi))


def check_clip(ctx: CheckContext) -> list[Measurement]:
    """A homogeneous box cut by the near plane, the far plane or both (planes perpendicular to the
    view direction, parallel and perspective): only the part between them is drawn, against
    1 - (1 - a)^(L / d_u) with L the clipped path length."""
    out = []
    tf = TransferFunction1D.constant(0.45, (0.3, 0.8, 0.6), opacity_unit_distance=0.6)
    cases = [c for c in CLIP_CASES if not ctx.quick or c[0] in CLIP_QUICK]
    for kind in ctx.kinds():
        volume = _box(kind)
        renderer = ctx.renderer()
        for name, parallel, near, far in cases:
            w, h = 48, 40
            camera = Camera.orbit(volume.bounds, -35, 25, zoom=1.3, parallel=parallel, aspect=w / h)
            camera = clipped_camera(camera, volume.bounds, near, far)
            if not ctx.capabilities.kinds[kind].clipping:  # type: ignore[index]
                out.append(
                    _refusal(
                        "clip",
                        f"{kind}, {name}, declared not drawn",
                        functools.partial(ctx.draw, renderer, volume, tf, camera, w, h),
                    )
                )
                continue
            image = ctx.draw(renderer, volume, tf, camera, w, h)
            expected = oracles.homogeneous_image(oracles.box_path_lengths(camera, w, h, volume.bounds),
                                                 (0.3, 0.8, 0.6), 0.45, 0.6)  # fmt: skip
            out.append(
                Measurement(
                    "clip", f"{kind}, {name}", "RMSE", _rmse(image, expected), ctx.accuracy(kind).rmse
                )
            )
    return out


#: Clip-region cases: (name, parallel, planes as (origin, normal) in fractions of the box, crop box
#: in fractions of the box or None). Each cuts the box's image where the camera sees the cut.
CLIP_REGION_CASES = (
    ("perspective, one oblique plane", False, (((0.5, 0.45, 0.5), (1.0, 0.6, -0.4)),), None),
    ("parallel, a wedge of two planes", True, (((0.4, 0.5, 0.5), (0.3, 1.0, 0.2)), ((0.6, 0.5, 0.5), (-1.0, 0.2, 0.5))), None),
    ("perspective, a plane and a crop box", False, (((0.5, 0.5, 0.5), (-0.2, 0.4, 1.0)),), (0.1, 0.8, 0.2, 0.9, 0.0, 0.7)),
    ("parallel, a crop box", True, (), (0.25, 0.9, 0.0, 0.6, 0.15, 1.0)),
)  # fmt: skip
#: The cases a quick run keeps.
CLIP_REGION_QUICK = ("perspective, one oblique plane", "perspective, a plane and a crop box")


def _clip_region_of(
    bounds: Sequence[float], planes: Sequence[Any], box: Sequence[float] | None
) -> ClipRegion:
    """A clip region given in fractions of `bounds` (xmin, xmax, ...), in world units."""
    lo = np.asarray(bounds[0::2], dtype=np.float64)
    span = np.asarray(bounds[1::2], dtype=np.float64) - lo
    world = [ClipPlane(tuple(lo + span * np.asarray(o)), tuple(np.asarray(n) / span)) for o, n in planes]
    crop = None if box is None else tuple(lo[a // 2] + span[a // 2] * box[a] for a in range(6))
    return ClipRegion(tuple(world), crop)  # type: ignore[arg-type]


def check_clip_region(ctx: CheckContext) -> list[Measurement]:
    """A homogeneous box cut by oblique planes and a crop box (`RenderSettings.clip`): the kept
    part is drawn with a flat cut, against 1 - (1 - a)^(L / d_u) with L the length of each ray in
    the kept region; a renderer whose kind does not declare `clip_region` refuses such a frame."""
    out = []
    tf = TransferFunction1D.constant(0.45, (0.8, 0.5, 0.3), opacity_unit_distance=0.5)
    cases = [c for c in CLIP_REGION_CASES if not ctx.quick or c[0] in CLIP_REGION_QUICK]
    for kind in ctx.kinds():
        volume = _box(kind)
        renderer = ctx.renderer()
        for name, parallel, planes, box in cases:
            w, h = 48, 40
            camera = Camera.orbit(volume.bounds, 30, 20, zoom=1.3, parallel=parallel, aspect=w / h)
            region = _clip_region_of(volume.bounds, planes, box)
            settings = RenderSettings(clip=region)
            if not ctx.capabilities.kinds[kind].clip_region:  # type: ignore[index]
                out.append(_refusal("clip_region", f"{kind}, {name}, declared not drawn",
                                    functools.partial(ctx.draw, renderer, volume, tf, camera, w, h, settings)))  # fmt: skip
                continue
            image = ctx.draw(renderer, volume, tf, camera, w, h, settings)
            lengths = oracles.box_path_lengths(camera, w, h, volume.bounds, region.half_spaces())
            expected = oracles.homogeneous_image(lengths, (0.8, 0.5, 0.3), 0.45, 0.5)
            whole = oracles.homogeneous_image(oracles.box_path_lengths(camera, w, h, volume.bounds),
                                              (0.8, 0.5, 0.3), 0.45, 0.5)  # fmt: skip
            assert _rmse(expected, whole) > 0.03, name  # the cut shows
            out.append(Measurement("clip_region", f"{kind}, {name}", "RMSE", _rmse(image, expected),
                                   ctx.accuracy(kind).rmse))  # fmt: skip
    return out


#: Cut-face cases: (name, parallel, planes, crop box) as `CLIP_REGION_CASES`, each keeping a side
#: that faces away from the camera (so rays enter through the cut) and a box inside the volume.
CLIP_CAP_CASES = (
    ("perspective, one oblique plane", False, (((0.5, 0.45, 0.5), (-1.0, -0.6, 0.4)),), None),
    ("parallel, a plane and a crop box", True, (((0.55, 0.5, 0.5), (-0.6, -0.3, 0.5)),), (0.05, 0.9, 0.1, 0.95, 0.08, 0.8)),
    ("perspective, a crop box", False, (), (0.3, 0.85, 0.05, 0.7, 0.1, 0.75)),
)  # fmt: skip


def _inner_pixels(mask: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """Pixels off the image's border whose four neighbours have the same `mask` value as they do:
    away from an edge of the cut (`oracles.at_an_edge`)."""
    inner = np.zeros_like(mask)
    inner[1:-1, 1:-1] = True
    return inner & ~oracles.at_an_edge(mask)


def check_clip_cap(ctx: CheckContext) -> list[Measurement]:
    """Cut faces (`ClipRegion.cap`): a box of s = x + y / 2 with a constant opacity, cut by oblique
    planes and a crop box inside it. Where a ray enters the kept part through a plane or a box
    face it shows the TF's colour at the entry point, opaque; elsewhere (a ray that enters through
    the volume's boundary) no face is drawn. Against the closed form on pixels away from the
    cut's edges; a renderer whose kind does not declare `clip_cap` refuses the frame."""
    out = []
    tf = TransferFunction1D([[0.0, 0.1, 0.9, 0.3], [8.0, 0.9, 0.2, 0.7]], [[0.0, 0.3], [8.0, 0.3]], 0.6)
    cases = CLIP_CAP_CASES[:1] if ctx.quick else CLIP_CAP_CASES
    for kind in ctx.kinds():
        volume = lattice_volume(
            kind, lambda x, y, z: x + 0.5 * y, (5, 4, 4), (0.7, 1.1, 0.9), (1.0, 0.5, 2.0)
        )
        renderer = ctx.renderer()
        for name, parallel, planes, box in cases:
            w, h = 48, 40
            camera = Camera.orbit(volume.bounds, 30, 20, zoom=1.3, parallel=parallel, aspect=w / h)
            region = replace(_clip_region_of(volume.bounds, planes, box), cap=True)
            settings = RenderSettings(clip=region)
            if not ctx.capabilities.kinds[kind].clip_cap:  # type: ignore[index]
                out.append(_refusal("clip_cap", f"{kind}, {name}, declared not drawn",
                                    functools.partial(ctx.draw, renderer, volume, tf, camera, w, h, settings)))  # fmt: skip
                continue
            image = ctx.draw(renderer, volume, tf, camera, w, h, settings)
            through, entry = oracles.entered_through_a_plane(
                camera, w, h, volume.bounds, region.half_spaces()
            )
            rgb, _ = tf.sample(entry[..., 0] + 0.5 * entry[..., 1])
            inner = _inner_pixels(through)
            faces = inner & through
            assert faces.sum() > 100, name  # the faces show
            expected = np.concatenate([rgb, np.ones(rgb.shape[:-1] + (1,))], axis=-1)
            error = float(np.sqrt(np.mean((image[faces] - expected[faces]) ** 2)))
            out.append(
                Measurement("clip_cap", f"{kind}, {name}, faces", "RMSE", error, ctx.accuracy(kind).rmse)
            )
            lengths = oracles.box_path_lengths(camera, w, h, volume.bounds, region.half_spaces())
            volume_only = inner & ~through & (lengths > 0)  # rays that enter through the volume's boundary
            if volume_only.sum() > 100:
                opaque = float(np.mean(image[volume_only][:, 3] > 0.999))  # their short paths are translucent
                out.append(
                    Measurement("clip_cap", f"{kind}, {name}, no face", "share drawn opaque", opaque, 0.0)
                )
    return out


RAMP_COLOUR = [(0.3, 0.1), (1.4, 0.9), (2.0, 0.3)]


def check_ramp(ctx: CheckContext) -> list[Measurement]:
    """s = x viewed along x: constant opacity, colour linear with a kink, against the closed-form
    emission integral (both directions)."""
    out = []
    tf = TransferFunction1D(
        [[x, c, 1 - c, 0.5] for x, c in RAMP_COLOUR], [[0, 0.3]], opacity_unit_distance=0.6
    )
    tau = -math.log(1 - 0.3) / 0.6
    for kind in ctx.kinds():
        volume = lattice_volume(kind, lambda x, y, z: x, (6, 4, 3), (0.5, 1.2, 0.9))
        b = volume.bounds
        renderer = ctx.renderer()
        n = 16
        for sign in (-1.0, 1.0):
            camera = axis_camera(b, 0, sign, 0.35 * min(b[3] - b[2], b[5] - b[4]))
            image = ctx.draw(renderer, volume, tf, camera, n, n)
            entry, exit_ = (b[0], b[1]) if sign < 0 else (b[1], b[0])
            red, alpha = oracles.linear_colour_emission(RAMP_COLOUR, tau, entry, exit_)
            green, _ = oracles.linear_colour_emission([(x, 1 - c) for x, c in RAMP_COLOUR], tau, entry, exit_)
            expected = np.broadcast_to([red, green, 0.5 * alpha, alpha], image.shape)
            case = f"{kind}, from {'-' if sign < 0 else '+'}x"
            out.append(Measurement("ramp", case, "RMSE", _rmse(image, expected), ctx.accuracy(kind).rmse))
    return out


def check_projection(ctx: CheckContext) -> list[Measurement]:
    """Maximum, minimum and average along z in a parallel view against the lattice's columns."""
    out = []
    rng = np.random.default_rng(11)
    dims, spacing = (9, 7, 5), (0.5, 0.5, 1.3)
    values = rng.random(dims[::-1])
    tf = TransferFunction1D([[0, 0.1, 0.9, 0.3], [1, 0.8, 0.2, 0.6]], [[0.1, 0.0], [0.9, 1.0]])
    for kind in ctx.kinds():
        modes = [m for m in (BlendMode.MAXIMUM, BlendMode.MINIMUM, BlendMode.AVERAGE)
                 if m in ctx.capabilities.kinds[kind].blend_modes]  # type: ignore[index]  # fmt: skip
        if not modes:
            continue
        volume = lattice_volume(kind, lambda x, y, z: values.reshape(-1), dims, spacing)
        camera = column_camera(dims, spacing, (0.0, 0.0, 0.0), volume.bounds[5])
        renderer = ctx.renderer()
        for mode in modes:
            image = ctx.draw(renderer, volume, tf, camera, dims[0], dims[1], RenderSettings(blend_mode=mode))
            expected = oracles.projection_rgba(tf, oracles.column_projection(values, str(mode))[::-1])
            # the outermost columns lie on the volume's boundary, where a ray may or may not hit
            err = _rmse(image[1:-1, 1:-1], expected[1:-1, 1:-1])
            out.append(Measurement("projection", f"{kind}, {mode}", "RMSE", err, ctx.accuracy(kind).rmse))
    return out


def check_nan(ctx: CheckContext) -> list[Measurement]:
    """NaN points make every cell they touch transparent: a box whose far half is NaN draws as the
    box of its finite cells."""
    out = []
    tf = TransferFunction1D.constant(0.4, (0.3, 0.6, 0.9), opacity_unit_distance=0.7)
    dims, spacing, origin = (8, 4, 4), (0.5, 0.9, 0.8), (0.0, 0.0, 0.0)
    finite_until = 3  # points with i <= 3 are finite: cells 0..2 along x are whole
    for kind in ctx.kinds():
        volume = lattice_volume(kind, lambda x, y, z: np.where(x <= finite_until * spacing[0] + 1e-9, 1.0, np.nan),
                                dims, spacing, origin)  # fmt: skip
        b = list(volume.bounds)
        b[1] = finite_until * spacing[0]
        w, h = 40, 32
        camera = Camera.orbit(volume.bounds, 40, 25, zoom=1.2, aspect=w / h)
        image = ctx.draw(ctx.renderer(), volume, tf, camera, w, h)
        expected = oracles.homogeneous_image(
            oracles.box_path_lengths(camera, w, h, b), (0.3, 0.6, 0.9), 0.4, 0.7
        )
        out.append(Measurement("nan", kind, "RMSE", _rmse(image, expected), ctx.accuracy(kind).rmse))
    return out


def check_point(ctx: CheckContext) -> list[Measurement]:
    """One bright point off centre lands where the camera contract projects it (the alpha-weighted
    centroid of its blob, which is point-symmetric): catches flipped rows, swapped axes, a wrong
    field of view or aspect, and half-pixel shifts."""
    out = []
    dims, spacing, origin = (12, 10, 8), (1.0, 1.2, 0.9), (-3.0, 1.0, 0.5)
    bright = (8, 3, 5)
    point = tuple(o + s * i for o, s, i in zip(origin, spacing, bright, strict=True))

    def spot(x, y, z):
        return np.where(np.isclose(x, point[0]) & np.isclose(y, point[1]) & np.isclose(z, point[2]), 1.0, 0.0)

    tf = TransferFunction1D([[0, 1, 1, 1]], [[0, 0.0], [1, 0.9]], opacity_unit_distance=0.5)
    for kind in ctx.kinds():
        volume = lattice_volume(kind, spot, dims, spacing, origin)
        renderer = ctx.renderer()
        cases = [("perspective", Camera.orbit(volume.bounds, 25, 15, zoom=1.6, aspect=1.4), 1.4),
                 ("parallel", axis_camera(volume.bounds, 2, 1.0, 4.5), 1.25)]  # fmt: skip
        for name, camera, aspect in cases:
            h = 60
            w = int(round(h * aspect))
            image = ctx.draw(renderer, volume, tf, camera, w, h)
            cx, cy = oracles.weighted_centroid(image[..., 3])
            px, py = oracles.pixel_of(camera, w, h, point)
            offset = math.hypot(cx - px, cy - py)
            out.append(Measurement("point", f"{kind}, {name} {w}x{h}", "offset px", offset,
                                   ctx.accuracy(kind).position_px))  # fmt: skip
    return out


def check_step(ctx: CheckContext) -> list[Measurement]:
    """A homogeneous slab filling the view at several steps: the opacity is corrected for the step,
    so every step gives the closed form."""
    out = []
    tf = TransferFunction1D.constant(0.3, (0.2, 0.8, 0.5), opacity_unit_distance=1.0)
    steps = (1.0, 0.25) if ctx.quick else (1.0, 0.5, 0.25)
    for kind in ctx.kinds():
        volume = lattice_volume(kind, 1.0, (5, 5, 6), (1.0, 1.0, 1.0))  # 5 units thick along z
        b = volume.bounds
        # off the centre line, so that no ray runs inside a face of the tetrahedralized lattice
        camera = axis_camera(b, 2, 1.0, 0.3 * (b[3] - b[2]), shift=(0.137, 0.071, 0.0))
        n = 16
        renderer = ctx.renderer()
        expected = oracles.homogeneous_image(
            oracles.box_path_lengths(camera, n, n, b), (0.2, 0.8, 0.5), 0.3, 1.0
        )
        for step in steps:
            image = ctx.draw(renderer, volume, tf, camera, n, n, RenderSettings(step=step))
            out.append(Measurement("step", f"{kind}, step {step:g}", "RMSE", _rmse(image, expected),
                                   ctx.accuracy(kind).rmse))  # fmt: skip
    return out


def check_shading(ctx: CheckContext) -> list[Measurement]:
    """Shading on changes the image of a field with a gradient by more than the renderer's own
    error; with shading off the lighting parameters change nothing."""
    out = []
    tf = TransferFunction1D.constant(0.3, (1.0, 0.6, 0.3), opacity_unit_distance=1.2)
    lit = RenderSettings(shade=True, ambient=0.0, diffuse=0.5, specular=0.0)  # about half as bright
    for kind in ctx.kinds():
        volume = lattice_volume(kind, lambda x, y, z: x, (5, 4, 3), (0.8, 1.1, 0.9))
        camera = Camera.orbit(volume.bounds, 70, -25, zoom=1.2)
        n = 24
        renderer = ctx.renderer()
        plain = ctx.draw(renderer, volume, tf, camera, n, n)
        other_lights = ctx.draw(renderer, volume, tf, camera, n, n,
                                RenderSettings(ambient=0.9, diffuse=0.1, specular=1.0, specular_power=50.0))  # fmt: skip
        out.append(Measurement("shading", f"{kind}, off", "max abs change with the lights", float(
            np.abs(other_lights - plain).max()), 0.0))  # fmt: skip
        if not ctx.capabilities.kinds[kind].shading:  # type: ignore[index]
            continue
        shaded = ctx.draw(renderer, volume, tf, camera, n, n, lit)
        out.append(Measurement("shading", f"{kind}, on", "RMSE change from unshaded", _rmse(shaded, plain),
                               ctx.accuracy(kind).rmse, at_least=True))  # fmt: skip
    return out


def _default_level(renderer: type[Renderer], kind: SceneClass) -> RenderSettings:
    """What a renderer draws at quality `default` on a scene of this kind: the measured level
    (`volren.quality`), or, for a renderer with no measurements (which `auto` never picks), the
    most accurate level of its declared quality axis, or its defaults."""
    from volren.quality import table

    measured = table().measurement(renderer.name, kind, "default")
    if measured is not None:
        return measured.level.apply(RenderSettings())
    axis = renderer.capabilities.quality  # fast to accurate
    return axis[-1].apply() if axis else RenderSettings()


#: The sheet check's tilts: the view direction's sideways component against the sheet's normal
#: (oblique, so that no renderer's samples fall in phase with the lattice on every ray).
THIN_TILTS = (0.3, 0.7)


def check_thin(ctx: CheckContext) -> list[Measurement]:
    """A sheet one lattice spacing thin (one layer of points at 1, the rest 0) under a TF visible
    only above 0.5, seen obliquely in parallel projection at the renderer's `default` quality
    level for the scene (`_default_level`): no pixel may be off by more than 0.1 (`volren.testing.metrics`) from the
    closed-form opacity, equal on every ray (`oracles.tent_sheet_alpha`). What a step too long or
    pixels interpolated between rays drop is a thin feature like this one."""
    out = []
    colour = (0.9, 0.8, 0.3)
    tf = TransferFunction1D([[0.0, *colour]], [[0.0, 0.0], [0.5, 0.0], [1.0, 0.9]], opacity_unit_distance=1.0)
    layer = 3.0
    for kind in ctx.kinds():
        volume = lattice_volume(kind, lambda x, y, z: np.where(np.isclose(z, layer), 1.0, 0.0), (11, 11, 7))
        renderer = ctx.renderer()
        settings = _default_level(type(renderer), SceneClass.of(volume, tf))
        b = np.asarray(volume.bounds)
        centre = np.array([(b[0] + b[1]) / 2.0, (b[2] + b[3]) / 2.0, layer])
        for tilt in THIN_TILTS:
            direction = np.array([tilt, 0.45 * tilt, -1.0])
            direction /= np.linalg.norm(direction)
            camera = Camera(position=tuple(centre - 30.0 * direction), focal_point=tuple(centre),
                            view_up=(0.0, 1.0, 0.0), parallel=True, parallel_scale=2.5, clipping_range=(1.0, 100.0))  # fmt: skip
            n = 24
            image = ctx.draw(renderer, volume, tf, camera, n, n, settings)
            alpha = oracles.tent_sheet_alpha(tf, 2.0, float(direction[2]))
            expected = np.broadcast_to(
                [colour[0] * alpha, colour[1] * alpha, colour[2] * alpha, alpha], image.shape
            )
            off = image_error(image, expected).off
            out.append(Measurement("thin", f"{kind}, tilt {tilt:g}", "pixels off by > 0.1", off, 0))
    return out


class _Cancel(Exception):
    """Raised by the kit's progress callback to cancel a frame."""


def check_eye_inside(ctx: CheckContext) -> list[Measurement]:
    """A perspective eye inside a homogeneous box (a fly-through): as the box check's closed form
    where the kind declares `eye_inside`, else refused with a one-line VolrenError."""
    out = []
    tf = TransferFunction1D.constant(0.35, (0.9, 0.4, 0.2), opacity_unit_distance=0.8)
    for kind in ctx.kinds():
        volume = _box(kind)
        lo, hi = np.asarray(volume.bounds[0::2]), np.asarray(volume.bounds[1::2])
        camera = Camera(position=tuple(lo + (hi - lo) * (0.3, 0.4, 0.35)), focal_point=tuple(hi - (hi - lo) * 0.1),
                        clipping_range=(0.01, 50.0))  # fmt: skip
        w, h = 48, 40
        if ctx.capabilities.kinds[kind].eye_inside:  # type: ignore[index]
            image = ctx.draw(ctx.renderer(), volume, tf, camera, w, h)
            expected = oracles.homogeneous_image(oracles.box_path_lengths(camera, w, h, volume.bounds),
                                                 (0.9, 0.4, 0.2), 0.35, 0.8)  # fmt: skip
            out.append(
                Measurement("eye_inside", kind, "RMSE", _rmse(image, expected), ctx.accuracy(kind).rmse)
            )
            continue
        renderer = ctx.renderer()
        out.append(
            _refusal(
                "eye_inside",
                f"{kind}, declared not drawn",
                functools.partial(ctx.draw, renderer, volume, tf, camera, w, h),
            )
        )
    return out


def _refusal(check: str, case: str, draw: Callable[[], Any]) -> Measurement:
    """A view the renderer declares it cannot draw: refused with a one-line VolrenError, not drawn."""
    try:
        draw()
    except VolrenError as exc:
        return Measurement(check, case, "refusals not in one line", int("\n" in str(exc)), 0)
    return Measurement(check, case, "frames drawn instead of refused", 1, 0)


def _kit_scene(kind: str) -> tuple[Volume, TransferFunction1D, Camera]:
    volume = lattice_volume(
        kind, lambda x, y, z: np.sin(x) + np.cos(1.3 * y) + 0.5 * z, (8, 7, 6), (0.9, 0.8, 1.0)
    )
    tf = TransferFunction1D([[-2, 0.2, 0.3, 1.0], [4, 1.0, 0.8, 0.1]], [[-1, 0.0], [4, 0.8]], 0.6)
    return volume, tf, Camera.orbit(volume.bounds, 15, 35)


def check_progress(ctx: CheckContext) -> list[Measurement]:
    """The progress callback is called with fractions that never decrease, all in [0, 1]."""
    out = []
    for kind in ctx.kinds():
        volume, tf, camera = _kit_scene(kind)
        calls: list[float] = []
        n = 48
        ctx.draw(ctx.renderer(), volume, tf, camera, n, n, progress=calls.append)
        bad = sum(1 for f in calls if not 0.0 <= f <= 1.0) + sum(
            1 for a, b in itertools.pairwise(calls) if b < a
        )
        out.append(Measurement("progress", f"{kind}, {len(calls)} calls", "out of order or range",
                               bad + (0 if calls else 1), 0))  # fmt: skip
    return out


def check_cancel(ctx: CheckContext) -> list[Measurement]:
    """An exception raised from the progress callback comes out of `render`, and the next frame
    equals one that was never interrupted."""
    out = []
    for kind in ctx.kinds():
        volume, tf, camera = _kit_scene(kind)
        n = 48
        renderer = ctx.renderer()
        before = ctx.draw(renderer, volume, tf, camera, n, n)
        raised = None

        def cancel(fraction: float) -> None:
            raise _Cancel()

        try:
            ctx.draw(renderer, volume, tf, camera.azimuth(10), n, n, progress=cancel)
        except _Cancel:
            raised = True
        except Exception as exc:  # noqa: BLE001 - any other outcome is the renderer's fault
            raise ContractError(
                f"{kind}: cancelling raised {type(exc).__name__}: {exc} instead of the callback's exception"
            ) from None
        out.append(Measurement("cancel", kind, "cancel exceptions swallowed", 0 if raised else 1, 0))
        after = ctx.draw(renderer, volume, tf, camera, n, n)
        out.append(
            Measurement(
                "cancel", f"{kind}, next frame", "max abs change", float(np.abs(after - before).max()), 0.0
            )
        )
    return out


def check_release(ctx: CheckContext) -> list[Measurement]:
    """release() may be called twice; any use after it is a one-line VolrenError."""
    kind = ctx.kinds()[0]
    volume, tf, camera = _kit_scene(kind)
    renderer = ctx.renderer()
    ctx.draw(renderer, volume, tf, camera, 8, 8)
    renderer.release()
    renderer.release()
    bad = 0
    for name, use in (("render", lambda: renderer.render(camera, 8, 8)),
                      ("set_volume", lambda: renderer.set_volume(volume)),
                      ("set_transfer_function", lambda: renderer.set_transfer_function(tf)),
                      ("set_settings", lambda: renderer.set_settings(RenderSettings()))):  # fmt: skip
        try:
            use()
        except VolrenError as exc:
            bad += "\n" in str(exc)
            continue
        except Exception as exc:  # noqa: BLE001
            raise ContractError(
                f"{name} after release raised {type(exc).__name__}, not VolrenError"
            ) from None
        raise ContractError(f"{name} after release did not raise")
    return [Measurement("release", kind, "uses after release not refused in one line", bad, 0)]


#: A value no option kind accepts (bool, int, float, str and choice all refuse a list).
NO_OPTION_VALUE = ["not", "an", "option", "value"]
#: An option name no renderer declares.
NO_SUCH_OPTION = "volren_kit_no_such_option"


def check_options(ctx: CheckContext) -> list[Measurement]:
    """Options are declared once, as a tuple of OptionSpec in `options`, with `option_help` derived
    from them; set_settings accepts every declared default and refuses, in one line naming the
    option, a value of no option kind for each and an option not declared."""
    renderer = ctx.renderer()
    cls = type(renderer)
    specs = getattr(cls, "options", None)
    if not isinstance(specs, tuple) or not all(isinstance(spec, OptionSpec) for spec in specs):
        raise ContractError(
            "options are not declared as a tuple of OptionSpec in the class attribute `options`"
        )
    if dict(cls.option_help) != option_help_of(specs):
        raise ContractError("option_help is not the one derived from `options` (option_help_of)")
    renderer.set_settings(RenderSettings(options={s.name: s.default for s in specs if s.default is not None}))
    accepted = []
    for name in [*(spec.name for spec in specs), NO_SUCH_OPTION]:
        try:
            renderer.set_settings(RenderSettings(options={name: NO_OPTION_VALUE}))
        except VolrenError as exc:
            if "\n" in str(exc) or name not in str(exc):
                raise ContractError(f"option {name}={NO_OPTION_VALUE!r}: the refusal is not one line naming the "
                                    f"option: {str(exc)[:200]!r}") from None  # fmt: skip
            continue
        accepted.append(name)
    return [Measurement("options", f"{len(specs)} declared through OptionSpec, an unknown one",
                        f"bad values accepted ({', '.join(accepted) or 'none'})", len(accepted), 0)]  # fmt: skip


def kit_tf_2d() -> TransferFunction2D:
    return TransferFunction2D(
        (-2.0, 4.0), (0.0, 3.0), [TFWidget.gaussian((1.0, 1.0), (1.0, 1.0), (1, 0.5, 0), 0.6)]
    )


def contract_combinations(kind_support: Any) -> Iterator[tuple[int, RenderSettings, bool]]:
    """Every (TF dims, settings) the contract knows, and whether `kind_support` claims it."""
    for dims, pre, shade, mode in itertools.product((1, 2), (False, True), (False, True), list(BlendMode)):
        settings = RenderSettings(preintegration=pre, shade=shade, blend_mode=mode)
        claimed = dims in kind_support.tf_dims and (not pre or kind_support.preintegration) \
            and (not pre or dims == 1 or kind_support.preintegration_2d) \
            and (not shade or kind_support.shading) and mode in kind_support.blend_modes \
            and (dims == 1 or mode in kind_support.blend_modes_2d)  # fmt: skip
        yield dims, settings, claimed


def check_capabilities(ctx: CheckContext) -> list[Measurement]:
    """Every combination claimed renders; every one not claimed, and every volume kind not claimed,
    is refused with a one-line VolrenError before any work (no progress call)."""
    out = []
    caps = ctx.capabilities
    for kind in KINDS:
        volume, tf1, camera = _kit_scene(kind)
        if kind not in caps.kinds:
            try:
                ctx.renderer().set_volume(volume)
            except VolrenError:
                out.append(Measurement("capabilities", f"{kind} not claimed", "accepted", 0, 0))
                continue
            raise ContractError(f"set_volume accepted a {kind} volume that the capabilities do not claim")
        tf2 = kit_tf_2d()
        renderer, refusing = ctx.renderer(), ctx.renderer()
        claimed = refused = 0
        for dims, settings, is_claimed in contract_combinations(caps.kinds[kind]):  # type: ignore[index]
            what = f"{kind} {dims}D TF, pre-integration {settings.preintegration}, shade {settings.shade}, {settings.blend_mode}"
            tf = tf1 if dims == 1 else tf2
            if ctx.quick and is_claimed and claimed >= 6:
                continue
            if is_claimed:
                claimed += 1
                try:
                    ctx.draw(renderer, volume, tf, camera, 12, 12, settings)
                except ContractError:
                    raise
                except Exception as exc:  # noqa: BLE001
                    raise ContractError(f"claimed {what} failed: {type(exc).__name__}: {exc}") from None
                continue
            refused += 1
            calls: list[float] = []
            try:
                ctx.draw(refusing, volume, tf, camera, 12, 12, settings, progress=calls.append)
            except VolrenError as exc:
                if calls:
                    raise ContractError(
                        f"{what} is not claimed but was refused only after work began"
                    ) from None
                if "\n" in str(exc):
                    raise ContractError(f"{what}: the refusal is not one line") from None
                continue
            except Exception as exc:  # noqa: BLE001
                raise ContractError(
                    f"{what} is not claimed and raised {type(exc).__name__}, not VolrenError"
                ) from None
            raise ContractError(f"{what} is not claimed but rendered")
        out.append(Measurement("capabilities", f"{kind}, {claimed} claimed rendered, {refused} refused",
                               "violations", 0, 0))  # fmt: skip
        if caps.tf_drag_options:  # the app adds them to its previews during TF drags: they must draw
            try:
                ctx.draw(
                    renderer, volume, tf1, camera, 12, 12, RenderSettings(options=dict(caps.tf_drag_options))
                )
            except Exception as exc:  # noqa: BLE001
                raise ContractError(f"tf_drag_options {dict(caps.tf_drag_options)} failed on {kind}: "
                                    f"{type(exc).__name__}: {exc}") from None  # fmt: skip
            out.append(Measurement("capabilities", f"{kind}, tf_drag_options rendered", "violations", 0, 0))
    return out


def check_labels(ctx: CheckContext) -> list[Measurement]:
    """Label volumes (a TF per label, `volren.model.labels`) where uniform grids declare `labels`:
    a constant slab of one label beside a hidden one, seen along x from both sides, against the
    closed form (the label's weight ramps over the boundary cell, adding half a cell), and a smooth
    field with a hidden label and one in its own colour against the `reference` renderer, at the
    default settings (pre-integrated too where `labels_preintegration` is declared). A renderer
    whose grids do not declare `labels` refuses such a frame in one line; one that declares
    `labels` without `labels_preintegration` refuses it pre-integrated."""
    support = ctx.capabilities.kinds.get("uniform")
    if support is None:
        return [Measurement("labels", "no uniform grids claimed (label maps lie on grids)", "skipped", 0, 0)]
    slab, slab_tf = label_slab()
    scene, scene_tf = label_scene()
    n = 32
    camera = Camera.orbit(scene.bounds, 30, 25, zoom=1.2)
    if not support.labels:
        draw = functools.partial(ctx.draw, ctx.renderer(), scene, scene_tf, camera, n, n)
        return [_refusal("labels", "uniform, declared not drawn", draw)]
    renderer = ctx.renderer()
    out = _slab_along_x(
        ctx, renderer, "labels", "slab", slab, slab_tf, label_slab_rgba(), support.accuracy.rmse
    )
    reference = reference_image(scene, scene_tf, camera, n, n).astype(np.float64)
    assert reference[..., 3].max() > 0.5
    modes = [False, True] if support.labels_preintegration and support.preintegration else [False]
    for pre in modes:
        image = ctx.draw(renderer, scene, scene_tf, camera, n, n, RenderSettings(preintegration=pre))
        out.append(Measurement("labels", f"three labels, pre-integration {pre}", "RMSE to reference",
                               _rmse(image, reference), support.accuracy.rmse))  # fmt: skip
    if support.preintegration and not support.labels_preintegration:
        draw = functools.partial(ctx.draw, ctx.renderer(), scene, scene_tf, camera, n, n,
                                 RenderSettings(preintegration=True))  # fmt: skip
        out.append(_refusal("labels", "pre-integrated, declared not drawn", draw))
    return out


def _slab_along_x(ctx: CheckContext, renderer: Renderer, check: str, what: str, slab: Volume, tf: Any,
                  rgba: NDArray[np.float64], bound: float) -> list[Measurement]:  # fmt: skip
    """A slab seen along x (from both sides unless quick), every pixel against the closed form `rgba`."""
    b = slab.bounds
    out = []
    for sign in (1.0,) if ctx.quick else (1.0, -1.0):
        view = axis_camera(b, 0, sign, 0.35 * min(b[3] - b[2], b[5] - b[4]))
        image = ctx.draw(renderer, slab, tf, view, 16, 16)
        error = _rmse(image, np.broadcast_to(rgba, image.shape))
        out.append(Measurement(check, f"{what}, from {'+' if sign > 0 else '-'}x", "RMSE", error, bound))
    return out


def check_channels(ctx: CheckContext) -> list[Measurement]:
    """Multi-channel volumes (a TF per channel, their extinctions and emissions added:
    `volren.model.channels`) where uniform grids declare `channels`: a constant two-channel slab
    seen along x from both sides against the closed form of the summed extinction, and three smooth
    overlapping channels (one at weight 2) against the `reference` renderer, within the grids'
    `accuracy.rmse`. A renderer whose grids do not declare `channels` refuses such a frame in one
    line, and one that pre-integrates refuses it pre-integrated (channels are post-classified)."""
    support = ctx.capabilities.kinds.get("uniform")
    if support is None:
        return [Measurement("channels", "no uniform grids claimed (channels lie on grids)", "skipped", 0, 0)]
    slab, slab_tf = channel_slab()
    scene, scene_tf = channel_scene()
    n = 32
    camera = Camera.orbit(scene.bounds, 30, 25, zoom=1.2)
    if not support.channels:
        draw = functools.partial(ctx.draw, ctx.renderer(), scene, scene_tf, camera, n, n)
        return [_refusal("channels", "uniform, declared not drawn", draw)]
    renderer = ctx.renderer()
    out = _slab_along_x(ctx, renderer, "channels", "two-channel slab", slab, slab_tf, channel_slab_rgba(),
                        support.accuracy.rmse)  # fmt: skip
    reference = reference_image(scene, scene_tf, camera, n, n).astype(np.float64)
    assert reference[..., 3].max() > 0.5
    image = ctx.draw(renderer, scene, scene_tf, camera, n, n, RenderSettings())
    out.append(Measurement("channels", "three channels", "RMSE to reference", _rmse(image, reference),
                           support.accuracy.rmse))  # fmt: skip
    if support.preintegration:
        draw = functools.partial(ctx.draw, ctx.renderer(), scene, scene_tf, camera, n, n,
                                 RenderSettings(preintegration=True))  # fmt: skip
        out.append(_refusal("channels", "pre-integrated, declared not drawn", draw))
    return out


#: The composite of a bricked render equals the whole render to float rounding (DESIGN.md).
BRICK_RMSE = 1e-5


def check_bricks(ctx: CheckContext) -> list[Measurement]:
    """A renderer that claims regions draws a volume cut into uneven bricks, composited front to
    back, equal to its whole-volume render (parallel, with sample planes on brick faces, and
    perspective; every claimed pre-integration and shading); one that does not claim them refuses
    `set_region` with a one-line VolrenError."""
    from volren.bricked.layout import BrickLayout
    from volren.bricked.sort_last import render_bricked
    from volren.bricked.source import VolumeSource

    support = ctx.capabilities.kinds.get("uniform")
    # mean spacing 1: at step 0.5 along z the sample planes fall on the brick faces (every 3 cells)
    volume = lattice_volume(
        "uniform", lambda x, y, z: np.sin(x) + np.cos(1.3 * y) + 0.5 * z, (8, 7, 6), (1.2, 0.8, 1.0)
    )
    assert isinstance(volume, UniformVolume)
    tf = TransferFunction1D([[-2, 0.2, 0.3, 1.0], [4, 1.0, 0.8, 0.1]], [[-1, 0.0], [4, 0.3]], 1.0)
    if support is None or not support.regions:
        layout = BrickLayout(volume.dimensions, volume.spacing, volume.origin, volume.value_range, 3)
        renderer = ctx.renderer()
        try:
            set_region = renderer.set_region  # type: ignore[attr-defined]
        except AttributeError:
            return [Measurement("bricks", "regions not claimed, no set_region", "accepted", 0, 0)]
        try:
            set_region(layout.region(layout.brick_at((0, 0, 0))))
        except VolrenError as exc:
            return [
                Measurement("bricks", "regions not claimed", "refusal not one line", int("\n" in str(exc)), 0)
            ]
        raise ContractError("set_region accepted a region that the capabilities do not claim")
    out = []
    b = volume.bounds
    cameras = [("parallel along z", axis_camera(b, 2, 1.0, 0.5 * (b[1] - b[0]))),
               ("perspective", Camera.orbit(b, 25, 30, zoom=1.3))]  # fmt: skip
    combinations = [(pre, shade) for pre in (False, True) for shade in (False, True)
                    if (not pre or support.preintegration) and (not shade or support.shading)]  # fmt: skip
    if ctx.quick:
        combinations = combinations[:: max(1, len(combinations) - 1)]
    n = 24
    for pre, shade in combinations:
        settings = RenderSettings(preintegration=pre, shade=shade)
        renderer = ctx.renderer()
        for name, camera in cameras:
            whole = ctx.draw(renderer, volume, tf, camera, n, n, settings)
            bricked, _ = render_bricked(renderer, VolumeSource(volume), tf, camera, n, n, brick=3)
            problem = _check_values(bricked)
            if problem:
                raise ContractError(f"bricked {name}: {problem}")
            ctx._inputs.pop(id(renderer), None)  # the renderer now holds the last brick
            out.append(Measurement("bricks", f"{name}, pre-integration {pre}, shade {shade}", "RMSE to whole",
                                   _rmse(bricked.astype(np.float64), whole), BRICK_RMSE))  # fmt: skip
    return out


@dataclass(frozen=True)
class Check:
    """A named check and what it verifies (its function's docstring)."""

    name: str
    run: Callable[[CheckContext], list[Measurement]]

    @property
    def description(self) -> str:
        return " ".join((self.run.__doc__ or "").split())


CHECKS: Sequence[Check] = tuple(
    Check(fn.__name__.removeprefix("check_"), fn)
    for fn in (check_output, check_empty, check_box, check_clip, check_clip_region, check_clip_cap, check_ramp, check_projection, check_nan, check_point,
               check_step, check_thin, check_shading, check_eye_inside, check_progress, check_cancel, check_release,
               check_capabilities, check_options, check_bricks, check_labels, check_channels)
)  # fmt: skip
