"""The outline's polygon helpers (core/prepare/polygon.py)."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from leafstudio.core.prepare.polygon import ring_crossings


def _crosses_by_pairs(ring: np.ndarray) -> bool:
    """Every pair of segments that are not neighbours along the ring, tested one by one."""
    n = len(ring)
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
