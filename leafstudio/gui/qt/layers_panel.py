"""The Layers dock's panel: a checkable list of the 3D view's layers (gui/model/layers.py), the
mesh's edges, what its colours show, and the camera presets. Features add their widgets below
(`add_widget`: explain.py's view aids)."""

from __future__ import annotations

from collections.abc import Callable

from PySide6.QtCore import Qt
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QHBoxLayout,
    QListWidget,
    QListWidgetItem,
    QPushButton,
    QVBoxLayout,
    QWidget,
)

from leafstudio.gui.model.layers import LAYERS, MESH_COLORINGS, unavailable
from leafstudio.gui.model.textures import LEAF, LEAF_LABEL, TEXTURE, TEXTURE_LABEL
from leafstudio.gui.qt.view_camera import CAMERAS

COLORING_TIP = (
    "What the mesh's colours show: the leaf as it looks (its texture lit as a leaf: green, "
    "veins, a sheen, its underside lighter as if lit through; the default but for scans), its "
    "height above the leaf's plane, how it bends "
    "(mean or Gaussian curvature; red bends one way, blue the other), or the texture an "
    "export writes (blade and veins, the photo the leaf came from, or the image chosen "
    "in Export mesh) mapped through the mesh's UVs, as Blender shows it."
)


class LayersPanel(QWidget):
    """The layer list (`list`: each item's UserRole data is its layer key), `edges`, `coloring`
    (each item's data LEAF, a MESH_COLORINGS name or TEXTURE) and a button per camera preset."""

    def __init__(self, camera: Callable[[str], object], parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.list, self.edges = QListWidget(), QCheckBox("Show mesh edges")
        self._missing: set[str] = set()  # layers whose extra is not installed
        for key, label, on in LAYERS:
            item = QListWidgetItem(label)
            item.setData(Qt.ItemDataRole.UserRole, key)
            item.setFlags(item.flags() | Qt.ItemFlag.ItemIsUserCheckable)
            item.setCheckState(Qt.CheckState.Checked if on else Qt.CheckState.Unchecked)
            if why := unavailable(key):  # a missing extra: said where the user looks
                item.setFlags(item.flags() & ~Qt.ItemFlag.ItemIsEnabled)
                item.setCheckState(Qt.CheckState.Unchecked)
                item.setToolTip(why)
                self._missing.add(key)
            self.list.addItem(item)
        self.set_available("scan", False)  # until a scan is open
        self.set_available("blade", False)  # until a bent leaf is shown (reports._show_result)
        self.list.setMaximumHeight(self.list.sizeHintForRow(0) * len(LAYERS) + 8)
        self.edges.setToolTip("Draw the triangles' edges on the mesh.")
        self.coloring = QComboBox()
        self.coloring.addItem(LEAF_LABEL, LEAF)
        for name, (label, _) in MESH_COLORINGS.items():
            self.coloring.addItem(f"Colour by {label}", name)
        self.coloring.addItem(f"Show the {TEXTURE_LABEL}", TEXTURE)
        self.coloring.setToolTip(COLORING_TIP)
        cameras = QHBoxLayout()
        for preset in CAMERAS:
            button = QPushButton(preset.capitalize())
            button.setToolTip(f"Look at the leaf from the {preset} view.")
            button.clicked.connect(lambda _=False, p=preset: camera(p))
            cameras.addWidget(button)
        column = QVBoxLayout(self)
        column.addWidget(self.list)
        column.addWidget(self.edges)
        column.addWidget(self.coloring)
        column.addLayout(cameras)
        column.addStretch(1)

    def add_widget(self, widget: QWidget) -> None:
        """A feature's widget under the presets (above the stretch)."""
        layout = self.layout()
        layout.insertWidget(max(layout.count() - 1, 0), widget)

    def _item(self, key: str) -> QListWidgetItem:
        return next(
            item
            for item in map(self.list.item, range(self.list.count()))
            if item.data(Qt.ItemDataRole.UserRole) == key
        )

    def set_checked(self, key: str, on: bool) -> None:
        """Check or uncheck layer `key`'s item (its view follows through itemChanged); one whose
        extra is missing stays unchecked."""
        if key not in self._missing:
            state = Qt.CheckState.Checked if on else Qt.CheckState.Unchecked
            self._item(key).setCheckState(state)

    def set_available(self, key: str, available: bool) -> None:
        """Grey out layer `key`'s item while it has nothing to show (the scan's points while no
        scan is open: ticked, it looked shown), its tick kept for when it has; one whose extra
        is missing stays greyed out."""
        item = self._item(key)
        enabled = available and key not in self._missing
        flags = item.flags() & ~Qt.ItemFlag.ItemIsEnabled
        item.setFlags(flags | Qt.ItemFlag.ItemIsEnabled if enabled else flags)
