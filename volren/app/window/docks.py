"""The dock widgets around the viewport, and the wiring between them and the window.

Right: the transfer-function editors (1D and 2D, with undo and redo). Left: the rendering
settings (lighting, sampling, blend mode, crop box, background) and, tabbed with them, the dataset
facts, the labels of a segmentation (`panels.labels`) and the channels of a multi-channel volume
(`panels.channels`). Every panel edits the window's `ViewState`; this module only places them, forwards their
errors to the window's one-line reporter, tells the settings panels what the current renderer can
do, and turns a Ctrl+click on the volume into a 2D TF widget at the picked value and gradient, or,
with labels drawn, into the selection of the label seen there (`core.label_picking`).
"""

from __future__ import annotations

from typing import Protocol

from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import (
    QDockWidget,
    QGroupBox,
    QMenu,
    QMenuBar,
    QScrollArea,
    QStatusBar,
    QVBoxLayout,
    QWidget,
)

from volren.app.core.state import Change, ViewState
from volren.app.panels import (
    BackgroundPanel,
    BlendPanel,
    ChannelsPanel,
    ClippingPanel,
    CropPanel,
    DatasetInfoPanel,
    LabelsPanel,
    LightingPanel,
    SamplingPanel,
)
from volren.app.rendering.viewport import Viewport
from volren.app.tf_editor.history import TFHistory
from volren.app.tf_editor.panel import TransferFunctionPanel
from volren.app.window.field_undo import FieldUndoKeys, set_undo_shortcuts
from volren.app.window.file_actions import FileActions
from volren.model.labels import LabelMap
from volren.model.volume import UniformVolume
from volren.renderers.base import KindSupport
from volren.renderers.registry import RendererRegistry


class DockHost(Protocol):
    """What the docks use of the window they are placed in (`MainWindow`, whose QMainWindow is also
    the parent of their widgets and actions): named here, so that the window imports the docks and
    the docks do not import the window."""

    state: ViewState
    registry: RendererRegistry
    viewport: Viewport
    files: FileActions
    view_menu: QMenu

    def report_error(self, title: str, message: str) -> None: ...
    def menuBar(self) -> QMenuBar: ...
    def statusBar(self) -> QStatusBar: ...
    def width(self) -> int: ...
    def addDockWidget(self, area: Qt.DockWidgetArea, dock: QDockWidget) -> None: ...
    def tabifyDockWidget(self, first: QDockWidget, second: QDockWidget) -> None: ...
    def resizeDocks(
        self, docks: list[QDockWidget], sizes: list[int], orientation: Qt.Orientation
    ) -> None: ...


def _titled(title: str, panel: QWidget) -> QWidget:
    box = QGroupBox(title)
    layout = QVBoxLayout(box)
    layout.setContentsMargins(4, 4, 4, 4)
    layout.addWidget(panel)
    return box


#: The narrowest a dock gets when the window is small (its content scrolls sideways below its own width).
DOCK_MIN_WIDTH = 160
#: Above this share of the window's width, the docks give way to the viewport on a resize.
DOCKS_MAX_SHARE = 0.5


def _scrolled(widget: QWidget) -> QScrollArea:
    """In a scroll area, so that longer text after a load (bounds, notes) never widens the dock
    and squeezes the viewport under the person's mouse, and a small window can make the dock
    narrower than its controls (they scroll) instead of leaving the viewport a sliver."""
    scroll = QScrollArea()
    scroll.setWidgetResizable(True)
    scroll.setWidget(widget)
    scroll.setMinimumWidth(DOCK_MIN_WIDTH)
    return scroll


class Docks:
    """Builds the docks of `window` and keeps them in step with its renderer."""

    def __init__(self, window: DockHost) -> None:
        self.window = window
        state = window.state
        self.history = TFHistory(state, window)
        self.tf_panel = TransferFunctionPanel(state, self.history, window, self.two_d_reason)
        self.lighting = LightingPanel(state)
        self.sampling = SamplingPanel(state)
        self.blend = BlendPanel(state)
        self.crop = CropPanel(state)
        self.clipping = ClippingPanel(state)
        self.background = BackgroundPanel(state)
        self.dataset = DatasetInfoPanel(state)
        self.labels = LabelsPanel(state)
        self.channels = ChannelsPanel(state)
        self.dataset.arrayChosen.connect(window.files.show_array)

        self.tf_dock = self._dock(
            "Transfer function", "tf-dock", _scrolled(self.tf_panel), Qt.RightDockWidgetArea
        )
        settings = QWidget()
        layout = QVBoxLayout(settings)
        layout.setContentsMargins(2, 2, 2, 2)
        for title, panel in (
            ("Lighting", self.lighting),
            ("Sampling", self.sampling),
            ("Blend mode", self.blend),
            ("Crop box", self.crop),
            ("Clip planes", self.clipping),
            ("Background", self.background),
        ):
            layout.addWidget(_titled(title, panel))
        layout.addStretch(1)
        self.settings_dock = self._dock(
            "Rendering", "settings-dock", _scrolled(settings), Qt.LeftDockWidgetArea
        )
        self.dataset_dock = self._dock(
            "Dataset", "dataset-dock", _scrolled(self.dataset), Qt.LeftDockWidgetArea
        )
        self.labels_dock = self._dock("Labels", "labels-dock", self.labels, Qt.LeftDockWidgetArea)
        window.tabifyDockWidget(self.settings_dock, self.dataset_dock)
        self.channels_dock = self._dock("Channels", "channels-dock", self.channels, Qt.LeftDockWidgetArea)
        window.tabifyDockWidget(self.dataset_dock, self.labels_dock)
        window.tabifyDockWidget(self.labels_dock, self.channels_dock)
        self.channels_dock.hide()  # shown when a volume with channels opens (View menu: any time)
        self.settings_dock.raise_()

        self.undo_action = self.history.stack.createUndoAction(window, "&Undo")
        self.redo_action = self.history.stack.createRedoAction(window, "&Redo")
        set_undo_shortcuts(self.undo_action, self.redo_action)
        #: Ctrl+Z in a number field undoes the app's edit once the value typed is entered.
        self.field_undo = FieldUndoKeys(self.undo_action, self.redo_action, window)
        self.field_undo.watch(
            (self.tf_dock, self.settings_dock, self.dataset_dock, self.labels_dock, self.channels_dock)
        )
        edit_menu = window.menuBar().addMenu("&Edit")
        edit_menu.addAction(self.undo_action)
        edit_menu.addAction(self.redo_action)
        window.view_menu.addSeparator()
        for dock in (
            self.tf_dock,
            self.settings_dock,
            self.dataset_dock,
            self.labels_dock,
            self.channels_dock,
        ):
            window.view_menu.addAction(dock.toggleViewAction())

        for source in (self.tf_panel, self.crop):
            source.errorOccurred.connect(window.report_error)
        window.viewport.pointPicked.connect(self.pick)
        self._unsubscribe = state.subscribe(self._on_change)
        self._shown_tf_dims = 1
        self._shown_labels: LabelMap | None = None
        self._shown_channels: object = None
        self._update_capabilities()

    def _dock(self, title: str, name: str, widget: QWidget, area: Qt.DockWidgetArea) -> QDockWidget:
        dock = QDockWidget(title, self.window)
        dock.setObjectName(name)
        dock.setWidget(widget)
        self.window.addDockWidget(area, dock)
        return dock

    def keep_viewport_share(self) -> None:
        """After a resize, narrow the side docks so that together they take at most
        DOCKS_MAX_SHARE of the window's width (docks kept their width while the window shrank:
        at 900x600 the viewport was 169 px wide)."""
        window = self.window
        docks = [d for d in (self.tf_dock, self.settings_dock) if d.isVisible() and not d.isFloating()]
        if not docks:
            return
        budget = DOCKS_MAX_SHARE * window.width()
        used = sum(d.width() for d in docks)
        if used <= budget:
            return
        widths = [d.width() * budget / used for d in docks]
        short = sum(max(DOCK_MIN_WIDTH - w, 0.0) for w in widths)  # what the minimums add back,
        room = sum(w - DOCK_MIN_WIDTH for w in widths if w > DOCK_MIN_WIDTH)  # taken from the wider ones
        widths = [
            DOCK_MIN_WIDTH if w <= DOCK_MIN_WIDTH else w - short * (w - DOCK_MIN_WIDTH) / room for w in widths
        ]
        window.resizeDocks(docks, [max(DOCK_MIN_WIDTH, int(w)) for w in widths], Qt.Horizontal)

    # ------------------------------------------------------------------ capabilities
    def two_d_reason(self, kind: str) -> str | None:
        """Why no registered renderer draws a 2D TF on `kind` volumes (the 2D tab then offers
        none: it used to make one, which failed to render and left every renderer greyed out)."""
        for name in self.window.registry.names():
            try:
                support = self.window.registry.capabilities(name).kinds.get(kind)  # type: ignore[call-overload]
            except Exception:  # noqa: BLE001 - a broken plugin is reported by the chooser
                continue
            if support is not None and 2 in support.tf_dims:
                return None
        return (
            f"No renderer draws 2D transfer functions on {'tetrahedral' if kind == 'tet' else kind} volumes"
        )

    def _on_change(self, change: Change) -> None:
        # a TF edit matters only when it changes the TF's dimension: during a drag, refreshing
        # three panels on every edit took the GUI thread's time from the render thread
        tf = self.window.state.transfer_function
        dims = tf.dims if tf is not None else 1
        if change.what in ("renderer", "volume") or (change.what == "tf" and dims != self._shown_tf_dims):
            self._shown_tf_dims = dims
            self._update_capabilities()
        if change.what == "volume":
            labels = self.window.state.labels
            if labels is not None and labels is not self._shown_labels:  # labels opened: their list in front
                self.labels_dock.show()
                self.labels_dock.raise_()
            self._shown_labels = labels
            channels = self.window.state.channels
            if channels is not None and channels is not self._shown_channels:  # their list in front
                self.channels_dock.show()
                self.channels_dock.raise_()
            self._shown_channels = channels

    def current_support(self) -> KindSupport | None:
        """What the current renderer can do with the loaded volume (None: unknown, allow all)."""
        state = self.window.state
        if state.volume is None:
            return None
        try:
            caps = self.window.registry.capabilities(state.renderer)
        except Exception:  # noqa: BLE001 - a broken plugin is reported by the chooser
            return None
        return caps.kinds.get(state.volume.kind)

    def _update_capabilities(self) -> None:
        support = self.current_support()
        for panel in (self.lighting, self.sampling, self.blend):
            panel.set_capabilities(support)

    # ------------------------------------------------------------------ picking
    def pick(self, x: int, y: int) -> None:
        """Ctrl+click on the volume: a 2D TF widget at the value and gradient seen there; with labels
        drawn, the label seen there selected in the Labels panel (`pick_label`)."""
        from volren.app.core.picking import pick

        window, state = self.window, self.window.state
        frame = window.viewport.frame
        if state.volume is None or state.transfer_function is None or state.camera is None or frame is None:
            return
        if state.labels_drawn:
            self.pick_label(x, y)
            return
        if state.transfer_function.dims != 2:
            window.statusBar().showMessage(
                "Ctrl+click places a widget of a 2D transfer function: switch to the 2D tab first", 8000
            )
            return
        width, height = window.viewport.pixel_size()
        try:
            hit = pick(state.render_volume, state.transfer_function, state.camera, x, y, width, height)
        except Exception as exc:  # noqa: BLE001 - picking must never take the app down
            window.report_error("Cannot pick", f"picking failed: {exc}")
            return
        if hit is None:
            window.statusBar().showMessage("Nothing there to pick", 5000)
            return
        self.tf_panel.editor_2d.place_widget_at(hit.value, hit.gradient_magnitude)
        window.statusBar().showMessage(
            f"Widget placed at value {hit.value:.4g}, gradient magnitude {hit.gradient_magnitude:.4g}", 8000
        )

    def pick_label(self, x: int, y: int) -> None:
        """Select the first visible label along the ray through pixel (x, y) in the Labels panel."""
        from volren.app.core.label_picking import pick_label

        window, state = self.window, self.window.state
        volume, label_tf, camera = state.render_volume, state.label_transfer_function, state.camera
        if not isinstance(volume, UniformVolume) or label_tf is None or camera is None:
            return
        width, height = window.viewport.pixel_size()
        try:
            hit = pick_label(volume, label_tf, camera, x, y, width, height)
        except Exception as exc:  # noqa: BLE001 - picking must never take the app down
            window.report_error("Cannot pick", f"picking a label failed: {exc}")
            return
        if hit is None:
            window.statusBar().showMessage("No label drawn there", 5000)
            return
        self.labels.select_label(hit.label)
        self.labels_dock.show()
        self.labels_dock.raise_()
        labels = state.labels
        name = labels.label_name(hit.label) if labels is not None else str(hit.label)
        window.statusBar().showMessage(f"Picked {name} (label {hit.label}): the 1D editor edits its TF", 8000)

    def detach(self) -> None:
        self._unsubscribe()
        self.tf_panel.detach()
        self.history.detach()
