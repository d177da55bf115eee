"""A posed leaf keeps its size (core/pose_relief.py, core/hinge_fold.py): a pose bent the blade's
sheet, the margin's plane, and carried the relief on it, so a domed blade was drawn in wherever
it bent. bench_bent.py --size, an ovate form's mesh area posed over flat: fold 30° 0.90, 60°
0.82, 75° 0.79; curl 0.5 0.97, 1 0.94; roll 0.3 0.91, 0.5 0.86. The app's drawn leaf folded
45° and curled 0.4 measured 0.248 against 0.319 flat."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.core import pose_relief
from leafstudio.core.bend import Pose
from leafstudio.core.bent_curvature import bent_curvatures
from leafstudio.core.evaluate import surface_area
from leafstudio.core.hinge_fold import BAND, HingeFold
from leafstudio.core.placed import PlacedPose
from leafstudio.core.pose_jet import HINGE, posed_jet
from leafstudio.core.pose_relief import Relief, margin_relief, relief_of
from leafstudio.core.trianglemesh import CURVATURE_ARRAYS
from leafstudio.core.unfold_hinge import hinge_relief
from leafstudio.errors import LeafError
from leafstudio.forms.make import Form
from tests.core.test_bent_curvature import WORLD


def _area(result: ls.Result) -> float:
    mesh = result.triangle_mesh
    return float(surface_area(np.asarray(mesh.points), mesh.regular_faces))


@pytest.fixture(scope="module")
def flat_ovate() -> tuple[ls.Leaf, float]:
    blade = Form("ovate").leaf()
    return blade, _area(ls.reconstruct(blade, ls.Params(k=3, grid=128)))


@pytest.mark.parametrize(
    "pose",
    [{"fold": 30}, {"fold": 60}, {"fold": 75}, {"fold": -60}, {"roll": 0.3}, {"roll": 0.5}],
    ids=str,
)
def test_a_posed_form_keeps_its_flat_blades_area(flat_ovate, pose):
    blade, flat = flat_ovate
    leaf = Form("ovate", **pose).leaf(blade)
    posed = _area(ls.reconstruct(leaf, ls.Params(k=3, grid=128)))
    assert posed == pytest.approx(flat, rel=0.012)


@pytest.mark.parametrize(
    "pose", [{"curl": 1.0}, {"fold": 45.0, "curl": 0.5}, {"fold": 75.0, "curl": 1.0}], ids=str
)
def test_a_curl_keeps_the_midribs_length(pose):
    """The curl bends the blade about its midrib's mean height as the fold leaves it: about
    the blade's mean height a folded blade's midrib was stretched 1.25 times (fold 75, curl 1),
    about the margin's plane shrunk to 0.92."""
    blade = Form("ovate").leaf()
    leaf = Form("ovate", **pose).leaf(blade)

    def length(curve: np.ndarray) -> float:
        return float(np.linalg.norm(np.diff(curve, axis=0), axis=1).sum())

    assert length(leaf.veins[0]) == pytest.approx(length(blade.veins[0]), rel=0.005)


def test_a_fold_turns_each_half_rigidly_about_the_midrib_as_it_stands():
    """Past the crease's band a point keeps its distance from the hinge, and the blade comes
    back exactly; the midrib's own points stay where they stood (they are the hinge)."""
    blade = Form("elliptic").leaf()
    leaf = Form("elliptic", fold=50.0).leaf(blade)
    pose = leaf.bend
    midrib = blade.veins[0]
    np.testing.assert_allclose(pose.apply(midrib), midrib, atol=1e-12)
    for flat, bent in zip(blade.veins, leaf.veins, strict=True):
        np.testing.assert_allclose(pose.flatten(bent), flat, atol=1e-12)


def test_the_hinge_fold_is_undone_in_its_band_and_past_it():
    fold = HingeFold(np.cos(1.1), np.sin(1.1), 0.8, 0.03)
    rng = np.random.default_rng(5)
    y = np.concatenate([rng.uniform(-0.03, 0.03, 200), rng.uniform(-0.5, 0.5, 200), [0.0]])
    off = np.concatenate([rng.uniform(-1e-3, 1e-3, 200), rng.uniform(-0.1, 0.02, 200), [4e-4]])
    back = fold.unfolded(*fold.folded(y, off))
    np.testing.assert_allclose(back[0], y, atol=1e-12)
    np.testing.assert_allclose(back[1], off, atol=1e-12)
    assert back[0][-1] == 0.0  # a point on the crease comes back on it, not 1e-20 beside it


@pytest.mark.parametrize(
    "terms",
    [{"fold": 60.0}, {"roll": 0.5}, {"curl": 0.6}, {"fold": -45.0, "curl": 0.5, "roll": 0.3}],
    ids=str,
)
def test_a_pose_about_its_relief_carries_a_jet_as_its_differences_do(terms):
    """Pose.carry_jet in closed form (the hinge's and the sheet's derivatives along x) against
    central differences of the carried points, off the crease's band (its mixed second
    derivative, 42 at a fold of 60°, leaves the stencil's one-sided ∂uv a few 1e-4 off; the
    band's own derivatives are checked in the next test) and off the margin's height 0, the
    roll's sheet and a lone curl's level (the radius is C¹ there)."""
    blade = Form("ovate").leaf()
    pose = Form("ovate", **terms).leaf(blade).bend
    assert pose.relief is not None
    result = ls.reconstruct(blade, ls.Params(k=3, grid=64))
    mesh, frame = result.unit.triangle_mesh, result.frame  # the jet is the unit run's
    assert result.units.scale == 1.0  # only moved: the jet is the same in the form's frame
    placed = PlacedPose(pose, WORLD)
    flat = result.units.to_world(np.asarray(mesh.points))

    def curvatures(analytic: bool) -> dict:
        carry_jet = placed.carry_jet if analytic else None
        return bent_curvatures(placed.apply, carry_jet, frame, flat, placed.apply(flat), mesh.jet)

    exact, differenced = curvatures(True), curvatures(False)
    sheet = pose.relief.sheet(flat[:, 0])[0] if pose.roll else 0.0
    clear = (np.abs(flat[:, 1]) > BAND) & (np.abs(flat[:, 2]) > 1e-3)
    clear &= np.abs(flat[:, 2] - sheet) > 1e-3
    if pose.curl and not (pose.fold or pose.roll):  # the curl's radius is C¹ at its level
        clear &= np.abs(flat[:, 2] - pose._level()) > 1e-3
    assert np.count_nonzero(clear) > 0.5 * len(flat)
    for name in CURVATURE_ARRAYS:
        scale = np.abs(exact[name]).max()
        assert np.abs(exact[name] - differenced[name])[clear].max() < 1e-4 * scale, name


def test_the_hinge_folds_derivatives_in_its_band_are_its_differences():
    """pose_jet's fold about the hinge (a jet along y and o, the height over the hinge, as it
    carries a pose's) against HingeFold.folded's differences, in the band and past it."""
    fold = HingeFold(np.cos(1.047), np.sin(1.047), 0.9, 0.03)
    y = np.array([-0.029, -0.01, 0.002, 0.005, 0.02, 0.1])
    off = np.array([2e-4, -1e-3, 5e-4, 1e-3, -3e-3, -0.05])
    n = len(y)
    d = np.zeros((n, 5, 3))
    d[:, 0, 1] = d[:, 1, 2] = 1.0  # ∂u along y, ∂v along o
    flat = (np.array([-1.0, 1.0]), np.zeros((4, 1)))  # the hinge at height 0
    points, jet = posed_jet(
        np.column_stack([np.zeros(n), y, off]), d, 0.0, *flat, HINGE, fold.c, fold.s, 0.0,
        fold.share, fold.band, *flat, 0.0, 0.0, 0.0, 1e-12, np.zeros(3), 1.0,
    )  # fmt: skip
    e = 1e-6

    def at(dy: float, do: float) -> np.ndarray:
        return np.array(fold.folded(y + dy, off + do)).T  # (n, 2)

    np.testing.assert_allclose(points[:, 1:], at(0, 0), rtol=1e-15)
    np.testing.assert_allclose(jet[:, 0, 1:], (at(e, 0) - at(-e, 0)) / (2 * e), atol=1e-7)
    np.testing.assert_allclose(jet[:, 1, 1:], (at(0, e) - at(0, -e)) / (2 * e), atol=1e-7)
    yy = (at(e, 0) - 2 * at(0, 0) + at(-e, 0)) / e**2
    yo = (at(e, e) - at(e, -e) - at(-e, e) + at(-e, -e)) / (4 * e * e)
    np.testing.assert_allclose(jet[:, 2, 1:], yy, atol=1e-3)
    np.testing.assert_allclose(jet[:, 3, 1:], yo, atol=1e-3)


def test_a_relief_reads_back_from_its_project_entry_and_a_bad_one_is_one_error(tmp_path):
    leaf = Form("ovate", fold=40.0, roll=0.2).leaf()
    relief = leaf.bend.relief
    again = Relief.from_entry(json.loads(json.dumps(relief.entry())))
    assert again.key() == relief.key()
    path = tmp_path / "posed.leaf.json"
    ls.save_leaf(leaf, path)
    assert ls.load_leaf(path).bend.key() == leaf.bend.key()
    data = json.loads(path.read_text())
    data["bend"]["relief"]["knots"] = data["bend"]["relief"]["knots"][::-1]  # not increasing
    path.write_text(json.dumps(data))
    with pytest.raises(LeafError, match='"relief"'):
        ls.load_leaf(path)


def test_a_blade_without_veins_turns_about_its_sections_means():
    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    boundary = np.column_stack([0.5 + 0.5 * np.cos(t), 0.2 * np.sin(t), np.zeros_like(t)])
    relief = relief_of(boundary, [])
    assert relief is not None and relief.along == relief.knots
    assert relief.half_width == pytest.approx(0.2, rel=1e-3)
    assert relief_of(boundary[:, :][[0, 0, 0]], []) is None  # no extent: none


@pytest.mark.parametrize("key", ["along", "knots"])
def test_a_relief_whose_numbers_are_a_string_is_refused(key):
    """A string's characters read as digits: "0123456789" was the knots 0 to 9."""
    entry = Form("ovate", fold=40.0).leaf().bend.relief.entry()
    entry[key] = "0123456789"
    entry["midrib" if key == "along" else "mean"] = "0123456789"
    with pytest.raises(ValueError):
        Relief.from_entry(entry)


def test_a_blades_relief_is_made_once_and_a_changed_one_anew():
    """relief_of keeps the last blades' reliefs (the bend sliders ask at every step); a relief
    copied with other means bends about them, not about the first one's cached splines."""
    blade = Form("ovate").blade()
    first = relief_of(blade.boundary, blade.veins)
    assert relief_of(blade.boundary.copy(), [v.copy() for v in blade.veins]) is first
    raised = blade.veins[0].copy()
    raised[:, 2] += 0.01
    assert relief_of(blade.boundary, [raised, *blade.veins[1:]]) is not first
    x = np.array([0.5])
    first.sheet_height(x)  # its spline made and kept
    lifted = replace(first, mean=tuple(m + 0.01 for m in first.mean))
    assert lifted.sheet_height(x)[0] == pytest.approx(first.sheet_height(x)[0] + 0.01)


def test_a_blade_far_from_unit_size_has_its_relief_scaled():
    """Fuzzing finding (hunt26): a leaf 1e90 across (the app draws and measures up to 1e150)
    opened, and its bend slider raised a QhullError out of relief_of (Qhull's Delaunay of the
    curves overflowed past 1e77). The relief is now the unit blade's, scaled."""
    blade = Form("ovate", wave=0.1).blade()
    unit = relief_of(blade.boundary, blade.veins)
    for scale in (1e90, 1e-90):
        far = relief_of(blade.boundary * scale, [v * scale for v in blade.veins])
        np.testing.assert_allclose(np.array(far.mean) / scale, unit.mean, rtol=1e-9, atol=1e-15)
        assert far.rise == pytest.approx(unit.rise) and far.fall == pytest.approx(unit.fall)


@pytest.mark.parametrize("fold", [30.0, 60.0, 75.0])
def test_a_blade_with_lobes_behind_its_base_keeps_its_area_folded(fold):
    """hunt27: the hinge's spline carried its end pieces' cubics on past the midrib, so under a
    sagittate form's lobes (behind the base) it fell to 0.28 of the length below the blade, the
    fold's turn was eased for the steep rise that made, and the folded blade kept 0.97, 0.92
    and 0.90 of its area. The profiles are linear past their ends."""
    blade = Form("sagittate").leaf()
    flat = _area(ls.reconstruct(blade, ls.Params(k=3, grid=128)))
    posed = _area(
        ls.reconstruct(Form("sagittate", fold=fold).leaf(blade), ls.Params(k=3, grid=128))
    )
    assert posed == pytest.approx(flat, rel=0.005)
    relief = relief_of(blade.boundary, blade.veins)
    x = np.linspace(blade.boundary[:, 0].min(), relief.along[0], 5)
    _, slope, bend = relief.hinge(x)
    np.testing.assert_allclose(bend, 0.0, atol=1e-12)
    np.testing.assert_allclose(slope, slope[-1], atol=1e-12)


def test_a_relief_saved_before_its_ends_were_linear_bends_as_it_did(tmp_path):
    """A project's relief without "ends" had its curves bent with the cubic ends: it is read
    with them, so they flatten back as they were bent; a new one is saved with "ends":
    "linear"."""
    from scipy.interpolate import CubicSpline

    relief = Form("sagittate", fold=60.0).leaf().bend.relief
    entry = relief.entry()
    assert entry["ends"] == "linear"
    del entry["ends"]
    old = Relief.from_entry(entry)
    x = np.linspace(-0.3, 1.0, 50)
    cubic = CubicSpline(old.along, old.midrib, bc_type="natural")(x)
    np.testing.assert_array_equal(old.hinge_height(x), cubic)
    assert old.key() != relief.key()


def test_a_margin_relief_hinges_on_the_midrib_over_the_margins_plane():
    """A pose fitted to curves in 3D (core/unfold.py) folds about the flat midrib's heights,
    its sheet the margin's plane; it says so (`on_margin`, the app's sliders keep it), a
    blade's own relief does not, and a midrib that doubles back has none. Scaled (the fit is at
    unit size), its hinge is the same at the same place."""
    blade = Form("ovate").blade()
    relief = margin_relief(blade.boundary, blade.veins)
    assert relief is not None and relief.on_margin
    midrib = blade.veins[0]
    np.testing.assert_allclose(relief.hinge_height(midrib[:, 0]), midrib[:, 2], atol=1e-12)
    assert not any(relief.sheet_height(np.linspace(0.1, 0.9, 5)))
    assert not relief_of(blade.boundary, blade.veins).on_margin
    # its rise and fall are its margin's off the hinge, as the form's own relief reads them: a
    # fold eases its turn alike (they were 0, and ovate folded -75 was fitted -72.2)
    own = relief_of(blade.boundary, blade.veins)
    assert relief.fall == pytest.approx(own.fall, abs=1e-3) and relief.fall > np.deg2rad(10)
    assert margin_relief(blade.boundary, [midrib[[0, 5, 3]]]) is None
    big = relief.scaled(8.0)
    np.testing.assert_allclose(big.hinge_height(8 * midrib[:, 0]), 8 * midrib[:, 2], atol=1e-11)


def test_a_relief_says_it_is_fitted_not_its_means_and_a_project_keeps_it():
    """A fitted pose's relief (margin_relief) says its sheet is the margin's plane; a blade's
    own relief, read from a flat blade, has all its means 0 too, and once counted as fitted
    (the app then kept a drawn leaf's bend per unit: bending.fitted). A project writes it as
    "sheet"; one saved before reads it from margin_relief's knots with its means 0."""
    blade = Form("ovate").blade()
    flat = [np.column_stack([c[:, :2], np.zeros(len(c))]) for c in (blade.boundary, *blade.veins)]
    own = relief_of(flat[0], flat[1:])
    assert own is not None and not any(own.mean) and not own.on_margin
    fit = margin_relief(blade.boundary, blade.veins)
    assert fit is not None and fit.on_margin
    for relief, on_margin in ((own, False), (fit, True)):
        entry = relief.entry()
        assert entry["sheet"] == ("margin" if on_margin else "mean")
        assert Relief.from_entry(entry).on_margin is on_margin
        del entry["sheet"]  # a project saved before
        assert Relief.from_entry(entry).on_margin is on_margin
    with pytest.raises(ValueError, match="sheet"):
        Relief.from_entry(fit.entry() | {"sheet": "dome"})


def test_a_curled_hinges_rounds_make_each_spline_once_and_read_no_slopes_they_drop(monkeypatch):
    """unfold_hinge.hinge_relief sets each round's rise and fall itself: margin_relief given
    them reads none off the margin and makes the same relief as one read and then set, and a
    relief so set keeps its profiles' splines (Relief.sloped). A curled hinge's rounds read
    slopes they dropped and made each midrib's spline twice (ovate serrate waved 0.1, read from
    a CSV: open 2.82 -> 2.51 s CPU, the same fit; /work/notes/open36)."""
    blade = Form("ovate").blade()
    read = margin_relief(blade.boundary, blade.veins)
    made: list[bytes] = []
    real = pose_relief.profile_spline

    def counted(x, z, linear_ends=True):
        made.append(np.asarray(x, float).tobytes() + np.asarray(z, float).tobytes())
        return real(x, z, linear_ends)

    monkeypatch.setattr(pose_relief, "profile_spline", counted)
    given = margin_relief(blade.boundary, blade.veins, (0.1, 0.2))
    assert given == replace(read, rise=0.1, fall=0.2) and not made
    height = given.hinge_height(np.zeros(1))
    assert given.sloped(0.3, 0.0).hinge_height(np.zeros(1)) == height
    assert len(made) == 1  # the spline made once, for both
    made.clear()
    curled = hinge_relief(Pose(0.0, 0.5, 0.0, 0.0), blade.veins[0], blade.boundary, (0.1, 0.2))
    assert curled is not None and (curled.rise, curled.fall) == (0.1, 0.2)
    assert len(made) >= 5 and len(made) == len(set(made))  # a round each, none made again
