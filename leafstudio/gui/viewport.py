"""The 3D view: a pyvistaqt QtInteractor showing a Result's layers, with camera presets.

Every actor has a fixed name, so a new result replaces the old actors instead of piling up.
Main thread only (VTK rendering).
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import Signal
from PySide6.QtWidgets import QVBoxLayout, QWidget
from pyvistaqt import QtInteractor

from leafstudio.gui.layers import LAYERS, MESH_COLORINGS, SCALAR_BARS, Piece

CAMERAS = ("iso", "top", "side")


class Viewport(QWidget):
    """Draws layers of pieces; `rendered` fires after each new result is on screen."""

    rendered = Signal()

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.plotter = QtInteractor(self, auto_update=False)
        self.plotter.set_background("white", top="#dfe8f0")
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.plotter.interactor)
        self.visible = {key: on for key, _, on in LAYERS}
        self.show_edges = False
        self.mesh_coloring = "height"
        self._bar_titles = {
            "mesh": {label for label, _ in MESH_COLORINGS.values()},
            "probability": {SCALAR_BARS["probability"]},
        }
        self._mesh_piece: Piece | None = None
        self._names: dict[str, list[str]] = {key: [] for key, _, _ in LAYERS}
        self._normal = np.array([0.0, 0.0, 1.0])
        self._long_axis = np.array([1.0, 0.0, 0.0])
        self._has_content = False
        self._message = ""
        self._pieces: dict[str, list[Piece]] = {}
        self._announce = False
        self.plotter.render_window.AddObserver("EndEvent", self._on_render_end)

    # --- layers --------------------------------------------------------------------------------
    def show_layers(
        self, layers: dict[str, list[Piece]], normal: np.ndarray, axis: np.ndarray
    ) -> None:
        """Replace every layer by the given pieces; `normal` and `axis` orient the camera presets
        (the leaf plane's normal and long axis, world coordinates)."""
        first = not self._has_content
        self._normal, self._long_axis = np.asarray(normal, float), np.asarray(axis, float)
        for key, pieces in layers.items():
            self._pieces[key] = pieces
            if self.visible[key]:
                self._draw_layer(key)
            else:  # drawn when switched on: hidden layers cost nothing per result
                self._remove_layer(key)
        self._sync_scalar_bars()
        self._has_content = True
        self.set_message("", render=False)
        if first:
            self.camera("iso", render=False)
        self._announce = True
        self.redraw()

    def set_layer(self, key: str, pieces: list[Piece]) -> None:
        """Replace one layer's pieces (the scan and Poisson layers, which come apart from
        results); drawn now if the layer is on, else when it is switched on."""
        self._pieces[key] = pieces
        if self.visible[key]:
            self._draw_layer(key)
        else:
            self._remove_layer(key)
        self.redraw()

    def redraw(self) -> None:
        """Schedule one render of the scene (at the next paint; VTK renders in paintGL)."""
        self.plotter.interactor.update()

    def _on_render_end(self, *_: object) -> None:
        if self._announce:
            self._announce = False
            self.rendered.emit()

    def _draw_layer(self, key: str) -> None:
        pieces = self._pieces.get(key, [])
        names = [piece.name for piece in pieces]
        for stale in set(self._names[key]) - set(names):
            self.plotter.remove_actor(stale, render=False)
        for piece in pieces:
            self._add(key, piece)
        self._names[key] = names

    def _remove_layer(self, key: str) -> None:
        for name in self._names[key]:
            self.plotter.remove_actor(name, render=False)
        self._names[key] = []

    def _add(self, key: str, piece: Piece) -> None:
        style = dict(piece.style)
        if key == "mesh":
            self._mesh_piece = piece
            coloring = self.mesh_coloring if self.mesh_coloring in piece.ranges else "height"
            style.update(
                show_edges=self.show_edges,
                scalars=coloring,
                cmap=MESH_COLORINGS[coloring][1],
                clim=piece.ranges.get(coloring),
            )
        if piece.data.n_points == 0:
            self.plotter.remove_actor(piece.name, render=False)
            return
        actor = self.plotter.add_mesh(
            piece.data,
            name=piece.name,
            show_scalar_bar=False,
            reset_camera=False,
            render=False,
            **style,
        )
        if key == "mesh":
            actor.prop.interpolation = "phong"
        actor.SetVisibility(self.visible[key])

    def clear(self) -> None:
        """Remove every layer (a new, still empty sketch)."""
        for key in self._names:
            self._remove_layer(key)
        self._pieces.clear()
        self._mesh_piece = None
        self._sync_scalar_bars()
        self._has_content = False
        self.redraw()

    def actor_names(self, key: str) -> list[str]:
        """Names of the actors currently drawn for layer `key`."""
        return [n for n in self._names[key] if n in self.plotter.actors]

    def set_visible(self, key: str, on: bool) -> None:
        """Switch a layer on or off."""
        self.visible[key] = on
        if on and not self.actor_names(key):
            self._draw_layer(key)
        for name in self.actor_names(key):
            self.plotter.actors[name].SetVisibility(on)
        self._sync_scalar_bars()
        self.redraw()

    def set_mesh_coloring(self, name: str) -> None:
        """Colour the mesh by a point array of MESH_COLORINGS (height when the mesh lacks it)."""
        self.mesh_coloring = name
        if self._mesh_piece is not None and "mesh" in self.plotter.actors:
            self._add("mesh", self._mesh_piece)
            self._sync_scalar_bars()
            self.redraw()

    def set_edges(self, on: bool) -> None:
        """Show or hide the mesh's triangle edges."""
        self.show_edges = on
        for name in self.actor_names("mesh"):
            self.plotter.actors[name].prop.show_edges = on
        self.redraw()

    def _sync_scalar_bars(self) -> None:
        for key, title in SCALAR_BARS.items():
            if key == "mesh" and self._mesh_piece is not None:
                coloring = self.mesh_coloring
                title = MESH_COLORINGS[
                    coloring if coloring in self._mesh_piece.ranges else "height"
                ][0]
            names = self.actor_names(key)
            wanted = self.visible[key] and bool(names)
            for stale in self._bar_titles[key] & set(self.plotter.scalar_bars.keys()):
                self.plotter.remove_scalar_bar(stale, render=False)
            if wanted:
                left = {"mesh": 0.06, "probability": 0.54}[key]  # side by side along the bottom
                self.plotter.add_scalar_bar(
                    title=title,
                    mapper=self.plotter.actors[names[0]].mapper,
                    vertical=False,
                    position_x=left,
                    position_y=0.02,
                    width=0.4,
                    height=0.08,
                    color="#202020",
                    fmt="%.3g",
                    n_labels=2,  # the ends only: a middle label would sit under the title
                    title_font_size=14,
                    label_font_size=12,
                    render=False,
                )

    def set_message(self, text: str, render: bool = True) -> None:
        """A line of text over the view (a failure's message), or none."""
        if text == self._message:
            return
        self._message = text
        if text:
            self.plotter.add_text(
                text, position="upper_left", font_size=10, color="#b00020", name="message"
            )
        else:
            self.plotter.remove_actor("message", render=False)
        if render:
            self.redraw()

    # --- camera --------------------------------------------------------------------------------
    def camera(self, preset: str, render: bool = True) -> None:
        """Look at the leaf from the top (along its normal), the side (along its width) or iso."""
        n, u = self._normal, self._long_axis
        v = np.cross(n, u)
        direction = {"top": n, "side": -v, "iso": 0.45 * n - 0.75 * v - 0.45 * u}[preset]
        up = u if preset == "top" else n
        self.plotter.reset_camera(render=False)
        focus = np.asarray(self.plotter.camera.focal_point)
        distance = self.plotter.camera.distance
        self.plotter.camera_position = [
            tuple(focus + distance * direction / np.linalg.norm(direction)),
            tuple(focus),
            tuple(up),
        ]
        self.plotter.reset_camera(render=False)
        self.plotter.camera.zoom(1.1)
        if render:
            self.redraw()

    def close_plotter(self) -> None:
        """Release VTK resources (before the window goes)."""
        self.plotter.close()
