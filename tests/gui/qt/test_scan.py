"""Scans in the app: a scan opens as its extracted leaf (an editable sketch), its points are a
layer, the measurements panel reports its distances to each new mesh; a bad scan keeps the leaf;
the Poisson layer is computed when switched on and drawn beside our mesh."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QListWidgetItem

from leafstudio import workflows
from leafstudio.gui.model import scans
from leafstudio.gui.qt.main_window import MainWindow
from leafstudio.model import Leaf
from leafstudio.sources.scan import is_scan_file, looks_like_scan
from tests.gui.builders import FAST, six_column_scan, write_points

from .conftest import WAIT_MS, close_window, make_window, wait_result

FIDELITY = "Scan → mesh distance (blade points)"


def layer_item(window: MainWindow, key: str) -> QListWidgetItem:
    for row in range(window.layer_list.count()):
        item = window.layer_list.item(row)
        if item.data(Qt.ItemDataRole.UserRole) == key:
            return item
    raise KeyError(key)


def panel_section(window: MainWindow, title: str) -> dict[str, str]:
    for i in range(window.measurements.topLevelItemCount()):
        section = window.measurements.topLevelItem(i)
        if section.text(0) == title:
            return {
                section.child(j).text(0): section.child(j).text(1)
                for j in range(section.childCount())
            }
    return {}


def wait_fidelity(qtbot, window: MainWindow) -> dict[str, str]:
    """Wait until the shown result's scan distances are in the panel; return their rows."""
    qtbot.waitUntil(
        lambda: (
            window.session.shown.fidelity is not None
            and window.session.shown.fidelity[0] == window.session.last_id
            and window.session.result is not None
            and window.session.result.leaf is window.session.state.leaf
            and bool(panel_section(window, FIDELITY))
        ),
        timeout=WAIT_MS,
    )
    return panel_section(window, FIDELITY)


def record_threads(monkeypatch, name: str, module=scans) -> list[int]:
    """Record the thread of every call to module.`name` (a core geometry function)."""
    threads: list[int] = []
    real = getattr(module, name)

    def recording(*args, **kwargs):
        threads.append(threading.get_ident())
        return real(*args, **kwargs)

    monkeypatch.setattr(module, name, recording)
    return threads


@pytest.fixture
def scan_window(qtbot, tmp_path, monkeypatch):
    """A window that opened a synthetic 6-column scan (as `leafstudio gui SCAN` would)."""
    win = make_window(qtbot, tmp_path / "settings.ini", FAST)
    win.extract_threads = record_threads(monkeypatch, "extract_leaf", workflows)
    path = write_points(tmp_path / "scan.txt", six_column_scan())
    assert win.open_path(path)  # a scan, not a leaf: read and extracted off the main thread
    wait_fidelity(qtbot, win)
    yield win
    close_window(win)


def test_a_scan_opens_as_an_editable_leaf_with_its_points_and_distances(
    scan_window, qtbot, tmp_path
):
    window = scan_window
    extracted = window.session.state.scan.extraction.leaf
    assert window.session.state.leaf is extracted and window.session.state.path.endswith("scan.txt")
    assert window.extract_threads and threading.main_thread().ident not in window.extract_threads
    assert window.session.result.mesh.n_points > 100 and "mesh" in window.viewport.plotter.actors
    sketch = window.editor.view.sketch
    assert len(sketch.boundary) >= 3 and len(sketch.veins) == len(extracted.veins) >= 1

    rows = wait_fidelity(qtbot, window)
    assert int(rows["Points"]) == window.session.state.scan.extraction.blade.sum() > 500
    mean, top = float(rows["Mean"]), float(rows["Max"])
    assert 0 < mean < 0.01 * window.session.result.length and mean <= top
    assert rows["Beyond 2% of length"].endswith("%")
    assert window.measurements.topLevelItem(0).text(0) == FIDELITY  # shown first
    assert panel_section(window, "Scan → mesh distance (all points)")

    actors = window.viewport.plotter.actors
    assert actors["scan:blade"].GetVisibility()
    assert layer_item(window, "scan").flags() & Qt.ItemFlag.ItemIsEnabled
    assert (
        actors["scan:blade"].mapper.dataset.n_points
        == window.session.state.scan.extraction.blade.sum()
    )
    layer_item(window, "scan").setCheckState(Qt.CheckState.Unchecked)
    assert not actors["scan:blade"].GetVisibility()
    layer_item(window, "scan").setCheckState(Qt.CheckState.Checked)
    assert actors["scan:blade"].GetVisibility()

    view = window.editor.view  # an edit: a new leaf, a new mesh, its distances recomputed
    view.selected = (-1, 0)
    view.delete_selected()
    assert window.isWindowModified() and window.session.state.leaf is not extracted
    wait_fidelity(qtbot, window)
    assert window.session.state.scan is not None and window.session.history.can_undo()
    window.session.history.undo()
    assert window.session.state.leaf is extracted
    wait_fidelity(qtbot, window)

    turn = np.linspace(0, 2 * np.pi, 40, endpoint=False)  # a leaf with no scan: greyed out again
    outline = np.column_stack([np.cos(turn), 0.4 * np.sin(turn)])
    path = write_points(tmp_path / "leaf.csv", outline)
    window.session.history.set_clean()
    assert window.open_path(path)
    qtbot.waitUntil(lambda: window.session.state.scan is None, timeout=WAIT_MS)
    assert not layer_item(window, "scan").flags() & Qt.ItemFlag.ItemIsEnabled
    assert layer_item(window, "scan").checkState() == Qt.CheckState.Checked  # the tick kept


def test_the_scan_layer_is_greyed_out_while_no_scan_is_open(window):
    """Ticked by default, "Scan points" looked shown for a leaf with no scan (the demo); it is
    greyed out, its tick kept for the next scan."""
    item = layer_item(window, "scan")
    assert window.session.state.scan is None
    assert not item.flags() & Qt.ItemFlag.ItemIsEnabled
    assert item.checkState() == Qt.CheckState.Checked
    assert layer_item(window, "mesh").flags() & Qt.ItemFlag.ItemIsEnabled


def test_a_bad_scan_shows_a_dialog_and_keeps_the_mesh(window, qtbot, tmp_path):
    leaf, mesh = window.session.state.leaf, window.session.result.mesh
    line = np.column_stack([np.linspace(0, 1, 80), np.zeros((80, 2)), np.ones((80, 3))])
    for name, path in (
        ("line.txt", write_points(tmp_path / "line.txt", line)),  # read, but no blade in it
        ("broken.pcd", str(tmp_path / "broken.pcd")),  # no such file
    ):
        with qtbot.waitSignal(window.failure_shown, timeout=WAIT_MS) as failure:
            assert window.open_path(path)
        assert name in failure.args[0] and "\n" not in failure.args[0]
        box = window.last_error_box
        assert box.isVisible() and name in box.text()
        box.close()
        assert (
            window.session.state.leaf is leaf
            and window.session.result.mesh is mesh
            and window.session.state.scan is None
        )
        assert "mesh" in window.viewport.plotter.actors


@pytest.mark.open3d
def test_the_poisson_layer_appears_beside_our_mesh_when_switched_on(window, qtbot, monkeypatch):
    threads = record_threads(monkeypatch, "poisson_surface")
    assert "poisson" not in window.viewport.plotter.actors  # off: not computed
    layer_item(window, "poisson").setCheckState(Qt.CheckState.Checked)
    qtbot.waitUntil(lambda: "poisson" in window.viewport.plotter.actors, timeout=WAIT_MS)
    actor = window.viewport.plotter.actors["poisson"]
    assert actor.GetVisibility() and actor.prop.opacity < 1
    assert len(threads) == 1 and threads[0] != threading.main_thread().ident
    side = window.session.result.frame.v
    ours = np.asarray(window.session.result.mesh.points) @ side
    theirs = np.asarray(actor.mapper.dataset.points) @ side
    assert theirs.min() > ours.max()  # beside ours, not over it
    window.panel.k.setValue(4)  # same leaf: the surface stays
    wait_result(qtbot, window, lambda o: o.result.params.k == 4)
    assert window.viewport.plotter.actors["poisson"] is actor and len(threads) == 1
    layer_item(window, "poisson").setCheckState(Qt.CheckState.Unchecked)
    assert not actor.GetVisibility()


def test_scans_are_told_from_leaves(tmp_path):
    scan = six_column_scan()
    assert looks_like_scan(Leaf(boundary=scan[:, :3], veins=[]))
    t = np.linspace(0, 2 * np.pi, 300, endpoint=False)
    outline = np.column_stack([np.cos(t), 0.4 * np.sin(t), 0.05 * np.sin(3 * t)])
    assert not looks_like_scan(Leaf(boundary=outline, veins=[]))
    assert not looks_like_scan(Leaf(boundary=scan[:, :3], veins=[scan[:5, :3]]))
    assert is_scan_file(write_points(tmp_path / "wide.csv", scan))
    assert not is_scan_file(write_points(tmp_path / "leaf.csv", scan[:, :4]))
    assert is_scan_file(str(tmp_path / "any.pcd"))


def test_a_scan_still_being_read_is_superseded_by_a_later_open(window, qtbot, tmp_path):
    path = write_points(tmp_path / "scan.txt", six_column_scan())
    assert window.open_path(path)
    window.open_demo("parallel")  # opened before the scan is read: the demo stays
    demo_leaf = window.session.state.leaf
    qtbot.waitUntil(window.worker.is_idle, timeout=WAIT_MS)
    wait_result(qtbot, window, lambda o: o.result.leaf is demo_leaf)
    assert (
        window.session.state.leaf is demo_leaf
        and window.session.state.scan is None
        and window.session.state.path is None
    )


def test_a_scans_warning_stays_on_the_status_line_whenever_its_distances_come_in(
    qtbot, tmp_path, monkeypatch
):
    """The scan's distances are measured on the side lane as soon as a result is in; when they
    came in before the result was drawn, their warning ("the surface folds back on itself")
    was appended to the status line and then replaced by the result's own text (soybean
    pot1_1's screenshot showed none). The window now says the scan's warnings with the
    result's."""
    real = scans.fidelity_sections

    def warning(result, scan):
        sections, _ = real(result, scan)
        return sections, ["the surface folds back on itself at 0.8% of its edges"]

    monkeypatch.setattr(scans, "fidelity_sections", warning)
    drawn = MainWindow._show_result

    def after_the_distances(self):  # the order that lost the warning, made certain
        qtbot.waitUntil(lambda: self.session.shown.fidelity is not None, timeout=WAIT_MS)
        drawn(self)

    monkeypatch.setattr(MainWindow, "_show_result", after_the_distances)
    window = make_window(qtbot, tmp_path / "settings.ini", FAST)
    assert window.open_path(write_points(tmp_path / "scan.txt", six_column_scan()))
    wait_fidelity(qtbot, window)
    qtbot.waitUntil(lambda: "shown in" in window.status_text.text(), timeout=WAIT_MS)
    qtbot.wait(200)  # anything else due on the status line
    assert "folds back on itself" in window.status_text.text()
    close_window(window)


def test_a_scans_first_sketch_edit_is_said_in_the_window_and_one_undo_brings_the_scan_back(
    scan_window, qtbot
):
    """Session 31, noticed: the first edit of a scan's sketch replaced the scan's outline and
    veins by the sketch's curves without a word. The status line says so (still once the
    edit's result is drawn), a note over the sketch says it while the sketch draws the leaf,
    and one Undo brings the scan's own outline back, the note gone."""
    window, session = scan_window, scan_window.session
    opened, polygon = session.state.leaf, session.result.polygon.copy()
    boundary = opened.boundary.copy()
    note = window.editor.outline_note
    assert not note.isVisible()
    view = window.editor.view  # the user's edit: a boundary point deleted in the editor
    view.selected = (-1, 0)
    view.delete_selected()
    assert session.state.leaf is not opened
    assert "replaced the scan's outline and veins" in window.status_text.text()
    assert note.isVisible() and "Drawn by the sketch" in note.text()
    wait_result(qtbot, window, lambda o: o.result.leaf is session.leaf)
    qtbot.waitUntil(lambda: "shown in" in window.status_text.text(), timeout=WAIT_MS)
    assert "replaced the scan's outline and veins" in window.status_text.text()
    window.actions["edit.undo"].trigger()  # one Undo
    assert session.state.leaf is opened and np.array_equal(session.leaf.boundary, boundary)
    assert not note.isVisible()
    wait_result(qtbot, window, lambda o: o.result.leaf is opened)
    np.testing.assert_array_equal(session.result.polygon, polygon)
    window.actions["edit.redo"].trigger()
    assert note.isVisible()


def test_the_scans_outline_note_lets_clicks_through_to_the_sketch(scan_window, qtbot):
    """review32: the note over the sketch's foot stays while the sketch draws the leaf, and it
    took the clicks over it: at the window's 1500 x 920 it covered 50 of the view's 262 pixels,
    where a click added no point. A click there reaches the sketch."""
    from PySide6.QtTest import QTest

    window, session = scan_window, scan_window.session
    view, note = window.editor.view, window.editor.outline_note
    view.selected = (-1, 0)
    view.delete_selected()  # the first edit: the note shows
    wait_result(qtbot, window, lambda o: o.result.leaf is session.leaf)
    assert note.isVisible()
    count = len(session.state.sketch.boundary)
    under = view.childAt(note.geometry().center())  # what the window system clicks there
    QTest.mouseClick(
        under, Qt.MouseButton.LeftButton, pos=under.mapFrom(view, note.geometry().center())
    )
    assert under is not note and len(session.state.sketch.boundary) == count + 1


def test_the_pose_terms_tips_say_scan_for_a_scan_and_saved_from_one_for_its_project(
    scan_window, qtbot, tmp_path
):
    """closing32: the Forms dock's pose boxes and the Fold/Curl/Roll/Twist sliders, off for a
    leaf bent by its scan's sheet, said "This scan…" for a project saved from a scan too, where
    no scan is open."""
    window = scan_window
    boxes, sliders = window.forms_panel.pose_boxes, window.bend.sliders
    tips = [w.toolTip() for w in (*boxes.values(), *sliders.values())]
    assert all(tip.startswith("This scan is bent") for tip in tips)
    project = str(tmp_path / "scan.leaf.json")
    assert window.save_to(project)
    assert window.open_path(project)
    state = window.session.state  # saved: its path is the project's already
    qtbot.waitUntil(lambda: window.session.state.serial != state.serial, timeout=WAIT_MS)
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.leaf)
    assert window.session.state.path == project and window.session.state.scan is None
    assert window.session.leaf.bend is not None
    for widget in (*boxes.values(), *sliders.values()):
        assert not widget.isEnabled()
        assert widget.toolTip().startswith("This leaf, saved from a scan, is bent"), widget


def test_the_note_over_the_sketch_closes_and_stays_closed_until_it_says_something_new(
    scan_window, qtbot
):
    """closing32: the note over the sketch's foot after a scan's first sketch edit could not
    be dismissed. Its close control (inside it; the rest of it lets clicks through to the
    sketch) hides it, further edits keep it hidden; undone back to the scan and redone, it is
    said anew."""
    from PySide6.QtTest import QTest

    window, session = scan_window, scan_window.session
    editor, view = window.editor, window.editor.view
    note, close = editor.outline_note, editor.outline_close
    view.selected = (-1, 0)
    view.delete_selected()
    assert note.isVisible() and close.isVisible()
    assert note.geometry().contains(close.geometry())
    assert note.testAttribute(Qt.WidgetAttribute.WA_TransparentForMouseEvents)
    QTest.mouseClick(close, Qt.MouseButton.LeftButton)
    assert not note.isVisible() and not close.isVisible()
    wait_result(qtbot, window, lambda o: o.result.leaf is session.leaf)
    view.selected = (-1, 3)
    view.delete_selected()  # a second edit: still drawn by the sketch, nothing new to say
    assert session.outline_note and not note.isVisible()
    window.actions["edit.undo"].trigger()
    window.actions["edit.undo"].trigger()  # the scan's own curves back: nothing to say
    assert not session.outline_note and not note.isVisible()
    window.actions["edit.redo"].trigger()  # replaced again: said again
    assert note.isVisible() and close.isVisible()


def test_a_result_with_many_notes_reads_in_a_window_1280_wide(qtbot, tmp_path):
    """closing32: with a scan open the status line ran its notes one after another (450
    characters after a sketch edit), cut at about 150 in a window 1280 wide: the later notes
    and the measuring time after them were not on screen. The line now says its head (the
    measuring time in it) and its first note; a button counts the notes, every note whole in
    its tooltip and in the box it opens."""
    from PySide6.QtTest import QTest

    window = make_window(qtbot, tmp_path / "settings.ini", FAST)
    window.resize(1280, 720)
    t = np.linspace(0, 2 * np.pi, 80, endpoint=False)  # a flat blade: the result notes it
    boundary = np.column_stack([0.5 + 0.5 * np.cos(t), 0.2 * np.sin(t), 0 * t])
    midrib = np.column_stack([np.linspace(0.02, 0.98, 12), np.zeros(12), np.zeros(12)])
    window.session.new_document(Leaf(boundary, [midrib]), title="flat")
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.leaf)
    status, button = window.status_text, window.notes_button
    qtbot.waitUntil(lambda: "measured in" in status.text(), timeout=WAIT_MS)
    first = status.line().notes[0]
    later = [  # the scan's distances' warnings, as they come (MainWindow._on_side_note)
        "the surface is 1.0% of the leaf's length from the scan on average (95% of points "
        "within 2.8%): it does not follow this scan well",
        "the surface folds back on itself at 0.5% of its edges (creases past 90°), where the "
        "scan is doubled or its blade curls under: compare it with the scan's points first",
    ]
    for note in later:
        window._on_side_note(note)
    head, _, rest = status.text().partition(" — ")
    assert "measured in" in head and rest.lower().startswith(first.lower())
    shown = status.fontMetrics().elidedText(status.text(), Qt.TextElideMode.ElideRight,
                                            status.width())  # fmt: skip
    assert status.width() < 1280 and shown.lower().startswith(f"{head} — {first[:40]}".lower())
    assert button.isVisible() and button.text().endswith("3 notes")
    for note in (first, *later):
        assert note[1:] in button.toolTip() and note[1:] in status.toolTip()
    QTest.mouseClick(button, Qt.MouseButton.LeftButton)
    assert button.box is not None and later[1][1:] in button.box.text()
    # closing33: the tooltips said the notes in lower case, the box capitalised them; each is
    # said alike in all three (status_line.said), as a sentence
    boxed = button.box.text().split("\n\n")
    assert boxed[0][0].isupper() and boxed[1:] == [n[:1].upper() + n[1:] for n in later]
    for tip in (button.toolTip(), status.toolTip()):
        assert [line[2:] for line in tip.splitlines() if line.startswith("• ")] == boxed
    button.box.close()
    window.status_text.setText("Opening cancelled")  # a message of its own: no notes
    assert not button.isVisible()
    close_window(window)
