"""GLSL kept in .glsl files, with a small preprocessor in front of the driver's.

Drivers know nothing of files: they get one string per stage and report errors as
`source-string:line`. So `load_shader` expands `#include "file.glsl"` itself (each file once,
cycles and missing files reported with the including file and line), injects `#define`s right
after `#version`, and writes `#line N S` directives at every file boundary, S indexing the
file table kept in the `ShaderSource`. `ShaderSource.translate_log` turns the driver's
`S:LINE` back into `file.glsl:LINE`, and `compile_program` does that for every build error.

Mesa drops the source-string number on semantic errors (an undeclared name is reported as
`0:LINE(COL)` whatever file it is in; only syntax and preprocessor errors keep it), so by
default the `#line` numbers of file S are offset by S * LINE_STRIDE: the line number alone
then names the file, and the translation is right on every driver.

`#include` lines are expanded whatever `#if` they sit in: this preprocessor does not
evaluate conditions (the driver's does, after expansion). Directives in comments are ignored.
"""

from __future__ import annotations

import math
import numbers
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from volren.errors import VolrenError

SHADER_DIR = Path(__file__).resolve().parent / "shaders"
"""Where the package's own .glsl files live; searched after any explicit search dirs."""

LINE_STRIDE = 100_000
"""With unique line numbers, file S's line N is given to the driver as S * LINE_STRIDE + N."""

DEFINES_NAME = "<defines>"
"""The file-table name of the injected #define block (an error there is reported as such)."""

DefineValue = str | int | float | bool

_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_VERSION = re.compile(r"\s*#\s*version\s+(\d+)(\s+\w+)?\s*(//.*)?$")
_INCLUDE = re.compile(r'\s*#\s*include\s*(?:"([^"]*)"|<([^>]*)>)\s*(?://.*|/\*.*\*/\s*)?$')
_INCLUDE_ANY = re.compile(r"\s*#\s*include\b")
_PRAGMA_ONCE = re.compile(r"\s*#\s*pragma\s+once\s*(//.*)?$")
_DIRECTIVE_VERSION = re.compile(r"\s*#\s*version\b")

# Log formats, each at the start of a line: Mesa `0:12(5): error`, NVIDIA `0(12) : error C0000`,
# AMD, Intel Windows, ANGLE, Apple `ERROR: 0:12: ...`.
_LOG_MESA = re.compile(r"^(?P<pre>\s*)(?P<src>\d+):(?P<line>\d+)(?P<post>\(\d+\))", re.M)
_LOG_NVIDIA = re.compile(r"^(?P<pre>\s*)(?P<src>\d+)\((?P<line>\d+)\)(?P<post>)", re.M)
_LOG_PREFIXED = re.compile(
    r"^(?P<pre>\s*(?:ERROR|WARNING|INFO|error|warning|info):\s*)(?P<src>\d+):(?P<line>\d+)(?P<post>:)", re.M
)

STAGES = ("vertex", "fragment", "geometry", "tess_control", "tess_evaluation", "compute")


class ShaderCompileError(VolrenError):
    """A shader that the driver refused; `log` keeps the translated multi-line driver log."""

    def __init__(self, message: str, log: str = "") -> None:
        super().__init__(message)
        self.log = log


@dataclass(frozen=True)
class ShaderSource:
    """An expanded shader: the text for the driver, and the file table its `#line`s refer to."""

    text: str
    files: tuple[str, ...]
    """Display names, indexed by the source-string number S of `#line N S`."""
    paths: tuple[Path | None, ...]
    """The file behind each name (None for the injected defines)."""
    version: str
    defines: Mapping[str, str] = field(default_factory=dict)
    unique_lines: bool = True

    def __str__(self) -> str:
        return self.text

    @property
    def name(self) -> str:
        """The main file's display name."""
        return self.files[0]

    def location(self, source: int, line: int) -> tuple[str, int] | None:
        """The (file, line) behind a driver's `source:line`, or None when it is not ours."""
        if self.unique_lines:
            # The line number carries the file; the source number may be Mesa's bogus 0.
            source, line = divmod(line, LINE_STRIDE)
        if 0 <= source < len(self.files):
            return self.files[source], line
        return None

    def translate_log(self, log: str) -> str:
        """`log` with each leading `S:LINE`, `S(LINE)` or `ERROR: S:LINE` made `file:LINE`."""

        def replace(match: re.Match[str]) -> str:
            where = self.location(int(match["src"]), int(match["line"]))
            if where is None:
                return match[0]
            return f"{match['pre']}{where[0]}:{where[1]}{match['post']}"

        for pattern in (_LOG_MESA, _LOG_NVIDIA, _LOG_PREFIXED):
            log = pattern.sub(replace, log)
        return log


def load_shader(
    name_or_path: str | Path,
    defines: Mapping[str, DefineValue] | None = None,
    search_dirs: Iterable[str | Path] = (),
    *,
    unique_lines: bool = True,
) -> ShaderSource:
    """Read a .glsl file, expand its includes and inject `defines` after `#version`.

    A `Path` or an absolute name is read as is; a plain name is looked up in `search_dirs`,
    then in the package's shader folder. Includes are looked up next to the including file,
    then in the same folders. `unique_lines=False` writes plain `#line N S` (see the module
    docstring for why that is not the default).
    """
    dirs = [Path(d) for d in search_dirs]
    if SHADER_DIR.is_dir():
        dirs.append(SHADER_DIR)
    main = _find_main(name_or_path, dirs)
    formatted = _format_defines(defines or {})
    define_lines = [f"#define {name} {value}" for name, value in formatted.items()]
    expander = _Expander(main, dirs, unique_lines)
    expander.add_file(main)  # index 0: the main file

    lines = _read(main, None)
    version_at = _version_line(lines, main)
    version_match = _VERSION.match(lines[version_at])
    assert version_match is not None
    number, profile = version_match[1], (version_match[2] or "").strip()
    expander.old_line_semantics = int(number) < (300 if profile == "es" else 330)

    out = lines[: version_at + 1]
    if define_lines:
        defines_index = expander.add_file(None)
        out.append(expander.line_directive(defines_index, 1))
        out.extend(define_lines)
    out.append(expander.line_directive(0, version_at + 2))
    expander.stack.append(main)
    out.extend(expander.expand(main, lines[version_at + 1 :], first_line=version_at + 2))
    # What is left of `#include` is in comments; moderngl (5.13) would still try to resolve it.
    text = re.sub(r"#(\s*)include\b", r"# \1include", "\n".join(out) + "\n")
    return ShaderSource(
        text=text,
        files=tuple(expander.names),
        paths=tuple(expander.paths),
        version=f"{number} {profile}".strip(),
        defines=formatted,
        unique_lines=unique_lines,
    )


def compile_program(
    ctx: Any,
    vertex: ShaderSource | None = None,
    fragment: ShaderSource | None = None,
    geometry: ShaderSource | None = None,
    tess_control: ShaderSource | None = None,
    tess_evaluation: ShaderSource | None = None,
    compute: ShaderSource | None = None,
    **program_kwargs: Any,
) -> Any:
    """`ctx.program(...)` or `ctx.compute_shader(...)` from expanded sources.

    A build error becomes a `ShaderCompileError` (a VolrenError) whose message starts with a
    one-line summary (the stage and its first error as `file.glsl:LINE`) followed by the whole
    driver log, translated; `.log` keeps the log with its line breaks.
    """
    import moderngl  # here, so that importing this module stays light

    sources = {
        "vertex": vertex,
        "fragment": fragment,
        "geometry": geometry,
        "tess_control": tess_control,
        "tess_evaluation": tess_evaluation,
        "compute": compute,
    }
    given = {stage: src for stage, src in sources.items() if src is not None}
    if compute is not None:
        if len(given) > 1 or program_kwargs:
            raise VolrenError("compile_program: a compute shader cannot be combined with other stages")
    elif vertex is None:
        raise VolrenError("compile_program: a program needs a vertex shader (or give a compute shader)")
    try:
        if compute is not None:
            return ctx.compute_shader(compute.text)
        kwargs = {f"{stage}_shader": src.text for stage, src in given.items()}
        return ctx.program(**kwargs, **program_kwargs)
    except moderngl.Error as exc:
        raise _build_error(str(exc), given) from exc


def _build_error(log: str, sources: Mapping[str, ShaderSource]) -> ShaderCompileError:
    """Translate moderngl's error text (sections headed `<stage>_shader` / `=====`) per stage."""
    parts = re.split(r"^(\w+)_shader\n=+\n", log, flags=re.M)
    # parts: [preamble, stage1, body1, stage2, body2, ...]
    translated = [parts[0]]
    failed: list[str] = []
    first_error = ""
    for stage, body in zip(parts[1::2], parts[2::2]):
        src = sources.get(stage)
        body = src.translate_log(body) if src is not None else body
        failed.append(stage)
        header = f"{stage}_shader"
        translated.append(f"{header}\n{'=' * len(header)}\n{body}")
        if not first_error:
            first_error = next((ln.strip() for ln in body.splitlines() if ln.strip()), "")
    full = "".join(translated).strip()
    if failed:
        names = ", ".join(sources[s].name if s in sources else s for s in failed)
        summary = f"{' and '.join(s.replace('_', ' ') for s in failed)} shader ({names}) did not compile: {first_error}"
    else:  # a link error or anything else without stage sections
        summary = next(
            (ln.strip() for ln in full.splitlines() if ln.strip()), "shader program failed to build"
        )
    return ShaderCompileError(f"{summary} | driver log: {full}", log=full)


class _Expander:
    """The include walk: file table, include-once set, and the stack used to spot cycles."""

    def __init__(self, main: Path, dirs: list[Path], unique_lines: bool) -> None:
        self.roots = [main.parent, *dirs]
        self.dirs = dirs
        self.unique_lines = unique_lines
        self.old_line_semantics = False
        self.names: list[str] = []
        self.paths: list[Path | None] = []
        self.index: dict[Path, int] = {}
        self.done: set[Path] = set()
        self.stack: list[Path] = []

    def add_file(self, path: Path | None) -> int:
        self.names.append(DEFINES_NAME if path is None else self.display_name(path))
        self.paths.append(path)
        if path is not None:
            self.index[path] = len(self.paths) - 1
        return len(self.paths) - 1

    def display_name(self, path: Path) -> str:
        """Relative to the folder it was found from when possible: short, and still findable."""
        for root in self.roots:
            try:
                return path.relative_to(root.resolve()).as_posix()
            except ValueError:
                continue
        return str(path)

    def line_directive(self, source: int, line: int) -> str:
        """`#line` so that the next line is reported as `line` of file `source`."""
        if self.unique_lines:
            line += source * LINE_STRIDE
        if self.old_line_semantics:  # before GLSL 3.30 / ES 3.00, #line N names the line before
            line -= 1
        return f"#line {line} {source}"

    def expand(self, path: Path, lines: list[str], first_line: int) -> list[str]:
        """`lines` of `path` (numbered from `first_line`) with includes expanded in place."""
        self.done.add(path)
        out: list[str] = []
        in_comment = False
        me = self.index[path]
        for number, text in enumerate(lines, start=first_line):
            starts_in_comment = in_comment
            in_comment = _ends_in_block_comment(text, in_comment)
            if starts_in_comment:
                out.append(text)
                continue
            where = f"{self.names[me]}:{number}"
            if _DIRECTIVE_VERSION.match(text):
                raise VolrenError(f"{where}: #version is only allowed as the first line of the main shader")
            if _PRAGMA_ONCE.match(text):
                out.append("")  # every file is included once anyway; keep the line count
                continue
            if not _INCLUDE_ANY.match(text):
                out.append(text)
                continue
            match = _INCLUDE.match(text)
            if match is None:
                raise VolrenError(f'{where}: malformed #include (expected #include "file.glsl")')
            target = self.resolve(match[1] if match[1] is not None else match[2], path, where)
            if target in self.stack:
                chain = " -> ".join(
                    self.display_name(p) for p in [*self.stack[self.stack.index(target) :], target]
                )
                raise VolrenError(f"{where}: include cycle: {chain}")
            if target in self.done:
                out.append("")  # already included: an include guard, like #pragma once
                continue
            index = self.add_file(target)
            self.stack.append(target)
            out.append(self.line_directive(index, 1))
            out.extend(self.expand(target, _read(target, where), first_line=1))
            self.stack.pop()
            out.append(self.line_directive(me, number + 1))
        return out

    def resolve(self, name: str, including: Path, where: str) -> Path:
        """Next to the including file first, then the search dirs."""
        candidates = [including.parent / name, *(d / name for d in self.dirs)]
        for candidate in candidates:
            if candidate.is_file():
                return candidate.resolve()
        looked = ", ".join(str(c.parent) for c in candidates)
        raise VolrenError(f'{where}: cannot find include "{name}" (looked in: {looked})')


def _find_main(name_or_path: str | Path, dirs: list[Path]) -> Path:
    if isinstance(name_or_path, Path) or Path(name_or_path).is_absolute():
        path = Path(name_or_path)
        if not path.is_file():
            raise VolrenError(f"{path}: shader file not found")
        return path.resolve()
    for folder in dirs:
        if (folder / name_or_path).is_file():
            return (folder / name_or_path).resolve()
    looked = ", ".join(str(d) for d in dirs) or "no search dirs"
    raise VolrenError(f"{name_or_path}: shader file not found (looked in: {looked})")


def _read(path: Path, where: str | None) -> list[str]:
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        prefix = f"{where}: " if where else ""
        raise VolrenError(f"{prefix}{path}: cannot read shader ({exc})") from exc
    if len(lines) >= LINE_STRIDE:
        raise VolrenError(f"{path}: shader files are limited to {LINE_STRIDE - 1} lines")
    return lines


def _version_line(lines: list[str], path: Path) -> int:
    """Index of the `#version` line, which must come before anything but blanks and comments."""
    in_comment = False
    for index, text in enumerate(lines):
        starts_in_comment = in_comment
        in_comment = _ends_in_block_comment(text, in_comment)
        stripped = _strip_comments(text, starts_in_comment).strip()
        if not stripped:
            continue
        if _VERSION.match(text) and not starts_in_comment:
            return index
        raise VolrenError(
            f"{path.name}:{index + 1}: a main shader must start with #version (e.g. #version 430), "
            "so that defines can be injected after it"
        )
    raise VolrenError(f"{path.name}: no #version line (a main shader must start with one, e.g. #version 430)")


def _format_defines(defines: Mapping[str, DefineValue]) -> dict[str, str]:
    """GLSL text for each define value: bools as 1/0, floats with a decimal point."""
    out: dict[str, str] = {}
    for name, value in defines.items():
        if not isinstance(name, str) or not _IDENTIFIER.match(name):
            raise VolrenError(f"shader define {name!r}: not a valid GLSL identifier")
        if name.startswith("GL_") or "__" in name:
            raise VolrenError(
                f"shader define {name!r}: names starting with GL_ or containing __ are reserved"
            )
        if isinstance(value, bool) or type(value).__name__ == "bool_":
            text = "1" if value else "0"
        elif isinstance(value, numbers.Integral):
            text = str(int(value))
        elif isinstance(value, numbers.Real):
            number = float(value)
            if not math.isfinite(number):
                raise VolrenError(f"shader define {name}: {value} is not a finite number")
            text = repr(number)
        elif isinstance(value, str):
            if "\n" in value or "\r" in value:
                raise VolrenError(f"shader define {name}: the value must be one line")
            text = value.strip()
        else:
            raise VolrenError(f"shader define {name}: {type(value).__name__} values are not supported")
        out[name] = text
    return out


def _strip_comments(text: str, in_comment: bool) -> str:
    """`text` without its comments (`in_comment`: the line starts inside a block comment)."""
    result = []
    i = 0
    while i < len(text):
        if in_comment:
            end = text.find("*/", i)
            if end < 0:
                break
            in_comment, i = False, end + 2
        elif text.startswith("//", i):
            break
        elif text.startswith("/*", i):
            in_comment, i = True, i + 2
        else:
            result.append(text[i])
            i += 1
    return "".join(result)


def _ends_in_block_comment(text: str, in_comment: bool) -> bool:
    """Whether a block comment is still open at the end of this line."""
    i = 0
    while i < len(text):
        if in_comment:
            end = text.find("*/", i)
            if end < 0:
                return True
            in_comment, i = False, end + 2
        elif text.startswith("//", i):
            return False
        elif text.startswith("/*", i):
            in_comment, i = True, i + 2
        else:
            i += 1
    return in_comment
