"""Leaf forms: each term meets its definition, measured on the generated outline; every shape,
margin and venation reconstructs into one piece; veins grow inside outlines these tests did not
draw (the demos, a lobed leaf, a real scan's extracted outline)."""

from __future__ import annotations

import itertools
import warnings
from dataclasses import replace
from functools import cache
from pathlib import Path

import numpy as np
import pytest
import shapely
from shapely.geometry import LineString, Polygon

import leafstudio as ls
from leafstudio.cli import main
from leafstudio.core.evaluate import mesh_facts
from leafstudio.core.pipeline import Pipeline
from leafstudio.errors import LeafError
from leafstudio.forms import SHAPES, VENATION_KINDS, Form, grow_veins
from leafstudio.forms.terms import APEXES, MARGINS, USER_BASES, format_terms
from tests import leaves

DATA = Path(__file__).parents[1] / "data"


@cache
def outline(**terms) -> np.ndarray:
    return Form(**terms).outline().xy


@cache
def leaf_of(**terms) -> ls.Leaf:
    return Form(**terms).leaf()


# --- measurements on an outline -----------------------------------------------------------------
def widest_at(xy: np.ndarray) -> float:
    """x of the greatest half-width, as a share of the base-to-apex length (1)."""
    return float(xy[np.argmax(np.abs(xy[:, 1])), 0])


def aspect(xy: np.ndarray) -> float:
    """L/W: the base-to-apex length (1) over the greatest width."""
    return 1.0 / float(np.ptp(xy[:, 1]))


def concave_runs(xy: np.ndarray) -> int:
    """Runs of vertices where the (counter-clockwise) outline turns clockwise: its notches."""
    a, b = xy - np.roll(xy, 1, axis=0), np.roll(xy, -1, axis=0) - xy
    cross = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    turn = np.arctan2(cross, (a * b).sum(axis=1))
    concave = turn < -0.01
    return int(np.sum(concave & ~np.roll(concave, 1)))


def pockets(xy: np.ndarray) -> list[tuple[float, bool]]:
    """The blade's notches seen against its convex hull: (depth, holds the base) for each."""
    poly = Polygon(xy)
    rest = poly.convex_hull.difference(poly)
    hull_ring = poly.convex_hull.exterior
    out = []
    for part in getattr(rest, "geoms", [rest]):
        if part.is_empty:
            continue
        coords = np.asarray(part.exterior.coords)
        depth = float(shapely.distance(hull_ring, shapely.points(coords)).max())
        out.append((depth, part.distance(shapely.Point(0, 0)) < 1e-6))
    return out


def lobe_count(xy: np.ndarray) -> int:
    width = float(np.ptp(xy[:, 1]))
    deep = [p for p in pockets(xy) if p[0] > 0.1 * width and not p[1]]
    return len(deep) + 1


def tip_angle(xy: np.ndarray, index: int, reach: float = 0.04) -> float:
    """The angle (degrees) at outline vertex `index` between the sides `reach` away along it."""
    p = xy[index]
    d = np.linalg.norm(xy - p, axis=1)
    n = len(xy)
    sides = []
    for step in (1, -1):
        i = index
        while d[i] < reach:
            i = (i + step) % n
        sides.append(xy[i] - p)
    a, b = sides
    return float(np.degrees(np.arccos(a @ b / np.linalg.norm(a) / np.linalg.norm(b))))


def apex_index(xy: np.ndarray) -> int:
    on_axis = np.abs(xy[:, 1]) < 1e-9
    return int(np.flatnonzero(on_axis)[np.argmax(xy[on_axis, 0])])


def teeth_tips(xy: np.ndarray) -> list[float]:
    """For each tooth of the lower half (base to apex): where its tip lies between the notches
    either side, as a share of the way from the basal notch to the apical one."""
    half = xy[: apex_index(xy) + 1]
    a, b = half[1:-1] - half[:-2], half[2:] - half[1:-1]
    turn = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    notches = np.flatnonzero(turn < 0) + 1
    notches = notches[np.r_[True, np.diff(notches) > 1]]
    out = []
    for i, j in itertools.pairwise(notches):
        chord = half[j] - half[i]
        seg = half[i : j + 1]
        rel = seg - half[i]
        off = np.abs(rel[:, 0] * chord[1] - rel[:, 1] * chord[0]) / np.linalg.norm(chord)
        tip = seg[np.argmax(off)]
        out.append(float((tip - half[i]) @ chord / (chord @ chord)))
    return out


# --- the convention -----------------------------------------------------------------------------
@pytest.mark.parametrize("shape", SHAPES)
def test_base_at_origin_apex_on_x_at_length_one_flat(shape):
    leaf = leaf_of(shape=shape)
    xy = leaf.boundary[:, :2]
    assert np.allclose(leaf.boundary[:, 2], 0)
    assert np.any(np.all(np.abs(xy) < 1e-12, axis=1))  # the base is an outline point
    assert xy[:, 0].max() == pytest.approx(1.0)
    assert abs(xy[apex_index(xy), 1]) < 1e-12 and xy[apex_index(xy), 0] == pytest.approx(1.0)
    assert Polygon(xy).is_valid
    assert np.ptp(xy[:, 1]) > 0


# --- shapes -------------------------------------------------------------------------------------
def test_shapes_meet_their_definitions():
    w = {name: widest_at(outline(shape=name)) for name in SHAPES}
    r = {name: aspect(outline(shape=name)) for name in SHAPES}
    assert r["linear"] >= 12
    lin = outline(shape="linear")
    middle = np.abs(lin[(lin[:, 0] > 0.2) & (lin[:, 0] < 0.8), 1])
    assert middle.min() > 0.9 * middle.max()  # sides nearly parallel
    assert w["lanceolate"] < 0.45 and r["lanceolate"] >= 3
    assert w["oblanceolate"] > 0.55 and r["oblanceolate"] >= 3
    assert 0.4 <= w["elliptic"] <= 0.6
    obl = outline(shape="oblong")
    third = np.abs(obl[(obl[:, 0] > 1 / 3) & (obl[:, 0] < 2 / 3), 1])
    assert third.min() > 0.95 * third.max()
    assert w["ovate"] < 0.4 and w["obovate"] > 0.6
    assert 0.9 <= r["orbicular"] <= 1.1
    assert w["deltoid"] < 0.15
    assert w["spatulate"] > 0.7
    spat = outline(shape="spatulate")
    assert (
        np.abs(spat[(spat[:, 0] > 0.1) & (spat[:, 0] < 0.4), 1]).max()
        < 0.4 * np.abs(spat[:, 1]).max()
    )  # a long narrow base
    assert r["reniform"] < 1


@pytest.mark.parametrize("shape", ["elliptic", "ovate", "cordate", "linear"])
@pytest.mark.parametrize("target", [1.5, 3.0, 6.0])
def test_aspect_sets_length_over_width(shape, target):
    assert aspect(outline(shape=shape, aspect=target)) == pytest.approx(target, rel=0.02)


@pytest.mark.parametrize("shape", ["cordate", "reniform", "sagittate"])
def test_basal_lobes_reach_back_past_the_base(shape):
    xy = outline(shape=shape)
    assert xy[:, 0].min() < -0.05
    sinus = [depth for depth, at_base in pockets(xy) if at_base]
    assert sinus and sinus[0] > 0.05  # the base sits in a notch
    if shape == "cordate":
        assert widest_at(xy) < 0.4


def test_sagittate_lobes_point_back_and_hastate_lobes_flare_outward():
    sag = outline(shape="sagittate")
    back = sag[np.argmin(sag[:, 0])]
    assert back[0] < -0.2 and abs(back[1]) > 0.02  # a lobe's tip, behind the base, off the axis
    has = outline(shape="hastate")
    tip = np.argmax(np.abs(has[:, 1]))
    assert -0.02 < has[tip, 0] < 0.2  # the widest points are the lobes, beside the base
    assert tip_angle(has, tip, 0.03) < 100  # pointed lobes
    body = np.abs(has[(has[:, 0] > 0.25) & (has[:, 0] < 0.35), 1]).max()
    assert abs(has[tip, 1]) > 1.2 * body


# --- apex and base ------------------------------------------------------------------------------
@pytest.mark.parametrize("shape", ["elliptic", "ovate", "orbicular"])
def test_apex_terms(shape):
    def angle(apex):
        xy = outline(shape=shape, apex=apex)
        return tip_angle(xy, apex_index(xy), 0.03)

    assert angle("acute") < 90 < angle("obtuse")
    assert angle("acuminate") < angle("acute")
    assert angle("rounded") > 130
    xy = outline(shape=shape, apex="acuminate")
    distal = xy[xy[:, 0] > 0.75]
    assert concave_runs(distal) >= 1 or concave_runs(xy) > concave_runs(
        outline(shape=shape, apex="acute")
    )  # concave sides before the tip
    for apex, (lo, hi) in (("retuse", (0.005, 0.04)), ("emarginate", (0.04, 0.12))):
        xy = outline(shape=shape, apex=apex)
        notch = 1.0 - xy[apex_index(xy), 0]
        assert lo < notch < hi, (apex, notch)


@pytest.mark.parametrize("shape", ["elliptic", "obovate", "oblong"])
def test_base_terms(shape):
    def angle(base):
        return tip_angle(outline(shape=shape, base=base), 0, 0.03)

    assert angle("cuneate") < 90
    assert angle("rounded") > 130
    xy = outline(shape=shape, base="truncate")
    near = np.abs(xy[xy[:, 0] < 0.03, 1]).max()
    assert near > 0.6 * np.abs(xy[:, 1]).max()  # straight across: nearly full width at once
    assert outline(shape=shape, base="cordate")[:, 0].min() < -0.03


def test_a_shape_with_basal_lobes_keeps_its_base():
    with pytest.raises(LeafError, match="cordate base by definition"):
        Form("cordate", base="cuneate")


# --- margin -------------------------------------------------------------------------------------
@pytest.mark.parametrize("margin", ["serrate", "serrulate", "dentate", "crenate", "sinuate"])
@pytest.mark.parametrize("shape,teeth", [("elliptic", 24), ("ovate", 40), ("lanceolate", 60)])
def test_teeth_counted_against_the_option(shape, margin, teeth):
    found = concave_runs(outline(shape=shape, margin=margin, teeth=teeth)) - concave_runs(
        outline(shape=shape)
    )
    assert abs(found - teeth) <= max(1, 0.1 * teeth), found


def test_serrate_teeth_point_to_the_apex_and_dentate_teeth_outward():
    serrate = teeth_tips(outline(shape="elliptic", margin="serrate", teeth=30))
    dentate = teeth_tips(outline(shape="elliptic", margin="dentate", teeth=30))
    assert len(serrate) >= 10 and len(dentate) >= 10
    assert np.median(serrate) > 0.65  # the tip leans toward the apex
    assert 0.4 < np.median(dentate) < 0.6  # straight out
    fine = outline(shape="elliptic", margin="serrulate")
    coarse = outline(shape="elliptic", margin="serrate")
    assert concave_runs(fine) > 1.5 * concave_runs(coarse)  # serrulate: finer


def test_crenate_teeth_are_rounded_and_sinuate_waves_shallow():
    crenate = outline(shape="elliptic", margin="crenate", teeth=20)
    dentate = outline(shape="elliptic", margin="dentate", teeth=20)
    tips = lambda xy: [tip_angle(xy, i, 0.012) for i in np.argsort(-np.abs(xy[:, 1]))[:3]]  # noqa: E731
    assert min(tips(crenate)) > max(tips(dentate)) + 15
    sinuate = outline(shape="elliptic", margin="sinuate")
    entire = outline(shape="elliptic")
    gap = shapely.distance(Polygon(entire).exterior, shapely.points(sinuate)).max()
    assert 0.003 < gap < 0.05  # shallow


@pytest.mark.parametrize("lobes", [2, 3, 5, 7])
@pytest.mark.parametrize("shape", ["ovate", "orbicular", "cordate"])
def test_lobes_counted_by_sinuses_deeper_than_a_tenth_of_the_width(shape, lobes):
    xy = outline(shape=shape, margin="lobed", lobes=lobes)
    assert lobe_count(xy) == lobes
    assert Polygon(xy).is_valid


def test_palmate_venation_lobes_palmately():
    xy = outline(shape="orbicular", margin="lobed", lobes=5, venation="palmate")
    assert lobe_count(xy) == 5


# --- venation -----------------------------------------------------------------------------------
def _lines(veins):
    return [LineString(v[:, :2]) for v in veins]


def _no_crossings(veins) -> bool:
    lines = _lines(veins)
    return not any(a.crosses(b) for a, b in itertools.combinations(lines, 2))


def _inside(leaf, tolerance=1e-6) -> bool:
    poly = Polygon(leaf.boundary[:, :2]).buffer(tolerance)
    return all(shapely.contains_xy(poly, v[:, 0], v[:, 1]).all() for v in leaf.veins)


@pytest.mark.parametrize("shape", ["elliptic", "ovate", "cordate", "lanceolate"])
def test_pinnate_midrib_and_secondaries_reaching_the_margin(shape):
    leaf = leaf_of(shape=shape, secondaries=5)
    midrib, *others = leaf.veins
    assert np.linalg.norm(midrib[0, :2]) < 0.02 and np.linalg.norm(midrib[-1, :2] - [1, 0]) < 0.02
    assert np.abs(midrib[:, 1]).max() < 1e-9
    assert len(others) >= 7  # 5 a side, one may be dropped where it cannot reach the margin
    ring = Polygon(leaf.boundary[:, :2]).exterior
    for vein in others:
        assert abs(vein[0, 1]) < 1e-9  # starts on the midrib
        assert ring.distance(shapely.Point(vein[-1, :2])) < 0.03  # reaches the margin
        assert vein[:, 0].max() > vein[0, 0]  # runs toward the apex
    assert _inside(leaf) and _no_crossings(leaf.veins)


@pytest.mark.parametrize("shape", ["orbicular", "reniform", "cordate"])
def test_palmate_three_or_more_primaries_diverge_from_the_base(shape):
    leaf = leaf_of(shape=shape, venation="palmate")
    from_base = [v for v in leaf.veins if np.linalg.norm(v[0, :2]) < 0.03 and len(v) > 5]
    assert len(from_base) >= 3
    angles = sorted(np.degrees(np.arctan2(v[5, 1] - v[0, 1], v[5, 0] - v[0, 0])) for v in from_base)
    assert min(np.diff(angles)) > 15  # diverging
    assert _inside(leaf) and _no_crossings(leaf.veins)


@pytest.mark.parametrize("shape", ["linear", "lanceolate", "elliptic"])
def test_parallel_veins_run_base_to_apex_without_crossing(shape):
    leaf = leaf_of(shape=shape, venation="parallel")
    assert len(leaf.veins) >= 5
    for vein in leaf.veins:
        assert vein[0, 0] < 0.05 and vein[-1, 0] > 0.95
    assert _inside(leaf) and _no_crossings(leaf.veins)


@pytest.mark.parametrize("shape", ["elliptic", "obovate"])
def test_arcuate_secondaries_curve_toward_the_apex_along_the_margin(shape):
    leaf = leaf_of(shape=shape, venation="arcuate")
    ring = Polygon(leaf.boundary[:, :2]).exterior
    curving = 0
    for vein in leaf.veins[1:]:
        start = np.arctan2(abs(vein[3, 1] - vein[0, 1]), vein[3, 0] - vein[0, 0])
        end = np.arctan2(abs(vein[-1, 1] - vein[-4, 1]), vein[-1, 0] - vein[-4, 0])
        near = ring.distance(shapely.Point(vein[-1, :2])) < 0.08
        curving += bool(end < start - 0.3 and near)
    assert curving >= 0.6 * (len(leaf.veins) - 1)
    assert _inside(leaf) and _no_crossings(leaf.veins)


@pytest.mark.parametrize("shape", list(SHAPES))
def test_an_arcuate_secondary_bends_smoothly_into_its_arch(shape):
    """The colonized path ran on past the arches' ring toward the margin and the arch was walked
    from the ring's nearest point, back inward: a Z at the start of every arch (a turn of 56-179
    degrees between two steps, on every shape). It now turns onto the ring where it reaches it."""
    leaf = leaf_of(shape=shape, venation="arcuate")
    for vein in leaf.veins[1:]:
        step = np.diff(vein[:, :2], axis=0)
        step = step[np.linalg.norm(step, axis=1) > 1e-9]
        heading = np.arctan2(step[:, 1], step[:, 0])
        turns = np.degrees(np.abs(np.angle(np.exp(1j * np.diff(heading)))))
        assert turns.max(initial=0.0) < 75.0
    assert _inside(leaf) and _no_crossings(leaf.veins)


def test_vein_heights_give_relief():
    leaf = leaf_of(shape="ovate")
    for vein in leaf.veins:
        assert np.all(vein[:, 2] >= 0) and vein[:, 2].max() < 0.15
    assert leaf.veins[0][:, 2].max() > 0.03  # the midrib stands highest, as in the demos


# --- relief and variants ------------------------------------------------------------------------
def test_a_fold_turns_each_half_up_about_the_midrib_keeping_its_width():
    """Each half turns rigidly about the midrib as it stands (its hinge, core/hinge_fold.py):
    every point keeps its distance from the hinge and its angle off it turns by the fold. The
    fold lifted the relief straight up (y -> y cos, z += |y| sin), which drew a domed blade in:
    an ovate form folded 60° kept 0.82 of its area (bench_bent.py --size)."""
    flat = leaf_of(shape="ovate")
    folded = leaf_of(shape="ovate", fold=30.0)
    pose = folded.bend
    np.testing.assert_allclose(folded.boundary[:, 0], flat.boundary[:, 0], atol=1e-12)
    hinge = pose.relief.hinge(flat.boundary[:, 0])[0]
    clear = np.abs(flat.boundary[:, 1]) > 0.05  # past the crease's band (hinge_fold.BAND)
    assert clear.sum() > 100
    y, off = flat.boundary[clear, 1], flat.boundary[clear, 2] - hinge[clear]
    y2, off2 = folded.boundary[clear, 1], folded.boundary[clear, 2] - hinge[clear]
    np.testing.assert_allclose(np.hypot(y2, off2), np.hypot(y, off), atol=1e-12)
    turned = np.angle((np.abs(y2) + 1j * off2) / (np.abs(y) + 1j * off))
    np.testing.assert_allclose(turned, np.radians(30), atol=1e-12)
    # and the flat blade comes back exactly
    np.testing.assert_allclose(pose.flatten(folded.boundary), flat.boundary, atol=1e-12)


def test_a_curl_lays_the_midrib_on_a_circle_by_its_length():
    flat = leaf_of(shape="ovate")
    curled = leaf_of(shape="ovate", curl=0.2)
    assert curled.veins[0][-1, 2] > flat.veins[0][-1, 2] + 0.15
    # the blade curls about its midrib's mean height (core/pose_relief.py): a point at that
    # height lies on the circle of radius 1 / (2 curl) over the base (the parabola z = curl x²
    # there), as far along it as it was on the blade; a margin point (no relief) the level
    # below it
    on_margin = np.abs(flat.boundary[:, 2]) < 1e-12
    assert on_margin.sum() > 10
    pose = curled.bend
    radius, level = 1 / 0.4, pose.relief.posed_level(replace(pose, curl=0.0))
    assert 0.03 < level < 0.06  # the midrib's mean height
    x, z = curled.boundary[on_margin, 0], curled.boundary[on_margin, 2] - level
    np.testing.assert_allclose(np.hypot(x, z - radius), radius + level, atol=1e-12)
    along = radius * np.arctan2(x, radius - z)
    np.testing.assert_allclose(along, flat.boundary[on_margin, 0], atol=1e-12)

    def length(curve: np.ndarray) -> float:
        return float(np.linalg.norm(np.diff(curve, axis=0), axis=1).sum())

    # the midrib keeps its length (its relief, carried along the circle's normal, a little
    # less): a shear z += curl x² lengthened a curl of 1's midrib 1.42 times
    assert length(curled.veins[0]) == pytest.approx(length(flat.veins[0]), rel=0.02)


def test_a_wave_is_a_height():
    waved = leaf_of(shape="ovate", wave=0.03)
    assert np.ptp(waved.boundary[:, 2]) == pytest.approx(0.06, rel=0.05)
    assert waved.boundary[0, 2] == 0  # none at the base
    # and flat there: the wave fades in, so the two halves meet at the base without a V
    near = np.linalg.norm(waved.boundary[:, :2] - waved.boundary[0, :2], axis=1) < 0.03
    assert np.abs(waved.boundary[near, 2]).max() < 0.1 * 0.03


def test_same_seed_same_leaf_other_seeds_vary_a_little():
    a, b = (
        leaf_of(shape="ovate", margin="serrate", seed=3),
        leaf_of(shape="ovate", margin="serrate", seed=3),
    )
    np.testing.assert_array_equal(a.boundary, b.boundary)
    others = [leaf_of(shape="ovate", margin="serrate", seed=s) for s in (1, 2, 4)]
    ratios = [aspect(o.boundary[:, :2]) for o in others]
    assert len({round(r, 6) for r in ratios}) == 3  # not copies
    assert max(ratios) < 1.15 * min(ratios)  # but one plant
    assert all(abs(len(o.veins) - len(a.veins)) <= 2 for o in others)


def test_bad_terms_are_one_line_errors():
    with pytest.raises(LeafError, match="unknown shape"):
        Form("heart")
    with pytest.raises(LeafError, match="--teeth needs a toothed margin"):
        Form("ovate", teeth=10)
    with pytest.raises(LeafError, match="--lobes must be between"):
        Form("ovate", margin="lobed", lobes=40)


def test_terms_are_read_whatever_their_case_and_surrounding_spaces(tmp_path, capsys):
    """`leafstudio form Ovate` was refused ("unknown shape 'Ovate'; choose from ..., ovate, ...")
    and so was `make_form("Ovate")`: a term is now the same word in any case, spaces around it
    dropped, in the API, in `form` (its shape, --apex, --base, --margin, --venation) and in
    `slides --compare`; the form keeps the term's own spelling."""
    from leafstudio.cli.slides import comparisons
    from leafstudio.forms import make_form

    form = Form(" Ovate ", apex="Acute", base="ROUNDED", margin="Serrate", venation="Pinnate ")
    assert (form.shape, form.apex, form.base, form.margin, form.venation) == (
        "ovate", "acute", "rounded", "serrate", "pinnate",
    )  # fmt: skip
    np.testing.assert_array_equal(make_form("OVATE").boundary, make_form("ovate").boundary)
    out = tmp_path / "o.leaf.json"
    argv = ["form", "Ovate", "--margin", "Serrate", "--venation", "Arcuate", "-o", str(out)]
    assert main(argv) == 0, capsys.readouterr().err
    assert "ovate leaf" in capsys.readouterr().err
    assert [f.shape for f in comparisons(["Ovate, OBOVATE"])[0][1]] == ["ovate", "obovate"]


# --- every combination reconstructs -------------------------------------------------------------
def _spill(result, leaf) -> float:
    """Mesh area outside the outline (triangles whose centre is outside), over the leaf's area."""
    tm = result.triangle_mesh
    xy = tm.points[:, :2]
    tri = np.asarray(tm.regular_faces)
    centre = xy[tri].mean(axis=1)
    poly = Polygon(leaf.boundary[:, :2])
    out = ~shapely.contains_xy(poly.buffer(1e-9), centre[:, 0], centre[:, 1])
    a, b, c = xy[tri[:, 0]], xy[tri[:, 1]], xy[tri[:, 2]]
    area = 0.5 * np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    return float(area[out].sum() / poly.area)


COMBINATIONS = [
    (shape, margin, VENATION_KINDS[(i + j) % len(VENATION_KINDS)])
    for i, shape in enumerate(SHAPES)
    for j, margin in enumerate(MARGINS)
] + [(shape, "entire", venation) for shape in SHAPES for venation in VENATION_KINDS]
COMBINATIONS += [(shape, "lobed", "palmate") for shape in SHAPES]  # lobes cut toward the base


@pytest.mark.parametrize("shape,margin,venation", sorted(set(COMBINATIONS)))
def test_every_shape_margin_and_venation_reconstructs_in_one_piece(shape, margin, venation):
    """Every shape with every margin and with every venation (each venation in turn across the
    margins), at grid 128: one component, one boundary loop, nothing outside the outline. The
    mesh's facts alone (metrics["mesh"]'s), not the whole metrics: their distances, shape and
    curvature took a sixth of the test."""
    leaf = leaf_of(shape=shape, margin=margin, venation=venation)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = Pipeline(leaf).run(ls.Params(grid=128))
    facts = mesh_facts(result.triangle_mesh)
    assert facts["components"] == 1 and facts["boundary_loops"] == 1
    assert _spill(result, leaf) < 1e-3


def test_relief_reconstructs_through_the_pipeline():
    leaf = leaf_of(shape="ovate", margin="serrate", fold=25.0, curl=0.15, wave=0.02)
    result = Pipeline(leaf).run(ls.Params(grid=128))
    assert result.metrics["mesh"]["components"] == 1
    assert result.metrics["boundary"]["max"] < 0.02  # the margin keeps its heights
    z = result.triangle_mesh.points[:, 2]
    assert np.ptp(z) > 0.15  # fold and curl show in the surface


# --- veins for outlines the tests did not draw --------------------------------------------------
def _check_grown(boundary, veins, base, length):
    poly = Polygon(boundary[:, :2]) if boundary.shape[1] == 2 else None
    assert len(veins) >= 5
    assert np.linalg.norm(veins[0][0] - base) < 0.03 * length  # the midrib starts at the base
    assert _no_crossings(veins) if poly is not None else True
    return poly


@pytest.mark.parametrize("name", ["nested", "parallel"])
def test_veins_grow_inside_the_demos(name):
    boundary = ls.demo(name).boundary
    veins = grow_veins(boundary)  # the base found: the longest axis's end at the origin
    assert np.linalg.norm(veins[0][0, :2]) < 0.02 and veins[0][-1, 0] > 0.97
    leaf = ls.Leaf(boundary=boundary, veins=veins)
    assert _inside(leaf) and _no_crossings(veins)
    ring = Polygon(boundary[:, :2]).exterior
    reach = [ring.distance(shapely.Point(v[-1, :2])) < 0.02 for v in veins[1:]]
    assert np.mean(reach) >= 0.8
    assert Pipeline(leaf).run(ls.Params(grid=96)).metrics["mesh"]["components"] == 1


@pytest.mark.parametrize("venation", VENATION_KINDS)
def test_veins_grow_inside_a_lobed_leaf(venation):
    leaf, _ = leaves.lobed()
    sinus = np.argmin(np.linalg.norm(leaf.boundary[:, :2], axis=1))  # between two lobes
    base = leaf.boundary[sinus, :2]
    veins = grow_veins(leaf.boundary[:, :2], venation, base=base)
    grown = ls.Leaf(boundary=leaf.boundary, veins=veins)
    assert _inside(grown) and _no_crossings(veins)
    assert np.linalg.norm(veins[0][0, :2] - base) < 0.05


def test_veins_grow_inside_a_real_scans_outline():
    real = ls.load_leaf(DATA / "soybean_extracted.leaf.json")
    length = float(np.ptp(real.boundary, axis=0).max())
    base = real.veins[0][0]
    veins = grow_veins(real.boundary, base=base)
    assert np.linalg.norm(veins[0][0] - base) < 0.05 * length
    grown = ls.Leaf(boundary=real.boundary, veins=veins)
    result = Pipeline(grown).run(ls.Params(grid=96))
    assert result.metrics["mesh"]["components"] == 1
    # every vein point lies inside the outline as the pipeline sees it, near its surface
    assert result.metrics["veins"]["max"] < 0.03 * length
    auto = grow_veins(real.boundary)  # no base given: still a midrib along the longest axis
    assert len(auto) >= 5


@pytest.mark.parametrize(
    "boundary,message",
    [
        (np.column_stack([np.linspace(0, 1, 10), np.zeros(10)]), "encloses no area"),
        (np.array([[0, 0], [1, np.nan], [0, 1]]), "NaN"),
        (np.zeros((2, 2)), "n >= 3"),
    ],
)
def test_grow_veins_refuses_outlines_without_a_blade(boundary, message):
    with pytest.raises(LeafError, match=message):
        grow_veins(boundary)


def test_grow_veins_keeps_the_boundarys_coordinates():
    boundary = ls.demo("nested").boundary * 1000 + [5e4, -3e4, 7]
    veins = grow_veins(boundary, base=boundary[0])
    assert np.linalg.norm(veins[0][0, :2] - boundary[0, :2]) < 20  # 2% of the length
    assert all(np.all(v[:, 2] >= 7) and np.all(v[:, 2] < 7 + 100) for v in veins)


# --- the command line ---------------------------------------------------------------------------
def test_form_list_prints_every_term(capsys):
    assert main(["form", "--list"]) == 0
    text = capsys.readouterr().out
    for term in [*SHAPES, *APEXES, *USER_BASES, *MARGINS, *VENATION_KINDS]:
        assert f"  {term} " in text
    assert text.strip() == format_terms()


def test_form_writes_a_leaf_or_a_mesh(tmp_path):
    out = tmp_path / "f.leaf.json"
    assert main(["form", "cordate", "--margin", "serrate", "--teeth", "30", "-o", str(out)]) == 0
    leaf = ls.load_leaf(out)
    assert leaf.boundary[:, 0].max() == pytest.approx(1.0) and len(leaf.veins) > 3
    mesh = tmp_path / "f.obj"
    assert main(["form", "ovate", "--fold", "20", "-o", str(mesh)]) == 0
    assert mesh.stat().st_size > 1000


def test_veins_command_grows_veins_in_a_leaf_file(tmp_path, capsys):
    src = tmp_path / "nested.csv"
    ls.save_leaf(ls.Leaf(boundary=ls.demo("nested").boundary), src)
    out = tmp_path / "veined.leaf.json"
    assert main(["veins", str(src), "-o", str(out), "--venation", "arcuate"]) == 0
    leaf = ls.load_leaf(out)
    assert len(leaf.veins) >= 5 and np.allclose(leaf.boundary, ls.demo("nested").boundary)


@pytest.mark.parametrize(
    "argv,message",
    [
        (["form", "heart", "-o", "x.csv"], "unknown shape"),
        (["form", "ovate"], "-o FILE"),
        (["form", "ovate", "-o", "x.docx"], "unknown file type"),
        (["form", "ovate", "--teeth", "5", "-o", "x.csv"], "toothed margin"),
        (["veins", "missing.csv", "-o", "x.csv"], "no such file"),
    ],
)
def test_bad_form_and_veins_arguments_are_one_line_and_exit_2(tmp_path, capsys, argv, message):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize(
    ("shape", "terms"),
    [
        ("oblanceolate", dict(venation="parallel", apex="acuminate", seed=202, fold=46.5,
                              curl=-0.42, wave=0.089)),
        ("spatulate", dict(margin="crenate", venation="parallel", apex="acuminate", seed=882,
                           fold=10.6, curl=0.5, wave=0.09)),
        ("linear", dict(margin="lobed", venation="palmate", seed=344, curl=0.11, wave=0.079)),
    ],
)  # fmt: skip
def test_relief_within_its_ranges_still_reconstructs(shape, terms):
    """Review finding: fold, curl and wave together tilt the boundary's plane, so vein ends near
    the margin fell outside the outline ("vein 1: 14 of 70 points lie outside the boundary"), and
    a wave taller than a linear blade is wide made its outline cross itself."""
    result = ls.reconstruct(Form(shape, **terms).leaf(), ls.Params(grid=64))
    assert result.metrics["mesh"]["components"] == 1
    assert result.metrics["mesh"]["boundary_loops"] == 1
