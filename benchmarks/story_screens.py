"""Screenshots of issue 12's user stories, driven through the real main window, with the leaf's
framing in the 3D view as JSON.

Run under a display:
`xvfb-run -a -s "-screen 0 1600x1000x24" .venv/bin/python benchmarks/story_screens.py --out DIR`.

Stories (each shot is the whole window, `DIR/s3-story-<name>.png`):
1. File > New, then 12 boundary clicks, a midrib and four side veins clicked in the sketch view
   (QTest mouse clicks, as a user), waiting for each result: shots after 3 points, at the end,
   in the top view, and after the Iso button;
2. Demos > Nested, then Demos > Parallel, then a form picked in the Forms gallery;
3. two real scans opened one after the other (soybean, then sugar beet) from ../shared/realleaves,
   each in iso (as opened) and in the top view;
4. a dark palette; then the same at QT_SCALE_FACTOR=2 in a subprocess (a virtual screen of its
   own, twice as large, when xvfb-run is there).

For each shot the JSON gives the leaf's framing in the 3D view: the share of the viewport's width
and height that the result mesh's points span on screen (projected with the renderer's world to
display transform, as tests/gui/qt/test_drawing.py measures it), the same for the blade's robust
bounds (gui/model/framing.py: 1st-99th percentiles, the points the camera frames), the share of mesh
points that fall outside the view (clipped) or under the height colour bar, and whether the
sketch view's transform changed while drawing. The issue's framing target: >= 60% along one
axis and >= 35% along the other.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from PySide6.QtCore import QSettings, Qt
from PySide6.QtGui import QColor, QPalette
from PySide6.QtTest import QTest
from PySide6.QtWidgets import QApplication, QMessageBox

from leafstudio.core.bend import Pose
from leafstudio.core.evaluate import surface_area
from leafstudio.gui.model.framing import best_iso, blade_bounds
from leafstudio.gui.model.layers import vein_color
from leafstudio.gui.qt.main_window import MainWindow
from leafstudio.gui.qt.view_camera import BAR_BAND
from leafstudio.gui.qt.viewport import grab_window

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from tests.leaves import CLICKED_MIDRIB as MIDRIB  # the clicks, shared with the tests
from tests.leaves import CLICKED_SIDE_VEINS as SIDE_VEINS
from tests.leaves import clicked_outline as boundary_clicks

REAL = Path(__file__).resolve().parents[2] / "shared" / "realleaves"
SCANS = (
    "soybean_11_20190508T043118_pot1_1.txt",
    "sugarbeet_f00012_20170829T010129_pot1_1.txt",
)
WAIT_S = 300.0
STORIES = ("draw", "demos", "scans", "dark", "bent")
DARK = {
    QPalette.ColorRole.Window: "#202124",
    QPalette.ColorRole.Base: "#17181a",
    QPalette.ColorRole.AlternateBase: "#232427",
    QPalette.ColorRole.Button: "#2a2b2e",
    QPalette.ColorRole.Text: "#e8e8e8",
    QPalette.ColorRole.WindowText: "#e8e8e8",
    QPalette.ColorRole.ButtonText: "#e8e8e8",
    QPalette.ColorRole.PlaceholderText: "#9a9a9a",
}


def process(ms: int) -> None:
    """Run the event loop for `ms` milliseconds."""
    end = time.perf_counter() + ms / 1000
    while time.perf_counter() < end:
        QApplication.processEvents()
        time.sleep(0.005)


def wait_until(check, timeout_s: float = WAIT_S, what: str = "") -> None:
    end = time.perf_counter() + timeout_s
    while not check():
        if time.perf_counter() > end:
            raise TimeoutError(f"timed out waiting for {what or check}")
        QApplication.processEvents()
        time.sleep(0.01)


def settle(window: MainWindow) -> None:
    """Wait until the session has nothing pending: the newest request shown (or refused with a
    message), the worker idle (measurements in), and a few more turns of the event loop."""

    def done() -> bool:
        session = window.session
        if not window.worker.is_idle():
            return False
        return session.last_id == 0 or session.shown_id >= session.last_id or bool(session.message)

    process(100)
    wait_until(done, what="the result")
    process(400)


def click(window: MainWindow, xy) -> dict:
    """A left click at plane point `xy` in the sketch view; whether the view moved."""
    view = window.editor.view
    before = view.transform()
    pos = view.view_point(np.asarray(xy, float)).toPoint()
    no_key = Qt.KeyboardModifier.NoModifier
    QTest.mouseClick(view.viewport(), Qt.MouseButton.LeftButton, no_key, pos)
    QApplication.processEvents()
    return {"moved": view.transform() != before}


def framing(window: MainWindow) -> dict:
    """The shown leaf's framing in the 3D view."""
    result = window.session.result
    if result is None:
        return {"leaf": None}
    renderer = window.viewport.plotter.renderer
    width, height = renderer.GetSize()
    points = np.asarray(result.triangle_mesh.points)
    mesh_xy = window.viewport.display_points(points[:: max(1, len(points) // 3000)])
    frame = window.session.view_frame() or result.frame
    blade = blade_bounds(points, frame)
    blade_xy = window.viewport.display_points(blade.extent_points())
    inside = (
        (mesh_xy[:, 0] >= 0)
        & (mesh_xy[:, 0] <= width)
        & (mesh_xy[:, 1] >= 0)
        & (mesh_xy[:, 1] <= height)
    )
    under_bar = np.zeros(len(mesh_xy), bool)
    for bar in window.viewport.plotter.scalar_bars.values():
        # the bar's box as drawn (viewport shares), up to the band kept for its title
        x0, y0 = bar.GetPositionCoordinate().GetValue()[:2]
        wide = bar.GetPosition2Coordinate().GetValue()[0]
        under_bar |= (
            (mesh_xy[:, 0] >= x0 * width)
            & (mesh_xy[:, 0] <= (x0 + wide) * width)
            & (mesh_xy[:, 1] >= y0 * height)
            & (mesh_xy[:, 1] <= BAR_BAND * height)
        )
    mesh_fill = (float(np.ptp(mesh_xy[:, 0]) / width), float(np.ptp(mesh_xy[:, 1]) / height))
    blade_fill = (float(np.ptp(blade_xy[:, 0]) / width), float(np.ptp(blade_xy[:, 1]) / height))
    return {
        "viewport_px": [int(width), int(height)],
        "mesh_fill_wh": [round(v, 3) for v in mesh_fill],
        "blade_fill_wh": [round(v, 3) for v in blade_fill],
        "meets_target": bool(max(blade_fill) >= 0.6 and min(blade_fill) >= 0.35),
        "mesh_points_outside_view": round(float(1.0 - inside.mean()), 4),
        "mesh_points_under_colour_bar": round(float(under_bar.mean()), 4),
        "veins": len(result.leaf.veins),
        "vein_colours_match": vein_colours_match(window),
    }


def vein_colours_match(window: MainWindow) -> bool:
    """True when each vein's points in the 3D view have the sketch's colour for that vein."""
    plotter = window.viewport.plotter
    sketch_veins = len(window.editor.view.sketch.veins)
    count = len(window.session.result.leaf.veins)
    if sketch_veins and sketch_veins != count:
        return False
    for i in range(count):
        actor = plotter.actors.get(f"points:vein{i}")
        if actor is None:
            continue
        expected = QColor(vein_color(i))
        got = [round(c * 255) for c in actor.prop.color.float_rgb]
        if got != [expected.red(), expected.green(), expected.blue()]:
            return False
    return True


def iso_turn(window: MainWindow) -> float:
    """Degrees between the camera's direction now and the iso direction a fresh opening of the
    shown leaf would take (framing.best_iso on its blade bounds)."""
    plotter = window.viewport.plotter
    camera = plotter.camera
    now = np.asarray(camera.position) - np.asarray(camera.focal_point)
    frame = window.session.view_frame() or window.session.result.frame
    bounds = blade_bounds(np.asarray(window.session.result.triangle_mesh.points), frame)
    width, height = plotter.renderer.GetSize()
    fresh, _ = best_iso(bounds, camera.view_angle, width / max(height, 1))
    cos = now @ fresh / (np.linalg.norm(now) * np.linalg.norm(fresh))
    return round(float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))), 1)


def top_view_way_round(window: MainWindow) -> dict:
    """In the top view, does the sketch's right-most point show right of the centre and its
    top-most point above it (the same way round as the sketch)?"""
    sketch = window.editor.view.sketch
    frame = window.session.view_frame()
    if frame is None or len(sketch.boundary) < 3:
        return {}
    b = sketch.boundary

    def at(xy) -> np.ndarray:
        return window.viewport.display_points(frame.to_world(np.asarray([xy]), np.zeros(1)))[0]

    centre = at(b.mean(axis=0))
    right = at(b[np.argmax(b[:, 0])])
    top = at(b[np.argmax(b[:, 1])])
    return {
        "sketch_right_is_screen_right": bool(right[0] > centre[0]),
        "sketch_up_is_screen_up": bool(top[1] > centre[1]),
    }


class Shooter:
    """Saves whole-window shots and collects their figures."""

    def __init__(self, window: MainWindow, out: Path, suffix: str = "") -> None:
        self.window, self.out, self.suffix = window, out, suffix
        self.shots: list[dict] = []

    def __call__(self, story: str, name: str, **extra: object) -> dict:
        window = self.window
        process(200)
        path = self.out / f"s3-story-{name}{self.suffix}.png"
        if not grab_window(window, window.viewport).save(str(path)):
            raise OSError(f"{path}: cannot write the PNG")
        entry = {
            "story": story,
            "shot": path.name,
            "title": window.windowTitle(),
            "status": window.status_text.text(),
            "framing": framing(window),
            **extra,
        }
        self.shots.append(entry)
        return entry


def trigger(window: MainWindow, menu: str, text: str) -> None:
    """Trigger the menu item whose text (without '&') starts with `text`."""
    for action in window.menus[menu].actions():
        if action.text().replace("&", "").startswith(text):
            action.trigger()
            return
    raise LookupError(f"{menu} > {text}: no such menu item")


def story_draw(window: MainWindow, shot: Shooter) -> None:
    """File > New, 12 boundary points, a midrib, four side veins, through the sketch view."""
    trigger(window, "File", "New sketch")
    process(300)
    view = window.editor.view
    start = view.transform()
    moves: list[bool] = []
    for i, xy in enumerate(boundary_clicks()):
        moves.append(click(window, xy)["moved"])
        if i == 2:
            settle(window)
            shot("draw", "1a-new-after-3-points", sketch_view_moved=any(moves))
    settle(window)
    shot("draw", "1b-12-boundary-points", sketch_view_moved=any(moves))
    QTest.mouseClick(window.editor.new_vein, Qt.MouseButton.LeftButton)
    for xy in MIDRIB:
        moves.append(click(window, xy)["moved"])
    for vein in SIDE_VEINS:
        QTest.mouseClick(window.editor.new_vein, Qt.MouseButton.LeftButton)
        for xy in vein:
            moves.append(click(window, xy)["moved"])
    settle(window)
    sketch = view.sketch
    drawn = {
        "boundary_points": len(sketch.boundary),
        "vein_points": [len(v) for v in sketch.veins],
        "sketch_view_moved": any(moves) or view.transform() != start,
        "undo_steps": window.session.history.index,
    }
    shot("draw", "1c-drawn-leaf-iso", iso_turned_from_fresh_deg=iso_turn(window), **drawn)
    window.viewport.camera("top")
    process(300)
    shot("draw", "1d-drawn-leaf-top", top_view=top_view_way_round(window), **drawn)
    window.viewport.camera("iso")  # the Iso button: the iso view chosen for the whole leaf
    process(300)
    shot("draw", "1e-drawn-leaf-iso-button", iso_turned_from_fresh_deg=iso_turn(window), **drawn)
    flat = mesh_area(window)
    window.session.set_bend(Pose(fold=45.0, curl=0.4))  # as the bend sliders set it
    settle(window)
    window.viewport.camera("iso")
    process(300)
    shot("draw", "1f-drawn-leaf-folded-curled", area_over_flat=round(mesh_area(window) / flat, 4))


def mesh_area(window: MainWindow) -> float:
    """The shown result's mesh area."""
    mesh = window.session.result.triangle_mesh
    return float(surface_area(np.asarray(mesh.points), mesh.regular_faces))


def story_demos(window: MainWindow, shot: Shooter) -> None:
    """Demos > Nested, Demos > Parallel, then a gallery form."""
    trigger(window, "Demos", "Nested")
    settle(window)
    shot("demos", "2a-demo-nested")
    trigger(window, "Demos", "Parallel")
    settle(window)
    shot("demos", "2b-demo-parallel-after-nested")
    name = pick_form(window, "lanceolate")
    if name is None:
        return
    shot("demos", f"2c-form-{name}", form=name)
    window.docks["Sketch"].raise_()
    process(300)
    shot("demos", f"2d-form-{name}-sketch", form=name)


def pick_form(window: MainWindow, shape: str, **pose: float) -> str | None:
    """Click `shape` (the first shape if it is not there) in the Forms dock's gallery, its pose
    sliders set to `pose` first (the rest at 0), and wait for it; the shape picked, or None
    without a Forms dock."""
    panel = getattr(window, "forms_panel", None)
    if panel is None:
        return None
    window.docks["Forms"].show()
    window.docks["Forms"].raise_()
    process(300)
    for term in ("fold", "curl", "roll", "twist", "wave"):
        getattr(panel, term).setValue(pose.get(term, 0.0))
    gallery = panel.gallery
    names = [gallery.item(i).data(Qt.ItemDataRole.UserRole) for i in range(gallery.count())]
    row = names.index(shape) if shape in names else 0
    item = gallery.item(row)
    gallery.scrollToItem(item)
    process(100)
    rect = gallery.visualItemRect(item)
    QTest.mouseClick(gallery.viewport(), Qt.MouseButton.LeftButton, pos=rect.center())
    wait_until(lambda: names[row] in window.windowTitle(), what="the chosen form")
    settle(window)
    return names[row]


def story_bent(window: MainWindow, shot: Shooter) -> None:
    """Issue 21's three: a grass blade rolled and an ovate leaf half folded (the Forms dock's
    pose sliders), and the curled soybean scan as File > Open opens it."""
    for shape, pose, name in (
        ("linear", {"roll": 0.8}, "4a-grass-blade-rolled"),
        ("ovate", {"fold": 45.0}, "4b-ovate-half-folded"),
    ):
        if pick_form(window, shape, **pose) is None:
            break
        window.viewport.camera("iso")
        process(300)
        shot("bent", name, form=shape, **pose)
    path = str(REAL / SCANS[0])
    window.session.history.set_clean()
    if not window.open_path(path):
        raise RuntimeError(f"{path}: not opened")
    wait_until(lambda: window.session.state.path == path, what="the soybean scan")
    settle(window)
    shot("bent", "4c-soybean-scan-curled", scan=SCANS[0])


def story_scans(window: MainWindow, shot: Shooter) -> None:
    """Two real scans, one after the other, as File > Open would open them."""
    for i, name in enumerate(SCANS):
        path = str(REAL / name)
        window.session.history.set_clean()
        if not window.open_path(path):
            raise RuntimeError(f"{path}: not opened")
        wait_until(lambda p=path: window.session.state.path == p, what=f"the scan {name}")
        settle(window)
        kind = name.split("_")[0]
        shot("scans", f"3{'ab'[i]}-scan-{kind}", scan=name)
        window.viewport.camera("top")
        process(300)
        way_round = top_view_way_round(window)
        shot("scans", f"3{'ab'[i]}-scan-{kind}-top", scan=name, top_view=way_round)


def dark_palette() -> QPalette:
    palette = QPalette()
    for role, color in DARK.items():
        palette.setColor(role, QColor(color))
    for role in (
        QPalette.ColorRole.Text,
        QPalette.ColorRole.WindowText,
        QPalette.ColorRole.ButtonText,
    ):  # greyed out as a dark theme greys them (unset, they keep the active colour)
        palette.setColor(QPalette.ColorGroup.Disabled, role, QColor("#6e6e6e"))
    return palette


def story_dark(window: MainWindow, shot: Shooter) -> None:
    """The nested demo under a dark palette (the whole application's)."""
    QApplication.instance().setPalette(dark_palette())
    window.session.history.set_clean()
    trigger(window, "Demos", "Nested")
    settle(window)
    window.editor.view.sketch  # noqa: B018  (the sketch is drawn with the palette)
    canvas = window.editor.view.backgroundBrush().color()
    background = window.viewport.plotter.renderer.GetBackground()
    shot(
        "dark",
        "4-dark-palette",
        scale_factor=os.environ.get("QT_SCALE_FACTOR", "1"),
        device_pixel_ratio=window.devicePixelRatioF(),
        canvas_lightness=round(canvas.lightnessF(), 3),
        background_3d=[round(c, 3) for c in background],
        vein_point_size=window.viewport.plotter.actors["points:vein0"].prop.point_size,
    )


def run(stories: list[str], out: Path, suffix: str) -> list[dict]:
    app = QApplication.instance() or QApplication(sys.argv[:1])
    QMessageBox.question = staticmethod(lambda *a, **k: QMessageBox.StandardButton.Discard)
    with tempfile.TemporaryDirectory() as tmp:
        settings = QSettings(str(Path(tmp) / "settings.ini"), QSettings.Format.IniFormat)
        window = MainWindow(settings)
        available = app.primaryScreen().availableGeometry()
        window.resize(min(1500, available.width()), min(920, available.height()))
        window.show()
        process(500)
        shot = Shooter(window, out, suffix)
        try:
            for name in stories:
                {
                    "draw": story_draw,
                    "demos": story_demos,
                    "scans": story_scans,
                    "dark": story_dark,
                    "bent": story_bent,
                }[name](window, shot)
        finally:
            window.session.history.set_clean()
            window.worker.shutdown()
            window.close()
            process(200)
    return shot.shots


def scaled_run(out: Path) -> list[dict]:
    """The dark story again at QT_SCALE_FACTOR=2, in a subprocess (a screen of its own)."""
    env = dict(os.environ, QT_SCALE_FACTOR="2")
    command = [sys.executable, __file__, "--out", str(out), "--stories", "dark"]
    command.append("--suffix=-scale2")  # with "=": a value that starts with "-"
    if shutil.which("xvfb-run"):
        command = ["xvfb-run", "-a", "-s", "-screen 0 3200x2000x24", *command]
    done = subprocess.run(command, env=env, capture_output=True, text=True, timeout=900)
    if done.returncode != 0:
        return [{"story": "dark", "error": done.stderr.strip().splitlines()[-5:]}]
    return json.loads(done.stdout)["shots"]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, help="folder for the PNGs")
    parser.add_argument("--stories", nargs="*", default=list(STORIES), choices=STORIES)
    parser.add_argument("--suffix", default="", help="added to each PNG's name")
    parser.add_argument("--no-scale2", action="store_true", help="skip the QT_SCALE_FACTOR=2 run")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    shots = run(args.stories, out, args.suffix)
    if "dark" in args.stories and not args.suffix and not args.no_scale2:
        shots += scaled_run(out)
    report = {
        "shots": shots,
        "platform": QApplication.platformName(),
        "wall_s": round(time.perf_counter() - start, 1),
        "load_average": [round(v, 2) for v in os.getloadavg()],
    }
    print(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
