"""Keeping numba's on-disk cache honest for packages whose kernels call each other.

numba's ``cache=True`` checks only the source file of the function it compiled, not the modules
that function calls into, so a kernel in one module would keep running an old copy of a helper
in another module after an edit. A package whose kernels span modules calls `drop_stale_cache`
from its ``__init__``: it removes the package's cache files whenever any of its sources is newer.
"""

from __future__ import annotations

from pathlib import Path


def drop_stale_cache(package_dir: str | Path, *dependencies: str | Path) -> None:
    """Delete the package's numba cache files (``__pycache__/*.nbi``, ``*.nbc``) older than the
    newest source in it or in the `dependencies` (folders of modules its kernels call into)."""
    here = Path(package_dir).resolve()
    cache = here / "__pycache__"
    folders = [here, *(Path(d).resolve() for d in dependencies)]
    try:
        newest = max(p.stat().st_mtime for folder in folders for p in folder.glob("*.py"))
        stale = [p for p in cache.glob("*.nb[ic]") if p.stat().st_mtime < newest]
    except (OSError, ValueError):
        return
    for path in stale:
        try:
            path.unlink()
        except OSError:
            pass
