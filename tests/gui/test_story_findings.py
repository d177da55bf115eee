"""What the story screenshots showed (benchmarks/story_screens.py, issue 12): checks on the
window for each finding."""

from __future__ import annotations

from leafstudio.gui import explain


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
