"""Step 2: the MPU implicit g of eqs. 1-2: its weights, sign and zero level."""

import numpy as np
import pytest
import shapely
from shapely.geometry import LinearRing

from leafstudio.core.mpu import bspline_weight, build_mpu
from leafstudio.core.prepare.outline import leaf_polygon
from leafstudio.core.prepare.polygon import contains, outward_normals, thin_curve
from leafstudio.core.steps import frame_stage
from leafstudio.sources.demos import demo
from tests import leaves


def _implicit(polygon: np.ndarray, tol: float = 1e-3):
    return build_mpu(polygon, outward_normals(polygon), tol, lambda q: contains(polygon, q))


def test_eq2_bspline_weight_by_hand():
    t = np.array([0.0, 1 / 6, 1 / 3, 0.5, 2 / 3, 1.0, 1.5])
    expected = [0.75, 0.75 - 2.25 / 36, 0.5, 9 / 8 * 0.25, 9 / 8 / 9, 0.0, 0.0]
    np.testing.assert_allclose(bspline_weight(t), expected)


def test_eq1_single_cell_reproduces_its_line():
    """With one linear fit, g = Σ w f / Σ w is that line wherever w > 0."""
    square = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)
    side = np.column_stack([np.linspace(-1, 1, 50), np.full(50, -1.0)])
    g = build_mpu(side, np.tile([0.0, -1.0], (50, 1)), 1e-3, lambda q: contains(square, q))
    pts = np.array([[0.0, -0.5], [0.3, -1.2], [-0.4, 0.0]])
    np.testing.assert_allclose(g(pts), pts[:, 1] + 1, atol=1e-9)


@pytest.mark.parametrize("name", ["nested", "parallel"])
def test_zero_level_passes_through_the_boundary(name):
    polygon = leaf_polygon(demo(name).boundary[:, :2])
    g = _implicit(polygon)
    err = np.abs(g(polygon))
    assert np.median(err) < 1e-4
    assert err.max() < 3e-3  # worst at the cusp of the nested base


def test_sign_inside_and_outside_a_concave_lobed_leaf():
    leaf, region = leaves.lobed()
    polygon = leaf_polygon(leaf.boundary[:, :2])
    g = _implicit(polygon)
    xs = np.linspace(-0.8, 0.8, 161)
    pts = np.column_stack([a.ravel() for a in np.meshgrid(xs, xs)])
    inside = contains(np.asarray(region.exterior.coords), pts)
    dist = np.abs(np.hypot(*pts.T) - leaves.lobed_radius(np.arctan2(pts[:, 1], pts[:, 0])))
    clear = dist > 0.01  # away from the margin itself the sign must be exact
    assert np.all((g(pts[clear]) > 0) == inside[clear])


def test_thin_tip_is_neither_leaked_nor_cut():
    """Near the sharp tip of a narrow leaf: just inside is positive, just beside is negative, down
    to the last three boundary samples before the tip (they are 0.0067 apart)."""
    leaf, _ = leaves.narrow()
    polygon = leaf_polygon(leaf.boundary[:, :2])
    g = _implicit(polygon)
    x = np.linspace(0.9, 0.98, 20)
    w = leaves.narrow_halfwidth(x)
    assert np.all(g(np.column_stack([x, np.zeros_like(x)])) > 0)  # the midline reaches the tip
    assert np.all(g(np.column_stack([x, 0.5 * w])) > 0)
    assert np.all(g(np.column_stack([x, 1.6 * w + 1e-3])) < 0)
    assert np.all(g(np.column_stack([x, -1.6 * w - 1e-3])) < 0)
    assert g(np.array([[1.01, 0.0]]))[0] < 0  # past the tip


def test_unordered_boundary_gives_the_same_region():
    leaf = demo("nested")
    rng = np.random.default_rng(3)
    ordered = leaf_polygon(leaf.boundary[:, :2])
    shuffled = leaf_polygon(rng.permutation(leaf.boundary[:, :2]))
    g1, g2 = _implicit(ordered), _implicit(shuffled)
    pts = rng.uniform([-0.1, -0.2], [1.1, 0.2], size=(2000, 2))
    assert np.mean((g1(pts) > 0) == (g2(pts) > 0)) > 0.998


def test_gradient_matches_finite_differences():
    polygon = leaf_polygon(demo("parallel").boundary[:, :2])
    g = _implicit(polygon)
    pts = np.random.default_rng(4).uniform([0.05, -0.3], [0.95, 0.3], size=(200, 2))
    _, grad = g.evaluate(pts, gradient=True)
    eps = 1e-6
    fd = np.column_stack(
        [(g(pts + d) - g(pts - d)) / (2 * eps) for d in (np.array([eps, 0]), np.array([0, eps]))]
    )
    np.testing.assert_allclose(grad, fd, atol=1e-5)
    # near the margin g behaves like a distance: |∇g| close to 1
    near = np.abs(g(pts)) < 0.02
    assert np.all(np.abs(np.linalg.norm(grad[near], axis=1) - 1) < 0.1)


def test_supports_leave_no_gaps_inside_an_ellipse():
    """Every point of the region is well inside some cell's support: g is positive and its
    gradient moderate everywhere inside, not only at the grid nodes the pipeline happens to use."""
    theta = np.linspace(0, 2 * np.pi, 300, endpoint=False)
    polygon = np.column_stack([0.5 * np.cos(theta), 0.2 * np.sin(theta)])
    g = _implicit(polygon)
    xs = np.linspace(-0.5, 0.5, 401)
    pts = np.column_stack([a.ravel() for a in np.meshgrid(xs, np.linspace(-0.2, 0.2, 161))])
    level = (pts[:, 0] / 0.5) ** 2 + (pts[:, 1] / 0.2) ** 2
    inside = pts[level < 0.9]
    value, grad = g.evaluate(inside, gradient=True)
    assert np.all(value > 0)
    assert np.linalg.norm(grad, axis=1).max() < 3


@pytest.mark.parametrize("vertices", [3000, 1500, 1000])
def test_a_finely_resampled_outline_keeps_a_compact_quadtree(vertices):
    """The nested demo's outline resampled to 30,000 points and thinned to a few thousand (as a
    dense scan's is): cells beyond its sharp tip, whose balls all grow to the tip's points, were
    split to the depth limit for a sign no split could mend (35,000 cells instead of ~700)."""
    polygon = frame_stage(demo("nested")).polygon
    closed = np.vstack([polygon, polygon[:1]])
    arc = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(closed, axis=0), axis=1))])
    at = np.linspace(0, arc[-1], 30000, endpoint=False)
    dense = np.column_stack([np.interp(at, arc, closed[:, k]) for k in range(2)])
    outline = dense[thin_curve(dense, arc[-1] / vertices)]
    implicit = _implicit(outline)
    assert len(implicit.centers) < 1000
    grid = np.stack(np.meshgrid(np.linspace(-0.6, 0.6, 60), np.linspace(-0.3, 0.3, 30)), -1)
    xy = grid.reshape(-1, 2)
    far = shapely.distance(LinearRing(outline), shapely.points(xy)) > 0.01
    np.testing.assert_array_equal(implicit(xy[far]) > 0, contains(outline, xy[far]))


def test_a_split_cells_children_tile_it():
    """mpu.QUADRANTS (build_mpu's children's offsets, made once): times half the child's side
    from the parent's centre, the four children's centres, one in each quadrant."""
    from leafstudio.core.mpu import QUADRANTS

    assert QUADRANTS.shape == (4, 2)
    assert {tuple(q) for q in np.sign(QUADRANTS).tolist()} == {(-1, -1), (1, -1), (-1, 1), (1, 1)}
    np.testing.assert_array_equal(np.abs(QUADRANTS), 1)
