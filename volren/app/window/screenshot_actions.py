"""File > Save Screenshot: the view rendered at a chosen size in the background (with a progress
dialog that can cancel it), or the viewport or the whole window grabbed as shown."""

from __future__ import annotations

from collections.abc import Callable

from PyQt5.QtGui import QKeySequence
from PyQt5.QtWidgets import QAction, QMainWindow

from volren.app.core.loading import PathArg
from volren.app.core.state import ViewState
from volren.app.files import screenshot_dialog
from volren.app.files.screenshot import ScreenshotJob, Screenshotter, check_writable
from volren.app.rendering.render_service import RendererFactory
from volren.app.rendering.viewport import Viewport
from volren.app.window.job_progress import FileJobActions
from volren.errors import VolrenError

ERROR_TITLE = "Cannot save the screenshot"


class ScreenshotActions(FileJobActions):
    """The Save Screenshot action, its dialog, `render` and `save`; `saved(path)` after each PNG."""

    def __init__(
        self,
        window: QMainWindow,
        state: ViewState,
        viewport: Viewport,
        renderer_factory: RendererFactory,
        report_error: Callable[[str, str], None],
        folder: Callable[[], str] | None = None,
    ) -> None:
        """`folder()`: where the person works now (the first screenshot is proposed there)."""
        self.screenshotter = Screenshotter(renderer_factory)
        super().__init__(window, self.screenshotter, ERROR_TITLE, "volren.png", report_error, folder)
        self._state = state
        self._viewport = viewport
        self.action = QAction(
            "Save Screens&hot…", window, shortcut=QKeySequence("Ctrl+Shift+S"), triggered=self._dialog
        )
        self.action.setToolTip("Render the view at a chosen resolution and save it as PNG")

    def save(self, path: PathArg, whole_window: bool = False) -> bool:
        """Write the viewport (or the whole window) as shown, as PNG; reports and returns False on
        failure. `render` renders at a chosen size instead."""
        try:
            check_writable(path)  # Qt would write into a device, or wait on a FIFO for a reader
        except VolrenError as exc:
            self._report_error(ERROR_TITLE, str(exc))
            return False
        pixmap = (self._window if whole_window else self._viewport).grab()
        if not pixmap.save(str(path), "PNG"):
            self._report_error(ERROR_TITLE, f"{path}: cannot write a PNG file there")
            return False
        self._on_saved(str(path))
        return True

    def render(self, path: PathArg, width: int, height: int) -> bool:
        """Render a full-quality `width` x `height` frame of the view with the current renderer in
        the background and write it as PNG (`saved` or a reported error follow); False when it
        cannot even start (nothing shown, a folder that cannot be written)."""
        try:
            check_writable(path)
            job = ScreenshotJob.of_view(self._state, path, width, height)
        except VolrenError as exc:
            self._report_error(ERROR_TITLE, str(exc))
            return False
        self._show_progress("Save screenshot", f"Rendering {job.width} x {job.height} with {job.renderer}…")
        self.screenshotter.start(job)
        return True

    def _dialog(self) -> None:
        choice = screenshot_dialog.ask_screenshot(
            self._window, self._proposed_path(), self._viewport.pixel_size()
        )
        if choice is None:
            return
        self._path = choice.path
        if choice.whole_window:
            self.save(choice.path, whole_window=True)
        else:
            self.render(choice.path, choice.width, choice.height)
