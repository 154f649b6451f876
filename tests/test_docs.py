"""The documentation is a map: a short README that links to docs/, links that lead somewhere, and
no work-session references ("stop 12", "issue 3", "seed 003") in the code or the docs, which cite
the paper or book and its section instead (a reader outside the project can resolve those)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
README = REPO / "README.md"
MAX_README_LINES = 200
#: Where session references may not appear: the package, the plugins, the benchmarks and every page.
SEARCHED = ("volren", "plugins", "benchmarks", "docs", "README.md", "BENCHMARKS.md", "CHANGELOG.md")
#: The pages, where a path on the machine that wrote them means nothing to a reader.
PAGES = ("docs", "README.md", "BENCHMARKS.md", "CHANGELOG.md")
MACHINE_PATH = re.compile(r"(?<![\w.~-])/(?:work|home|root|tmp|Users)/")
SESSION_REFERENCE = re.compile(r"stop [0-9]+|issue [0-9]+|seed 00[0-9]|00[0-9] seed", re.IGNORECASE)
#: Markdown links and images: [text](target) and ![alt](target).
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
#: Pages whose relative links must all resolve: the README and the docs' map, then every page it lists.
LINKED_PAGES = (README, REPO / "docs" / "index.md")


def text_files(root: Path):
    """Every text file under `root` (or `root` itself), without caches and build metadata."""
    paths = [root] if root.is_file() else sorted(p for p in root.rglob("*") if p.is_file())
    for path in paths:
        if "__pycache__" in path.parts or any(part.endswith(".egg-info") for part in path.parts):
            continue
        data = path.read_bytes()
        if b"\0" in data:
            continue  # binary: images, arrays
        try:
            yield path, data.decode("utf-8")
        except UnicodeDecodeError:
            continue


def relative_links(page: Path) -> list[str]:
    """The targets of `page`'s links that are paths in this repository (no URLs, no bare anchors)."""
    text = re.sub(r"```.*?```", "", page.read_text(encoding="utf-8"), flags=re.S)
    return [t for t in LINK.findall(text) if not re.match(r"[a-z][a-z0-9+.-]*:|#", t)]


def test_the_readme_is_short():
    lines = README.read_text(encoding="utf-8").count("\n")
    assert lines <= MAX_README_LINES, f"README.md has {lines} lines; the details belong in docs/"


def lines_matching(pattern: re.Pattern[str], roots: tuple[str, ...]) -> list[str]:
    """ "file:line: text" for each line under `roots` (relative to the repository) that `pattern` finds."""
    return [
        f"{path.relative_to(REPO)}:{number}: {line.strip()[:100]}"
        for root in roots
        for path, text in text_files(REPO / root)
        for number, line in enumerate(text.splitlines(), 1)
        if pattern.search(line)
    ]


def test_no_session_references_in_code_or_docs():
    assert lines_matching(SESSION_REFERENCE, SEARCHED) == []


def test_no_machine_paths_in_the_pages():
    assert lines_matching(MACHINE_PATH, PAGES) == []


@pytest.mark.parametrize("page", LINKED_PAGES, ids=lambda p: p.relative_to(REPO).as_posix())
def test_relative_links_lead_to_files(page):
    missing = [t for t in relative_links(page) if not (page.parent / t.split("#")[0]).exists()]
    assert missing == [], f"{page.relative_to(REPO)} links to what does not exist"


def test_the_pages_the_map_lists_link_to_files_too():
    index = REPO / "docs" / "index.md"
    pages = {
        (index.parent / t.split("#")[0]).resolve()
        for t in relative_links(index)
        if t.split("#")[0].endswith(".md")
    }
    missing = [
        f"{page.relative_to(REPO)} -> {t}"
        for page in sorted(pages)
        for t in relative_links(page)
        if not (page.parent / t.split("#")[0]).exists()
    ]
    assert missing == []
