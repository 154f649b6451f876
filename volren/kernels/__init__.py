"""CPU kernels (numpy and numba) that renderers and the app share, and nothing renderer-specific.

Why: the reference renderer defines the truth, so the renderers it judges must not borrow its
internals; what several of them need lives here, neutral, and is tested on its own:

- `camera_rays`: the rays through many pixel centres in one numba pass;
- `row_blocks`: a frame rendered in blocks of rows, with progress after each;
- `image_refinement`: image-space adaptive refinement (rays on a coarse grid, more where needed);
- `tf_eval`: exact evaluation of a 1D transfer function inside kernels (`pack_tf`);
- `shading`: the Blinn-Phong headlight of DESIGN.md's optical model and its no-shading threshold;
- `sample_placement`: a ray caster's midpoint rule (segments cut at a per-pixel phase);
- `tet_projection`: tetrahedra projected to pixel boxes and binned per pixel;
- `tet_clipping`: a ray clipped against one tetrahedron's face planes, exact at shared faces;
- `box_clipping`: a ray clipped to a box (slab test);
- `clip_planes`: a ray clipped to the kept side of the clip region's planes (`RenderSettings.clip`);
- `cut_faces`: the opaque face where a ray enters the clip region through a plane (`ClipRegion.cap`);
- `ray_block`: a block of pixel rays with their candidate cells, as one kernel parameter;
- `trilinear`: a grid's trilinear value at an index point, the samplers' fetch;
- `label_sample`, `channel_sample`, `mixed_sample`: one post-classified sample of a label volume
  (a TF per label, blended across label boundaries) or of mixed channels, and the overload that
  picks between them, for every sample-based renderer (raycast, objectorder, shearwarp);
- `native`: a C source built with the machine's compiler on first use and loaded with ctypes
  (a renderer keeps a numba kernel for machines where none builds).

The tetrahedra's face planes themselves are part of the one mesh preparation,
`volren.model.tet_mesh.prepare_mesh` (`PreparedMesh.planes`). Each renderer keeps its own
integrator. Kernels import only `volren.model` (the progress callback and option rules included),
`volren.errors` and `volren.numba_cache` (an import-linter contract in pyproject.toml).

numba's on-disk cache checks only the source of the function it compiled, so a renderer package
whose kernels call (and inline) these calls `drop_stale_cache_of` from its ``__init__``.
"""

from pathlib import Path

from volren.numba_cache import drop_stale_cache

KERNELS_DIR = Path(__file__).resolve().parent


def drop_stale_cache_of(package_dir: str | Path) -> None:
    """Drop the numba cache files of a package whose kernels call these, when they are older than
    its sources or ours: its cached machine code holds the copies of our kernels it inlined."""
    drop_stale_cache(package_dir, KERNELS_DIR)
