"""The `tetra` renderer: exact oracles, the reference renderer, tessellation independence,
rays through vertices and edges, holes and non-convex meshes."""

from __future__ import annotations

import numpy as np
import pytest

from tests.renderers.analytic import box_path_lengths, homogeneous_image, rmse
from volren.api import prepared_renderer
from volren.errors import VolrenError, VolrenWarning
from volren.model.camera import Camera
from volren.model.settings import RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import TetVolume, UniformVolume

SIZE = 48
#: Corners of a unit cube as bits x + 2 y + 4 z.
_KUHN = [(0, 1, 3, 7), (0, 1, 5, 7), (0, 2, 3, 7), (0, 2, 6, 7), (0, 4, 5, 7), (0, 4, 6, 7)]
_FIVE_EVEN = [(0, 1, 2, 4), (3, 1, 2, 7), (5, 1, 4, 7), (6, 2, 4, 7), (1, 2, 4, 7)]
_FIVE_ODD = [(1, 0, 3, 5), (2, 0, 3, 6), (4, 0, 5, 6), (7, 3, 5, 6), (0, 3, 5, 6)]


def cube_grid(
    n: int, scheme: str, field=lambda x, y, z: x + 2 * y + 3 * z
) -> tuple[TetVolume, UniformVolume]:
    """n^3 unit cubes split into tetrahedra (Kuhn's 6 or alternating 5), and the same field on
    the uniform grid of their corners."""
    k, j, i = np.mgrid[0 : n + 1, 0 : n + 1, 0 : n + 1]
    points = np.stack([i.ravel(), j.ravel(), k.ravel()], axis=1).astype(np.float64)
    index = lambda x, y, z: (z * (n + 1) + y) * (n + 1) + x  # noqa: E731
    tets = []
    for z in range(n):
        for y in range(n):
            for x in range(n):
                corner = [index(x + (c & 1), y + ((c >> 1) & 1), z + ((c >> 2) & 1)) for c in range(8)]
                pattern = _KUHN if scheme == "kuhn" else (_FIVE_EVEN if (x + y + z) % 2 == 0 else _FIVE_ODD)
                tets += [[corner[c] for c in tet] for tet in pattern]
    values = field(points[:, 0], points[:, 1], points[:, 2])
    mesh = TetVolume(points, np.array(tets), values)
    grid = UniformVolume(values.reshape(n + 1, n + 1, n + 1).astype(np.float64))
    return mesh, grid


def render(name, volume, tf, camera, size=SIZE, **settings):
    with prepared_renderer(name, volume, tf, RenderSettings(**settings)) as renderer:
        image = renderer.render(camera, size, size)
        return image, dict(renderer.last_frame.counters)


def ramp(lo: float, hi: float, unit: float = 2.0) -> TransferFunction1D:
    return TransferFunction1D(
        color=[[lo, 0.1, 0.4, 1.0], [hi, 1.0, 0.7, 0.2]],
        opacity=[[lo, 0.0], [0.5 * (lo + hi), 0.6], [hi, 0.1]],
        opacity_unit_distance=unit,
    )


@pytest.fixture(scope="module")
def grids():
    kuhn, grid = cube_grid(4, "kuhn")
    five, _ = cube_grid(4, "five")
    tf = ramp(*grid.value_range)
    camera = Camera.orbit(grid.bounds, 30, 20, 1.0)
    reference, _ = render("reference", grid, tf, camera)
    return kuhn, five, grid, tf, camera, reference


def test_tessellation_independence(grids):
    """A linear field gives the same image on two tetrahedralizations of the same box, and it
    matches the reference on the uniform grid of the same (trilinear = linear) field."""
    kuhn, five, grid, tf, camera, reference = grids
    images = {name: render("tetra", mesh, tf, camera)[0] for name, mesh in (("kuhn", kuhn), ("five", five))}
    assert reference[..., 3].max() > 0.5
    assert rmse(images["kuhn"], images["five"]) < 2e-4
    for image in images.values():
        assert rmse(image, reference) < 5e-4
        assert np.abs(image - reference).max() < 0.01


def test_walks_cross_the_references_segments(grids):
    """The length-weighted average of the value along each ray is exact in both renderers (linear
    in each cell), so it tells whether the walk crosses exactly the reference's segments: a missed,
    doubled or misplaced segment changes it."""
    kuhn, five, _, tf, camera, _ = grids
    reference, _ = render("reference", kuhn, tf, camera, blend_mode="average")
    assert np.count_nonzero(reference[..., 3] > 0.05) > 500
    for mesh in (kuhn, five):
        image, counters = render("tetra", mesh, tf, camera, blend_mode="average", options={"backend": "cpu"})
        assert np.abs(image - reference).max() < 2e-6
        assert counters["walks_cut"] == 0


@pytest.mark.parametrize("scheme", ["kuhn", "five"])
def test_rays_through_vertices_and_edges(scheme):
    """A parallel view down z with a pixel centre on every vertex column (and edge midpoints in
    between): every ray runs along edges or through vertices of the mesh. Homogeneous medium:
    alpha = 1 - (1 - a)^(L / d) with L the box's depth."""
    n = 3
    mesh, _ = cube_grid(n, scheme, field=lambda x, y, z: 0 * x + 5.0)
    tf = TransferFunction1D(color=[[0, 0.2, 0.9, 0.5]], opacity=[[0, 0.3]], opacity_unit_distance=1.5)
    pixels = 2 * n + 1  # centres at the vertices and the midpoints between them
    camera = Camera(
        position=(1.5, 1.5, 10.0),
        focal_point=(1.5, 1.5, 1.5),
        parallel=True,
        parallel_scale=n * pixels / (pixels - 1) / 2.0,
        clipping_range=(1.0, 20.0),
    )
    origins, _ = camera.pixel_rays(pixels, pixels)
    assert np.allclose(origins[..., 0] * 2, np.round(origins[..., 0] * 2))  # on vertices and edges
    image, counters = render("tetra", mesh, tf, camera, pixels, options={"backend": "cpu"})
    lengths = box_path_lengths(camera, pixels, pixels, mesh.bounds)
    expected = homogeneous_image(lengths, (0.2, 0.9, 0.5), 0.3, 1.5)
    assert np.isfinite(image).all() and counters["walks_cut"] == 0
    # Rays lying in the box's side faces touch the mesh without entering it; the others run
    # through interior vertices and along interior edges.
    inner = np.s_[1:-1, 1:-1]
    assert np.abs(image[inner] - expected[inner]).max() < 1e-4


def test_holes_from_nonfinite_and_flat_cells():
    """Cells with a NaN value are holes: rays leave the mesh there and re-enter beyond."""
    mesh, _ = cube_grid(3, "kuhn", field=lambda x, y, z: 0 * x + 2.0)
    values = mesh.values.copy()
    centre = np.argmin(
        np.linalg.norm(mesh.points - 1.5, axis=1) + 10 * (np.abs(mesh.points - 1) > 0.5).any(axis=1)
    )
    values[centre] = np.nan  # an interior vertex: its cells become a hole
    holed = TetVolume(mesh.points, mesh.tets, values)
    tf = TransferFunction1D(color=[[0, 1, 1, 1]], opacity=[[0, 0.2], [4, 0.2]])
    camera = Camera.orbit(mesh.bounds, 10, 10, 1.0)
    full, _ = render("tetra", mesh, tf, camera)
    with_hole, counters = render("tetra", holed, tf, camera)
    reference, _ = render("reference", holed, tf, camera)
    assert np.isfinite(with_hole).all()
    assert (with_hole[..., 3] <= full[..., 3] + 1e-6).all() and with_hole[..., 3].min() >= 0
    assert (full[..., 3] - with_hole[..., 3]).max() > 0.02
    assert rmse(with_hole, reference) < 5e-4


def test_early_termination_and_transparent_cells(grids):
    kuhn, _, _, tf, camera, _ = grids
    opaque = TransferFunction1D(color=[[0, 1, 1, 1]], opacity=[[0, 0.0], [10, 0.0], [11, 1.0], [24, 1.0]])
    images, counters = {}, {}
    for alpha in (1.0, 0.99):
        images[alpha], counters[alpha] = render(
            "tetra", kuhn, opaque, camera, options={"termination_alpha": alpha}
        )
    assert images[1.0][..., 3].max() > 0.99
    assert np.abs(images[1.0] - images[0.99]).max() <= 0.01 + 1e-6
    assert counters[0.99]["cells_integrated"] < counters[1.0]["cells_integrated"]
    assert counters[1.0]["cells_transparent"] > 0
    # without the skip every cell walked through is integrated; the transparent ones add (almost)
    # nothing: only the table's interpolation next to the opacity ramp
    every, every_counters = render(
        "tetra", kuhn, opaque, camera, options={"termination_alpha": 1.0, "skip_transparent": False}
    )
    assert (
        every_counters["cells_integrated"] == every_counters["cell_steps"] > counters[1.0]["cells_integrated"]
    )
    assert every_counters["cells_transparent"] == 0
    assert np.abs(every - images[1.0]).max() < 0.01


def shells() -> tuple[TetVolume, TransferFunction1D]:
    """A radial field on 6^3 cubes (whole numbers at the vertices) and a TF that shows two shells
    of it: opacity only strictly between 2.4 and 3.6 and between 12.4 and 15.6. A cell's value
    range has whole-number ends, so a transparent cell's values stay 0.4 (almost 4 table bins) away
    from any opacity, and the table gives it exactly nothing: skipping it changes no pixel."""
    mesh, _ = cube_grid(6, "kuhn", field=lambda x, y, z: (x - 3.0) ** 2 + (y - 3.0) ** 2 + (z - 3.0) ** 2)
    tf = TransferFunction1D(
        color=[[0, 0.9, 0.5, 0.1], [27, 0.2, 0.6, 1.0]],
        opacity=[[0, 0], [2.4, 0], [3, 0.5], [3.6, 0], [12.4, 0], [14, 0.8], [15.6, 0]],
        opacity_unit_distance=2.0,
    )
    return mesh, tf


def shell_cameras(mesh: TetVolume) -> dict[str, tuple[Camera, int]]:
    """A perspective view, and a parallel view down z with a pixel centre on every vertex column
    and edge midpoint: rays run along the edges where visible and transparent cells meet."""
    pixels = 2 * 6 + 1
    along_edges = Camera(
        position=(3.0, 3.0, 20.0),
        focal_point=(3.0, 3.0, 3.0),
        parallel=True,
        parallel_scale=6 * pixels / (pixels - 1) / 2.0,
        clipping_range=(1.0, 40.0),
    )
    return {
        "perspective": (Camera.orbit(mesh.bounds, 30, 20, 1.0), SIZE),
        "along_edges": (along_edges, pixels),
    }


@pytest.mark.parametrize("view", ["perspective", "along_edges"])
def test_rays_jump_over_transparent_cells(view):
    """With skip_transparent, a ray walks only the visible cells: it leaves them at a transparent
    cell and re-enters at the next visible one. That must give the image of the walk through every
    cell (no leaks where rays cross the shells at edges and vertices) with far fewer cell steps,
    and match the reference."""
    mesh, tf = shells()
    camera, size = shell_cameras(mesh)[view]
    jumped, jumped_counters = render("tetra", mesh, tf, camera, size, options={"backend": "cpu"})
    walked, walked_counters = render(
        "tetra", mesh, tf, camera, size, options={"backend": "cpu", "skip_transparent": False}
    )
    reference, _ = render("reference", mesh, tf, camera, size)
    assert reference[..., 3].max() > 0.3
    assert np.abs(jumped - walked).max() < 1e-6  # measured: 0 (bit-identical)
    assert jumped_counters["cell_steps"] < 0.9 * walked_counters["cell_steps"]
    assert jumped_counters["walks_cut"] == 0 and jumped_counters["entries_dropped"] == 0
    assert rmse(jumped, reference) < 2e-3


def test_tf_edits_keep_the_walk_set_while_the_visible_cells_stay():
    """A held renderer keeps the set of cells rays walk through while a TF edit leaves the same
    cells visible (a peak's height), and rebuilds it when they change (a shell's support widened):
    each frame equals a new renderer's of the edited TF, so a stale set never hides cells."""
    mesh, tf = shells()
    camera, size = shell_cameras(mesh)["perspective"]
    edits = {
        "lower peak": [[0, 0], [2.4, 0], [3, 0.3], [3.6, 0], [12.4, 0], [14, 0.8], [15.6, 0]],
        "wider shell": [[0, 0], [1.2, 0], [3, 0.3], [3.6, 0], [12.4, 0], [14, 0.8], [15.6, 0]],
    }
    options = {"backend": "cpu"}
    with prepared_renderer("tetra", mesh, tf, RenderSettings(options=options)) as held:
        held.render(camera, size, size)
        sets = [held._visible_walk[1]]
        for opacity in edits.values():
            tf.set_opacity_points(np.array(opacity, dtype=np.float64))
            held.set_transfer_function(tf)
            image = held.render(camera, size, size)
            sets.append(held._visible_walk[1])
            fresh, _ = render("tetra", mesh, tf, camera, size, options=options)
            assert np.array_equal(image, fresh)
    assert sets[1] is sets[0]  # the peak's height: same cells
    assert sets[2] is not sets[1] and sets[2].cells.sum() > sets[1].cells.sum()


def refined(volume, tf, camera, size, stride, tolerance, **settings):
    return render(
        "tetra",
        volume,
        tf,
        camera,
        size,
        options={"backend": "cpu", "image_stride": stride, "refine_tolerance": tolerance},
        **settings,
    )


@pytest.mark.parametrize("mode", ["composite", "maximum", "average"])
def test_adaptive_refinement_stays_close_with_fewer_rays(grids, mode):
    """image_stride > 1 casts every 8th pixel's ray, then more only where neighbouring rays differ
    by more than refine_tolerance; the rest is interpolated. On the linear field's cube: measured
    24-37 % of the rays and RMSE 0.0017-0.0033 against a ray per pixel at tolerance 0.05. At
    tolerance 0 only blocks with four equal corners (the background) are interpolated, and the
    image is that of a ray per pixel to rounding (the rays come from `Camera.rays`)."""
    kuhn, _, _, tf, camera, _ = grids
    size = 96
    full, full_counters = render("tetra", kuhn, tf, camera, size, blend_mode=mode, options={"backend": "cpu"})
    image, counters = refined(kuhn, tf, camera, size, 8, 0.05, blend_mode=mode)
    assert full_counters["rays_cast"] == size * size
    assert counters["rays_cast"] < 0.45 * size * size
    assert counters["cell_steps"] < 0.5 * full_counters["cell_steps"]
    assert counters["walks_cut"] == 0 and counters["entries_dropped"] == 0
    assert rmse(image, full) < 5e-3 and np.abs(image - full).max() < 0.08
    exact, exact_counters = refined(kuhn, tf, camera, size, 8, 0.0, blend_mode=mode)
    assert exact_counters["rays_cast"] < size * size
    assert np.abs(exact - full).max() < 1e-5


def test_adaptive_refinement_with_the_eye_inside_the_mesh(grids):
    """Rays that start in the cells the near plane cuts, and boundary faces behind the eye (listed
    in every pixel), reach the refined pixels' entry lists as they reach the full image's."""
    kuhn, _, _, tf, _, _ = grids
    camera = Camera(
        position=(2.1, 1.9, 1.2), focal_point=(2.0, 2.0, 4.0), view_angle=60.0, clipping_range=(0.05, 20.0)
    )
    full, _ = render("tetra", kuhn, tf, camera, 64, options={"backend": "cpu"})
    image, counters = refined(kuhn, tf, camera, 64, 8, 0.0)
    assert full[..., 3].min() > 0.05  # every ray starts in the mesh
    assert counters["entries_dropped"] == 0
    assert np.abs(image - full).max() < 1e-5
    coarse, coarse_counters = refined(kuhn, tf, camera, 64, 8, 0.05)
    assert coarse_counters["rays_cast"] < 0.1 * 64 * 64  # measured 2 %: a smooth view from inside
    assert rmse(coarse, full) < 3e-3  # measured 0.00058


def test_adaptive_refinement_follows_sharp_edges():
    """The shells have sharp silhouettes and inner edges: blocks across them are split down to
    single pixels (measured RMSE 0.0005 and largest difference 0.019 against a ray per pixel)."""
    mesh, tf = shells()
    camera = Camera.orbit(mesh.bounds, 30, 20, 1.0)
    full, _ = render("tetra", mesh, tf, camera, 96, options={"backend": "cpu"})
    image, counters = refined(mesh, tf, camera, 96, 8, 0.02)
    assert counters["rays_cast"] < 0.5 * 96 * 96
    assert rmse(image, full) < 1.5e-3 and np.abs(image - full).max() < 0.04


@pytest.mark.parametrize("mode", ["maximum", "minimum", "average"])
def test_projections_match_the_reference(grids, mode):
    kuhn, _, _, tf, camera, _ = grids
    reference, _ = render("reference", kuhn, tf, camera, blend_mode=mode)
    image, _ = render("tetra", kuhn, tf, camera, blend_mode=mode)
    assert np.abs(image - reference).max() < 1e-4


def test_bad_options(grids):
    kuhn, _, _, tf, camera, _ = grids
    for options, message in (
        ({"integration": "fast"}, "integration"),
        ({"table_size": 1}, "table_size"),
        ({"termination_alpha": 0}, "termination_alpha"),
        ({"skip_transparent": "no"}, "skip_transparent"),
        ({"image_stride": 3}, "image_stride"),
        ({"image_stride": 0}, "image_stride"),
        ({"refine_tolerance": -0.1}, "refine_tolerance"),
        ({"refine_tolerance": "low"}, "refine_tolerance"),
        ({"backend": "gl", "image_stride": 4}, "cpu backend only"),
    ):
        with pytest.raises(VolrenError, match=message):
            render("tetra", kuhn, tf, camera, 8, options=options)


# ----------------------------------------------------------------------------- real data
@pytest.fixture(scope="module")
def spx(shared_data):
    from tests.conftest import load_scene_tf
    from volren.io import load_volume

    volume = load_volume(shared_data / "tets" / "spx.vtk", scalars="scalars")
    return volume, load_scene_tf("spx-spiky"), Camera.orbit(volume.bounds, 30, 20, 1.0)


@pytest.mark.vtk
def test_spx_against_reference_and_vtk(spx):
    """spx is non-convex: rays leave and re-enter. No holes or streaks: the average along each ray
    (exact in both renderers) matches the reference's, so the walks cross the same segments; the
    composite differs by table accuracy (the 256-entry value axis blurs the spikes by a fraction of
    an entry; measured RMSE 0.0020)."""
    volume, tf, camera = spx
    size = 64
    reference, _ = render("reference", volume, tf, camera, size)
    image, counters = render("tetra", volume, tf, camera, size)
    average, _ = render("tetra", volume, tf, camera, size, blend_mode="average", options={"backend": "cpu"})
    reference_average, _ = render("reference", volume, tf, camera, size, blend_mode="average")
    assert counters["walks_cut"] == 0 and counters["entries_dropped"] == 0
    assert np.abs(average - reference_average).max() < 2e-6
    assert np.array_equal(average[..., 3] > 0, reference_average[..., 3] > 0)
    assert rmse(image, reference) < 3e-3
    vtk_image, _ = render("vtk", volume, tf, camera, size, preintegration=True)
    vtk_error = rmse(vtk_image, reference)
    print(f"spx-spiky {size}^2: RMSE tetra {rmse(image, reference):.5f}, vtk {vtk_error:.5f}")
    # VTK: a 128-bin table, and silhouettes half a pixel off (scenes README); measured 0.028 here
    assert vtk_error < 0.05


@pytest.mark.vtk
def test_blunt_fin_subset_against_reference_and_vtk(shared_data):
    """A block of blunt fin's cells (its zero-volume cells were dropped on loading, leaving
    holes the rays must step over) against the reference: the same pixels covered (no holes or
    streaks), and VTK's pre-integrated ray caster on the same scene for scale."""
    from tests.conftest import load_scene_tf
    from volren.io import load_volume

    with pytest.warns(VolrenWarning, match="zero-volume"):
        full = load_volume(shared_data / "tets" / "bluntfin_tets.vtu", scalars="Density")
    centres = full.points[full.tets].mean(axis=1)
    lo, hi = np.percentile(centres, 30, axis=0), np.percentile(centres, 60, axis=0)
    keep = np.all((centres >= lo) & (centres <= hi), axis=1)
    used, tets = np.unique(full.tets[keep], return_inverse=True)
    block = TetVolume(full.points[used], tets.reshape(-1, 4), full.values[used])
    tf = load_scene_tf("bluntfin-smooth")
    camera = Camera.orbit(block.bounds, 30, 20, 1.0)
    reference, _ = render("reference", block, tf, camera)
    image, counters = render("tetra", block, tf, camera)
    average, _ = render("tetra", block, tf, camera, blend_mode="average", options={"backend": "cpu"})
    reference_average, _ = render("reference", block, tf, camera, blend_mode="average")
    assert reference[..., 3].max() > 0.02
    assert counters["walks_cut"] == 0
    assert np.abs(average - reference_average).max() < 2e-6
    assert rmse(image, reference) < 1e-3
    covered = reference[..., 3] > 1e-3  # the TF is faint here: alpha reaches 0.03
    assert np.count_nonzero(covered) > 300
    assert np.array_equal(image[..., 3] > 1e-3, covered)
    assert np.array_equal(average[..., 3] > 0, reference_average[..., 3] > 0)
    vtk_image, _ = render("vtk", block, tf, camera, preintegration=True)
    vtk_error = rmse(vtk_image, reference)
    print(f"blunt fin block {SIZE}^2: RMSE tetra {rmse(image, reference):.7f}, vtk {vtk_error:.5f}")
    # VTK's silhouettes sit about half a pixel off (scenes README): measured 0.0012 here
    assert vtk_error < 0.004
