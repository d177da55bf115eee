"""A boundary of few points is a polygon the pipeline reconstructs (fuzzing, issue 24: three
points gave NaN curvatures, four to seven an internal error)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import shapely

import leafstudio as ls
from leafstudio.core.prepare.outline import SPARSE_OUTLINE, trace_outline
from tests.leaves import metric_numbers


def _polygon(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    angles = np.sort(rng.uniform(0, 2 * np.pi, n)) if seed else np.arange(n) * 2 * np.pi / n
    radii = rng.uniform(0.5, 1.5, n) if seed else np.ones(n)
    return np.column_stack([radii * np.cos(angles), 0.5 * radii * np.sin(angles), np.zeros(n)])


@pytest.mark.parametrize("n", [3, 4, 5, 6, 7, 10])
@pytest.mark.parametrize("seed", [0, 3, 11])
@pytest.mark.parametrize("repeats", [1, 20])
def test_a_few_boundary_points_give_a_finite_mesh(n, seed, repeats):
    boundary = np.repeat(_polygon(n, seed), repeats, axis=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # no veins given: flat
        result = ls.reconstruct(ls.Leaf(boundary, []), ls.Params(grid=48))
    numbers = metric_numbers(result.metrics)
    assert np.all(np.isfinite(numbers))
    assert np.all(np.isfinite(result.triangle_mesh.points))
    if seed == 0:  # a regular polygon, read in its order: the mesh covers it
        area = shapely.Polygon(_polygon(n, seed)[:, :2]).area
        assert result.metrics["leaf"]["projected_area"] == pytest.approx(area, rel=0.05)


def test_the_added_points_lie_on_the_polygons_edges():
    square = np.array([[0, 0], [2, 0], [2, 1], [0, 1]], dtype=float)
    outline = trace_outline(square, np.zeros(4), "exact")
    assert len(outline.polygon) >= SPARSE_OUTLINE
    ring = shapely.LinearRing(square)
    assert shapely.distance(ring, shapely.points(outline.polygon)).max() < 1e-12
    assert {tuple(p) for p in square} <= {tuple(p) for p in outline.polygon}
