"""The GLSL preprocessor: includes, defines, #line mapping and driver-log translation."""

from __future__ import annotations

import re
import struct
from pathlib import Path

import pytest

from volren.errors import VolrenError
from volren.renderers import glsl
from volren.renderers.glsl import LINE_STRIDE, ShaderCompileError, compile_program, load_shader

FIXTURES = Path(__file__).resolve().parent / "glsl_fixtures"
SEARCH = FIXTURES / "search"


def line_of(relative: str, text: str) -> int:
    """The 1-based line of fixture `relative` that contains `text` (so no magic numbers)."""
    lines = (FIXTURES / relative).read_text().splitlines()
    return next(number for number, line in enumerate(lines, start=1) if text in line)


def driver_line(source, relative: str, text: str) -> tuple[int, int]:
    """The (source-string, line) a driver would report for the fixture line containing `text`."""
    index = source.files.index(relative)
    line = line_of(relative, text)
    return index, line + (index * LINE_STRIDE if source.unique_lines else 0)


def code_lines(source) -> list[str]:
    """The expanded text without the injected #line directives."""
    return [line for line in source.text.splitlines() if not line.startswith("#line")]


# --- includes -------------------------------------------------------------------------------------


def test_includes_expand_in_order_once_each():
    """A diamond include puts common.glsl once, before a.glsl's body, then b and helper, then main."""
    source = load_shader(FIXTURES / "main.glsl")
    text = source.text
    markers = ["COMMON_MARKER = 7", "A_MARKER", "HELPER_RELATIVE", "B_MARKER", "MAIN_MARKER"]
    positions = [text.index(marker) for marker in markers]
    assert positions == sorted(positions)
    assert text.count("const int COMMON_MARKER") == 1
    assert source.files == ("main.glsl", "lib/a.glsl", "lib/common.glsl", "lib/b.glsl", "lib/helper.glsl")
    assert "#include" not in text and "#pragma once" not in text


def test_expanded_lines_match_the_files():
    """Every code line of the expansion is the original line that #line says it is."""
    source = load_shader(FIXTURES / "main.glsl", unique_lines=False)
    current_file, current_line = 0, 1
    checked = 0
    for line in source.text.splitlines()[1:]:
        if match := re.fullmatch(r"#line (\d+) (\d+)", line):
            current_line, current_file = int(match[1]), int(match[2])
            continue
        original = (FIXTURES / source.files[current_file]).read_text().splitlines()[current_line - 1]
        assert line in (original, "")  # blanked: an include guard or #pragma once
        checked += bool(line)
        current_line += 1
    assert checked > 10


def test_relative_include_beats_search_dirs():
    """b.glsl's helper.glsl is the one next to it, even when a search dir has one too."""
    source = load_shader(FIXTURES / "main.glsl", search_dirs=[SEARCH])
    assert "HELPER_RELATIVE" in source.text
    assert "HELPER_SEARCH" not in source.text


def test_search_dirs_find_main_files_and_includes():
    """A plain name is looked up in the search dirs, and so is an include not next to its file."""
    source = load_shader("uses_search.glsl", search_dirs=[SEARCH, FIXTURES])
    assert source.files == ("uses_search.glsl", "search/only_here.glsl")  # relative to the main file
    assert "ONLY_HERE_MARKER" in source.text
    with pytest.raises(VolrenError, match=r'uses_search\.glsl:2: cannot find include "only_here\.glsl"'):
        load_shader(FIXTURES / "uses_search.glsl")


def test_include_cycle_names_file_and_line():
    """a -> b -> a is reported at the include in cycle_b.glsl, with the chain."""
    line = line_of("cycle_b.glsl", '#include "cycle_a.glsl"')
    with pytest.raises(
        VolrenError,
        match=rf"cycle_b\.glsl:{line}: include cycle: cycle_a\.glsl -> cycle_b\.glsl -> cycle_a\.glsl",
    ):
        load_shader(FIXTURES / "cycle_a.glsl")


def test_missing_include_names_file_and_line():
    """A missing include names the including file and line, and where it looked."""
    line = line_of("missing.glsl", "does_not_exist")
    with pytest.raises(
        VolrenError, match=rf'missing\.glsl:{line}: cannot find include "does_not_exist\.glsl" \(looked in: '
    ):
        load_shader(FIXTURES / "missing.glsl")


def test_missing_main_file_and_missing_version():
    """No file, or no #version line, are both clear errors."""
    with pytest.raises(VolrenError, match=r"nope\.glsl: shader file not found"):
        load_shader("nope.glsl", search_dirs=[FIXTURES])
    with pytest.raises(VolrenError, match=r"no_version\.glsl:2: a main shader must start with #version"):
        load_shader(FIXTURES / "no_version.glsl")


def test_version_in_an_included_file_is_rejected(tmp_path):
    """Only the main file may have #version; an included one is reported at its line."""
    (tmp_path / "main.glsl").write_text('#version 430\n#include "inc.glsl"\n')
    (tmp_path / "inc.glsl").write_text("// inc\n#version 430\n")
    with pytest.raises(VolrenError, match=r"inc\.glsl:2: #version is only allowed"):
        load_shader(tmp_path / "main.glsl")


# --- defines --------------------------------------------------------------------------------------


def test_version_stays_first_and_defines_follow_it():
    """#version is the first directive, the defines come right after it, typed as GLSL."""
    source = load_shader(
        FIXTURES / "defines.glsl", {"VALUE": 42, "FLAG": True, "OFF": False, "SCALE": 1.0, "EXPR": "(1 + 2)"}
    )
    lines = source.text.splitlines()
    version_at = line_of("defines.glsl", "#version 430") - 1
    assert lines[version_at] == "#version 430"
    original = (FIXTURES / "defines.glsl").read_text().splitlines()
    assert lines[:version_at] == [line.replace("#include", "# include") for line in original[:version_at]]
    assert original[0].startswith("/*")  # only a comment comes before #version
    assert lines[version_at + 1] == f"#line {LINE_STRIDE + 1} 1"
    assert lines[version_at + 2 : version_at + 7] == [
        "#define VALUE 42",
        "#define FLAG 1",
        "#define OFF 0",
        "#define SCALE 1.0",
        "#define EXPR (1 + 2)",
    ]
    assert lines[version_at + 7] == f"#line {version_at + 2} 0"
    assert source.files == ("defines.glsl", glsl.DEFINES_NAME)
    assert source.defines == {"VALUE": "42", "FLAG": "1", "OFF": "0", "SCALE": "1.0", "EXPR": "(1 + 2)"}
    assert source.version == "430"
    assert "not_an_include" in source.text  # an #include inside a comment is left alone


@pytest.mark.parametrize("name", ["1ABC", "A-B", "", "A B", "GL_FOO", "MY__NAME"])
def test_invalid_define_names_are_rejected(name):
    """Names that are not identifiers, or are reserved by GLSL, are refused up front."""
    with pytest.raises(VolrenError, match="shader define"):
        load_shader(FIXTURES / "defines.glsl", {name: 1})


@pytest.mark.parametrize("value", [float("nan"), float("inf"), "two\nlines", None, [1]])
def test_invalid_define_values_are_rejected(value):
    """Non-finite floats, multi-line strings and other types are refused."""
    with pytest.raises(VolrenError, match="shader define VALUE"):
        load_shader(FIXTURES / "defines.glsl", {"VALUE": value})


def test_line_directives_follow_old_glsl_semantics(tmp_path):
    """Before GLSL 3.30, `#line N` names the directive's own line, so N is one less."""
    (tmp_path / "old.glsl").write_text("#version 120\nvoid main() {}\n")
    (tmp_path / "new.glsl").write_text("#version 300 es\nvoid main() {}\n")
    assert load_shader(tmp_path / "old.glsl").text.splitlines()[1] == "#line 1 0"
    assert load_shader(tmp_path / "new.glsl").text.splitlines()[1] == "#line 2 0"
    assert load_shader(tmp_path / "new.glsl").version == "300 es"


# --- log translation ------------------------------------------------------------------------------

LOG_FORMATS = {
    "mesa": ("{s}:{line}(5): error: `x' undeclared", "{file}:{orig}(5): error: `x' undeclared"),
    "nvidia": (
        '{s}({line}) : error C1008: undefined variable "x"',
        '{file}:{orig} : error C1008: undefined variable "x"',
    ),
    "amd": (
        "ERROR: {s}:{line}: 'x' : undeclared identifier",
        "ERROR: {file}:{orig}: 'x' : undeclared identifier",
    ),
}
PLACES = {"included": ("lib/helper.glsl", "HELPER_RELATIVE"), "main": ("main.glsl", "MAIN_MARKER")}


@pytest.mark.parametrize("unique_lines", [True, False], ids=["unique", "plain"])
@pytest.mark.parametrize("place", PLACES)
@pytest.mark.parametrize("fmt", LOG_FORMATS)
def test_translate_log_maps_each_format(fmt, place, unique_lines):
    """Mesa, NVIDIA and AMD logs are rewritten to file:line, for the main and an included file."""
    source = load_shader(FIXTURES / "main.glsl", unique_lines=unique_lines)
    relative, marker = PLACES[place]
    s, line = driver_line(source, relative, marker)
    raw, expected = LOG_FORMATS[fmt]
    log = "\n".join([raw.format(s=s, line=line), "unrelated text 3:4", ""])
    translated = source.translate_log(log)
    orig = line_of(relative, marker)
    assert translated == "\n".join([expected.format(file=relative, orig=orig), "unrelated text 3:4", ""])


def test_translate_log_ignores_mesas_source_zero_with_unique_lines():
    """Mesa reports semantic errors as source 0; the unique line number still names the file."""
    source = load_shader(FIXTURES / "main.glsl")
    _, line = driver_line(source, "lib/a.glsl", "A_MARKER")
    assert (
        source.translate_log(f"0:{line}(12): error: boom")
        == f"lib/a.glsl:{line_of('lib/a.glsl', 'A_MARKER')}(12): error: boom"
    )


def test_translate_log_leaves_unknown_sources_alone():
    """A source number outside the file table is not rewritten."""
    source = load_shader(FIXTURES / "main.glsl", unique_lines=False)
    assert source.translate_log("99:3(1): error: x") == "99:3(1): error: x"


# --- real OpenGL (Mesa llvmpipe through EGL) ------------------------------------------------------


@pytest.fixture(scope="module")
def ctx():
    """A GL 4.3 EGL context (compute shaders; Mesa's llvmpipe has them), or fail with the reason."""
    from volren.renderers.opengl import opengl_problem

    problem = opengl_problem()
    if problem:
        pytest.fail(problem, pytrace=False)
    import moderngl

    try:
        context = moderngl.create_standalone_context(backend="egl", require=430)
    except Exception as exc:  # moderngl/glcontext raise plain Exceptions
        pytest.fail(f"no OpenGL 4.3 context through EGL (Mesa too old?): {exc}", pytrace=False)
    yield context
    context.release()


@pytest.mark.gl
def test_compile_error_in_included_file_names_that_file(ctx):
    """The driver's error in lib/broken.glsl comes back as lib/broken.glsl:LINE, summary first."""
    source = load_shader(FIXTURES / "broken_main.glsl")
    with pytest.raises(ShaderCompileError) as info:
        compile_program(ctx, compute=source)
    line = line_of("lib/broken.glsl", "BROKEN_MARKER")
    message = str(info.value)
    assert message.startswith(f"compute shader (broken_main.glsl) did not compile: lib/broken.glsl:{line}(")
    assert "undeclared_name" in message
    assert isinstance(info.value, VolrenError)
    assert f"lib/broken.glsl:{line}(" in info.value.log and "\n" in info.value.log


@pytest.mark.gl
def test_syntax_error_in_main_file_after_include(ctx, tmp_path):
    """A syntax error after an include is reported in the main file at its own line."""
    (tmp_path / "inc.glsl").write_text("int f() { return 1; }\n")
    (tmp_path / "main.glsl").write_text(
        '#version 430\nlayout(local_size_x = 1) in;\n#include "inc.glsl"\n\nvoid main() {\n    int x = f()\n}\n'
    )
    with pytest.raises(ShaderCompileError, match=r"did not compile: main\.glsl:7\(1\): error: syntax error"):
        compile_program(ctx, compute=load_shader(tmp_path / "main.glsl", {"UNUSED": 1}))


@pytest.mark.gl
def test_defines_reach_the_driver(ctx):
    """A compute shader writes its #define'd values into a buffer."""
    source = load_shader(FIXTURES / "defines.glsl", {"VALUE": 1234, "FLAG": True, "SCALE": 1.5})
    shader = compile_program(ctx, compute=source)
    buffer = ctx.buffer(reserve=3 * 4)
    buffer.bind_to_storage_buffer(0)
    shader.run(1)
    ctx.finish()
    assert struct.unpack("3i", buffer.read()) == (1234, 1, 3)
    buffer.release()
    shader.release()
