"""The `reference` renderer: the truth that every other renderer's error is measured against.

DESIGN.md's emission-absorption model integrated in float64 along each pixel ray, refined until
two successive levels agree to a tolerance. Modules: `tf_eval` (exact TF evaluation in numba),
`ray_integral` (the adaptive per-ray quadrature and exact max / min / average), `shading`
(Blinn-Phong headlight), `uniform` (trilinear grids), `tets` (tetrahedral meshes) and `renderer`
(the `ReferenceRenderer` class).

numba's on-disk cache (``cache=True``) checks only the source file of the function it compiled,
not the modules that function calls into, so a kernel in `uniform.py` would keep running an old
copy of `ray_integral.py` after an edit. `_drop_stale_numba_cache` therefore removes this
package's cache files whenever any of its sources is newer than them.
"""

from pathlib import Path


def _drop_stale_numba_cache() -> None:
    here = Path(__file__).resolve().parent
    cache = here / "__pycache__"
    try:
        newest = max(p.stat().st_mtime for p in here.glob("*.py"))
        stale = [p for p in cache.glob("*.nb[ic]") if p.stat().st_mtime < newest]
    except (OSError, ValueError):
        return
    for path in stale:
        try:
            path.unlink()
        except OSError:
            pass


_drop_stale_numba_cache()

from volren.renderers.reference.renderer import ReferenceRenderer  # noqa: E402

__all__ = ["ReferenceRenderer"]
