"""The Forms gallery: thumbnails drawn once, definitions beside the choosers, a chosen form as the
document (an editable sketch, one undo step), veins grown in the current outline."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtWidgets import QDockWidget

from leafstudio.forms import SHAPES
from leafstudio.gui import forms_dock
from leafstudio.gui.forms_dock import FormsPanel, leaf_sketch, thumbnail
from tests.gui.conftest import wait_result


@pytest.fixture
def panel(window):
    existing = getattr(window, "forms_panel", None)
    return existing if existing is not None else forms_dock.install(window)


def test_every_shape_has_a_thumbnail_drawn_once(qtbot):
    for name in SHAPES:
        image = thumbnail(name)
        assert image is thumbnail(name)  # cached
        alpha = np.array([image.pixelColor(x, y).alpha() for x in range(0, 84, 3) for y in (42,)])
        assert alpha.max() > 0  # something drawn across the middle
    widget = FormsPanel()
    qtbot.addWidget(widget)
    assert widget.gallery.count() == len(SHAPES)


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


def test_a_chosen_form_becomes_the_document_as_an_editable_sketch(window, panel, qtbot):
    assert isinstance(window.forms_dock, QDockWidget)
    before = window.session.leaf
    panel.gallery.setCurrentRow(list(SHAPES).index("cordate"))
    panel.margin.setCurrentText("serrate")
    panel.choose_now()
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.leaf)
    state = window.session.state
    assert state.sketch is not None and len(state.sketch.boundary) >= 40
    assert state.leaf.boundary[:, 0].min() < 0  # the cordate lobes
    assert "cordate" in state.title
    window.session.undo()  # one undo step brings the demo back
    assert window.session.leaf is before


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

    from leafstudio.forms import Form
    from leafstudio.forms.terms import MARGINS
    from leafstudio.gui.sketch_model import ring_crossings

    for shape, margin in itertools.product(SHAPES, MARGINS):
        form = Form(shape, margin=margin)
        sketch = leaf_sketch(form.leaf(), form.teeth_count)
        assert len(ring_crossings(sketch.boundary_curve())) == 0, (shape, margin)
