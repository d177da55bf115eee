"""Bent leaves: the paper's steps on the flat blade, the mesh bent (issue 21, findings 1-2)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.core.bend import Pose, cut_along
from leafstudio.core.trianglemesh import TriangleMesh
from leafstudio.forms.make import Form, seen_on_edge

POSES = [  # the table, and the form the CLI refused
    ("ovate", {"fold": 60}),
    ("ovate", {"fold": 75}),
    ("linear", {"curl": 0.6}),
    ("ovate", {"fold": -75, "curl": 1.0}),
    ("lanceolate", {"aspect": 30, "curl": 1.0, "fold": 60}),
]


@pytest.mark.parametrize(("shape", "pose"), POSES)
def test_a_posed_form_is_reconstructed_as_well_as_a_flat_one(shape, pose):
    """Today ovate fold 75 is 0.29 of the length off its veins and 0.32 off its boundary, linear
    curl 0.6 warns that it stands on edge, and lanceolate aspect 30 curl 1 fold 60 is refused."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no side-on warning
        leaf = Form(shape, **pose).leaf()
        result = ls.reconstruct(leaf, ls.Params(k=3, grid=128))
    assert not seen_on_edge(leaf)
    assert result.metrics["veins"]["max"] <= 2e-3 * result.length
    assert result.metrics["boundary"]["max"] <= 1e-9 * result.length


def test_a_flat_form_has_no_bend_and_runs_as_before():
    leaf = Form("ovate").leaf()
    assert leaf.bend is None
    same = ls.reconstruct(ls.Leaf(leaf.boundary, leaf.veins), ls.Params(grid=64))
    result = ls.reconstruct(leaf, ls.Params(grid=64))
    assert np.array_equal(result.triangle_mesh.points, same.triangle_mesh.points)


def test_the_bent_mesh_is_the_flat_blades_mesh_bent():
    """Reconstructing the posed form is reconstructing its flat blade and posing the mesh, with
    the fold's crease cut into it: the flat run's vertices come first, then those of the cut,
    which lie on the midrib."""
    leaf = Form("elliptic", fold=40, curl=0.3).leaf()
    pose = leaf.bend
    assert isinstance(pose, Pose)
    bent = ls.reconstruct(leaf, ls.Params(grid=64)).triangle_mesh
    blade = ls.Leaf(pose.flatten(leaf.boundary), [pose.flatten(v) for v in leaf.veins])
    flat = ls.reconstruct(blade, ls.Params(grid=64)).triangle_mesh
    n = len(flat.points)
    assert np.allclose(pose.flatten(bent.points[:n]), flat.points, atol=1e-12)
    assert len(bent.points) > n and np.allclose(bent.points[n:, 1], 0, atol=1e-12)
    assert len(bent.regular_faces) > len(flat.regular_faces)


def test_a_cut_keeps_the_area_and_leaves_no_triangle_across_the_line():
    x, y = np.meshgrid(np.linspace(0, 1, 5), np.linspace(-0.5, 0.45, 5))
    points = np.column_stack([x.ravel(), y.ravel(), np.zeros(25)])
    faces = []
    for i in range(4):
        for j in range(4):
            a = 5 * i + j
            faces += [(a, a + 1, a + 6), (a, a + 6, a + 5)]
    mesh = TriangleMesh(points, np.array(faces), {"height": points[:, 0].copy()})
    cut = cut_along(mesh, points[:, 1] - 0.01)
    corners = cut.points[cut.regular_faces]
    area = 0.5 * np.linalg.norm(
        np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
    )
    assert area.sum() == pytest.approx(1.0 * 0.95)
    side = np.sign(np.round(corners[:, :, 1] - 0.01, 12))
    assert not np.any((side.max(axis=1) > 0) & (side.min(axis=1) < 0))
    assert np.allclose(cut.point_data["height"], cut.points[:, 0])  # interpolated linearly
