"""`raycast`: an image-order ray caster on the CPU (numba) for uniform grids."""

from volren.renderers.raycast.renderer import RaycastRenderer

__all__ = ["RaycastRenderer"]
