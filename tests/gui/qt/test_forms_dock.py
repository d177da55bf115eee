"""The Forms gallery: thumbnails drawn once, definitions beside the choosers, a chosen form as the
document (an editable sketch, one undo step), veins grown in the current outline."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from PySide6.QtCore import QSize, Qt
from PySide6.QtGui import QImage
from PySide6.QtWidgets import QDockWidget

from leafstudio.core.bend import Pose
from leafstudio.forms import SHAPES, Form
from leafstudio.forms.terms import RELIEF
from leafstudio.gui.model.bending import can_pose
from leafstudio.gui.model.form_sketch import leaf_sketch, with_grown_veins
from leafstudio.gui.qt import forms_dock
from leafstudio.gui.qt.forms_dock import FormsPanel, thumbnail
from leafstudio.model import Leaf
from leafstudio.sources.demos import demo
from tests.gui.builders import six_column_scan, write_points
from tests.gui.qt.conftest import WAIT_MS, close_window, image_pixels, make_window, wait_result


@pytest.fixture
def panel(window):
    existing = getattr(window, "forms_panel", None)
    return existing if existing is not None else forms_dock.install(window)


def test_every_shape_has_a_thumbnail_drawn_once(qtbot):
    for name in SHAPES:
        image = thumbnail(name)
        assert image is thumbnail(name)  # cached
        width, height = forms_dock.THUMBNAIL
        alpha = np.array([image.pixelColor(x, height - 6).alpha() for x in range(0, width, 3)])
        assert alpha.max() > 0  # something drawn near the bottom: the leaf sits on it
    widget = FormsPanel()
    qtbot.addWidget(widget)
    assert widget.gallery.count() == len(SHAPES)


def test_the_gallerys_thumbnails_are_mostly_leaf_not_blank_bands(qtbot):
    """Drawn in squares, the forms (base to apex across) left a band of nothing above them:
    48% of a thumbnail's rows on average, 92% for linear. Landscape frames fit them."""
    empty = []
    for name in SHAPES:
        image = thumbnail(name).convertToFormat(QImage.Format.Format_Alpha8)
        rows = np.frombuffer(image.constBits(), np.uint8, image.sizeInBytes())
        drawn = rows.reshape(image.height(), image.bytesPerLine())[:, : image.width()] > 0
        empty.append(1 - drawn.any(axis=1).mean())
        assert drawn.any(axis=0).mean() > 0.5 or name in ("orbicular", "reniform", "hastate")
    assert np.mean(empty) < 0.35


def test_a_new_window_grows_the_gallerys_veins_off_the_main_thread(qtbot, tmp_path, monkeypatch):
    """The gallery opens with each form's outline and shows its veins once a side lane has grown
    them, after the first leaf is on screen (0.7 s the window's first start waited for on the
    main thread)."""
    monkeypatch.setattr(forms_dock, "_thumbnails", {})  # as in a new process
    growers = []
    grow = Form.leaf
    monkeypatch.setattr(
        Form, "leaf", lambda form: growers.append(threading.get_ident()) or grow(form)
    )
    window = make_window(qtbot, tmp_path / "settings.ini")
    gallery = window.forms_panel.gallery
    window.open_demo("nested")  # as the app starts
    wait_result(qtbot, window)  # the veins grow once the first leaf is on screen
    qtbot.waitUntil(lambda: not window.forms_panel.missing_veins(), timeout=WAIT_MS)
    assert not window.forms_panel.veins_due()
    qtbot.waitUntil(lambda: window.worker.is_idle(), timeout=WAIT_MS)
    assert len(growers) == len(SHAPES) and threading.get_ident() not in growers
    for row in range(gallery.count()):
        item = gallery.item(row)
        shown = item.icon().pixmap(QSize(*forms_dock.THUMBNAIL)).toImage()
        veined = thumbnail(item.data(Qt.ItemDataRole.UserRole))
        assert np.array_equal(image_pixels(shown), image_pixels(veined))
        assert not np.array_equal(
            image_pixels(shown), image_pixels(forms_dock.outline_thumbnail(item.text()))
        )
    close_window(window)


def test_each_choice_shows_its_definition(qtbot):
    widget = FormsPanel()
    qtbot.addWidget(widget)
    widget.margin.setCurrentText("serrate")
    assert "toward the apex" in widget.texts["Margin"].text()
    assert widget.teeth.isEnabled() and not widget.lobes.isEnabled()
    widget.venation.setCurrentText("palmate")
    assert "from the base" in widget.texts["Venation"].text()
    widget.gallery.setCurrentRow(list(SHAPES).index("cordate"))
    assert not widget.base.isEnabled()  # the shape's own base
    assert "heart" in widget.shape_text.text()
    widget.gallery.setCurrentRow(list(SHAPES).index("oblong"))
    assert widget.texts["Base"].text().startswith("rounded: the base is")  # not the apex's words
    seed = widget.seed.value()
    widget.variant.click()
    assert widget.seed.value() == seed + 1 and widget.form().seed == seed + 1


def choose(qtbot, window, panel) -> None:
    """Choose the panel's form, and wait for its document: a blade grows on a lane."""
    serial = window.session.state.serial
    panel.choose_now()
    qtbot.waitUntil(lambda: window.session.state.serial != serial, timeout=WAIT_MS)


def test_a_chosen_form_becomes_the_document_as_an_editable_sketch(window, panel, qtbot):
    assert isinstance(window.docks["Forms"], QDockWidget)
    before = window.session.leaf
    panel.gallery.setCurrentRow(list(SHAPES).index("cordate"))
    panel.margin.setCurrentText("serrate")
    choose(qtbot, window, panel)
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.leaf)
    state = window.session.state
    assert state.sketch is not None and len(state.sketch.boundary) >= 40
    assert state.leaf.boundary[:, 0].min() < 0  # the cordate lobes
    assert "cordate" in state.title
    window.session.undo()  # one undo step brings the demo back
    assert window.session.leaf is before


def _highlighted(panel) -> str | None:
    item = panel.gallery.currentItem()
    return None if item is None else item.data(Qt.ItemDataRole.UserRole)


def test_the_gallery_highlights_the_open_forms_shape_or_nothing(window, panel, qtbot):
    """The gallery highlighted "ovate" whatever leaf was open (the demo, a scan, a cordate form
    made from it): it highlights the open form's shape, and nothing for a leaf that is not a
    form, through undo and redo; following the document chooses nothing itself."""
    wait_result(qtbot, window)
    assert _highlighted(panel) is None  # the nested demo: not a form
    assert "pick a shape" in panel.shape_text.text()
    panel.gallery.setCurrentRow(list(SHAPES).index("cordate"))
    choose(qtbot, window, panel)
    assert _highlighted(panel) == "cordate"
    window.session.new_document(demo("parallel"), title="parallel")  # File > Open, say
    assert _highlighted(panel) is None
    qtbot.wait(3 * forms_dock.DEBOUNCE_MS)
    assert window.session.state.title == "parallel"  # no form chosen by the change
    window.session.undo()
    assert _highlighted(panel) == "cordate"
    window.session.undo()
    assert _highlighted(panel) is None
    window.session.redo()
    assert _highlighted(panel) == "cordate"


def test_grow_veins_fills_the_current_outline_as_one_step(window, panel, qtbot):
    wait_result(qtbot, window)
    veins_before = len(window.session.leaf.veins)
    panel.venation.setCurrentText("arcuate")
    panel.grow_button.click()
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.leaf)
    grown = window.session.leaf
    assert len(grown.veins) >= 5 and len(grown.veins) != veins_before
    window.session.undo()
    assert len(window.session.leaf.veins) == veins_before
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.leaf)
    window.editor.grow_kind.setCurrentText("parallel")  # the same from the sketch editor
    window.editor.grow_button.click()
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.leaf)
    veins = window.session.leaf.veins
    assert len(veins) == 7 and all(v[-1, 0] - v[0, 0] > 0.8 for v in veins)  # base to apex


def test_a_forms_sketch_keeps_tooth_tips():
    from leafstudio.forms import Form

    leaf = Form("elliptic", margin="dentate", teeth=20).leaf()
    sketch = leaf_sketch(leaf, 20)
    curve = sketch.boundary_curve()
    assert np.ptp(curve[:, 1]) == pytest.approx(np.ptp(leaf.boundary[:, 1]), rel=0.05)


def test_every_forms_sketch_curve_is_a_simple_outline():
    import itertools

    from leafstudio.core.prepare.polygon import ring_crossings
    from leafstudio.forms import Form
    from leafstudio.forms.terms import MARGINS

    for shape, margin in itertools.product(SHAPES, MARGINS):
        form = Form(shape, margin=margin)
        # the outline alone: the sketch's boundary is drawn from it (growing each form's veins,
        # which this does not look at, took 10 s)
        xy = form.outline().xy
        sketch = leaf_sketch(Leaf(np.column_stack([xy, np.zeros(len(xy))]), []), form.teeth_count)
        assert len(ring_crossings(sketch.boundary_curve())) == 0, (shape, margin)


def _click_outside_the_boundary(qtbot, view) -> None:
    """One drawing click just outside the boundary, between two of its control points (never on
    one): the editor adds one boundary point to the sketch it shows."""
    from tests.gui.qt.test_sketch import click

    boundary = view.sketch.boundary
    gaps = np.linalg.norm(np.roll(boundary, -1, axis=0) - boundary, axis=1)
    widest = int(np.argmax(gaps))
    middle = 0.5 * (boundary[widest] + boundary[(widest + 1) % len(boundary)])
    xy = middle + 0.02 * (middle - boundary.mean(axis=0))
    assert view.hit(view.view_point(xy)) is None  # a click there adds a point
    click(qtbot, view, xy)


def test_grown_veins_are_what_the_sketch_editor_shows_and_the_next_click_edits(
    window, panel, qtbot
):
    """Review s3 finding 2: after Grow veins the editor kept the old sketch, so the next click
    committed the old veins (7) and threw the grown ones (10) away."""
    session, view = window.session, window.editor.view
    before = session.editable_sketch()
    panel.grow.emit("pinnate")
    wait_result(qtbot, window, lambda o: o.result.leaf is session.leaf)
    grown = session.state.sketch
    assert len(grown.veins) != len(before.veins)
    assert view.sketch is grown  # the editor shows the grown veins
    assert window.editor.curve.count() >= len(grown.veins) + 1  # and lists them
    _click_outside_the_boundary(qtbot, view)
    after = session.state.sketch
    assert after is not grown and len(after.boundary) == len(grown.boundary) + 1
    assert len(after.veins) == len(grown.veins)  # the grown veins are kept
    assert all(np.array_equal(a, b) for a, b in zip(after.veins, grown.veins, strict=True))
    session.undo()  # the click
    session.undo()  # Grow veins is one step
    assert view.sketch is before  # the loaded leaf's derived sketch again


def test_growing_veins_keeps_mirror_on(window, panel, qtbot):
    """Review s3 finding 2: Grow veins built a new sketch without the saved Mirror flag."""
    session, editor = window.session, window.editor
    editor.mirror.setChecked(True)
    panel.grow.emit("pinnate")
    wait_result(qtbot, window, lambda o: o.result.leaf is session.leaf)
    assert session.state.sketch.symmetric
    assert editor.view.sketch is session.state.sketch and editor.mirror.isChecked()
    grown = session.state.sketch
    _click_outside_the_boundary(qtbot, editor.view)
    after = session.state.sketch
    assert after is not grown and after.symmetric
    # a mirrored edit keeps the clicked side's veins and reflects them: grown veins, never the
    # demo's old ones (the midrib and at least one side vein are the grown ones, unchanged)
    kept = [g for g in grown.veins if any(np.array_equal(a, g) for a in after.veins)]
    assert len(kept) >= 2 and np.array_equal(after.veins[0], grown.veins[0])


def test_with_grown_veins_keeps_the_sketchs_other_fields():
    from dataclasses import replace

    from leafstudio.forms import Form

    leaf = Form("elliptic").leaf()
    sketch = replace(leaf_sketch(leaf, 0), symmetric=True)
    grown = with_grown_veins(sketch, "pinnate")
    assert grown.symmetric and grown.frame is sketch.frame
    assert np.array_equal(grown.boundary, sketch.boundary) and len(grown.veins) >= 3


def test_every_pose_the_dock_allows_is_shown_without_a_side_on_note(window, panel, qtbot):
    """elliptic folded 75 degrees stood on edge to the plane the reconstruction fitted, and the
    dock said so under the pose; a form now knows its pose and is reconstructed on its flat
    blade (issue 21), so no note is needed."""
    panel.gallery.setCurrentRow(list(SHAPES).index("elliptic"))
    panel.fold.setValue(75.0)
    choose(qtbot, window, panel)
    assert window.session.leaf.bend.fold == 75.0
    assert not panel.pose_note.isVisibleTo(panel)


def test_a_folded_tube_picked_says_its_roll_was_eased_off_its_seam(window, panel, qtbot):
    """elliptic folded 75 and rolled 1 came in rolled 0.99 (pose_limits.SEAM_SHARE: closed to
    its seam its sheet passed through itself), as `form` says, but the dock said nothing
    (bowls38): the note under the pose says so, and is gone for a roll taken as asked."""
    panel.gallery.setCurrentRow(list(SHAPES).index("elliptic"))
    panel.fold.setValue(75.0)
    panel.roll.setValue(1.0)
    choose(qtbot, window, panel)
    assert panel.pose_note.isVisibleTo(panel)
    assert "Roll 1 eased to 0.99" in panel.pose_note.text(), panel.pose_note.text()
    panel.roll.setValue(0.5)  # the same blade (a blade grown for another would be kept)
    choose(qtbot, window, panel)
    assert window.session.pose.roll == pytest.approx(0.5 * np.pi / window.session.half_width)
    assert not panel.pose_note.isVisibleTo(panel)


def test_a_chosen_forms_veins_grow_off_the_main_thread_and_a_pose_change_grows_none(
    window, panel, qtbot, monkeypatch
):
    """Choosing a form grew its veins on the main thread (70-100 ms held, issue 24: no stall
    over 50 ms), and each change of a pose slider grew them again; the blade now grows on a
    lane, the dock keeps the last one and a pose change only poses it."""
    grown: list[tuple[Form, bool]] = []
    blade = Form.blade_and_note

    def spy(form: Form) -> tuple:
        grown.append((form, threading.current_thread() is threading.main_thread()))
        return blade(form)

    monkeypatch.setattr(Form, "blade_and_note", spy)
    panel.gallery.setCurrentRow(list(SHAPES).index("ovate"))
    choose(qtbot, window, panel)
    for fold in (30.0, 60.0):
        panel.fold.setValue(fold)
        panel.choose_now()  # at once: the kept blade, posed
        assert window.session.leaf.bend.fold == fold
    assert [(f.shape, on_main) for f, on_main in grown] == [("ovate", False)]
    panel.margin.setCurrentText("serrate")
    choose(qtbot, window, panel)
    (form, on_main) = grown[-1]
    assert len(grown) == 2 and form.margin == "serrate" and form.fold == 0 and not on_main
    posed = form.with_(fold=60.0).leaf()
    assert np.array_equal(window.session.leaf.boundary, posed.boundary)
    assert all(map(np.array_equal, window.session.leaf.veins, posed.veins))


def test_only_the_last_chosen_form_becomes_the_document(window, panel, qtbot):
    """Two forms chosen before the first one's blade has grown: the last one is the document,
    and the first one's blade, when it comes, changes nothing."""
    serial = window.session.state.serial
    panel.gallery.setCurrentRow(list(SHAPES).index("cordate"))
    panel.choose_now()
    panel.gallery.setCurrentRow(list(SHAPES).index("linear"))
    panel.choose_now()
    qtbot.waitUntil(lambda: window.session.state.serial != serial, timeout=WAIT_MS)
    qtbot.waitUntil(lambda: window.worker.is_idle("forms"), timeout=WAIT_MS)
    qtbot.wait(50)  # any answer still queued to this thread
    assert window.session.state.title.startswith("linear")
    assert window.session.history.index == 1  # one step: the cordate form never arrived


def test_a_pose_changed_while_the_blade_grows_is_the_one_shown(window, panel, qtbot, monkeypatch):
    """Review: a slider's change that came before the chosen form's blade was dropped (the
    document was not the gallery's yet), and a pose change started a second growth of the
    same blade. (A shape no other test here chooses: the dock keeps the last blade.)"""
    grown: list[Form] = []
    blade = Form.blade_and_note
    monkeypatch.setattr(Form, "blade_and_note", lambda f: grown.append(f) or blade(f))
    serial = window.session.state.serial
    panel.gallery.setCurrentRow(list(SHAPES).index("reniform"))
    panel.choose_now()
    panel.fold.setValue(30.0)
    panel.chosen.emit(panel.form(), False)  # the debounced change, before the blade came
    qtbot.waitUntil(lambda: window.session.state.serial != serial, timeout=WAIT_MS)
    qtbot.waitUntil(lambda: window.worker.is_idle("forms"), timeout=WAIT_MS)
    assert window.session.state.title.startswith("reniform")
    assert window.session.leaf.bend is not None and window.session.leaf.bend.fold == 30.0
    assert [f.shape for f in grown] == ["reniform"]


def test_a_document_opened_while_the_blade_grows_is_not_replaced(window, panel, qtbot):
    panel.gallery.setCurrentRow(list(SHAPES).index("hastate"))
    panel.choose_now()
    window.session.open_demo("parallel")  # before the blade came
    qtbot.waitUntil(lambda: window.worker.is_idle("forms"), timeout=WAIT_MS)
    qtbot.wait(50)  # the blade's answer, queued to this thread
    assert not window.session.state.title.startswith("hastate")
    assert np.array_equal(window.session.leaf.boundary, demo("parallel").boundary)


def test_a_pose_change_keeps_the_sketch_drawn_and_another_form_draws_its_own(window, panel, qtbot):
    """A pose changes the leaf, not the flat blade the sketch shows: the sketch view drew every
    curve and point again (10-18 ms of the main thread's piece, issue 24); it now keeps its
    scene, and a new blade still replaces it."""
    import shiboken6

    view = window.editor.view
    panel.gallery.setCurrentRow(list(SHAPES).index("ovate"))
    choose(qtbot, window, panel)
    drawn = view.scene().items()
    panel.fold.setValue(40.0)
    panel.choose_now()  # at once: the kept blade, posed
    assert window.session.leaf.bend.fold == 40.0
    assert all(shiboken6.isValid(item) for item in drawn)
    assert view.scene().items() == drawn
    panel.gallery.setCurrentRow(list(SHAPES).index("cordate"))
    choose(qtbot, window, panel)
    assert not any(shiboken6.isValid(item) for item in drawn)


def test_grow_veins_starts_at_the_base_of_a_midrib_written_apex_first(window, panel, qtbot):
    """Grow veins on a leaf without a sketch grew from vein 1's first point: a midrib written
    apex first (taken base first for the length, the export and the view) had the grown midrib
    start at its apex; it now starts at its base, as for the leaf written base first."""
    from leafstudio.forms import make_form

    leaf = make_form("ovate", venation="pinnate")
    starts = []
    for given in (leaf, Leaf(leaf.boundary, [leaf.veins[0][::-1], *leaf.veins[1:]])):
        window.session.new_document(given)
        wait_result(qtbot, window, lambda o: o.result.leaf is window.session.leaf)
        panel.venation.setCurrentText("pinnate")
        panel.grow_button.click()
        wait_result(qtbot, window, lambda o: o.result.leaf is window.session.leaf)
        starts.append(window.session.leaf.veins[0][0])
    np.testing.assert_allclose(starts[1], starts[0], atol=1e-6)


def test_the_docks_pose_bends_an_edited_form_keeping_its_edits_and_the_panels_curl(
    window, panel, qtbot
):
    """appreview31, finding 2: ovate folded 45 in the dock, curled 0.5 in the Parameters panel,
    a boundary point moved, then the dock's Roll nudged: the document became a pristine "New
    leaf: ovate form" (the point and the curl gone), and the dock's Curl read 0 meanwhile. The
    dock's pose now shows the document's and bends the edited leaf, one undo step."""
    session = window.session
    panel.gallery.setCurrentRow(list(SHAPES).index("ovate"))
    panel.fold.setValue(45.0)
    choose(qtbot, window, panel)
    window.bend.sliders["curl"].setValue(0.5)  # the Parameters panel's: one step at once
    assert session.pose.curl == 0.5 and panel.curl.value() == 0.5  # both show the document's
    sketch = session.editable_sketch()
    moved = sketch.moved(-1, 5, sketch.boundary[5] + 0.05 * (sketch.boundary[5] - [0.5, 0]))
    session.commit_sketch(moved, "Move point")
    assert "Edited since it was made" in panel.shape_text.text()
    steps = session.history.index
    panel.roll.setValue(0.3)  # the dock's Roll, debounced
    qtbot.waitUntil(lambda: session.pose.roll != 0, timeout=WAIT_MS)
    assert session.state.sketch is moved  # the edit kept
    pose, width = session.pose, session.half_width
    assert (pose.fold, pose.curl) == (45.0, 0.5)  # the panel's curl kept
    assert pose.roll * width / np.pi == pytest.approx(0.3)
    assert session.history.index == steps + 1 and session.history.undo_text().startswith("Bend")
    assert window.bend.sliders["roll"].value() == pytest.approx(0.3)
    session.undo()
    assert session.state.sketch is moved and session.pose.roll == 0 and panel.roll.value() == 0


def test_the_docks_other_terms_wait_for_a_shape_picked_once_the_form_is_edited(
    window, panel, qtbot
):
    """An edited form's margin changed in the dock keeps the edits (its new terms apply to the
    next shape picked, a new leaf, one undo step); an unedited form bent in the Parameters
    panel is made anew with that bend."""
    session = window.session
    panel.gallery.setCurrentRow(list(SHAPES).index("ovate"))
    choose(qtbot, window, panel)
    window.bend.sliders["curl"].setValue(0.4)
    serial = session.state.serial
    panel.margin.setCurrentText("serrate")  # unedited: made anew, curled as it was
    qtbot.waitUntil(lambda: session.state.serial != serial, timeout=WAIT_MS)
    assert session.state.title == "ovate form" and session.pose.curl == pytest.approx(0.4)
    sketch = session.editable_sketch()
    moved = sketch.moved(-1, 3, sketch.boundary[3] * 1.02)
    session.commit_sketch(moved, "Move point")
    panel.margin.setCurrentText("entire")
    qtbot.wait(3 * forms_dock.DEBOUNCE_MS)
    assert session.state.sketch is moved  # not replaced
    choose(qtbot, window, panel)  # a shape picked: a new leaf with the dock's terms
    assert session.state.sketch is not moved and session.pose.curl == pytest.approx(0.4)
    session.undo()
    assert session.state.sketch is moved


def test_a_scans_dock_shows_no_pose_and_a_shape_picked_then_is_not_bent_by_the_last_leaf(
    window, panel, qtbot, tmp_path
):
    """Session 31, noticed: with a scan open (bent by its sheet, which no pose may replace) the
    dock's pose boxes were off but kept the last form's fold of 45, and a shape picked then came
    in folded 45 though nobody asked. They show what applies (no pose: cleared, and why), and
    the shape picked starts from the terms the dock shows."""
    session = window.session
    panel.gallery.setCurrentRow(list(SHAPES).index("ovate"))
    panel.fold.setValue(45.0)
    choose(qtbot, window, panel)
    assert session.pose.fold == 45.0 and panel.fold.value() == 45.0
    assert window.open_path(write_points(tmp_path / "scan.txt", six_column_scan()))
    qtbot.waitUntil(lambda: session.state.scan is not None, timeout=WAIT_MS)
    wait_result(qtbot, window, lambda o: o.result.leaf is session.leaf)
    assert not can_pose(session.leaf)  # bent by the sheet fitted to its points
    assert not panel.fold.isEnabled()
    assert panel.pose_figures() == {"fold": 0.0, "curl": 0.0, "roll": 0.0, "twist": 0.0}
    assert "sheet" in panel.fold.toolTip()
    panel.gallery.setCurrentRow(list(SHAPES).index("lanceolate"))
    choose(qtbot, window, panel)
    assert "lanceolate" in session.state.title and session.pose == Pose()
    assert panel.fold.isEnabled() and panel.fold.toolTip() == RELIEF["fold"]
