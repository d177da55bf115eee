"""The vein correction's values chosen for the whole surface's bending (issue 21, item 4).

correct.py brings the height surface onto the vein points with a spline c, each value c(v_i)
free within a tolerance. Chosen so that c alone bends least (projected gradient steps on c's
own energy, as it first was), the surface through the veins still creased more than the paper's
pure GMM surface on some rows of `bench_bent.py --veins` (99th-percentile dihedral: deltoid's
margin band 2.35° against 2.19°, a drawn leaf's 8.54° against 8.32°, linear's 7.81° against
7.78°): c bent least where the mixture bent most. Here the values are chosen within the same
tolerances so that the surface itself, z = T · (M + c) over the grid's nodes inside the leaf,
bends least: the sum of its squared second differences (xx, yy and the cross difference) on a
lattice of the nodes (`lattice`: finer in the margin band), with c's own bending added at
OWN_BENDING of the lattice's measure of it (the bends between the lattice's nodes). c is
linear in its values (the spline's weights are one solve of them), so this is a small quadratic
program in the values, box-constrained, solved by projected gradient steps (FISTA) from the
residuals themselves (starting from c's own least-bending values changed nothing). The margin
band's 99th-percentile dihedral falls below the paper's surface on every gallery form
(lanceolate 3.17° -> 1.73°, deltoid 1.90° -> 1.82°), and its inside on all but oblanceolate's
(2.94° against 2.85°: correct.py); solved once more with the sharpest bends weighed more
(sharpest), oblanceolate's too (2.74°).

Farther in than the margin band the lattice takes every second of its nodes, its differences over
two of its steps (four grid steps on the sketch the app's story clicks, tests/leaves.
clicked_sketch, 0.031 of its length): a bend narrower than that goes unseen, and the values,
CENTER_STEP apart along the veins (0.008 there), were free to make one. Where a side vein leaves
the midrib they did: the largest dihedral within 0.03 of the length of a side vein's start was
4.38° against the paper's 1.63°, and the sketch's 99th-percentile interior dihedral 1.58° against
1.49°; on ovate folded 60° (grid 64) the same crease beside the midrib at a side vein's start, k2
5.12, where the paper's bends at most 3.45 off its midrib. c's own energy, ∫ (Δc)² + c²/ℓ⁴
over the plane, sees every bend of c: with it 1.73°, 1.485° and 3.34. (The lattice at one step
everywhere, without it, left 1.74° but 1.496° inside, a vein's end creasing between its nodes, and
grew a rolled grass blade's area: a lanceolate of aspect 30 is four grid steps wide, its relief
0.004 of the length against the tube's radius 0.005, and its rolled area over its flat went 0.999
-> 1.031, the paper's surface 0.992, the form's own 0.980.) c's own energy also charges the
counter-bend by which c took out the mixture's own near the midrib's apex end: there, on ovate flat
at grid 64, k2 5.58 -> 5.86 (the paper's surface 8.55).

What K does not change, the lattice, φ at its nodes and the gram (Bending), is the pipeline's
bending stage (correct.pinning), kept when only K moves; the surface stage solves the program
with it, and c at the lattice's nodes, φ times the weights, serves the overshoot check and z
there. Its cost against the paper's surface through the veins as main had it (2026-12-03, grid
128, one BLAS thread, CPU time of a run, main and this alternated 60 times, min / median): the
nested demo cold 50.0 / 59.8 ms against 48.9 / 59.2, after a K change 22.6 / 27.3 against
26.4 / 34.3; ovate cold 94.6 / 114.6 against 88.2 / 106.4 (7% over: 21 more centres, those of
the band already close enough, pinned here, make the mesh stage's curvatures 14% dearer), after
a K change 51.4 / 61.0 against 56.0 / 67.4.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse

from leafstudio.core.buckets import kernel_array
from leafstudio.core.grid import Grid
from leafstudio.core.jit import njit

LATTICE_NODES = 2500  # grid nodes, about, on the lattice whose bending is summed
FINE = 0.97  # T below this: the margin band, where the lattice is finer (see lattice; 0.8 and 0.6
# took 0.6 and 1.2 ms off the correction's 9.9 on a flat ovate at grid 128, each with one more
# --variants row rougher than the paper's surface: linear lobed, oblanceolate serrate)
POWER_STEPS = 20  # power steps for the largest eigenvalue of the normal matrix
# c's own bending, ∫ (Δc)² + c²/ℓ⁴ = (2π/ℓ²) wᵀΦw, is added at this share of the lattice's measure
# of it (the lattice's sum over a step h stands for h² ∫ c_xx² + c_yy² + 4 c_xy², own_weight).
# bench_bent --veins (16 rows) and --variants (84), rows rougher than the paper's surface, and
# the clicked sketch's interior against its 1.488°: 0: 4 and 29 (1.582°); 0.1: 1.491°; 0.15:
# 2 and 20 (1.485°); 0.2: 1.480°; 0.25: 2 and 25 (1.483°), a serrate orbicular's margin band
# 13.79° -> 14.99° against the paper's 14.92° (0.2: 14.90°; tests/core/test_correct.py); 0.5: 2
# and 34, 1: 3 and 41 (c's own bending alone, as it first was, made margin bands rougher)
OWN_BENDING = 0.15
SHARP = 90  # percentile of the rows' bends: a row bending more weighs more (sharpest)
HEAVIEST = 3.0  # ... at most this many times the rows' mean weight
# c's own energy is weighed up with the rows' mean weight in that second solve, and by this much
# more: weighed more, the sharpest rows pull the values toward bends between the lattice's nodes,
# which only c's own energy sees (the largest dihedral within 0.03 of the length of a side vein's
# start on the clicked sketch, tests/core/test_correct.py: 1.73° as it was, the paper's 1.63°; 0:
# 1.95°; 0.5: 1.83°; 1: 1.75°; 2: 1.77°, a drawn leaf's inside 8.64°)
SHARP_OWN = 1.0
STEPS = 25  # projected gradient steps, of each of least_bending's two solves (one solve of 50,
# as it first was, and 100: the same bench_bent --veins rows, 0.01° apart; two of 50, before
# SHARP_OWN: the same rows within 0.03°, --variants 16 rows rougher than the paper's either way)


@dataclass(frozen=True)
class Bending:
    """What the surface's bending on the lattice needs that K does not change (the pipeline's
    bending stage: moving K reruns only `least_bending`'s solve, not these)."""

    on: np.ndarray  # (n,) the grid nodes inside the leaf that are on the lattice
    taper: np.ndarray  # (n,) T(g/δ) there
    differences: scipy.sparse.csr_matrix  # (r, n) D, single precision
    phi: np.ndarray  # (n, m) φ(|x − v_j| / ℓ) there for each spline centre v_j
    gram: np.ndarray  # (m, m) (TΦ)ᵀ DᵀD (TΦ), from single precision
    among: np.ndarray  # (m, m) φ(|v_i − v_j| / ℓ) between the centres
    own: float  # the weight of c's own energy wᵀΦw beside the gram: own_weight
    tapered: np.ndarray  # (n, m) TΦ in single precision: the gram's factor (least_bending)

    def pinned(self, pins: np.ndarray) -> Bending:
        """The same for the centres where the (m,) bool `pins` is set (no copy when all are)."""
        if pins.all():
            return self
        cross = np.ix_(pins, pins)
        return replace(
            self,
            phi=self.phi[:, pins],
            gram=self.gram[cross],
            among=self.among[cross],
            tapered=np.ascontiguousarray(self.tapered[:, pins]),
        )


def lattice(
    grid: Grid, index: np.ndarray, taper: np.ndarray
) -> tuple[np.ndarray, scipy.sparse.csr_matrix, float]:
    """Which of the grid's nodes at the (n,) flat indices `index` (row-major, grid.points's
    order) are kept on the lattice, as positions in `index`, the second differences between
    them, (rows, kept) sparse, one row per direction (x, y, and the cross difference) wherever
    all its nodes are kept, and the lattice's step h in the plane. In the margin band (T < FINE)
    the lattice takes every stride-th row and column from the nodes' lowest (stride so that
    about LATTICE_NODES would be kept over the whole blade), farther in every second of those:
    the surface bends most where the taper brings it down (a stride of 3 left margin bands
    rougher than the paper's surface), and the solve's cost grows with the nodes (the bends
    between the nodes farther in: OWN_BENDING). The rows are laid out straight in compressed form (a
    fixed count of entries per row: building D through scipy's coordinate form took 3 of the
    nested demo's 3.7 ms at grid 128)."""
    stride = max(1, round(float(np.sqrt(len(index) / LATTICE_NODES))))
    step = stride * grid.spacing
    on, at = _lattice_cells(
        np.asarray(index, dtype=np.int64), int(grid.shape[1]), stride, kernel_array(taper)
    )
    if len(on) == 0:
        return on, scipy.sparse.csr_matrix((0, 0), dtype=np.float32), step
    band = taper[on] < FINE
    even = (at[:, 0] | at[:, 1]) % 2 == 0
    coarse = ~band & even
    width = int(at[:, 1].max()) + 5
    number = np.full((int(at[:, 0].max()) + 5) * width, -1, dtype=np.int64)
    flat = (at[:, 0] + 2) * width + at[:, 1] + 2
    number[flat] = np.arange(len(on))  # two rings of -1 around it
    # farther in, a difference over twice the step is four times one over the step, and stands
    # for four of them: weighed by 2 / 4
    # on a blade small on the grid (stride 1) the band's differences are taken at every second
    # node each way, each standing for four (weighed by 2): the same rows' figures, a quarter of
    # the rows (the nested demo's gram at grid 128: 3.5 -> 1 ms; at stride 2 too, 0.9 ms less on a
    # flat ovate at grid 128, but the clicked sketch's inside went 1.49° -> 1.50°, past the paper's)
    fine = (band & even, 2.0) if stride == 1 else (band, 1.0)
    reached, values, row_sizes = _stencil_rows(flat, number, width, fine[0], fine[1], coarse)
    used = np.zeros(len(on), dtype=bool)  # the nodes the rows reach, numbered again
    used[reached] = True
    renumbered = np.cumsum(used) - 1
    differences = scipy.sparse.csr_matrix(
        (
            values.astype(np.float32),
            renumbered[reached],
            np.concatenate([[0], np.cumsum(row_sizes)]),
        ),
        shape=(len(row_sizes), int(used.sum())),
    )
    return on[used], differences, step


@njit(cache=True, nogil=True)
def _lattice_cells(index, nx, stride, taper):
    """The positions in the (n,) flat indices `index` (rows of `nx`) of the nodes on the lattice,
    every stride-th row and column from all the nodes' lowest (T > 0 or not), those where T > 0,
    and their (k, 2) column and row over the stride (numpy's dozen whole-array steps took 0.11 ms
    of lattice's 0.37 on a flat ovate at grid 128, best of 200; the same nodes, integers)."""
    n = len(index)
    row_min, column_min = np.iinfo(np.int64).max, np.iinfo(np.int64).max
    for i in range(n):
        row_min = min(row_min, index[i] // nx)
        column_min = min(column_min, index[i] % nx)
    on = np.empty(n, np.int64)
    count = 0
    for i in range(n):
        row, column = index[i] // nx - row_min, index[i] % nx - column_min
        if row % stride == 0 and column % stride == 0 and taper[i] > 0:
            on[count] = i
            count += 1
    at = np.empty((count, 2), np.int64)
    for s in range(count):
        at[s, 0] = (index[on[s]] % nx - column_min) // stride
        at[s, 1] = (index[on[s]] // nx - row_min) // stride
    return on[:count], at


def own_weight(step: float, reach: float) -> float:
    """μ, the weight of c's own energy wᵀΦw beside the lattice's bending (least_bending):
    ∫ (Δc)² + c²/ℓ⁴ = (2π/ℓ²) wᵀΦw (φ = −kei(r/ℓ) is 2π/ℓ² times the Green's function of
    Δ² + ℓ⁻⁴), and the lattice's sum over a `step` h stands for h² times its integral, so
    μ = OWN_BENDING · 2π h² / ℓ² for the reach ℓ."""
    return OWN_BENDING * 2 * np.pi * (step / reach) ** 2


STENCILS = (  # (offsets in rows and columns, coefficients) of each second difference
    (np.array([(1, 0), (0, 0), (-1, 0)]), np.array([1.0, -2.0, 1.0])),
    (np.array([(0, 1), (0, 0), (0, -1)]), np.array([1.0, -2.0, 1.0])),
    (np.array([(1, 1), (-1, -1), (1, -1), (-1, 1)]), np.array([0.5, 0.5, -0.5, -0.5])),
)


# the stencils' entries one after another: offsets in rows and columns, and coefficients
STENCIL_OFFSETS = np.vstack([offsets for offsets, _ in STENCILS])
STENCIL_COEFFICIENTS = np.concatenate([coefficients for _, coefficients in STENCILS])
STENCIL_STARTS = np.cumsum([0] + [len(offsets) for offsets, _ in STENCILS])


def _stencil_rows(
    flat: np.ndarray,
    number: np.ndarray,
    width: int,
    fine: np.ndarray,
    fine_scale: float,
    coarse: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """D's rows (lattice): the lattice's numbers of their nodes, their coefficients and their
    sizes, one after another: each stencil's rows over one step from the (n,) bool `fine`
    nodes (weighed by `fine_scale`), then over two steps from the `coarse` ones (weighed by
    0.5), each where all its nodes are on the lattice (`number`, -1 off it, at the nodes' flat
    places `flat` in rows of `width`)."""
    return _rows(
        flat,
        number,
        width,
        (fine, coarse),
        np.array([1, 2]),
        np.array([fine_scale, 0.5]),
        STENCIL_OFFSETS,
        STENCIL_COEFFICIENTS,
        STENCIL_STARTS,
    )


@njit(cache=True, nogil=True)
def _rows(flat, number, width, centres, reaches, scales, offsets, coefficients, starts):
    """_stencil_rows in one compiled pass, rows in the same order (numpy's index arrays, a
    stencil and a reach at a time, took 0.27 ms of lattice's 0.52 on ovate at grid 128, line
    timing of 200 calls; this 0.07 ms, best of 200; lattice 0.40 -> 0.28 ms, best of 60, two
    pairs; D and the nodes the same to the bit on every gallery form at grids 32-200)."""
    most = 2 * len(flat) * len(coefficients)
    reached = np.empty(most, dtype=np.int64)
    values = np.empty(most)
    sizes = np.empty(2 * len(flat) * (len(starts) - 1), dtype=np.int64)
    entries, rows = 0, 0
    for s in range(len(reaches)):
        centre, reach, scale = centres[s], reaches[s], scales[s]
        for q in range(len(starts) - 1):
            for i in range(len(flat)):
                if not centre[i]:
                    continue
                kept = True
                for e in range(starts[q], starts[q + 1]):
                    step = reach * (offsets[e, 0] * width + offsets[e, 1])
                    if number[flat[i] + step] < 0:
                        kept = False
                        break
                if not kept:
                    continue
                for e in range(starts[q], starts[q + 1]):
                    step = reach * (offsets[e, 0] * width + offsets[e, 1])
                    reached[entries] = number[flat[i] + step]
                    values[entries] = scale * coefficients[e]
                    entries += 1
                sizes[rows] = starts[q + 1] - starts[q]
                rows += 1
    return reached[:entries], values[:entries], sizes[:rows]


def bending_gram(tapered: np.ndarray, differences: scipy.sparse.csr_matrix) -> np.ndarray:
    """(m, m) (D T Φ)ᵀ (D T Φ) for the (n, m) single precision `tapered` TΦ at the lattice's
    nodes (single precision: half the time for the same bench_bent rows). As (DTΦ)ᵀ(DTΦ), r m²
    products, when the r rows are fewer than the nodes (the band's rows sampled, lattice), else
    as (TΦ)ᵀ (DᵀD TΦ), n m² (ovate at grid 128: r = 4249, n = 1603, 3.1 -> 1.2 ms; BLAS's
    product runs at its peak either way)."""
    if differences.shape[0] <= differences.shape[1]:
        bends = np.asarray(differences @ tapered)
        return (bends.T @ bends).astype(float)
    d = differences
    return (tapered.T @ _bend_twice(d.indptr, d.indices, d.data, tapered)).astype(float)


@njit(cache=True, nogil=True)
def _bend_twice(indptr, indices, data, x):
    """Dᵀ D x for the (r, n) compressed rows (indptr, indices, data) of D and the (n, m) x, a
    row of D x at a time (scipy's D @ x, then Dᵀ @ that: 2.8 ms on ovate at grid 128 with an
    (r, m) temporary; this, 1.3 ms)."""
    n, m = x.shape
    out = np.zeros((n, m), dtype=np.float32)
    row = np.empty(m, dtype=np.float32)
    for r in range(len(indptr) - 1):
        for j in range(m):
            row[j] = 0.0
        for e in range(indptr[r], indptr[r + 1]):
            weight, node = data[e], indices[e]
            for j in range(m):
                row[j] += weight * x[node, j]
        for e in range(indptr[r], indptr[r + 1]):
            weight, node = data[e], indices[e]
            for j in range(m):
                out[node, j] += weight * row[j]
    return out


def least_bending(
    bending: Bending,
    relief: np.ndarray,
    start: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    spline: np.ndarray,
) -> np.ndarray:
    """(m,) values in [lo, hi] from `start` for which T · (M + c) bends least on the lattice,
    then again with its sharpest bends weighed more (sharpest).

    Parameters
    ----------
    bending : Bending
        The lattice, with φ and the gram of the m centres the values are for (Bending.pinned).
    relief : (n,) float array
        M, the mixture alone, at the lattice's nodes.
    start, lo, hi : (m,) float arrays
        The values to start from and their bounds.
    spline : (m, m) float array
        The spline's weights per unit value at each vein point (c on the lattice: phi @ spline).

    The normal matrix is Sᵀ G S with G the bending gram (Bending.gram), and μ S for c's own
    energy: with S = Φ⁻¹ (the spline's λ aside), wᵀΦw = vᵀ S v. Every value is free within its
    bounds: moved only as a broken line through every second centre's (a program half the size),
    a drawn leaf's margin band went 8.46° -> 8.93° (bench_bent --veins), cordate's 1.17° -> 1.33°.
    """
    d, taper = bending.differences, bending.taper
    normal = spline.T @ bending.gram @ spline
    # in place: the steps read A by rows, and S, from LAPACK, is in column order (A + μS came out
    # in column order: _projected_steps 0.36 -> 2.1 ms at ovate's 200 centres)
    normal += bending.own * spline
    tapered = (taper * relief).astype(np.float32)
    # Dᵀ D T M by scipy's two products: Dᵀ's reads D's rows in order, as _bend_twice does, and
    # the same bits (_bend_twice on one column, a loop of one per entry: 0.092 ms on a flat ovate
    # at grid 128; this 0.038, best of 200; /work/notes/perf38/micro_alt.py)
    bends = d.T @ (d @ tapered)
    shift = spline.T @ (bending.phi.T @ (taper * bends))
    values = _projected_steps(normal, shift, start, lo, hi, STEPS)
    surface = taper * (relief + bending.phi @ (spline @ values))
    rows, extra, more = sharpest(d @ surface.astype(np.float32))
    if len(rows) == 0:
        return values
    root = np.sqrt(extra).astype(np.float32)[:, None]
    sharp, sharp_relief = _rows_times(d.indptr, d.indices, d.data, rows, bending.tapered, tapered)
    # (k, m): D T Φ S at those rows, times their extra weight's root, in single precision as the
    # gram (in double: 1.37 of the 2.8 ms the second solve added on a flat ovate at grid 128)
    bent = root * (sharp @ spline.astype(np.float32))
    normal += bent.T @ bent  # (BLAS's syrk, half the products, then mirrored: 0.33 ms, this 0.23)
    normal += (more + SHARP_OWN) * bending.own * spline
    shift += bent.T @ (root[:, 0] * sharp_relief)
    return _projected_steps(normal, shift, values, lo, hi, STEPS)


@njit(cache=True, nogil=True)
def _rows_times(indptr, indices, data, rows, x, v):
    """(D[rows] x, D[rows] v) for the (r, n) compressed rows (indptr, indices, data) of D, the
    (n, m) x and the (n,) v, each row's sum in D's order from 0 as scipy's products add them,
    in x's and v's single precision (scipy's row slice D[rows] and its two products: 0.10 ms at
    a flat ovate's 425 sharpest rows at grid 128, this 0.03 (/work/notes/cpu39/micro_rows.py);
    the same bits)."""
    m = x.shape[1]
    out = np.zeros((len(rows), m), dtype=np.float32)
    line = np.zeros(len(rows), dtype=np.float32)
    for k in range(len(rows)):
        total = np.float32(0.0)
        for e in range(indptr[rows[k]], indptr[rows[k] + 1]):
            weight, node = data[e], indices[e]
            for j in range(m):
                out[k, j] += weight * x[node, j]
            total += weight * v[node]
        line[k] = total
    return out, line


def sharpest(bends: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """The lattice's rows bending more than the SHARP-th percentile s of all, the weight each
    takes on beside its 1, (b/s)² (the whole at most HEAVIEST times the rows' mean weight), and
    how much that mean grew, both before the cap (least_bending weighs c's own energy up by as
    much: the capped rows' mean grows less, on the gallery forms 0 to 0.17 less, oblong's 1.191
    against 1.358; review37).

    A squared sum weighs a bend b by b², these rows by b² (1 + (b/s)²), nearer b⁴: the values
    are chosen against the few sharp bends that the 99th-percentile dihedral counts, not only the
    many gentle ones. bench_bent --veins, oblanceolate's inside, the one row rougher than the
    paper's surface: 2.94° -> 2.74° against 2.85°, every row as smooth or smoother (margin bands
    rougher than before but not than the paper's: lanceolate 1.73° -> 2.06° against 3.17°; a
    drawn leaf's 8.00° -> 7.88°, its inside 8.59° -> 8.63° against 8.32° and 9.01°); --variants,
    21 of 84 rougher than the paper's surface in a band (20 before), by 3.72° in all, not 4.51°;
    the forms over every 7th pose, own surface worst p95 1.68e-3 -> 1.62e-3, median 6.99e-4 ->
    6.58e-4. Every row weighed 1 + (b/s)², over their mean, at most 3: 2.82°, but the gram made
    again (2.8 ms more on a flat ovate at grid 128); weighed from the start values, without the
    first solve: 2.87°; every row weighed and no HEAVIEST, 20 rougher variants by 4.08°."""
    size = np.abs(bends)
    sharp = _percentile(size, SHARP) if len(bends) else 0.0
    if not np.isfinite(sharp) or sharp <= 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0), 0.0
    rows = np.flatnonzero(size > sharp)
    extra = (bends[rows].astype(float) / sharp) ** 2
    more = float(extra.sum()) / len(bends)
    return rows, np.minimum(extra, HEAVIEST * (1 + more) - 1), more


def _percentile(a: np.ndarray, q: float) -> float:
    """float(np.percentile(a, q)) of a non-empty (n,) `a`, its 'linear' method as numpy computes
    it (the two neighbours of (n − 1) q/100 by a partition, then numpy's _lerp in a's dtype; NaN
    when a has one): np.percentile's glue took 0.09 ms of sharpest on a flat ovate's 4249 rows at
    grid 128, this 0.02, best of 7 x 500; the same value on 20000 random float32 arrays of 1 to
    6000, ties and NaN among them (/work/notes/cpu39/micro_pct.py)."""
    n = len(a)
    virtual = (n - 1) * (q / 100)
    below = float(np.floor(virtual))
    gamma = virtual - below  # a Python float: weak beside a's dtype, as numpy's own is
    lo, hi = (n - 1, n - 1) if virtual >= n - 1 else (int(below), int(below) + 1)
    part = np.partition(a, (lo, hi))
    if np.isnan(a.max()):
        return float("nan")
    low, high = part[lo], part[hi]
    diff = high - low
    return float(high - diff * (1 - gamma) if gamma >= 0.5 else low + diff * gamma)


@njit(cache=True, nogil=True, fastmath=True)
def _matvec(matrix, x, out):
    """out = A x for the (m, m) `matrix` A, each row's sum in vector lanes (fastmath: 0.32 ->
    0.23 ms for _projected_steps' 70 products at 200 centres)."""
    for i in range(len(out)):
        total = 0.0
        for j in range(len(x)):
            total += matrix[i, j] * x[j]
        out[i] = total


@njit(cache=True, nogil=True)
def _projected_steps(normal, shift, start, lo, hi, steps):
    """The box-constrained minimum of ½ vᵀAv + shiftᵀv from `start` (A = `normal`): the largest
    eigenvalue by POWER_STEPS power steps, then `steps` projected gradient steps with Nesterov's
    momentum (FISTA); `start` itself when A has no finite positive eigenvalue. Compiled whole:
    the loop's numpy calls took 0.7 of least_bending's 1.35 ms on a flat ovate at grid 128
    (200 centres, best of 60); compiled, least_bending takes 1.07 ms."""
    m = len(start)
    probe, moved = np.ones(m), np.empty(m)
    largest = 0.0
    for _ in range(POWER_STEPS):  # the largest eigenvalue (A is positive semi-definite)
        _matvec(normal, probe, moved)
        total = 0.0
        for i in range(m):
            total += moved[i] * moved[i]
        largest = np.sqrt(total)
        if not np.isfinite(largest) or largest <= 0:
            return start.copy()
        for i in range(m):
            probe[i] = moved[i] / largest
    largest *= 1.1  # the power steps come from below
    values, previous, ahead = start.copy(), start.copy(), start.copy()
    momentum = 1.0
    for _ in range(steps):
        _matvec(normal, ahead, moved)
        following = 0.5 * (1 + np.sqrt(1 + 4 * momentum**2))
        pull = (momentum - 1) / following
        for i in range(m):
            values[i] = min(max(ahead[i] - (moved[i] + shift[i]) / largest, lo[i]), hi[i])
        for i in range(m):
            ahead[i] = values[i] + pull * (values[i] - previous[i])
            previous[i] = values[i]
        momentum = following
    return values
