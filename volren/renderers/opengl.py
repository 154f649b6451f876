"""Check, once per process, that an OpenGL context can be made before anything tries to.

Without EGL and a Mesa driver VTK segfaults on its first render; moderngl raises. Both are
worse than a message that says what to install, so GL renderers call `require_opengl()` first.
The check loads the libraries with ctypes and then creates (and drops) a tiny moderngl EGL
context, which fails with an exception rather than a crash.
"""

from __future__ import annotations

import ctypes
import functools

from volren.errors import VolrenError

DEBIAN_PACKAGES = "libegl1 libgl1 libgl1-mesa-dri"
INSTALL_HINT = f"on Debian/Ubuntu install them with: sudo apt-get install {DEBIAN_PACKAGES}"


@functools.cache
def opengl_problem() -> str | None:
    """None when an offscreen OpenGL (EGL) context works here, else why not."""
    for library, package in (("libEGL.so.1", "libegl1"), ("libGL.so.1", "libgl1")):
        try:
            ctypes.CDLL(library)
        except OSError:
            return f"OpenGL is not available: {library} is missing (package {package}); {INSTALL_HINT}"
    try:
        import moderngl

        ctx = moderngl.create_standalone_context(backend="egl")
        ctx.release()
    except Exception as exc:  # moderngl/glcontext raise plain Exceptions here
        reason = " ".join(str(exc).split()) or type(exc).__name__
        return f"cannot create an offscreen OpenGL context through EGL ({reason}); {INSTALL_HINT}"
    return None


def require_opengl() -> None:
    """Raise a VolrenError naming the packages to install when OpenGL cannot work."""
    problem = opengl_problem()
    if problem:
        raise VolrenError(problem)
