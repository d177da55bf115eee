"""What the 3D view does per result, counted rather than timed: one render of the scene, and
text that is set in place (software OpenGL makes every extra render or font fit a stall)."""

from __future__ import annotations

from tests.gui.conftest import wait_result


def _count_renders(window) -> list[int]:
    """A list that grows by one at the start of each render of the 3D view's window."""
    count: list[int] = []
    window.viewport.plotter.render_window.AddObserver("StartEvent", lambda *_: count.append(1))
    return count


def test_a_new_result_is_rendered_once(window, qtbot):
    qtbot.wait(200)  # whatever the first result left to paint
    renders = _count_renders(window)
    window.panel.k.setValue(5)
    wait_result(qtbot, window, lambda o: o.result.params.k == 5)
    qtbot.wait(300)  # time for any render queued behind it
    assert len(renders) == 1
    label = window.viewport.plotter.actors["k_label"]
    assert label.input == f"K = {window.outcome.result.chosen_k}"


def test_the_k_label_is_one_text_actor_updated_in_place(window, qtbot):
    plotter = window.viewport.plotter
    label = plotter.actors["k_label"]
    window.panel.k.setValue(5)
    wait_result(qtbot, window, lambda o: o.result.params.k == 5)
    assert plotter.actors["k_label"] is label  # not made anew (nor its font fitted anew)
    assert label.input == f"K = {window.outcome.result.chosen_k}"
