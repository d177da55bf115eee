"""The vein correction's derivatives at the mesh's grid nodes by differences of its values
there (core/node_derivatives.py), against their closed form."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

import leafstudio as ls
from leafstudio.core.curvature import graph_curvatures
from leafstudio.core.grid import Grid
from leafstudio.core.node_derivatives import _around, node_derivatives
from leafstudio.forms.make import Form


def _quadratic(xy: np.ndarray) -> np.ndarray:
    x, y = xy.T
    return 0.3 - 0.7 * x + 1.1 * y + 2.0 * x * x - 1.5 * x * y + 0.8 * y * y


def test_the_stencil_nodes_are_a_3_by_3_dilation_of_the_asked_ones():
    """_around grows the asked nodes as scipy's binary dilation with a 3 x 3 block does, edges
    of the grid included."""
    from scipy.ndimage import binary_dilation

    rng = np.random.default_rng(3)
    for shape, share in (((17, 23), 0.05), ((9, 6), 0.3), ((1, 5), 0.5), ((40, 31), 0.9)):
        asked = rng.random(shape) < share
        asked[0, -1] = True  # a corner
        expected = binary_dilation(asked, np.ones((3, 3), dtype=bool))
        np.testing.assert_array_equal(_around(asked), expected)


def test_differences_are_exact_on_a_quadratic_and_ask_only_for_the_unknown_nodes():
    grid = Grid(origin=np.array([-1.0, -0.5]), spacing=0.05, shape=(21, 41))
    ny, nx = grid.shape
    known = np.zeros(ny * nx, dtype=bool)
    known.reshape(ny, nx)[3:-3, 3:-3] = True
    asked = []

    def value(xy: np.ndarray) -> np.ndarray:
        asked.append(len(xy))
        return _quadratic(xy)

    nodes = np.flatnonzero(known)
    c, gradient, hessian = node_derivatives(
        value, grid, known, _quadratic(grid.points[known]), nodes
    )
    x, y = grid.points[nodes].T
    np.testing.assert_allclose(c, _quadratic(grid.points[nodes]))
    np.testing.assert_allclose(gradient[:, 0], -0.7 + 4.0 * x - 1.5 * y, atol=1e-9)
    np.testing.assert_allclose(gradient[:, 1], 1.1 - 1.5 * x + 1.6 * y, atol=1e-9)
    np.testing.assert_allclose(hessian[:, 0, 0], 4.0, atol=1e-7)
    np.testing.assert_allclose(hessian[:, 1, 1], 1.6, atol=1e-7)
    np.testing.assert_allclose(hessian[:, 0, 1], -1.5, atol=1e-7)
    np.testing.assert_allclose(hessian[:, 1, 0], -1.5, atol=1e-7)
    ring = (ny - 4) * (nx - 4) - (ny - 6) * (nx - 6)  # the nodes one step past the known ones
    assert asked == [ring]


def test_a_node_whose_stencil_runs_off_the_grid_gets_none():
    grid = Grid(origin=np.zeros(2), spacing=0.1, shape=(5, 5))
    known = np.ones(25, dtype=bool)
    values = _quadratic(grid.points)
    assert node_derivatives(_quadratic, grid, known, values, np.array([0])) is None
    assert node_derivatives(_quadratic, grid, known, values, np.array([12])) is not None


@pytest.mark.parametrize("shape", ["ovate", "hastate"])
def test_the_meshs_curvatures_through_the_veins_are_the_closed_forms_away_from_the_veins(
    shape, monkeypatch
):
    """The mesh stage took ∇c and ∇²c in closed form at every vertex (232 ms at grid 512, more
    than the rest of the run); at its grid nodes they are now differences of c. Away from the
    spline's centres (three grid steps and more: c's Hessian has a log r spike at each) the
    curvatures are the closed form's to 2% of their largest, and to 1e-3 at the median."""
    import leafstudio.core.steps as steps

    asked = []
    differences = steps.node_derivatives
    monkeypatch.setattr(steps, "node_derivatives", lambda *a: asked.append(a) or differences(*a))
    result = ls.reconstruct(Form(shape).leaf(), ls.Params(grid=128))
    unit = result.unit
    assert len(asked) == 1 and len(asked[0][-1]) > 0.8 * len(unit.triangle_mesh.points)
    mesh = unit.triangle_mesh
    xy, _ = unit.frame.to_plane(np.asarray(mesh.points))
    margin = np.arange(len(xy)) < len(unit.polygon)
    _, grad, hess = unit.surface.derivatives(xy, margin)
    closed = graph_curvatures(grad, hess)
    far = cKDTree(unit.surface.correction.centers).query(xy)[0] > 3 * unit.grid.spacing
    assert far.mean() > 0.5
    for name in ("mean_curvature", "gaussian_curvature"):
        shown = np.asarray(mesh.point_data[name])
        assert np.all(np.isfinite(shown))
        off = np.abs(shown - closed[name])[far] / np.abs(closed[name]).max()
        assert off.max() < 0.02 and np.median(off) < 1e-3, name
