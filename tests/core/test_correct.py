"""The surface passes through the veins (issue 21, finding 3; core/correct.py)."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.core import correct, vein_centers
from leafstudio.core.bending import Bending
from leafstudio.core.buckets import kernel_array
from leafstudio.core.evaluate import dihedral_angles, margin_creases, triangles_of
from leafstudio.core.grid import make_grid
from leafstudio.forms.make import make_form
from leafstudio.forms.terms import SHAPES
from leafstudio.gui.model.sketch_model import Sketch
from tests.leaves import clicked_sketch

VEIN_TOLERANCE = 1e-3  # of the length: the target


def drawn_leaf() -> ls.Leaf:
    """As in the app: a 12-point outline, a midrib and four side veins started on it (snapped:
    they branch at the midrib's height there), the heights of their other control points raised
    by hand (none on the margin itself, which stays at height 0)."""
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    boundary = np.column_stack([0.5 + 0.5 * np.cos(t), 0.25 * np.sin(t) * (1 + 0.3 * np.sin(t))])
    x = np.linspace(0.05, 0.95, 5)
    midrib = np.column_stack([x, np.zeros(5), [0.03, 0.07, 0.09, 0.06, 0.02]])
    sketch = Sketch(boundary=boundary, veins=(midrib,))
    for x0, side, raised in [
        (0.3, 1, [0.06, 0.03]),
        (0.3, -1, [0.07, 0.025]),
        (0.6, 1, [0.05, 0.035]),
        (0.6, -1, [0.065, 0.02]),
    ]:
        start = sketch.snap_to_vein(np.array([x0, 0.0]), 0.01)
        assert start is not None
        rest = np.column_stack([[x0 + 0.08, x0 + 0.15], side * np.array([0.08, 0.15]), raised])
        sketch = sketch.with_vein(np.vstack([start, rest]))
    leaf = sketch.to_leaf()
    assert leaf is not None
    return leaf


def _run(leaf: ls.Leaf, **params) -> ls.Result:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ls.reconstruct(leaf, ls.Params(grid=128, **params))


@pytest.mark.parametrize("shape", list(SHAPES))
def test_every_gallery_form_passes_through_its_veins(shape):
    """Today the largest vein-point distance is 1.1e-3 to 9.5e-3 of the length at K = 3."""
    result = _run(make_form(shape), k=3)
    assert result.metrics["veins"]["max"] <= VEIN_TOLERANCE * result.length
    assert result.metrics["boundary"]["max"] <= 1e-9 * result.length  # z = b on the margin


@pytest.mark.parametrize("shape", list(SHAPES))
def test_every_gallery_forms_surface_through_its_veins_is_no_rougher_than_the_papers(shape):
    """Issue 21's bar: margin and interior smoothness (99th-percentile dihedral) no worse than
    the paper's pure GMM surface's. Oblanceolate's inside was 2.94° against 2.85°: the values
    were chosen for the least squared bending, which the many gentle bends outweigh where the
    blade narrows beside the midrib (bending.sharpest)."""
    leaf = make_form(shape)
    ours, theirs = (margin_creases(_run(leaf, k=3, through_veins=on)) for on in (True, False))
    for band in ("margin_p99", "interior_p99"):
        assert ours[band] <= theirs[band]


@pytest.mark.parametrize("shape", ["lanceolate", "cordate", "hastate"])
def test_a_drip_tip_passes_through_its_veins(shape):
    """Review of issue 21: an acuminate apex's midrib stood 1.75e-3 (lanceolate), 4.2e-3
    (cordate) and 4.3e-3 (hastate) of the length off the mesh: the dome's grid is coarser than
    the tip, and its read-back raised the midrib there (forms/relief.py, ROOF_CAP)."""
    result = _run(make_form(shape, apex="acuminate"), k=3)
    assert result.metrics["veins"]["max"] <= VEIN_TOLERANCE * result.length


def test_a_toothed_forms_surface_through_its_veins_is_no_rougher_than_the_papers():
    """A serrate orbicular form's veins ran into its teeth as high as the dome read back past the
    margin: the surface through them creased at the teeth (99th-percentile margin dihedral 18.3°
    against the paper's 14.9°)."""
    leaf = make_form("orbicular", margin="serrate")
    through = _run(leaf, k=3)
    paper = _run(leaf, k=3, through_veins=False)
    assert through.metrics["veins"]["max"] <= VEIN_TOLERANCE * through.length
    assert margin_creases(through)["margin_p99"] <= margin_creases(paper)["margin_p99"]


@pytest.mark.parametrize("shape", ["ovate", "cordate", "sagittate", "spatulate", "elliptic"])
def test_a_waved_form_passes_through_its_veins(shape):
    """Issue 21: a wave of 0.1 left the midrib's ends 7.1e-3 (ovate) of the length off the mesh,
    next to the base, where the margin's wave rose at full slope from both sides into a V; then
    the base b(x), a spline through 48 of the outline's points, missed the heights between them
    and the veins riding on it: sagittate 4.4e-3, spatulate and elliptic 1.4e-3."""
    result = _run(make_form(shape, wave=0.1), k=3)
    assert result.metrics["veins"]["max"] <= VEIN_TOLERANCE * result.length


def test_a_drawn_leaf_with_hand_raised_veins_passes_through_them_without_new_creases():
    """Today 4.9e-3 of the length at K = 7; the creases (99th-percentile dihedral angle in the
    margin band and inside) are no rougher than the paper's surface's. With centres on the veins
    alone they were (8.46° against 8.32° in the band, 9.04° against 9.01° inside): the side veins
    end 0.020 of the length high 0.010 from the margin, and the spline lifted each end as a bump
    that the taper pulled down beside it (vein_centers.free_centers)."""
    leaf = drawn_leaf()
    through = _run(leaf, k=7)
    paper = _run(leaf, k=7, through_veins=False)
    assert paper.metrics["veins"]["max"] > 3 * VEIN_TOLERANCE * paper.length
    assert through.metrics["veins"]["max"] <= VEIN_TOLERANCE * through.length
    ours, theirs = margin_creases(through), margin_creases(paper)
    for band in ("margin_p99", "interior_p99"):
        assert ours[band] <= theirs[band]


def test_only_a_vein_end_standing_steeply_over_the_margin_gets_free_centres():
    """On a unit disk (g the distance to its margin, length 2), a side vein ending 0.05 from the
    margin gets free centres about its end when it stands twice that high there, on no vein,
    inside the blade and FREE_RING of the length from the end; as high as a form's dome (a
    quarter of its distance to the margin) it gets none."""

    def distance_in(xy: np.ndarray) -> np.ndarray:
        return 1.0 - np.linalg.norm(xy, axis=1)

    midrib = np.column_stack([np.linspace(-0.9, 0.9, 60), np.zeros(60)])
    side = np.column_stack([np.zeros(20), np.linspace(0.0, 0.95, 20)])
    veins = [midrib, side]
    on_veins = np.vstack(veins)
    gentle = [0.25 * distance_in(v) for v in veins]
    steep = [gentle[0], np.linspace(0.25, 0.1, 20)]  # its end 0.1 high, 0.05 from the margin
    length, delta = 2.0, 0.2  # T = tanh(0.05 / 0.2) = 0.24 at the side vein's end
    args = (on_veins, length, distance_in, delta)
    assert len(vein_centers.free_centers(veins, gentle, *args)) == 0
    free = vein_centers.free_centers(veins, steep, *args)
    assert 1 <= len(free) <= vein_centers.FREE_SPOKES
    ring = vein_centers.FREE_RING * length
    np.testing.assert_allclose(np.linalg.norm(free - side[-1], axis=1), ring)
    assert np.all(np.tanh(distance_in(free) / delta) >= vein_centers.FREE_TAPER)
    gaps = np.linalg.norm(free[:, None] - on_veins[None], axis=2).min(axis=1)
    assert np.all(gaps >= 0.5 * ring)


@pytest.mark.parametrize(
    ("shape", "interior"), [("ovate", 3.4), ("oblong", 3.4), ("cordate", 3.4), ("sagittate", 4.0)]
)
def test_a_forms_surface_through_its_veins_is_as_smooth_as_the_papers(shape, interior):
    """A form's veins stood a quarter of their distance to the margin high: a roof, 14° each side
    of the midrib, which a surface through them had to follow (99th-percentile interior dihedral
    4.6° on ovate, 5.8° on oblong, 9.9° on sagittate, where the paper's surface, 6.5e-3 off the
    midrib, had 3.4°). On the forms' smooth dome (forms/relief.py) it is under 3.4° (sagittate,
    its lobes veinless, 3.4°: under 4°) and the margin band's under 4°, with every vein point
    within 1e-3 of the length."""
    result = _run(make_form(shape), k=3)
    assert result.metrics["veins"]["max"] <= VEIN_TOLERANCE * result.length
    creases = margin_creases(result)
    assert creases["interior_p99"] <= interior
    assert creases["margin_p99"] <= 4.0


@pytest.mark.parametrize(
    ("shape", "margin", "interior"),
    [("cordate", 1.6, 1.6), ("reniform", 1.3, 1.6), ("sagittate", 1.8, 2.75)],
)
def test_a_sinus_forms_surface_through_its_veins_has_no_dent_at_the_notch(shape, margin, interior):
    """The dome was flattened within 0.15 of the length around the base; at a sinus's notch
    the correction then bent the surface through the veins into a dent (99th-percentile
    dihedral, margin band / inside: cordate 2.01° / 1.98°, reniform 1.22° / 1.79°, sagittate
    2.14° / 2.81°). Flattened within 0.27 there (forms/relief.py) they are 1.36° / 1.46°,
    1.08° / 1.42° and 1.55° / 2.65°."""
    result = _run(make_form(shape), k=3)
    assert result.metrics["veins"]["max"] <= VEIN_TOLERANCE * result.length
    creases = margin_creases(result)
    assert creases["margin_p99"] <= margin
    assert creases["interior_p99"] <= interior


def _lattice(centers: np.ndarray) -> Bending:
    """The lattice of a grid's nodes 0.3 about the (m, 2) `centers`, all inside (T = 1), as the
    pipeline's bending stage makes it (length 1)."""
    grid = make_grid(np.vstack([centers.min(axis=0) - 0.3, centers.max(axis=0) + 0.3]), 64)
    inside = np.ones(len(grid.points), dtype=bool)
    return correct.lattice_bending(kernel_array(centers), 1.0, grid, inside, np.ones(len(inside)))


def _fit(centers: np.ndarray, taper: np.ndarray, residual: np.ndarray, bending: Bending):
    """fit_correction as onto_veins calls it, on a flat mixture (M = 0 on the lattice)."""
    relief = np.zeros(len(bending.on))
    return correct.fit_correction(centers, taper, residual, 1.0, 1.0, bending, relief)


def test_values_within_their_slack_bend_the_surface_less():
    """A spike on a line of values is lowered within its slack, every value stays within it,
    and the surface's bending on the lattice falls (bending.least_bending)."""
    centers = np.column_stack([np.linspace(0, 1, 21), np.zeros(21)])
    centers[::2, 1] = 0.05  # two rows: a 2-D spline
    target = np.where(np.arange(21) == 10, 0.01, 0.0)
    taper, slack = np.ones(21), 0.004
    bending = _lattice(centers)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(correct, "TOLERANCE", 0.0)
        exact = _fit(centers, taper, target, bending)
        mp.setattr(correct, "TOLERANCE", slack)
        relaxed = _fit(centers, taper, target, bending)
    assert exact is not None and relaxed is not None
    assert np.allclose(exact.value(centers), target, atol=1e-9)
    values = relaxed.value(centers)
    assert np.all(np.abs(values - target) <= slack + 1e-9)
    assert values[10] < 0.01 - 0.5 * slack

    def energy(c: correct.VeinCorrection) -> float:  # |D T c|² on the lattice
        return float(
            np.sum((bending.differences @ (bending.taper * (bending.phi @ c.weights))) ** 2)
        )

    assert energy(relaxed) < 0.5 * energy(exact)


def test_a_vein_point_in_the_margin_band_has_more_slack():
    """correct.BAND_TOLERANCE: a spike on a line of values in the margin band (T < BAND) is
    lowered by more than TOLERANCE (over T), within BAND_TOLERANCE; inside (T = 1) by no more
    than TOLERANCE."""
    centers = np.column_stack([np.linspace(0, 1, 21), np.zeros(21)])
    centers[::2, 1] = 0.05
    target = np.where(np.arange(21) == 10, 0.01, 0.0)
    bending = _lattice(centers)
    for taper, most in ((1.0, correct.TOLERANCE), (0.3, correct.BAND_TOLERANCE)):
        fitted = _fit(centers, np.full(21, taper), taper * target, bending)
        assert fitted is not None
        off = np.abs(taper * fitted.value(centers) - taper * target)
        assert off.max() <= most + 1e-9
        assert off[10] > 0.9 * most


def test_a_system_not_positive_definite_is_solved_as_before():
    """φ is cut at KELVIN_END, so P = Φ + λT⁻² need not be positive definite in floating point:
    then the weights come from P's LU inverse, and still solve the rows T_i² (Φ w)_i + λ w_i =
    T_i² values_i (a centre with T = 0 keeps weight 0), as before the Cholesky factor."""
    centers = np.column_stack([np.linspace(0, 1, 21), np.zeros(21)])
    centers[::2, 1] = 0.05
    bending = _lattice(centers)
    indefinite = replace(bending, among=bending.among - 0.2 * np.eye(21))
    assert np.linalg.eigvalsh(indefinite.among).min() < 0
    taper = np.where(np.arange(21) == 20, 0.0, 1.0)
    target = 0.003 * np.sin(np.linspace(0, 3, 21)) * taper
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(correct, "TOLERANCE", 0.0)  # the values are the targets
        fitted = _fit(centers, taper, target, indefinite)
    assert fitted is not None
    assert fitted.weights[20] == 0.0
    rows = taper[:, None] ** 2 * indefinite.among + correct.VEIN_SMOOTHING * np.eye(21)
    assert np.allclose(rows @ fitted.weights, taper**2 * target, rtol=0, atol=1e-9)


def test_a_wavy_form_keeps_its_margin_on_the_boundary():
    """The correction lives inside the taper: on a base surface (a wavy margin's) the mesh's
    margin stays on the boundary's heights, and outside the margin z is the base exactly."""
    leaf = make_form("elliptic", wave=0.05)
    result = _run(leaf, k=3)
    assert result.metrics["boundary"]["max"] <= 1e-9 * result.length
    unit = result.unit
    assert unit.surface.correction is not None
    centre = unit.polygon.mean(axis=0)
    outside = centre + 1.02 * (unit.polygon - centre)
    assert np.all(unit.surface.implicit(outside) < 0)
    assert np.array_equal(unit.surface(outside), unit.surface.base(outside))


def test_the_papers_surface_stays_available():
    """through_veins=False: the paper's pure GMM surface, no correction, off the veins (deltoid:
    3.1e-3 of the length)."""
    leaf = make_form("deltoid")
    paper = _run(leaf, k=3, through_veins=False)
    assert paper.unit.surface.correction is None
    assert paper.metrics["veins"]["max"] > 2 * VEIN_TOLERANCE * paper.length


def test_the_correction_has_closed_form_derivatives():
    """∇c and ∇²c agree with finite differences away from the spline's centres."""
    result = _run(make_form("ovate"), k=3)
    c = result.unit.surface.correction
    xy = np.array([[0.3, 0.07], [0.55, -0.1], [0.12, 0.02]])
    value, grad, hess = c.derivatives(xy)
    assert np.allclose(value, c.value(xy))
    h = 1e-5
    for axis in range(2):
        step = np.zeros(2)
        step[axis] = h
        numeric = (c.value(xy + step) - c.value(xy - step)) / (2 * h)
        assert np.allclose(grad[:, axis], numeric, rtol=1e-5, atol=1e-7)
        numeric_h = (c.derivatives(xy + step)[1] - c.derivatives(xy - step)[1]) / (2 * h)
        assert np.allclose(hess[:, axis], numeric_h, rtol=1e-4, atol=1e-5)


def test_a_later_veins_centres_near_an_earlier_veins_kept_ones_are_left_to_it():
    """A side vein leaving the midrib loses its points within JUNCTION of the midrib's centres;
    a third vein near only the side vein's dropped points keeps its own."""
    near = 0.5 * vein_centers.JUNCTION
    midrib = np.column_stack([np.linspace(0, 1, 126), np.zeros(126)])
    side = np.column_stack([np.full(10, 0.5), near + np.linspace(0, 0.2, 10)])
    third = np.array([[0.508, 0.012], [0.9, 0.3]])  # 0.010 from the side vein's first point
    kept, _ = vein_centers.spline_centers([midrib, side, third], 1.0)
    side_kept = side[kept[1]]
    assert np.all(side_kept[:, 1] >= vein_centers.JUNCTION)  # none beside the midrib's centres
    assert len(side_kept) >= 2
    assert len(kept[2]) == 2


def test_the_corrections_gradient_alone_is_its_derivatives_first_two():
    """VeinCorrection.value_and_gradient gives c and ∇c as `derivatives` does, a centre itself
    included (∇c = 0 there), and the mesh's curvatures at the margin, where ∇²c is left out (T = 0
    multiplies it), are those of the closed form with it."""
    result = _run(make_form("ovate"), k=3)
    surface = result.unit.surface
    c = surface.correction
    xy = np.vstack([result.unit.polygon[::7], c.centers[:3], [[0.3, 0.07]]])
    value, grad = c.value_and_gradient(xy)
    full = c.derivatives(xy)
    np.testing.assert_allclose(value, full[0], rtol=0, atol=1e-13 * np.abs(full[0]).max())
    np.testing.assert_allclose(grad, full[1], rtol=0, atol=1e-13 * np.abs(full[1]).max())
    rim = result.unit.polygon
    margin = np.ones(len(rim), dtype=bool)
    value, grad = c.value_and_gradient(rim)
    left_out = surface.derivatives(
        rim, margin, correction_at=(value, grad, np.zeros((len(rim), 2, 2)))
    )
    closed = surface.derivatives(rim, margin)
    for ours, theirs in zip(left_out[1:], closed[1:], strict=True):
        np.testing.assert_allclose(ours, theirs, rtol=1e-12, atol=1e-12 * np.abs(theirs).max())


def test_a_straight_midrib_alone_gives_a_calm_correction():
    """Centres on one line leave a slope across it undetermined: it must not blow up (it reached
    1e14 on a curled leaf's midrib before the linear part was restricted to the line)."""
    t = np.linspace(0, 2 * np.pi, 160, endpoint=False)
    xy = np.column_stack([0.5 * np.cos(t), 0.2 * np.sin(t)])
    lift = lambda p: np.column_stack([p, 0.4 * p[:, 0] ** 2 + 0.5 * p[:, 1] ** 2])  # noqa: E731
    midrib = np.column_stack([np.linspace(-0.46, 0.46, 40), np.zeros(40)])
    result = _run(ls.Leaf(boundary=lift(xy), veins=[lift(midrib)]), k=3)
    unit = result.unit
    c = unit.surface.correction.value(unit.grid.points[unit.inside])
    assert np.abs(c).max() < 0.01 * unit.length
    assert result.metrics["veins"]["max"] <= VEIN_TOLERANCE * result.length


def test_the_correction_fades_away_from_the_veins():
    """The thin-plate spline (r² log r and a plane) carried the slope and level it had at the
    last vein out into every veinless part of the blade: a reniform form's lobes beside the
    notch were lowered by 0.02 of the length. Past a few REACH of the veins it is now nothing."""
    vein = np.column_stack([np.linspace(-0.15, 0.15, 31), 0.02 * np.sin(np.linspace(0, 3, 31))])
    residual = 0.004 * np.sin(np.linspace(0, 2 * np.pi, 31)) + 0.003
    fitted = _fit(vein, np.ones(31), residual, _lattice(vein))
    assert fitted is not None
    assert np.allclose(fitted.value(vein), residual, atol=correct.TOLERANCE + 1e-9)
    far = np.array([[0.0, 0.5], [0.55, 0.0], [-0.4, -0.4]])  # 0.4-0.5 off the vein
    assert np.all(np.abs(fitted.value(far)) <= 0.05 * np.abs(residual).max())


def test_a_round_based_forms_inside_is_no_rougher_through_its_veins_than_the_papers():
    """Issue 21: orbicular's inside (the 99th-percentile dihedral farther in than three grid
    steps of the margin) was rougher through its veins than on the paper's surface, 1.29°
    against 1.08° at grid 128: its midrib followed the dome's flattening at its rounded base
    (forms/relief.py), flat and then turning up. A rounded base is no longer flattened."""
    leaf = make_form("orbicular")
    through = _run(leaf, k=3)
    paper = _run(leaf, k=3, through_veins=False)
    assert through.metrics["veins"]["max"] <= VEIN_TOLERANCE * through.length
    assert margin_creases(through)["interior_p99"] <= margin_creases(paper)["interior_p99"]


@pytest.mark.parametrize("shape", ["reniform", "oblong", "hastate"])
def test_a_forms_margin_band_is_no_rougher_than_the_papers(shape):
    """Issue 21: through its veins, reniform's margin band (the 99th-percentile dihedral within
    three grid steps of the margin) was rougher than the paper's surface's, 2.40° against 1.80°
    at grid 96 (1.77° against 1.36° at 128): the correction lowered the veinless lobes beside
    the notch. Hastate's was 4.77° against 2.84° at grid 96 (3.98° against 3.66° at 128): a bump
    beside each lobe's notch, spread into the lobe (forms/relief.py, notches). Oblong, no lobes,
    stays no rougher either."""
    leaf = make_form(shape)
    through = ls.reconstruct(leaf, ls.Params(k=3, grid=96))
    paper = ls.reconstruct(leaf, ls.Params(k=3, grid=96, through_veins=False))
    assert through.metrics["veins"]["max"] <= VEIN_TOLERANCE * through.length
    assert margin_creases(through)["margin_p99"] <= margin_creases(paper)["margin_p99"]


def test_a_side_vein_into_a_base_corner_leaves_the_margin_band_no_rougher_than_the_papers():
    """Issue 21: deltoid's side vein runs into a corner of its base. With the correction's values
    chosen for the spline's own bending its margin band was rougher than the paper's surface's
    (99th-percentile dihedral 2.35° against 2.19° at grid 128); chosen for the whole surface's
    bending (core/bending.py) 2.04°, every vein point still within 1e-3 of the length."""
    leaf = make_form("deltoid")
    through = _run(leaf, k=3)
    paper = _run(leaf, k=3, through_veins=False)
    assert through.metrics["veins"]["max"] <= VEIN_TOLERANCE * through.length
    assert margin_creases(through)["margin_p99"] <= margin_creases(paper)["margin_p99"]


def _largest_crease_near(result: ls.Result, points: np.ndarray, reach: float) -> float:
    """The largest dihedral angle (degrees) of the mesh's edges whose middles lie within `reach`
    (of the length) of any of the (p, 2) plane `points`."""
    angles, edges = dihedral_angles(
        np.asarray(result.triangle_mesh.points), triangles_of(result.triangle_mesh)
    )
    middles = result.mesh_on_blade()[0][edges].mean(axis=1)
    apart = np.linalg.norm(middles[:, None] - points[None], axis=2).min(axis=1)
    return float(angles[apart < reach * result.length].max())


def test_no_crease_where_a_side_vein_leaves_the_midrib():
    """Issue 21: the values, CENTER_STEP apart along the veins, made a bend where a side vein
    leaves the midrib that the lattice, its differences over four grid steps farther in than the
    margin band, did not see: the largest dihedral within 0.03 of the length of a side vein's
    start was 4.38° on the clicked sketch, against the paper's 1.63°; with c's own bending
    (core/bending.py) 1.73°."""
    leaf = clicked_sketch().to_leaf()  # the sketch the app's story clicks, auto vein heights
    through, paper = _run(leaf, k=3), _run(leaf, k=3, through_veins=False)
    starts = np.array([through.frame.to_plane(v)[0][0] for v in through.leaf.veins[1:]])
    ours = _largest_crease_near(through, starts, 0.03)
    assert ours <= 1.15 * _largest_crease_near(paper, starts, 0.03)
