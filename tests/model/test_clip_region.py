"""The clip region: planes and a crop box, their half-spaces, checks, and the file form."""

from __future__ import annotations

import numpy as np
import pytest

from volren.errors import VolrenError
from volren.model.clip_region import MAX_PLANES, NO_CLIP, ClipPlane, ClipRegion
from volren.model.scene import Scene
from volren.model.settings import RenderSettings
from volren.model.transfer_function import TransferFunction1D


def test_a_plane_keeps_the_side_its_normal_points_to_and_invert_the_other():
    plane = ClipPlane((1.0, 2.0, 3.0), (0.0, 0.0, 2.0))
    region = ClipRegion((plane,))
    points = np.array([[0.0, 0.0, 3.5], [0.0, 0.0, 2.5], [9.0, -9.0, 3.0]])
    assert region.keeps(points).tolist() == [True, False, True]  # points on the plane are kept
    inverted = ClipRegion((ClipPlane((1.0, 2.0, 3.0), (0.0, 0.0, 2.0), invert=True),))
    assert inverted.keeps(points).tolist() == [False, True, True]


def test_half_spaces_have_unit_normals_and_the_box_adds_its_six_faces():
    region = ClipRegion((ClipPlane((0, 0, 0), (3.0, 4.0, 0.0)),), (0.0, 1.0, -1.0, 2.0, 5.0, 6.0))
    rows = region.half_spaces()
    assert rows.shape == (7, 4)
    assert np.allclose(np.linalg.norm(rows[:, :3], axis=1), 1.0)
    rng = np.random.default_rng(3)
    points = rng.uniform(-2, 7, size=(2000, 3))
    inside_box = np.all((points >= (0, -1, 5)) & (points <= (1, 2, 6)), axis=1)
    assert np.array_equal(region.keeps(points), inside_box & (points @ (3.0, 4.0, 0.0) >= 0))


def test_half_spaces_in_grid_index_space_keep_the_same_points():
    region = ClipRegion((ClipPlane((0.3, -0.2, 1.0), (1.0, -2.0, 0.5)), ClipPlane((1, 1, 1), (0, 1, 1))),
                        (0.1, 2.0, -1.0, 0.5, 0.0, 3.0))  # fmt: skip
    origin, spacing = np.array([-1.0, 0.5, 2.0]), np.array([0.7, 1.1, 0.9])
    index_rows = region.half_spaces_in_grid(origin, spacing)
    rng = np.random.default_rng(5)
    index_points = rng.uniform(-5, 10, size=(3000, 3))
    world_points = origin + spacing * index_points
    kept_in_index = np.all(index_points @ index_rows[:, :3].T + index_rows[:, 3] >= 0, axis=1)
    assert np.array_equal(kept_in_index, region.keeps(world_points))
    assert kept_in_index.any() and not kept_in_index.all()


@pytest.mark.parametrize(("make", "message"), [
    (lambda: ClipPlane((0, 0, 0), (0, 0, 0)), "normal must not be zero"),
    (lambda: ClipPlane((0, 0), (1, 0, 0)), "origin is three finite numbers"),
    (lambda: ClipPlane((0, 0, float("nan")), (1, 0, 0)), "origin is three finite numbers"),
    (lambda: ClipPlane((0, 0, 0), "up"), "normal is three numbers"),
    (lambda: ClipPlane((0, 0, 0), (1, 0, 0), invert="yes"), "invert must be true or false"),
    (lambda: ClipRegion(tuple(ClipPlane((0, 0, 0), (1, 0, 0)) for _ in range(MAX_PLANES + 1))), "at most 6"),
    (lambda: ClipRegion((), (1, 0, 0, 1, 0, 1)), "xmin 1 is above xmax 0"),
    (lambda: ClipRegion.from_dict({"planes": [{"origin": [0, 0, 0]}]}), "has 'origin', 'normal'"),
    (lambda: ClipRegion.from_dict({"plane": []}), "unknown clip keys"),
    (lambda: ClipPlane.parse("1,2,3"), "six numbers OX,OY,OZ,NX,NY,NZ"),
])  # fmt: skip
def test_bad_clip_input_is_a_one_line_error(make, message):
    with pytest.raises(VolrenError, match=message) as exc:
        make()
    assert "\n" not in str(exc.value)


def test_settings_and_scenes_carry_the_clip_region_through_their_dicts():
    region = ClipRegion(
        (ClipPlane((1, 2, 3), (0, 1, 0), invert=True), ((0, 0, 0), (1, 1, 1))), (0, 9, 0, 9, 0, 9)
    )
    settings = RenderSettings(step=0.25, clip=region)
    assert settings.clip.planes[1] == ClipPlane((0, 0, 0), (1, 1, 1))  # a pair, as the Python API takes it
    assert RenderSettings.from_dict(settings.to_dict()) == settings
    tf = TransferFunction1D.ramp(0.0, 1.0)
    scene = Scene("v.vti", tf, settings=settings)
    assert Scene.from_dict(scene.to_dict()).settings.clip == region


def test_settings_without_clipping_write_no_clip_key():
    """Files from renderings without clipping stay as earlier versions wrote them."""
    assert "clip" not in RenderSettings().to_dict()
    assert RenderSettings().clip is NO_CLIP or RenderSettings().clip.is_empty
    assert RenderSettings.from_dict({"clip": {"planes": []}}).clip.is_empty


def test_a_plane_switched_off_clips_nothing_but_is_kept_in_the_file():
    off = ClipPlane((0, 0, 0), (1, 0, 0), enabled=False)
    region = ClipRegion((off,))
    assert region.is_empty and region.half_spaces().shape == (0, 4)
    settings = RenderSettings(clip=region)
    assert settings.to_dict()["clip"] == {"planes": [{"origin": [0.0, 0.0, 0.0], "normal": [1.0, 0.0, 0.0],
                                                      "enabled": False}]}  # fmt: skip
    assert RenderSettings.from_dict(settings.to_dict()) == settings
