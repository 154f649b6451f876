"""volren: volume rendering of uniform grids and tetrahedral meshes.

    import volren
    rgba = volren.render("head.mhd", "bone.json", renderer="vtk", size=(512, 512), azimuth=30)
    with volren.drawing("head.mhd", "bone.json") as d:   # prepared once for many frames
        frames = [d.frame(d.orbit(azimuth=a)).image for a in range(0, 360, 30)]

Importing volren is cheap: VTK, PyVista, numba and Qt load only when something needs them.
"""

from __future__ import annotations

from typing import Any

__all__ = ["VolrenError", "__version__", "drawing", "render"]


def _version() -> str:
    """The installed distribution's version: pyproject.toml's, the only copy in the repository."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("volren")
    except PackageNotFoundError:  # a source tree on sys.path that was never installed
        return "0+unknown"


def __getattr__(name: str) -> Any:
    if name == "__version__":
        return _version()
    if name == "render":
        from volren.api import render

        return render
    if name == "drawing":
        from volren.api import drawing

        return drawing
    if name == "VolrenError":
        from volren.errors import VolrenError

        return VolrenError
    raise AttributeError(f"module 'volren' has no attribute {name!r}")
