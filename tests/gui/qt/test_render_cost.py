"""What the 3D view does per result, counted rather than timed: one render of the scene, text
set in place, measuring only once the result is drawn, and a large mesh drawn through fewer of
its own vertices while edges and exports keep it whole (software OpenGL makes every extra render,
font fit or vertex a main-thread stall)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from leafstudio.core.pipeline import Pipeline
from leafstudio.gui.model import display_mesh
from leafstudio.gui.model.display_mesh import display_subset
from leafstudio.gui.qt import worker as worker_module
from leafstudio.gui.qt.viewport import drop_back_lights
from leafstudio.gui.qt.worker import PIPELINE, Worker
from leafstudio.sources.demos import demo
from tests.gui.builders import FAST
from tests.gui.qt.conftest import WAIT_MS, exported, settled, wait_result


def _count_renders(window) -> list[int]:
    """A list that grows by one at the start of each render of the 3D view's window."""
    count: list[int] = []
    window.viewport.plotter.render_window.AddObserver("StartEvent", lambda *_: count.append(1))
    return count


def test_a_new_result_is_rendered_once(window, qtbot):
    settled(qtbot, window)  # whatever the first result left to draw
    renders = _count_renders(window)
    window.panel.k.setValue(5)
    wait_result(qtbot, window, lambda o: o.result.params.k == 5)
    settled(qtbot, window)  # any render queued behind it
    assert len(renders) == 1
    label = window.viewport.plotter.actors["k_label"]
    assert label.input == f"K = {window.session.shown.outcome.result.chosen_k}"


def test_the_k_label_is_one_text_actor_updated_in_place(window, qtbot):
    plotter = window.viewport.plotter
    label = plotter.actors["k_label"]
    window.panel.k.setValue(5)
    wait_result(qtbot, window, lambda o: o.result.params.k == 5)
    assert plotter.actors["k_label"] is label  # not made anew (nor its font fitted anew)
    assert label.input == f"K = {window.session.shown.outcome.result.chosen_k}"


def test_a_result_is_measured_once_drawn_and_not_when_a_newer_one_waits(qtbot, monkeypatch):
    """Measuring (hundreds of ms of CPU at grid 512) waits until the window has drawn the
    result, so that it never slows the render; a result already replaced is not measured.

    The worker stops waiting for a draw after DRAWN_WAIT_S (a hidden window never draws) and
    measures anyway: on a loaded machine the main thread could see a result, or submit the next
    request, more than those 2 s after it was yielded. Here no draw is late: the wait lasts as
    long as the test's own."""
    monkeypatch.setattr(worker_module, "DRAWN_WAIT_S", WAIT_MS / 1000)
    worker = Worker()
    worker.measure_after_drawn = True
    got: dict[str, list] = {"yielded": [], "done": []}
    worker.yielded.connect(lambda kind, jid, value: got["yielded"].append(value))
    worker.done.connect(lambda kind, jid, value: got["done"].append(jid))
    try:
        leaf = demo("nested")
        first = worker.submit_pipeline(leaf, FAST)
        qtbot.waitUntil(lambda: bool(got["yielded"]), timeout=WAIT_MS)
        qtbot.wait(100)
        assert got["done"] == []  # not measured while not drawn
        assert not worker.is_idle()
        got["yielded"][0].drawn.set()
        qtbot.waitUntil(lambda: got["done"] == [first], timeout=WAIT_MS)

        second = worker.submit_pipeline(leaf, FAST.with_(k=4))
        qtbot.waitUntil(lambda: len(got["yielded"]) == 2, timeout=WAIT_MS)
        third = worker.submit_pipeline(leaf, FAST.with_(k=5), interrupt=False)
        qtbot.waitUntil(lambda: len(got["yielded"]) == 3, timeout=WAIT_MS)
        assert got["yielded"][2].request.id == third
        got["yielded"][2].drawn.set()
        # not `waitUntil(worker.is_idle)`: the lane is idle just after it emits `done`, which the
        # main thread may not have received yet. The lane runs one job at a time, so once the
        # third's `done` is here, whatever the second sent came before it.
        qtbot.waitUntil(lambda: third in got["done"], timeout=WAIT_MS)
        assert got["done"] == [first, third]  # the second was replaced before it was drawn
        assert second not in got["done"]
    finally:
        worker.shutdown()
        assert worker.join(WAIT_MS / 1000)  # no job outlives the test


def test_the_window_lets_the_worker_measure_once_the_result_is_on_screen(
    window, qtbot, monkeypatch
):
    # the worker measures anyway DRAWN_WAIT_S after the result (a hidden window never draws):
    # a busy machine's main thread can be later than that; here it is never too late
    monkeypatch.setattr(worker_module, "DRAWN_WAIT_S", WAIT_MS / 1000)
    rendered: list[bool] = []
    window.viewport.rendered.connect(lambda: rendered.append(True))
    measured_after_render: list[bool] = []
    window.worker.done.connect(
        lambda kind, *_: kind == PIPELINE and measured_after_render.append(bool(rendered))
    )
    window.panel.k.setValue(5)
    wait_result(qtbot, window, lambda o: o.result.params.k == 5)
    qtbot.waitUntil(lambda: bool(measured_after_render), timeout=WAIT_MS)
    assert measured_after_render == [True]
    assert window.session.shown.measured_id == window.session.shown_id


def _plane_areas(xy: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Signed areas of the triangles on the plane."""
    a, b, c = xy[faces[:, 0]], xy[faces[:, 1]], xy[faces[:, 2]]
    (u, v), (s, t) = (b - a).T, (c - a).T
    return 0.5 * (u * t - v * s)


def test_a_large_mesh_is_drawn_through_a_subset_of_its_own_vertices():
    result = Pipeline(demo("nested")).run(FAST.with_(grid=96))
    mesh = result.triangle_mesh
    xy = result.frame.to_plane(mesh.points)[0]
    grid, outline = result.grid, result.on_outline()
    faces = mesh.regular_faces
    assert display_subset(xy, faces, grid.origin, grid.spacing, outline, len(faces)) is None
    keep, drawn = display_subset(xy, faces, grid.origin, grid.spacing, outline, len(faces) // 4)
    assert len(faces) // 6 < len(drawn) <= len(faces) // 3  # blocks of 2 x 2 nodes
    assert set(np.flatnonzero(outline).tolist()) <= set(
        keep.tolist()
    )  # the margin is drawn exactly
    assert len(np.unique(keep)) == len(keep) and drawn.max() < len(keep)
    assert (drawn[:, 0] != drawn[:, 1]).all() and (drawn[:, 1] != drawn[:, 2]).all()
    assert len(np.unique(np.sort(drawn, axis=1), axis=0)) == len(drawn)  # no repeats
    full, shown = _plane_areas(xy, faces), _plane_areas(xy[keep], drawn)
    # the same blade, without holes or folds: signed and unsigned areas match the full mesh's
    assert np.isclose(shown.sum(), full.sum(), rtol=1e-3)
    assert np.abs(shown).sum() < 1.01 * np.abs(full).sum()


def test_a_mesh_that_is_not_over_the_grid_is_drawn_whole():
    rng = np.random.default_rng(1)
    xy = rng.random((400, 2))
    faces = rng.integers(0, 400, (2000, 3))
    assert display_subset(xy, faces, np.zeros(2), 0.013, np.arange(400) < 10, 100) is None


def test_the_outline_is_a_flag_per_vertex_not_a_count():
    """display_subset took the outline's count before exports32; a count given now (a 0-d
    array) drew the demo's 1667 vertices as 1 and no triangle, silently: it is refused."""
    xy = np.column_stack([np.repeat(np.arange(40.0), 40), np.tile(np.arange(40.0), 40)])
    faces = np.column_stack([np.arange(1500), np.arange(1500) + 1, np.arange(1500) + 40])
    with pytest.raises(ValueError, match=r"\(1600,\) bool array"):
        display_subset(xy, faces, np.zeros(2), 1.0, 10, 100)


def test_the_view_draws_a_lighter_mesh_but_edges_and_exports_are_the_full_one(
    window, qtbot, tmp_path, monkeypatch
):
    import pyvista as pv

    monkeypatch.setattr(display_mesh, "DISPLAY_TRIANGLES", 500)
    window.panel.k.setValue(5)
    result = wait_result(qtbot, window, lambda o: o.result.params.k == 5).result
    full = result.triangle_mesh
    drawn = window.viewport.plotter.actors["mesh"].mapper.dataset
    assert 0 < drawn.n_cells < len(full.regular_faces) // 2
    assert {"height", "Normals"} <= set(drawn.point_data.keys())
    window.edges.setChecked(True)  # edges show the mesh as it is
    drawn = window.viewport.plotter.actors["mesh"].mapper.dataset
    assert drawn.n_cells == len(full.regular_faces) and drawn.n_points == len(full.points)
    window.edges.setChecked(False)  # (the drawn dataset may be updated in place)
    assert window.viewport.plotter.actors["mesh"].mapper.dataset.n_cells < len(full.regular_faces)
    out = tmp_path / "leaf.ply"
    assert exported(qtbot, window.save_mesh(str(out)))
    assert pv.read(out).n_points == len(full.points)  # the export is the full mesh


def test_the_background_is_one_colour_in_light_and_dark(window):
    """A gradient background is a full-view pass of its own in every render."""
    from PySide6.QtGui import QColor, QPalette

    renderer = window.viewport.plotter.renderer
    assert not renderer.GetGradientBackground()
    light = renderer.GetBackground()
    dark = QPalette()
    dark.setColor(QPalette.ColorRole.Base, QColor("#17181a"))
    window.setPalette(dark)
    assert not renderer.GetGradientBackground()
    assert max(renderer.GetBackground()) < 0.3 < min(light)


def test_the_view_has_no_light_behind_the_leaf(window):
    """Software OpenGL shades each pixel of the mesh once per light; pyvista's two back lights
    (camera lights behind the focal point) light nothing that faces the view."""
    lights = window.viewport.plotter.renderer.lights
    assert [light.is_camera_light and light.position[2] < 0 for light in lights] == [False] * 3
    assert sorted(light.intensity for light in lights) == [0.25, 0.25, 0.75]  # head, fill, key


def test_the_back_lights_dropped_leave_the_leaf_as_it_looked(window, qtbot):
    """The same image, to the eye, with pyvista's back lights added back (under 1 of 255 on
    average, in the iso, top and side views)."""
    import pyvista as pv

    viewport = window.viewport
    kit = pv.Plotter(off_screen=True)
    back = [light for light in kit.renderer.lights if light.position[2] < 0]
    kit.close()
    assert len(back) == 2
    for preset in ("iso", "top", "side"):
        viewport.camera(preset, render=False)
        viewport.plotter.render()
        without = viewport.image()
        for light in back:
            viewport.plotter.renderer.add_light(light)
        viewport.plotter.render()
        with_back = viewport.image()
        drop_back_lights(viewport.plotter.renderer)
        a, b = (np.asarray(image.constBits()).astype(float) for image in (without, with_back))
        assert 0 < np.abs(a - b).mean() < 1.0, preset


def test_a_status_text_repaints_the_window_once(window, qtbot):
    """A QLabel's new text laid the status bar out again and repainted the main window a second
    time a moment later: one more composition of the whole window with the 3D view (status.py)."""
    from PySide6.QtCore import QEvent, QObject
    from PySide6.QtGui import QPalette

    repaints: list[int] = []

    class Repaints(QObject):
        def eventFilter(self, obj, event):
            if event.type() == QEvent.Type.UpdateRequest and obj is window:
                repaints.append(1)
            return False

    settled(qtbot, window)  # whatever the first result left to paint
    spy = Repaints()
    window.installEventFilter(spy)
    window.status_text.setText("K=5, grid 48: gmm 3 ms · surface 4 ms (total 7 ms)")
    qtbot.wait(300)
    window.removeEventFilter(spy)
    assert len(repaints) == 1
    assert window.status_text.text().startswith("K=5")
    window.status_text.setStyleSheet("color: #b00020")  # how a failure is shown
    window.status_text.ensurePolished()
    assert window.status_text.palette().color(QPalette.ColorRole.WindowText).name() == "#b00020"


def test_no_measuring_while_a_slider_is_held(window, qtbot, monkeypatch):
    """Measuring holds the pipeline's lane (~0.1 s at grid 512): during a drag it would delay
    the drag's next value; the result the drag leaves is measured when the slider is let go."""
    measured: list[int] = []
    window.worker.done.connect(lambda kind, *_: kind == PIPELINE and measured.append(1))
    # not measured anyway DRAWN_WAIT_S after the result (for a window that never draws), which
    # a busy machine's main thread can reach before the check below
    monkeypatch.setattr(worker_module, "DRAWN_WAIT_S", WAIT_MS / 1000)
    monkeypatch.setattr(window.panel, "is_dragging", lambda: True)
    window.panel.k.setValue(5)
    qtbot.waitUntil(lambda: window.session.shown.outcome.result.params.k == 5, timeout=WAIT_MS)
    qtbot.wait(300)  # drawn by now, and not measured
    assert measured == [] and not window.worker.is_idle()
    monkeypatch.setattr(window.panel, "is_dragging", lambda: False)
    window.panel.released.emit()
    qtbot.waitUntil(lambda: measured == [1], timeout=WAIT_MS)
    assert window.session.shown.measured_id == window.session.shown_id


def test_a_new_layer_waits_for_the_render_of_an_actor_made_before_it(window, qtbot):
    """An opened scan recolours the mesh by height (a new actor) and adds its points (new
    actors too): each new kind of actor sets up its shaders at its first render, tens of ms of
    the main thread under software OpenGL, so the points wait for the mesh's render and each
    render sets up one (issue 24: the scan's opening stalled 56-60 ms in that one render)."""
    from functools import partial

    from leafstudio.gui.model.pieces import Piece, cloud, dots

    settled(qtbot, window)  # whatever the first result left to draw
    viewport = window.viewport
    scene: list[set[str]] = []  # the actors of each render
    viewport.plotter.render_window.AddObserver(
        "StartEvent", lambda *_: scene.append(set(viewport.plotter.actors))
    )
    points = np.random.default_rng(0).normal(size=(20_000, 3)) * [0.3, 0.1, 0.01]
    scan = [Piece("scan:blade", partial(cloud, points), dots("#2e7d32", 3.0, len(points)))]
    before = viewport.mesh_coloring
    viewport.set_mesh_coloring("height")  # a new mesh actor
    viewport.set_layer("scan", scan)
    qtbot.waitUntil(lambda: any("scan:blade" in names for names in scene), timeout=WAIT_MS)
    first = next(i for i, names in enumerate(scene) if "scan:blade" in names)
    assert first >= 1  # the recoloured mesh had a render of its own
    viewport.set_mesh_coloring(before)
    viewport.set_layer("scan", [])


def test_a_loaded_leafs_sketch_is_drawn_a_turn_after_its_first_result(window, qtbot, tmp_path):
    """A loaded leaf's sketch is derived from its first result: the session's work on that
    result (the derivation, the framing) and the editor's drawing of the sketch are two pauses
    of the main thread, not one (issue 24: 40 ms together for a 2-million-point scan's)."""
    from tests.gui.builders import write_points

    t = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    path = write_points(tmp_path / "leaf.csv", np.column_stack([np.cos(t), 0.4 * np.sin(t), 0 * t]))
    drawn_then = []
    session, editor = window.session, window.editor
    session.result_shown.connect(
        lambda *_: drawn_then.append(editor.view.sketch is session.derived)
    )
    assert window.open_path(path)
    qtbot.waitUntil(lambda: session.state.path == path, timeout=WAIT_MS)  # read
    wait_result(qtbot, window, lambda o: o.result.leaf is session.state.leaf)
    qtbot.waitUntil(lambda: editor.view.sketch is session.derived, timeout=WAIT_MS)
    assert drawn_then[0] is False


def test_a_result_that_fits_the_camera_makes_its_new_actors_a_turn_later(
    window, qtbot, monkeypatch
):
    """A new document's result fits the camera (10-15 ms of the main thread) and may need new
    actors (a scan with more veins than the leaf before: 4-6 ms each); both in one turn made
    the 2M-point scan's longest pause, 29-49 ms (issue 24). The pieces that reuse an actor are
    drawn with the fit, the new ones after its render."""
    from functools import partial

    from leafstudio.gui.model.layers import vein_color
    from leafstudio.gui.model.pieces import Piece, cloud, dots

    settled(qtbot, window)  # whatever the first result left to draw
    viewport = window.viewport
    outcome = window.session.shown.outcome
    log: list[str] = []
    viewport.plotter.render_window.AddObserver("StartEvent", lambda *_: log.append("render"))
    made = viewport.plotter.add_mesh
    monkeypatch.setattr(
        viewport.plotter, "add_mesh", lambda *a, **k: log.append("new") or made(*a, **k)
    )
    points = np.random.default_rng(0).normal(size=(40, 3)) * 0.1
    extra = Piece("points:vein99", partial(cloud, points), dots(vein_color(99), 7.0, 40))
    layers = {**outcome.layers, "points": [*outcome.layers["points"], extra]}
    viewport.show_layers(layers, outcome.result.frame, None, "reset")  # the blade's bounds kept
    assert log == []  # the fit done, nothing new made yet
    qtbot.waitUntil(lambda: "points:vein99" in viewport.actor_names("points"), timeout=WAIT_MS)
    assert log[:2] == ["render", "new"]  # made after the fit's render
    viewport.show_layers(outcome.layers, outcome.result.frame)


def test_an_opened_scans_main_thread_pieces_each_let_a_due_timer_fire(
    window, qtbot, tmp_path, monkeypatch
):
    """Opening a scan makes several main-thread pieces (its mesh recoloured by height, the
    session's work on its first result, its sketch, the result drawn, the renders, the layers
    that waited for a render), each tens of ms for a 2-million-point scan. A piece's "own turn"
    must let due timers and input in before it, or two pieces make one stall: a zero-delay call
    is a posted event, run before due timers (issue 24: 93 ms of the main thread's CPU between
    two ticks of bench_gui's 5 ms timer). A zero-interval timer, due at every turn, must fire
    between any two of them."""
    from PySide6.QtCore import QTimer

    from tests.gui.builders import six_column_scan, write_points

    settled(qtbot, window)  # whatever the first result left to draw
    log: list[str] = []
    probe = QTimer()
    probe.setInterval(0)
    probe.timeout.connect(lambda: log.append("tick"))

    def logged(owner, name: str) -> None:
        real = getattr(owner, name)
        monkeypatch.setattr(owner, name, lambda *a, **k: (log.append(name), real(*a, **k))[1])

    viewport, session = window.viewport, window.session
    for owner, name in (
        (viewport, "set_mesh_coloring"),
        (viewport, "_draw_later"),
        (window.session, "accept_drawable"),
        (window.editor.view, "set_sketch"),
        (window, "_show_result"),
    ):
        logged(owner, name)
    viewport.plotter.render_window.AddObserver("StartEvent", lambda *_: log.append("render"))
    path = write_points(tmp_path / "scan.txt", six_column_scan())
    probe.start()
    try:
        assert window.open_path(path)
        qtbot.waitUntil(lambda: session.state.scan is not None, timeout=WAIT_MS)  # read
        wait_result(qtbot, window, lambda o: o.result.leaf is session.state.leaf)
        qtbot.waitUntil(lambda: window.editor.view.sketch is session.derived, timeout=WAIT_MS)
        qtbot.waitUntil(window.worker.is_idle, timeout=WAIT_MS)
        settled(qtbot, window)  # the layers and renders queued behind it
    finally:
        probe.stop()
        monkeypatch.undo()
    pieces = [entry for entry in log if entry != "tick"]  # in order, a tick between each
    assert {"set_mesh_coloring", "accept_drawable", "set_sketch", "_show_result"} <= set(pieces)
    together = [pair for pair in itertools.pairwise(log) if "tick" not in pair]
    assert together == []


def test_an_opened_scans_points_wait_for_the_render_of_its_mesh_recoloured(window, qtbot, tmp_path):
    """Opening a scan recolours the mesh by height (a new actor) and adds the scan's points: the
    first render of each new kind of actor sets up its shaders (software OpenGL: tens of ms of
    the main thread), and both in one render were 29 ms of a 2M-point scan's main thread."""
    from tests.gui.builders import six_column_scan, write_points

    settled(qtbot, window)
    plotter, session, seen = window.viewport.plotter, window.session, []

    def on_render(*_: object) -> None:
        mesh = plotter.actors.get("mesh")
        shown = [a.GetVisibility() for n, a in plotter.actors.items() if n.startswith("scan:")]
        seen.append((mesh is not None and bool(mesh.mapper.GetScalarVisibility()), any(shown)))

    tag = plotter.render_window.AddObserver("StartEvent", on_render)
    try:
        assert window.open_path(write_points(tmp_path / "scan.txt", six_column_scan()))
        qtbot.waitUntil(lambda: session.state.scan is not None, timeout=WAIT_MS)
        wait_result(qtbot, window, lambda o: o.result.leaf is session.state.leaf)
        settled(qtbot, window)
    finally:
        plotter.render_window.RemoveObserver(tag)
    assert next(s for s in seen if s[0]) == (True, False)  # the recoloured mesh's render alone
    assert seen[-1] == (True, True)


def test_a_loaded_leafs_sketch_is_derived_with_its_curves_off_the_main_thread(
    window, qtbot, tmp_path, monkeypatch
):
    """The sketch derived from a loaded leaf's first result, with the splines of its curves,
    is the worker's work (issue 24: 18 + 15 ms of the main thread for a 2M-point scan's)."""
    import threading

    from leafstudio.gui.model.sketch_model import BOUNDARY, Sketch
    from tests.gui.builders import write_points

    threads: list[int] = []
    real = Sketch.from_result
    monkeypatch.setattr(
        Sketch, "from_result", lambda r: (threads.append(threading.get_ident()), real(r))[1]
    )
    t = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    path = write_points(tmp_path / "leaf.csv", np.column_stack([np.cos(t), 0.4 * np.sin(t), 0 * t]))
    session = window.session
    assert window.open_path(path)
    qtbot.waitUntil(lambda: session.state.path == path, timeout=WAIT_MS)  # read
    wait_result(qtbot, window, lambda o: o.result.leaf is session.state.leaf)
    qtbot.waitUntil(lambda: window.editor.view.sketch is session.derived, timeout=WAIT_MS)
    assert threads and threading.get_ident() not in threads
    made = session.derived.__dict__.get("_curves", {})
    assert set(made) == {BOUNDARY, *range(len(session.derived.veins))}


def test_a_results_mesh_and_its_other_layers_are_drawn_in_two_turns_then_rendered_once(
    window, qtbot, monkeypatch
):
    """A result's layers made one main-thread pause of 17-48 ms for a 2M-point scan (issue
    24): the mesh is drawn with the result, the other layers in a later turn (a due timer
    fires between), and the render comes after both, once."""
    from PySide6.QtCore import QTimer

    settled(qtbot, window)  # whatever the first result left to draw
    viewport, log = window.viewport, []
    real = viewport._draw_layer
    monkeypatch.setattr(viewport, "_draw_layer", lambda key, *a: (log.append(key), real(key, *a)))
    viewport.plotter.render_window.AddObserver("StartEvent", lambda *_: log.append("render"))
    probe = QTimer()
    probe.setInterval(0)
    probe.timeout.connect(lambda: log.append("tick"))
    outcome = window.session.shown.outcome
    probe.start()
    viewport.show_layers(outcome.layers, outcome.result.frame)
    assert log == ["mesh"]
    qtbot.waitUntil(lambda: "render" in log, timeout=WAIT_MS)
    settled(qtbot, window)  # a second render would come after it
    probe.stop()
    drawn = [entry for entry in log if entry != "tick"]
    assert drawn == [
        "mesh",
        *[k for k in outcome.layers if k != "mesh" and viewport.visible[k]],
        "render",
    ]
    assert log.index("tick") < log.index(drawn[1])
