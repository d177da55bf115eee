"""Point-to-mesh distances (core/distance.py): by hand in every region of a triangle, and against
open3d on a reconstructed leaf."""

from __future__ import annotations

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.core.distance import mesh_distances

TRIANGLE = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


@pytest.mark.parametrize(
    "point, expected",
    [
        ((0.2, 0.2, 0.5), 0.5),  # above the face
        ((-1.0, -1.0, 0.0), np.sqrt(2)),  # beyond corner a
        ((2.0, 0.0, 1.0), np.sqrt(2)),  # beyond corner b
        ((0.0, 3.0, 0.0), 2.0),  # beyond corner c
        ((0.5, -1.0, 0.0), 1.0),  # beside edge ab
        ((1.0, 1.0, 0.0), 1 / np.sqrt(2)),  # beside edge bc
        ((-1.0, 0.5, 2.0), np.sqrt(5)),  # beside edge ca, above the plane
    ],
)
def test_each_region_of_a_triangle_by_hand(point, expected):
    d = mesh_distances(TRIANGLE, np.array([[0, 1, 2]]), np.array([point]))
    assert d[0] == pytest.approx(expected, abs=1e-12)


def test_flat_triangles_and_vertices_of_no_triangle():
    line = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 0, 5]])  # a flat triangle, a stray
    d = mesh_distances(line, np.array([[0, 1, 2]]), np.array([[1.0, 1, 0], [3, 0, 0], [0, 0, 4.9]]))
    np.testing.assert_allclose(d, [1.0, 1.0, 4.9], atol=1e-12)
    assert len(mesh_distances(TRIANGLE, np.array([[0, 1, 2]]), np.zeros((0, 3)))) == 0


@pytest.mark.open3d
def test_a_reconstructed_leaf_agrees_with_open3d():
    import open3d as o3d

    mesh = ls.reconstruct(ls.demo("parallel"), ls.Params(k=2, grid=64)).triangle_mesh
    rng = np.random.default_rng(2)
    near = mesh.points[rng.integers(0, mesh.n_points, 400)] + rng.normal(0, 0.02, (400, 3))
    points = np.vstack([near, rng.uniform(-0.7, 0.7, (100, 3))])
    centre = mesh.points.mean(axis=0)
    scene = o3d.t.geometry.RaycastingScene()
    tmesh = o3d.t.geometry.TriangleMesh()
    tmesh.vertex.positions = o3d.core.Tensor((mesh.points - centre).astype(np.float32))
    tmesh.triangle.indices = o3d.core.Tensor(mesh.regular_faces.astype(np.int32))
    scene.add_triangles(tmesh)
    expected = scene.compute_distance(o3d.core.Tensor((points - centre).astype(np.float32)))
    ours = mesh_distances(mesh.points, mesh.regular_faces, points)
    np.testing.assert_allclose(ours, expected.numpy(), atol=2e-6)


def _brute_force(vertices: np.ndarray, triangles: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The nearest triangle found by measuring every one (each alone: no search at all)."""
    each = [mesh_distances(vertices, tri[None], points) for tri in triangles]
    return np.min(each, axis=0)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_hierarchy_finds_the_nearest_triangle_among_slivers_and_far_points(seed):
    """A bumpy grid with long slivers across it (finding 7: one long edge used to widen every
    point's search), flat triangles, duplicated vertices; points near it, far from it, on it."""
    rng = np.random.default_rng(seed)
    n = 12
    x, y = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    z = 0.05 * rng.normal(size=x.shape)
    vertices = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    quads = np.array([[i * n + j, i * n + j + 1, (i + 1) * n + j + 1, (i + 1) * n + j]
                      for i in range(n - 1) for j in range(n - 1)])  # fmt: skip
    triangles = np.vstack([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    slivers = rng.integers(0, n * n, size=(6, 3))
    slivers[:2, 2] = slivers[:2, 1]  # flat: two corners the same
    triangles = np.vstack([triangles, slivers])
    points = np.vstack([
        vertices[rng.integers(0, n * n, 100)] + rng.normal(0, 0.03, (100, 3)),
        rng.uniform(-3, 4, (60, 3)),  # far away
        vertices[:20],  # on the mesh
    ])  # fmt: skip
    np.testing.assert_allclose(
        mesh_distances(vertices, triangles, points),
        _brute_force(vertices, triangles, points),
        rtol=0,
        atol=1e-12,
    )
