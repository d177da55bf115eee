"""The window's menus as data: a table of actions (id, menu, title, what it does, shortcut, tip)
that the window builds its menu bar from, as napari's `_qt/_qapp_model/qactions`; a feature
adds its own rows the same way (explain.py: the exports for slides) through
`MainWindow.add_actions`.

An action's callback takes the window. A `submenu` row is a menu filled each time it opens: its
callback takes the window and that menu. `before` places a row ahead of an action already
there (a feature's export above Quit); `separator` puts a line before it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from PySide6.QtGui import QKeySequence

from leafstudio.gui.qt.view_camera import CAMERAS
from leafstudio.sources.demos import DEMOS

Shortcut = str | QKeySequence.StandardKey
MENU_TITLES = {
    "File": "&File",
    "Edit": "&Edit",
    "View": "&View",
    "Demos": "&Demos",
    "Help": "&Help",
}


@dataclass(frozen=True)
class Action:
    """One menu entry.

    Attributes
    ----------
    id : str
        Its name in `MainWindow.actions` ("file.open").
    menu : str
        The menu it sits in ("File"; MENU_TITLES gives the bar's text).
    title : str
        Its text, with the mnemonic's "&".
    callback : callable(window) or callable(window, menu)
        What it does (a submenu: fills the menu as it opens).
    shortcut : str, StandardKey, tuple of them, or None
        Its keys; a tuple gives several (the first is shown).
    tip : str
        The status bar's words while it is under the pointer.
    tooltip : str
        The tooltip's words.
    separator : bool
        A line before it.
    before : str or None
        The id of the action it goes before (None: at the end of its menu).
    submenu : bool
        A menu filled by `callback` each time it opens.
    """

    id: str
    menu: str
    title: str
    callback: Callable[..., Any]
    shortcut: Shortcut | tuple[Shortcut, ...] | None = None
    tip: str = ""
    tooltip: str = ""
    separator: bool = False
    before: str | None = None
    submenu: bool = False

    def key_sequences(self) -> list[QKeySequence]:
        """Its shortcuts, without duplicates or keys the platform lacks."""
        keys = self.shortcut if isinstance(self.shortcut, tuple) else (self.shortcut,)
        found = [QKeySequence(k) for k in keys if k is not None]
        return list(dict.fromkeys(k for k in found if not k.isEmpty()))


def show_once(make: Callable[[Any], Any]) -> Callable[[Any], None]:
    """An action's callback that makes its dialog the first time (`make(window)`) and shows
    and raises that same dialog every time."""
    made: list[Any] = []

    def show(window) -> None:
        if not made:
            made.append(make(window))
        made[0].show()
        made[0].raise_()

    return show


KEYS = QKeySequence.StandardKey

# fmt: off
FILE_ACTIONS = (
    Action(
        "file.new", "File", "&New sketch", lambda w: w.new_sketch(), KEYS.New, "Draw a new leaf",
    ),
    Action(
        "file.open", "File", "&Open…", lambda w: w.open_dialog(), KEYS.Open,
        "Open a leaf, project or scan",
    ),
    Action(
        "file.open_scan", "File", "Open s&can…", lambda w: w.open_scan_dialog(), "Ctrl+Shift+O",
        "Open a 3D scan of a leaf: its boundary and veins are extracted and can be edited",
    ),
    Action(
        "file.open_photo", "File", "Open &photo…", lambda w: w.open_photo_dialog(), None,
        "Open a photo or scan of one leaf on a plain background: its outline, grown veins",
    ),
    Action(
        "file.recent", "File", "Open &recent", lambda w, menu: w.fill_recent(menu), submenu=True,
    ),
    Action(
        "file.save", "File", "&Save", lambda w: w.save(), KEYS.Save,
        "Save the project (.leaf.json)", separator=True,
    ),
    Action("file.save_as", "File", "Save &as…", lambda w: w.save_as(), KEYS.SaveAs),
    Action(
        "file.export_mesh", "File", "&Export mesh…", lambda w: w.export_mesh_dialog(), "Ctrl+E",
        "Write the mesh: .glb, .gltf, .obj (textured), .ply, .stl, .3mf, .vtp or .vtk",
    ),
    Action(
        "file.export_solid", "File", "Export so&lid for printing…",
        lambda w: w.export_solid_dialog(), None,
        "Write the leaf as a closed solid of a chosen thickness (.stl, .3mf, .obj, .ply, .glb)",
    ),
    Action(
        "file.export_screenshot", "File", "Export &screenshot…",
        lambda w: w.export_screenshot_dialog(), "Ctrl+Shift+E",
    ),
    Action("file.quit", "File", "&Quit", lambda w: w.close(), KEYS.Quit, separator=True),
)

EDIT_ACTIONS = (
    Action("edit.undo", "Edit", "&Undo", lambda w: w.session.undo(), KEYS.Undo),
    Action(
        "edit.redo", "Edit", "&Redo", lambda w: w.session.redo(),
        (KEYS.Redo, "Ctrl+Shift+Z", "Ctrl+Y"),
    ),
)

VIEW_ACTIONS = tuple(
    Action(
        f"view.{p}", "View", f"{p.capitalize()} view", lambda w, p=p: w.viewport.camera(p),
        f"Ctrl+{i}",
    )
    for i, p in enumerate(CAMERAS, start=1)
)

DEMO_ACTIONS = tuple(
    Action(
        f"demos.{name}", "Demos", f"{name.capitalize()} veins", lambda w, n=name: w.open_demo(n),
        tip=f"The paper's {name} leaf",
    )
    for name in DEMOS
)

# fmt: on
HELP_ACTIONS = (Action("help.about", "Help", "&About LeafStudio", lambda w: w.about()),)

WINDOW_ACTIONS = FILE_ACTIONS + EDIT_ACTIONS + VIEW_ACTIONS + DEMO_ACTIONS + HELP_ACTIONS
