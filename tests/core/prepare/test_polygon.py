"""The outline's polygon helpers (core/prepare/polygon.py)."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from leafstudio.core.prepare.polygon import (
    _qhull_perimeter,
    distinct_each,
    distinct_indices,
    hull_perimeter,
    ring_crossings,
)


def _crosses_by_pairs(ring: np.ndarray) -> bool:
    """Every pair of segments that are not neighbours along the ring (a point repeated in a row
    taken once), tested one by one."""
    ring = np.array([p for i, p in enumerate(ring) if not np.array_equal(p, ring[i - 1])])
    n = len(ring)
    if n < 4:
        return False
    segments = [shapely.LineString([ring[i], ring[(i + 1) % n]]) for i in range(n)]
    return any(
        segments[i].intersects(segments[j])
        for i in range(n)
        for j in range(i + 2, n)
        if (i - j) % n > 1
    )


def _rings(seed: int) -> list[np.ndarray]:
    """Star-shaped rings (simple), random walks closed (mostly crossing), a figure eight, rings
    with a repeated point, a spike back along an edge, a touch at a vertex, on a coarse lattice
    so that points coincide and segments overlap."""
    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(0, 2 * np.pi, 12))
    star = np.column_stack([np.cos(t), np.sin(t)]) * rng.uniform(0.5, 1.5, (12, 1))
    walk = np.round(rng.normal(size=(9, 2)) * 2) / 2
    eight = np.array([[0, 0], [1, 1], [2, 0], [2, 1], [1, 0], [0, 1]], dtype=float)
    repeated = np.insert(star, 4, star[4], axis=0)
    spike = np.insert(star, 5, star[4] + 0.5 * (star[5] - star[4]), axis=0)
    spike = np.insert(spike, 6, star[4], axis=0)
    touch = np.array([[0, 0], [2, 0], [2, 2], [1, 0], [0, 2]], dtype=float)
    return [star, walk, eight, repeated, spike, touch]


@pytest.mark.parametrize("seed", range(12))
def test_a_ring_crosses_itself_exactly_when_two_of_its_segments_meet(seed):
    for ring in _rings(seed):
        assert (len(ring_crossings(ring)) > 0) == _crosses_by_pairs(ring), ring.tolist()


def test_a_point_given_twice_in_a_row_is_no_crossing():
    """A closed polyline repeats its first point at the end and a sketch or file may hold a point
    twice: a step of length 0 meets its neighbours' neighbours at that point, which is no
    crossing."""
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    ring = np.column_stack([2 * np.cos(t), np.sin(t)])
    for given in (np.vstack([ring, ring[:1]]), np.insert(ring, 7, ring[7], axis=0),
                  np.repeat(ring, 3, axis=0)):  # fmt: skip
        assert len(ring_crossings(given)) == 0
    eight = np.column_stack([np.sin(t), np.sin(t) * np.cos(t)])
    assert len(ring_crossings(np.vstack([eight, eight[:1]]))) > 0


@pytest.mark.parametrize("seed", range(4))
def test_the_hull_perimeter_is_qhulls(seed):
    """The compiled monotone chain measures the hull as Qhull does, within rounding: random
    clouds of 3 to 1000 points at any aspect, and star-shaped rings, nearly all on their hull
    as a leaf's outline is."""
    rng = np.random.default_rng(seed)
    clouds = [rng.normal(size=(n, 2)) * rng.uniform(0.01, 100, 2) for n in (3, 4, 10, 1000)]
    for points in clouds + _rings(seed):
        points = np.asarray(points, dtype=float)
        if len(np.unique(points, axis=0)) < 3:
            continue
        np.testing.assert_allclose(hull_perimeter(points), _qhull_perimeter(points), rtol=1e-12)


def test_a_flat_hull_is_left_to_qhull():
    """Collinear points, fewer than three and points that are not finite measure 0, as Qhull
    has them; a hull all but flat is Qhull's own figure."""
    line = np.column_stack([np.arange(5.0), 2 * np.arange(5.0)])
    for points in (line, np.zeros((5, 2)), line[:2], np.array([[0, 0], [1, 1], [np.nan, 0]])):
        assert hull_perimeter(points) == 0.0
    thin = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 1e-12]])
    assert hull_perimeter(thin) == _qhull_perimeter(thin)


def test_the_curves_repeats_found_at_once_are_each_curves_own():
    """distinct_each (the frame stage's: curves whose points are all apart found in one compiled
    pass) drops the repeats distinct_indices drops: copies a hair apart, points apart along one
    axis but not the other, one point and none, and curves at 1e-200 and 1e200."""
    rng = np.random.default_rng(5)
    walk = np.cumsum(rng.normal(size=(30, 2)), axis=0)
    copies = np.insert(walk, [4, 9, 9], walk[[3, 8, 8]] + 1e-14, axis=0)
    column = np.column_stack([np.zeros(10), np.arange(10.0)])  # apart along y only
    grid = np.column_stack([np.repeat(np.arange(4.0), 4), np.tile(np.arange(4.0), 4)])
    curves = [walk, copies, column, grid, walk[:1], walk[:0], walk * 1e-200, walk * 1e200]
    for scale in (1.0, 1e-3, 1e12):
        for got, curve in zip(distinct_each(curves, scale), curves, strict=True):
            np.testing.assert_array_equal(got, distinct_indices(curve, scale))
    assert len(distinct_each([copies], 1.0)[0]) == len(walk)


def test_distinct_points_found_by_the_bucket_search_are_the_trees():
    """distinct_indices' bucket search (polygon._apart_in_the_plane) ahead of the k-d tree keeps
    the same points as the tree alone, on sets with shared coordinates and near repeats."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    from leafstudio.core.prepare.polygon import distinct_indices, unit_power

    def tree_only(points: np.ndarray) -> np.ndarray:
        n, unit = len(points), unit_power(points)
        pairs = cKDTree(points * unit).query_pairs(1e-9 * unit, output_type="ndarray")
        if not len(pairs):
            return np.arange(n)
        links = coo_matrix((np.ones(len(pairs), dtype=bool), (pairs[:, 0], pairs[:, 1])), (n, n))
        return np.sort(np.unique(connected_components(links, directed=False)[1], True)[1])

    rng = np.random.default_rng(8)
    for trial in range(300):
        x = rng.standard_normal((int(rng.integers(2, 300)), 2)) * rng.choice([1e-3, 1.0, 1e5])
        if trial % 2:
            x = np.round(x, int(rng.integers(0, 3)))
        if trial % 3 == 0:
            k = int(rng.integers(1, len(x) + 1))
            x = np.vstack(
                [x, x[:k] + rng.choice([0.0, 1e-12, 1e-10]) * rng.standard_normal((k, 2))]
            )
        np.testing.assert_array_equal(distinct_indices(x, 1.0), tree_only(x))
