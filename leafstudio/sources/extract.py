"""From a leaf scan (a point cloud of its whole surface) to what the paper takes: boundary, veins.

1. Clean: drop points far from their neighbours (outliers) and small detached clusters.
2. Keep the blade: a petiole is a thin strand, so the points of the blade's interior have many
   more neighbours within a ball of radius r than a strand's; the blade is the largest connected
   group of such "core" points, grown back by r/2 to recover its margin and tip (a morphological
   opening of the point set). The largest strand left is the petiole; it marks the base.
3. Project the blade on its PCA plane; its outline is a concave hull that bridges scanner stripes
   (and nothing wider), opened a little to cut off a stub of petiole, evenly resampled and lifted
   to the scan's heights by a local plane fit (so the margin's heights come from the scan, not
   from the nearest point), averaged along the outline against the edge's noise.
4. Midrib: from the base to the tip, through the middle of the blade's cross-sections, lifted to
   the surface. Side veins: straight from the midrib toward the margin at 50° to it, lifted too,
   and cut where the scan has a gap.

Units and size: the scan is moved and scaled to unit size first (nothing overflows at 1e200, and
the constants meet the same leaf in any units), and a scan of more than BUDGET points is thinned
to one point per occupied voxel (the voxel's centroid, the voxel as large as needed to keep at
most BUDGET): the steps above then cost the same for 1e5 or 1e7 points, and the blade and petiole
masks go back to every scan point through its voxel. Smaller scans are used as they are.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import shapely
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree
from shapely.geometry import Polygon

from leafstudio._shared import progress
from leafstudio.core.plane import fixed_sample, principal_extents, principal_spreads
from leafstudio.core.prepare.plausibility import check_leaf_like
from leafstudio.core.prepare.vein_order import veins_inside_outline
from leafstudio.core.sheet import fit_sheet
from leafstudio.core.sheet_bend import Scaled
from leafstudio.errors import LeafError
from leafstudio.model import Leaf
from leafstudio.sources.scan import OUTLINE_POINTS
from leafstudio.sources.scan_holes import holes
from leafstudio.sources.scan_outline import held_part, outline, resample
from leafstudio.sources.scan_thinning import voxel_thinning
from leafstudio.sources.scan_veins import (
    PETIOLE_SHARE,
    SIDE_POINTS,
    base_point,
    midline,
    side_veins,
)

MIN_POINTS = 50
OUTLIER_FACTOR = 3.0  # a point whose mean neighbour distance exceeds this many medians is noise
NEIGHBOURS = 8
LINK = 4.0  # points closer than this many median neighbour distances are connected
CLUSTER_SHARE = 0.1  # detached clusters smaller than this share of the largest are dropped
BALL = 0.08  # r, the ball of the blade test, as a fraction of the scan's length
CORE = 0.4  # core points have at least this share of the busiest balls' count
EDGE = 0.3  # margin points, grown back near the core, at least this share (a strand has less)
LIFT_NEIGHBOURS = 32  # the veins' heights, from a plane through this many scan points: soybean
# pot1_1's (doubled layers) at sheet.SMOOTHING 1e-3 crinkled its mesh at 16 (p99 inside 75.4;
# 32: 65.3, its distance to the scan 0.96 -> 0.97% of its length); 8 and 64 at 2e-3: 72.0, 49.3
RIM_KERNEL = np.array([1.0, 2.0, 3.0, 2.0, 1.0])  # smooths the margin's heights along it
STRAND = 0.35  # a petiole's second spread is at most this share of its first (the real scans'
# petioles: 0.06-0.23; the pieces of blade the ball test leaves: sheets 0.60-0.64, strips 0.12-0.34)
STICK_OUT = 0.5  # ... and its far end this share of its length from the blade (petioles: 0.92-1.05;
# strips along the margin: 0.09-0.18)
BUDGET = 40_000  # larger scans are thinned to at most this many voxel centroids
PROBES = 10_000  # blade_points counts a ball's points among this many at most
HELD = 1.0  # a flattened blade's outline keeps within this many sheet cells of a sheet centre
FINDING = "finding the leaf in the scan"  # what extract_leaf's progress reports say it does
ENDS = 4.0  # a big scan's blade ends are sought in cubes this many diagonals from the outermost


@dataclass(frozen=True)
class Extraction:
    """What `extract_leaf` found.

    Attributes
    ----------
    leaf : Leaf
        Boundary (evenly resampled, in order) and veins (midrib first), in scan coordinates.
    blade : (n,) bool array
        Which scan points belong to the blade (not outliers, clutter or petiole).
    petiole : (n,) bool array
        Which scan points were taken as the petiole.
    length : float
        The blade's length along its main axis, in scan units.
    """

    leaf: Leaf
    blade: np.ndarray
    petiole: np.ndarray
    length: float


class _Found(NamedTuple):
    """What `_extract` found on the scan at unit size: the blade and petiole masks, the blade
    point nearest the base, the blade's plane and the points in it, the region its points keep
    to, and the outline, its points, its spacing and the base on it in the plane; then the leaf
    and the holes (`_veins`)."""

    blade: np.ndarray  # (n,) bool
    petiole: np.ndarray  # (n,) bool
    base: int | None  # the blade point nearest a base the petiole or an axis told
    origin: np.ndarray  # (3,)
    axes: np.ndarray  # (3, 3) rows: u (length), v, normal
    local: np.ndarray  # (n, 3) the points in the plane's frame: u, v and the height
    region: Polygon
    polygon: Polygon
    boundary_xy: np.ndarray  # (count, 2)
    spacing: float  # the veins', the region's and the rim's (not the outline's: `count`)
    base_xy: np.ndarray  # (2,)
    leaf: Leaf | None = None  # boundary and veins (`_veins`)
    holes: tuple[np.ndarray, ...] = ()  # (k, 2) rings in the plane, on a flattened blade
    # (scan_holes.py)


def _neighbour_spacing(points: np.ndarray) -> np.ndarray:
    """(n,) mean distance from each point to its NEIGHBOURS nearest others."""
    dist, _ = cKDTree(points).query(points, k=min(NEIGHBOURS + 1, len(points)))
    return dist[:, 1:].mean(axis=1)


def _components(points: np.ndarray, radius: float) -> np.ndarray:
    """(n,) label of each point's connected group, linking points within `radius`."""
    pairs = cKDTree(points).query_pairs(radius, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(points),) * 2)
    return connected_components(graph, directed=False)[1]


def clean_scan(points: np.ndarray, spacing: np.ndarray | None = None) -> np.ndarray:
    """(n,) bool: the points kept once outliers and small detached clusters are dropped
    (`spacing`: their _neighbour_spacing, when the caller has it)."""
    spacing = _neighbour_spacing(points) if spacing is None else spacing
    typical = float(np.median(spacing))
    if not typical > 0:
        raise LeafError("most of the scan's points coincide: no surface to find a leaf on")
    keep = spacing <= OUTLIER_FACTOR * typical
    labels = _components(points[keep], LINK * typical)
    sizes = np.bincount(labels)
    big = sizes >= CLUSTER_SHARE * sizes.max()
    kept = np.flatnonzero(keep)
    keep[kept[~big[labels]]] = False
    return keep


def blade_points(points: np.ndarray) -> np.ndarray:
    """(n,) bool: the blade among cleaned scan points, without a petiole that sticks out."""
    radius = BALL * float(principal_extents(points)[0])
    if len(points) > PROBES:  # each ball's count from a random share of the points, scaled up
        probes = fixed_sample(points, PROBES)
        found = cKDTree(probes).query_ball_point(points, radius, return_length=True)
        counts = found * (len(points) / PROBES)
    else:
        counts = cKDTree(points).query_ball_point(points, radius, return_length=True)
    busy = np.percentile(counts, 90)
    core = counts >= CORE * busy
    if not core.any():
        raise LeafError("no leaf blade in the scan: no point has the neighbours a surface gives")
    typical = float(np.median(_neighbour_spacing(points)))
    labels = _components(points[core], LINK * typical)
    main = np.flatnonzero(core)[labels == np.argmax(np.bincount(labels))]
    near, _ = cKDTree(points[main]).query(points, distance_upper_bound=0.5 * radius)
    return np.isfinite(near) & (counts >= EDGE * busy)


def split_scan(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n,) bool masks of a scan's blade and its petiole (the rest: outliers and clutter).

    The points blade_points leaves out fall into connected pieces. The petiole is the largest
    piece that is a strand sticking out of the blade (_sticks_out); every other piece that
    touches the blade is blade: a margin whose balls hold fewer points (a strip along the edge,
    or a part of the blade the scanner saw obliquely, its stripes farther apart). Taking the
    largest piece left as the petiole, whatever its shape, dropped 16% of the soybean pot1_1
    blade, and on sugar beet pot1_7 took a piece of the blade for the petiole and the real
    petiole for clutter (review finding)."""
    spacing = _neighbour_spacing(points)  # once: the cleaning and the pieces' link take it
    clean = clean_scan(points, spacing)
    blade = np.zeros(len(points), dtype=bool)
    blade[np.flatnonzero(clean)[blade_points(points[clean])]] = True
    rest = np.flatnonzero(clean & ~blade)
    petiole = np.zeros(len(points), dtype=bool)
    if len(rest) == 0:
        return blade, petiole
    link = LINK * float(np.median(spacing))
    labels = _components(points[rest], link)
    gap = cKDTree(points[blade]).query(points[rest])[0]
    sizes = np.bincount(labels)
    for label in np.argsort(sizes)[::-1]:
        if sizes[label] < PETIOLE_SHARE * blade.sum():
            break
        piece = labels == label
        if _sticks_out(points[rest[piece]], gap[piece]):
            petiole[rest[piece]] = True
            break
    touching = np.bincount(labels, weights=gap <= link, minlength=len(sizes)) > 0
    blade[rest[touching[labels] & ~petiole[rest]]] = True
    return blade, petiole


def _sticks_out(piece: np.ndarray, gap: np.ndarray) -> bool:
    """True for an (m, 3) piece of a scan that is a strand (its second spread at most STRAND of
    its first) whose far end lies at least STICK_OUT of its length from the blade (`gap`: each
    point's distance to the blade): a petiole, not a strip along the blade's margin."""
    spread = principal_spreads(piece)
    length = 2 * np.sqrt(3) * spread[0]  # a uniform segment's length from its spread
    return bool(spread[1] <= STRAND * spread[0] and gap.max() >= STICK_OUT * length)


def _plane(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The PCA frame of points: origin (3,) and axes (3, 3), rows u (length), v, normal."""
    origin = points.mean(axis=0)
    axes = np.linalg.svd(points - origin, full_matrices=False)[2]
    if np.linalg.det(axes) < 0:
        axes[2] = -axes[2]
    return origin, axes


def lift(query: np.ndarray, xy: np.ndarray, h: np.ndarray) -> np.ndarray:
    """(q,) heights at (q, 2) plane points from a weighted local plane fit to the scan's (n, 2)
    points and (n,) heights (extrapolates sensibly at the margin, smooths scanner noise)."""
    k = min(LIFT_NEIGHBOURS, len(xy))
    dist, idx = cKDTree(xy).query(query, k=k)
    d = xy[idx] - query[:, None, :]
    design = np.concatenate([np.ones((len(query), k, 1)), d], axis=2)
    weight = 1.0 / (dist + dist[:, :1] + 1e-12)
    normal = np.einsum("nk,nki,nkj->nij", weight, design, design)
    scale = np.trace(normal, axis1=1, axis2=2)[:, None, None]
    normal += 1e-6 * scale * np.eye(3)
    rhs = np.einsum("nk,nki,nk->ni", weight, design, h[idx])
    return np.linalg.solve(normal, rhs[..., None])[:, 0, 0]


def extract_leaf(
    points: np.ndarray,
    base_end: str = "auto",
    count: int = OUTLINE_POINTS,
    at_unit: UnitScan | None = None,
) -> Extraction:
    """Boundary and veins of the leaf in a scan of its surface.

    Parameters
    ----------
    points : (n, 3) float array
        The scan's points.
    base_end : str, default: "auto"
        Which end of the blade is its base: "auto" (where the petiole was, else the wider end),
        or a world direction "+x", "-x", "+y", "-y", "+z", "-z" (the base is the end that way).
    count : int, default: 200
        Boundary points; the veins are sampled at the same spacing.
    at_unit : UnitScan, optional
        `unit_scan(points)`, when the caller made it already (check_scan took it too).

    Raises
    ------
    LeafError
        If the scan has too few points or no blade can be found.
    """
    if count < 8:
        raise LeafError(f"the boundary needs at least 8 points, got {count}")
    # each step's share of the time, on a 2-million-point scan and on soybean pot1_1 (whose
    # sheet costs most: its blade fills more cubes), in progress reports (the app's busy bar)
    progress.report(0.0, FINDING)
    if at_unit is None:
        at_unit = unit_scan(points)
    centre, scale, unit = at_unit.centre, at_unit.scale, at_unit.unit
    thinned, cell, size = at_unit.thinned, at_unit.cell, at_unit.size
    progress.report(0.1, FINDING)
    found = _extract(thinned, base_end, count)  # its veins only if no sheet is fitted
    progress.report(0.3, FINDING)
    span = float(np.ptp(thinned[found.blade] @ found.axes[0]))
    with progress.share(0.3, 0.75):
        sheet = fit_sheet(thinned[found.blade], found.axes[2], span)
    flatten = (lambda q: q) if sheet is None else sheet.flatten
    flat = thinned if sheet is None else sheet.flatten(thinned)
    progress.report(0.8, FINDING)
    if sheet is not None:  # the blade unrolled (core/sheet.py), its outline and veins found there
        held = (sheet.centres_flat(), HELD * sheet.cell)
        found = _extract(flat, base_end, count, (found.blade, found.petiole, found.base), held)
    found = _veins(found, count, None if sheet is None else held)
    progress.report(0.9, FINDING)
    leaf, blade, petiole = found.leaf, found.blade, found.petiole
    origin, axes, region = found.origin, found.axes, found.region
    length = float(np.ptp((flat[blade] - origin) @ axes[0]))
    if cell is not None:  # each point as its cube's centroid; a petiole stub cut as there
        # a point lies within its cube's diagonal of the cube's centroid: a cube whose centroid
        # is deeper in the region than that is inside, and the blade's two ends lie in cubes
        # within two diagonals of the outermost centroids (ENDS: twice that, for the
        # flattening's stretch). Only the other cubes' points are flattened (all 2 million of a
        # big scan's points took most of its opening time)
        xy = (flat - origin) @ axes[:2].T
        reach = np.sqrt(3) * size
        deep = shapely.contains_xy(region.buffer(-reach), xy[:, 0], xy[:, 1])
        u = np.where(blade, xy[:, 0], np.nan)
        ends = (u <= np.nanmin(u) + ENDS * reach) | (u >= np.nanmax(u) - ENDS * reach)
        blade, petiole = blade[cell], petiole[cell]
        test = np.flatnonzero(blade & ~(deep & ~ends)[cell])
        local = (flatten(unit[test]) - origin) @ axes.T
        cut = ~shapely.contains_xy(region, local[:, 0], local[:, 1]) & ~deep[cell[test]]
        blade[test[cut]], petiole[test[cut]] = False, True
        at_ends = ~cut & ends[cell[test]]
        length = float(np.ptp(local[at_ends, 0])) if at_ends.any() else length
    bend = None
    if sheet is not None:  # holes in the flat blade, in the sheet's (u, v)
        rings = [(origin + np.pad(r, ((0, 0), (0, 1))) @ axes)[:, :2] for r in found.holes]
        bend = Scaled(sheet, centre, scale, holes=tuple(rings))
    progress.report(1.0, FINDING)

    def world(q: np.ndarray) -> np.ndarray:
        return centre + scale * q if bend is None else bend.bent(centre + scale * q)

    return Extraction(
        leaf=Leaf(boundary=world(leaf.boundary), veins=[world(v) for v in leaf.veins], bend=bend),
        blade=blade,
        petiole=petiole,
        length=scale * length,
    )


@dataclass(frozen=True, eq=False)
class UnitScan:
    """A scan moved and scaled to unit size (nothing overflows at 1e200), and thinned to at most
    BUDGET voxel centroids (voxel_thinning: the thinned points, each point's cube, the cubes'
    side). Made once for a scan's check and its extraction: thinning 2 million points takes
    a second, and both see the scan so."""

    centre: np.ndarray  # (3,)
    scale: float
    unit: np.ndarray  # (n, 3): (points - centre) / scale
    thinned: np.ndarray  # (m, 3) at unit size
    cell: np.ndarray | None  # (n,) each point's cube in `thinned`; None: not thinned
    size: float


def unit_scan(points: np.ndarray) -> UnitScan:
    """`points` at unit size and thinned (UnitScan); LeafError when they cannot be a scan."""
    points = np.asarray(points, dtype=float)
    if len(points) < MIN_POINTS:
        raise LeafError(f"too few points for a leaf scan: {len(points)} (need {MIN_POINTS})")
    if not np.all(np.isfinite(points)):
        raise LeafError("the scan holds NaN or infinite coordinates")
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre, scale = lo / 2 + hi / 2, float(np.max(hi / 2 - lo / 2)) * 2
    if not scale > 0 or not np.isfinite(scale):
        raise LeafError("the scan's points all coincide")
    unit = (points - centre) / scale
    return UnitScan(centre, scale, unit, *voxel_thinning(unit, BUDGET))


def check_scan(
    points: np.ndarray, force: bool = False, at_unit: UnitScan | None = None
) -> list[str]:
    """plausibility.check_leaf_like on a scan as extract_leaf sees it (a large one by its voxel
    centroids: linear time; the check is scale-free). `leafstudio extract` and `batch --scans`
    both run it first, so they refuse the same scans with the same line (or, with `force`,
    return the same warnings). `at_unit`: `unit_scan(points)`, made once for both."""
    if at_unit is None:
        at_unit = unit_scan(points)
    return check_leaf_like(at_unit.thinned, force=force)


def _extract(
    points: np.ndarray,
    base_end: str,
    count: int,
    split: tuple[np.ndarray, np.ndarray, int | None] | None = None,
    held: tuple[np.ndarray, float] | None = None,
) -> _Found:
    """extract_leaf's blade, outline and base on the scan at unit size (and thinned); `_veins`
    finds the rest (the first pass's are not needed once the blade is unrolled). `split`: the
    blade and petiole masks and the base's blade point found before (on the unflattened scan,
    where a petiole and a world axis mean what they say; None for the wider end); `held`: on a
    flattened blade, the sheet's centres (m, 3: its cell means) and how far from them the sheet
    is known."""
    blade, petiole = split_scan(points) if split is None else (split[0].copy(), split[1].copy())
    if blade.sum() < MIN_POINTS:
        raise LeafError(f"found only {blade.sum()} blade points in the scan (need {MIN_POINTS})")
    framed = points[blade]
    if held is not None:  # a flattened blade's frame from its points where the sheet is known: a
        # point between two layers of a curl may be flattened onto either, off the sheet, and
        # it turned the frame (soybean pot1_1 scaled by 3: its length 5e-5 off)
        gap = cKDTree(held[0][:, :2]).query(framed[:, :2], distance_upper_bound=held[1])[0]
        known = np.isfinite(gap)
        framed = framed[known] if known.sum() >= MIN_POINTS else framed
    origin, axes = _plane(framed)
    local = (points - origin) @ axes.T
    xy = local[blade, :2]
    if np.ptp(xy[:, 1]) < 1e-3 * np.ptp(xy[:, 0]):
        raise LeafError("the scan's points lie on a line, not a leaf surface")
    polygon = outline(xy, float(np.ptp(xy[:, 0])))
    if held is not None:
        polygon = held_part(polygon, ((held[0] - origin) @ axes.T)[:, :2], held[1])
    boundary_xy = resample(polygon, count)
    # the veins, the region and the rim's smoothing at a spacing of their own: --points sets how
    # finely the outline is written, not what is blade (it did), nor the cost (quadratic in it)
    spacing = polygon.length / OUTLINE_POINTS
    region = polygon.buffer(spacing)
    cut = ~shapely.contains_xy(region, local[:, 0], local[:, 1])
    petiole |= blade & cut  # a stub of petiole trimmed by the opening
    blade &= ~cut
    if blade.sum() < MIN_POINTS:
        raise LeafError(
            f"found only {blade.sum()} blade points within the blade's outline (need "
            f"{MIN_POINTS}): the scan does not look like a leaf surface"
        )
    xy = local[blade, :2]
    # the base: on the flat blade, its wider end (the points cut there are the held part's, no
    # petiole: soybean pot1_1's base landed in a bay by them); the petiole's end or a world
    # axis's as found on the unflattened scan (a petiole's flat points lie off the sheet)
    told = local[petiole, :2] if split is None else np.zeros((0, 2))
    carried = None if split is None else split[2]
    if carried is None:
        base = base_point(base_end, axes, boundary_xy, xy, told)
    else:
        base = boundary_xy[np.argmin(np.linalg.norm(boundary_xy - local[carried, :2], axis=1))]
    base_at = None
    if split is None and (base_end != "auto" or len(told) >= PETIOLE_SHARE * len(xy)):
        base_at = int(np.flatnonzero(blade)[np.argmin(np.linalg.norm(xy - base, axis=1))])
    return _Found(
        blade=blade,
        petiole=petiole,
        base=base_at,
        origin=origin,
        axes=axes,
        local=local,
        region=region,
        polygon=polygon,
        boundary_xy=boundary_xy,
        spacing=spacing,
        base_xy=base,
    )


def _veins(found: _Found, count: int, held: tuple[np.ndarray, float] | None) -> _Found:
    """`found` (by `_extract`) with its leaf: the boundary and veins lifted to the scan's
    heights, and the holes on a flattened blade (`held`)."""
    origin, axes, polygon, boundary_xy = found.origin, found.axes, found.polygon, found.boundary_xy
    local = found.local[found.blade]
    xy, h = local[:, :2], local[:, 2]
    spacing = found.spacing
    midrib = midline(boundary_xy, found.base_xy, spacing)
    gaps = cKDTree(xy)  # the blade's points and their gap, for the side veins and the holes
    gap = float(np.percentile(gaps.query(xy, k=2)[0][:, 1], 95))
    reach = 2.0 * gap

    def covered(q: np.ndarray) -> np.ndarray:
        return np.isfinite(gaps.query(q, distance_upper_bound=reach)[0])

    veins_xy = [midrib, *side_veins(polygon, midrib, covered, spacing)]

    def world(q: np.ndarray, z: np.ndarray | None = None) -> np.ndarray:
        z = lift(q, xy, h) if z is None else z
        return origin + np.column_stack([q, z]) @ axes

    # the margin's heights are the noisiest (mixed returns at the edge): average along the outline
    taps = max(len(RIM_KERNEL), round(len(RIM_KERNEL) * count / OUTLINE_POINTS))
    reach = np.linspace(0, len(RIM_KERNEL) - 1, taps)  # RIM_KERNEL's reach, whatever the count
    kernel = np.interp(reach, np.arange(len(RIM_KERNEL)), RIM_KERNEL)
    rim = np.convolve(np.tile(lift(boundary_xy, xy, h), 3), kernel / kernel.sum(), "same")
    boundary = world(boundary_xy, rim[count : 2 * count])
    veins = veins_inside_outline(boundary, [world(v) for v in veins_xy], spacing)
    # a side vein cut by the outline to a stub is dropped, as side_veins drops a short one (pot1_7)
    veins = veins[:1] + [v for v in veins[1:] if len(v) >= SIDE_POINTS]
    rings = holes(found.region, gaps, gap) if held is not None else []
    return found._replace(leaf=Leaf(boundary=boundary, veins=veins), holes=tuple(rings))
