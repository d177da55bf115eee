"""Do points trace a curve or cover a surface? `surface_spread`, by which the pipeline refuses a
whole scan given where a leaf's boundary belongs (plausibility.check_not_a_surface).

Round a few hundred of the points, a neighbourhood of COVER_REACH of the cloud's length holds a
piece of curve (its second spread is small beside its largest) or a patch of surface (the two are
alike); the median of that ratio over the neighbourhoods is the measure. The length and width are
the straight (principal) extents, and the neighbourhood is capped at COVER_WIDTH of the width, so
that a narrow blade's two margins fall in separate ones.

A bent or curled narrow blade is as wide across, straight, as its bend: its two margins can share
a neighbourhood, and a bent strip scanned whole can look like a curve. Two looks inside each
neighbourhood take the blade's own width instead:
- two strands: points that part into two line-like groups with one clear gap between them are a
  narrow blade's two margins, and count at their strands' spread (a filled patch does not part; a
  striped scan's lines part into many groups, not two);
- a narrow band: points that fill a band narrower than their neighbourhood evenly (flat across
  it, where a noisy curve's spread is bell-shaped) are measured again at the band's scale.

Points too sparse for a neighbourhood of that reach to hold a few (a 400-point blob, a
hemisphere's points) are judged point by point instead (`filled_share`): inside an area a point's
nearest neighbours surround it; on an outline they lie ahead and behind.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from leafstudio.core.plane import fixed_sample, principal_extents

COVER_REACH = 0.05  # the neighbourhood of a point: this share of the length round it,
COVER_WIDTH = 0.25  # or this share of the width if less, so that a narrow blade's two margins
# (20-30 times longer than wide) never fall in one neighbourhood and look like a surface
COVER_SPREAD = 0.45  # median ratio of the two largest spreads in it: a curve's is near 0 (noise
# of 1% of the length: 0.11, of 2%: 0.35; teeth: at most 0.12), a surface's near 1 (the real
# scans: 0.73 to 0.86, a quarter of their points 0.53 to 0.73; benchmarks/bench_plausibility.py)
COVER_CENTRES = 500  # neighbourhoods measured
COVER_POINTS = 5000  # points they are taken from, at most
COVER_LEAST = 8  # a neighbourhood with fewer points is not measured (a sparse outline)
# two strands, in a neighbourhood whose ratio is over STRAND_LINE
STRAND_POINTS = 64  # points of a neighbourhood looked at, at most
STRAND_DIRECTIONS = 8  # directions across it tried first for the gap between two strands
STRAND_SHARE = 0.1  # each strand holds at least this share of the points
STRAND_SECOND = 0.5  # any other gap in between is under this share of the widest (not stripes)
STRAND_APART = 3.0  # the strands' centres lie this many times their summed spreads apart
STRAND_LINE = 0.25  # each strand's own spread ratio is under this (a line, not half a patch)
# a narrow band (a bent strip scanned whole read 0.12-0.28 without this look)
BAND_WIDTH = (0.2, 0.7)  # the band's width, a share of the neighbourhood's diameter
BAND_FLAT = 2.1  # kurtosis across it at most (filled evenly: 1.8, a noisy curve: 3)
BAND_CLOSER = 0.35  # measured again within this share of the band's width round the centre
BAND_LEAST = 32  # points a neighbourhood needs for that (a kurtosis of fewer is unsure)
# too sparse for that (filled_share): points with neighbours on every side
FILL_NEAREST = 8  # a point's nearest neighbours looked at
FILL_GAP = np.radians(120)  # surrounded: no wider gap between its neighbours' directions
FILL_FROM = 100  # fewer distinct points are not judged: at 60, real scans thinned (0.20) and
# noisy outlines (0.20) meet. From 150 before: a real scan thinned to 100 points was read as a
# boundary (soybean pot1_15: a mesh of 0.37 of the blade's area, perimeter 2.2 times its own)
SPREAD_FROM = 150  # a cloud of fewer points is asked its filled share too, whatever its spread:
# a real scan thinned to 100 points can hold enough in its neighbourhoods for a spread, and
# sugar beet pot1_1's was 0.40-0.47 (a curve's, under COVER_SPREAD), its share 0.30-0.42;
# outlines of 100-300 points with noise up to 0.5% of the length: shares at most 0.15
FILL_SHARE = 0.2  # more of the points surrounded: they fill an area. benchmarks/bench_fill.py,
# from 150 points: outlines at most 0.13 (every form's shape and margin subsampled to 150-300
# points, in order, shuffled, noise up to 0.5% of the length; the scans' extracted boundaries
# 0.07), areas at least 0.28 (a real scan thinned to 150 points; points inside a narrow form
# 0.29; discs, hemispheres, caps, flattened blobs 0.35-0.54); with noise of 1% of the length, 4
# outlines of 294 pass it (up to 0.31): such a sparse cloud is a band as wide as its spacing.
# From 100 points (bench_fill.py, 100-300): outlines at most 0.15 with noise up to 0.5% (a
# linear lobed form at 120), 13 of 490 refused with noise of 1% (up to 0.27; 6 of 98 at 100,
# 4 of 98 at 150); real scans thinned at least 0.22; points inside a linear form 0.20, let
# through


@dataclass(frozen=True)
class _Neighbourhoods:
    """The points within reach of each of m centres, one neighbourhood after the other.

    local: (N, 3) the points, in units of the reach round their centre; owner: (N,) whose;
    starts, sizes: (m,) where each begins and how many it holds (at least its centre);
    mean, spread: (m, 3) the mean and the variances along the principal axes (ascending);
    axes: (m, 3, 3) those axes as columns.
    """

    local: np.ndarray
    owner: np.ndarray
    starts: np.ndarray
    sizes: np.ndarray
    mean: np.ndarray
    spread: np.ndarray
    axes: np.ndarray


def _ratio(spread: np.ndarray) -> np.ndarray:
    """The second largest of ascending variances (..., 3) over the largest."""
    return spread[..., 1] / np.maximum(spread[..., 2], 1e-300)


def _moments(local: np.ndarray, owner: np.ndarray, m: int):
    """The count, mean (m, 3) and covariance (m, 3, 3) of the points (n, 3) of each of m
    groups (`owner`: (n,) each point's)."""
    count = np.bincount(owner, minlength=m)
    share = 1.0 / np.maximum(count, 1)
    mean = np.column_stack([np.bincount(owner, local[:, i], m) for i in range(3)]) * share[:, None]
    covariance = np.empty((m, 3, 3))
    for i in range(3):
        for j in range(i, 3):
            moment = np.bincount(owner, local[:, i] * local[:, j], m) * share
            covariance[:, i, j] = covariance[:, j, i] = moment - mean[:, i] * mean[:, j]
    return count, mean, covariance


def _neighbourhoods(points: np.ndarray, centres: np.ndarray, reach: float) -> _Neighbourhoods:
    """The points within `reach` of each centre, and their principal spreads."""
    pairs = cKDTree(centres).sparse_distance_matrix(
        cKDTree(points), reach, output_type="ndarray"
    )  # one array, several times faster than query_ball_point's lists
    order = np.argsort(pairs["i"], kind="stable")
    owner = pairs["i"][order]
    # rows by take: numpy's fancy index of these (n, 3) arrays took 4 times as long (0.18 ms)
    local = (points.take(pairs["j"][order], axis=0) - centres.take(owner, axis=0)) / reach
    sizes, mean, covariance = _moments(local, owner, len(centres))
    spread, axes = np.linalg.eigh(covariance)
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    return _Neighbourhoods(local, owner, starts, sizes, mean, spread, axes)


def _padded(near: _Neighbourhoods, chosen: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """At most STRAND_POINTS points of each chosen neighbourhood (evenly through its list) as a
    (m, STRAND_POINTS, 3) array, zero past each one's own, and the mask of its own."""
    starts, sizes = near.starts[chosen], near.sizes[chosen]
    step = np.maximum(1, -(-sizes // STRAND_POINTS))  # ceil
    slot = np.arange(STRAND_POINTS)
    mask = slot[None, :] < -(-sizes // step)[:, None]
    index = starts[:, None] + np.where(mask, slot[None, :] * step[:, None], 0)
    return np.where(mask[..., None], near.local[index], 0.0), mask


def _widest_gap(values: np.ndarray, mask: np.ndarray, least: np.ndarray):
    """The widest gap between the sorted real `values` of each row (..., n) with at least `least`
    of them each side: its width, its middle, and the second widest such gap's width."""
    ranked = np.sort(np.where(mask, values, np.inf), axis=-1)
    with np.errstate(invalid="ignore"):
        gaps = np.diff(ranked, axis=-1)
    j = np.arange(1, gaps.shape[-1] + 1)
    n = mask.sum(axis=-1)[..., None]
    gaps = np.where((j >= least[..., None]) & (j <= n - least[..., None]), gaps, -1.0)
    cut = gaps.argmax(axis=-1)[..., None]
    widest = np.take_along_axis(gaps, cut, -1)[..., 0]
    middle = np.take_along_axis(ranked, cut, -1)[..., 0] + 0.5 * widest
    return widest, middle, np.partition(gaps, -2, axis=-1)[..., -2]


def _scatter(points: np.ndarray, inside: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The mean and scatter matrix of each row's points (m, k, d) where `inside` (m, k)."""
    weight = inside[..., None]
    mean = (points * weight).sum(axis=1) / np.maximum(inside.sum(axis=1), 1)[:, None]
    centred = (points - mean[:, None]) * weight
    return mean, centred.transpose(0, 2, 1) @ centred


def _two_strands(near: _Neighbourhoods, chosen: np.ndarray) -> np.ndarray:
    """For each chosen neighbourhood, the larger spread ratio of its two strands when its points
    part into two line-like strands with one clear gap between them, else inf."""
    padded, mask = _padded(near, chosen)
    least = np.maximum(3, np.ceil(STRAND_SHARE * mask.sum(axis=1))).astype(int)
    plane = padded @ near.axes[chosen][:, :, 1:]  # in the neighbourhood's plane
    # the widest gap over a few directions parts the two sides roughly ...
    angles = np.linspace(0, np.pi, STRAND_DIRECTIONS, endpoint=False)
    proj = (plane @ np.stack([np.cos(angles), np.sin(angles)])).transpose(0, 2, 1)
    shape = proj.shape  # (m, directions, points)
    widest, middle, _ = _widest_gap(
        proj, np.broadcast_to(mask[:, None], shape), np.broadcast_to(least[:, None], shape[:2])
    )
    rows, best = np.arange(len(plane)), widest.argmax(axis=1)
    left = mask & (proj[rows, best] < middle[rows, best][:, None])
    # ... and the gap is measured again square to the sides' mean direction
    doubled = np.zeros((len(plane), 2))  # each side's axis as a doubled angle (no sign)
    for side in (left, mask & ~left):
        (xx, xy), (_, yy) = _scatter(plane, side)[1].transpose(1, 2, 0)
        doubled += np.column_stack([xx - yy, 2 * xy]) / np.maximum(xx + yy, 1e-300)[:, None]
    along = 0.5 * np.arctan2(doubled[:, 1], doubled[:, 0])
    proj = plane[..., 0] * -np.sin(along)[:, None] + plane[..., 1] * np.cos(along)[:, None]
    widest, middle, second = _widest_gap(proj, mask, least)
    left = mask & (proj < middle[:, None])
    parted = (widest > 0) & (second <= STRAND_SECOND * widest)
    centres, spreads, worst = [], [], np.zeros(len(plane))
    for side in (left, mask & ~left):
        mean, scatter = _scatter(proj[..., None], side)
        centres.append(mean[:, 0])
        spreads.append(np.sqrt(scatter[:, 0, 0] / np.maximum(side.sum(axis=1), 1)))
        worst = np.maximum(worst, _ratio(np.linalg.eigvalsh(_scatter(padded, side)[1])))
    parted &= np.abs(centres[1] - centres[0]) >= STRAND_APART * (spreads[0] + spreads[1])
    return np.where(parted & (worst <= STRAND_LINE), worst, np.inf)


def _narrow_band(near: _Neighbourhoods, chosen: np.ndarray) -> np.ndarray:
    """For each chosen neighbourhood, its spread ratio within BAND_CLOSER of its width round its
    centre when its points fill a band narrower than it evenly (and that holds COVER_LEAST
    points); else 0."""
    m = len(near.sizes)
    width = np.sqrt(12 * np.maximum(near.spread[:, 1], 0))  # an even band's (across: 2nd axis)
    chosen = chosen & (near.sizes >= BAND_LEAST)
    chosen &= (width >= 2 * BAND_WIDTH[0]) & (width <= 2 * BAND_WIDTH[1])  # the diameter is 2
    rows = np.flatnonzero(chosen[near.owner])
    owner, local = near.owner[rows], near.local[rows]
    across = np.einsum("ij,ij->i", local - near.mean[owner], near.axes[owner, :, 1])
    fourth = np.bincount(owner, across**4, m) / np.maximum(near.sizes, 1)
    band = chosen & (fourth <= BAND_FLAT * near.spread[:, 1] ** 2)  # the kurtosis
    radius = BAND_CLOSER * width[owner]
    closer = band[owner] & (np.einsum("ij,ij->i", local, local) <= radius**2)
    count, _, covariance = _moments(local[closer], owner[closer], m)
    return np.where(band & (count >= COVER_LEAST), _ratio(np.linalg.eigvalsh(covariance)), 0.0)


def _unit_cloud(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, float] | None:
    """At most COVER_POINTS of the (n, 3) points, centred and scaled to unit size (finite sums
    at 1e200 or 1e-200), the neighbourhoods' centres among them and their reach (COVER_REACH of
    the length, COVER_WIDTH of the width if less); None for no points, a non-finite one, or
    points on one line."""
    points = fixed_sample(np.asarray(points, dtype=float), COVER_POINTS)
    if len(points) == 0 or not np.isfinite(points).all():
        return None
    low, high = points.min(axis=0), points.max(axis=0)
    points = points - (low / 2 + high / 2)
    points /= max(float(np.abs(points).max()), 1e-300)
    length, width = (float(extent) for extent in principal_extents(points)[:2])
    if not np.isfinite(length) or length <= 0:
        return None
    reach = min(COVER_REACH * length, COVER_WIDTH * width)
    return None if reach <= 0 else (points, points[:: max(1, len(points) // COVER_CENTRES)], reach)


def _too_sparse(sizes: np.ndarray) -> bool:
    """Whether most neighbourhoods (`sizes`: the points each holds) hold too few to measure."""
    return int(np.sum(sizes >= COVER_LEAST)) < len(sizes) / 2


def surface_cover(points: np.ndarray) -> tuple[float, float]:
    """(surface_spread, filled_share) of the (n, 3) points, their unit cloud and neighbourhoods
    found once: the pipeline asks both of every boundary (plausibility.check_not_a_surface). The
    share is looked at only where the spread cannot tell: most neighbourhoods too sparse, or a
    cloud of fewer than SPREAD_FROM points that the spread does not take for a surface."""
    unit = _unit_cloud(points)
    if unit is None:
        return 0.0, 0.0
    near = _neighbourhoods(*unit)
    if _too_sparse(near.sizes):
        return 0.0, _filled(unit[0])
    spread = _spread(near)
    if spread <= COVER_SPREAD and len(unit[0]) < SPREAD_FROM:
        return spread, _filled(unit[0])
    return spread, 0.0


def surface_spread(points: np.ndarray) -> float:
    """How much the (n, 3) points cover a surface rather than trace a curve: the median, over
    neighbourhoods of COVER_REACH of the length (COVER_WIDTH of the width if less), of their
    second spread over their largest (0 on a curve, 1 on a surface); 0 when most neighbourhoods
    hold too few points to tell (filled_share looks at those). A neighbourhood holding two
    line-like strands with one clear gap between them (a bent narrow blade's two margins) counts
    at its strands' spread instead; one whose points fill a narrower band evenly (a bent narrow
    scan) at the band's own scale. Scale-free and independent of the points' order and of any
    outline traced through them."""
    return surface_cover(points)[0]


def _spread(near: _Neighbourhoods) -> float:
    """surface_spread over neighbourhoods most of which hold enough points."""
    measured = near.sizes >= COVER_LEAST
    ratios = _ratio(near.spread)
    chosen = np.flatnonzero(measured & (ratios > STRAND_LINE))
    strands = np.full(len(ratios), np.inf)
    if len(chosen):
        strands[chosen] = _two_strands(near, chosen)
    ratios = np.where(np.isfinite(strands), strands, ratios)
    ratios = np.maximum(ratios, _narrow_band(near, measured & ~np.isfinite(strands)))
    return float(np.median(ratios[measured]))


def filled_share(points: np.ndarray) -> float:
    """For points too sparse for surface_spread (a 400-point blob, a hemisphere's points: issue
    24, finding 15), the share of them that their FILL_NEAREST nearest neighbours surround: no
    gap between the neighbours' directions, in their own plane, is wider than FILL_GAP. Points
    in an area are surrounded but for its rim; a point on an outline has its neighbours ahead
    and behind, the gaps between them near half a turn. 0 for a cloud dense enough for
    surface_spread (and of SPREAD_FROM points or more, or covering a surface by it), or of
    fewer than FILL_FROM distinct points. Scale-free, order-free, and
    local in 3D (a curled leaf's outline is a curve at every point, whatever its shadow)."""
    return surface_cover(points)[1]


def _filled(cloud: np.ndarray) -> float:
    """filled_share of a unit cloud too sparse for surface_spread."""
    cloud = np.unique(cloud, axis=0)  # a point given twice is not its own neighbour
    if len(cloud) < FILL_FROM:
        return 0.0
    nearest = cKDTree(cloud).query(cloud, k=FILL_NEAREST + 1)[1]
    around = cloud[nearest[:, 1:]] - cloud[:, None, :]
    local = cloud[nearest] - cloud[nearest].mean(axis=1, keepdims=True)
    axes = np.linalg.eigh(local.transpose(0, 2, 1) @ local)[1]  # ascending: the plane's last
    angles = np.sort(
        np.arctan2(
            np.einsum("nkd,nd->nk", around, axes[:, :, 1]),
            np.einsum("nkd,nd->nk", around, axes[:, :, 2]),
        ),
        axis=1,
    )
    gaps = np.diff(np.concatenate([angles, angles[:, :1] + 2 * np.pi], axis=1), axis=1)
    return float(np.mean(gaps.max(axis=1) < FILL_GAP))
