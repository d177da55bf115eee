"""Issue 22, finding 1: every layer of the method shows when ticked with the mesh on. Ticking a
layer must change at least 2% of the 3D view's pixels, on each demo and on three gallery forms
(before: p(x) changed 61 pixels, the EM samples 6, the zero contour a thin line under the
boundary's dots)."""

from __future__ import annotations

import numpy as np
import pytest

from leafstudio.forms import make_form
from tests.gui.qt.conftest import image_pixels, wait_result

LEAVES = ("nested", "parallel", "ovate", "lobed palmate", "cordate serrate")
FORMS = {
    "ovate": lambda: make_form("ovate"),
    "lobed palmate": lambda: make_form("orbicular", margin="lobed", lobes=5, venation="palmate"),
    "cordate serrate": lambda: make_form("cordate", margin="serrate", teeth=24),
}
CHANGED = 0.02  # the share of the view's pixels a ticked layer must change
TOLERANCE = 24  # a pixel changed when a channel moved more than this (of 255)


def _open(window, qtbot, name: str) -> None:
    before = window.session.shown_id
    if name in FORMS:
        window.session.new_document(FORMS[name](), title=name)
    else:
        window.open_demo(name)
    wait_result(qtbot, window, lambda _o: window.session.shown_id != before)


def view_pixels(window) -> np.ndarray:
    """The 3D view's pixels as rendered now."""
    window.viewport.plotter.render()
    return image_pixels(window.viewport.image())


def changed_share(a: np.ndarray, b: np.ndarray) -> float:
    """The share of pixels where any channel moved more than TOLERANCE."""
    moved = np.abs(a.astype(int) - b.astype(int)).max(axis=2) > TOLERANCE
    return float(moved.mean())


LAYERS = ("contour", "implicit", "probability", "em", "samples")
_SHARES: dict[str, dict[str, float]] = {}  # layer -> leaf -> share, measured once per run


def _measure_shares(qtbot, window) -> dict[str, dict[str, float]]:
    """Each layer's changed share on each leaf: one window (the lent one, given back at its
    size: LentWindow puts back its layers and resets its document), each leaf reconstructed once
    and every layer ticked over it in turn (the plain view rendered again before each tick)."""
    shares: dict[str, dict[str, float]] = {layer: {} for layer in LAYERS}
    size = window.size()
    try:
        window.resize(1024, 800)  # the 3D view about 600 px wide (docks as tabs: projector.py)
        for key in window.viewport.visible:
            window.layers.set_checked(key, key in ("mesh", "points"))
        for name in LEAVES:
            _open(window, qtbot, name)
            window.viewport.camera("iso")
            for layer in LAYERS:
                plain = view_pixels(window)
                window.layers.set_checked(layer, True)
                ticked = view_pixels(window)
                window.layers.set_checked(layer, False)
                shares[layer][name] = round(changed_share(plain, ticked), 4)
    finally:
        window.resize(size)
    return shares


@pytest.mark.parametrize("layer", LAYERS)
def test_a_ticked_layer_shows_over_the_mesh(qtbot, lent_window, layer):
    if not _SHARES:
        _SHARES.update(_measure_shares(qtbot, lent_window.lend(qtbot)))
    shares = _SHARES[layer]
    assert set(shares) == set(LEAVES)
    assert min(shares.values()) >= CHANGED, shares


def test_a_bent_leafs_flat_layers_bring_the_leaf_laid_flat_with_them(window, qtbot):
    """closing32: a bent leaf's g, p(x) and EM layers are drawn on its flat blade, and the
    "Bent leaf laid flat" layer, which lines up with them, stayed off. Ticking g on a folded
    form ticks it; unticking g unticks it."""
    from leafstudio.core.bend import Pose

    wait_result(qtbot, window)
    visible = window.viewport.visible
    window.layers.set_checked("implicit", True)  # on the demo, unbent: nothing laid flat
    assert not visible["blade"]
    window.session.set_bend(Pose(fold=45.0))
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.leaf)
    qtbot.waitUntil(lambda: visible["blade"], timeout=5000)  # the bend's result brings it
    assert visible["implicit"]
    assert "blade:outline" in window.viewport.plotter.actors
    window.layers.set_checked("implicit", False)
    assert not visible["blade"]
    window.layers.set_checked("probability", True)
    assert visible["blade"]
    window.layers.set_checked("probability", False)
    assert not visible["blade"]
