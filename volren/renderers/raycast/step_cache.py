"""The step that raycast's error target chose, kept on disk so that the next process does not search again.

Why: the search (`step_choice`) marches ~4096 rays at up to seven steps, one of them 16x finer than
the coarsest; on the shared grids that was 0.45-0.5 s of a 0.69 s frame, paid again by every
one-shot `volren render`. Its result is a pure function of what it marched, so it is stored under
a digest of all of it and read back instead of searched when the same scene is drawn again:

- the volume's values as the kernels read them (every byte: a step found on another volume would
  silently change the image's accuracy, so no subsample; SHA-256 runs at about 1 GB/s, in
  threads for large volumes, a few percent of a search), and its origin and spacing;
- the TF, the coarsest step, pre-integration and the options that change the march (the
  renderer's own in-memory key);
- the view the rays were sampled in: the first frame's inverse view-projection matrix, the
  sample image's size, the depth range and the sample phases. A renderer keeps its step while
  only the camera moves (the step must not change between the frames of a rotation), so the
  step depends on the view of the first frame after a TF or volume change; keyed on that view,
  a cached step is exactly the step the search would find, and the image is the same to the bit;
- the code that searches and marches (the sources of this package and of `volren.kernels`, numba's
  and numpy's versions): an edit to a kernel changes the errors the search measures.

Files are written atomically (a temporary file renamed over the entry); one that cannot be read
or parsed, or holds another key, is ignored and the step searched again; a cache folder that
cannot be written to leaves the search uncached. Where: ``$VOLREN_STEP_CACHE``, else
``$XDG_CACHE_HOME/volren/steps`` (``~/.cache/volren/steps``), beside the other caches of volren.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import tempfile
import weakref
from collections.abc import Callable, Iterable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

CACHE_ENV = "VOLREN_STEP_CACHE"
FORMAT_VERSION = 1
#: Bytes hashed per thread at a time: larger volumes are hashed as a list of chunk digests in threads
#: (hashlib releases the GIL while it hashes).
CHUNK_BYTES = 1 << 25

_digests: dict[int, tuple[weakref.ref, str]] = {}
_code: str | None = None


def cache_dir() -> Path:
    """$VOLREN_STEP_CACHE, else $XDG_CACHE_HOME/volren/steps (default ~/.cache/volren/steps)."""
    configured = os.environ.get(CACHE_ENV)
    if configured:
        return Path(configured).expanduser()
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "volren" / "steps"


def array_digest(values: NDArray) -> str:
    """SHA-256 (hex) of an array's dtype, shape and every byte, remembered while the array lives
    (a renderer's values are never written to once set)."""
    known = _digests.get(id(values))
    if known is not None and known[0]() is values:
        return known[1]
    data = memoryview(np.ascontiguousarray(values)).cast("B")  # type: ignore[arg-type]  # numpy types the buffer protocol from Python 3.12
    digest = hashlib.sha256(f"{values.dtype.str}:{values.shape}|".encode())
    if len(data) <= CHUNK_BYTES:
        digest.update(data)
    else:
        chunks = [data[i : i + CHUNK_BYTES] for i in range(0, len(data), CHUNK_BYTES)]
        with ThreadPoolExecutor(max_workers=min(len(chunks), os.cpu_count() or 1, 8)) as pool:
            for part in pool.map(lambda chunk: hashlib.sha256(chunk).digest(), chunks):
                digest.update(part)
    text = digest.hexdigest()
    ident = id(values)
    try:
        _digests[ident] = (weakref.ref(values, lambda _: _digests.pop(ident, None)), text)
    except TypeError:  # an array type that takes no weak references: not remembered
        pass
    return text


def code_digest() -> str:
    """SHA-256 of the sources of the ray caster (its C march too) and its kernels and of numba's and
    numpy's versions (numba's read from its metadata: a frame the C march draws does not import it)."""
    global _code
    if _code is None:
        from importlib.metadata import version

        here = Path(__file__).resolve().parent
        digest = hashlib.sha256(f"{FORMAT_VERSION}|{version('numba')}|{np.__version__}".encode())
        for folder in (here, here.parent.parent / "kernels"):
            for path in sorted([*folder.glob("*.py"), *folder.glob("*.c")]):
                digest.update(path.name.encode() + b"\0")
                try:
                    digest.update(path.read_bytes())
                except OSError:
                    digest.update(b"unreadable")
        _code = digest.hexdigest()
    return _code


def scene_key(values: NDArray, parts: Iterable[object]) -> str:
    """The entry's name: a digest of the volume's values, the code, and `parts` (numbers, bytes,
    strings, tuples and arrays: everything else the search's result depends on)."""
    digest = hashlib.sha256(f"{array_digest(values)}|{code_digest()}".encode())
    for part in parts:
        _update(digest, part)
    return digest.hexdigest()


def _update(digest, part: object) -> None:
    if isinstance(part, np.ndarray):
        array = np.ascontiguousarray(part)
        digest.update(f"a{array.dtype.str}{array.shape}:".encode())
        digest.update(memoryview(array).cast("B"))  # type: ignore[arg-type]
    elif isinstance(part, (tuple, list)):
        digest.update(f"t{len(part)}(".encode())
        for item in part:
            _update(digest, item)
        digest.update(b")")
    elif isinstance(part, bytes):
        digest.update(f"b{len(part)}:".encode() + part)
    elif isinstance(part, (bool, int, float, str, np.generic)) or part is None:
        text = repr(part.item() if isinstance(part, np.generic) else part)
        digest.update(f"{type(part).__name__}{len(text)}:{text}".encode())
    else:
        raise TypeError(f"cannot key the step cache on a {type(part).__name__}")


def read(key: str) -> tuple[float, float] | None:
    """The (step, estimated error) stored under `key`, or None when missing, unreadable or not valid."""
    try:
        entry = json.loads((cache_dir() / f"{key}.json").read_text(encoding="utf-8"))
        if entry["format"] != FORMAT_VERSION or entry["key"] != key:
            return None
        step, error = float(entry["step"]), float(entry["error"])
    except Exception:  # missing, truncated, not JSON, wrong fields: search again
        return None
    if not (math.isfinite(step) and step > 0.0 and math.isfinite(error) and error >= 0.0):
        return None
    return step, error


def write(key: str, step: float, error: float) -> None:
    """Store (step, error) under `key` atomically; a folder that cannot be written to is no error."""
    folder = cache_dir()
    text = json.dumps({"format": FORMAT_VERSION, "key": key, "step": step, "error": error})
    tmp_name = None
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile("w", dir=folder, prefix=f".{key[:16]}-", suffix=".tmp",
                                         delete=False, encoding="utf-8") as f:  # fmt: skip
            tmp_name = f.name
            f.write(text)
        os.replace(tmp_name, folder / f"{key}.json")
        tmp_name = None
    except OSError:
        pass
    finally:
        if tmp_name is not None:
            try:
                os.unlink(tmp_name)
            except OSError:
                pass


def remembered_step(values: NDArray, parts: Iterable[object], search: Callable[[], tuple[float, float]]
                    ) -> tuple[float, float]:  # fmt: skip
    """`search()`'s (step, estimated error), read from the cache when this scene (`values`, `parts`)
    was searched before, else searched and stored."""
    key = scene_key(values, parts)
    found = read(key)
    if found is not None:
        return found
    step, error = search()
    write(key, step, error)
    return step, error
