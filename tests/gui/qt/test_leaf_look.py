"""Issue 23, finding 5: the app showed a heat map, not a leaf. The Leaf look (the leaf's texture,
lit with a sheen, its underside paler as if lit through) is the first colouring and the one forms
and drawn leaves open in; a scan opens coloured by height, and the next leaf gets the Leaf look
back unless the user chose height."""

from __future__ import annotations

from leafstudio.gui.model.textures import LEAF, TEXTURE
from tests.gui.builders import six_column_scan, write_points

from .conftest import WAIT_MS, wait_result


def _leaf_look_drawn(window) -> bool:
    actor = window.viewport.plotter.actors.get("mesh")
    return (
        actor is not None
        and window.viewport.texture_key is not None
        and actor.GetTexture() is not None
        and actor.prop.specular > 0
        and actor.GetBackfaceProperty() is not None
    )


def test_a_form_opens_in_the_leaf_look_and_a_scan_by_height(window, qtbot, tmp_path):
    assert window.layers.coloring.itemData(0) == LEAF  # first in the list
    assert window.coloring.currentData() == LEAF
    qtbot.waitUntil(lambda: _leaf_look_drawn(window), timeout=WAIT_MS)
    assert window.viewport.texture_actor_image().shape == (1024, 1024, 4)  # blade and veins
    assert "height" not in window.viewport.plotter.scalar_bars  # an image, no colour scale
    back = window.viewport.plotter.actors["mesh"].GetBackfaceProperty()
    assert back.GetAmbient() > window.viewport.plotter.actors["mesh"].prop.ambient  # lit through

    assert window.open_path(write_points(tmp_path / "scan.txt", six_column_scan()))
    wait_result(qtbot, window, lambda outcome: window.session.state.scan is not None)
    assert window.coloring.currentData() == "height"
    assert "height" in window.viewport.plotter.scalar_bars

    window.open_demo("nested")  # not a scan: the Leaf look again
    wait_result(qtbot, window, lambda outcome: window.session.state.scan is None)
    assert window.coloring.currentData() == LEAF
    qtbot.waitUntil(lambda: _leaf_look_drawn(window), timeout=WAIT_MS)


def test_a_colouring_the_user_picked_is_kept_for_the_next_leaf(window, qtbot):
    for choice in ("height", TEXTURE):
        window.coloring.setCurrentIndex(window.coloring.findData(choice))
        window.open_demo("parallel")
        wait_result(qtbot, window)
        assert window.coloring.currentData() == choice


def test_a_scans_height_colouring_is_not_remembered_as_the_users_choice(window, qtbot, tmp_path):
    """A scan opened last, the app closed: the next start opened every leaf coloured by height
    (the scan's colouring was stored as if the user had picked it). The Leaf look is stored."""
    assert window.open_path(write_points(tmp_path / "scan.txt", six_column_scan()))
    wait_result(qtbot, window, lambda outcome: window.session.state.scan is not None)
    assert window.coloring.currentData() == "height"
    window._store_settings()
    assert window.settings.value("view/coloring") == LEAF
    window.coloring.setCurrentIndex(window.coloring.findData(TEXTURE))  # the user's choice
    window._store_settings()
    assert window.settings.value("view/coloring") == TEXTURE
