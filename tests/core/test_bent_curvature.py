"""A bent leaf's curvature arrays are the bent surface's (core/bent_curvature.py, issue 21): they
were the flat blade's, so a rolled grass blade was coloured as if flat and a curled scan's
curvature summary ignored its curl."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.core.bend import Pose, flat_leaf
from leafstudio.core.bent_curvature import affine_jet, bent_curvatures
from leafstudio.core.placed import PlacedPose
from leafstudio.core.plane import Frame
from leafstudio.core.prepare.units import Units
from leafstudio.core.trianglemesh import CURVATURE_ARRAYS, TriangleMesh
from leafstudio.forms.make import Form

WORLD = Frame(np.zeros(3), np.eye(3)[0], np.eye(3)[1], np.eye(3)[2])


@pytest.fixture(scope="module")
def flat_mesh():
    """The flat ovate's unit-size mesh (with its surface's jet) and its plane."""
    result = ls.reconstruct(Form("ovate").leaf(), ls.Params(k=3, grid=64))
    unit = result.unit or result
    return unit.triangle_mesh, unit.frame


def _curvatures(bend, mesh: TriangleMesh, frame: Frame, analytic: bool) -> dict:
    flat, jet = mesh.points, mesh.jet
    carry_jet = bend.carry_jet if analytic else None
    return bent_curvatures(bend.apply, carry_jet, frame, flat, bend.apply(flat), jet)


class Identity:
    def apply(self, points):
        return np.array(points, dtype=float)

    def carry_jet(self, jet):
        return jet


@pytest.mark.parametrize("analytic", [True, False])
def test_no_bend_gives_the_flat_surfaces_curvatures(flat_mesh, analytic):
    mesh, frame = flat_mesh
    got = _curvatures(Identity(), mesh, frame, analytic)
    for name in CURVATURE_ARRAYS:
        want = mesh.point_data[name]
        assert np.abs(got[name] - want).max() < 1e-6 * np.abs(want).max(), name


@pytest.mark.parametrize(
    "pose",
    [
        Pose(fold=60.0),
        Pose(roll=4.0),
        Pose(twist=1.5),
        Pose(curl=0.6),
        Pose(fold=-45.0, curl=0.5, roll=3.0, twist=0.8),
    ],
)
def test_a_pose_carries_a_jet_as_its_stencils_differences_do(flat_mesh, pose):
    """The closed form (Pose.carry_jet) against central differences of the carried points, away
    from a fold's crease and from height 0, where a roll's radius is C¹ only (_rolled_radius),
    and from the height a curl bends about (0 with no relief, as the roll, fold and twist leave
    it: Pose._level), where the curl's is: the stencil would straddle them. (A vertex 2e-5 from
    the curl's height made central differences' k2 off by 4.3e-3 of its largest, the rest of
    the blade's 6.5e-5: pose 4, with c's own bending, core/bending.py.)"""
    mesh, frame = flat_mesh
    placed = PlacedPose(pose, frame)  # the blade's frame is the run's plane here
    exact = _curvatures(placed, mesh, frame, analytic=True)
    differenced = _curvatures(placed, mesh, frame, analytic=False)
    xy, z = frame.to_plane(mesh.points)
    clear = (np.abs(xy[:, 1]) > 1e-3) & (np.abs(z) > 1e-3)
    if pose.curl != 0:
        uncurled = PlacedPose(replace(pose, curl=0.0), frame).apply(mesh.points)
        clear &= np.abs(frame.to_plane(uncurled)[1]) > 1e-3
    assert np.count_nonzero(clear) > 0.7 * len(z)
    for name in CURVATURE_ARRAYS:
        scale = np.abs(exact[name]).max()
        assert np.abs(exact[name] - differenced[name])[clear].max() < 1e-4 * scale, name


def _plane_points(n: int = 50) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(3)
    points = np.column_stack([rng.uniform(0.05, 0.6, n), rng.uniform(-0.1, 0.1, n), np.zeros(n)])
    return points, np.zeros((n, 5))


def test_a_roll_a_curl_and_a_twist_have_a_cylinders_and_a_helicoids_curvatures():
    points, jet = _plane_points()
    mesh = TriangleMesh(points, np.zeros((0, 3), int), jet=jet)
    for analytic in (True, False):
        rolled = _curvatures(Pose(roll=4.0), mesh, WORLD, analytic)
        # a cylinder of radius 1/4, the margins up: concave toward +z
        np.testing.assert_allclose(rolled["k1"], 4.0, rtol=1e-5)
        np.testing.assert_allclose(rolled["mean_curvature"], 2.0, rtol=1e-5)
        assert np.abs(rolled["gaussian_curvature"]).max() < 1e-4
        curled = _curvatures(Pose(curl=0.3), mesh, WORLD, analytic)  # the midrib's circle: 0.6
        np.testing.assert_allclose(curled["k1"], 0.6, rtol=1e-5)
        twisted = _curvatures(Pose(twist=1.5), mesh, WORLD, analytic)
        y = points[:, 1]
        helicoid = -(1.5**2) / (1 + (1.5 * y) ** 2) ** 2
        np.testing.assert_allclose(twisted["gaussian_curvature"], helicoid, rtol=1e-4)
        assert np.abs(twisted["mean_curvature"]).max() < 1e-4  # a minimal surface


def test_a_rolled_forms_mesh_is_coloured_by_its_roll():
    """Form("ovate", roll=0.5) rolls its blade to a radius of about 0.2 of its length: the
    mesh's mean curvature rose by about half the roll's curvature over the flat form's."""
    leaf = Form("ovate", roll=0.5).leaf()
    params = ls.Params(k=3, grid=64)
    rolled = ls.reconstruct(leaf, params).metrics["curvature"]["mean_curvature"]["mean"]
    flat = ls.reconstruct(Form("ovate").leaf(), params).metrics["curvature"]
    rise = rolled - flat["mean_curvature"]["mean"]
    assert abs(rise - leaf.bend.roll / 2) < 0.15 * leaf.bend.roll


def test_a_folds_crease_has_the_curvature_of_its_sides():
    """A fold's crease (its vertices on the midrib) takes its + side's curvature: no spike where
    both sides' triangles meet, nor in the band beside it where the halves' turn sets in
    (core/hinge_fold.py): both within 1.1 times the largest of the rest of the blade or of the
    same band on the flat blade, the surface's own there. (A domed blade folded about its
    arched midrib is itself a little more curved than flat: ovate folded 60°, k1 4.1 at the
    margin against 3.4. The surface itself bends most near the midrib's apex end: k2 5.91 in
    the flat blade's band, 5.81 folded, against 3.16 in the rest of either, with c's own
    bending, core/bending.py; without it a crease the correction made where a side vein
    leaves the midrib, 5.12, stood for the rest.)"""
    params = ls.Params(k=3, grid=64)
    leaf = Form("ovate", fold=60.0).leaf()
    folded = ls.reconstruct(leaf, params).triangle_mesh
    flat = ls.reconstruct(flat_leaf(leaf), params).triangle_mesh  # in the blade's coordinates
    across = np.abs(leaf.bend.flatten(np.asarray(folded.points))[:, 1])
    near = across < 0.05  # the crease and its band (hinge_fold.BAND of the length, 1)
    flat_near = np.abs(np.asarray(flat.points)[:, 1]) < 0.05
    assert (across < 1e-9).sum() > 50 and (~near).sum() > 1000 and flat_near.sum() > 100
    for name in CURVATURE_ARRAYS:
        values, own = np.abs(folded.point_data[name]), np.abs(flat.point_data[name])
        assert values[near].max() <= 1.1 * max(values[~near].max(), own[flat_near].max())


@pytest.mark.parametrize("roll", [4.0, -4.0])
def test_a_margin_at_height_0_takes_the_reliefs_side_of_a_roll(flat_mesh, roll):
    """The rolled radius is C¹ only at height 0, where every margin vertex lies: its curvature
    is the limit from the relief's side (heights just above 0) for either sign of roll; the
    branch was round-off's (a margin's curvature changed by a tenth with the leaf's size)."""
    mesh, frame = flat_mesh
    placed = PlacedPose(Pose(roll=roll), frame)
    on = frame.to_plane(mesh.points)[1] == 0
    assert on.sum() > 100
    at = _curvatures(placed, mesh, frame, analytic=True)["mean_curvature"]
    lifted = TriangleMesh(mesh.points + 1e-9 * frame.normal, mesh.regular_faces, jet=mesh.jet)
    above = _curvatures(placed, lifted, frame, analytic=True)["mean_curvature"]
    assert np.abs(at - above)[on].max() < 1e-6 * np.abs(at).max()


def test_a_pose_at_1e300_has_its_unit_sizes_curvatures():
    """A leaf 1e300 across bends in its own units: k² of a roll of 1e-300 underflowed to 0."""
    points, jet = _plane_points(5)
    points[:, 2] = 0.01
    mesh = TriangleMesh(points, np.zeros((0, 3), int), jet=jet)
    units = Units(np.zeros(3), 1e300)
    for pose, k1 in ((Pose(roll=2.0), 2.0), (Pose(curl=0.3), 0.6)):
        unit = _curvatures(pose, mesh, WORLD, analytic=True)["k1"]
        huge = Pose(roll=pose.roll / 1e300, curl=pose.curl / 1e300)

        def carry_jet(flat_jet, huge=huge):
            return affine_jet(units.to_unit, huge.carry_jet(affine_jet(units.to_world, flat_jet)))

        got = bent_curvatures(pose.apply, carry_jet, WORLD, points, pose.apply(points), jet)["k1"]
        np.testing.assert_allclose(got, unit, rtol=1e-9)
        assert np.abs(unit - k1).max() < 0.05 * k1  # the relief 0.01 up: a little off the sheet's


def test_the_outline_points_a_rolls_sag_halvings_add_take_the_margins_limits():
    """The points bent_mesh.sag_splits adds on the outline's edges were put on the surface
    (bent_result._onto_surface) with its derivatives from wherever g's sign put them, not the
    limits from inside that the outline's own vertices take: on a linear blade rolled into a
    tube their k1 stood 0.50 off the mean of their outline neighbours' (median; 0.049 with the
    limits), their k2 0.58 where the neighbours' is about 1."""
    from leafstudio.assets.solid import boundary_edges

    params = ls.Params(k=3, grid=64)
    leaf = Form("linear", roll=1.0).leaf()
    result = ls.reconstruct(leaf, params)
    mesh = result.triangle_mesh
    first = len(ls.reconstruct(flat_leaf(leaf), params).triangle_mesh.points)  # a roll cuts none
    outline = result.on_outline()
    halved = np.flatnonzero(outline[first:]) + first
    assert len(halved) > 20
    edges = boundary_edges(mesh.regular_faces)
    edges = edges[outline[edges[:, 0]] & outline[edges[:, 1]]]
    k1 = np.asarray(mesh.point_data["k1"])
    around = np.zeros(len(k1))
    count = np.zeros(len(k1))
    np.add.at(around, edges.ravel(), k1[edges[:, ::-1]].ravel())
    np.add.at(count, edges.ravel(), 1.0)
    off = np.abs(k1[halved] - around[halved] / count[halved])
    assert np.median(off) < 0.002 * np.median(np.abs(k1[halved]))  # 0.0057 without the limits
