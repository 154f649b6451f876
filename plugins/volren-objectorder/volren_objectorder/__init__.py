"""volren-objectorder: object-order ray casting (Mora, Jessel and Caubet 2002), a volren renderer
plugin written only against volren's public contract."""

from pathlib import Path

from volren.kernels import drop_stale_cache_of

drop_stale_cache_of(Path(__file__).parent)

from volren_objectorder.renderer import ObjectOrderRenderer  # noqa: E402

__all__ = ["ObjectOrderRenderer"]
