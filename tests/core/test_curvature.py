"""Curvature: closed-form derivatives of z(x) against finite differences and analytic shapes."""

from __future__ import annotations

import numpy as np
import pytest
from plyfile import PlyData

import leafstudio as ls
from leafstudio.core.curvature import (
    CURVATURE_ARRAYS,
    graph_curvatures,
    implicit_derivatives,
    taper_derivatives,
)
from leafstudio.core.gmm import Mixture

STEP = 1e-6


@pytest.fixture(scope="module")
def nested():
    return ls.reconstruct(ls.demo("nested"), ls.Params(k=3, grid=48))


def _inside_points(result, count: int, seed: int) -> np.ndarray:
    nodes = result.grid.points[result.inside]
    rng = np.random.default_rng(seed)
    return nodes[rng.choice(len(nodes), count)] + rng.uniform(-0.3, 0.3, (count, 2)) * (
        result.grid.spacing
    )


def _finite_differences(function, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Central differences of a (value, gradient, ...) function: gradient and Hessian."""
    grad = np.empty((len(xy), 2))
    hess = np.empty((len(xy), 2, 2))
    for axis in range(2):
        step = np.zeros(2)
        step[axis] = STEP
        plus, minus = function(xy + step), function(xy - step)
        grad[:, axis] = (plus[0] - minus[0]) / (2 * STEP)
        hess[:, axis, :] = (plus[1] - minus[1]) / (2 * STEP)
    return grad, hess


@pytest.mark.parametrize("which", ["implicit", "surface"])
def test_derivatives_match_finite_differences(nested, which):
    function = {
        "implicit": lambda xy: implicit_derivatives(nested.surface.implicit, xy),
        "surface": nested.surface.derivatives,
    }[which]
    xy = _inside_points(nested, 300, seed=3)
    _, grad, hess = function(xy)
    fd_grad, fd_hess = _finite_differences(function, xy)
    assert np.allclose(grad, fd_grad, atol=1e-6 * np.abs(grad).max())
    # ∇²g is piecewise (C1 B-splines): a few points may straddle a seam of some cell
    close = np.all(np.abs(hess - fd_hess) <= 1e-4 * np.abs(hess).max(), axis=(1, 2))
    assert close.mean() > 0.97
    assert np.allclose(hess, hess.transpose(0, 2, 1))


def test_implicit_hessian_far_from_the_leaf(nested):
    far = np.array([[3.0, 2.0], [-2.0, -1.5]])
    function = lambda xy: implicit_derivatives(nested.surface.implicit, xy)  # noqa: E731
    _, _, hess = function(far)
    assert np.allclose(hess, _finite_differences(function, far)[1], atol=1e-5)


def _bump(height: float, sigma: float) -> Mixture:
    amplitude = height * 2 * np.pi * sigma**2
    return Mixture(np.ones(1), np.zeros((1, 2)), sigma**2 * np.eye(2)[None], np.full(1, amplitude))


def test_single_gaussian_bump_has_the_curvatures_of_its_surface_of_revolution():
    height, sigma = 0.3, 0.2
    xy = np.random.default_rng(0).uniform(-0.5, 0.5, (200, 2))
    _, grad, hess = _bump(height, sigma).derivatives(xy)
    curv = graph_curvatures(grad, hess)
    # z = f(r) = h exp(−r²/2σ²): meridian f''/(1+f'²)^1.5, parallel f'/(r (1+f'²)^0.5)
    r = np.linalg.norm(xy, axis=1)
    f = height * np.exp(-(r**2) / (2 * sigma**2))
    f1 = -r / sigma**2 * f
    f2 = (r**2 / sigma**4 - 1 / sigma**2) * f
    meridian = f2 / (1 + f1**2) ** 1.5
    parallel = f1 / (r * np.sqrt(1 + f1**2))
    assert np.allclose(curv["gaussian_curvature"], meridian * parallel)
    assert np.allclose(curv["mean_curvature"], (meridian + parallel) / 2)
    assert np.allclose(curv["k1"], np.maximum(meridian, parallel))
    assert np.allclose(curv["k2"], np.minimum(meridian, parallel))


def test_bump_peak_is_an_umbilic_dome():
    height, sigma = 0.3, 0.2
    _, grad, hess = _bump(height, sigma).derivatives(np.zeros((1, 2)))
    curv = graph_curvatures(grad, hess)
    assert curv["k1"][0] == pytest.approx(-height / sigma**2)
    assert curv["k2"][0] == pytest.approx(-height / sigma**2)
    assert curv["gaussian_curvature"][0] == pytest.approx(height**2 / sigma**4)


def test_margin_points_take_the_limit_from_inside():
    g = np.array([-1e-9, 1e-12])
    grad_g = np.array([[0.0, 1.0], [0.0, 1.0]])
    hess_g = np.zeros((2, 2, 2))
    _, outside, _ = taper_derivatives(g, grad_g, hess_g, 0.1)
    _, margin, _ = taper_derivatives(g, grad_g, hess_g, 0.1, margin=np.array([True, True]))
    assert np.allclose(outside[0], 0.0)
    assert np.allclose(margin, [[0.0, 10.0], [0.0, 10.0]])


def test_mesh_carries_curvature_arrays_into_exports(nested, tmp_path):
    mesh = nested.mesh
    for name in CURVATURE_ARRAYS:
        assert np.all(np.isfinite(mesh[name]))
    assert np.all(mesh["k1"] >= mesh["k2"])
    assert np.allclose(mesh["k1"] * mesh["k2"], mesh["gaussian_curvature"])
    assert np.allclose((mesh["k1"] + mesh["k2"]) / 2, mesh["mean_curvature"])
    # the veins are ridges: the mean curvature is negative (domed) somewhere and not zero on the
    # margin, where the inside limit is used
    assert mesh["mean_curvature"].min() < 0
    n_outline = len(nested.polygon)
    assert np.count_nonzero(mesh["mean_curvature"][:n_outline]) > 0.9 * n_outline
    import pyvista as pv

    ls.save_mesh(nested, tmp_path / "leaf.vtp")
    back = pv.read(tmp_path / "leaf.vtp")
    assert np.allclose(back["gaussian_curvature"], mesh["gaussian_curvature"])
    ls.save_mesh(nested, tmp_path / "leaf.ply")
    vertex = PlyData.read(str(tmp_path / "leaf.ply"))["vertex"]
    assert np.allclose(vertex["mean_curvature"], mesh["mean_curvature"])
    assert np.allclose(np.column_stack([vertex[c] for c in "xyz"]), mesh.points)
