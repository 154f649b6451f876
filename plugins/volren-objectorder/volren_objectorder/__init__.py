"""volren-objectorder: object-order ray casting (Mora, Jessel and Caubet 2002), a volren renderer
plugin written only against volren's public contract."""

from volren_objectorder.renderer import ObjectOrderRenderer

__all__ = ["ObjectOrderRenderer"]
