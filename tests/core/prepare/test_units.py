"""Units do not matter (issue 10, finding 5): the same leaf at any size or position gives the same
figures relative to its length, to 1e-9, and very small or very large leaves run."""

from __future__ import annotations

import numpy as np
import pytest

import leafstudio as ls

PARAMS = ls.Params(k=3, grid=64)


def _leaf() -> ls.Leaf:
    """The nested demo bent a little (y + 0.05 x²): the demo is exactly symmetric, and a Delaunay
    triangulation of mirror-image margin points meets exact ties (cocircular quads) that
    round-off may break either way, moving area-weighted curvature means by 1e-6."""
    leaf = ls.demo("nested")

    def bend(p: np.ndarray) -> np.ndarray:
        return p + np.column_stack([0 * p[:, 0], 0.05 * p[:, 0] ** 2, 0 * p[:, 0]])

    return ls.Leaf(boundary=bend(leaf.boundary), veins=[bend(v) for v in leaf.veins])


def _scaled(leaf: ls.Leaf, factor: float, shift: np.ndarray | float = 0.0) -> ls.Leaf:
    return ls.Leaf(
        boundary=leaf.boundary * factor + shift, veins=[v * factor + shift for v in leaf.veins]
    )


def _relative_figures(result: ls.Result, mesh_points: bool = True) -> np.ndarray:
    """Every figure of a run made dimensionless by the leaf's length: distances and sizes over
    the length, areas over its square, curvatures times it (Gaussian times its square); with
    `mesh_points`, also two read off the mesh's world points (whose round-off is the world's)."""
    m, length = result.metrics, result.length
    leaf, curvature = m["leaf"], m["curvature"]
    figures = [
        *(m[part][s] / length for part in ("boundary", "veins") for s in ("min", "max", "mean")),
        m["mesh"]["area"] / length**2,
        leaf["area"] / length**2,
        leaf["projected_area"] / length**2,
        *(leaf[key] / length for key in ("perimeter", "length", "width", "height")),
        leaf["aspect_ratio"],
        *(
            curvature[name][s] * length
            for name in ("mean_curvature", "k1", "k2")
            for s in ("min", "max", "mean")
        ),
        *(curvature["gaussian_curvature"][s] * length**2 for s in ("min", "max", "mean")),
    ]
    if not mesh_points:
        return np.asarray(figures)
    mesh = result.triangle_mesh
    plane = result.frame.to_plane(mesh.points)
    figures += [np.abs(plane[1]).max() / length, float(np.ptp(plane[0][:, 0])) / length]
    return np.asarray(figures)


@pytest.fixture(scope="module")
def reference() -> np.ndarray:
    return _relative_figures(ls.reconstruct(_leaf(), PARAMS))


@pytest.mark.parametrize("factor", [1e-6, 0.04, 4000.0, 1e6])
def test_every_relative_figure_is_the_same_at_any_size(reference, factor):
    result = ls.reconstruct(_scaled(_leaf(), factor), PARAMS)
    np.testing.assert_allclose(_relative_figures(result), reference, rtol=1e-9, atol=1e-9)


def test_a_leaf_far_from_the_origin_gives_the_figures_of_the_same_points_near_it():
    """The points 1e8 away are rounded to float64 there; those very points, moved back (exactly,
    by Sterbenz's lemma), are the leaf to compare with."""
    shift = np.array([1e8, -3e7, 2.5e7])
    far = _scaled(_leaf(), 1.0, shift)
    near = _scaled(far, 1.0, -shift)
    got = _relative_figures(ls.reconstruct(far, PARAMS), mesh_points=False)
    want = _relative_figures(ls.reconstruct(near, PARAMS), mesh_points=False)
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("factor", [1e-9, 1e150])
def test_tiny_and_huge_leaves_run_and_map_back(reference, factor):
    leaf = _scaled(_leaf(), factor)
    result = ls.reconstruct(leaf, PARAMS)
    np.testing.assert_allclose(_relative_figures(result), reference, rtol=1e-9, atol=1e-9)
    # the mesh is in the input's coordinates, its outline on the input's boundary
    assert np.ptp(result.triangle_mesh.points[:, 0]) == pytest.approx(
        np.ptp(leaf.boundary[:, 0]), rel=1e-6
    )
    xy = result.grid.points[result.inside][::50]
    assert np.all(np.isfinite(result.height(xy)))
