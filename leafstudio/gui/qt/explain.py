"""The app explaining itself: a tooltip on every layer tying it to the paper, view aids (height
exaggeration, a kept colour range, K in the view), and File > Export of a turntable (GIF or MP4)
and of the steps side by side (PNG) for slides (render/slides.py). The steps one at a time, in
plain words, are the lesson (View > Lesson, lesson_view.py).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PySide6.QtCore import Qt
from PySide6.QtWidgets import (
    QCheckBox,
    QDoubleSpinBox,
    QFileDialog,
    QHBoxLayout,
    QLabel,
    QVBoxLayout,
    QWidget,
)
from vtkmodules.vtkCommonMath import vtkMatrix4x4  # one module: `import vtk` loads every one

from leafstudio.gui.model.view_aids import STRETCH_OFF, k_label, stretches
from leafstudio.gui.qt.actions import Action

# each layer's tooltip: what it shows and which step of the paper it comes from
LAYER_HELP: dict[str, str] = {
    "mesh": "The reconstructed surface (step 6), coloured as chosen below: z(x) = b(x) + "
    "tanh(g/δ) Σ a_k N(x | μ_k, Σ_k), trimmed at the margin.",
    "points": "The input: boundary points (black) and vein points (a colour per vein), with the "
    "heights the surface must follow.",
    "curves": "The boundary and vein curves through the input points, in order.",
    "blade": "A bent leaf laid flat, as the method works on it: its outline and input points "
    "unbent onto the flat blade, where g, its zero contour, p(x) and the EM samples are drawn "
    "(the mesh is bent back from it).",
    "contour": "The zero contour of g (eqs. 1-2), drawn on top: the MPU implicit of the "
    "outline is positive inside, negative outside; this line is where the surface is cut.",
    "implicit": "g(x), the MPU implicit of the outline (eqs. 1-2), coloured over the surface "
    "and around it: blue inside the leaf (g > 0), red outside (g < 0), white on the margin.",
    "probability": "p(x), the height guide (eqs. 4-5), coloured over the surface: each point "
    "takes the nearest vein's height, falling to zero at the margin; the mixture is fitted to "
    "it.",
    "samples": "The GMM samples: the kept grid nodes lifted to the fitted surface z(x).",
    "em": "The EM samples: points drawn where p(x) is large, each coloured by the Gaussian that "
    "owns it, with each Gaussian's 1σ (thick) and 2σ (thin) ellipses.",
    "scan": "A scan of the real leaf, if one is open, to compare the surface with.",
    "poisson": "Screened Poisson's surface from the same points, beside ours: it spills past "
    "the margin (the paper's Fig. 10).",
}


def add_layer_help(window) -> None:
    """Give each item of the window's layer list its LAYER_HELP tooltip, after what the item
    says already (the extra a disabled layer needs)."""
    layers = window.layer_list
    for i in range(layers.count()):
        item = layers.item(i)
        text = LAYER_HELP.get(item.data(Qt.ItemDataRole.UserRole))
        if text:
            item.setToolTip(f"{item.toolTip()}\n\n{text}" if item.toolTip() else text)


SEE_THROUGH = 0.35  # the mesh's opacity when the layers under it should show
K_FONT_PX = 24  # K's label in the view: its size in logical pixels (VTK points at 72 DPI)
K_POSITION = (0.985, 0.98)  # its upper right corner, in the view's normalized coordinates


def stretch_matrix(result, scale: float):
    """A vtkMatrix4x4 stretching the view `scale` times along the leaf's normal, about its plane
    (None for no stretch, no result, or a posed leaf: view_aids.stretches): relief is a few
    percent of a leaf's length."""
    if result is None or scale == 1.0 or not stretches(result):
        return None
    n, o = np.asarray(result.frame.normal), np.asarray(result.frame.origin)
    linear = np.eye(3) + (scale - 1.0) * np.outer(n, n)  # stretch along the normal only
    m = np.eye(4)
    m[:3, :3] = linear
    m[:3, 3] = o - linear @ o  # about the leaf's plane
    matrix = vtkMatrix4x4()
    for i in range(4):
        for j in range(4):
            matrix.SetElement(i, j, float(m[i, j]))
    return matrix


class ViewAids(QWidget):
    """Height exaggeration (the relief is a few percent of the length), a colour range kept
    while K changes (so K's effect shows), and K written in the view. They act on the actors the
    viewport drew, after each result and layer change: the viewport's own code is unchanged."""

    def __init__(self, window) -> None:
        super().__init__()
        self.window_ = window
        self.exaggeration = QDoubleSpinBox()
        self.exaggeration.setRange(1.0, 20.0)
        self.exaggeration.setSingleStep(0.5)
        self.exaggeration.setPrefix("Height × ")
        self.exaggeration.setToolTip(
            "Stretch the view along the leaf's normal: relief is a few percent of the length. "
            "Only the view changes, never the mesh or its files."
        )
        self.keep = QCheckBox("Keep the colour range")
        self.keep.setToolTip(
            "Keep the mesh's colour range as it is now while K or other settings change, so the "
            "effect of K shows as a change of colour."
        )
        self.see_through = QCheckBox("See-through mesh")
        self.see_through.setToolTip(
            "Draw the mesh translucent, so the layers under it (p(x), the zero contour of g, the "
            "EM samples) can be read with the mesh shown."
        )
        self.kept: tuple[str, tuple[float, float]] | None = None
        self._label: tuple[str, str, int] | None = None  # K's text, colour and size, as drawn
        column = QVBoxLayout(self)
        column.setContentsMargins(0, 0, 0, 0)
        row = QHBoxLayout()
        row.addWidget(self.exaggeration)
        row.addWidget(self.see_through)
        column.addLayout(row)
        column.addWidget(self.keep)
        self.stretch_note = QLabel(STRETCH_OFF)
        self.stretch_note.setWordWrap(True)
        self.stretch_note.setStyleSheet("color: #b00020;")
        self.stretch_note.hide()
        column.addWidget(self.stretch_note)
        self.exaggeration.valueChanged.connect(lambda _: self.apply())
        self.see_through.toggled.connect(lambda _: self.apply())
        self.keep.toggled.connect(self._on_keep)

    def _mesh_actor(self):
        return self.window_.viewport.plotter.actors.get("mesh")

    def _on_keep(self, on: bool) -> None:
        actor = self._mesh_actor()
        self.kept = None
        if on and actor is not None:
            self.kept = (actor.mapper.array_name, tuple(actor.mapper.scalar_range))
        self.apply()

    def _matrix(self):
        return stretch_matrix(self.window_.session.result, self.exaggeration.value())

    def apply(self) -> None:
        """Exaggeration, kept colours and K's label on what the viewport shows now."""
        plotter = self.window_.viewport.plotter
        matrix = self._matrix()
        for name, actor in plotter.actors.items():
            if name != "k_label" and hasattr(actor, "SetUserMatrix"):
                actor.SetUserMatrix(matrix)
        actor = self._mesh_actor()
        if actor is not None:
            actor.prop.opacity = SEE_THROUGH if self.see_through.isChecked() else 1.0
        if self.kept is not None and actor is not None and actor.mapper.array_name == self.kept[0]:
            actor.mapper.scalar_range = self.kept[1]
        result = self.window_.session.result
        if result is not None:
            self._show_k(k_label(result))
        off = result is not None and self.exaggeration.value() != 1.0 and not stretches(result)
        self.stretch_note.setVisible(off)  # Height × set, and off for this bent leaf
        # one render at the next paint, with the result's own: a render here would be a second
        # (and a third, from the frame it ends with) full render of the scene per result
        self.window_.viewport.redraw()

    def _show_k(self, text: str) -> None:
        """K in the view's upper right corner: one text actor, its string set in place (a
        corner annotation fits its font anew whenever its text changes, about 15 ms of the
        main thread's time in every render that follows a result)."""
        import pyvista as pv

        plotter, viewport = self.window_.viewport.plotter, self.window_.viewport
        # in points: the Qt VTK widgets set the render window's DPI to 72 x the pixel ratio,
        # and VTK scales text by it (scaling by the ratio here too made it twice too large)
        label = (text, viewport.text_color(), K_FONT_PX)
        actor = plotter.actors.get("k_label")
        if not isinstance(actor, pv.Text):
            actor = pv.Text(text)
            actor.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
            actor.SetPosition(*K_POSITION)
            actor.prop.justification_horizontal = "right"
            actor.prop.justification_vertical = "top"
            plotter.add_actor(
                actor, name="k_label", reset_camera=False, pickable=False, render=False
            )
        elif label == self._label:
            return
        actor.input = label[0]
        actor.prop.color = label[1]
        actor.prop.font_size = label[2]
        self._label = label


def export_slide(window, kind: str, path: str):
    """Start writing the shown result's turntable or steps figure to `path` in the background
    (exports.py: its off-screen renders run in the export process, not on this thread): the
    job's handle, or None if refused (an error box says why)."""
    from leafstudio.errors import LeafError
    from leafstudio.gui.model.exports import slide
    from leafstudio.render.slides import check_turntable_path

    result = window.session.result
    if result is None:
        window.show_error("Nothing to export", "There is no reconstructed leaf yet.")
        return None
    try:
        name = (check_turntable_path(path) if kind == "turntable" else Path(path)).name
    except LeafError as exc:
        window.show_error("Cannot export", str(exc))
        return None
    return window.run_export(name, slide, kind, result, path)


def install(window) -> ViewAids:
    """Add File > Export turntable / steps figure (rows of the window's action table), a
    tooltip on every layer, and the view aids (height exaggeration, kept colour range, K) under
    the layers; returns the view aids."""
    add_layer_help(window)
    aids = ViewAids(window)
    window.layers.add_widget(aids)
    window.result_shown.connect(lambda _outcome: aids.apply())
    window.layer_list.itemChanged.connect(lambda _item: aids.apply())
    window.coloring.currentIndexChanged.connect(lambda _row: aids.apply())
    window.edges.toggled.connect(lambda _on: aids.apply())
    window.add_actions(explain_actions())
    return aids


def explain_actions() -> tuple[Action, ...]:
    """The exports for slides, as rows of the window's action table."""

    def ask(window, kind: str, caption: str, filters: str, suffix: str) -> None:
        path, _ = QFileDialog.getSaveFileName(window, caption, "", filters)
        if path:
            export_slide(window, kind, path if "." in path.rsplit("/", 1)[-1] else path + suffix)

    exports = tuple(
        Action(
            f"file.export_{kind}",
            "File",
            text,
            lambda w, k=kind, t=text, f=filters, s=suffix: ask(w, k, t.replace("&", ""), f, s),
            before="file.quit",
        )
        for kind, text, filters, suffix in (
            ("turntable", "Export &turntable…", "Animations (*.gif *.mp4)", ".gif"),
            ("steps", "Export steps &figure…", "PNG (*.png)", ".png"),
        )
    )
    return exports
