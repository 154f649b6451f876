"""volren-shearwarp: pre-integrated shear-warp on the CPU, a renderer plugin for volren written only
against volren's public contract."""

from volren_shearwarp.renderer import ShearWarpRenderer

__all__ = ["ShearWarpRenderer"]
