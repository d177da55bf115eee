"""What core/unfold.py asks of curves before it fits a pose (core/unfold_checks.py)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from leafstudio.core.unfold_checks import above_noise, bent, margin_noise
from leafstudio.forms.make import Form
from tests.core.test_correct import drawn_leaf


def _bent(leaf) -> bool:
    return bent(np.asarray(leaf.boundary), np.asarray(leaf.veins[0]))


@pytest.mark.parametrize("shape", ["reniform", "orbicular"])
def test_a_bowl_whose_rim_lies_on_a_plane_is_bent(shape):
    """Curled and rolled one way, the margin lies nearly on a plane (reniform curled -1 and rolled
    -0.3: 0.117 of its width off it, 0.016 off the quadric) and the midrib sinks under it, 1.40
    times as long as its shadow there: it ran as a height field, 26.5% short as a CSV (pose36).
    Rolled -0.2 and curled -0.5 the rim lies within OFF_PLANE (0.06; reniform 0.052, orbicular
    0.0065 of the width off its plane), the midrib 1.15-1.16 times its shadow."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        leaf = Form(shape, curl=-0.5, roll=-0.2).leaf()
    assert not bent(np.asarray(leaf.boundary))  # the margin alone says flat
    assert _bent(leaf)


@pytest.mark.parametrize("shape", ["ovate", "reniform", "orbicular", "cordate", "linear"])
def test_a_flat_blades_raised_midrib_is_not_a_bend(shape):
    """A flat form's dome and a drawn leaf's hand-raised veins lift the midrib off the margin's
    plane (1.0005-1.036 and 1.012 times its shadow): they run as before, no pose fitted."""
    assert not _bent(Form(shape).leaf())
    assert not _bent(drawn_leaf())


def _noisy(leaf, share: float, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """`leaf`'s boundary and midrib with Gaussian noise of `share` of its diagonal, each axis."""
    rng = np.random.default_rng(seed)
    size = share * float(np.linalg.norm(np.ptp(leaf.boundary, axis=0)))
    return tuple(c + rng.normal(0.0, size, c.shape) for c in (leaf.boundary, leaf.veins[0]))


@pytest.mark.parametrize(
    ("shape", "terms"), [("elliptic", {"fold": 40.0}), ("ovate", {"curl": 0.5})]
)
def test_a_margins_digitising_noise_is_read_and_a_forms_own_curve_has_none(shape, terms):
    leaf = Form(shape, **terms).leaf()
    diagonal = float(np.linalg.norm(np.ptp(leaf.boundary, axis=0)))
    assert margin_noise(leaf.boundary, leaf.veins[0]) == 0.0
    for share in (1e-4, 5e-4, 2e-3):
        read = margin_noise(*_noisy(leaf, share))
        assert read == pytest.approx(share * diagonal, rel=0.2)


def test_a_toothed_margins_corners_are_read_as_little_noise():
    """The teeth lie in the blade: across it, a serrate form's corners read 4e-5-1.1e-4 of the
    diagonal (all its points off their neighbours' quadratic: 1.8e-4)."""
    leaf = Form("ovate", margin="serrate", fold=45.0).leaf()
    diagonal = float(np.linalg.norm(np.ptp(leaf.boundary, axis=0)))
    assert margin_noise(leaf.boundary, leaf.veins[0]) <= 1.5e-4 * diagonal


def test_what_a_fit_leaves_is_taken_beyond_the_noise():
    """A fit that leaves no more than the noise leaves nothing beyond it; one that leaves more,
    its excess (the noise's variance off its square)."""
    assert above_noise(0.9e-3, 1e-3, 5, 60) == 0.0
    assert above_noise(5e-3, 1e-3, 5, 60) == pytest.approx(np.sqrt(25 - 1.441) * 1e-3, rel=1e-3)
    assert above_noise(2e-3, 0.0, 5, 60) == 2e-3


@pytest.mark.parametrize("midrib", [[[0.5, 0.0, 0.0]], [[0.5, 0.0, 0.0], [0.5, 0.0, 0.0]]])
def test_a_flat_leafs_midrib_of_no_length_is_not_a_bend(midrib):
    """A first vein of one point (as a click starts one), or of one point repeated, has no
    shadow: it read as foreshortened without end, and a flat leaf refused for its outline
    crossing itself was told it "is bent in 3D and no pose lays it flat" (review36)."""
    import leafstudio as ls
    from leafstudio.core.unfolded import unposed_hint

    t = np.linspace(0.0, 2 * np.pi, 100, endpoint=False)
    boundary = np.column_stack([np.cos(t), 0.5 * np.sin(t), 0 * t])
    assert not bent(boundary, np.array(midrib))
    assert unposed_hint(ls.Leaf(boundary, [np.array(midrib)])) == ""


def test_a_drawn_leafs_midrib_lifted_in_the_side_view_is_not_a_bend():
    """The clicked leaf's midrib raised to 0.5 at its tip in the side view (1.17 times its shadow)
    over its outline drawn flat: no bowl, whose rim is never on a plane to rounding. It started
    the fit at every edit (0.95 s CPU, no pose found), and a refusal of it (a side vein dragged
    out) was told it was "a posed or scanned leaf saved as a point list" (review36)."""
    from leafstudio.core.unfolded import unposed_hint
    from tests.leaves import clicked_sketch

    leaf = clicked_sketch().with_profile(0, 0.0, 0.5).to_leaf()
    assert not _bent(leaf)
    assert unposed_hint(leaf) == ""
