"""analysis.edge_counts, compiled (edges bucketed by their lower vertex), gives what one sorted
key per edge gives: the same edges in the same order, the same counts, on grid meshes, fans
(a hub vertex with thousands of edges), repeated and degenerate triangles, and no triangles."""

from __future__ import annotations

import numpy as np
import pytest

from leafstudio.core.analysis import SMALL_BUCKET, boundary_loops, edge_counts


def by_sorted_keys(triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The formulation edge_counts replaced: np.unique over one integer key per edge."""
    edges = np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1).astype(np.int64)
    base = int(edges.max(initial=0)) + 1
    keys, counts = np.unique(edges[:, 0] * base + edges[:, 1], return_counts=True)
    return np.column_stack([keys // base, keys % base]).reshape(-1, 2), counts


def grid_mesh(n: int) -> np.ndarray:
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1), indexing="ij")
    a = (i * n + j).ravel()
    return np.vstack(
        [np.column_stack([a, a + 1, a + n]), np.column_stack([a + 1, a + n + 1, a + n])]
    )


def fan(n: int) -> np.ndarray:
    return np.column_stack([np.zeros(n - 2, int), np.arange(1, n - 1), np.arange(2, n)])


rng = np.random.default_rng(7)
MESHES = {
    "grid": grid_mesh(40),
    "shuffled grid": rng.permutation(grid_mesh(30)),
    "fan": fan(20 * SMALL_BUCKET),
    "reversed fan": fan(3 * SMALL_BUCKET)[::-1, ::-1],
    "random with repeats": rng.integers(0, 60, (500, 3)),
    "one triangle three times": np.array([[0, 1, 2], [2, 1, 0], [0, 1, 2]]),
    "none": np.empty((0, 3), np.int64),
}


@pytest.mark.parametrize("name", MESHES)
def test_edge_counts_match_the_sorted_keys(name):
    triangles = MESHES[name]
    edges, counts = edge_counts(triangles)
    want_edges, want_counts = by_sorted_keys(triangles)
    np.testing.assert_array_equal(edges, want_edges)
    np.testing.assert_array_equal(counts, want_counts)
    assert edges.dtype == np.int64 and edges.shape == (len(counts), 2)


def test_a_grid_mesh_has_one_boundary_loop_from_given_counts():
    triangles = grid_mesh(12)
    assert boundary_loops(triangles, edge_counts(triangles)) == boundary_loops(triangles) == 1
