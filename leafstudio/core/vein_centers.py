"""Where the vein correction's spline has its centres (correct.py): the vein points thinned
along each vein (CENTER_STEP), less those of a later vein within JUNCTION of an earlier one
(where a side vein leaves the midrib, the two disagree by a little within a grid cell, and
meeting both bent the surface into a ridge tighter than a thick solid's sheets can follow) or
steeper than STEEPEST from one (two veins drawn across each other at different heights: the
result names them, correct.Pinning.notes); and a few centres on no vein about a vein's end that
stands steeply above the margin (free_centers), whose values the surface's bending chooses.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from leafstudio.core.buckets import kernel_array
from leafstudio.core.jit import njit
from leafstudio.core.mpu import MPUImplicit
from leafstudio.core.prepare.polygon import thin_curve
from leafstudio.core.surface import taper_of

CENTER_STEP = 0.008  # vein points closer than this share of the length are one spline centre
# (a drawn or clicked leaf's, 0.006-0.009 apart; a form's are 0.02 apart and all kept: at 0.03,
# every other one, the correction took 6.0 ms of a flat ovate's CPU at grid 128, not 9.9, but 46 of
# the 84 --variants left a vein point beyond 1e-3 of the length, a drawn leaf's 5.0e-3)
BAND = 0.5  # T below this: the margin band, where a vein point close enough is left as it is
JUNCTION = 0.011  # of the length: a vein's points this near an earlier vein's are left to it
STEEPEST = 1.0  # ... and those near one (within MEETS) whose height differs from it by more
# than this times their distance and by more than APART: two veins drawn across each other at
# different heights (a bowed midrib over a basal vein, 0.052 of the length apart where they cross)
# made the correction a wall between them, a triangle edge 5.1 grid cells long in 3D
# (tests/core/test_sinus.py)
MEETS = 3 * JUNCTION  # of the length: compared at any distance, a steep but consistent blade
# (a waved, curled form given in 3D, left unbent) lost up to 144 centres and named 20 pairs
APART = 0.02  # of the length: a side vein drawn to start 1.2% below a raised midrib is no
# disagreement; nor one noisy point of a scan's vein (soybean pot1_1, 3.8% off its neighbours
# at 0.038 of the length from another vein)
STEEP_END = 0.5  # a vein's end in the margin band that stands higher than this times its distance
# to the margin gets FREE_SPOKES free centres FREE_RING of the length around it (free_centers):
# the gallery's forms rise 0.32 at most, a clicked sketch's 0.31, a drawn leaf's raised side
# veins 1.0 and 2.0
FREE_RING = 0.03  # of the length (0.02: a drawn leaf's margin band 8.35° against the paper's
# 8.32°; 0.025 8.22°, 0.03 8.00°, 0.035 7.88°: bench_bent --veins)
FREE_SPOKES = 6  # around each steep end (5: 8.02°, 8: 8.19°)
FREE_TAPER = 0.02  # T at a free centre no less than this: nearer the margin T · c is nothing
MOST_CENTERS = 800  # beyond this the veins are thinned further: the dense solve grows as its
# cube (3000 centres took seconds a run; the app reruns this on every slider step)


def _thin_vein(vein: np.ndarray, step: float) -> np.ndarray:
    """Indices of a vein's (m, 2) points at least `step` apart along it, its end kept in place
    of the point before it when that lies within half a step (two centres a hair apart with
    different residuals take opposite weights of thousands: a spike beside the vein's end)."""
    kept = thin_curve(vein, step, keep_end=True)
    if len(kept) > 2 and np.linalg.norm(vein[kept[-1]] - vein[kept[-2]]) < 0.5 * step:
        kept = np.delete(kept, -2)
    return kept


def spline_centers(
    veins: list[np.ndarray],
    length: float,
    heights: list[np.ndarray] | None = None,
    taper: Callable[[np.ndarray], np.ndarray] | None = None,
) -> tuple[list[np.ndarray], list[tuple[int, int, float]]]:
    """Indices kept of each vein's (m_i, 2) points: at least CENTER_STEP · length apart along it
    (polygon.thin_curve), at most MOST_CENTERS in all, none within JUNCTION · length of an
    earlier vein's, nor (given each point's height, (m_i,) `heights`) steeper than STEEPEST
    from one; and the veins that disagreed so, (later, earlier, largest height difference),
    where the later's point lies inward of the margin band (T at (n, 2) points, `taper`, no less
    than BAND): in the band the surface comes down to the margin and follows neither vein (a
    basal vein rising steeply along a sinus's margin from the notch, beside the midrib's start,
    T under 0.03 there, was named)."""
    step = CENTER_STEP * length
    kept = [_thin_vein(v, step) for v in veins]
    total = sum(len(k) for k in kept)
    if total > MOST_CENTERS:
        step *= total / MOST_CENTERS
        kept = [_thin_vein(v, step) for v in veins]
    # at a junction the earlier (longer) vein decides (a k-d tree per vein took 1.6 ms on a
    # gallery form; the pairs vein by vein, 0.69 ms in all; all pairs at once in numpy, 0.29 ms;
    # compiled, each point against the points kept before it, 0.017 ms, best of 60: a flat
    # ovate at grid 128, 13 veins, 212 points thinned; spline_centers 0.29 -> 0.12 ms; the
    # same centres on every gallery form at four lengths)
    points = kernel_array(np.vstack([v[k] for v, k in zip(veins, kept, strict=True)]))
    sizes = np.array([len(k) for k in kept], dtype=np.int64)
    if heights is None:
        h = np.zeros(len(points))
    else:
        h = np.concatenate([z[k] for z, k in zip(heights, kept, strict=True)]).astype(float)
    reaches = np.array([JUNCTION, MEETS, APART]) * length
    laid, against, gap2 = _clear_of_earlier(points, h, sizes, reaches, STEEPEST)
    starts = np.concatenate([[0], np.cumsum(sizes)])
    owner = np.repeat(np.arange(len(veins)), sizes)
    nearest: dict[tuple[int, int], tuple[float, float]] = {}  # (gap², height apart) where nearest
    steep = np.flatnonzero(against >= 0)
    if taper is not None and len(steep):
        steep = steep[taper(points[steep]) >= BAND]
    for i in steep:
        pair, here = (int(owner[i]), int(owner[against[i]])), (gap2[i], abs(h[i] - h[against[i]]))
        nearest[pair] = min(nearest.get(pair, here), here)
    disagree = [(later, earlier, apart) for (later, earlier), (_, apart) in sorted(nearest.items())]
    kept = [k[laid[a:b]] for k, a, b in zip(kept, starts[:-1], starts[1:], strict=True)]
    return kept, disagree


def free_centers(
    veins: list[np.ndarray],
    heights: list[np.ndarray],
    on_veins: np.ndarray,
    length: float,
    implicit: MPUImplicit,
    delta: float,
    end_g: np.ndarray | None = None,
) -> np.ndarray:
    """(f, 2) spline centres on no vein, FREE_SPOKES of them FREE_RING · length around each
    end of the (m_i, 2) `veins` that lies in the margin band (T < BAND) and stands higher above
    the base (its `heights`) than STEEP_END times its distance to the margin (g): none nearer
    than half the ring to a centre on a vein (`on_veins`) or to each other, none where T is
    under FREE_TAPER.

    With centres on the veins alone, the spline must lift such an end by r/T (T about 0.1 ten
    grid cells from the margin) as a bump about it, which the taper then pulls down to the
    margin beside it: a drawn leaf's side vein 0.020 of the length high 0.010 from the margin
    creased its margin band (99th-percentile dihedral 8.46° against the paper's 8.32°) and its
    inside (9.04° against 9.01°). The free centres' values are chosen with the others for the
    whole surface's bending (bending.least_bending, unbounded), so the climb from the margin
    to the end is shaped, not left to one bump: 8.00° and 8.59° (bench_bent --veins). Forms
    and gently raised sketches have no such end and are unchanged. `end_g`: g at those ends
    (each vein's first and last point), if known."""
    ends = np.array([v[i] for v in veins if len(v) for i in (0, -1)]).reshape(-1, 2)
    rise = np.array([abs(z[i]) for z in heights if len(z) for i in (0, -1)])
    g = end_g if end_g is not None else implicit(ends) if len(ends) else np.zeros(0)
    steep = (taper_of(g, delta) < BAND) & (rise > STEEP_END * np.maximum(g, 0.0))
    if not steep.any():
        return np.zeros((0, 2))
    turns = np.linspace(0.0, 2 * np.pi, FREE_SPOKES, endpoint=False)
    ring = FREE_RING * length * np.column_stack([np.cos(turns), np.sin(turns)])
    spokes = (ends[steep][:, None, :] + ring[None]).reshape(-1, 2)
    spokes = spokes[taper_of(implicit(spokes), delta) >= FREE_TAPER]
    apart = 0.5 * FREE_RING * length
    free: list[np.ndarray] = []
    for point in spokes:  # a few dozen at most: each against the centres kept
        if np.linalg.norm(on_veins - point, axis=1).min(initial=np.inf) < apart:
            continue
        if free and np.linalg.norm(np.array(free) - point, axis=1).min() < apart:
            continue
        free.append(point)
    return np.array(free).reshape(-1, 2)


@njit(cache=True, nogil=True)
def _clear_of_earlier(points, heights, sizes, reaches, steepest):
    """(n,) bool: the (n, 2) `points`, veins of `sizes` points one after another, that lie no
    nearer than reaches[0] to a point of an earlier vein that is itself kept, nor within
    reaches[1] of one and more than reaches[2] and `steepest` times their distance apart in
    height; (n,) the nearest earlier point a point was that steep from (-1: none), and (n,) its
    squared distance."""
    near2, meets2, apart = reaches[0] ** 2, reaches[1] ** 2, reaches[2]
    laid = np.zeros(len(points), dtype=np.bool_)
    against = np.full(len(points), -1, dtype=np.int64)
    gap2 = np.full(len(points), np.inf)
    start = 0
    for size in sizes:
        for i in range(start, start + size):
            clear = True
            for j in range(start):
                if laid[j]:
                    dx, dy = points[i, 0] - points[j, 0], points[i, 1] - points[j, 1]
                    distance2 = dx * dx + dy * dy
                    if distance2 < near2:
                        clear = False
                        against[i] = -1
                        break
                    rise = abs(heights[i] - heights[j])
                    steep = rise > apart and rise * rise > steepest * steepest * distance2
                    if distance2 < meets2 and steep and distance2 < gap2[i]:
                        clear = False
                        against[i], gap2[i] = j, distance2
            laid[i] = clear
        start += size
    return laid, against, gap2
