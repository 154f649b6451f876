"""Check, once per process, that an OpenGL context can be made before anything tries to.

Without EGL and a Mesa driver VTK segfaults on its first render; moderngl raises. Both are
worse than a message that says what to install, so GL renderers call `require_opengl()` first.
The check loads the libraries with ctypes and then creates (and drops) a tiny moderngl EGL
context, which fails with an exception rather than a crash.
"""

from __future__ import annotations

import ctypes
import functools
from typing import Any

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


class GLObjectOwner:
    """Keeps the GL objects something made, so that releasing it can free them all (tests check
    that it does). Subclasses set `self._objects = []` and free `self._objects` on release."""

    _objects: list[Any]

    def _track(self, obj: Any) -> Any:
        self._objects.append(obj)
        return obj

    def _drop(self, obj: Any) -> None:
        if obj is not None:
            obj.release()
            self._objects = [o for o in self._objects if o is not obj]

    @property
    def gl_objects(self) -> list[Any]:
        """The GL objects held now."""
        return list(self._objects)

    def _release_gl_objects(self, ctx: Any) -> None:
        """Free every tracked object, newest first, in `ctx` (None: the context is gone already)."""
        if ctx is not None:
            with ctx:
                for obj in reversed(self._objects):
                    obj.release()
        self._objects.clear()


def mat4_bytes(m: Any) -> bytes:
    """A numpy (row-major) 4x4 matrix as GLSL's column-major float32 bytes."""
    import numpy as np

    return np.ascontiguousarray(np.asarray(m, dtype=np.float64).T, dtype=np.float32).tobytes()
