"""Boundary clouds as scanners give them (issue 10, part A): noisy, unordered, dense, unevenly
spaced. Each finding of the issue first, then the properties any valid leaf must have."""

from __future__ import annotations

import json

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import leafstudio as ls
from leafstudio.cli import main
from leafstudio.core.evaluate import margin_creases
from leafstudio.core.grid import make_grid
from leafstudio.core.mesher import MAX_EDGE, conforming_grid_mesh
from leafstudio.core.prepare.outline import trace_outline
from leafstudio.core.prepare.polygon import contains
from tests.leaves import ellipse_cloud as _ellipse
from tests.leaves import random_leaf as _random_leaf

ELLIPSE_AREA = 2 * np.pi  # semi-axes 2 and 1


def _midrib(n: int = 50) -> np.ndarray:
    x = np.linspace(-1.6, 1.6, n)
    return np.column_stack([x, np.zeros(n), 0.1 * (1 - (x / 2) ** 2)])


def test_finding1_noisy_shuffled_ellipse_measures_its_area(tmp_path, capsys):
    """3,000 shuffled points with noise of 0.05% of the length: the area was 2.44, not 6.28."""
    boundary = _ellipse(3000, 0.0005 * 4)
    path = tmp_path / "ellipse.csv"
    np.savetxt(path, boundary, delimiter=",")
    assert main(["measure", str(path), "--json"]) == 0
    area = json.loads(capsys.readouterr().out)["area"]
    assert area == pytest.approx(ELLIPSE_AREA, rel=0.01)


@pytest.mark.parametrize("n, sigma", [(10_000, 0.00013 * 4), (10_000, 0.002)])
def test_finding1_noise_gives_no_false_errors(n, sigma):
    """Veins inside a noisy shuffled boundary were said to lie outside it (or the outline to
    cross itself)."""
    leaf = ls.Leaf(boundary=_ellipse(n, sigma, seed=1), veins=[_midrib()])
    result = ls.reconstruct(leaf, ls.Params(k=2, grid=64))
    m = result.metrics
    assert m["mesh"]["components"] == 1 and m["mesh"]["boundary_loops"] == 1
    assert m["leaf"]["projected_area"] == pytest.approx(ELLIPSE_AREA, rel=0.01)


def test_finding2_ordered_points_at_random_spacing_are_recognised_as_ordered():
    """They went to the concave hull (153 s at 1e5 points): they keep their points and order."""
    boundary = _ellipse(20_000, 0.0, shuffle=False, even=False)[:, :2]
    outline = trace_outline(boundary)
    assert not outline.smoothed
    inputs = {tuple(p) for p in boundary}
    assert all(tuple(p) in inputs for p in outline.polygon)
    assert shapely.Polygon(outline.polygon).area == pytest.approx(ELLIPSE_AREA, rel=1e-4)


def test_order_does_not_matter_for_a_clean_dense_boundary():
    """Shuffled, the same points give the same outline as in order (so the same mesh)."""
    ordered = _ellipse(50_000, 0.0, shuffle=False, even=False)[:, :2]
    shuffled = np.random.default_rng(5).permutation(ordered)
    a, b = trace_outline(ordered), trace_outline(shuffled)
    np.testing.assert_allclose(a.polygon, b.polygon, atol=1e-9)  # points 1e-10 apart may swap


def test_order_does_not_matter_for_a_noisy_boundary():
    noisy = _ellipse(20_000, 0.004, shuffle=False)
    a = ls.reconstruct(ls.Leaf(noisy, []), ls.Params(grid=64))
    b = ls.reconstruct(ls.Leaf(np.random.default_rng(2).permutation(noisy), []), ls.Params(grid=64))
    np.testing.assert_allclose(a.polygon, b.polygon, atol=1e-9)
    np.testing.assert_allclose(a.triangle_mesh.points, b.triangle_mesh.points, atol=1e-9)


def test_repeated_points_5e_12_apart_trace_the_outline_they_trace_together():
    """Issue 24, finding 19: at unit size two inputs 5e-12 apart traced outlines of different
    vertex counts. A cloud's repeated points were dropped by rounding them to a grid of 1e-9:
    the few copies 5e-12 apart that fell either side of a rounding boundary were kept, their
    neighbour 5e-12 away shrank the spacing the cells are sized by, and the outline moved by up
    to 0.75% of the length. Repeats are now points within 1e-9 of the size, wherever they lie."""
    cloud = _ellipse(3000, 0.01)[:, :2]  # length 4
    for seed in range(6):  # a few copies of 600 fall either side of a rounding boundary
        rng = np.random.default_rng(seed)
        copies = cloud[rng.choice(len(cloud), 600, replace=False)]
        together = trace_outline(np.vstack([cloud, copies]))
        apart = trace_outline(np.vstack([cloud, copies + rng.normal(0, 5e-12, copies.shape)]))
        assert len(apart.polygon) == len(together.polygon)
        np.testing.assert_allclose(apart.polygon, together.polygon, atol=1e-9)


def _ovate(n: int, sigma: float, seed: int = 3) -> ls.Leaf:
    """An ovate leaf (length 1) with a midrib and two veins, boundary noise σ in x, y and z."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    x = 0.5 - 0.5 * np.cos(t)
    y = 0.3 * np.sin(t) * (1 - 0.4 * x)
    boundary = np.column_stack([x, y, np.zeros(n)]) + rng.normal(0, sigma, (n, 3))
    s = np.linspace(0.05, 0.95, 40)
    midrib = np.column_stack([s, np.zeros_like(s), 0.04 * np.sin(np.pi * s)])
    return ls.Leaf(boundary=rng.permutation(boundary), veins=[midrib])


@pytest.mark.parametrize("grid", [128, 256])
def test_finding4_a_noisy_margin_is_smooth_and_on_the_data(grid):
    """Noise of 0.2% of the length: the margin band's 99th-percentile dihedral angle was 63-68°
    against 3-7° inside. Now at most twice the interior's and under 10°, the boundary points
    within 1.5 σ of the mesh on average, the area within 1%."""
    sigma = 0.002
    leaf = _ovate(4000, sigma)
    result = ls.reconstruct(leaf, ls.Params(k=2, grid=grid))
    creases = margin_creases(result)
    margin, interior = creases["margin_p99"], creases["interior_p99"]
    assert margin <= max(2 * interior, 1.0) and margin < 10
    m = result.metrics
    assert m["boundary"]["mean"] <= 1.5 * sigma
    t = np.linspace(0, 2 * np.pi, 20000)
    x = 0.5 - 0.5 * np.cos(t)
    exact = shapely.Polygon(np.column_stack([x, 0.3 * np.sin(t) * (1 - 0.4 * x)])).area
    assert m["leaf"]["projected_area"] == pytest.approx(exact, rel=0.01)


def test_clean_boundaries_keep_their_points_on_the_mesh():
    """Demos, sketches and extract's outlines: clean, so their points are the margin's."""
    for name in ("nested", "parallel"):
        leaf = ls.demo(name)
        outline = trace_outline(leaf.boundary[:, :2])
        assert not outline.smoothed
        np.testing.assert_array_equal(np.sort(outline.polygon, axis=0),
                                      np.sort(leaf.boundary[:, :2], axis=0))  # fmt: skip


@settings(
    max_examples=8, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)  # the same examples in every CI run; widen max_examples locally to search further
@given(
    seed=st.integers(0, 10_000),
    n=st.integers(2000, 20_000),
    noise=st.sampled_from([0.0, 1e-4, 1e-3, 5e-3, 1e-2]),
    size=st.sampled_from([1e-6, 1e-3, 1.0, 1e3, 1e6]),  # the pipeline runs at unit size
)
def test_any_valid_leaf_gives_one_clean_piece_of_the_right_area(seed, n, noise, size):
    leaf, area = _random_leaf(seed, n, noise, size)
    params = ls.Params(grid=64)
    result = ls.reconstruct(leaf, params)
    m = result.metrics
    assert m["mesh"]["components"] == 1 and m["mesh"]["boundary_loops"] == 1
    assert m["leaf"]["projected_area"] == pytest.approx(area, rel=0.01)
    shuffled = ls.Leaf(np.random.default_rng(seed + 1).permutation(leaf.boundary), [])
    again = ls.reconstruct(shuffled, params)
    np.testing.assert_allclose(again.polygon, result.polygon, atol=1e-9 * size)


def test_finding8_no_slivers_where_the_grid_keeps_no_node():
    """Where the implicit drops the grid nodes of a region inside the outline (as it did by a
    cordate leaf's basal sinus), Delaunay joined far margin points by slivers: now no edge but
    the outline's own is longer than MAX_EDGE grid steps, and the triangles still tile it."""
    angle = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    polygon = np.column_stack([np.cos(angle), 0.6 * np.sin(angle)])
    grid = make_grid(polygon, 128)
    x, y = grid.points.T
    inside = contains(polygon, grid.points) & ~((x < -0.3) & (np.abs(y) < 0.35))  # a hole
    xy, triangles, _ = conforming_grid_mesh(polygon, grid, inside)
    b = len(polygon)
    edges = np.unique(np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0)
    ring = (edges[:, 1] < b) & np.isin(edges[:, 1] - edges[:, 0], [1, b - 1])
    length = np.linalg.norm(xy[edges[:, 0]] - xy[edges[:, 1]], axis=1)
    assert length[~ring].max() <= MAX_EDGE * grid.spacing
    corners = xy[triangles]
    u, v = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    signed = (u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]) / 2
    assert np.all(signed > 0)
    assert signed.sum() == pytest.approx(shapely.Polygon(polygon).area, rel=1e-9)


@pytest.mark.parametrize("corners", [40, 60])
def test_finding8_a_sparse_heart_has_no_slivers_from_its_sinus(corners):
    """Finding 8 as a user meets it: a heart-shaped (cordate) sketch of a few dozen clean points
    with a midrib from its notch, grid 128. The old mesher joined the notch to the waist by
    triangles 0.09-0.13 of the leaf length long; now no edge is longer than a few grid cells."""
    from leafstudio.core.evaluate import triangles_of

    t = np.linspace(0, 2 * np.pi, corners, endpoint=False)
    x = 16 * np.sin(t) ** 3
    y = 13 * np.cos(t) - 5 * np.cos(2 * t) - 2 * np.cos(3 * t) - np.cos(4 * t)
    heart = np.column_stack([x, y, np.zeros(corners)]) / 16
    along = np.linspace(0, 1, 30)
    midrib = np.column_stack([np.zeros(30), -1.0 + 1.25 * along, 0.05 * np.sin(np.pi * along)])
    result = ls.reconstruct(ls.Leaf(heart, [midrib]), ls.Params(grid=128))
    mesh = result.triangle_mesh
    triangles = triangles_of(mesh)
    corners_xyz = mesh.points[triangles]
    edges = np.linalg.norm(corners_xyz - np.roll(corners_xyz, 1, axis=1), axis=2)
    assert edges.max() <= 4 * result.length / 128


def test_the_margin_can_be_chosen_over_the_measured_noise():
    """Params.margin: "exact" keeps the points as the margin, "smooth" smooths a clean one."""
    noisy = _ellipse(2000, 0.0005, shuffle=False)  # noisy, but the ring through it is simple
    exact = ls.reconstruct(ls.Leaf(noisy, []), ls.Params(grid=64, margin="exact"))
    auto = ls.reconstruct(ls.Leaf(noisy, []), ls.Params(grid=64))
    inputs = {tuple(np.round(p, 9)) for p in exact.frame.to_plane(noisy)[0]}
    assert all(tuple(np.round(p, 9)) in inputs for p in exact.polygon)
    assert not any(tuple(np.round(p, 9)) in inputs for p in auto.polygon[:50])
    outline = trace_outline(ls.demo("nested").boundary[:, :2], margin="smooth")
    assert outline.smoothed
    with pytest.raises(ls.LeafError, match="margin must be one of"):
        ls.Params(margin="jagged")


def test_the_command_line_takes_the_margin(tmp_path, capsys):
    path = tmp_path / "noisy.csv"
    np.savetxt(path, _ellipse(2000, 0.0005, shuffle=False), delimiter=",")
    areas = {}
    for margin in ("exact", "smooth"):
        assert main(["measure", str(path), "--json", "--grid", "32", "--margin", margin]) == 0
        areas[margin] = json.loads(capsys.readouterr().out)["area"]
    assert areas["exact"] != areas["smooth"]
    assert areas["exact"] == pytest.approx(areas["smooth"], rel=0.01)
    assert main(["measure", str(path), "--margin", "jagged"]) == 2


@pytest.mark.parametrize("count", [5, 12, 40])
def test_sketched_outlines_are_clean(count):
    """A sketch's boundary (a periodic spline through a few clicks, even irregular ones) keeps
    its points as the margin."""
    from leafstudio.gui.model.sketch_model import closed_curve  # no Qt in the sketch's model

    rng = np.random.default_rng(count)
    angle = np.sort(rng.uniform(0, 2 * np.pi, count))
    radius = rng.uniform(0.8, 1.2, (count, 1))
    clicks = np.column_stack([np.cos(angle), 0.5 * np.sin(angle)]) * radius
    outline = trace_outline(closed_curve(clicks))
    assert not outline.smoothed


def test_a_cloud_that_fills_the_leaf_gives_its_outline():
    """Points over the whole blade (a scan given as a boundary) trace no margin: the outline of
    the region they fill, not an error."""
    rng = np.random.default_rng(4)
    r, t = np.sqrt(rng.uniform(0, 1, 20_000)), rng.uniform(0, 2 * np.pi, 20_000)
    filled = np.column_stack([2 * r * np.cos(t), r * np.sin(t)])
    outline = trace_outline(filled)
    assert outline.smoothed
    assert shapely.Polygon(outline.polygon).area == pytest.approx(ELLIPSE_AREA, rel=0.05)


def test_a_whole_scan_given_as_the_boundary_is_refused():
    """Review finding: the points of a whole leaf's surface given as its boundary were taken as
    an outline without a word (its area off by 4.5%, the points' surface lost). A warning was not
    enough (the real scans passed it: tests/test_scan_as_boundary.py); now an error points to
    `extract`, and a noisy outline (1% of the length) reconstructs."""
    rng = np.random.default_rng(0)
    angle, radius = rng.uniform(0, 2 * np.pi, 20000), np.sqrt(rng.uniform(0, 1, 20000))
    surface = np.column_stack(
        [2 * radius * np.cos(angle), radius * np.sin(angle), 0.05 * (1 - radius**2)]
    )
    with pytest.raises(ls.LeafError, match=r"cover a surface.*extract"):
        ls.reconstruct(ls.Leaf(surface, []), ls.Params(grid=48))
    noisy = ls.reconstruct(ls.Leaf(_ellipse(20000, 0.04), []), ls.Params(grid=48))
    assert noisy.metrics["leaf"]["projected_area"] == pytest.approx(ELLIPSE_AREA, rel=0.01)
