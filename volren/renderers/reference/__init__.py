"""The `reference` renderer: the truth that every other renderer's error is measured against.

DESIGN.md's emission-absorption model integrated in float64 along each pixel ray, refined until
two successive levels agree to a tolerance. Modules: `ray_integral` (the adaptive per-ray
quadrature and exact max / min / average: the reference's own integrator, shared with no other
renderer), `tf2d` (its quadrature of 2D transfer functions on grids), `refinement` (the levels
around either quadrature and the rule that stops them), `uniform` (trilinear grids), `labelled`
and `label_classes` (label volumes on grids: a TF per label, blended across labels), `channels`
(multi-channel volumes on grids: a TF per channel, their extinctions added), `tets`
(tetrahedral meshes), `segment` (one linear segment's integral, the oracle of pre-integration
tables) and `renderer` (the `ReferenceRenderer` class). What it shares with other renderers (TF
evaluation, shading, projection, clipping) is in `volren.kernels`, and the tetrahedra's face
planes come from `volren.model.tet_mesh`.

numba's on-disk cache does not notice edits to the modules a kernel calls into, so stale cache
files are dropped on import (`volren.numba_cache`).
"""

from pathlib import Path

from volren.numba_cache import drop_stale_cache

_volren = Path(__file__).parents[2]
drop_stale_cache(Path(__file__).parent, _volren / "kernels", _volren / "model" / "preintegration")

from volren.renderers.reference.renderer import ReferenceRenderer  # noqa: E402
from volren.renderers.reference.segment import segment_rgba  # noqa: E402

__all__ = ["ReferenceRenderer", "segment_rgba"]
