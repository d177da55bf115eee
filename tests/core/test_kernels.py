"""The compiled (numba) kernels give what the plain definitions give: each is checked against a
brute-force or reference (shapely, scikit-learn) computation on awkward input."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from shapely.geometry import LinearRing, Polygon
from sklearn.mixture import GaussianMixture

import leafstudio as ls
from leafstudio.core.buckets import bucket_points, kth_distances, neighbour_distances
from leafstudio.core.gmm import Mixture, _search_right, fit_mixture
from leafstudio.core.grid import make_grid
from leafstudio.core.height import nearest_in_groups
from leafstudio.core.mesher import conforming_grid_mesh, inner_nodes
from leafstudio.core.mpu import bspline_weight, build_mpu
from leafstudio.core.prepare.outline import leaf_polygon
from leafstudio.core.prepare.polygon import (
    contains,
    distinct_indices,
    outward_normals,
    thin_outline,
)
from leafstudio.core.steps import frame_stage
from leafstudio.core.surface import _levenberg_marquardt, _pack, _residual_rows
from leafstudio.sources.demos import PAPER_K


def _star(n: int = 240, seed: int = 1) -> np.ndarray:
    """A jagged star-shaped polygon, counter-clockwise."""
    rng = np.random.default_rng(seed)
    angle = np.sort(rng.uniform(0, 2 * np.pi, n))
    radius = rng.uniform(0.3, 1.0, n)
    return np.column_stack([radius * np.cos(angle), radius * np.sin(angle)])


def _slotted_square() -> np.ndarray:
    """A unit square with a slot 0.01 wide cut from its top edge down to y = 0.3."""
    return np.array(
        [[0, 0], [1, 0], [1, 1], [0.505, 1], [0.505, 0.3], [0.495, 0.3], [0.495, 1], [0, 1]],
        dtype=float,
    )


@pytest.fixture(scope="module")
def nested_frame():
    return frame_stage(ls.demo("nested"))


def test_mpu_value_is_eq1_summed_over_every_cell(nested_frame):
    polygon = nested_frame.polygon
    implicit = build_mpu(polygon, outward_normals(polygon), 1e-3, lambda q: contains(polygon, q))
    rng = np.random.default_rng(0)
    xy = np.vstack([rng.uniform(-0.6, 0.6, (400, 2)) * [1, 0.3], polygon[:20]])
    dist = np.linalg.norm(xy[:, None] - implicit.centers[None], axis=2)
    w = bspline_weight(dist / implicit.radii[None])
    f = xy @ implicit.coef[:, :2].T + implicit.coef[:, 2]
    covered = w.sum(axis=1) > 0
    expected = (w * f).sum(axis=1)[covered] / w.sum(axis=1)[covered]
    g, grad, hess = implicit.derivatives(xy)
    np.testing.assert_allclose(g[covered], expected, rtol=1e-12, atol=1e-14)
    assert np.array_equal(implicit(xy), g)
    np.testing.assert_array_equal(implicit.evaluate(xy, gradient=True)[1], grad)
    step = 1e-6  # the gradient is the derivative of the value
    numeric = (implicit(xy + [step, 0]) - implicit(xy - [step, 0])) / (2 * step)
    np.testing.assert_allclose(grad[:, 0], numeric, atol=1e-5)
    assert np.allclose(hess, hess.transpose(0, 2, 1))


def test_nearest_in_groups_is_the_brute_force_answer():
    rng = np.random.default_rng(3)
    points = rng.uniform(0, 1, (300, 2))
    points[:40] = np.round(points[:40] * 8) / 8  # repeats: ties to average
    group = rng.integers(0, 5, len(points))
    values = rng.normal(size=len(points))
    queries = np.vstack([rng.uniform(-0.2, 1.2, (2000, 2)), points[:50]])
    dist, position, value, second = nearest_in_groups(queries, points, group, values)
    d = np.linalg.norm(queries[:, None] - points[None], axis=2)
    per_group = np.stack([np.where(group == k, d, np.inf).min(axis=1) for k in range(5)], axis=1)
    first = np.argmin(per_group, axis=1)
    np.testing.assert_allclose(dist, d.min(axis=1), rtol=1e-12)
    np.testing.assert_allclose(second, np.sort(per_group, axis=1)[:, 1], rtol=1e-12)
    tied = (group[None] == first[:, None]) & (d <= dist[:, None] * (1 + 1e-9) + 1e-15)
    count = tied.sum(axis=1)
    np.testing.assert_allclose(position, (tied @ points) / count[:, None], rtol=1e-12)
    np.testing.assert_allclose(value, (tied @ values) / count, rtol=1e-12, atol=1e-15)
    assert np.all(np.isinf(nearest_in_groups(queries, points, np.zeros(300, int), values)[3]))


def test_neighbour_distances_are_the_brute_force_answer():
    rng = np.random.default_rng(4)
    clustered = np.vstack([rng.normal(0, 0.01, (500, 2)), rng.uniform(-3, 3, (300, 2))])
    on_a_line = np.column_stack([np.sort(rng.uniform(0, 1, 400)), np.zeros(400)])
    for points in (clustered, on_a_line):
        which = rng.choice(len(points), 150, replace=False)
        d = np.linalg.norm(points[which, None] - points[None], axis=2)
        d[np.arange(len(which)), which] = np.inf
        np.testing.assert_allclose(neighbour_distances(points, which), d.min(axis=1))
    assert np.isinf(neighbour_distances(np.zeros((1, 2)), np.array([0]))).all()
    blob = np.vstack([rng.normal(0, 1e-4, (3000, 2)), [[5.0, 5.0], [-5.0, 3.0]]])  # crowded
    which = np.arange(0, len(blob), 7)
    d = np.linalg.norm(blob[which, None] - blob[None], axis=2)
    d[np.arange(len(which)), which] = np.inf
    np.testing.assert_allclose(neighbour_distances(blob, which), d.min(axis=1))


def test_kth_distances_are_the_k_d_trees_to_the_bit():
    """mpu's grown balls took their radii from scipy's cKDTree (issue 21): the same figures,
    for centres inside and outside the points' box, repeated points, and fewer points than k."""
    from scipy.spatial import cKDTree

    rng = np.random.default_rng(6)
    t = rng.uniform(0, 2 * np.pi, 500)
    ring = np.column_stack([np.cos(t), 0.3 * np.sin(t)])
    repeats = np.round(rng.uniform(0, 1, (300, 2)) * 5) / 5
    for points in (ring, repeats, ring[:4]):
        centres = rng.uniform(points.min(axis=0) - 1, points.max(axis=0) + 1, (400, 2))
        for k in (1, 6):
            expected = cKDTree(points).query(centres, k=k)[0]
            expected = expected if k == 1 else expected[:, -1]
            got = kth_distances(points, centres, k, bucket_points(points))
            np.testing.assert_array_equal(got, expected)


def test_search_right_is_numpys_searchsorted():
    """sample_guide's picks were rng.choice's, by numpy's searchsorted (issue 21): the same
    indices for a cdf with flat runs (nodes where p is 0) and draws right on its values."""
    rng = np.random.default_rng(7)
    p = rng.uniform(0, 1, 3000)
    p[rng.uniform(0, 1, 3000) < 0.6] = 0.0
    cdf = (p / p.sum()).cumsum()
    cdf /= cdf[-1]
    u = np.concatenate([rng.uniform(0, 1, 4000), cdf[rng.integers(0, 2999, 500)], [0.0]])
    np.testing.assert_array_equal(_search_right(cdf, u), cdf.searchsorted(u, side="right"))


def test_distinct_indices_drop_repeats_wherever_the_points_lie():
    rng = np.random.default_rng(5)
    points = rng.uniform(0, 1, (500, 2))
    points = np.vstack([points, points[rng.integers(0, 500, 200)]])[rng.permutation(700)]
    for offset in (0.0, 5.0, -3.0):
        shifted = points + offset
        first = np.unique(np.round(shifted / 1e-9), axis=0, return_index=True)[1]
        np.testing.assert_array_equal(distinct_indices(shifted, 1.0), np.sort(first))
    assert len(distinct_indices(np.zeros((0, 2)), 1.0)) == 0


@pytest.mark.parametrize("polygon", [_star(), _slotted_square()], ids=["star", "slot"])
def test_contains_and_clearance_agree_with_shapely(polygon):
    rng = np.random.default_rng(2)
    lo, hi = polygon.min(axis=0) - 0.1, polygon.max(axis=0) + 0.1
    xy = rng.uniform(lo, hi, (20000, 2))
    expected = shapely.covers(Polygon(polygon), shapely.points(xy))
    np.testing.assert_array_equal(contains(polygon, xy), expected)
    midpoints = (polygon + np.roll(polygon, -1, 0)) / 2  # on the edges, up to rounding
    assert contains(polygon, np.vstack([polygon, midpoints])).all()
    clear = shapely.distance(LinearRing(polygon), shapely.points(xy)) > 0.4 * 0.02
    np.testing.assert_array_equal(inner_nodes(polygon, xy, 0.02), clear)


@pytest.mark.parametrize("polygon", [_star(), _slotted_square()], ids=["star", "slot"])
def test_grid_mesh_tiles_the_polygon_with_its_outline_as_the_only_boundary(polygon):
    grid = make_grid(polygon, 60)
    inside = contains(polygon, grid.points)
    xy, triangles, kept = conforming_grid_mesh(polygon, grid, inside)
    b = len(polygon)
    n_kept = int(np.count_nonzero(kept))  # between them: points added against slivers
    assert np.array_equal(xy[:b], polygon) and np.array_equal(xy[-n_kept:], grid.points[kept])
    expected = inside & contains(polygon, grid.points)
    expected[expected] = inner_nodes(polygon, grid.points[expected], grid.spacing)
    np.testing.assert_array_equal(kept, expected)
    corners = xy[triangles]
    u, v = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    signed = (u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]) / 2
    assert np.all(signed > 0)  # counter-clockwise, none degenerate
    assert signed.sum() == pytest.approx(Polygon(polygon).area, rel=1e-9)
    edges = np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    unique, count = np.unique(edges, axis=0, return_counts=True)
    assert count.max() == 2
    ring = {tuple(sorted((i, (i + 1) % b))) for i in range(b)}
    assert {tuple(e) for e in unique[count == 1]} == ring
    assert np.array_equal(np.unique(triangles), np.arange(len(xy)))


def test_em_repeats_for_a_seed_and_lands_where_sklearn_does():
    rng = np.random.default_rng(4)
    samples = np.vstack([rng.normal(c, 0.1, (700, 2)) for c in ([0, 0], [1, 0.2], [0.4, 1.0])])
    first, again = fit_mixture(samples, 3, 7), fit_mixture(samples, 3, 7)
    assert np.array_equal(first.means, again.means)
    reference = GaussianMixture(3, covariance_type="full", random_state=7, reg_covar=1e-6)
    reference.fit(samples)
    order, ref_order = np.argsort(first.means[:, 0]), np.argsort(reference.means_[:, 0])
    np.testing.assert_allclose(first.means[order], reference.means_[ref_order], atol=1e-3)
    np.testing.assert_allclose(first.weights[order], reference.weights_[ref_order], atol=1e-3)


def test_levenberg_marquardt_recovers_a_mixture_and_never_worsens_the_start():
    truth = Mixture(
        weights=np.full(2, 0.5),
        means=np.array([[0.3, 0.1], [0.7, -0.1]]),
        covariances=np.array([[[0.02, 0.005], [0.005, 0.01]], [[0.015, 0.0], [0.0, 0.03]]]),
        amplitudes=np.array([0.02, 0.03]),
    )
    xy = np.random.default_rng(5).uniform([0, -0.4], [1, 0.4], (600, 2))
    ones = np.ones(len(xy))
    target = truth.value(xy)
    start = Mixture(truth.weights, truth.means + 0.05, truth.covariances * 1.3, truth.amplitudes)

    def cost(theta):
        res = _residual_rows(xy, ones, target, theta.reshape(-1, 6), np.empty((0, len(theta))))
        return res @ res

    fitted = _levenberg_marquardt(xy, ones, target, _pack(start), 60, 0.0)
    assert cost(fitted) < 1e-12 * cost(_pack(start))
    np.testing.assert_allclose(fitted, _pack(truth), atol=1e-5)
    exact = _levenberg_marquardt(xy, ones, target, _pack(truth), 5, 0.0)  # stays put
    assert cost(exact) <= cost(_pack(truth))


def test_mpu_on_grid_nodes_is_evaluate_at_them():
    result = ls.reconstruct(ls.demo("parallel"), ls.Params(k=3, grid=96)).unit  # the MPU's size
    implicit, grid = result.surface.implicit, result.grid
    np.testing.assert_array_equal(implicit.on_grid(grid), implicit.evaluate(grid.points))
    nodes = result.inside.copy()
    nodes[::3] = False
    xy = np.vstack([result.polygon, grid.points[nodes]])
    on_grid = implicit.derivatives_on_grid(xy, grid, nodes)
    for a, b in zip(on_grid, implicit._blend(xy, 2), strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)


def test_thin_outline_keeps_a_dense_outline_within_a_tiny_distance():
    angle = np.linspace(0, 2 * np.pi, 40000, endpoint=False)
    circle = np.column_stack([np.cos(angle), 0.5 * np.sin(angle)])
    keep = thin_outline(circle, most=2000)
    assert 1500 <= len(keep) <= 2000 and keep[0] == 0 and np.all(np.diff(keep) > 0)
    thinned = LinearRing(circle[keep])
    assert shapely.distance(thinned, shapely.points(circle)).max() < 1e-5
    np.testing.assert_array_equal(thin_outline(circle[:1000], most=2000), np.arange(1000))


def test_a_dense_outline_with_a_slit_narrower_than_the_thinning_stays_a_valid_subset():
    """A unit square traced by 24,000 points with a wavy slit 4e-4 wide down to y = 0.3: chords
    of the thinned walls (step about 2e-3) cut across it, so the outline must be thinned less,
    not repaired (a repair fills the slit with vertices that are no input points)."""
    y = np.linspace(1, 0.3, 4000)
    wave = 0.005 * np.sin(600 * y)
    down = np.column_stack([0.5002 + wave, y])
    up = np.column_stack([0.4998 + wave[::-1], y[::-1]])
    edge = np.linspace(0, 1, 4000, endpoint=False)
    bottom_right = np.column_stack([np.r_[edge, np.ones(4000)], np.r_[np.zeros(4000), edge]])
    top_right = np.column_stack([np.linspace(1, down[0, 0], 2000, endpoint=False), np.ones(2000)])
    top_left = np.column_stack([np.linspace(up[-1, 0], 0, 2000, endpoint=False), np.ones(2000)])
    left = np.column_stack([np.zeros(4000), 1 - edge])
    dense = np.vstack([bottom_right, top_right, down, up, top_left, left])
    polygon = leaf_polygon(dense)
    assert Polygon(polygon).is_valid and len(polygon) < len(dense)
    inputs = {tuple(p) for p in np.round(dense, 12)}
    assert all(tuple(p) in inputs for p in np.round(polygon, 12))  # each an input point
    assert Polygon(polygon).area == pytest.approx(Polygon(dense).area, rel=1e-5)


def _densified(curve: np.ndarray, per_edge: int, closed: bool) -> np.ndarray:
    """`per_edge` points along each edge of a polyline (the input points kept among them)."""
    ends = np.vstack([curve, curve[:1]]) if closed else curve
    t = np.arange(per_edge)[None, :, None] / per_edge
    inner = ends[:-1, None] + t * (ends[1:, None] - ends[:-1, None])
    dense = inner.reshape(-1, 3)
    return dense if closed else np.vstack([dense, curve[-1:]])


def test_a_dense_scan_is_thinned_and_still_within_the_issue_figures():
    nested = ls.demo("nested")
    leaf = ls.Leaf(
        boundary=_densified(nested.boundary, 40, closed=True),
        veins=[_densified(v, 60, closed=False) for v in nested.veins],
    )
    assert len(leaf.boundary) > 3 * 3000 and len(leaf.vein_points) > 3000
    result = ls.reconstruct(leaf, ls.Params(k=PAPER_K["nested"], grid=128))
    assert len(result.polygon) <= 3000
    m = result.metrics  # from every input point to the mesh
    assert m["boundary"]["mean"] <= 1e-3 and m["boundary"]["max"] <= 5e-3
    assert m["veins"]["mean"] <= 5e-3
    assert m["mesh"]["components"] == 1 and m["mesh"]["boundary_loops"] == 1


def test_every_compiled_kernel_lives_where_the_kernel_cache_stamp_looks():
    """kernelcache's stamp (whether a run will compile) hashes the modules under core/: a kernel
    elsewhere would change without the stamp noticing."""
    from pathlib import Path

    from leafstudio._shared import kernelcache

    package = Path(ls.__file__).parent
    compiled = {p for p in package.rglob("*.py") if "@njit" in p.read_text(encoding="utf-8")}
    assert compiled and all(kernelcache.CORE in p.parents for p in compiled)


def test_the_bucket_walk_gathers_every_point_of_a_box_and_none_far_from_it():
    """buckets.gather, the one bucket walk (the MPU's fits and sums, near_edges): every point in
    the box, each once, and nothing beyond the buckets the box overlaps."""
    from leafstudio.core.buckets import bucket_points, gather

    rng = np.random.default_rng(3)
    points = rng.random((3000, 2)) * [2.0, 1.0]
    b = bucket_points(points)
    out = np.empty(len(points), np.int64)
    boxes = [(0.2, 0.5, 0.1, 0.3), (-1, 3, -1, 2), (1.9, 2.5, 0.9, 1.5), (5, 6, 5, 6)]
    for x0, x1, y0, y1 in boxes:
        found = out[: gather(b, x0, x1, y0, y1, out)]
        assert len(set(found.tolist())) == len(found)
        x, y = points[:, 0], points[:, 1]
        inside = np.flatnonzero((x >= x0) & (x <= x1) & (y >= y0) & (y <= y1))
        assert set(inside.tolist()) <= set(found.tolist())
        near = points[found]
        assert np.all(near >= [x0 - b.size, y0 - b.size])
        assert np.all(near <= [x1 + b.size, y1 + b.size])
