"""A smooth correction that brings the height surface onto every vein point (issue 21, item 4).

The Gaussian mixture follows the veins only in the least-squares sense: on the gallery's forms
the largest vein-point distance is 0.4-1% of the length, on a drawn leaf with hand-raised veins
0.5% and more, and the curves a designer drew hang in the air. After the mixture is fitted, the
residuals on the veins, r_i = h_i − T(g_i/δ) M(v_i), are taken up by a spline c(x) inside the
same taper:

    z(x) = b(x) + T(g(x)/δ) · (Σ_k a_k N_k(x) + c(x)),
    c(x) = Σ_j w_j φ(|x − v_j|),     φ(r) = −kei(r / ℓ),  ℓ = REACH · length.

φ is the Green's function of Δ² + ℓ⁻⁴ (kei a Kelvin function): c is the interpolant that least
bends and stays least far from zero, ∫ (Δc)² + c² / ℓ⁴. Within ℓ of the veins it bends as a
thin-plate spline (−kei(ρ) = π/4 + ρ² log ρ / 4 + O(ρ²): the same r² log r), and past them it
fades to nothing, as e^(−r/ℓ√2). The thin-plate spline itself (r² log r plus a plane) kept
whatever slope and level it had at the last vein out into every veinless part of the blade
(issue 21, the margin band): a reniform form's two lobes beside the notch were lowered 0.02 of
the length and a hastate form's lobe tips raised 0.01, an orbicular form's margin tilted by the
plane, and the margin band's 99th-percentile dihedral rose over the paper's surface (reniform
1.36° -> 1.77°, hastate 3.66° -> 4.41°, orbicular 1.18° -> 1.36°; then 1.22°, 3.98°, 1.20°; now
1.08°, 1.28° against 1.30° (the dome flattened at hastate's lobes' notches, forms/relief.py) and
1.21°).
A cubic kernel r³ creased a drawn leaf's margin band 50% more. T(0) = 0 keeps z = b exactly on
the margin. The coefficients solve

    min Σ_i (T_i c(v_i) − r_i)² + λ wᵀ Φ w,

whose normal equations are the rows T_i² (Φ w)_i + λ w_i = T_i r_i: where T_i is 1 this is the
usual smoothing spline, and a vein point on or outside the margin (T_i = 0) gets no weight, so
nothing pulls the margin off the boundary. λ is tiny (VEIN_SMOOTHING): it only keeps the solve
well posed when vein points nearly coincide. φ is positive definite, so no polynomial part is
needed (the thin-plate spline's plane was undetermined across a lone midrib).

Pinned exactly, the spline drew a ridge tight onto a vein wherever the veins stand on a roof (a
form's veins are a quarter of their distance to the margin high: 14° each side of the midrib,
which the mixture rounds 6.5e-3 of the length low). So each value c(v_i) may move within
TOLERANCE / T_i of r_i / T_i to where the spline bends least (`_within`, projected gradient steps
on the bending energy, the factorised system reused): ovate's 99th-percentile interior dihedral
5.0° -> 4.6°, oblong's 6.4° -> 5.8°, every vein point within 1e-3 of the length on the mesh.
In the margin band (T_i < BAND) the tolerance is BAND_TOLERANCE: there the surface comes down
to the margin within a short way, and a vein point held tight beside a corner or a raised vein
end bends the spline just where the taper creases (p99 margin dihedral at BAND_TOLERANCE =
TOLERANCE: deltoid 2.45°, spatulate 2.45°, a drawn leaf's 8.84°, its inside 9.15°; now 2.35°,
2.37°, 8.54°, 9.10°, every vein point within 8e-4 of the length). Where the blade is bent, that
wider tolerance is divided by the bend's stretch once more (onto_veins).

Given the grid's nodes (as the pipeline gives them), the values are chosen within the same
tolerances for the whole surface's bending instead, T · (M + c) on a lattice of the nodes
(bending.py), not c's alone: c then bends against the mixture's own bends rather than where it
bends least by itself. bench_bent --veins, 99th-percentile dihedral against the paper's surface,
margin band: linear 7.05° (7.78°), deltoid 1.98° (2.19°), orbicular 1.09° (1.18°), a drawn
leaf's 8.49° (8.32°, was 8.54°); every gallery form's margin band and inside but oblanceolate's
and orbicular's inside (2.94° against 2.85°, 1.30° against 1.08°: the dip of the form's base
flattening) now as smooth or smoother; every vein point still within 8e-4 of the length. The
points of the band already close enough (CLOSE_ENOUGH) are pinned too then: the surface moves
there as well.

The spline's centres are the vein points thinned along each vein (CENTER_STEP), less those of
a later vein within JUNCTION of an earlier one (where a side vein leaves the midrib, the two
disagree by a little within a grid cell, and meeting both bent the surface into a ridge tighter
than a thick solid's sheets can follow), and less the points no smooth correction should chase
(`reachable`).

φ and its derivatives are read from tables by compiled kernels (kelvin.py); φ's Hessian has a
log r singularity at each centre, as the thin-plate spline's; ∇²c (curvatures only) reads its
radial parts at no less than HESSIAN_CUT of the length, so a mesh vertex that falls on a vein
point gets a finite curvature.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import partial

import numpy as np
import scipy.linalg

from leafstudio.core.bending import Bending, bending_gram, lattice, least_bending
from leafstudio.core.buckets import kernel_array
from leafstudio.core.grid import Grid
from leafstudio.core.kelvin import (
    KELVIN,
    KELVIN_STEP,
    phi_at,
    phi_matrix,
    spline_derivatives,
    spline_value,
)
from leafstudio.core.mpu import MPUImplicit
from leafstudio.core.prepare.polygon import thin_curve
from leafstudio.core.surface import HeightSurface, taper_of

CENTER_STEP = 0.008  # vein points closer than this share of the length are one spline centre
VEIN_SMOOTHING = 1e-9  # λ (φ is dimensionless: φ(0) = π/4)
BAND = 0.5  # T below this: the margin band, where a vein point close enough is left as it is
CLOSE_ENOUGH = 2e-4  # of the length: a band point this close to the surface needs no pinning
HESSIAN_CUT = 1e-3  # ∇²φ's radial parts are read at max(r, this share of the length)
REACH = 0.1  # ℓ, of the length: the correction fades as e^(−r/ℓ√2) past the veins (0.05: a
# drawn leaf's margin band 9.1° against the paper's 8.3°; 0.3: reniform's lobes 1.44° against 1.36°)
JUNCTION = 0.011  # of the length: a vein's points this near an earlier vein's are left to it
OVERSHOOT = 6.0  # T·c beyond this many times the largest residual is no smooth correction
# (the gallery's forms: 0.62-1.21 times; a drawn leaf with hand-raised veins 2.8; a fan of
# basal veins from a sinus's notch into narrow lobes 17)
TOLERANCE = 4e-4  # of the length: each vein point may stay this far off the surface when that
# lets the spline bend less (_within)
BAND_TOLERANCE = 7e-4  # ... and this far in the margin band (T < BAND), see the module
POWER_STEPS = 12
RELAX_STEPS = 40
CHECKED = 2000  # nodes at most where the correction is checked (_tame)
MOST_CENTERS = 800  # beyond this the veins are thinned further: the dense solve grows as its
# cube (3000 centres took seconds a run; the app reruns this on every slider step)

#: (target, lo, hi, spline) -> values in [lo, hi]: how fit_correction chooses its values
Choose = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]


def _phi_among(centers: np.ndarray, reach: float) -> np.ndarray:
    """(m, m) φ(|v_i − v_j| / ℓ) between the (m, 2) spline centres."""
    return phi_at(np.sqrt(((centers[:, None, :] - centers[None, :, :]) ** 2).sum(axis=2)) / reach)


@dataclass(frozen=True)
class VeinCorrection:
    """c(x) = Σ_j w_j φ(|x − v_j|), φ(r) = −kei(r/ℓ): the correction inside the taper."""

    centers: np.ndarray  # (m, 2) spline centres on the veins
    weights: np.ndarray  # (m,) w_j
    reach: float  # ℓ
    cut: float  # the radius, over ℓ, below which ∇²φ's radial parts are not read (HESSIAN_CUT)

    def value(self, xy: np.ndarray) -> np.ndarray:
        """c at (n, 2) plane points."""
        xy = kernel_array(np.atleast_2d(np.asarray(xy, dtype=float)))
        return spline_value(xy, self.centers, self.weights, self.reach, KELVIN, KELVIN_STEP)

    def derivatives(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """c (n,), ∇c (n, 2) and ∇²c (n, 2, 2) in closed form: with d = x − v, r = |d| and
        ρ = r/ℓ, ∇φ = φ'(r) d/r and ∇²φ = φ'' d dᵀ/r² + φ'/r (I − d dᵀ/r²), where φ' = −kei'(ρ)/ℓ
        and φ'' = −(ker(ρ) − kei'(ρ)/ρ)/ℓ² (read at ρ no less than `cut`)."""
        xy = kernel_array(np.atleast_2d(np.asarray(xy, dtype=float)))
        return spline_derivatives(
            xy, self.centers, self.weights, self.reach, self.cut, KELVIN, KELVIN_STEP
        )


def _thin_vein(vein: np.ndarray, step: float) -> np.ndarray:
    """Indices of a vein's (m, 2) points at least `step` apart along it, its end kept in place
    of the point before it when that lies within half a step (two centres a hair apart with
    different residuals take opposite weights of thousands: a spike beside the vein's end)."""
    kept = thin_curve(vein, step, keep_end=True)
    if len(kept) > 2 and np.linalg.norm(vein[kept[-1]] - vein[kept[-2]]) < 0.5 * step:
        kept = np.delete(kept, -2)
    return kept


def spline_centers(veins: list[np.ndarray], length: float) -> list[np.ndarray]:
    """Indices kept of each vein's (m_i, 2) points: at least CENTER_STEP · length apart along it
    (polygon.thin_curve), at most MOST_CENTERS in all, none within JUNCTION · length of an
    earlier vein's."""
    step = CENTER_STEP * length
    kept = [_thin_vein(v, step) for v in veins]
    total = sum(len(k) for k in kept)
    if total > MOST_CENTERS:
        step *= total / MOST_CENTERS
        kept = [_thin_vein(v, step) for v in veins]
    laid = np.zeros((0, 2))
    reach = (JUNCTION * length) ** 2
    for i, vein in enumerate(veins):  # at a junction the earlier (longer) vein decides
        if len(laid):  # all pairs: a k-d tree per vein took 1.6 ms on a gallery form
            apart = ((vein[kept[i], None, :] - laid[None, :, :]) ** 2).sum(axis=2)
            kept[i] = kept[i][~np.any(apart < reach, axis=1)]
        laid = np.vstack([laid, vein[kept[i]]])
    return kept


def reachable(
    taper: np.ndarray,
    residual: np.ndarray,
    relief: float,
    length: float,
    stretch: np.ndarray | float = 1.0,
    settle: bool = True,
) -> np.ndarray:
    """(m,) bool: the vein points the spline is made to pass through.

    Left out: a point that only a correction higher than the veins' own relief could reach
    (|r| > relief · T: a vein raised next to the margin, which z = b there cannot follow without
    a spike), and a point in the margin band (T < BAND) that is already within CLOSE_ENOUGH of the
    length (a thin tip's midrib: pinning it there only sharpens the tip), over its `stretch`
    (onto_veins); unless not `settle` (a correction chosen for the whole surface's bending,
    bending.py, moves the surface there too).
    """
    spike = np.abs(residual) > relief * taper
    close = CLOSE_ENOUGH * length / stretch if settle else -1.0
    settled = (taper < BAND) & (np.abs(residual) <= close)
    return (taper > 0) & ~spike & ~settled


def fit_correction(
    centers: np.ndarray,
    taper: np.ndarray,
    residual: np.ndarray,
    length: float,
    stretch: np.ndarray | float = 1.0,
    choose: Choose | None = None,
    among: np.ndarray | None = None,
) -> VeinCorrection | None:
    """The spline c with T_i c(v_i) within TOLERANCE of r_i at the vein points (BAND_TOLERANCE
    in the margin band; over their `stretch`, onto_veins), bending least: c itself, or, given
    `choose`, what it chooses (the whole surface's bending, bending.py).

    Parameters
    ----------
    centers : (m, 2) float array
        Vein points in the plane (spline_centers).
    taper : (m,) float array
        T(g/δ) there, in [0, 1].
    residual : (m,) float array
        h_i − T_i M(v_i): what the mixture leaves to correct.
    length : float
        The leaf's length (λ and the Hessian's cut-off scale with it).
    stretch : (m,) float array or float, default 1
        How many times a distance off the surface grows at each point when the blade is bent.
    choose : callable, optional
        (target, lo, hi, spline) -> values in [lo, hi], with `spline` the (m, m) weights per
        unit value (S⁻¹ diag(T²)); default `_within`.
    among : (m, m) float array, optional
        φ between the centres, when known (the pipeline's bending stage has it).

    Returns
    -------
    VeinCorrection, or None when no vein point lies inside the margin.
    """
    inside = taper > 0
    if np.count_nonzero(inside) < 3:
        return None
    reach = REACH * length
    phi = _phi_among(centers, reach) if among is None else among
    m = len(centers)
    t2 = taper**2
    system = t2[:, None] * phi
    system[np.diag_indices(m)] += VEIN_SMOOTHING
    try:
        factors = scipy.linalg.lu_factor(system, check_finite=False)
    except (np.linalg.LinAlgError, ValueError):
        return None

    def spline_of(values: np.ndarray) -> np.ndarray:  # w with T_i c(v_i) = T_i values_i
        return scipy.linalg.lu_solve(factors, t2 * values)

    target = np.divide(residual, taper, out=np.zeros(m), where=taper > 0)
    # the band's wider tolerance is a flat blade's: where a bend stretches a distance off it,
    # that is shrunk once more (a rolled and folded deltoid's veins 1.04e-3 of the length off)
    tolerance = np.where(taper < BAND, BAND_TOLERANCE / stretch, TOLERANCE)
    slack = tolerance * length / (np.maximum(taper, 1e-3) * stretch)
    if choose is None:
        values = _within(target, slack, spline_of)
    else:  # the spline's weights per unit value: S⁻¹ diag(T²)
        spline = scipy.linalg.lu_solve(factors, np.diag(t2), check_finite=False)
        values = choose(target, target - slack, target + slack, spline)
    weights = spline_of(values)
    if not np.all(np.isfinite(weights)):
        return None
    return VeinCorrection(
        centers=kernel_array(centers),
        weights=weights,
        reach=reach,
        cut=HESSIAN_CUT / REACH,
    )


def _within(
    target: np.ndarray, slack: np.ndarray, spline_of: Callable[[np.ndarray], np.ndarray]
) -> np.ndarray:
    """(m,) values within `slack` of `target` whose spline bends least, nearly: projected
    gradient steps (FISTA) on the bending energy vᵀ K v, whose gradient is the spline's weights
    (`spline_of`, one back-substitution). The stiffest bends go first: a ridge the spline drew
    tight onto a vein (a form's midrib, where side veins stand on a roof 14° each side) is
    widened while every vein point stays within the slack."""

    def weights(values: np.ndarray) -> np.ndarray:
        return spline_of(values)[: len(values)]

    probe = np.random.default_rng(0).standard_normal(len(target))
    for _ in range(POWER_STEPS):  # the largest eigenvalue of K: the step
        probe = weights(probe)
        largest = float(np.linalg.norm(probe))
        if not np.isfinite(largest) or largest == 0:
            return target
        probe /= largest
    lo, hi = target - slack, target + slack
    values = previous = ahead = target
    momentum = 1.0
    for _ in range(RELAX_STEPS):
        values = np.clip(ahead - weights(ahead) / largest, lo, hi)
        following = 0.5 * (1 + np.sqrt(1 + 4 * momentum**2))
        ahead = values + (momentum - 1) / following * (values - previous)
        previous, momentum = values, following
    return values


@dataclass(frozen=True)
class Pinning:
    """The spline's centres on the veins and, given the grid's nodes, the lattice their
    correction bends least on: what onto_veins needs that K does not change (the pipeline's
    bending stage)."""

    kept: list[np.ndarray]  # indices of each vein's points that are centres (spline_centers)
    centers: np.ndarray  # (m, 2)
    taper: np.ndarray  # (m,) T(g/δ) at the centres
    bending: Bending | None  # the lattice (bending.py), with φ for every centre


def pinning(
    veins: list[np.ndarray],
    length: float,
    implicit: MPUImplicit,
    delta: float,
    grid: Grid | None = None,
    inside: np.ndarray | None = None,
    node_taper: np.ndarray | None = None,
) -> Pinning:
    """The spline's centres on the (m_i, 2) `veins` and T there (T = tanh(g/δ)), and, given the
    grid, its nodes inside the leaf ((ny * nx,) bool) and T there, the lattice of them with φ
    and the bending gram for every centre (bending.py)."""
    kept = spline_centers(veins, length)
    centers = np.vstack([v[k] for v, k in zip(veins, kept, strict=True)])
    centers = kernel_array(centers)
    taper = taper_of(implicit(centers), delta)
    if grid is None or inside is None or node_taper is None:
        return Pinning(kept, centers, taper, None)
    index = np.flatnonzero(inside)
    on, differences = lattice(grid, index, node_taper)
    reach = REACH * length
    lattice_taper = kernel_array(node_taper[on])
    phi, tapered = phi_matrix(
        kernel_array(grid.points[index[on]]), centers, reach, KELVIN, KELVIN_STEP, lattice_taper
    )
    gram = bending_gram(tapered, differences)
    among = phi_matrix(centers, centers, reach, KELVIN, KELVIN_STEP, np.ones(len(centers)))[0]
    return Pinning(kept, centers, taper, Bending(on, lattice_taper, differences, phi, gram, among))


def onto_veins(
    surface: HeightSurface,
    heights: list[np.ndarray],
    length: float,
    pinned: Pinning,
    nodes: tuple[np.ndarray, np.ndarray] | None = None,
    stretch: list[np.ndarray] | None = None,
) -> tuple[HeightSurface, np.ndarray | None]:
    """`surface` with a VeinCorrection that brings it onto the vein points, and c at the nodes
    when the correction was chosen for the whole surface's bending (on the lattice from its φ).

    Parameters
    ----------
    surface : HeightSurface
        The fitted surface (no correction yet).
    heights : list of (m_i,) float arrays
        Each vein's points' heights above the base.
    length : float
        The leaf's length.
    pinned : Pinning
        The spline's centres (`pinning` of the veins in the plane) and their lattice.
    nodes : ((n, 2), (n,)) float arrays, optional
        Points inside the leaf and T(g/δ) there, where the correction is checked: a correction
        that adds more than OVERSHOOT times the largest residual anywhere is refitted without
        the vein points of the margin band, and dropped if it still does (see `_tame`).
    stretch : list of (m_i,) float arrays, optional
        How many times the leaf's bend lengthens a distance off the blade at each vein point
        (bend.normal_stretch, at least 1): a fold on a rolled tube shears its section, and a
        vein point TOLERANCE off the flat surface stood up to 3.9 times that off the bent mesh.
        Each point's tolerance is divided by it.
    """
    kept, centers, taper, bending = pinned.kept, pinned.centers, pinned.taper, pinned.bending
    h = np.concatenate([z[k] for z, k in zip(heights, kept, strict=True)])
    residual = h - taper * surface.relief(centers)
    relief = float(np.abs(h).max())
    grows = (
        np.ones(len(h))
        if stretch is None
        else np.concatenate([s[k] for s, k in zip(stretch, kept, strict=True)])
    )
    relief_on = None if bending is None else surface.relief(nodes[0][bending.on])
    keep = reachable(taper, residual, relief, length, grows, settle=bending is None)
    for pins in (keep, keep & (taper >= BAND)):
        if bending is None:
            correction = fit_correction(
                centers[pins], taper[pins], residual[pins], length, grows[pins]
            )
        else:
            some = bending.pinned(pins)
            correction = fit_correction(
                centers[pins], taper[pins], residual[pins], length, grows[pins],
                partial(least_bending, some, relief_on), some.among,
            )  # fmt: skip
        if correction is None:
            return surface, None
        largest = np.abs(residual[pins]).max()
        if bending is not None:  # c on the lattice from its φ; checked there
            on_lattice = some.phi @ correction.weights
            if np.all(np.abs(bending.taper * on_lattice) <= OVERSHOOT * largest):
                corrected = replace(surface, correction=correction)
                return corrected, _at_nodes(correction, nodes[0], bending.on, on_lattice)
        elif nodes is None or _tame(correction, nodes, largest):
            return replace(surface, correction=correction), None
    return surface, None


def _at_nodes(
    correction: VeinCorrection, xy: np.ndarray, on: np.ndarray, on_lattice: np.ndarray
) -> np.ndarray:
    """c at the (n, 2) nodes `xy`, known at those of them `on` the lattice."""
    value = np.empty(len(xy))
    value[on] = on_lattice
    rest = np.ones(len(xy), dtype=bool)
    rest[on] = False
    value[rest] = correction.value(xy[rest])
    return value


def _tame(correction: VeinCorrection, nodes: tuple[np.ndarray, np.ndarray], largest: float) -> bool:
    """Whether T·c stays within OVERSHOOT times the largest residual it corrects at the nodes.

    Pinned points of the margin band (T small, so c must be r/T there) whose r/T differ a lot
    over a short way (a short basal vein in a narrow lobe, a notch) tilt the spline's affine part
    steeply: a fan of veins from a sinus's notch bent the apex down 25 times the veins' relief,
    for residuals under 1% of the length."""
    xy, taper = nodes
    every = max(1, len(xy) // CHECKED)  # a tilt is as wide as the blade: a sample finds it
    tilt = taper[::every] * correction.value(xy[::every])
    return bool(np.all(np.abs(tilt) <= OVERSHOOT * largest))
