"""The 3D view: a pyvista Plotter widget (native_view.py) showing a Result's layers, with camera
presets (view_camera.py).

Every actor has a fixed name; a new result's dataset is copied into the actor already drawn
(a shallow copy, no new actor, mapper or lookup table), so that what follows a result on the main
thread stays short. The camera frames the blade's robust bounds (framing.py) when the session
says so, and otherwise stays where the user put it. Point and line sizes follow the device pixel
ratio; the background and text follow the palette. Main thread only (VTK rendering).
"""

from __future__ import annotations

from functools import partial
from typing import Any

import numpy as np
from PySide6.QtCore import QEvent, QPoint, QRect, Signal
from PySide6.QtGui import QImage, QPainter, QPalette, QPixmap
from PySide6.QtWidgets import QVBoxLayout, QWidget

from leafstudio.core.plane import Frame
from leafstudio.gui.model.fields import bar_format
from leafstudio.gui.model.framing import BladeBounds
from leafstudio.gui.model.layers import BOUNDARY_COLOR, LAYERS, MESH_COLORINGS, SCALAR_BARS, Piece
from leafstudio.gui.model.textures import LEAF, SHOWS_TEXTURE
from leafstudio.gui.qt.native_view import make_plotter
from leafstudio.gui.qt.turns import later
from leafstudio.gui.qt.view_camera import CameraPlacing

SIZED = ("point_size", "line_width")  # style keys in device pixels: scaled by the pixel ratio

MINIMUM_SIZE = (360, 240)  # the view's least width and height, in pixels


class Viewport(CameraPlacing, QWidget):
    """Draws layers of pieces; `rendered` fires after each new result is on screen."""

    rendered = Signal()

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.plotter = make_plotter(self)
        drop_back_lights(self.plotter.renderer)
        self.setMinimumSize(*MINIMUM_SIZE)  # widening a dock must not squeeze the leaf out
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.plotter.interactor)
        self.visible = {key: on for key, _, on in LAYERS}
        self.show_edges = False
        self.show_bars = (
            True  # colour bars for the coloured layers (off: the lesson's plan has them)
        )
        self.mesh_coloring = LEAF  # the layers panel's first choice
        self._bar_titles = {key: {title} for key, title in SCALAR_BARS.items()}
        self._bar_titles["mesh"] = {label for label, _ in MESH_COLORINGS.values()}
        self._mesh_piece: Piece | None = None
        self._texture = None  # pyvista.Texture for the TEXTURE colouring, made on this thread
        self._plain = None  # its stand-in while the image is being made
        self.texture_key: tuple | None = None  # what the texture shows (gui/model/textures.py)
        self._names: dict[str, list[str]] = {key: [] for key, _, _ in LAYERS}
        self._frame = Frame(np.zeros(3), np.eye(3)[0], np.eye(3)[1], np.eye(3)[2])
        self._bounds: BladeBounds | None = None
        self._has_content = False
        self._message = ""
        self._pieces: dict[str, list[Piece]] = {}
        self._announce = False
        self._bars: dict[str, tuple] = {}
        self._placed: tuple | None = None  # the preset and camera the view last framed with
        self._redraw_due = False
        self._made = False  # an actor made since the last render (its first render sets it up)
        self._later: set[str] = set()  # layers that wait for that render (set_layer)
        self.plotter.render_window.AddObserver("EndEvent", self._on_render_end)
        self.apply_palette()

    # --- look ----------------------------------------------------------------------------------
    def pixel_ratio(self) -> float:
        """Device pixels per logical pixel (2 on a high-DPI screen): VTK sizes are in device
        pixels, Qt's in logical ones."""
        return float(self.devicePixelRatioF())

    def text_color(self) -> str:
        return self.palette().color(QPalette.ColorRole.WindowText).name()

    def _dark(self) -> bool:
        return self.palette().color(QPalette.ColorRole.Base).lightnessF() < 0.5

    def apply_palette(self) -> None:
        """Background and text colours from the palette (light or dark). The background is
        one colour, a shade off the palette's base: a gradient is a full-view pass of its own
        in every render, a third of a render's cost under software OpenGL."""
        base = self.palette().color(QPalette.ColorRole.Base)
        shade = base.lighter(118) if self._dark() else base.darker(106)
        self.plotter.set_background(shade.name())
        for key in self._pieces:  # colours that follow the palette
            if self.visible[key]:
                self._draw_layer(key)
        self._bars.clear()
        self._sync_scalar_bars()
        self.redraw()

    def changeEvent(self, event: QEvent) -> None:
        super().changeEvent(event)
        if event.type() == QEvent.Type.PaletteChange:
            self.apply_palette()

    # --- layers --------------------------------------------------------------------------------
    def show_layers(
        self,
        layers: dict[str, list[Piece]],
        frame: Frame,
        bounds: BladeBounds | None = None,
        framing: str | None = None,
    ) -> None:
        """Replace every layer by the given pieces. `frame` orients the camera presets (the
        plane the sketch shows); `bounds` is the blade's box, framed when `framing` is "reset"
        (the iso preset) or "refit" (the current direction); otherwise the camera stays.

        A fit over a view already drawn is a turn of its own: pieces that need a new actor
        (a scan with more veins than the leaf before) wait for its render, as in set_layer
        (a 2M-point scan's fit 10-15 ms and its new actors 22-26 ms were one pause). The mesh
        is drawn now, the other layers a turn later, before the render (a 2M-point scan's
        result took 17-48 ms of the main thread in one piece)."""
        self._frame = frame
        if bounds is not None:
            self._bounds = bounds
        make = framing is None or not (self._has_content and self.isVisible())
        rest = []
        for key, pieces in layers.items():
            self._pieces[key] = pieces
            if not self.visible[key]:  # drawn when switched on: hidden layers cost nothing
                self._remove_layer(key)
            elif key == "mesh":
                self._draw_layer(key, make)
            else:
                rest.append(key)
        if rest:
            later(self, partial(self._draw_rest, rest, make))
        self._sync_scalar_bars()
        self._has_content = True
        self.set_message("", render=False)
        if framing == "reset":
            self.camera("iso", render=False)
        elif framing == "refit":
            self.refit(render=False)
        self._announce = True
        self.redraw()

    def set_layer(self, key: str, pieces: list[Piece]) -> None:
        """Replace one layer's pieces (the scan and Poisson layers, which come apart from
        results); drawn now if the layer is on, else when it is switched on. Nothing drawn
        before or after (a hidden Poisson layer with each result): no render.

        A layer whose actors are new waits for the render due when another actor was made
        since the last one (an opened scan's points after the mesh recoloured by height): the
        first render of a new kind of actor sets up its shaders, tens of milliseconds of the
        main thread each under software OpenGL, so two new kinds take two renders."""
        self._pieces[key] = pieces
        drawn = bool(self._names[key])
        if self._made and not drawn and pieces and self.visible[key] and self.isVisible():
            self._later.add(key)
            self.redraw()
            return
        self._later.discard(key)
        if self.visible[key]:
            self._draw_layer(key)
        else:
            self._remove_layer(key)
        if drawn or self._names[key]:
            self.redraw()

    def redraw(self) -> None:
        """Schedule one render of the scene, in a later turn of the event loop than the work
        that asked for it: a result's layers and its render are then two short pauses of the
        main thread, with input handled between them, rather than one long one. Many asks
        before that turn make one render."""
        if not self._redraw_due:
            self._redraw_due = True
            later(self, self._redraw_now)

    def _redraw_now(self) -> None:
        self._redraw_due = False
        self.plotter.interactor.update()  # VTK renders at the widget's paint

    def _on_render_end(self, *_: object) -> None:
        self._made = False
        if self._later:
            later(self, self._draw_later)
        if self._announce:
            self._announce = False
            self.rendered.emit()

    def _draw_later(self) -> None:
        """Draw the layers that waited for a render (set_layer, show_layers)."""
        later, self._later = self._later, set()
        for key in sorted(later):
            self.set_layer(key, self._pieces.get(key, []))

    def _draw_rest(self, keys: list[str], make: bool) -> None:
        """A result's layers but the mesh (show_layers), then its render."""
        for key in keys:
            if self.visible[key]:
                self._draw_layer(key, make)
        self.redraw()  # the one already due, unless it came first

    def _draw_layer(self, key: str, make: bool = True) -> None:
        """Draw layer `key`'s pieces; with `make` False, those that need a new actor wait for
        the next render (their old actors hidden meanwhile)."""
        pieces = self._pieces.get(key, [])
        names = [piece.name for piece in pieces]
        for stale in set(self._names[key]) - set(names):
            self.plotter.remove_actor(stale, render=False)
        actors = self.plotter.actors  # read once: pyvista walks every actor at each read
        for piece in pieces:
            if not self._add(key, piece, make, actors.get(piece.name)):
                self._later.add(key)
        self._names[key] = names

    def _remove_layer(self, key: str) -> None:
        for name in self._names[key]:
            self.plotter.remove_actor(name, render=False)
        self._names[key] = []

    def _add(self, key: str, piece: Piece, make: bool = True, actor: Any = None) -> bool:
        """Draw a piece in its actor (`actor`, else the plotter's of its name), or in a new one
        if `make`; False when it needs one and `make` is False."""
        style = dict(piece.style)
        if key == "mesh" and self.mesh_coloring in SHOWS_TEXTURE:
            self._mesh_piece = piece
            # white under the image (its colours as they are); until the leaf's is made, one
            # texel of the blade's colour (the same actor then takes the image in place).
            # Opaque: alpha 0 outside the outline is dropped (glTF's MASK), never sorted.
            texture = self._texture if self._texture is not None else self._plain_texture()
            style.update(
                show_edges=self.show_edges, texture=texture, color="white", force_opaque=True
            )
            if self.mesh_coloring == LEAF:
                style.update(LEAF_LOOK)
        elif key == "mesh":
            self._mesh_piece = piece
            coloring = self.mesh_coloring if self.mesh_coloring in piece.ranges else "height"
            style.update(
                show_edges=self.show_edges,
                scalars=coloring,
                cmap=MESH_COLORINGS[coloring][1],
                clim=piece.ranges.get(coloring),
            )
        # a large mesh is drawn lighter (display_mesh.py), but its edges are the full mesh's
        data = piece.full_data if key == "mesh" and self.show_edges else piece.data
        if data.n_points == 0:
            self.plotter.remove_actor(piece.name, render=False)
            return True
        ratio = self.pixel_ratio()
        style.update({k: style[k] * ratio for k in SIZED if k in style})
        if style.get("color") == BOUNDARY_COLOR and self._dark():
            style["color"] = self.text_color()  # the near-black boundary on a dark background
        if actor is None:
            actor = self.plotter.actors.get(piece.name)
        if actor is not None and self._same_kind(actor, data, style):
            held = actor.mapper.GetInputDataObject(0, 0)  # the dataset the mapper draws
            held.ShallowCopy(data)
            if "scalars" in style:
                held.GetPointData().SetActiveScalars(style["scalars"])
                actor.mapper.array_name = style["scalars"]
                clim = style.get("clim")
                if clim is not None:
                    actor.mapper.scalar_range = clim
            if "texture" in style:
                actor.SetTexture(style["texture"])
            actor.prop.show_edges = bool(style.get("show_edges", actor.prop.show_edges))
            actor.SetVisibility(self.visible[key])
            return True
        if not make:
            if actor is not None:
                actor.SetVisibility(False)  # not another result's data under this one's camera
            return False
        self._made = True
        actor = self.plotter.add_mesh(
            data,
            name=piece.name,
            show_scalar_bar=False,
            reset_camera=False,
            render=False,
            **style,
        )
        if key == "mesh":
            actor.prop.interpolation = "phong"
        actor._leafstudio_style = _style_key(style)  # what an in-place update must not change
        actor.SetVisibility(self.visible[key])
        return True

    @staticmethod
    def _same_kind(actor, data, style: dict) -> bool:
        """True when the drawn actor can take the new dataset in place: same style, and the same
        kind of dataset (its cells' kind decides the mapper's work)."""
        old = actor.mapper.dataset
        return (
            getattr(actor, "_leafstudio_style", None) == _style_key(style)
            and type(old) is type(data)
            and bool(old.n_cells) == bool(data.n_cells)
        )

    def clear(self) -> None:
        """Remove every layer (a new, still empty sketch)."""
        for key in self._names:
            self._remove_layer(key)
        self._pieces.clear()
        self._later.clear()
        self._mesh_piece = None
        self._sync_scalar_bars()
        self._has_content = False
        self.redraw()

    def actor_names(self, key: str) -> list[str]:
        """Names of the actors currently drawn for layer `key`."""
        actors = self.plotter.actors  # a new dict at each call: pyvista walks every actor
        return [n for n in self._names[key] if n in actors]

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

    def set_texture(self, image: np.ndarray | None, key: tuple | None, draw: bool = True) -> None:
        """The image the TEXTURE colouring maps through the mesh's UVs ((h, w, 3 or 4) uint8,
        row 0 at t = 1, as an export writes it; None: the blade's plain colour), and what it
        shows (`key`, gui/model/textures.py); `draw=False` leaves the mesh to the next result."""
        self._texture = None if image is None else _texture(image)
        if self._texture is not None:
            self._texture.interpolate = True  # smooth texels, as renderers filter them
        self.texture_key = key
        if draw and self.mesh_coloring in SHOWS_TEXTURE:
            self.set_mesh_coloring(self.mesh_coloring)

    def _plain_texture(self):
        """A one-texel texture of the generated blade colour (assets/texture.py)."""
        import pyvista as pv

        from leafstudio.assets.texture import BLADE

        if self._plain is None:
            self._plain = pv.Texture(np.array([[BLADE]], dtype=np.uint8))
        return self._plain

    def texture_actor_image(self) -> np.ndarray | None:
        """The image on the mesh actor now (row 0 at t = 1), or None (for tests and checks)."""
        actor = self.plotter.actors.get("mesh")
        texture = actor.GetTexture() if actor is not None else None
        return None if texture is None else np.asarray(texture.to_array())

    def set_edges(self, on: bool) -> None:
        """Show or hide the mesh's triangle edges (over the full mesh: a large one is otherwise
        drawn through fewer vertices, display_mesh.py)."""
        self.show_edges = on
        if self._mesh_piece is not None and self.actor_names("mesh"):
            self._add("mesh", self._mesh_piece)
        self.redraw()

    def _sync_scalar_bars(self) -> None:
        """A scalar bar per visible coloured layer, side by side along the bottom, its ends
        written in plain decimals (fields.bar_format); the bars already there are kept when
        the same ones are wanted (making one costs several milliseconds)."""
        wanted: dict[str, tuple[str, object]] = {}
        for key, title in SCALAR_BARS.items():
            if key == "mesh" and self._mesh_piece is not None:
                coloring = self.mesh_coloring
                title = MESH_COLORINGS[
                    coloring if coloring in self._mesh_piece.ranges else "height"
                ][0]
            names = self.actor_names(key)
            if not (self.show_bars and self.visible[key] and names):
                continue
            if key == "mesh" and self.mesh_coloring in SHOWS_TEXTURE:
                continue  # an image, not a colour scale
            wanted[key] = (title, self.plotter.actors[names[0]].mapper)
        shown = {key: (title, id(mapper)) for key, (title, mapper) in wanted.items()}
        if shown == self._bars and all(t in self.plotter.scalar_bars for t, _ in shown.values()):
            return
        for key in SCALAR_BARS:
            for stale in self._bar_titles[key] & set(self.plotter.scalar_bars.keys()):
                self.plotter.remove_scalar_bar(stale, render=False)
        self._bars = shown
        gap = 0.1  # room for the end labels of neighbouring bars
        width = min(0.4, 0.94 / max(len(wanted), 1) - gap)
        for i, (title, mapper) in enumerate(wanted.values()):
            low, high = mapper.scalar_range
            self.plotter.add_scalar_bar(
                title=title,
                mapper=mapper,
                vertical=False,
                position_x=0.06 + i * (width + gap),
                position_y=0.02,
                width=width,
                height=0.08,
                color=self.text_color(),
                fmt=bar_format(low, high),
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

    def image(self) -> QImage:
        """The 3D view as drawn now, from VTK's frame buffer: Qt cannot grab a native window
        (native_view.py), and this is the same on every platform."""
        pixels = np.ascontiguousarray(self.plotter.screenshot(None, return_img=True)[..., :3])
        height, width = pixels.shape[:2]
        image = QImage(pixels.data, width, height, 3 * width, QImage.Format.Format_RGB888).copy()
        image.setDevicePixelRatio(self.pixel_ratio())
        return image

    def close_plotter(self) -> None:
        """Release VTK resources (before the window goes)."""
        self.plotter.close()


def grab_window(window: QWidget, viewport: Viewport) -> QPixmap:
    """The whole window as on screen, with the 3D view painted from its own frame buffer over
    the place Qt's grab leaves blank (native_view.py)."""
    pixmap = window.grab()
    if viewport.isVisible():
        painter = QPainter(pixmap)
        corner = viewport.mapTo(window, QPoint(0, 0))
        painter.drawImage(QRect(corner, viewport.size()), viewport.image())
        painter.end()
    return pixmap


# The Leaf look (gui/model/textures.LEAF): the texture lit with a waxy sheen, never dark (a blade
# lets light through), its underside paler and warmer, as a leaf's lit from behind looks.
LEAF_LOOK = {
    "ambient": 0.25,
    "diffuse": 0.85,
    "specular": 0.25,
    "specular_power": 18.0,
    "backface_params": {"ambient": 0.45, "diffuse": 0.75, "color": (1.0, 1.0, 0.72)},
}


def drop_back_lights(renderer: Any) -> None:
    """Remove the camera lights placed behind the focal point (pyvista's light kit has two, at
    azimuth ±110°): a surface facing the view, two-sided lighting turning back faces to it,
    catches none of their light, but software OpenGL shades every lit pixel of the mesh once per
    light. Each view's image changes by 0.06 of 255 on average (the iso, top and side views of
    the nested demo, a 2M-point scan); a render of that scan costs 12-15% less."""
    lights = renderer.lights
    kept = [light for light in lights if not (light.is_camera_light and light.position[2] < 0)]
    if len(kept) < len(lights):
        renderer.remove_all_lights()
        for light in kept:
            renderer.add_light(light)


def _style_key(style: dict) -> tuple:
    """A hashable summary of an actor's style, without the per-result colour range."""
    dropped = ("clim", "show_edges", "texture")  # set on the actor in place
    return tuple(sorted((k, repr(v)) for k, v in style.items() if k not in dropped))


def _texture(image: np.ndarray):
    """A pyvista Texture of an (h, w, c) uint8 image, row 0 at the top: pv.Texture(image)'s
    texels, without its transposed Fortran-order copy (21 -> 2 ms of the main thread at 1024²)."""
    import pyvista as pv

    grid = pv.ImageData(dimensions=(image.shape[1], image.shape[0], 1))
    grid.point_data["Image"] = np.ascontiguousarray(image[::-1]).reshape(-1, image.shape[2])
    grid.set_active_scalars("Image")
    return pv.Texture(grid)
