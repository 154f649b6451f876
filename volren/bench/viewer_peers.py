"""A volren scene drawn the way a PyVista or a napari user draws it: the peers of what users get
today, beside VTK's fastest mapper (`benchmarks.fastest_peer`).

Each peer is built from a uniform `Volume` and a `TransferFunction1D` and draws frames through the
renderer Protocol's shape (`render(camera, width, height) -> float32 (H, W, 4)`, `last_frame`,
`release`, a context manager), so `render_frame`, `volren bench run`'s `time_turning` and the
error metric take it as they take a renderer; it is no registered renderer (`volren render` cannot
pick it). Its images follow DESIGN.md's output rules: premultiplied RGBA over black (alpha 0 where
nothing is drawn), row 0 at the top, the 8-bit channels read back as k / 255.

Construction is cheap; the first `render` makes the plotter or canvas, uploads the grid and draws,
so the one-shot cost of a peer is its construction and first frame. Later frames at the same size
reuse everything: they set the camera, draw and read the pixels back, which is what is timed.

- `PyVistaPeer`: ``pyvista.Plotter(off_screen=True)`` and ``add_volume`` with what a user passes:
  the grid, a colour map of the TF's colours, the TF's opacity sampled over its range, ``clim`` =
  that range and ``opacity_unit_distance`` = the TF's (PyVista's default, the grid's diagonal over
  its mean sample count, would change the optical model). Everything else is add_volume's default:
  the theme's mapper (``smart``, which on llvmpipe runs VTK's GPU ray caster, measured through
  its last render mode, at VTK's own sample distance), nearest-neighbour interpolation (pyvista's
  VolumeProperty default, measured), opacity clipped to 0.998 (its lookup table's), shading off.
  The scalar bar add_volume adds by default is left out: it is not part of the volume.
- `VispyPeer`: vispy's Volume visual as napari draws a 3D Image layer: ``method="translucent"``,
  linear interpolation, vispy's default ``relative_step_size`` 0.8 (napari's `ImageLayerNode` builds
  its `VolumeNode` without one, src/napari/_vispy/layers/image.py, and no layer setting reaches it),
  napari's float texture, and napari's translucent blending (src/napari/_vispy/utils/gl.py,
  `BLENDING_MODES`: alpha accumulates, so the canvas' alpha is the volume's). vispy treats samples
  as voxels: its box reaches half a spacing beyond the outer samples, drawn with their values, so
  on a grid whose border is not transparent it draws a shell that `reference` (the grid's bounds)
  does not (on marschner_lobb, 64x64: RMSE 0.044 at vispy's step and at a quarter of it alike,
  alpha summed 4.5 % above the reference's). Headless through vispy's EGL app on llvmpipe.
"""

from __future__ import annotations

import math
import os
import time
from typing import Any

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.transfer_function import MAX_OPACITY, TransferFunction1D
from volren.model.volume import UniformVolume, Volume
from volren.renderers.base import FrameStats

#: The peers by curve name, in plotting order.
VIEWER_PEERS = ("pyvista", "vispy")
#: Colours in PyVista's lookup table (add_volume's default `n_colors`).
PYVISTA_COLORS = 256
#: Opacity samples handed to add_volume. Not `PYVISTA_COLORS`: pyvista 0.49 stores an array of
#: exactly `n_colors` opacities as the table's raw 0-255 bytes, so values in [0, 1] (what its docs
#: ask for) draw nearly transparent; any other length is interpolated onto the table as documented.
PYVISTA_OPACITY_SAMPLES = 255
#: vispy's `Volume(relative_step_size=...)` default, which napari keeps: the ray step in voxels.
NAPARI_RELATIVE_STEP = 0.8
#: Entries of the colour map handed to vispy: its own lookup-table length (vispy.color.colormap.LUT_len).
VISPY_COLORS = 1024
#: napari's "translucent" blending (napari/_vispy/utils/gl.py): alpha adds up in the canvas.
NAPARI_TRANSLUCENT = {
    "depth_test": True,
    "cull_face": False,
    "blend": True,
    "blend_func": ("src_alpha", "one_minus_src_alpha", "one", "one"),
    "blend_equation": "func_add",
}


def colour_range(tf: TransferFunction1D, volume: UniformVolume) -> tuple[float, float]:
    """The `clim` a user gives: the TF's control-point range, where it is not constant (beyond it
    both peers clamp to the end colours, as the TF does); a constant TF gets the data range."""
    lo, hi = tf.value_range
    if hi > lo:
        return lo, hi
    lo, hi = volume.value_range
    return (lo, hi) if hi > lo else (lo - 0.5, lo + 0.5)


def rgba_image(pixels: NDArray[np.uint8]) -> NDArray[np.float32]:
    """(H, W, 4) 8-bit premultiplied RGBA, row 0 at the top, as float32 k / 255, colour at most
    alpha (rounding each channel on its own can leave colour one step above it)."""
    image = np.ascontiguousarray(pixels[..., :4], dtype=np.float32) / np.float32(255.0)
    np.minimum(image[..., :3], image[..., 3:], out=image[..., :3])
    return image


class ViewerPeer:
    """What both peers share: the Protocol's frame bookkeeping and closing."""

    name = "peer"

    def __init__(self, volume: Volume, tf: TransferFunction1D) -> None:
        if not isinstance(volume, UniformVolume):
            raise VolrenError(f"the {self.name} peer draws uniform grids only, got a {volume.kind} volume")
        if tf.dims != 1:
            raise VolrenError(f"the {self.name} peer takes a 1D transfer function")
        self.volume, self.tf = volume, tf
        self.clim = colour_range(tf, volume)
        self.last_frame: FrameStats | None = None

    def render(self, camera: Camera, width: int, height: int, progress: Any = None) -> NDArray[np.float32]:
        start = time.perf_counter()
        try:
            image = self._draw(camera, width, height)
        except VolrenError:
            raise
        except Exception as exc:  # a tool that cannot draw here (GL, EGL) is a benchmark's cell, not its end
            raise VolrenError(f"the {self.name} peer failed: {type(exc).__name__}: {exc}") from exc
        self.last_frame = FrameStats((time.perf_counter() - start) * 1000.0, width, height, {})
        if progress is not None:
            progress(1.0)
        return image

    def _draw(self, camera: Camera, width: int, height: int) -> NDArray[np.float32]:
        raise NotImplementedError

    def release(self) -> None:
        """Free the window or canvas; a later frame makes a new one."""

    def __enter__(self) -> ViewerPeer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


# ----------------------------------------------------------------------------------------- PyVista
class PyVistaPeer(ViewerPeer):
    """``Plotter.add_volume`` off screen, as a PyVista user draws the scene (module docstring).

    A frame: our camera onto the plotter's (the vtk renderer's own conversion), ``plotter.render()``
    and ``plotter.screenshot(transparent_background=True)``, which reads the window's RGBA back."""

    name = "pyvista"

    def __init__(self, volume: Volume, tf: TransferFunction1D) -> None:
        super().__init__(volume, tf)
        self._plotter: Any = None

    def _open(self, width: int, height: int) -> None:
        from volren.extras import require

        require("bench", "the pyvista peer (its colour map)")
        import pyvista as pv
        from matplotlib.colors import ListedColormap

        volume = self.volume
        grid = pv.ImageData(dimensions=volume.dimensions, spacing=volume.spacing, origin=volume.origin)
        grid.point_data["values"] = volume.values.reshape(-1)  # x fastest: VTK's point order
        lo, hi = self.clim
        rgb, _ = self.tf.sample(np.linspace(lo, hi, PYVISTA_COLORS))
        _, opacity = self.tf.sample(np.linspace(lo, hi, PYVISTA_OPACITY_SAMPLES))
        plotter = pv.Plotter(off_screen=True, window_size=[width, height])
        plotter.set_background("black")
        plotter.add_volume(
            grid,
            scalars="values",
            cmap=ListedColormap(rgb),
            opacity=opacity,
            clim=(lo, hi),
            opacity_unit_distance=self.tf.opacity_unit_distance,
            show_scalar_bar=False,
        )
        self._plotter = plotter

    def _draw(self, camera: Camera, width: int, height: int) -> NDArray[np.float32]:
        from volren.vtk_messages import vtk_messages

        if self._plotter is not None:
            return self._frame(camera, width, height)
        # VTK tries an X window before EGL and says so on stderr; caught, and its errors raised
        with vtk_messages() as messages:
            self._open(width, height)
            image = self._frame(camera, width, height)
        if messages.errors:
            raise VolrenError(f"the pyvista peer failed: {messages.errors[0].text[:300]}")
        return image

    def _frame(self, camera: Camera, width: int, height: int) -> NDArray[np.float32]:
        from volren.renderers.vtk_mappers.convert import set_camera

        plotter = self._plotter
        if tuple(plotter.window_size) != (width, height):
            plotter.window_size = [width, height]
        set_camera(plotter.camera, camera)
        plotter.camera.is_set = True  # else the first screenshot resets the camera to fit the data
        plotter.render()
        pixels = plotter.screenshot(transparent_background=True, return_img=True)
        return rgba_image(np.asarray(pixels))

    def release(self) -> None:
        if self._plotter is not None:
            self._plotter.close()
            self._plotter = None


# ------------------------------------------------------------------------------------------- vispy
def vispy_matrix(camera: Camera, volume: UniformVolume, width: int, height: int) -> NDArray[np.float64]:
    """vispy's transform (row vectors: p @ M) from the Volume visual's voxel coordinates (x, y, z
    index, voxel centres at whole numbers) to the canvas' document coordinates (pixels, y down,
    depth as OpenGL's [-1, 1]): the grid's placement, then our camera's view and projection
    (`Camera.view_matrix`, `projection_matrix`, as every renderer of ours projects), then the
    viewport. Kept homogeneous, so vispy's shader recovers each pixel's ray exactly as it does
    under its own perspective cameras."""
    place = np.diag([*volume.spacing, 1.0])
    place[:3, 3] = volume.origin
    viewport = np.array(
        [[width / 2, 0, 0, width / 2], [0, -height / 2, 0, height / 2], [0, 0, 1, 0], [0, 0, 0, 1]]
    )
    return (viewport @ camera.projection_matrix(width / height) @ camera.view_matrix() @ place).T


def vispy_step(camera: Camera, volume: UniformVolume) -> float:
    """The world length of vispy's ray step along the view direction: it steps
    `NAPARI_RELATIVE_STEP` in voxel units, which a grid's spacing stretches by 1 / |d / spacing| for
    the unit world direction d (on an isotropic grid, the relative step times the spacing)."""
    d = camera.direction / np.asarray(volume.spacing, dtype=np.float64)
    return NAPARI_RELATIVE_STEP / float(np.linalg.norm(d))


def napari_colormap(tf: TransferFunction1D, clim: tuple[float, float], step: float) -> NDArray[np.float32]:
    """(VISPY_COLORS, 4) RGBA over `clim`: the TF's colour, and as alpha the opacity of one vispy
    step of `step` world units, 1 - exp(-tau step) = 1 - (1 - a)^(step / d_u) (DESIGN.md's model).

    napari has no opacity per unit length: its translucent method composites the colour map's
    alpha once per sample, whatever the step, so this per-sample opacity is the best a careful
    napari user can do to draw volren's optical model (the step being vispy's, fixed per view)."""
    values = np.linspace(clim[0], clim[1], VISPY_COLORS)
    rgb, alpha = tf.sample(values)
    per_sample = -np.expm1(np.log1p(-np.minimum(alpha, MAX_OPACITY)) * (step / tf.opacity_unit_distance))
    return np.concatenate([rgb, per_sample[:, None]], axis=1).astype(np.float32)


def _vispy_app() -> Any:
    """vispy with its EGL app (headless; Mesa's surfaceless platform unless EGL_PLATFORM is set),
    or a VolrenError saying what is missing."""
    os.environ.setdefault("EGL_PLATFORM", "surfaceless")
    try:
        import vispy
    except ModuleNotFoundError:
        raise VolrenError(
            "the vispy peer needs vispy and PyOpenGL, which are not installed: pip install 'volren[bench]'"
        ) from None
    try:
        vispy.use(app="egl")
        from vispy import app

        app.use_app("egl")
    except Exception as exc:  # vispy raises RuntimeError, ImportError, OSError by backend
        raise VolrenError(f"the vispy peer cannot open an EGL context: {exc}") from None
    return vispy


class VispyPeer(ViewerPeer):
    """vispy's Volume visual as napari draws a 3D Image layer (module docstring).

    Placement and camera are one `MatrixTransform` (`vispy_matrix`): the same view and projection
    our renderers use, where a TurntableCamera would need its own angles, fov and distance fitted
    to ours. The colour map's alpha is `napari_colormap`'s per-sample opacity, rebuilt when the
    step's world length changes with the view (anisotropic grids only). A frame: the transform,
    ``canvas.render()`` (draws into a new framebuffer and reads its RGBA back)."""

    name = "vispy"

    def __init__(self, volume: Volume, tf: TransferFunction1D) -> None:
        super().__init__(volume, tf)
        self._canvas: Any = None
        self._visual: Any = None
        self._step: float | None = None

    def _open(self, width: int, height: int) -> None:
        _vispy_app()
        from vispy import scene
        from vispy.visuals.transforms import MatrixTransform

        try:
            canvas = scene.SceneCanvas(size=(width, height), show=False, bgcolor=(0.0, 0.0, 0.0, 0.0))
        except Exception as exc:
            raise VolrenError(f"the vispy peer cannot make a canvas: {exc}") from None
        data = np.asarray(self.volume.values, dtype=np.float32)  # napari's float texture ("auto")
        visual = scene.visuals.Volume(
            data,
            parent=canvas.scene,
            method="translucent",
            clim=self.clim,
            interpolation="linear",
            relative_step_size=NAPARI_RELATIVE_STEP,
            texture_format="auto",
        )
        visual.set_gl_state(**NAPARI_TRANSLUCENT)
        visual.transform = MatrixTransform()
        self._canvas, self._visual = canvas, visual

    def _colormap(self, step: float) -> None:
        from vispy.color import Colormap

        if self._step is None or not math.isclose(step, self._step, rel_tol=1e-9):
            self._visual.cmap = Colormap(napari_colormap(self.tf, self.clim, step))
            self._step = step

    def _draw(self, camera: Camera, width: int, height: int) -> NDArray[np.float32]:
        if self._canvas is None:
            self._open(width, height)
        canvas = self._canvas
        if tuple(canvas.size) != (width, height):
            canvas.size = (width, height)
        self._colormap(vispy_step(camera, self.volume))
        self._visual.transform.matrix = vispy_matrix(camera, self.volume, width, height)
        pixels = canvas.render(alpha=True)
        if pixels.shape[:2] != (height, width):
            raise VolrenError(
                f"vispy returned {pixels.shape[1]}x{pixels.shape[0]} pixels for {width}x{height}"
            )
        return rgba_image(pixels)

    def release(self) -> None:
        if self._canvas is not None:
            self._canvas.close()
            self._canvas = self._visual = None
            self._step = None


PEER_CLASSES: dict[str, type[ViewerPeer]] = {"pyvista": PyVistaPeer, "vispy": VispyPeer}


def open_peer(name: str, volume: Volume, tf: TransferFunction1D) -> ViewerPeer:
    """The peer called `name` (one of `VIEWER_PEERS`) for this scene; a VolrenError names why it
    cannot draw it (a volume it does not take; a missing package or EGL shows at the first frame)."""
    if name not in PEER_CLASSES:
        raise VolrenError(f"unknown viewer peer {name!r}; choose from {', '.join(VIEWER_PEERS)}")
    return PEER_CLASSES[name](volume, tf)
