"""File > Open Recent: the last opened (and saved) files, most recent first, kept across runs.

The list lives in QSettings (organisation "volren", application "volren", key `recent/files`),
so it survives restarts and is shared by every window. The QSettings object is injectable: tests
pass one backed by a temporary INI file and never touch the person's own settings.

Paths are stored absolute, so the list means the same from any working directory. A file that
disappeared stays in the list (a network drive may be back tomorrow) but shows greyed out and
cannot be chosen; "Clear" empties the list.
"""

from __future__ import annotations

import os
from pathlib import Path

from PyQt5.QtCore import QObject, QSettings, pyqtSignal
from PyQt5.QtWidgets import QAction, QMenu, QWidget

from volren.app.core.loading import PathArg

ORGANISATION = "volren"
APPLICATION = "volren"
KEY = "recent/files"
#: The folder the person last opened or saved something in: where file dialogs start.
FOLDER_KEY = "dialogs/folder"
LIMIT = 10


def app_settings() -> QSettings:
    """The app's own settings store (per user, native format)."""
    return QSettings(ORGANISATION, APPLICATION)


class RecentFiles(QObject):
    """The recent-files list over a QSettings; `changed` after every edit."""

    changed = pyqtSignal()

    def __init__(
        self, settings: QSettings | None = None, limit: int = LIMIT, parent: QObject | None = None
    ) -> None:
        super().__init__(parent)
        self._settings = settings if settings is not None else app_settings()
        self.limit = limit

    def paths(self) -> list[str]:
        """The stored paths, most recent first (at most `limit`)."""
        value = self._settings.value(KEY, [])
        if isinstance(value, str):  # INI files give a one-element list back as a plain string
            value = [value]
        if not isinstance(value, list):
            return []
        return [str(v) for v in value if isinstance(v, str) and v][: self.limit]

    def add(self, path: PathArg) -> None:
        """Put `path` first (moving it up when it is already listed); its folder is where the
        next file dialog starts."""
        entry = os.path.abspath(os.fspath(path))
        self._store([entry, *(p for p in self.paths() if p != entry)])
        self.remember_folder(entry)

    def folder(self) -> str:
        """Where file dialogs start: the folder last opened or saved in, "" (the working folder)
        when none is known or it is gone."""
        value = self._settings.value(FOLDER_KEY, "")
        return value if isinstance(value, str) and value and os.path.isdir(value) else ""

    def remember_folder(self, path: PathArg) -> None:
        """`path`'s folder (or `path`, a folder) is where the person works now."""
        entry = os.path.abspath(os.fspath(path))
        self._settings.setValue(FOLDER_KEY, entry if os.path.isdir(entry) else os.path.dirname(entry))

    def remove(self, path: PathArg) -> None:
        entry = os.path.abspath(os.fspath(path))
        self._store([p for p in self.paths() if p != entry])

    def clear(self) -> None:
        self._store([])

    def _store(self, paths: list[str]) -> None:
        self._settings.setValue(KEY, paths[: self.limit])
        self._settings.sync()  # other windows and the next run see it at once
        self.changed.emit()


class RecentFilesMenu(QMenu):
    """The "Open Recent" submenu; rebuilt each time it opens, so missing files show as such."""

    fileChosen = pyqtSignal(str)

    def __init__(self, recent: RecentFiles, parent: QWidget | None = None) -> None:
        super().__init__("Open &Recent", parent)
        self._recent = recent
        self.clear_action = QAction("&Clear", self, triggered=recent.clear)
        self.aboutToShow.connect(self.rebuild)
        recent.changed.connect(self.rebuild)
        self.rebuild()

    def rebuild(self) -> None:
        """One entry per path ("1 bonsai.vti  (/data)"), greyed when the file is gone; then Clear."""
        for action in self.actions():  # QMenu.clear() would delete clear_action too
            self.removeAction(action)
            if action is not self.clear_action:
                action.deleteLater()
        paths = self._recent.paths()
        for number, path in enumerate(paths, start=1):
            self.addAction(self._entry(number, path))
        if not paths:
            empty = self.addAction("No recent files")
            empty.setEnabled(False)
        self.addSeparator()
        self.addAction(self.clear_action)
        self.clear_action.setEnabled(bool(paths))

    def _entry(self, number: int, path: str) -> QAction:
        p = Path(path)
        label = f"{p.name or path}  ({p.parent})".replace("&", "&&")
        accelerator = f"&{number} " if number < 10 else f"{number} "
        action = QAction(accelerator + label, self)
        action.setData(path)
        if p.exists():
            action.setToolTip(path)
            action.setStatusTip(path)
            action.triggered.connect(lambda _checked=False, chosen=path: self.fileChosen.emit(chosen))
        else:
            action.setEnabled(False)
            action.setToolTip(f"{path} (missing)")
            action.setStatusTip(f"{path} is missing")
        return action

    def entries(self) -> list[QAction]:
        """The file entries, in menu order (for tests and keyboard-free use)."""
        return [a for a in self.actions() if isinstance(a.data(), str)]
