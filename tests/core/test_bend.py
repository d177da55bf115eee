"""Bent leaves: the paper's steps on the flat blade, the mesh bent (issue 21, findings 1-2)."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.core.bend import Pose
from leafstudio.core.bent_mesh import sag_splits
from leafstudio.core.correct import BAND_TOLERANCE
from leafstudio.core.cuts import carried, carried_data, cut_levels
from leafstudio.core.evaluate import mesh_facts
from leafstudio.core.hinge_fold import BAND
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
    which lie on the midrib, and the halvings of edges the bend sags (beside the crease, in the
    band where the halves' turn sets in, core/hinge_fold.py)."""
    leaf = Form("elliptic", fold=40, curl=0.3).leaf()
    pose = leaf.bend
    assert isinstance(pose, Pose)
    bent = ls.reconstruct(leaf, ls.Params(grid=64)).triangle_mesh
    blade = ls.Leaf(pose.flatten(leaf.boundary), [pose.flatten(v) for v in leaf.veins])
    flat = ls.reconstruct(blade, ls.Params(grid=64)).triangle_mesh
    n = len(flat.points)
    back = pose.flatten(bent.points[:n])
    assert np.allclose(back[:, :2], flat.points[:, :2], atol=1e-12)
    # the heights within the veins' tolerance: where the bend stretches a distance off the
    # blade the bent run pins its veins closer (correct.py; 2e-9 here)
    assert np.abs(back[:, 2] - flat.points[:, 2]).max() <= 2 * BAND_TOLERANCE
    added = np.abs(pose.flatten(bent.points[n:])[:, 1])
    assert len(added) and (added < 1e-12).sum() > 20 and added.max() <= BAND
    assert len(bent.regular_faces) > len(flat.regular_faces)


def test_a_cut_keeps_the_area_and_leaves_no_triangle_across_the_line():
    mesh = _grid_mesh(5, 0.45)
    points = mesh.points
    faces, plan = cut_levels(mesh.regular_faces, points[:, 1], np.array([0.01]))
    cut = TriangleMesh(carried(points, plan), faces, carried_data(mesh.point_data, plan))
    corners = cut.points[cut.regular_faces]
    area = 0.5 * np.linalg.norm(
        np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
    )
    assert area.sum() == pytest.approx(1.0 * 0.95)
    side = np.sign(np.round(corners[:, :, 1] - 0.01, 12))
    assert not np.any((side.max(axis=1) > 0) & (side.min(axis=1) < 0))
    assert np.allclose(cut.point_data["height"], cut.points[:, 0])  # interpolated linearly


def test_cuts_along_many_levels_leave_no_triangle_across_any_and_no_crack():
    """Levels closer than a triangle is wide (a tight roll's lines): every piece lies between two
    levels, the area is kept and every edge inside the sheet has two triangles (no point cut twice,
    which would open a crack)."""
    mesh = _grid_mesh(7, 0.5, jitter=0.03)
    points = mesh.points
    levels = np.concatenate([np.linspace(-0.4, 0.4, 23), [points[10, 1]]])  # one through a vertex
    cut_faces, plan = cut_levels(mesh.regular_faces, points[:, 1], levels)
    cut = TriangleMesh(carried(points, plan), cut_faces)
    assert _area(cut) == pytest.approx(_area(mesh))
    corners = cut.points[cut_faces]
    for level in levels:
        side = np.sign(np.round(corners[:, :, 1] - level, 12))
        assert not np.any((side.max(axis=1) > 0) & (side.min(axis=1) < 0))
    count, count_before = _edge_uses(cut_faces), _edge_uses(mesh.regular_faces)
    # the outline's edges are cut into pieces, the inside ones all shared by two triangles
    assert (count <= 2).all() and (count == 1).sum() >= (count_before == 1).sum()
    assert np.unique(np.round(cut.points, 12), axis=0).shape[0] == len(cut.points)


def _wrapped(points: np.ndarray, radius: float = 0.3) -> np.ndarray:
    """(n, 3) flat points wrapped about the x axis on a cylinder of `radius`."""
    angle = points[:, 1] / radius
    return np.column_stack([points[:, 0], radius * np.sin(angle), radius * (1 - np.cos(angle))])


def _gaps(points: np.ndarray, faces: np.ndarray, carry) -> np.ndarray:
    """How far `carry` takes each edge's midpoint from its bent chord."""
    edges = np.unique(np.sort(np.vstack([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]),
                              axis=1), axis=0)  # fmt: skip
    a, b = points[edges[:, 0]], points[edges[:, 1]]
    return np.linalg.norm(carry((a + b) / 2) - (carry(a) + carry(b)) / 2, axis=1)


def test_edges_a_bend_sags_are_halved_until_their_chords_lie_on_it_and_the_mesh_stays_whole():
    """A grid wrapped on a tight cylinder: its chords sag 5e-3 off it; halved three times they
    lie within the tolerance, the flat area and the first points are kept, every edge inside
    the sheet has two triangles (no hanging point, no crack), the winding is kept (no edge twice
    the same way round) and the point arrays are carried."""
    mesh = _grid_mesh(11, 0.5, jitter=0.01)
    points, faces = mesh.points, mesh.regular_faces
    assert _gaps(points, faces, _wrapped).max() > 4e-3
    split, plan, _ = sag_splits(points, faces, _wrapped, 1e-4)
    cut = TriangleMesh(carried(points, plan), split, carried_data(mesh.point_data, plan))
    assert _gaps(cut.points, split, _wrapped).max() <= 1e-4
    assert len(cut.points) > 4 * len(points) and np.array_equal(cut.points[: len(points)], points)
    assert _area(cut) == pytest.approx(_area(mesh))
    facts = mesh_facts(cut)
    assert facts["boundary_loops"] == 1 and facts["non_manifold_edges"] == 0
    assert _border_length(cut.points, split) == pytest.approx(_border_length(points, faces))
    directed = np.vstack([split[:, [0, 1]], split[:, [1, 2]], split[:, [2, 0]]])
    assert len(np.unique(directed, axis=0)) == len(directed)
    assert np.allclose(cut.point_data["height"], cut.points[:, 0])


def test_a_bend_that_sags_no_edge_leaves_the_mesh_as_it_is():
    mesh = _grid_mesh(6, 0.5)
    sheared = lambda p: p + p[:, [1]] * [0.0, 0.0, 2.0]  # noqa: E731 (linear: no sag)
    faces, plan, _ = sag_splits(mesh.points, mesh.regular_faces, sheared, 1e-9)
    assert np.array_equal(faces, mesh.regular_faces) and plan == []


def _border_length(points: np.ndarray, faces: np.ndarray) -> float:
    """The flat length of the edges that one triangle holds: a point hanging on an edge inside
    the sheet would add its two halves to it."""
    edges = np.sort(np.vstack([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    edges, count = np.unique(edges, axis=0, return_counts=True)
    lone = edges[count == 1]
    return float(np.linalg.norm(points[lone[:, 0]] - points[lone[:, 1]], axis=1).sum())


def _area(mesh: TriangleMesh) -> float:
    c = mesh.points[mesh.regular_faces]
    return float(0.5 * np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1).sum())


def _edge_uses(faces: np.ndarray) -> np.ndarray:
    """How many faces hold each edge."""
    edges = np.sort(np.vstack([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    return np.unique(edges, axis=0, return_counts=True)[1]


def _grid_mesh(n: int, top: float, jitter: float = 0.0) -> TriangleMesh:
    """n x n points over [0, 1] x [-0.5, top], moved at random by up to `jitter`, in triangles,
    with a "height" array of x."""
    x, y = np.meshgrid(np.linspace(0, 1, n), np.linspace(-0.5, top, n))
    points = np.column_stack([x.ravel(), y.ravel(), np.zeros(n * n)])
    points[:, :2] += np.random.default_rng(3).uniform(-jitter, jitter, (n * n, 2))
    a = (n * np.arange(n - 1)[:, None] + np.arange(n - 1)).ravel()
    faces = np.vstack(
        [np.column_stack([a, a + 1, a + n + 1]), np.column_stack([a, a + n + 1, a + n])]
    )
    return TriangleMesh(points, faces, {"height": points[:, 0].copy()})


@pytest.mark.parametrize(
    "terms",
    [
        {"fold": 60.0},
        {"roll": 0.5},
        {"curl": -0.6},
        {"twist": 0.5},
        {"fold": -75.0, "roll": 1.0},
        {"fold": 45.0, "curl": 0.5, "roll": 0.5, "twist": 0.5},
    ],
    ids=str,
)
@pytest.mark.parametrize("relief", [True, False], ids=["relief", "sheet"])
def test_a_poses_compiled_carry_bends_points_as_its_apply(terms, relief):
    """Pose.carry (pose_jet.py's kernel, how a bent run carries its mesh) is `apply` to
    round-off: points over the blade, on and beside the crease's band and at the sheet's height,
    for a pose about a relief and one about the sheet z = 0."""
    blade = Form("ovate").leaf()
    pose = Form("ovate", **terms).leaf(blade).bend
    pose = pose if relief else replace(pose, relief=None)
    rng = np.random.default_rng(5)
    x = rng.uniform(0.0, 1.0, 4000) * np.ptp(blade.boundary[:, 0]) + blade.boundary[:, 0].min()
    y = np.concatenate([rng.uniform(-0.3, 0.3, 3000), rng.uniform(-BAND, BAND, 990), np.zeros(10)])
    z = np.where(rng.random(4000) < 0.2, 0.0, rng.uniform(-0.05, 0.05, 4000))
    points = np.column_stack([x, y, z])
    expected = pose.apply(points)
    assert np.abs(pose.carry(points) - expected).max() <= 1e-14 * np.abs(expected).max()


def test_a_bent_result_keeps_its_flat_blade_for_its_metrics():
    """Result.blade: the flat blade a bent run measures its midrib on (blade_midrib flattened
    the bent leaf's veins again for the metrics), the same midrib; a flat run has none."""
    from leafstudio.core.evaluate import blade_midrib

    leaf = Form("ovate", fold=45.0, curl=0.5, roll=0.5, twist=0.5).leaf()
    result = ls.reconstruct(leaf, ls.Params(k=3, grid=32))
    assert result.blade is not None and result.blade.bend is None
    np.testing.assert_array_equal(blade_midrib(result.blade), blade_midrib(leaf))
    assert ls.reconstruct(Form("ovate").leaf(), ls.Params(k=3, grid=32)).blade is None
