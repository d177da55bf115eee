"""What the story screenshots showed (benchmarks/story_screens.py, issue 12): checks on the
window for each finding."""

from __future__ import annotations

from PySide6.QtCore import Qt

from leafstudio.gui.model.layers import vein_color
from leafstudio.gui.model.sketch_model import BOUNDARY
from leafstudio.gui.qt import explain

from .conftest import wait_result
from .test_sketch import click


def _label_height(window) -> float:
    """The K label's height on screen, in device pixels, as VTK lays it out."""
    plotter = window.viewport.plotter
    label = plotter.actors["k_label"]
    box = [0.0] * 4
    label.GetBoundingBox(plotter.renderer, box)
    return box[3] - box[2]


def test_the_k_label_is_as_large_in_logical_pixels_at_any_pixel_ratio(window, monkeypatch):
    """At a device pixel ratio of 2 the Qt VTK widgets set the render window's DPI to 144, and
    VTK already scales text by DPI / 72: the label's font size in points must not be scaled by
    the ratio as well (it showed twice too large at QT_SCALE_FACTOR=2)."""
    aids = window.view_aids
    render_window = window.viewport.plotter.render_window
    render_window.SetDPI(72)
    aids._label = None
    aids.apply()
    single = _label_height(window)
    assert single > 0.5 * explain.K_FONT_PX
    monkeypatch.setattr(window.viewport, "pixel_ratio", lambda: 2.0)
    render_window.SetDPI(144)  # what QVTKRenderWindowInteractor sets at ratio 2
    aids._label = None
    aids.apply()
    assert 1.7 < _label_height(window) / single < 2.3  # was 4: the ratio applied twice


def test_a_new_document_starts_with_no_point_selected_on_the_boundary(window, qtbot):
    """The nested demo opened after drawing showed the drawing's chosen vein (vein 5) and its
    selected point on the demo's vein 5: a click then added to a vein the user never chose."""
    window.new_sketch()
    view = window.editor.view
    for xy in ((0.1, 0.0), (0.5, 0.2), (0.9, 0.0), (0.5, -0.2)):
        click(qtbot, view, xy)
    for start, end in (((0.1, 0.0), (0.9, 0.0)), ((0.5, 0.0), (0.6, 0.12))):
        qtbot.mouseClick(window.editor.new_vein, Qt.MouseButton.LeftButton)
        click(qtbot, view, start)
        click(qtbot, view, end)
    assert view.active == 1 and view.selected == (1, 1)
    window.session.history.set_clean()
    window.open_demo("nested")
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
    assert view.active == BOUNDARY and view.selected is None
    assert window.editor.curve.currentIndex() == 0


def test_no_side_vein_takes_the_midribs_colour():
    """A gallery form has 13 veins: its eighth was drawn in the midrib's red, in both views."""
    midrib = vein_color(0)
    assert all(vein_color(i) != midrib for i in range(1, 40))
    assert len({vein_color(i) for i in range(1, 7)}) == 6  # neighbours still differ


def test_the_sketch_lines_follow_the_pixel_ratio(window, monkeypatch):
    """Cosmetic pens are in device pixels: at QT_SCALE_FACTOR=2 the sketch's curves and the
    dots' rims were half as wide as at 1 (seen in s3-story-4-dark-palette-scale2.png)."""
    view = window.editor.view

    def widths() -> list[float]:
        view._redraw()
        return sorted(item.pen().widthF() for item in view.scene().items() if hasattr(item, "pen"))

    single = widths()
    assert single and min(single) >= 1
    monkeypatch.setattr(view, "devicePixelRatioF", lambda: 2.0)
    assert widths() == [2 * w for w in single]


def test_a_demos_boundary_side_view_does_not_call_it_a_scan(window):
    """With the boundary chosen, the side view said "boundary, from the scan" over the nested
    demo (and every loaded leaf): its heights come from whatever was loaded."""
    side = window.editor.profile_view
    window.editor.view.set_sketch(window.editor.view.sketch, fit=True)  # the boundary chosen
    assert side.vein == BOUNDARY and len(side.sketch.relief)
    caption = side.boundary_caption()
    assert "scan" not in caption and caption.startswith("boundary, as loaded: peak")


def test_a_posed_forms_flat_boundary_says_its_peak_is_0(window, qtbot, tmp_path):
    """A rolled and folded form opened from its file: the side view's boundary caption said
    "peak 4.8e-17", the round-off of laying its blade flat."""
    import leafstudio as ls
    from leafstudio.forms.make import Form
    from tests.gui.qt.conftest import wait_result

    path = tmp_path / "rolled.leaf.json"
    ls.save_leaf(Form("ovate", roll=0.5, fold=30.0).leaf(), path)
    window.session.history.set_clean()
    assert window.open_path(str(path))
    qtbot.waitUntil(lambda: window.session.state.path == str(path), timeout=60_000)
    wait_result(qtbot, window, lambda o: o.result.leaf.bend is not None)
    side = window.editor.profile_view
    window.editor.view.set_sketch(window.editor.view.sketch, fit=True)  # the boundary chosen
    qtbot.waitUntil(lambda: side.vein == BOUNDARY and len(side.sketch.relief) > 0, timeout=10_000)
    assert side.boundary_caption() == "boundary, as loaded: peak 0 (not editable)"
