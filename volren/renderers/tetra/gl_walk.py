"""The tetra walk as OpenGL compute shaders (moderngl), with the mesh in storage buffers.

Why a second implementation of `traversal`: a GPU runs one ray per invocation across thousands of
cores, and the walk (a few plane tests per cell, no large state) suits it. The same shaders run on
Mesa's llvmpipe, so CI tests them against the CPU walk on a machine without a GPU.

Per frame, three passes:
1. `clear.comp.glsl` empties the per-pixel entry lists;
2. the rasterizer draws the boundary faces turned towards the eye, each grown by ENTRY_MARGIN
   (`entry_faces.*.glsl`), and each fragment appends its face to its pixel's list (a fixed number
   of slots per pixel); cells the near
   plane cuts join the lists of their pixel boxes (`bin_near.comp.glsl`). When a list overflows, the
   slots grow and the faces are drawn again. (Binning in a compute shader, one invocation per
   face, took most of the frame: a large face is one invocation's long loop. The rasterizer
   spreads every face over the whole GPU; timings in docs/tetra-benchmark.md.)
3. `walk.comp.glsl` casts one ray per pixel and writes premultiplied RGBA (or the projected value).

The mesh goes to the GPU once per volume, the visibility flags and the 3D table once per TF
version (the renderer says when with keys); a frame sends only uniforms and reads the image back.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.kernels.shading import ShadeParams
from volren.kernels.tet_projection import projected_boxes
from volren.model.camera import Camera
from volren.renderers.glsl import compile_program, load_shader
from volren.renderers.opengl import GLObjectOwner, mat4_bytes, opengl_problem
from volren.renderers.tetra.walked_cells import WalkedCells

SHADER_DIR = Path(__file__).resolve().parent / "shaders"
#: Pixels per side of a walk work group.
LOCAL = 8
#: Invocations per work group of the clear and near-cell passes (as in their shaders).
CLEAR_GROUP, NEAR_GROUP = 256, 64
#: One vertex of a boundary face as the rasterizer reads it (entry_faces.vert.glsl).
FACE_VERTEX = np.dtype([("position", "<f4", 3), ("plane", "<f4", 4), ("candidate", "<u4")])
#: Work groups along x before a dispatch wraps into y (GL guarantees 65535).
MAX_GROUPS_X = 65535
#: Pixels by which each entry face grows before it is rasterized (entry_faces.geom.glsl): four
#: times the 1/256 pixel the rasterizer snaps to, so that every face a pixel centre lies on or
#: near is listed (the CPU walk lists faces within `entry_bins.MARGIN`, 0.01 pixel).
ENTRY_MARGIN = 1.0 / 64.0
#: Entry candidates a pixel's list holds at first (more when a frame needs them).
SLOTS = 4
#: Lanes of the walk's work counters (lists.glsl): 16 header bytes, then 16 bytes per lane.
STAT_LANES = 1024
COUNTER_BYTES = 16 + 16 * STAT_LANES
#: Cell ids share a 32-bit candidate with a 3-bit face code.
MAX_CELLS = 1 << 29
#: GL_RENDERER names of software rasterizers.
SOFTWARE = ("llvmpipe", "softpipe", "swrast", "lavapipe", "software")


@functools.cache
def gpu_renderer() -> str | None:
    """The GL_RENDERER of a hardware OpenGL 4.3 context here, or None (no GL, too old, or software)."""
    if opengl_problem() is not None:
        return None
    import moderngl

    try:
        ctx = moderngl.create_standalone_context(backend="egl", require=430)
    except Exception:  # noqa: BLE001 - no 4.3 context is an answer, not an error
        return None
    try:
        name = str(ctx.info["GL_RENDERER"])
    finally:
        ctx.release()
    return None if any(s in name.lower() for s in SOFTWARE) else name


@dataclass(frozen=True)
class GLMesh:
    """The mesh as the shaders read it (float32, coordinates relative to `centre`)."""

    centre: NDArray[np.float64]
    planes: NDArray[np.float32]  # (m * 4, 4) inward unit normal and offset per face
    neighbours: NDArray[np.int32]  # (m, 4): 4 * next cell + its face; -1 where the ray leaves the mesh
    fields: NDArray[
        np.float32
    ]  # (m * 2, 4): (gradient, value at corner 0), (corner 0, visible); see set_tables
    tolerance: float  # world units: 2e-6 of the mesh's size (float32 rounding)


def gl_mesh(
    points: NDArray,
    tets: NDArray,
    neighbours: NDArray,
    neighbour_faces: NDArray,
    packed: NDArray,
    tvals: NDArray,
    grads: NDArray,
    ok: NDArray,
) -> GLMesh:
    """`GLMesh` from the CPU walk's arrays (`TetraRenderer._prepare`)."""
    m = len(tets)
    if m >= MAX_CELLS:
        raise VolrenError(
            f"tetra: the GL walk takes at most {MAX_CELLS - 1} cells, this mesh has {m}; "
            "use the option backend=cpu"
        )
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre = (lo + hi) / 2.0
    # Shift the planes in float64, then round: -(D + N.c) rounds to exactly the neighbour's value.
    planes = packed.copy()
    planes[..., 3] += np.einsum("mfk,k->mf", packed[..., :3], centre)
    across_ok = np.where(neighbours >= 0, ok[np.maximum(neighbours, 0)], False)
    corner = points[tets[:, 0]] - centre
    fields = np.zeros((m, 2, 4))
    fields[:, 0, :3] = grads
    fields[:, 0, 3] = tvals[:, 0]
    fields[:, 1, :3] = corner
    size = float(np.linalg.norm(hi - lo))
    return GLMesh(
        centre=centre,
        planes=np.ascontiguousarray(planes, dtype=np.float32).reshape(-1, 4),
        neighbours=np.ascontiguousarray(
            np.where(across_ok, 4 * neighbours + neighbour_faces, -1), dtype=np.int32
        ),
        fields=np.ascontiguousarray(fields.reshape(-1, 4), dtype=np.float32),
        tolerance=2e-6 * max(size, 1e-30),
    )


def entry_face_vertices(mesh: GLMesh, points: NDArray, walked: WalkedCells) -> NDArray:
    """(3 f,) FACE_VERTEX: the boundary faces of the walked cells as triangles for the rasterizer,
    each vertex with its face's plane (as the walk reads it) and its candidate (cell * 8 + face)."""
    cell, face = walked.face_cells, walked.face_index
    vertices = np.empty((len(cell), 3), FACE_VERTEX)
    vertices["position"] = points[walked.triangles] - mesh.centre
    vertices["plane"] = mesh.planes.reshape(-1, 4, 4)[cell, face][:, None, :]
    vertices["candidate"] = (cell * 8 + face)[:, None]
    return vertices.ravel()


#: Rows of the clip region the walk takes (clip_planes.glsl's MAX_CLIP): six planes and a box's faces.
MAX_CLIP_ROWS = 12


@dataclass(frozen=True)
class WalkParameters:
    """What a frame needs besides the camera (see `walk.comp.glsl`'s uniforms)."""

    blend: int  # traversal.COMPOSITE ... AVERAGE
    shade: ShadeParams  # volren.kernels.shading.shade_params
    lo: float  # table index = (value - lo) * scale
    scale: float
    lmax: float
    termination: float
    max_steps: int
    jump: bool = False  # walk only the visible cells (`walked_cells`): leave at a transparent one
    #: (m, 4) world half-spaces of the clip region (`RenderSettings.clip`), m <= MAX_CLIP_ROWS
    clip: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 4)))


class GLWalk(GLObjectOwner):
    """The GL objects of the walk; `render` draws one frame."""

    def __init__(self) -> None:
        self._ctx: Any = None
        self._objects: list[Any] = []
        self._programs: dict[tuple, Any] = {}
        self._mesh: GLMesh | None = None
        self._mesh_buffers: dict[str, Any] = {}
        self._faces: tuple[Any, Any, int] | None = None  # (buffer, vertex array, vertices) of the entry faces
        self._keys: dict[str, Any] = {}
        self._table: Any = None
        self._frame: dict[str, Any] = {}
        self._slots = SLOTS

    # ------------------------------------------------------------------------ GL objects
    def context(self) -> Any:
        if self._ctx is None:
            problem = opengl_problem()
            if problem:
                raise VolrenError(problem)
            import moderngl

            try:
                self._ctx = moderngl.create_standalone_context(backend="egl", require=430)
            except Exception as exc:  # noqa: BLE001 - moderngl raises plain Exceptions
                raise VolrenError(
                    f"tetra: the GL walk needs OpenGL 4.3 compute shaders ({exc}); use the option backend=cpu"
                ) from None
        return self._ctx

    @property
    def mesh_key(self) -> Any:
        """The key the mesh in the buffers was uploaded with (None: none)."""
        return self._keys.get("mesh")

    @property
    def renderer_name(self) -> str:
        with self.context() as ctx:
            return str(ctx.info["GL_RENDERER"])

    def _buffer(self, data: NDArray) -> Any:
        # GL refuses empty buffers; a 16-byte one stands in for an empty array
        raw = data.tobytes() if data.nbytes else bytes(16)
        return self._track(self._ctx.buffer(raw))

    def _program(self, name: str, defines: dict[str, int] | None = None) -> Any:
        """The compute shader `name`.comp.glsl, or for "entry_faces" the face-drawing program."""
        key = (name, tuple(sorted((defines or {}).items())))
        if key not in self._programs:
            if name == "entry_faces":
                program = compile_program(
                    self.context(),
                    vertex=load_shader("entry_faces.vert.glsl", {}, [SHADER_DIR]),
                    geometry=load_shader("entry_faces.geom.glsl", {}, [SHADER_DIR]),
                    fragment=load_shader("entry_faces.frag.glsl", {}, [SHADER_DIR]),
                )
            else:
                source = load_shader(f"{name}.comp.glsl", defines or {}, [SHADER_DIR])
                program = compile_program(self.context(), compute=source)
            self._programs[key] = self._track(program)
        return self._programs[key]

    # --------------------------------------------------------------------------- uploads
    def set_mesh(self, key: Any, mesh: GLMesh) -> None:
        """Upload the mesh unless `key` says it is the one already there."""
        if self._keys.get("mesh") == key:
            return
        with self.context():  # another renderer's context may be current on this thread
            for buffer in self._mesh_buffers.values():
                self._drop(buffer)
            self._mesh = mesh
            self._mesh_buffers = {
                name: self._buffer(getattr(mesh, name)) for name in ("planes", "neighbours", "fields")
            }
        self._keys["mesh"] = key
        self._keys.pop("faces", None)
        self._keys.pop("tables", None)

    def set_entry_faces(self, key: Any, walked: WalkedCells, points: NDArray) -> None:
        """Upload the faces where rays enter the walked cells unless `key` says they are there.
        Call after `set_mesh`."""
        if self._keys.get("faces") == key:
            return
        assert self._mesh is not None
        vertices = entry_face_vertices(self._mesh, points, walked)
        with self.context() as ctx:
            if self._faces is not None:
                for obj in self._faces[:2]:
                    self._drop(obj)
            buffer = self._buffer(vertices)
            array = self._track(
                ctx.vertex_array(
                    self._program("entry_faces"),
                    [(buffer, "3f 4f 1u", "in_position", "in_plane", "in_candidate")],
                )
            )
            self._faces = (buffer, array, len(vertices))
        self._keys["faces"] = key

    def set_tables(self, key: Any, depth: NDArray, ratio: NDArray, visible: NDArray) -> None:
        """Upload the 3D table and the visibility flags (into the fields) unless `key` says they are there.
        Call after `set_mesh`.

        depth: (n, n) optical depth per length; ratio: (K, n, n, 3) colour per unit opacity."""
        if self._keys.get("tables") == key:
            return
        ctx = self.context()
        layers, n = ratio.shape[0], ratio.shape[1]
        with ctx:
            limit = int(ctx.info["GL_MAX_3D_TEXTURE_SIZE"])
        if max(n, layers) > limit:
            raise VolrenError(f"tetra: table_size {n} exceeds this driver's 3D texture limit {limit}")
        table = np.empty((layers, n, n, 4), dtype=np.float32)
        table[..., :3] = ratio
        table[..., 3] = depth[None]
        import moderngl

        with ctx:
            self._drop(self._table)
            self._table = self._track(ctx.texture3d((n, n, layers), 4, table.tobytes(), dtype="f4"))
            self._table.filter = (moderngl.NEAREST, moderngl.NEAREST)
            fields = self._mesh.fields.copy()
            fields[1::2, 3] = visible
            self._mesh_buffers["fields"].write(fields.tobytes())
        self._keys["tables"] = key

    # ---------------------------------------------------------------------------- frame
    def _frame_buffer(self, name: str, nbytes: int) -> Any:
        held = self._frame.get(name)
        if held is None or held.size < nbytes:
            self._drop(held)
            held = self._frame[name] = self._track(self._ctx.buffer(reserve=max(nbytes, 16)))
        return held

    def render(
        self, camera: Camera, width: int, height: int, params: WalkParameters, near_cells: tuple | None
    ) -> tuple[NDArray[np.float32], dict[str, float]]:
        """(H * W, 4) float32 per pixel, row 0 at the top, and the frame's counters.

        near_cells: (cells, boxes (k, 4) x0, x1, y0, y1) the near plane cuts, or None."""
        ctx = self.context()
        mesh = self._mesh
        assert mesh is not None and self._table is not None
        with ctx:
            bin_query, walk_query = ctx.query(time=True), ctx.query(time=True)
            counters = self._frame_buffer("counters", COUNTER_BYTES)
            counters.write(bytes(COUNTER_BYTES))
            counters.bind_to_storage_buffer(6)
            pixels = width * height
            self._frame_buffer("counts", 4 * pixels).bind_to_storage_buffer(4)
            world_to_clip = (
                camera.projection_matrix(width / height) @ camera.view_matrix() @ _translation(mesh.centre)
            )
            while True:
                self._frame_buffer("slots", 4 * self._slots * pixels).bind_to_storage_buffer(5)
                with bin_query:
                    self._clear(pixels)
                    ctx.memory_barrier()
                    self._bin(camera, width, height, world_to_clip, near_cells)
                    ctx.memory_barrier()
                most = int(np.frombuffer(counters.read(size=4), np.uint32)[0])
                if most <= self._slots:
                    break
                self._slots = most
                counters.write(bytes(COUNTER_BYTES))
            result = self._frame_buffer("result", 16 * pixels)
            result.bind_to_storage_buffer(11)
            with walk_query:
                self._walk(camera, width, height, world_to_clip, params)
                ctx.memory_barrier()
            image = np.empty((pixels, 4), np.float32)
            result.read_into(image, size=16 * pixels)
            stats = np.frombuffer(counters.read(size=COUNTER_BYTES), np.uint32)[4:].reshape(-1, 4).sum(axis=0)
            bin_ms, walk_ms = bin_query.elapsed / 1e6, walk_query.elapsed / 1e6
            error = ctx.error
            if error != "GL_NO_ERROR":
                raise VolrenError(f"tetra: OpenGL reported {error} while walking the mesh")
        return image, {
            "entry_slots": float(self._slots),
            "cell_steps": float(stats[0]),
            "cells_integrated": float(stats[1]),
            "walks_cut": float(stats[2]),
            "rays_hit": float(stats[3]),
            "gpu_bin_ms": bin_ms,
            "gpu_walk_ms": walk_ms,
            "gpu_ms": bin_ms + walk_ms,
        }

    def _clear(self, pixels: int) -> None:
        program = self._program("clear")
        program["u_count"].value = pixels
        _dispatch(program, math.ceil(pixels / CLEAR_GROUP))

    def _bin(
        self, camera: Camera, width: int, height: int, world_to_clip: NDArray, near_cells: tuple | None
    ) -> None:
        """Fill the entry lists: the facing boundary faces through the rasterizer, then the near cells."""
        import moderngl

        mesh = self._mesh
        assert mesh is not None
        ctx = self._ctx
        program = self._program("entry_faces")
        _set(program, "u_world_to_clip", mat4_bytes(world_to_clip))
        _set(program, "u_parallel", bool(camera.parallel))
        _set(program, "u_eye", tuple(float(v) for v in np.asarray(camera.position) - mesh.centre))
        _set(program, "u_view_dir", tuple(float(v) for v in camera.direction))
        _set(program, "u_tolerance", mesh.tolerance)
        _set(program, "u_size", (width, height))
        _set(program, "u_slots", self._slots)
        _set(program, "u_margin", ENTRY_MARGIN)
        target = self._frame.get("target")
        if target is None or target.size != (width, height):
            # the new one first, bound, then the old one freed: moderngl rebinds the framebuffer that
            # was bound when it makes one, and binding a freed one is GL_INVALID_OPERATION
            old = (self._frame.get("target"), self._frame.get("target_colour"))
            colour = self._frame["target_colour"] = self._track(
                ctx.renderbuffer((width, height), 1, dtype="f1")
            )
            target = self._frame["target"] = self._track(ctx.framebuffer(color_attachments=[colour]))
            target.color_mask = (False, False, False, False)
            target.use()
            for obj in old:
                self._drop(obj)
        target.use()
        ctx.disable(moderngl.BLEND | moderngl.DEPTH_TEST | moderngl.CULL_FACE)
        assert self._faces is not None
        if self._faces[2]:
            self._faces[1].render(moderngl.TRIANGLES)
        if near_cells is not None:
            cells, boxes = near_cells
            near = self._program("bin_near")
            self._frame_buffer("near_boxes", boxes.nbytes).bind_to_storage_buffer(9)
            self._frame_buffer("near_cells", cells.nbytes).bind_to_storage_buffer(10)
            self._frame["near_boxes"].write(np.ascontiguousarray(boxes, np.int32).tobytes())
            self._frame["near_cells"].write(np.ascontiguousarray(cells, np.uint32).tobytes())
            _set(near, "u_size", (width, height))
            _set(near, "u_near_count", len(cells))
            _set(near, "u_slots", self._slots)
            _dispatch(near, math.ceil(len(cells) / NEAR_GROUP))

    def _walk(
        self, camera: Camera, width: int, height: int, world_to_clip: NDArray, p: WalkParameters
    ) -> None:
        mesh = self._mesh
        assert mesh is not None
        program = self._program(
            "walk", {"BLEND": p.blend, "SHADE": int(bool(p.shade.on)), "JUMP": int(p.jump)}
        )
        buffers = self._mesh_buffers
        for name, binding in (("planes", 0), ("neighbours", 1), ("fields", 2)):
            buffers[name].bind_to_storage_buffer(binding)
        self._table.use(location=0)
        _set(program, "u_table", 0)
        _set(program, "u_clip_to_world", mat4_bytes(np.linalg.inv(world_to_clip)))
        _set(program, "u_size", (width, height))
        _set(program, "u_slots", self._slots)
        _set(program, "u_lo", p.lo)
        _set(program, "u_scale", p.scale)
        _set(program, "u_lmax", p.lmax)
        _set(program, "u_tolerance", mesh.tolerance)
        _set(program, "u_termination", p.termination if p.termination < 1.0 else 2.0)
        _set(program, "u_max_steps", p.max_steps)
        # the shader's world is the mesh's, moved by -centre (float precision far from the origin)
        clip = np.zeros((MAX_CLIP_ROWS, 4), np.float32)
        clip[: len(p.clip), :3] = p.clip[:, :3]
        clip[: len(p.clip), 3] = p.clip[:, 3] + p.clip[:, :3] @ np.asarray(mesh.centre, dtype=np.float64)
        _set(program, "u_clip", clip.tobytes())
        _set(program, "u_clip_count", len(p.clip))
        light = p.shade
        _set(
            program,
            "u_phong",
            (float(light.ambient), float(light.diffuse), float(light.specular), float(light.power)),
        )
        _set(program, "u_gradient_threshold", float(light.gradient_threshold))
        _set(program, "u_light", (float(light.lx), float(light.ly), float(light.lz)))
        program.run(math.ceil(width / LOCAL), math.ceil(height / LOCAL), 1)

    def release(self) -> None:
        self._release_gl_objects(self._ctx)
        if self._ctx is not None:
            self._ctx.release()
        self._ctx = None
        self._programs.clear()
        self._mesh_buffers.clear()
        self._faces = None
        self._frame.clear()
        self._keys.clear()
        self._table = self._mesh = None
        self._slots = SLOTS


def near_plane_cells(
    camera: Camera, width: int, height: int, points: NDArray, tets: NDArray, ok: NDArray, bounds: NDArray
) -> tuple | None:
    """(cells, pixel boxes) of the usable cells the near plane cuts, or None when it cuts none.
    The common case (the eye outside the mesh's box) costs eight dot products."""
    view = camera.view_matrix()
    near = camera.clipping_range[0]
    corners = np.array([[x, y, z, 1.0] for x in bounds[0:2] for y in bounds[2:4] for z in bounds[4:6]])
    depth = -(corners @ view[2])
    if depth.min() > near or depth.max() < near:
        return None
    pts = np.concatenate([points, np.ones((len(points), 1))], axis=1)
    d = -(pts @ view[2])
    cut = ok & (d[tets].min(axis=1) <= near) & (d[tets].max(axis=1) >= near)
    boxes = projected_boxes(camera, width, height, points, tets, cut)
    cells = np.nonzero(boxes[:, 0] >= 0)[0]
    if not len(cells):
        return None
    return cells.astype(np.uint32), boxes[cells].astype(np.int32)


def _dispatch(program: Any, groups: int) -> None:
    if groups <= 0:
        return
    x = min(groups, MAX_GROUPS_X)
    program.run(x, math.ceil(groups / x), 1)


def _set(program: Any, name: str, value: Any) -> None:
    """Set a uniform the compiler kept (unused ones are optimised away)."""
    if name in program:
        if isinstance(value, bytes):
            program[name].write(value)
        else:
            program[name].value = value


def _translation(offset: NDArray) -> NDArray[np.float64]:
    """The 4x4 matrix that adds `offset` to a point."""
    m = np.eye(4)
    m[:3, 3] = offset
    return m
