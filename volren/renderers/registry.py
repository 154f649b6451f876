"""Renderer discovery through the entry-point group ``volren.renderers``.

Built-in renderers are declared in volren's own pyproject.toml under that group, exactly as a
third-party package declares its own; nothing is special-cased except precedence (a plugin may
not shadow a built-in name). Entry points are read once and lazily; a renderer class is imported
only when it is first asked for. A plugin that fails to import is reported once (a
VolrenWarning) and stays listed under `failures`; the other renderers stay usable.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from importlib import import_module, metadata, util
from pathlib import Path
from typing import Any

from volren.errors import VolrenError, VolrenWarning
from volren.renderers.base import Capabilities, OptionSpec, Renderer

ENTRY_POINT_GROUP = "volren.renderers"
OWN_DISTRIBUTION = "volren"

#: The built-ins as declared in pyproject.toml; used only when volren runs uninstalled (no
#: distribution metadata). A test keeps the two lists equal.
BUILTIN_ENTRY_POINTS = {
    "vtk": "volren.renderers.vtk_mappers.renderer:VtkRenderer",
    "reference": "volren.renderers.reference.renderer:ReferenceRenderer",
    "slicer": "volren.renderers.slicer.renderer:SlicerRenderer",
    "tetra": "volren.renderers.tetra.renderer:TetraRenderer",
    "raycast": "volren.renderers.raycast.renderer:RaycastRenderer",
}


@dataclass(frozen=True)
class _Entry:
    name: str
    target: str  # "package.module:Class"
    source: str  # distribution name, or "in-process"
    builtin: bool
    loaded: Any = None  # the class when registered in-process


def _import_target(target: str) -> Any:
    module_name, _, attr = target.partition(":")
    obj = import_module(module_name)
    for part in attr.split(".") if attr else ():
        obj = getattr(obj, part)
    return obj


def _distribution_installed(name: str) -> bool:
    try:
        metadata.distribution(name)
    except metadata.PackageNotFoundError:
        return False
    return True


#: The methods of the Renderer Protocol.
RENDERER_METHODS = ("set_volume", "set_transfer_function", "set_settings", "render", "release")


def check_renderer_class(cls: Any, name: str) -> None:
    """Raise VolrenError unless `cls` has what the Renderer Protocol says at class level (the
    instance attribute `last_frame` is checked by `check_renderer_instance`)."""
    if not isinstance(cls, type):
        raise VolrenError(f"renderer {name!r} is {cls!r}, not a class")
    missing = [m for m in RENDERER_METHODS if not callable(getattr(cls, m, None))]
    if missing:
        raise VolrenError(f"renderer {name!r} ({cls!r}) lacks {', '.join(missing)}")
    if not isinstance(getattr(cls, "name", None), str):
        raise VolrenError(f"renderer {name!r} has no `name` string")
    if not isinstance(getattr(cls, "capabilities", None), Capabilities):
        raise VolrenError(f"renderer {name!r} has no `capabilities` Capabilities record")
    options = getattr(cls, "options", None)
    if not isinstance(options, tuple) or not all(isinstance(spec, OptionSpec) for spec in options):
        raise VolrenError(f"renderer {name!r} has no `options` tuple of OptionSpec")
    help_ = getattr(cls, "option_help", None)
    if not isinstance(help_, Mapping) or not all(
        isinstance(k, str) and isinstance(v, str) for k, v in help_.items()
    ):
        raise VolrenError(f"renderer {name!r} has no `option_help` mapping of option names to help text")


def check_renderer_instance(renderer: Any, name: str) -> None:
    """Raise VolrenError unless a new renderer has the Protocol's `last_frame` (None before a frame)."""
    if not hasattr(renderer, "last_frame"):
        raise VolrenError(f"renderer {name!r} has no `last_frame` attribute (set it to None in __init__)")


class RendererRegistry:
    """Names -> renderer classes, discovered from entry points and in-process registrations."""

    def __init__(
        self,
        entry_points: Callable[[], Iterable[metadata.EntryPoint]] | None = None,
        builtin_fallback: bool | None = None,
    ) -> None:
        """`entry_points` replaces discovery (tests); `builtin_fallback` adds BUILTIN_ENTRY_POINTS
        (default: only when volren's own distribution metadata is absent)."""
        self._entry_points = entry_points or (lambda: metadata.entry_points(group=ENTRY_POINT_GROUP))
        self._builtin_fallback = builtin_fallback
        self._entries: dict[str, _Entry] | None = None
        self._classes: dict[str, type] = {}
        self.failures: dict[str, str] = {}
        self._reported: set[str] = set()

    # ------------------------------------------------------------------------ discovery
    def _discover(self) -> dict[str, _Entry]:
        if self._entries is not None:
            return self._entries
        found: list[_Entry] = []
        for ep in self._entry_points():
            dist = getattr(ep, "dist", None)
            source = dist.name if dist is not None else "unknown"
            found.append(_Entry(ep.name, ep.value, source, source == OWN_DISTRIBUTION))
        fallback = self._builtin_fallback
        if fallback is None:
            fallback = not _distribution_installed(OWN_DISTRIBUTION)
        if fallback:
            found += [_Entry(n, t, OWN_DISTRIBUTION, True) for n, t in BUILTIN_ENTRY_POINTS.items()]
        entries: dict[str, _Entry] = {}
        # Built-ins first, then plugins by distribution name: the first claim on a name wins.
        for entry in sorted(found, key=lambda e: (not e.builtin, e.source, e.name)):
            other = entries.get(entry.name)
            if other is None:
                entries[entry.name] = entry
            elif other.target != entry.target:
                self._report(
                    f"dup:{entry.name}:{entry.source}",
                    f"renderer name {entry.name!r} from {entry.source} ({entry.target}) is ignored: "
                    f"{other.source} already provides it ({other.target})",
                )
        self._entries = entries
        return entries

    def _report(self, key: str, message: str) -> None:
        if key not in self._reported:
            self._reported.add(key)
            warnings.warn(message, VolrenWarning, stacklevel=3)

    # --------------------------------------------------------------------------- queries
    def names(self) -> list[str]:
        """Every registered name (without importing anything), built-ins first."""
        entries = self._discover()
        return sorted(entries, key=lambda n: (not entries[n].builtin, n))

    def available(self) -> list[str]:
        """The names whose class imports and passes the contract check."""
        out = []
        for name in self.names():
            try:
                self.get(name)
            except VolrenError:
                continue
            out.append(name)
        return out

    def get(self, name: str) -> type[Renderer]:
        """The renderer class for `name`; imports it on first use."""
        if name in self._classes:
            return self._classes[name]  # type: ignore[return-value]
        entries = self._discover()
        entry = entries.get(name)
        if entry is None:
            known = ", ".join(self.names()) or "none"
            raise VolrenError(f"unknown renderer {name!r}; registered: {known}")
        if name in self.failures:
            raise VolrenError(f"renderer {name!r} is unavailable: {self.failures[name]}")
        try:
            cls = entry.loaded if entry.loaded is not None else _import_target(entry.target)
            check_renderer_class(cls, name)
        except Exception as exc:  # a broken plugin must not take the others down
            reason = f"{entry.target} from {entry.source} failed to load: {type(exc).__name__}: {exc}"
            reason = " ".join(reason.split())
            self.failures[name] = reason
            self._report(f"fail:{name}", f"renderer {name!r} is unavailable: {reason}")
            raise VolrenError(f"renderer {name!r} is unavailable: {reason}") from None
        self._classes[name] = cls
        return cls

    def capabilities(self, name: str) -> Capabilities:
        return self.get(name).capabilities

    def create(self, name: str, **kwargs: Any) -> Renderer:
        """A new renderer instance, checked against the Protocol."""
        renderer = self.get(name)(**kwargs)
        try:
            check_renderer_instance(renderer, name)
        except VolrenError:
            renderer.release()
            raise
        return renderer

    def compatible(self, volume_kind: str, tf_dim: int = 1, settings=None) -> dict[str, str | None]:
        """For each available renderer: None if it can draw such a scene, else the reason."""
        out: dict[str, str | None] = {}
        for name in self.names():
            try:
                caps = self.capabilities(name)
            except VolrenError as exc:
                out[name] = str(exc)
                continue
            out[name] = caps.unsupported_reason(volume_kind, tf_dim, settings)
        return out

    def package_folder(self, name: str) -> Path | None:
        """The folder of the package that holds renderer `name`'s module, found from the entry point
        without importing the renderer (None for an unknown name or a module outside a package)."""
        entry = self._discover().get(name)
        package = entry.target.partition(":")[0].rpartition(".")[0] if entry is not None else ""
        try:
            spec = util.find_spec(package) if package else None
        except (ImportError, ValueError):
            return None
        folders = (spec.submodule_search_locations or []) if spec is not None else []
        return Path(folders[0]) if folders else None

    def data_file(self, name: str, filename: str) -> Path | None:
        """`filename` in renderer `name`'s package (`package_folder`): the data a renderer ships with
        itself (its measured quality levels, `volren.quality`); None where there is no such file."""
        folder = self.package_folder(name)
        path = folder / filename if folder is not None else None
        return path if path is not None and path.is_file() else None

    def registered_in_process(self, name: str) -> bool:
        """Whether `name` was registered by `register` in this process (another process, which reads
        only the entry points, does not know it)."""
        entry = self._discover().get(name)
        return entry is not None and entry.loaded is not None

    # ------------------------------------------------------------------------ mutation
    def register(self, name: str, cls: type, replace: bool = False) -> None:
        """Register a class in-process (scripts, tests); built-in names cannot be replaced."""
        entries = self._discover()
        if name in entries and not replace:
            raise VolrenError(f"renderer name {name!r} is already registered by {entries[name].source}")
        if name in entries and entries[name].builtin:
            raise VolrenError(f"renderer name {name!r} is a built-in and cannot be replaced")
        check_renderer_class(cls, name)
        entries[name] = _Entry(name, f"{cls.__module__}:{cls.__qualname__}", "in-process", False, cls)
        self._classes[name] = cls
        self.failures.pop(name, None)

    def unregister(self, name: str) -> None:
        entries = self._discover()
        if name in entries and entries[name].builtin:
            raise VolrenError(f"renderer name {name!r} is a built-in and cannot be removed")
        entries.pop(name, None)
        self._classes.pop(name, None)
        self.failures.pop(name, None)


#: The process-wide registry used by the CLI, the app and `volren.render`.
registry = RendererRegistry()
