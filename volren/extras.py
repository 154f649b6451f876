"""The optional parts of volren and what to install for each: a one-line error instead of a
traceback when an extra's package is missing.

    app:   PyQt5 (`volren view`, `volren bench app`)
    bench: matplotlib (the plots of `volren bench run`)
"""

from __future__ import annotations

import importlib
from types import ModuleType

from volren.errors import VolrenError

#: extra -> the module whose import proves it is installed.
EXTRAS = {"app": "PyQt5.QtWidgets", "bench": "matplotlib"}


def install_hint(extra: str) -> str:
    return f"pip install 'volren[{extra}]'"


def require(extra: str, what: str) -> ModuleType:
    """Import the extra's module, or raise a VolrenError saying that `what` needs it and how to
    install it. Only a missing package is translated: a package that is there but fails to load
    (a missing system library, say) raises as it is."""
    module = EXTRAS[extra]
    try:
        return importlib.import_module(module)
    except ModuleNotFoundError as exc:
        if not (exc.name or "").split(".")[0] == module.split(".")[0]:
            raise
        package = module.split(".")[0]
        raise VolrenError(f"{what} needs {package}, which is not installed: {install_hint(extra)}") from None
