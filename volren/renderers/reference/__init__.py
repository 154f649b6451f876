"""The `reference` renderer: the truth that every other renderer's error is measured against.

DESIGN.md's emission-absorption model integrated in float64 along each pixel ray, refined until
two successive levels agree to a tolerance. Modules: `tf_eval` (exact TF evaluation in numba),
`ray_integral` (the adaptive per-ray quadrature and exact max / min / average), `shading`
(Blinn-Phong headlight), `uniform` (trilinear grids), `tets` (tetrahedral meshes), `tf2d` (2D
transfer functions on grids) and `renderer` (the `ReferenceRenderer` class).

numba's on-disk cache does not notice edits to the modules a kernel calls into, so stale cache
files are dropped on import (`volren.numba_cache`).
"""

from pathlib import Path

from volren.numba_cache import drop_stale_cache

# the kernels also call into model.preintegration.segment_math (the emission centre)
drop_stale_cache(Path(__file__).parent, Path(__file__).parents[2] / "model" / "preintegration")

from volren.renderers.reference.renderer import ReferenceRenderer  # noqa: E402

__all__ = ["ReferenceRenderer"]
