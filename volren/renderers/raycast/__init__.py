"""`raycast`: an image-order ray caster on the CPU for uniform grids (its 1D march in C where a
compiler is found, `march_native`, else numba's, `march`)."""

from pathlib import Path

from volren.kernels import drop_stale_cache_of

drop_stale_cache_of(Path(__file__).parent)

from volren.renderers.raycast.renderer import RaycastRenderer  # noqa: E402

__all__ = ["RaycastRenderer"]
