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
1.21°; the reniform form pinnate, as it then was: palmate, its usual venation, 1.04° against
1.23°).
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
TOLERANCE / T_i of r_i / T_i, and the values are chosen so that the whole surface, T · (M + c)
on a lattice of the grid's nodes, bends least (bending.py): c bends against the mixture's own
bends. Chosen for c's own bending alone, ovate's 99th-percentile interior dihedral went 5.0° ->
4.6° and oblong's 6.4° -> 5.8°, but c bent least where the mixture bent most (deltoid's margin
band 2.35° against the paper's 2.19°). In the margin band (T_i < BAND) the tolerance is
BAND_TOLERANCE: there the surface comes down to the margin within a short way, and a vein point
held tight beside a corner or a raised vein end bends the spline just where the taper creases
(p99 margin dihedral at BAND_TOLERANCE = TOLERANCE, c's own bending: deltoid 2.45°, spatulate
2.45°, a drawn leaf's 8.84°, its inside 9.15°; then 2.35°, 2.37°, 8.54°, 9.10°). Where the
blade is bent, that wider tolerance is divided by the bend's stretch once more (fit_correction).
bench_bent --veins, 99th-percentile dihedral against the paper's surface, margin band: linear
7.09° (7.78°), deltoid 1.82° (1.90°), orbicular 0.84° (0.87°), a drawn leaf's 8.00° (8.32°;
8.46° before its raised veins' ends had free centres, vein_centers.free_centers: no gallery
form has such an end, the parallel demo 8 free centres, its band 5.38° -> 4.75° against 5.35°
and inside 3.86° -> 3.56° against 3.93°, soybean pot1_1 one, its mesh moved 0.1 mm); every gallery
form's margin band and inside but oblanceolate's inside (2.94° against 2.85°) as smooth or
smoother, and the clicked sketch's (tests/leaves.clicked_sketch: 1.57° and 1.485° against 1.70°
and 1.488°, bending.py); every vein point within 8e-4 of the length; 20 of the 84 apex and
margin variants (--variants) rougher in a band, none off by more than 1e-3 (solved again with
the sharpest bends weighed more, bending.sharpest, oblanceolate's inside is 2.74°).
Oblanceolate's own surface, the dome its veins lie on, is itself rougher inside than the
paper's (2.98°): its roughest edges lie beside the midrib where the blade narrows (0.3-0.5 of
the length from the base, within 0.02 of the length of a vein), which the paper's surface
rounds within 7.8e-4 of its veins; through them within TOLERANCE the surface bends as its dome
does (TOLERANCE 7e-4: 2.87°, 9e-4: 2.84° but a drawn leaf's and linear's veins 1.1e-3 off the
mesh). The points of the band already close to the surface are pinned too: the surface moves
there as well.

The spline's centres are the vein points thinned and chosen by vein_centers.py, less the points
no smooth correction should chase (`reachable`), and a few on no vein about a vein's end that
stands steeply above the margin band (vein_centers.free_centers), free in value.

φ and its derivatives are read from tables by compiled kernels (kelvin.py); φ's Hessian has a
log r singularity at each centre, as the thin-plate spline's; ∇²c (curvatures only) reads its
radial parts at no less than HESSIAN_CUT of the length, so a mesh vertex that falls on a vein
point gets a finite curvature.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg
import scipy.linalg.lapack

from leafstudio.core.bending import Bending, bending_gram, lattice, least_bending, own_weight
from leafstudio.core.buckets import kernel_array
from leafstudio.core.grid import Grid
from leafstudio.core.kelvin import (
    KEI,
    KELVIN,
    KELVIN_STEP,
    phi_matrix,
    spline_derivatives,
    spline_gradient,
    spline_value,
)
from leafstudio.core.mpu import MPUImplicit
from leafstudio.core.surface import HeightSurface, taper_of
from leafstudio.core.vein_centers import BAND, free_centers, spline_centers

VEIN_SMOOTHING = 1e-9  # λ (φ is dimensionless: φ(0) = π/4)
HESSIAN_CUT = 1e-3  # ∇²φ's radial parts are read at max(r, this share of the length)
REACH = 0.1  # ℓ, of the length: the correction fades as e^(−r/ℓ√2) past the veins (0.05: a
# drawn leaf's margin band 9.1° against the paper's 8.3°; 0.3: reniform's lobes 1.44° against 1.36°)
OVERSHOOT = 6.0  # T·c beyond this many times the largest residual is no smooth correction
# (the gallery's forms: 0.62-1.21 times; a drawn leaf with hand-raised veins 2.8; a fan of
# basal veins from a sinus's notch into narrow lobes 17)
TOLERANCE = 4e-4  # of the length: each vein point may stay this far off the surface when that
# lets the surface bend less (bending.least_bending)
BAND_TOLERANCE = 7e-4  # ... and this far in the margin band (T < BAND), see the module


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
        return spline_value(xy, self.centers, self.weights, self.reach, KEI, KELVIN_STEP)

    def value_and_gradient(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """c (n,) and ∇c (n, 2) at (n, 2) plane points, as `derivatives` gives them, without
        ∇²c (the margin's points, where the taper's T = 0 multiplies it: kelvin.spline_gradient,
        0.62 -> 0.36 ms at a flat ovate's 502 outline points at grid 128)."""
        xy = kernel_array(np.atleast_2d(np.asarray(xy, dtype=float)))
        return spline_gradient(xy, self.centers, self.weights, self.reach, KELVIN, KELVIN_STEP)

    def derivatives(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """c (n,), ∇c (n, 2) and ∇²c (n, 2, 2) in closed form: with d = x − v, r = |d| and
        ρ = r/ℓ, ∇φ = φ'(r) d/r and ∇²φ = φ'' d dᵀ/r² + φ'/r (I − d dᵀ/r²), where φ' = −kei'(ρ)/ℓ
        and φ'' = −(ker(ρ) − kei'(ρ)/ρ)/ℓ² (read at ρ no less than `cut`)."""
        xy = kernel_array(np.atleast_2d(np.asarray(xy, dtype=float)))
        return spline_derivatives(
            xy, self.centers, self.weights, self.reach, self.cut, KELVIN, KELVIN_STEP
        )


def reachable(taper: np.ndarray, residual: np.ndarray, relief: float) -> np.ndarray:
    """(m,) bool: the vein points the spline is made to pass through: those inside the margin
    (T > 0) but a point that only a correction higher than the veins' own relief could reach
    (|r| > relief · T: a vein raised next to the margin, which z = b there cannot follow without
    a spike). A point of the margin band already close to the surface is pinned too: the
    values are chosen for the whole surface's bending (bending.py), which moves it there too."""
    return (taper > 0) & ~(np.abs(residual) > relief * taper)


def fit_correction(
    centers: np.ndarray,
    taper: np.ndarray,
    residual: np.ndarray,
    length: float,
    stretch: np.ndarray | float,
    bending: Bending,
    relief: np.ndarray,
    free: np.ndarray | None = None,
) -> VeinCorrection | None:
    """The spline c with T_i c(v_i) within TOLERANCE of r_i at the vein points (BAND_TOLERANCE
    in the margin band; over their `stretch`, onto_veins), chosen so that the whole surface,
    T · (M + c), bends least on the lattice (bending.least_bending).

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
    stretch : (m,) float array or float
        How many times a distance off the surface grows at each point when the blade is bent
        (1: not bent).
    bending : Bending
        The lattice, with φ, the gram and φ between the centres, for these m centres
        (Bending.pinned).
    relief : (n,) float array
        M, the mixture alone, at the lattice's nodes.
    free : (m,) bool array, optional
        Centres on no vein (free_centers): their values are unbounded, from 0.

    Returns
    -------
    VeinCorrection, or None when no vein point lies inside the margin.
    """
    inside = taper > 0
    if np.count_nonzero(inside) < 3:
        return None
    m = len(centers)
    # the rows T_i² (Φ w)_i + λ w_i = T_i² values_i give w_i = 0 where T_i = 0 and elsewhere
    # w = S values, S = P⁻¹ with P = Φ + λ T⁻² symmetric positive definite: S from P's
    # Cholesky factor (an LU factor's solve of diag(T²) and the two products took 1.41 ms at
    # 200 centres, a flat ovate at grid 128; this 1.14 ms, best of 80)
    some = bending.pinned(inside)
    system = some.among.copy()
    # the diagonal as every (m + 1)-th of the flat entries (np.diag_indices_from's index arrays:
    # 0.029 -> 0.012 ms at a flat ovate's 200 centres, best of 200, the same bits)
    system.flat[:: len(system) + 1] += VEIN_SMOOTHING / taper[inside] ** 2
    factor, info = scipy.linalg.lapack.dpotrf(system, lower=1)
    if info == 0:
        inverse, info = scipy.linalg.lapack.dpotri(factor, lower=1, overwrite_c=1)
    if info == 0:  # its lower triangle mirrored (np.tril of both: 0.13 ms, this 0.06)
        np.copyto(inverse, inverse.T, where=np.tri(len(inverse), k=-1, dtype=bool).T)
    else:  # P not positive definite in floating point (φ is cut at KELVIN_END): LU, as before
        try:
            inverse = scipy.linalg.inv(system, check_finite=False)
        except (np.linalg.LinAlgError, ValueError):
            return None
    spline = inverse
    target = np.divide(residual, taper, out=np.zeros(m), where=inside)
    # the band's wider tolerance is a flat blade's: where a bend stretches a distance off it,
    # that is shrunk once more (a rolled and folded deltoid's veins 1.04e-3 of the length off)
    tolerance = np.where(taper < BAND, BAND_TOLERANCE / stretch, TOLERANCE)
    slack = tolerance * length / (np.maximum(taper, 1e-3) * stretch)
    if free is not None:
        slack = np.where(free, np.inf, slack)
    slack = slack[inside]
    start = target[inside]
    values = least_bending(some, relief, start, start - slack, start + slack, spline)
    weights = np.zeros(m)
    weights[inside] = spline @ values
    if not np.all(np.isfinite(weights)):
        return None
    return VeinCorrection(
        centers=kernel_array(centers),
        weights=weights,
        reach=REACH * length,
        cut=HESSIAN_CUT / REACH,
    )


@dataclass(frozen=True)
class Pinning:
    """The spline's centres on the veins and the lattice their correction bends least on: what
    onto_veins needs that K does not change (the pipeline's bending stage)."""

    kept: list[np.ndarray]  # indices of each vein's points that are centres (spline_centers)
    centers: np.ndarray  # (m, 2)
    taper: np.ndarray  # (m,) T(g/δ) at the centres
    bending: Bending  # the lattice (bending.py), with φ for every centre
    disagree: tuple[tuple[int, int, float], ...] = ()  # veins steeper apart than STEEPEST
    free: int = 0  # the last `free` centres lie on no vein: their values are free (free_centers)
    # T at the grid's nodes inside the leaf, as the surface stage takes it too (its tanh over a
    # flat ovate's 6895 nodes at grid 128: 0.02-0.035 ms, twice there; steps.compute_surface)
    node_taper: np.ndarray | None = None
    # g at every vein point, the veins one after another (pinning), as the surface stage reads it
    vein_g: np.ndarray | None = None

    def notes(self, length: float) -> list[str]:
        """What the leaf is told of veins that disagree where they meet (one note: a steeply
        folded blade given in 3D and left unbent meets its midrib so at every side vein)."""
        if not self.disagree:
            return []
        later, earlier, apart = max(self.disagree, key=lambda pair: pair[2])
        where = f"veins {earlier + 1} and {later + 1} meet {apart / length:.1%} of the length apart"
        if len(self.disagree) > 1:
            places = len(self.disagree)
            where = f"veins meet at different heights in {places} places (most: {where})"
        else:
            where += " in height"
        return [f"{where}: the surface follows the earlier vein there"]


def lattice_bending(
    centers: np.ndarray, length: float, grid: Grid, inside: np.ndarray, node_taper: np.ndarray
) -> Bending:
    """The lattice of the grid's nodes inside the leaf ((ny * nx,) bool `inside`, T there
    `node_taper`) with φ there and the bending gram for each of the (m, 2) `centers`, and φ
    between the centres (bending.py)."""
    index = np.flatnonzero(inside)
    on, differences, step = lattice(grid, index, node_taper)
    reach = REACH * length
    taper = kernel_array(node_taper[on])
    xy = kernel_array(grid.points.take(index[on], axis=0))  # [index[on]]: 8 times as long
    phi, tapered = phi_matrix(xy, centers, reach, KEI, KELVIN_STEP, taper)
    gram = bending_gram(tapered, differences)
    among = phi_matrix(centers, centers, reach, KEI, KELVIN_STEP, np.ones(len(centers)))[0]
    own = own_weight(step, reach)
    return Bending(on, taper, differences, phi, gram, among, own, tapered)


def pinning(
    veins: list[np.ndarray],
    heights: list[np.ndarray],
    length: float,
    implicit: MPUImplicit,
    delta: float,
    grid: Grid,
    inside: np.ndarray,
    node_taper: np.ndarray,
) -> Pinning:
    """The spline's centres on the (m_i, 2) `veins` (their points' `heights`: spline_centers), T
    there (T = tanh(g/δ)), and the lattice of the grid's nodes inside the leaf ((ny * nx,) bool
    `inside`, T there `node_taper`) with φ and the bending gram for every centre
    (lattice_bending)."""
    kept, disagree = spline_centers(
        veins, length, heights, lambda xy: taper_of(implicit(xy), delta)
    )
    on_veins = np.vstack([v[k] for v, k in zip(veins, kept, strict=True)])
    # g at every vein point once, read for the veins' ends, the centres on the veins and the
    # surface stage's vein rows: g is read point by point, so a subset's is the same to the bit
    # (the implicit's three calls at a flat ovate's 26 ends, 200 centres and 212 vein points
    # took 40, 59 and 73 us, best of 7 x 200, most of it each call's own glue; one call now)
    vein_g = implicit(kernel_array(np.vstack(veins)))
    starts = np.cumsum([0] + [len(v) for v in veins])
    ends = np.array([i for a, b in itertools.pairwise(starts) if b > a for i in (a, b - 1)])
    free = free_centers(
        veins, heights, on_veins, length, implicit, delta, vein_g[ends.astype(np.int64)]
    )
    on_g = vein_g[np.concatenate([a + k for a, k in zip(starts[:-1], kept, strict=True)])]
    g = np.concatenate([on_g, implicit(kernel_array(free))]) if len(free) else on_g
    centers = kernel_array(np.vstack([on_veins, free]))
    taper = taper_of(g, delta)
    bending = lattice_bending(centers, length, grid, inside, node_taper)
    return Pinning(kept, centers, taper, bending, tuple(disagree), len(free), node_taper, vein_g)


def onto_veins(
    surface: HeightSurface,
    heights: list[np.ndarray],
    length: float,
    pinned: Pinning,
    nodes: np.ndarray,
    mixture: np.ndarray,
    stretch: list[np.ndarray] | None = None,
) -> tuple[HeightSurface, np.ndarray | None]:
    """`surface` with a VeinCorrection that brings it onto the vein points, and c at the nodes
    (on the lattice from its φ); `surface` itself and None when no correction holds.

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
    nodes : (n, 2) float array
        The grid's nodes inside the leaf (those `pinned`'s lattice was made of). On the lattice,
        a correction that adds more than OVERSHOOT times the largest residual is refitted
        without the vein points of the margin band, and dropped if it still does: pinned points
        of the band (T small, so c must be r/T there) whose r/T differ a lot over a short way
        (a short basal vein in a narrow lobe, a notch) bent the apex down 25 times the veins'
        relief (a fan of veins from a sinus's notch), for residuals under 1% of the length.
    mixture : (n,) float array
        M, the mixture alone, at the nodes (the surface stage has it: z there takes it too).
    stretch : list of (m_i,) float arrays, optional
        How many times the leaf's bend lengthens a distance off the blade at each vein point
        (carried.normal_stretch, at least 1): a fold on a rolled tube turns its rolled section
        about the midrib as if it were flat, and a vein point TOLERANCE off the flat surface
        stands up to 1.4 times that off the bent mesh (3.9 when the fold was a shear). Each
        point's tolerance is divided by it.
    """
    kept, centers, taper, bending = pinned.kept, pinned.centers, pinned.taper, pinned.bending
    free = np.arange(len(centers)) >= len(centers) - pinned.free
    h = np.zeros(len(centers))
    h[~free] = np.concatenate([z[k] for z, k in zip(heights, kept, strict=True)])
    residual = np.where(free, 0.0, h - taper * surface.relief(centers))
    relief = float(np.abs(h).max())
    grows = np.ones(len(h))
    if stretch is not None:
        grows[~free] = np.concatenate([s[k] for s, k in zip(stretch, kept, strict=True)])
    relief_on = mixture[bending.on]
    keep = reachable(taper, residual, relief) | free
    for pins in (keep, keep & (taper >= BAND) & ~free):
        some = bending.pinned(pins)
        correction = fit_correction(
            centers[pins],
            taper[pins],
            residual[pins],
            length,
            grows[pins],
            some,
            relief_on,
            free[pins],
        )
        if correction is None:
            return surface, None
        largest = np.abs(residual[pins]).max()
        on_lattice = some.phi @ correction.weights  # c on the lattice from its φ; checked there
        if np.all(np.abs(bending.taper * on_lattice) <= OVERSHOOT * largest):
            corrected = replace(surface, correction=correction)
            return corrected, _at_nodes(correction, nodes, bending.on, on_lattice)
    return surface, None


def _at_nodes(
    correction: VeinCorrection, xy: np.ndarray, on: np.ndarray, on_lattice: np.ndarray
) -> np.ndarray:
    """c at the (n, 2) nodes `xy`, known at those of them `on` the lattice. The others take the
    kernel too: cubic interpolation over the lattice's two grid steps was off by 6e-5 of the
    length on a flat ovate at grid 128 (4e-3 on a drawn leaf), still 1e-6 eight steps from every
    centre, and node_derivatives' differences over one step made that 0.29 of curvature at the
    99th percentile, against c_xx's own 1.59."""
    value = np.empty(len(xy))
    value[on] = on_lattice
    rest = np.ones(len(xy), dtype=bool)
    rest[on] = False
    value[rest] = correction.value(xy.compress(rest, axis=0))  # xy[rest]: 8 times as long
    return value
