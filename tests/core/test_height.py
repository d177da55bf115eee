"""Step 3: the height guide p(x), eqs. 4-5, checked against values worked out by hand."""

import numpy as np
import pytest

from leafstudio.core.height import height_guide

# A boundary line y = 0 (densely sampled) and horizontal veins above it.
BOUNDARY = np.column_stack([np.linspace(-5, 5, 10001), np.zeros(10001)])


def _vein(y: float, h: float, x0: float = -5, x1: float = 5, n: int = 10001):
    x = np.linspace(x0, x1, n)
    return np.column_stack([x, np.full(n, y)]), np.full(n, h)


def test_eq4_rises_linearly_from_the_margin_to_the_vein():
    vein, h = _vein(2.0, 0.3)
    xy = np.array([[0.0, 0.0], [0.0, 0.5], [0.0, 1.0], [0.0, 1.5], [0.0, 2.0]])
    p = height_guide(xy, BOUNDARY, [vein], [h])
    # p = h_v |b - x| / |b - v'| with b = (0, 0), v' = (0, 2)
    np.testing.assert_allclose(p, [0.0, 0.075, 0.15, 0.225, 0.3], atol=1e-12)


def test_eq4_by_hand_at_a_slanted_point():
    """x = (1, 0.8): b = (1, 0), v' = (1, 2): |b - x| = 0.8, |b - v'| = 2, p = 0.5 * 0.4."""
    vein, h = _vein(2.0, 0.5)
    assert height_guide(np.array([[1.0, 0.8]]), BOUNDARY, [vein], [h])[0] == pytest.approx(0.2)


def test_eq5_between_two_parallel_veins_dips_to_three_quarters_midway():
    low, h_low = _vein(4.0, 0.4)
    high, h_high = _vein(6.0, 0.4)
    xy = np.array([[0.0, 4.0], [0.0, 4.5], [0.0, 5.0]])
    p = height_guide(xy, BOUNDARY, [low, high], [h_low, h_high])
    # h_v (1 - |v' - x| / (2 |v' - v''|)) with |v' - v''| = 2
    np.testing.assert_allclose(p, [0.4, 0.4 * (1 - 0.5 / 4), 0.3], atol=1e-12)


def test_ties_are_averaged():
    """Midway between two veins of different heights at equal distance: both heights count."""
    left = np.array([[-1.0, 2.0]])
    right = np.array([[1.0, 2.0]])
    x = np.array([[0.0, 1.0]])
    one_vein = height_guide(x, BOUNDARY, [np.vstack([left, right])], [np.array([0.2, 0.6])])
    # b = (0, 0); v' tied between (-1, 2) and (1, 2): |b - v'| = √5 for both, h_v = 0.4
    assert one_vein[0] == pytest.approx(0.4 * 1 / np.sqrt(5))


def test_tied_boundary_points_average_their_distances_to_the_vein():
    """x = (0, 1) is √2 from both boundary points (±1, 0); each is √10 from v' = (0, 3), so
    p = h √2 / √10 (the paper's average of |b − v'|, not the distance from their midpoint, 3)."""
    boundary = np.array([[-1.0, 0.0], [1.0, 0.0], [-9.0, 9.0], [9.0, 9.0]])
    p = height_guide(np.array([[0.0, 1.0]]), boundary, [np.array([[0.0, 3.0]])], [np.array([0.5])])
    assert p[0] == pytest.approx(0.5 * np.sqrt(2) / np.sqrt(10))


def test_signed_heights_give_a_negative_guide():
    vein, h = _vein(2.0, -0.3)
    p = height_guide(np.array([[0.0, 1.0]]), BOUNDARY, [vein], [h])
    assert p[0] == pytest.approx(-0.15)


def test_no_veins_gives_a_flat_guide():
    np.testing.assert_array_equal(height_guide(np.zeros((4, 2)), BOUNDARY, [], []), 0.0)


def test_thinning_to_half_a_grid_step_moves_the_guide_by_a_small_fraction_of_the_height():
    """The pipeline thins the curves to half its grid step; on a dense ellipse with a curved
    midrib the guide stays within 1% of the vein height of the unthinned one."""
    t = np.linspace(0, 2 * np.pi, 20000, endpoint=False)
    boundary = np.column_stack([np.cos(t), 0.4 * np.sin(t)])
    x = np.linspace(-0.9, 0.9, 8000)
    midrib = np.column_stack([x, 0.05 * np.sin(3 * x)])
    heights = 0.1 * (1 - x**2)
    gx, gy = np.meshgrid(np.linspace(-0.95, 0.95, 60), np.linspace(-0.35, 0.35, 30))
    xy = np.column_stack([gx.ravel(), gy.ravel()])
    xy = xy[(xy[:, 0] / 0.98) ** 2 + (xy[:, 1] / 0.38) ** 2 < 1]
    exact = height_guide(xy, boundary, [midrib], [heights])
    thinned = height_guide(xy, boundary, [midrib], [heights], step=0.5 * 2 / 128)
    assert np.abs(thinned - exact).max() <= 0.01 * heights.max()
    assert np.abs(thinned - exact).max() > 0  # the thinning did drop points


def test_thinning_keeps_each_vein_s_end_and_a_short_vein_whole():
    """A vein shorter than the step keeps both ends: midway between them, their tie averages
    both heights, as without thinning (the boundary's spacing is above the step: unchanged)."""
    boundary = np.column_stack([np.linspace(-5, 5, 5), np.zeros(5)])
    vein, h = np.array([[-1.0, 2.0], [1.0, 2.0]]), np.array([0.1, 0.2])
    xy = np.array([[0.0, 1.0]])
    exact = height_guide(xy, boundary, [vein], [h])
    np.testing.assert_allclose(height_guide(xy, boundary, [vein], [h], step=2.4), exact)
    assert exact[0] == pytest.approx(0.15 / np.sqrt(5))  # h 0.15, |b - x| 1, mean |b - v'| √5
