"""The `slicer` renderer: view-aligned sample planes through a 3D texture, with moderngl.

Why two paths over the same planes (option `path`):
- `slices` is the slicer of Real-Time Volume Graphics (section 3.3): polygons where the planes cut the volume's box,
  computed on the CPU (`proxy_geometry`), rasterized front to back and blended "under".
- `march` walks the same planes per pixel in a compute shader. It visits exactly the same sample
  points, so it gives the same image, but a ray can stop when it is opaque and jump over empty
  bricks, which blending cannot do cheaply.
Both classify the segment between two consecutive planes with `shaders/common.glsl`: post-
classified 1D TF (opacity corrected for the segment's length), pre-integrated 1D TF (a table for
the plane spacing, corrected per segment for the real length along the ray, Schulze et al. 2003) with
interpolated pre-integrated lighting (Lum et al.) when shading, a post-classified 2D TF, a label
volume's TF per label (blended in cells whose corners differ: Real-Time Volume Graphics, section 16.5)
or several channels' TFs with their extinctions added (Max 1995); the last two composite, unshaded and
post-classified only, as raycast and the reference draw them. The
segment from where a ray enters the box to its first plane and the one from its last plane to the
exit are integrated too (in the slice path the polygons are cut from a slightly grown box, so the
planes just before the box own the entry segments), so a homogeneous block looks the same at every
step.

What is not redone: the volume texture is uploaded when the volume changes, the gradient texture
only when shading or a 2D TF first needs it, TF tables and the brick mask when the TF version (or
the table size or plane spacing) changes. `uploads` counts each kind; frame counters say what a
frame did (samples fetched, brick jumps, rays stopped early, fragments, passes).
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.kernels.shading import gradient_threshold
from volren.model.bricks import BrickGrid
from volren.model.camera import Camera
from volren.model.channels import ChannelTransferFunction
from volren.model.labels import LabelTransferFunction, cell_classes
from volren.model.settings import BlendMode
from volren.model.volume import UniformVolume
from volren.renderers.base import (
    Accuracy,
    Capabilities,
    KindSupport,
    OptionSpec,
    ProgressCallback,
    QualityLevel,
    RendererBase,
)
from volren.renderers.glsl import compile_program, load_shader
from volren.renderers.opengl import GLObjectOwner, mat4_bytes, require_opengl
from volren.renderers.slicer import textures
from volren.renderers.slicer.proxy_geometry import slice_polygons, triangle_fan

SHADER_DIR = Path(__file__).resolve().parent / "shaders"
PATHS = ("march", "slices")
#: (values, gradient magnitudes) of the 2D TF texture.
TF2D_TABLE_SIZE = (512, 256)
_BLEND_CODES = {BlendMode.COMPOSITE: 0, BlendMode.MAXIMUM: 1, BlendMode.MINIMUM: 2, BlendMode.AVERAGE: 3}
_ALL_MODES = frozenset(BlendMode)
_LOCAL_SIZE = 8
#: Rows of the clip region the shaders take (common.glsl's MAX_CLIP): six planes and a box's faces.
MAX_CLIP_ROWS = 12
#: Lanes of the march path's work counters (march.comp.glsl), 4 uint32 each.
_STAT_LANES = 1024
_COUNTER_BYTES = 16 * _STAT_LANES


class SlicerRenderer(GLObjectOwner, RendererBase):
    """View-aligned slicing of uniform volumes on the GPU (or Mesa llvmpipe)."""

    name: ClassVar[str] = "slicer"
    capabilities: ClassVar[Capabilities] = Capabilities(
        kinds={
            "uniform": KindSupport(
                tf_dims=frozenset({1, 2}),
                preintegration=True,
                shading=True,
                blend_modes=_ALL_MODES,
                # kit (volren check-renderer slicer, llvmpipe): RMSE up to 0.023 (maximum projection
                # between samples), the point 0.02 px off
                accuracy=Accuracy(rmse=0.03, position_px=0.1),
                regions=True,
                clip_region=True,
                # composite, post-classified, unshaded, whole volumes (`_refuse_labels_channels`)
                labels=True,
                channels=True,
            )
        },
        backend="opengl",
        summary="moderngl view-aligned slicing: pre-integration, lighting, empty-space skipping",
        quality=(
            QualityLevel("step 2", step=2.0),
            QualityLevel("step 1", step=1.0),
            QualityLevel("step 0.5 (default)", step=0.5),
            QualityLevel("step 0.5, pre-integrated", step=0.5, preintegration=True),
            QualityLevel("step 0.25, pre-integrated", step=0.25, preintegration=True),
        ),
    )
    options: ClassVar[tuple[OptionSpec, ...]] = (
        OptionSpec(
            "path",
            "march",
            "choice",
            "march: a compute shader walks the slice planes per pixel, with early "
            "termination and brick skipping; slices: the planes as blended polygons",
            choices=PATHS,
        ),
        OptionSpec(
            "table_size", 512, "int", "entries per axis of the pre-integration table", low=2, high=4096
        ),
        OptionSpec("empty_space_skipping", True, "bool", "skip bricks whose values map to zero opacity"),
        OptionSpec(
            "early_termination", True, "bool", "stop a ray once its opacity reaches termination_alpha"
        ),
        OptionSpec(
            "termination_alpha",
            0.999,
            "float",
            "opacity at which early termination stops a ray",
            low=0.0,
            high=1.0,
            low_exclusive=True,
        ),
        OptionSpec("brick_size", 8, "int", "cells per brick edge for empty-space skipping", low=1),
        OptionSpec("jitter_seed", 1, "int", "seed of the per-pixel jitter when jitter is on", low=1),
        OptionSpec(
            "termination_interval",
            16,
            "int",
            "slices between early-termination passes in the slices path",
            low=1,
        ),
        OptionSpec(
            "volume_format",
            "float",
            "choice",
            "float: the volume as normalised float32; native: 8-bit data "
            "as an 8-bit texture (a quarter of the memory; Mesa llvmpipe then rounds every interpolated value)",
            choices=("float", "native"),
        ),
    )

    def __init__(self) -> None:
        super().__init__()
        self._ctx: Any = None
        self._in_frame = False
        self._objects: list[Any] = []  # every GL object made, for release()
        self._programs: dict[tuple, Any] = {}
        self._volume_tex: Any = None
        self._volume_info: textures.VolumeTexture | None = None
        self._gradient_tex: Any = None
        self._gradient_scale = 1.0
        self._bricks: BrickGrid | None = None
        self._tables: dict[str, tuple[tuple, Any]] = {}
        self._targets: dict[str, tuple[tuple, Any]] = {}
        self._mask_state: tuple[tuple, NDArray[np.bool_]] | None = None
        self._mask_tex: Any = None
        self._counter_buffer: Any = None  # the march path's work counters (4 x uint32)
        #: Label, cell-class, lookup and channel textures: (key, texture) by name, dropped with the volume.
        self._data: dict[str, tuple[tuple, Any]] = {}
        #: How often each kind of data went to the GPU (or was rebuilt) since the renderer was made.
        self.uploads: dict[str, int] = {"volume": 0, "gradient": 0, "tables": 0, "brick_mask": 0}

    # ------------------------------------------------------------------------ GL objects
    def _context(self) -> Any:
        if self._ctx is None:
            require_opengl()
            import moderngl

            try:
                self._ctx = moderngl.create_standalone_context(backend="egl", require=430)  # type: ignore[arg-type]
            except Exception:
                self._ctx = moderngl.create_standalone_context(backend="egl")  # type: ignore[arg-type]
        return self._ctx

    def _program(self, kind: str, defines: Mapping[str, int]) -> Any:
        key = (kind, tuple(sorted(defines.items())))
        program = self._programs.get(key)
        if program is None:
            ctx = self._context()
            if kind == "march":
                if ctx.version_code < 430:
                    raise VolrenError(
                        f"slicer path march needs OpenGL 4.3 compute shaders; this driver offers "
                        f"{ctx.version_code / 100:.1f}: use the option path=slices"
                    )
                program = compile_program(ctx, compute=load_shader("march.comp.glsl", defines, [SHADER_DIR]))
            elif kind == "slices":
                program = compile_program(
                    ctx,
                    vertex=load_shader("slice.vert.glsl", {}, [SHADER_DIR]),
                    fragment=load_shader("slice.frag.glsl", defines, [SHADER_DIR]),
                )
            else:
                program = compile_program(
                    ctx,
                    vertex=load_shader("terminate.vert.glsl", {}, [SHADER_DIR]),
                    fragment=load_shader("terminate.frag.glsl", {}, [SHADER_DIR]),
                )
            self._programs[key] = self._track(program)
        return program

    # ------------------------------------------------------------------------------ hooks
    def _volume_changed(self) -> None:
        # The TF tables stay: their keys hold every volume property they depend on (value range,
        # plane spacing), so the bricks of one bricked frame share them. The brick mask goes.
        # Outside a frame our context may not be current, and a texture deleted in another
        # context (or none) is never freed: every brick of a bricked frame would leak its volume.
        with self._ctx if (self._ctx is not None and not self._in_frame) else contextlib.nullcontext():
            for name in ("_volume_tex", "_gradient_tex"):
                self._drop(getattr(self, name))
                setattr(self, name, None)
            mask = self._tables.pop("brick_mask", None)
            if mask is not None:
                self._drop(mask[1])
            for _, tex in self._data.values():
                self._drop(tex)
            self._data.clear()
        self._volume_info = None
        self._bricks = None
        self._mask_state = None

    def _region_changed(self) -> None:
        # The value range the volume is normalised to may be the whole volume's now (or no longer).
        self._volume_changed()

    def ghost_voxels(self, spacing, camera: Camera, width: int, height: int) -> int:
        """A pre-integrated segment owned by a brick (its front is inside) ends up to one plane
        spacing along the ray beyond the face: its end value and gradient need that many voxels
        and one more (interpolation) and one more again (central differences). Post-classified
        segments are read at their middle, inside the box: one voxel (gradients)."""
        if not (self._settings.preintegration and self._settings.blend_mode == BlendMode.COMPOSITE):
            return 1
        spacing = tuple(float(h) for h in spacing)
        reach = (
            float(self._settings.step)
            * float(np.mean(spacing))
            / (self._min_cosine(camera, width, height) * min(spacing))
        )
        return int(math.floor(reach)) + 2

    # --------------------------------------------------------------------------- volume
    def _uniform_volume(self) -> UniformVolume:
        volume = self._volume
        assert isinstance(volume, UniformVolume)
        return volume

    def _ensure_volume(self, opts: Mapping[str, Any]) -> textures.VolumeTexture:
        native = opts["volume_format"] == "native"
        if self._volume_tex is not None and (
            self._volume_info is None
            or (self._volume_info.dtype == "f1")
            != (native and self._uniform_volume().values.dtype == np.uint8)
        ):
            self._drop(self._volume_tex)
            self._volume_tex = None
        if self._volume_tex is None:
            volume = self._uniform_volume()
            info = textures.volume_texture(volume, native, self._whole_value_range())
            nz, ny, nx = info.data.shape
            limit = self._context().info["GL_MAX_3D_TEXTURE_SIZE"]
            if max(nx, ny, nz) > limit:
                raise VolrenError(
                    f"slicer: the volume is {nx}x{ny}x{nz}, but this OpenGL driver allows 3D textures "
                    f"of at most {limit} per side"
                )
            tex = self._context().texture3d(
                (nx, ny, nz), 1, np.ascontiguousarray(info.data), dtype=info.dtype
            )
            tex.repeat_x = tex.repeat_y = tex.repeat_z = False
            self._volume_tex = self._track(tex)
            self._volume_info = info
            self.uploads["volume"] += 1
        assert self._volume_info is not None
        return self._volume_info

    def _ensure_gradient(self) -> Any:
        if self._gradient_tex is None:
            volume = self._uniform_volume()
            data, scale = textures.gradient_texture(volume, self._whole_value_range())
            nz, ny, nx = volume.values.shape
            tex = self._context().texture3d((nx, ny, nz), 3, data, dtype="f2")
            tex.repeat_x = tex.repeat_y = tex.repeat_z = False
            self._gradient_tex = self._track(tex)
            self._gradient_scale = scale
            self.uploads["gradient"] += 1
        return self._gradient_tex

    def _table(self, name: str, key: tuple, build) -> Any:
        """The texture `name`, rebuilt only when `key` (TF version, sizes, spacing) changes."""
        held = self._tables.get(name)
        if held is not None and held[0] == key:
            return held[1]
        if held is not None:
            self._drop(held[1])
        data = np.ascontiguousarray(build(), dtype=np.float32)
        is_mask = name == "brick_mask"
        if not is_mask:
            tex = self._context().texture((data.shape[1], data.shape[0]), data.shape[2], data, dtype="f4")
            tex.repeat_x = tex.repeat_y = False
        else:  # brick mask (bz, by, bx), one byte per brick
            bz, by, bx = data.shape
            tex = self._context().texture3d((bx, by, bz), 1, (data * 255).astype(np.uint8), dtype="f1")
            tex.filter = (self._nearest(), self._nearest())
            tex.repeat_x = tex.repeat_y = tex.repeat_z = False
        self._tables[name] = (key, self._track(tex))
        self.uploads["brick_mask" if is_mask else "tables"] += 1
        return tex

    @staticmethod
    def _nearest() -> int:
        import moderngl

        return moderngl.NEAREST

    def _target(self, name: str, width: int, height: int) -> Any:
        """A float RGBA texture (march) or framebuffer with depth (slices) of the frame's size."""
        key = (width, height)
        held = self._targets.get(name)
        if held is not None and held[0] == key:
            return held[1]
        if held is not None:
            for obj in held[1] if isinstance(held[1], tuple) else (held[1],):
                self._drop(obj)
        ctx = self._context()
        if name == "march_reader":  # reads a rectangle of the march target back
            value: Any = self._track(
                ctx.framebuffer(color_attachments=[self._target("march", width, height)])
            )
            self._targets[name] = (key, value)
            return value
        colour = self._track(ctx.texture((width, height), 4, dtype="f4"))
        colour.filter = (self._nearest(), self._nearest())
        if name == "march":
            value = colour
        else:
            depth = self._track(ctx.depth_renderbuffer((width, height)))
            fbo = self._track(ctx.framebuffer(color_attachments=[colour], depth_attachment=depth))
            term = self._track(ctx.framebuffer(color_attachments=[], depth_attachment=depth))
            value = (fbo, term, colour, depth)
        self._targets[name] = (key, value)
        return value

    # ----------------------------------------------------------------------- frame setup
    def _mode(self) -> int:
        """0 post-classified 1D TF, 1 pre-integrated 1D TF, 2 post-classified 2D TF, 3 labels, 4 channels."""
        if isinstance(self._tf, LabelTransferFunction):
            return 3
        if isinstance(self._tf, ChannelTransferFunction):
            return 4
        if getattr(self._tf, "dims", 1) == 2:
            return 2
        return 1 if self._settings.preintegration else 0

    def _spacing(self) -> float:
        return float(self._settings.step) * self._uniform_volume().characteristic_length

    def _skip_reach(self, spacing: float, brick: int, min_cosine: float) -> int:
        """Bricks a segment can reach beyond its own: a segment is at most one plane spacing
        along the view axis, so spacing / cos(angle of the ray) long."""
        volume = self._uniform_volume()
        return max(1, math.ceil(spacing / min_cosine / (brick * min(volume.spacing))))

    def _brick_mask(self, opts: Mapping[str, Any], spacing: float, min_cosine: float) -> dict[str, float]:
        """Classify the bricks for the current TF (dilated so that pre-integrated segments
        reaching into a neighbour are covered) and upload the mask when it changed."""
        volume = self._uniform_volume()
        if self._bricks is None or self._bricks.brick != opts["brick_size"]:
            self._bricks = BrickGrid.from_volume(volume, opts["brick_size"])
            self._mask_state = None
        grid = self._bricks
        tf: Any = self._tf  # a 1D or 2D TF: `_defines` skips bricks for labels and channels
        assert tf is not None
        reach = self._skip_reach(spacing, opts["brick_size"], min_cosine)
        key = (tf.version, opts["brick_size"], reach)
        if self._mask_state is None or self._mask_state[0] != key:
            self._mask_state = (key, grid.dilated(reach).visible(tf))
        visible = self._mask_state[1]
        self._mask_tex = self._table("brick_mask", key, lambda: (~visible).astype(np.float32))
        stats = grid.stats(visible)
        return {"bricks": stats.n_bricks, "bricks_empty": stats.n_bricks - stats.n_visible}

    def _defines(self, opts: Mapping[str, Any]) -> dict[str, int]:
        s = self._settings
        composite = s.blend_mode == BlendMode.COMPOSITE
        mode = self._mode() if composite else 0
        defines = {
            "CLASSIFY": mode,
            "SHADE": int(s.shade and composite),
            "BLEND": _BLEND_CODES[s.blend_mode],
            # the brick mask classifies the volume's values by a 1D or 2D TF, not labels or channels
            "SKIP": int(opts["empty_space_skipping"] and composite and mode < 3),
            "NONFINITE": int(self._uniform_volume().nonfinite_count > 0),
            "REGION": int(self._region is not None),
        }
        if mode == 3:
            defines["LOOKUP_WIDTH"] = textures.LOOKUP_WIDTH
        elif mode == 4:
            drawn = len(self._drawn_channels())
            defines["CHANNELS"] = drawn
            defines["CHANNEL_TEXTURES"] = max(1, -(-drawn // 4))
        return defines

    def _bind_clip(self, program: Any) -> None:
        """The clip region's half-spaces (world) for `clip_interval` in common.glsl."""
        rows = self._settings.clip.half_spaces()
        clip = np.zeros((MAX_CLIP_ROWS, 4), np.float32)
        clip[: len(rows)] = rows
        if "u_clip" in program:
            program["u_clip"].write(clip.tobytes())
        self._set(program, "u_clip_count", len(rows))

    def _set(self, program: Any, name: str, value: Any) -> None:
        if name in program:
            program[name].value = value

    def _bind(self, program: Any, defines: Mapping[str, int], camera: Camera, opts: Mapping[str, Any]) -> int:
        """Set the uniforms and textures both paths share; returns the next free texture unit."""
        volume = self._uniform_volume()
        info = self._ensure_volume(opts)
        tf: Any = self._tf  # the kind `defines["CLASSIFY"]` was chosen for
        assert tf is not None
        spacing = self._spacing()
        region = self._region
        bounds = (
            region.whole_bounds if region is not None else volume.bounds
        )  # where rays enter, planes anchor
        box_min = np.array(bounds[0::2])
        box_max = np.array(bounds[1::2])
        dims = np.array(volume.dimensions, dtype=np.float64)
        sp = np.array(volume.spacing)
        scale = 1.0 / (sp * dims)
        offset = (0.5 - np.array(volume.origin) / sp) / dims
        view_dir = np.asarray(camera.direction, dtype=np.float64)
        s = self._settings
        unit = 0
        self._volume_tex.use(location=unit)
        self._set(program, "u_volume", unit)
        unit += 1
        self._set(program, "u_value_map", tuple(float(v) for v in info.value_map))
        self._set(program, "u_box_min", tuple(box_min))
        self._set(program, "u_box_max", tuple(box_max))
        self._set(program, "u_world_to_tex_scale", tuple(scale))
        self._set(program, "u_world_to_tex_offset", tuple(offset))
        self._set(program, "u_view_dir", tuple(view_dir))
        self._set(program, "u_plane_base", float(view_dir @ box_min))
        self._set(program, "u_spacing", spacing)
        self._set(program, "u_jitter_seed", int(opts["jitter_seed"]) if s.jitter else 0)
        self._set(program, "u_light", tuple(-view_dir))
        self._bind_clip(program)
        if region is not None:
            self._set(program, "u_owner_min", region.owner_min)
            self._set(program, "u_owner_max", region.owner_max)
        lo, hi = info.lo, info.hi
        mode = defines["CLASSIFY"]
        n = opts["table_size"]
        if mode == 0:
            tex = self._table("post", (tf.version, lo, hi), lambda: textures.post_tf_table(tf, lo, hi))
            tex.use(location=unit)
            self._set(program, "u_tf", unit)
            self._set(program, "u_tf_size", float(textures.POST_TF_SIZE))
            unit += 1
        elif mode == 1:
            if defines["SHADE"]:
                key = (tf.version, lo, hi, n, spacing)
                pair: dict[str, NDArray] = {}

                def front() -> NDArray:
                    pair["front"], pair["back"] = textures.lighting_textures(tf, lo, hi, n, spacing)
                    return pair["front"]

                front_tex = self._table("light_front", key, front)
                back_tex = self._table(
                    "light_back",
                    key,
                    lambda: pair.get("back", textures.lighting_textures(tf, lo, hi, n, spacing)[1]),
                )
                front_tex.use(location=unit)
                back_tex.use(location=unit + 1)
                self._set(program, "u_preint", unit)
                self._set(program, "u_preint_back", unit + 1)
                unit += 2
            else:
                tex = self._table(
                    "preint",
                    (tf.version, lo, hi, n, spacing),
                    lambda: textures.preintegration_table(tf, lo, hi, n, spacing),
                )
                tex.use(location=unit)
                self._set(program, "u_preint", unit)
                unit += 1
            self._set(program, "u_preint_size", float(n))
        elif mode == 3:
            unit = self._bind_labels(program, unit, lo, hi)
        elif mode == 4:
            unit = self._bind_channels(program, unit)
        elif mode == 2:
            n_values, n_gradients = TF2D_TABLE_SIZE
            tex = self._table(
                "tf2d", (tf.version, lo, hi), lambda: textures.tf2d_table(tf, lo, hi, n_values, n_gradients)
            )
            tex.use(location=unit)
            self._set(program, "u_tf2d", unit)
            self._set(program, "u_tf2d_size", (float(n_values), float(n_gradients)))
            self._set(program, "u_tf2d_gradient_max", float(tf.gradient_range[1]))
            unit += 1
        if defines["SHADE"] or mode == 2:
            self._ensure_gradient().use(location=unit)
            self._set(program, "u_gradient", unit)
            self._set(program, "u_gradient_scale", float(self._gradient_scale))
            unit += 1
        if defines["SHADE"]:
            self._set(program, "u_ambient", float(s.ambient))
            self._set(program, "u_diffuse", float(s.diffuse))
            self._set(program, "u_specular", float(s.specular))
            self._set(program, "u_specular_power", float(s.specular_power))
            value_lo, value_hi = self._whole_value_range()
            span = float(value_hi - value_lo)
            self._set(program, "u_gradient_threshold", gradient_threshold(span, volume.characteristic_length))
        if defines["SKIP"]:
            grid_bricks = self._bricks
            assert grid_bricks is not None
            self._mask_tex.use(location=unit)
            self._set(program, "u_brick_mask", unit)
            self._set(program, "u_brick_origin", tuple(float(v) for v in volume.origin))
            self._set(program, "u_brick_size", tuple(float(opts["brick_size"] * h) for h in volume.spacing))
            bz, by, bx = grid_bricks.shape
            self._set(program, "u_brick_count", (bx, by, bz))
            unit += 1
        return unit

    def _data_texture(self, name: str, key: tuple, build) -> Any:
        """The texture `name` (label, cell-class, lookup or channel data), made by `build` (which
        uploads it) only when `key` changes."""
        held = self._data.get(name)
        if held is not None and held[0] == key:
            return held[1]
        if held is not None:
            self._drop(held[1])
        tex = self._track(build())
        self._data[name] = (key, tex)
        return tex

    def _integer_texture3d(self, data: NDArray, dtype: str) -> Any:
        """A one-component integer 3D texture of `data` (nz, ny, nx), read with texelFetch."""
        nz, ny, nx = data.shape
        tex = self._context().texture3d((nx, ny, nz), 1, np.ascontiguousarray(data), dtype=dtype)
        tex.filter = (self._nearest(), self._nearest())
        tex.repeat_x = tex.repeat_y = tex.repeat_z = False
        return tex

    def _bind_labels(self, program: Any, unit: int, lo: float, hi: float) -> int:
        """The label volume's textures: per cell its class (`cell_classes`), per point its label,
        label -> class, and the classes' tables over the volume's value range [lo, hi]."""
        tf = self._tf
        volume = self._uniform_volume()
        assert isinstance(tf, LabelTransferFunction) and volume.labels is not None
        labels = volume.labels
        classes = tf.classes(labels.max_label)
        n = textures.class_table_size(len(classes.tfs))
        rows = max(len(classes.tfs), 1)
        limit = self._context().info["GL_MAX_TEXTURE_SIZE"]
        if rows > limit:
            raise VolrenError(
                f"slicer: {rows} label styles that draw differently, but this OpenGL driver holds at most {limit}"
            )
        key = (labels.digest, classes.lookup.tobytes())
        cells = self._data_texture(
            "cells",
            key,
            lambda: self._integer_texture3d(
                cell_classes(labels.values, classes.lookup, labels.boundary), "i2"
            ),
        )
        points = self._data_texture(
            "labels",
            (labels.digest,),
            lambda: self._integer_texture3d(labels.values, f"u{labels.values.itemsize}"),
        )

        def lookup_texture() -> Any:
            data = textures.label_lookup(classes.lookup)
            tex = self._context().texture((data.shape[1], data.shape[0]), 1, data, dtype="i4")
            tex.filter = (self._nearest(), self._nearest())
            return tex

        lookup = self._data_texture("lookup", key, lookup_texture)
        table = self._table(
            "classes", (tf.version, tf.digest(), labels.max_label, lo, hi, n),
            lambda: textures.class_tables(classes.tfs, lo, hi, n),
        )  # fmt: skip
        for name, tex in (
            ("u_cells", cells),
            ("u_labels", points),
            ("u_lookup", lookup),
            ("u_classes", table),
        ):
            tex.use(location=unit)
            self._set(program, name, unit)
            unit += 1
        self._set(program, "u_lookup_count", len(classes.lookup))
        self._set(program, "u_classes_size", float(n))
        self._set(program, "u_dims", tuple(int(d) for d in volume.dimensions))
        return unit

    def _drawn_channels(self) -> list[int]:
        """The channels that draw: shown, with a weight above 0."""
        tf = self._tf
        assert isinstance(tf, ChannelTransferFunction)
        return [c for c in range(tf.count) if tf.drawn_weight(c) > 0.0]

    def _bind_channels(self, program: Any, unit: int) -> int:
        """The drawn channels, four to an RGBA texture normalised over each one's range, and their
        depth tables (`textures.channel_tables`)."""
        tf = self._tf
        volume = self._uniform_volume()
        assert isinstance(tf, ChannelTransferFunction) and volume.channels is not None
        channels = volume.channels
        drawn = self._drawn_channels() or [0]  # none drawn: channel 0's texture, no table row draws
        ranges = [channels.value_ranges[c] for c in drawn]
        spans = [textures.value_range_of(r) for r in ranges]
        key = (channels.digest, tuple(drawn))
        n = textures.POST_TF_SIZE
        for t in range(0, len(drawn), 4):

            def build(first: int = t) -> Any:
                data = textures.channel_textures(
                    channels.values[drawn[first : first + 4]], ranges[first : first + 4]
                )
                nz, ny, nx, _ = data.shape
                tex = self._context().texture3d((nx, ny, nz), 4, data, dtype="f4")
                tex.repeat_x = tex.repeat_y = tex.repeat_z = False
                return tex

            tex = self._data_texture(f"channels{t // 4}", key, build)
            tex.use(location=unit)
            self._set(program, f"u_channels{t // 4}", unit)
            unit += 1
        weights = [tf.drawn_weight(c) for c in drawn]  # 0 for channel 0 where none is drawn
        table = self._table(
            "channel_tables", (tf.version, tf.digest(), tuple(drawn), tuple(spans), n),
            lambda: textures.channel_tables([tf.tfs[c] for c in drawn], weights, spans, n),
        )  # fmt: skip
        table.use(location=unit)
        self._set(program, "u_channel_tables", unit)
        self._set(program, "u_channel_table_size", float(n))
        return unit + 1

    def _refuse_labels_channels(self) -> None:
        """What the label and channel models are not drawn with here (raycast's refusals and more):
        other blend modes, shading, bricks of a bricked render; one line each."""
        tf = self._tf
        what = (
            "label volumes" if isinstance(tf, LabelTransferFunction)
            else "multi-channel volumes" if isinstance(tf, ChannelTransferFunction) else None
        )  # fmt: skip
        if what is None:
            return
        s = self._settings
        if s.blend_mode != BlendMode.COMPOSITE:
            raise VolrenError(f"slicer: {what} are drawn composite only, not with {s.blend_mode}")
        if s.shade:
            raise VolrenError(f"slicer: {what} are drawn unshaded: switch shading off")
        if self._region is not None:
            raise VolrenError(f"slicer: {what} are not drawn as bricks of a bricked render")

    # ------------------------------------------------------------------------------ render
    def _render(
        self, camera: Camera, width: int, height: int, progress: ProgressCallback | None
    ) -> tuple[NDArray[np.float32], Mapping[str, float]]:
        # Other renderers (another slicer, VTK) make their own contexts current on this thread.
        with self._context():
            self._in_frame = True  # moderngl's `with` does not nest: nothing inside enters it again
            try:
                return self._render_current(camera, width, height, progress)
            finally:
                self._in_frame = False

    def _render_current(
        self, camera: Camera, width: int, height: int, progress: ProgressCallback | None
    ) -> tuple[NDArray[np.float32], Mapping[str, float]]:
        opts = self.opts
        if self._region is not None and opts["path"] != "march":
            raise VolrenError("slicer: drawing a brick of a bricked volume needs the option path=march")
        if self._settings.preintegration and getattr(self._tf, "dims", 1) == 2:
            raise VolrenError(
                "slicer: pre-integration needs a 1D transfer function; switch it off for 2D TFs"
            )
        self._refuse_labels_channels()
        defines = self._defines(opts)
        counters: dict[str, float] = {}
        before = dict(self.uploads)
        if defines["SKIP"]:
            counters.update(self._brick_mask(opts, self._spacing(), self._min_cosine(camera, width, height)))
        world_to_clip = camera.projection_matrix(width / height) @ camera.view_matrix()
        if opts["path"] == "march":
            raw = self._march(defines, camera, opts, width, height, world_to_clip, counters)
        else:
            raw = self._slices(defines, camera, opts, width, height, world_to_clip, counters)
        if progress is not None:
            progress(1.0)
        for kind, count in self.uploads.items():
            counters[f"uploaded_{kind}"] = count - before[kind]
        error = self._ctx.error
        if error != "GL_NO_ERROR":
            raise VolrenError(f"slicer: OpenGL reported {error} while drawing the frame")
        if self._region is not None:  # a brick: `_march` has put its rectangle the right way up
            return raw, counters
        image = raw[::-1]  # GL rows start at the bottom
        if self._settings.blend_mode != BlendMode.COMPOSITE:
            image = self._project_to_rgba(image)
        return np.ascontiguousarray(image, dtype=np.float32), counters

    def _march(self, defines, camera, opts, width, height, world_to_clip, counters) -> NDArray[np.float32]:
        program = self._program("march", defines)
        self._bind(program, defines, camera, opts)
        program["u_clip_to_world"].write(mat4_bytes(np.linalg.inv(world_to_clip)))
        # A brick's layer stopping at its own opacity would leave out what the whole render keeps.
        early = opts["early_termination"] and self._region is None
        termination = opts["termination_alpha"] if early else 2.0
        self._set(program, "u_termination", float(termination))
        image = self._target("march", width, height)
        image.bind_to_image(0, read=False, write=True)
        # a brick draws only the pixels its box projects to (GL rows start at the bottom)
        x0, y0, x1, y1 = (self._region.pixel_rect(camera, width, height) if self._region is not None
                          else (0, 0, width, height))  # fmt: skip
        gl_y0, gl_y1 = height - y1, height - y0
        self._set(program, "u_pixel_offset", (x0, gl_y0))
        self._set(program, "u_pixel_end", (x1, gl_y1))
        if self._counter_buffer is None:
            self._counter_buffer = self._track(self._context().buffer(reserve=_COUNTER_BYTES))
        buffer = self._counter_buffer
        buffer.write(bytes(_COUNTER_BYTES))
        buffer.bind_to_storage_buffer(1)
        query = self._ctx.query(time=True)
        with query:
            if x1 > x0 and gl_y1 > gl_y0:
                program.run(math.ceil((x1 - x0) / _LOCAL_SIZE), math.ceil((gl_y1 - gl_y0) / _LOCAL_SIZE), 1)
            self._ctx.memory_barrier()
        lanes = np.frombuffer(buffer.read(), dtype=np.uint32).reshape(_STAT_LANES, 4).astype(np.int64)
        samples, brick_steps, terminated, hit = lanes.sum(axis=0)
        counters.update(
            samples=int(samples),
            brick_steps=int(brick_steps),
            rays_terminated=int(terminated),
            rays_hit=int(hit),
            passes=1,
            gpu_ms=query.elapsed / 1e6,
        )
        if (x0, gl_y0, x1, gl_y1) == (0, 0, width, height):
            return np.frombuffer(image.read(), dtype=np.float32).reshape(height, width, 4)
        # A brick's rectangle, flipped into a zero image with row 0 at the top (the one full-size
        # array a brick costs); `_render_current` does not flip it again.
        image_top_down = np.zeros((height, width, 4), dtype=np.float32)
        if x1 > x0 and gl_y1 > gl_y0:
            reader = self._target("march_reader", width, height)
            rect = reader.read(viewport=(x0, gl_y0, x1 - x0, gl_y1 - gl_y0), components=4, dtype="f4")
            pixels = np.frombuffer(rect, dtype=np.float32).reshape(gl_y1 - gl_y0, x1 - x0, 4)
            image_top_down[y0:y1, x0:x1] = pixels[::-1]
        return image_top_down

    def _slices(self, defines, camera, opts, width, height, world_to_clip, counters) -> NDArray[np.float32]:
        import moderngl

        ctx = self._context()
        volume = self._uniform_volume()
        program = self._program("slices", defines)
        self._bind(program, defines, camera, opts)
        program["u_world_to_clip"].write(mat4_bytes(world_to_clip))
        self._set(program, "u_eye", tuple(float(v) for v in camera.position))
        self._set(program, "u_perspective", not camera.parallel)
        box_min = np.array(volume.bounds[0::2])
        box_max = np.array(volume.bounds[1::2])
        spacing = self._spacing()
        view_dir = np.asarray(camera.direction, dtype=np.float64)
        clip_min, clip_max = box_min, box_max
        if defines["SKIP"]:
            clip_min, clip_max = self._visible_box(box_min, box_max)
        if clip_min is None:
            vertices = np.zeros((0, 3), dtype=np.float32)
            starts = np.zeros(1, dtype=np.int64)
        else:
            # Grow the box so that the planes before it own the entry segments (slice.frag.glsl).
            margin = 2.5 * spacing / self._min_cosine(camera, width, height)
            stack = slice_polygons(
                clip_min - margin, clip_max + margin, view_dir, spacing, anchor=box_min, back_to_front=False
            )
            vertices = triangle_fan(stack).positions
            starts = np.concatenate([[0], np.cumsum((stack.counts - 2) * 3)])
        fbo, term_fbo, colour, _ = self._target("slices", width, height)
        composite = self._settings.blend_mode == BlendMode.COMPOSITE
        fbo.use()
        fbo.depth_mask = True  # a masked depth buffer is not cleared either
        extreme = self._settings.blend_mode in (BlendMode.MAXIMUM, BlendMode.MINIMUM)
        fbo.clear(-3.0e38 if extreme else 0.0, 0.0, 0.0, 0.0, depth=1.0)
        fbo.depth_mask = False
        fbo.use()
        ctx.enable(moderngl.BLEND | moderngl.DEPTH_TEST)
        ctx.disable(moderngl.CULL_FACE)
        ctx.depth_func = "<"
        if composite:
            ctx.blend_equation = moderngl.FUNC_ADD
            ctx.blend_func = moderngl.ONE_MINUS_DST_ALPHA, moderngl.ONE
        elif self._settings.blend_mode == BlendMode.AVERAGE:
            ctx.blend_equation = moderngl.FUNC_ADD
            ctx.blend_func = moderngl.ONE, moderngl.ONE
        else:
            ctx.blend_equation = moderngl.MAX
        queries = []
        passes = 0
        n_slices = len(starts) - 1
        terminated = 0
        if n_slices:
            vbo = ctx.buffer(np.ascontiguousarray(vertices, dtype=np.float32).tobytes())
            vao = ctx.vertex_array(program, [(vbo, "3f", "in_position")])
            early = composite and opts["early_termination"]
            batch = opts["termination_interval"] if early else n_slices
            term = self._program("terminate", {}) if early else None
            if term is not None:
                colour.use(location=15)
                term["u_accumulated"].value = 15
                term["u_termination"].value = float(opts["termination_alpha"])
                term_vao = ctx.vertex_array(term, [])
            for first in range(0, n_slices, batch):
                last = min(first + batch, n_slices)
                fbo.use()
                query = ctx.query(samples=True)
                with query:
                    vao.render(
                        moderngl.TRIANGLES,
                        vertices=int(starts[last] - starts[first]),
                        first=int(starts[first]),
                    )
                queries.append(query)
                passes += 1
                if term is not None and last < n_slices:
                    ctx.disable(moderngl.BLEND)
                    term_fbo.depth_mask = True
                    term_fbo.use()
                    term_vao.render(moderngl.TRIANGLES, vertices=3)
                    ctx.enable(moderngl.BLEND)
                    terminated += 1
            if term is not None:
                term_vao.release()
            vao.release()
            vbo.release()
        fragments = sum(q.samples for q in queries)
        per_fragment = 2 if (defines["CLASSIFY"] == 1 or not composite) else 1
        counters.update(
            fragments=fragments,
            samples=fragments * per_fragment,
            passes=passes,
            slices=n_slices,
            termination_passes=terminated,
        )
        ctx.disable(moderngl.BLEND | moderngl.DEPTH_TEST)
        raw = np.frombuffer(fbo.read(components=4, dtype="f4"), dtype=np.float32).reshape(height, width, 4)
        return raw

    @staticmethod
    def _min_cosine(camera: Camera, width: int, height: int) -> float:
        """A lower bound of the cosine between any pixel ray and the view direction: that of the
        rays through the image's corners (the pixel rays lie between them)."""
        if camera.parallel:
            return 1.0
        inverse = np.linalg.inv(camera.projection_matrix(width / height) @ camera.view_matrix())
        ndc = np.array([[x, y, z, 1.0] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        points = ndc @ inverse.T
        points = (points[:, :3] / points[:, 3:]).reshape(4, 2, 3)
        rays = points[:, 1] - points[:, 0]
        rays /= np.linalg.norm(rays, axis=1, keepdims=True)
        return float(max((rays @ np.asarray(camera.direction)).min(), 1e-3))

    def _visible_box(self, box_min: NDArray, box_max: NDArray) -> tuple[Any, Any]:
        """The bounds of the bricks that are not empty (None, None when all are empty), so slices
        are cut only where something can show."""
        grid = self._bricks
        assert grid is not None
        assert self._mask_state is not None
        visible = self._mask_state[1]
        if not visible.any():
            return None, None
        lo, hi = grid.brick_bounds()
        lo = lo[visible].min(axis=0)
        hi = hi[visible].max(axis=0)
        lo = np.maximum(lo, box_min)
        hi = np.minimum(hi, box_max)
        if not np.all(hi > lo):
            return None, None
        return lo, hi

    def _project_to_rgba(self, raw: NDArray[np.float32]) -> NDArray[np.float32]:
        """Maximum / minimum / average images: the normalised value per pixel through the TF."""
        info = self._volume_info
        tf: Any = self._tf  # a 1D TF: labels and channels are drawn composite only
        assert info is not None and tf is not None
        mode = self._settings.blend_mode
        if mode == BlendMode.AVERAGE:
            found = raw[..., 1] > 0
            x = np.where(found, raw[..., 0] / np.where(found, raw[..., 1], 1.0), 0.0)
        else:
            found = raw[..., 1] > 0
            x = raw[..., 0].astype(np.float64)
            if mode == BlendMode.MINIMUM:
                x = -x
        rgb, alpha = tf.sample(np.where(found, info.to_data_value(x), np.nan))
        out = np.zeros(raw.shape, dtype=np.float32)
        out[..., :3] = rgb * alpha[..., None]
        out[..., 3] = alpha
        return out

    # ------------------------------------------------------------------------------ release
    def release(self) -> None:
        """Free every GL object and the context."""
        self._release_gl_objects(self._ctx)
        self._programs.clear()
        self._tables.clear()
        self._data.clear()
        self._targets.clear()
        self._volume_tex = self._gradient_tex = self._counter_buffer = None
        if self._ctx is not None:
            self._ctx.release()
            self._ctx = None
        super().release()
