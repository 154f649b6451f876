"""The `slicer` renderer against exact oracles, the `reference` renderer and itself (both paths).

Images are small (48-64 pixels) because llvmpipe runs every fragment on the CPU.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.renderers.analytic import box_path_lengths, homogeneous_image, rmse
from volren.api import prepared_renderer
from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.settings import RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume
from volren.renderers.slicer.renderer import SlicerRenderer

pytestmark = pytest.mark.usefixtures("opengl")

PATHS = ("march", "slices")
SIZE = 48


def smooth_volume(n: int = 24) -> UniformVolume:
    z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(np.float64)
    values = np.sin(x / 4.0) + np.cos(y / 5.0) + z / 12.0
    return UniformVolume(values.astype(np.float32), spacing=(1.0, 1.2, 0.9), origin=(-3.0, 2.0, 1.0))


def ramp_tf(volume: UniformVolume, unit: float = 4.0) -> TransferFunction1D:
    lo, hi = volume.value_range
    return TransferFunction1D(
        color=[[lo, 0.2, 0.4, 1.0], [hi, 1.0, 0.8, 0.1]],
        opacity=[[lo, 0.0], [hi, 0.8]],
        opacity_unit_distance=unit,
    )


def render(name: str, volume, tf, settings: RenderSettings, camera: Camera, size: int = SIZE):
    with prepared_renderer(name, volume, tf, settings) as renderer:
        image = renderer.render(camera, size, size)
        return image, dict(renderer.last_frame.counters)


def exact(**options) -> dict:
    """Options that switch off the work skipping, so images are comparable bit for bit."""
    return {"early_termination": False, "empty_space_skipping": False, **options}


@pytest.fixture(scope="module")
def scene():
    volume = smooth_volume()
    return volume, ramp_tf(volume), Camera.orbit(volume.bounds, 30, 20, 1.0)


# ------------------------------------------------------------------------------ reference
@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize(
    "changes, bound",
    [
        # measured 2.3e-5, 2.2e-5, 6.3e-5 and 7.4e-5 (both paths)
        ({}, 1e-4),
        ({"preintegration": True}, 1e-4),
        ({"shade": True}, 2e-4),
        ({"shade": True, "preintegration": True}, 2e-4),
    ],
)
def test_composite_matches_reference(scene, path, changes, bound):
    volume, tf, camera = scene
    settings = RenderSettings(step=0.5, **changes)
    reference, _ = render("reference", volume, tf, settings.with_(preintegration=False), camera)
    image, _ = render("slicer", volume, tf, settings.with_(options={"path": path}), camera)
    assert np.isfinite(image).all()
    assert reference[..., 3].max() > 0.5  # the scene is not empty
    assert rmse(image, reference) < bound


def test_error_falls_with_step(scene):
    volume, tf, camera = scene
    reference, _ = render("reference", volume, tf, RenderSettings(), camera)
    errors = [
        rmse(render("slicer", volume, tf, RenderSettings(step=s), camera)[0], reference)
        for s in (2.0, 1.0, 0.5)
    ]
    assert errors[0] > errors[1] > errors[2]


# ------------------------------------------------------------------------- exact oracles
@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("preintegration", [False, True])
def test_homogeneous_block_is_step_invariant(path, preintegration):
    """A constant volume: alpha = 1 - (1 - a)^(L / d) per ray, whatever the number of slices,
    because the partial segments at the entry and exit are integrated with their real length."""
    volume = UniformVolume(np.full((10, 12, 14), 7.0, dtype=np.float32), spacing=(1.0, 0.8, 1.3))
    tf = TransferFunction1D(color=[[0, 0.9, 0.5, 0.2]], opacity=[[0, 0.3]], opacity_unit_distance=2.0)
    camera = Camera.orbit(volume.bounds, 35, 25, 1.2)
    expected = homogeneous_image(
        box_path_lengths(camera, SIZE, SIZE, volume.bounds), (0.9, 0.5, 0.2), 0.3, 2.0
    )
    for step in (1.0, 0.5, 0.3):
        settings = RenderSettings(step=step, preintegration=preintegration, options=exact(path=path))
        image, _ = render("slicer", volume, tf, settings, camera)
        inside = box_path_lengths(camera, SIZE, SIZE, volume.bounds) > 0.05
        assert np.abs(image - expected)[inside].max() < 2e-4, step


def column_camera(volume: UniformVolume) -> tuple[Camera, int, int]:
    """A parallel camera looking down -z with one pixel centre on every inner (x, y) grid column
    (the outermost columns lie on the box's faces, where rasterization rules decide)."""
    nx, ny, _ = volume.dimensions
    sx, sy, _ = volume.spacing
    b = volume.bounds
    centre = ((b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2)
    camera = Camera(
        position=(centre[0], centre[1], b[5] + 10.0),
        focal_point=centre,
        parallel=True,
        parallel_scale=(ny - 2) * sy / 2.0,
        clipping_range=(1.0, b[5] - b[4] + 20.0),
    )
    assert abs(nx * sx - ny * sy) < 1e-9
    return camera, nx - 2, ny - 2


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("mode, reduce", [("maximum", np.max), ("minimum", np.min), ("average", np.mean)])
def test_projections_match_the_columns(path, mode, reduce):
    """Along a grid column the trilinear field is piecewise linear between voxels, so its maximum
    and minimum are voxel values and its mean is the trapezoid rule over the voxels."""
    rng = np.random.default_rng(3)
    values = rng.integers(0, 256, size=(9, 16, 16)).astype(np.uint8)
    volume = UniformVolume(values)
    tf = TransferFunction1D(color=[[0, 0, 0, 1], [255, 1, 0.5, 0]], opacity=[[0, 0.1], [255, 1.0]])
    camera, width, height = column_camera(volume)
    if mode == "average":
        weights = np.ones(values.shape[0])
        weights[[0, -1]] = 0.5
        column = np.tensordot(weights / weights.sum(), values.astype(np.float64), axes=(0, 0))
    else:
        column = reduce(values.astype(np.float64), axis=0)
    rgb, alpha = tf.sample(column[1:-1, 1:-1][::-1])  # image row 0 is the top (largest y)
    expected = np.concatenate([rgb * alpha[..., None], alpha[..., None]], axis=-1)
    settings = RenderSettings(step=1.0, blend_mode=mode, options={"path": path})
    with prepared_renderer("slicer", volume, tf, settings) as renderer:
        image = renderer.render(camera, width, height)
    assert np.abs(image - expected).max() < 2e-5


@pytest.mark.parametrize("path", PATHS)
def test_spike_preintegration_beats_post_classification(path):
    """A TF spike narrower than the value change between neighbouring voxels, sampled once per
    voxel: point samples mostly step over it, the pre-integration table does not."""
    z, y, x = np.mgrid[0:24, 0:24, 0:24].astype(np.float64)
    values = 10.0 * np.sqrt((x - 11.5) ** 2 + (y - 11.5) ** 2 + (z - 11.5) ** 2)
    volume = UniformVolume(values.astype(np.float32))
    tf = TransferFunction1D(
        color=[[0, 1, 0.6, 0.2]],
        opacity=[[0, 0], [79, 0], [80, 0.9], [81, 0], [400, 0]],
        opacity_unit_distance=1.0,
    )
    camera = Camera.orbit(volume.bounds, 20, 10, 1.0)
    reference, _ = render("reference", volume, tf, RenderSettings(), camera)
    errors = {}
    for pre in (False, True):
        settings = RenderSettings(step=1.0, preintegration=pre, options={"path": path, "table_size": 1024})
        errors[pre] = rmse(render("slicer", volume, tf, settings, camera)[0], reference)
    assert reference[..., 3].max() > 0.3
    assert errors[True] * 5 < errors[False], errors


# ------------------------------------------------------------------------------- skipping
@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("preintegration", [False, True])
def test_skipping_is_honest(path, preintegration):
    """A dense ball in empty space, opaque enough for early termination: the image changes by at
    most the termination threshold's remainder, and fewer samples are taken."""
    z, y, x = np.mgrid[0:48, 0:48, 0:48].astype(np.float64)
    radius = np.sqrt((x - 24) ** 2 + (y - 26) ** 2 + (z - 23) ** 2)
    values = np.clip(200.0 - 25.0 * radius, 0, 200)
    volume = UniformVolume(values.astype(np.float32))
    tf = TransferFunction1D(color=[[0, 1, 1, 1]], opacity=[[0, 0], [5, 0], [60, 0.9], [200, 1]])
    camera = Camera.orbit(volume.bounds, 30, 20, 1.0)
    alpha = 0.99
    images, counters = {}, {}
    for on in (False, True):
        options = {
            "path": path,
            "early_termination": on,
            "empty_space_skipping": on,
            "brick_size": 4,
            "termination_alpha": alpha,
        }
        settings = RenderSettings(step=0.5, preintegration=preintegration, options=options)
        images[on], counters[on] = render("slicer", volume, tf, settings, camera)
    assert images[False][..., 3].max() > alpha
    assert np.abs(images[True] - images[False]).max() <= (1 - alpha) + 1e-5
    assert counters[True]["samples"] < 0.7 * counters[False]["samples"]
    assert counters[True]["bricks_empty"] > 0


def test_skipping_never_drops_a_preintegrated_segment_between_bricks():
    """Two bricks whose own values are all transparent, while the values between them are
    not: a pre-integrated segment from one to the other must still be drawn."""
    values = np.zeros((4, 4, 32), dtype=np.float32)
    values[..., 16:] = 100.0  # a jump between brick 1 (cells 8..15) and brick 2 (cells 16..23)
    volume = UniformVolume(values)
    tf = TransferFunction1D(color=[[0, 1, 1, 1]], opacity=[[0, 0], [40, 0], [50, 1], [60, 0], [100, 0]])
    camera = Camera.orbit(volume.bounds, 90, 0, 1.0)  # looking along x
    images = {}
    for on in (False, True):
        options = {"early_termination": False, "empty_space_skipping": on, "brick_size": 8}
        images[on], _ = render(
            "slicer", volume, tf, RenderSettings(step=1.0, preintegration=True, options=options), camera
        )
    assert images[False][..., 3].max() > 0.1
    assert np.abs(images[True] - images[False]).max() < 1e-6


# ---------------------------------------------------------------------------------- paths
@pytest.mark.parametrize(
    "changes",
    [
        {},
        {"preintegration": True},
        {"shade": True},
        {"preintegration": True, "shade": True},
        {"jitter": True},
    ],
)
def test_paths_agree(scene, changes):
    """The march and the slice paths visit the same sample points."""
    volume, tf, camera = scene
    settings = RenderSettings(step=0.7, **changes)
    march, _ = render("slicer", volume, tf, settings.with_(options=exact(path="march")), camera, 64)
    slices, _ = render("slicer", volume, tf, settings.with_(options=exact(path="slices")), camera, 64)
    diff = np.abs(march - slices).max(axis=-1)
    # Pixels whose ray grazes a polygon edge may differ by one segment (float32 rasterization).
    assert np.quantile(diff, 0.995) < 1e-4
    assert diff.max() < 0.05


def test_jitter_is_seeded(scene):
    volume, tf, camera = scene
    images = [
        render(
            "slicer", volume, tf, RenderSettings(step=2.0, jitter=True, options={"jitter_seed": seed}), camera
        )[0]
        for seed in (1, 1, 2)
    ]
    plain, _ = render("slicer", volume, tf, RenderSettings(step=2.0), camera)
    np.testing.assert_array_equal(images[0], images[1])
    assert np.abs(images[0] - images[2]).max() > 1e-4
    assert rmse(images[0], plain) < 0.02


# --------------------------------------------------------------------------------- data
@pytest.mark.parametrize(
    "dtype, options, bound",
    [
        (np.uint8, {}, 1e-4),
        (np.uint16, {}, 1e-4),
        (np.int16, {}, 1e-4),
        (np.float32, {}, 1e-4),
        # llvmpipe rounds each value filtered from an 8-bit texture to a whole step (textures.py).
        (np.uint8, {"volume_format": "native"}, 2e-2),
    ],
)
def test_every_precision_gives_the_same_image(dtype, options, bound):
    rng = np.random.default_rng(5)
    base = rng.integers(0, 120, size=(12, 12, 12)).astype(np.float64)
    camera = Camera.orbit((0, 11, 0, 11, 0, 11), 30, 20, 1.0)
    images = []
    for dt, offset, opts in ((np.float64, 0.0, {}), (dtype, -60.0 if dtype == np.int16 else 0.0, options)):
        volume = UniformVolume((base + offset).astype(dt))
        tf = TransferFunction1D(
            color=[[0 + offset, 1, 0.5, 0], [120 + offset, 0, 0.5, 1]],
            opacity=[[0 + offset, 0], [120 + offset, 0.6]],
        )
        settings = RenderSettings(step=0.5, preintegration=True, options=opts)
        images.append(render("slicer", volume, tf, settings, camera)[0])
    assert images[0][..., 3].max() > 0.3
    assert np.abs(images[0] - images[1]).max() < bound


@pytest.mark.parametrize("path", PATHS)
def test_nonfinite_values_are_transparent(path):
    clean = np.full((10, 10, 10), 50.0, dtype=np.float32)
    broken = clean.copy()
    broken[3:7, 3:7, 3:7] = np.nan
    broken[0, 0, 0] = np.inf
    tf = TransferFunction1D(color=[[0, 1, 1, 1]], opacity=[[0, 0.2], [100, 0.2]])
    camera = Camera.orbit((0, 9, 0, 9, 0, 9), 0, 0, 1.0)
    for pre in (False, True):
        settings = RenderSettings(preintegration=pre, options={"path": path})
        with_nan, _ = render("slicer", UniformVolume(broken), tf, settings, camera)
        without, _ = render("slicer", UniformVolume(clean), tf, settings, camera)
        assert np.isfinite(with_nan).all()
        assert (with_nan[..., 3] <= without[..., 3] + 1e-6).all()
        centre = SIZE // 2
        assert 0 < with_nan[centre, centre, 3] < without[centre, centre, 3] - 0.05


# ------------------------------------------------------------------------ GL and caching
def test_nothing_is_uploaded_again_when_only_the_camera_or_tf_changes(scene):
    volume, tf, camera = scene
    renderer = SlicerRenderer()
    try:
        renderer.set_volume(volume)
        renderer.set_transfer_function(tf)
        renderer.set_settings(RenderSettings(preintegration=True))
        renderer.render(camera, 32, 32)
        assert renderer.uploads == {"volume": 1, "gradient": 0, "tables": 1, "brick_mask": 1}
        renderer.render(camera.azimuth(40).zoom(1.3), 32, 32)
        assert renderer.last_frame.counters["uploaded_volume"] == 0
        assert renderer.last_frame.counters["uploaded_tables"] == 0
        tf.set_opacity_points([[tf.value_range[0], 0.0], [tf.value_range[1], 0.3]])
        renderer.render(camera, 32, 32)
        counters = renderer.last_frame.counters
        assert (
            counters["uploaded_volume"],
            counters["uploaded_tables"],
            counters["uploaded_brick_mask"],
        ) == (0, 1, 1)
        renderer.set_settings(RenderSettings(preintegration=True, shade=True))
        renderer.render(camera, 32, 32)
        assert renderer.uploads["gradient"] == 1 and renderer.uploads["volume"] == 1
    finally:
        renderer.release()


def test_release_frees_every_gl_object(scene):
    volume, tf, camera = scene
    renderer = SlicerRenderer()
    renderer.set_volume(volume)
    renderer.set_transfer_function(tf)
    for path in PATHS:
        renderer.set_settings(RenderSettings(shade=True, preintegration=True, options={"path": path}))
        renderer.render(camera, 32, 32)
        assert renderer._ctx.error == "GL_NO_ERROR"
    objects = renderer.gl_objects
    context = renderer._ctx
    assert len(objects) > 8
    renderer.release()
    assert all(type(obj.mglo).__name__ == "InvalidObject" for obj in objects)
    assert type(context.mglo).__name__ == "InvalidObject"
    with pytest.raises(VolrenError, match="released"):
        renderer.render(camera, 32, 32)


@pytest.mark.parametrize(
    "options, message",
    [
        ({"path": "raycast"}, "path must be one of"),
        ({"table_size": 1}, "table_size"),
        ({"termination_alpha": 1.5}, "termination_alpha"),
        ({"brick_size": 0}, "brick_size"),
        ({"colour": 1}, "has no option"),
    ],
)
def test_bad_options_are_one_line_errors(scene, options, message):
    volume, tf, camera = scene
    with pytest.raises(VolrenError, match=message) as info:
        with prepared_renderer("slicer", volume, tf, RenderSettings(options=options)) as renderer:
            renderer.render(camera, 16, 16)
    assert "\n" not in str(info.value)


@pytest.mark.vtk
def test_renderers_sharing_a_thread_keep_their_own_context(scene):
    """Each renderer makes its GL context current per frame: interleaving two slicers and VTK
    changes nothing."""
    volume, tf, camera = scene
    settings = [RenderSettings(), RenderSettings(preintegration=True, options={"path": "slices"})]
    alone = [render("slicer", volume, tf, s, camera, 32)[0] for s in settings]
    with (
        prepared_renderer("slicer", volume, tf, settings[0]) as first,
        prepared_renderer("slicer", volume, tf, settings[1]) as second,
        prepared_renderer("vtk", volume, tf) as vtk_renderer,
    ):
        for _ in range(2):
            images = [first.render(camera, 32, 32), second.render(camera, 32, 32)]
            vtk_renderer.render(camera, 32, 32)
    for image, expected in zip(images, alone, strict=True):
        np.testing.assert_array_equal(image, expected)


# ------------------------------------------------------------------------------- 2D TFs
def value_only_2d(tf1d_points, lo: float, hi: float, gmax: float):
    """A 2D TF of boxes over all gradients, one per value interval: a step TF in value alone."""
    from volren.model.transfer_function_2d import TFWidget, TransferFunction2D

    widgets = [TFWidget.box((a, b), (0.0, gmax), colour, opacity) for a, b, colour, opacity in tf1d_points]
    return TransferFunction2D(value_range=(lo, hi), gradient_range=(0.0, gmax), widgets=widgets)


@pytest.mark.parametrize("path", PATHS)
def test_2d_tf_matches_reference(scene, path):
    from volren.model.transfer_function_2d import TFWidget, TransferFunction2D

    volume, _, camera = scene
    lo, hi = volume.value_range
    tf = TransferFunction2D(
        value_range=(lo, hi),
        gradient_range=(0.0, 0.6),
        widgets=[
            TFWidget.gaussian((0.5 * (lo + hi), 0.25), (0.4, 0.15), (1.0, 0.6, 0.2), 0.7),
            TFWidget.triangle(lo + 0.8 * (hi - lo), 0.5, 0.6, (0.2, 0.5, 1.0), 0.9),
        ],
        opacity_unit_distance=2.0,
    )
    for shade in (False, True):
        reference, _ = render("reference", volume, tf, RenderSettings(shade=shade), camera)
        assert reference[..., 3].max() > 0.3
        # Measured 2.0e-3 / 1.6e-3 (shaded) at step 0.5, 5.2e-4 / 4.0e-4 at 0.25: the midpoint rule.
        errors = []
        for step in (0.5, 0.25):
            settings = RenderSettings(step=step, shade=shade, options={"path": path})
            errors.append(rmse(render("slicer", volume, tf, settings, camera)[0], reference))
        assert errors[0] < 4e-3 and errors[1] < errors[0] / 3


def test_2d_tf_of_value_alone_equals_the_1d_tf(scene):
    """A Gaussian widget too wide in gradient to vary there is a 1D TF of the value alone."""
    from volren.model.transfer_function_2d import TFWidget, TransferFunction2D

    volume, _, camera = scene
    lo, hi = volume.value_range
    widget = TFWidget.gaussian((lo + 0.6 * (hi - lo), 0.0), (0.1 * (hi - lo), 1e9), (0.3, 0.9, 0.4), 0.8)
    tf2 = TransferFunction2D(value_range=(lo, hi), gradient_range=(0.0, 10.0), widgets=[widget])
    xs = np.linspace(lo, hi, 2001)
    profile = widget.opacity_at(xs, 0.0)
    tf1 = TransferFunction1D(color=[[lo, 0.3, 0.9, 0.4]], opacity=np.stack([xs, profile], axis=1))
    settings = RenderSettings(step=0.5, options=exact())
    image2, _ = render("slicer", volume, tf2, settings, camera)
    image1, _ = render("slicer", volume, tf1, settings, camera)
    assert image1[..., 3].max() > 0.3
    assert np.abs(image2 - image1).max() < 2e-3


def test_2d_tf_refuses_preintegration(scene):
    volume, _, camera = scene
    lo, hi = volume.value_range
    tf2 = value_only_2d([(lo, hi, (1, 1, 1), 0.5)], lo, hi, 1.0)
    with pytest.raises(VolrenError, match="no pre-integration of 2D transfer functions"):
        render("slicer", volume, tf2, RenderSettings(preintegration=True), camera)


def test_2d_tf_skips_bricks_its_widgets_cannot_reach():
    from volren.model.bricks import BrickGrid
    from volren.model.transfer_function_2d import TFWidget, TransferFunction2D

    values = np.zeros((16, 16, 32), dtype=np.float32)
    values[..., 16:] = np.linspace(0, 100, 16)[None, None, :]
    grid = BrickGrid.from_array(values, 8)
    tf = TransferFunction2D(
        value_range=(0, 100),
        gradient_range=(0, 10),
        widgets=[TFWidget.box((60, 100), (0, 10), (1, 1, 1), 1.0)],
    )
    visible = grid.visible(tf)
    assert visible[..., 3].all() and not visible[..., :2].any()
    # The bound is exact for one widget: the box's peak wherever the brick's range meets it.
    np.testing.assert_array_equal(grid.max_opacity(tf)[..., 3], 1.0)


# ----------------------------------------------------------------------------- real data
def test_real_data_against_reference(shared_data):
    """A 64^3 block of the bonsai with its spiky scene TF: both classifications stay close to the
    reference, pre-integration closer (measured: see the bounds)."""
    from tests.conftest import load_scene_tf
    from volren.io import load_volume

    full = load_volume(shared_data / "uniform" / "bonsai.vti", scalars="ImageFile")
    block = UniformVolume(np.ascontiguousarray(full.values[96:160, 96:160, 96:160]), spacing=full.spacing)
    tf = load_scene_tf("bonsai-spiky")
    camera = Camera.orbit(block.bounds, 30, 20, 1.0)
    reference, _ = render("reference", block, tf, RenderSettings(), camera)
    assert reference[..., 3].max() > 0.5
    errors = {}
    for pre in (False, True):
        image, _ = render("slicer", block, tf, RenderSettings(step=0.5, preintegration=pre), camera)
        errors[pre] = rmse(image, reference)
    assert errors[True] < 0.5 * errors[False] and errors[True] < 0.01, errors


def test_a_volume_replaced_between_frames_frees_its_texture():
    """Volumes swapped outside a frame (time steps in the app, every brick of a bricked frame)
    have their textures freed in the slicer's own context: resident memory stays flat."""
    rng = np.random.default_rng(3)
    renderer = SlicerRenderer()
    tf = TransferFunction1D([[0, 1, 1, 1], [1, 1, 0, 0]], [[0, 0.0], [1, 0.5]])

    def resident_mb() -> float:
        with open("/proc/self/statm") as statm:
            return int(statm.read().split()[1]) * 4096 / 2**20

    try:
        renderer.set_transfer_function(tf)
        grown = []
        for step in range(40):
            renderer.set_volume(
                UniformVolume(rng.random((96, 96, 96), dtype=np.float32))
            )  # 3.4 MiB a texture
            renderer.render(Camera.orbit((0, 95, 0, 95, 0, 95)), 8, 8)
            if step in (9, 39):
                grown.append(resident_mb())
    finally:
        renderer.release()
    assert grown[1] - grown[0] < 40  # a leak would add 30 x 3.4 MiB = 100 MiB
