"""VTK's unstructured ray caster on a tangled mesh: cells that fold over a neighbour.

The lattice's centre point is pushed through a face of one of its cells, so a few cells invert
and overlap their neighbours. `reference` integrates every cell (the overlap counts twice); the
ray caster, walking from cell to cell, ran backwards across the folded faces and drew streaks
brighter than any pixel of the exact image (alpha 0.929 where `reference` has at most 0.915, and
0.992 against 0.937 with RMSE 0.056) until folded cells were detached (RMSE 0.011 and 0.015 after,
the unfolded lattice's).
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.renderers.test_vtk_renderer import lattice_tets
from volren.model.camera import Camera
from volren.model.settings import RenderSettings
from volren.model.tet_mesh import folded_cells
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import TetVolume
from volren.renderers.registry import registry
from volren.testing.metrics import image_error
from volren.testing.reference_images import reference_image

pytestmark = [pytest.mark.vtk, pytest.mark.usefixtures("opengl")]

SIZE = 64
LSB = 1.0 / 255.0

#: case -> (where the centre point (2, 2, 2) goes, TF, (azimuth, elevation))
FOLDS = {
    "two cells inverted": (
        (2.0, 1.3, 2.7),
        TransferFunction1D.constant(0.3, (1.0, 0.5, 0.25), opacity_unit_distance=1.0),
        (30, 20),
    ),
    "six cells inverted": ((3.6, 2.0, 2.0), TransferFunction1D.ramp(0, 24, 0.6), (120, -40)),
}


def lattice(centre: tuple[float, float, float] | None = None, order=(0, 1, 2, 3)) -> TetVolume:
    """A 4^3-cube lattice with a linear field, its centre point moved to `centre`, its cells
    listed in vertex `order`."""
    base = lattice_tets(4)
    points = base.points.copy()
    if centre is not None:
        points[np.all(points == 2.0, axis=1)] = centre
    values = base.points @ [1.0, 2.0, 3.0]
    return TetVolume(points, base.tets[:, order], values, name="lattice")


def vtk_image(volume: TetVolume, tf, camera: Camera, renderer=None, mapper: str = "raycast") -> np.ndarray:
    renderer = renderer or registry.create("vtk")
    renderer.set_volume(volume)
    renderer.set_transfer_function(tf)
    renderer.set_settings(RenderSettings(options={"mapper": mapper}))
    return renderer.render(camera, SIZE, SIZE)


CLAIMED_RMSE = registry.capabilities("vtk").kinds["tet"].accuracy.rmse


@pytest.mark.parametrize("case", sorted(FOLDS))
def test_cells_folded_over_a_neighbour_are_drawn_like_reference(tmp_path, case):
    centre, tf, (azimuth, elevation) = FOLDS[case]
    volume = lattice(centre)
    assert folded_cells(volume.points, volume.tets).any()
    camera = Camera.orbit(volume.bounds, azimuth, elevation, 1.0)
    reference = reference_image(volume, tf, camera, SIZE, SIZE, folder=tmp_path)
    with registry.create("vtk") as renderer:
        image = vtk_image(volume, tf, camera, renderer)
    assert image[..., 3].max() <= reference[..., 3].max() + LSB
    assert image_error(image, reference).rmse <= CLAIMED_RMSE


@pytest.mark.parametrize("order", [(0, 1, 2, 3), (1, 0, 2, 3)], ids=["as built", "every cell inverted"])
def test_an_unfolded_lattice_is_drawn_like_reference_in_either_vertex_order(tmp_path, order):
    centre, tf, (azimuth, elevation) = FOLDS["two cells inverted"]
    volume = lattice(order=order)
    assert not folded_cells(volume.points, volume.tets).any()
    camera = Camera.orbit(volume.bounds, azimuth, elevation, 1.0)
    reference = reference_image(volume, tf, camera, SIZE, SIZE, folder=tmp_path)
    with registry.create("vtk") as renderer:
        assert image_error(vtk_image(volume, tf, camera, renderer), reference).rmse <= CLAIMED_RMSE


def test_switching_mappers_keeps_the_ray_casters_image():
    """Only the ray caster gets folded cells detached; the dataset follows the mapper."""
    centre, tf, (azimuth, elevation) = FOLDS["six cells inverted"]
    volume = lattice(centre)
    camera = Camera.orbit(volume.bounds, azimuth, elevation, 1.0)
    with registry.create("vtk") as renderer:
        first = vtk_image(volume, tf, camera, renderer)
        vtk_image(volume, tf, camera, renderer, mapper="zsweep")
        assert np.array_equal(vtk_image(volume, tf, camera, renderer), first)
