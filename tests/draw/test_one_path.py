"""Only `volren.draw.frame` chooses how a frame is drawn: no other module outside the bricked
package (which defines them) imports the streamed or the cluster frame."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[2] / "volren"
#: The ways to draw a scene's frame other than `render_frame`, defined in volren/bricked (the
#: conformance kit and the bench call its `render_bricked` to test and measure bricks themselves).
FRAME_DRAWERS = {"render_streamed", "render_on_cluster"}


def drawers_imported(path: Path) -> set[str]:
    """The names of FRAME_DRAWERS that `path` imports (or reaches as an attribute)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.ImportFrom):
            found.update(alias.name for alias in node.names if alias.name in FRAME_DRAWERS)
        elif isinstance(node, ast.Attribute) and node.attr in FRAME_DRAWERS:
            found.add(node.attr)
    return found


def test_only_volren_draw_frame_draws_streamed_or_cluster_frames():
    callers = {
        path.relative_to(PACKAGE).as_posix()
        for path in PACKAGE.rglob("*.py")
        if not path.relative_to(PACKAGE).as_posix().startswith("bricked/") and drawers_imported(path)
    }
    assert callers == {"draw/frame.py"}
