"""volren-shearwarp: pre-integrated shear-warp on the CPU, a renderer plugin for volren written only
against volren's public contract."""

from pathlib import Path

from volren.kernels import drop_stale_cache_of

drop_stale_cache_of(Path(__file__).parent)

from volren_shearwarp.renderer import ShearWarpRenderer  # noqa: E402

__all__ = ["ShearWarpRenderer"]
