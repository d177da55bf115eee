"""Veins grown inside any outline: primaries laid first, secondaries by space colonization.

Method (Runions, Fuhrer, Lane, Federl, Rolland-Lagan and Prusinkiewicz, "Modeling and
visualization of leaf venation patterns", SIGGRAPH 2005, open venation):
1. The primaries are laid first: the midrib from the base to the apex along the outline's longest
   axis (through the middle of its cross-sections where the straight line would leave the blade);
   palmate venation adds two or four primaries from the base to the farthest margin points in
   sectors either side of the midrib (the lobes' tips in a lobed leaf); parallel venation lays
   2N + 1 veins through the same fractions of every cross-section from base to apex, so they
   converge at both ends and never cross.
2. Auxin sources are scattered over the blade (a jittered grid). Each source attracts the vein
   node nearest to it; each node that is attracted grows one step D toward the mean direction of
   its sources; sources within the kill distance of a node are removed; repeat until none grows.
   Growth starts only from the secondaries' seeds (stations along the primaries, alternating
   sides), so each seed colonises its own part of the blade.
   Departures, ours: the blade does not grow (Runions' marginal growth is what sets the veins'
   angle to the midrib); a tropism toward the apex stands in for it (secondaries leave at about
   55°), and for arcuate venation it strengthens near the margin so the secondaries curve up along
   it. Each seed's tree is reduced to its longest path (the secondary vein); an open secondary is
   continued straight to just inside the margin, an arcuate one along the margin toward the apex
   until it nears the next vein. In a narrow blade (a linear leaf, 20 or 30 times longer than
   wide) the step shrinks to half its half-width and the seeds leave at the tropism's angle, so
   its secondaries are short and steep, as in rosemary or willow (growth_step); grass-like leaves
   are parallel-veined (venation "parallel").
3. Heights: every vein point stands HEIGHT_RATIO times its distance to the margin above the
   blade's base surface (b(x) through a 3D outline's heights, 0 for a flat one), as the demos'
   midribs do (h = 0.25 w): the blade rises about 14° from the margin to the veins.
"""

from __future__ import annotations

import numpy as np
import shapely
from scipy.spatial import ConvexHull, QhullError, cKDTree
from shapely.geometry import LineString, MultiLineString, Point, Polygon

from leafstudio.core.base import fit_base
from leafstudio.core.plane import fit_frame
from leafstudio.core.prepare.outline import leaf_polygon
from leafstudio.core.prepare.units import Units
from leafstudio.errors import LeafError
from leafstudio.model import SEED_MAX

VENATION_KINDS = ("pinnate", "palmate", "parallel", "arcuate")
BASE_REACH = 0.05  # a base farther outside the outline than this share of its size is refused
HEIGHT_RATIO = 0.25  # vein height over its distance to the margin (sources/demos.py: h = 0.25 w)
BROAD_STEP = 0.035  # the growth step of a broad blade, as a share of the square root of its area
STEP = 0.02  # growth step D, in leaf lengths
NARROW_STEPS = 2  # a blade's half-width holds at least this many growth steps (see growth_step)
NARROW_TURN = np.deg2rad(35.0)  # a narrow blade's secondaries leave the midrib at 90° - this
SOURCES = 350  # auxin sources scattered over the blade
KILL = 1.2  # kill distance, in growth steps
MAX_ITERATIONS = 80
TROPISM = 0.6  # pull toward the apex added to each growth direction
PALMATE_TROPISM = 0.3  # palmate secondaries: a gentler pull along their primary
INSET = 0.006  # open secondaries end this far (leaf lengths) inside the margin
MIDRIB_SPAN = (0.01, 0.99)  # the midrib's share of base -> apex
DEFAULT_SECONDARIES = {"pinnate": 6, "arcuate": 6, "palmate": 3, "parallel": 3}


def _plane(boundary: np.ndarray, base):
    """(2D outline, heights or None, frame or None, base in 2D or None); the outline is checked
    already (grow_veins)."""
    points = np.asarray(boundary, dtype=float)
    b = None if base is None else np.asarray(base, dtype=float).ravel()
    if points.shape[1] == 2 or np.all(points[:, 2] == points[0, 2]):
        z0 = None if points.shape[1] == 2 else float(points[0, 2])
        return points[:, :2].copy(), None, z0, None if b is None else b[:2]
    frame = fit_frame(points, np.zeros((0, 3)))
    xy, h = frame.to_plane(points)
    if b is not None:
        if len(b) == 2:  # world x, y: lift to the nearest boundary point's z
            near = np.argmin(np.linalg.norm(points[:, :2] - b, axis=1))
            b = np.array([b[0], b[1], points[near, 2]])
        b = frame.to_plane(b[None])[0][0]
    return xy, h, frame, b


def _polygon(xy: np.ndarray) -> Polygon:
    """The outline as a valid shapely polygon (the pipeline's own outline for unordered points)."""
    poly = Polygon(xy)
    if poly.is_valid and poly.area > 0:
        return poly
    ring = leaf_polygon(xy)
    poly = Polygon(ring[0] if isinstance(ring, tuple) else ring)
    if not poly.is_valid:
        poly = shapely.make_valid(poly)
        if not isinstance(poly, Polygon):
            poly = max(getattr(poly, "geoms", [poly]), key=lambda g: g.area)
    return poly


def _ends(poly: Polygon) -> tuple[np.ndarray, np.ndarray]:
    """The two ends of the outline's longest axis (its diameter)."""
    ring = np.asarray(poly.exterior.coords)[:-1]
    try:
        hull = ring[ConvexHull(ring).vertices]
    except QhullError:
        hull = ring
    d = np.linalg.norm(hull[:, None] - hull[None], axis=2)
    i, j = np.unravel_index(np.argmax(d), d.shape)
    return hull[i], hull[j]


def _base_from_apex(poly: Polygon, apex: np.ndarray) -> np.ndarray:
    """Where the midrib meets the blade, seen from the apex: the far crossing of the line from the
    apex through the blade's centroid (a cordate leaf's sinus, not one of its lobes)."""
    c = np.asarray(poly.centroid.coords[0])
    d = c - apex
    d /= np.linalg.norm(d)
    far = apex + d * 4 * np.sqrt(poly.area + poly.length**2)
    cut = poly.exterior.intersection(LineString([apex, far]))
    pts = np.array([g.coords[0] for g in getattr(cut, "geoms", [cut]) if not g.is_empty])
    if len(pts) == 0:
        return c
    return pts[np.argmax((pts - apex) @ d)]


def _width_near(poly: Polygon, end: np.ndarray, other: np.ndarray, share: float) -> float:
    """The blade's width across the axis at `share` of the way from `end` to `other`."""
    d = other - end
    at = end + share * d
    n = np.array([-d[1], d[0]]) / np.linalg.norm(d) * 2 * np.linalg.norm(d)
    return poly.intersection(LineString([at - n, at + n])).length


def find_axis(poly: Polygon, base: np.ndarray | None, near_origin: np.ndarray | None = None):
    """(base, apex) of an outline: the apex is the margin point farthest from a given base; with
    no base, the longest axis's end that lies at the origin (the forms' convention) is the base,
    else its wider end (most leaves are widest below the middle)."""
    if base is not None:
        ring = np.asarray(poly.exterior.coords)[:-1]
        apex = ring[np.argmax(np.linalg.norm(ring - base, axis=1))]
        return np.asarray(base, dtype=float), apex
    e1, e2 = _ends(poly)
    candidates = [(_base_from_apex(poly, e2), e2), (_base_from_apex(poly, e1), e1)]
    length = np.linalg.norm(e2 - e1)
    if near_origin is not None:
        dist = [np.linalg.norm(b - near_origin) for b, _ in candidates]
        if min(dist) < 0.1 * length <= max(dist):
            return candidates[int(np.argmin(dist))]
    wide = [_width_near(poly, b, a, 0.25) for b, a in candidates]
    return candidates[int(np.argmax(wide))]


def _chords(poly: Polygon, xs: np.ndarray, mid: np.ndarray) -> np.ndarray:
    """(n, 2) the y-range of the blade's cross-section at each x (the part holding mid[i])."""
    span = 4 * (poly.bounds[3] - poly.bounds[1]) + 1
    lines = shapely.linestrings(
        np.stack(
            [
                np.column_stack([xs, np.full_like(xs, -span)]),
                np.column_stack([xs, np.full_like(xs, span)]),
            ],
            axis=1,
        )
    )
    out = np.zeros((len(xs), 2))
    for i, cut in enumerate(shapely.intersection(getattr(poly, "poly", poly), lines)):
        parts = [
            g for g in getattr(cut, "geoms", [cut]) if isinstance(g, LineString) and not g.is_empty
        ]
        if not parts:
            out[i] = mid[i], mid[i]
            continue
        ranges = [(min(c[1] for c in g.coords), max(c[1] for c in g.coords)) for g in parts]
        gaps = [
            0 if lo <= mid[i] <= hi else min(abs(lo - mid[i]), abs(hi - mid[i]))
            for lo, hi in ranges
        ]
        out[i] = ranges[int(np.argmin(gaps))]
    return out


class _Blade:
    """The blade's polygon with a fast inside test and distance to the margin (a k-d tree over
    the margin resampled at a fine step: shapely's exact distance is many times slower)."""

    def __init__(self, poly: Polygon) -> None:
        self.poly = poly
        shapely.prepare(poly)
        ring = poly.exterior
        step = ring.length / max(int(ring.length / 0.002), 64)
        dense = shapely.get_coordinates(ring.segmentize(step))
        self.tree = cKDTree(dense)
        self.area = poly.area

    def __getattr__(self, name: str):
        return getattr(self.poly, name)

    def gap(self, pts: np.ndarray) -> np.ndarray:
        """(n,) distance from each point to the margin."""
        return self.tree.query(np.asarray(pts, dtype=float))[0]

    def inside(self, pts: np.ndarray, margin: float = 0.0) -> np.ndarray:
        pts = np.asarray(pts, dtype=float)
        inside = shapely.contains_xy(self.poly, pts[:, 0], pts[:, 1])
        if margin > 0:
            inside &= self.gap(pts) > margin
        return inside


def _inside(blade: _Blade, pts: np.ndarray, margin: float = 0.0) -> np.ndarray:
    return blade.inside(pts, margin)


def _midrib(poly: Polygon) -> np.ndarray:
    """Base (0, 0) to apex (1, 0): straight if that stays inside, else through the middle of the
    cross-sections."""
    x = np.linspace(*MIDRIB_SPAN, max(int((MIDRIB_SPAN[1] - MIDRIB_SPAN[0]) / STEP), 8))
    straight = np.column_stack([x, np.zeros_like(x)])
    if _inside(poly, straight).all():
        return straight
    chords = _chords(poly, x, np.zeros_like(x))
    y = chords.mean(axis=1)
    y = np.convolve(np.pad(y, 2, mode="edge"), np.ones(5) / 5, mode="valid")
    return np.column_stack([x, y])


def _ray_end(poly: Polygon, start: np.ndarray, target: np.ndarray, share: float) -> np.ndarray:
    """Points from `start` toward `target`, up to `share` of the way, cut where they leave."""
    t = np.linspace(0, share, max(int(share * np.linalg.norm(target - start) / STEP), 4))
    pts = start + t[:, None] * (target - start)
    inside = _inside(poly, pts)
    inside[0] = True
    stop = np.argmin(inside) if not inside.all() else len(pts)
    return pts[:stop]


def _palmate_primaries(poly: _Blade, rng: np.random.Generator) -> list[np.ndarray]:
    """Two or four primaries from the base to the farthest margin points either side that the
    base sees: the straight vein stays inside the blade, clear of the sinuses."""
    ring = np.asarray(poly.exterior.coords)[:-1]
    angle = np.degrees(np.arctan2(ring[:, 1], ring[:, 0]))
    dist = np.linalg.norm(ring, axis=1)
    inner = poly.poly.buffer(-0.5 * STEP)
    shapely.prepare(inner)
    out = []
    for lo, hi, least in ((22, 70, 0.0), (75, 130, 0.3)):
        for sign in (1, -1):
            pick = np.flatnonzero((sign * angle >= lo) & (sign * angle <= hi))
            if len(pick) == 0 or dist[pick].max() < least:
                continue
            for index in pick[np.argsort(-dist[pick])][:60:3]:
                target = ring[index]
                start = np.array([0.012 * np.sign(target[0] + 1e-9), 0.0])
                end = start + 0.92 * (target - start)
                if inner.contains(LineString([start, end])):
                    vein = _ray_end(poly, start, target, 0.92)
                    if len(vein) >= 4:
                        out.append(vein)
                    break
    return out


def _parallel(poly: Polygon, count: int) -> list[np.ndarray]:
    """2 * count + 1 veins through fixed fractions of every cross-section, base to apex."""
    x = np.linspace(0.015, 0.985, 70)
    chords = _chords(poly, x, np.zeros_like(x))
    total = 2 * count + 1
    fractions = (np.arange(total) + 1) / (total + 1)
    inset = 0.04 * (chords[:, 1] - chords[:, 0])
    lo, hi = chords[:, 0] + inset, chords[:, 1] - inset
    return [np.column_stack([x, lo + f * (hi - lo)]) for f in fractions]


def _sources(poly: Polygon, rng: np.random.Generator) -> tuple[np.ndarray, float]:
    """Auxin sources on a jittered grid over the blade, and their spacing."""
    h = float(np.sqrt(poly.area / SOURCES))
    x0, y0, x1, y1 = poly.bounds
    gx, gy = np.meshgrid(np.arange(x0 + h / 2, x1, h), np.arange(y0 + h / 2, y1, h))
    pts = np.column_stack([gx.ravel(), gy.ravel()]) + rng.uniform(-0.35, 0.35, (gx.size, 2)) * h
    return pts[_inside(poly, pts, 0.3 * h)], h


def _stations(vein: np.ndarray, count: int, lo: float, hi: float, rng) -> list[tuple[int, int]]:
    """(index along the vein, side) of `count` seeds per side, alternating."""
    n = len(vein)
    out = []
    for side in (1, -1):
        shift = 0.0 if side == 1 else 0.5
        for j in range(count):
            f = lo + (hi - lo) * (j + 0.25 + shift * 0.5 + rng.uniform(-0.08, 0.08)) / count
            out.append((int(np.clip(round(f * (n - 1)), 1, n - 2)), side))
    return out


def growth_step(poly: Polygon) -> float:
    """The growth step D: STEP, or a fixed share of a broad blade's size (as many steps across a
    round leaf as across a narrow one), and at most a NARROW_STEPS-th of a narrow blade's
    half-width (its inscribed circle's radius). With STEP alone a blade over about 20 times
    longer than wide (a grass-like linear leaf) had no room for a secondary: its pinnate and
    arcuate secondaries all came out shorter than three steps and were dropped (review finding)."""
    step = max(STEP, BROAD_STEP * np.sqrt(poly.area))
    shape = getattr(poly, "poly", poly)  # a _Blade's polygon
    half = float(shapely.maximum_inscribed_circle(shape, 0.01 * step).length)
    return min(step, half / NARROW_STEPS)


def _colonize(
    poly: Polygon,
    primaries: list[np.ndarray],
    seeds: list[tuple[np.ndarray, np.ndarray, np.ndarray]],
    arcuate: bool,
    rng: np.random.Generator,
    tropism: float = TROPISM,
) -> list[np.ndarray]:
    """Space colonization from the seeds (station, start, preferred direction): each seed's
    longest path, beginning at its station on a primary, in steps of growth_step."""
    step = growth_step(poly)
    sources, h = _sources(poly, rng)
    fixed = np.vstack(primaries)
    pos = [fixed] + [s[1][None] for s in seeds]
    nodes = np.vstack(pos)
    n_fixed = len(fixed)
    tree_of = np.r_[np.full(n_fixed, -1), np.arange(len(seeds))]
    parent = np.r_[np.full(n_fixed, -1), np.full(len(seeds), -1)]
    depth = np.zeros(len(nodes), int)
    bias = np.array([s[2] for s in seeds])
    kill = KILL * step
    dist, near = cKDTree(nodes).query(sources)  # each source's nearest node, kept up to date
    for _ in range(MAX_ITERATIONS):
        alive = dist > kill
        sources, dist, near = sources[alive], dist[alive], near[alive]
        grow = tree_of[near] >= 0
        if not grow.any():
            break
        src, node = sources[grow], near[grow]
        unit = (src - nodes[node]) / np.maximum(dist[grow], 1e-12)[:, None]
        growing, slot = np.unique(node, return_inverse=True)
        total = np.zeros((len(growing), 2))
        np.add.at(total, slot, unit)
        direction = total / np.maximum(np.linalg.norm(total, axis=1), 1e-12)[:, None]
        pull = tropism * bias[tree_of[growing]]
        if arcuate:
            gap = poly.gap(nodes[growing])
            pull = pull * (1 + 3 * np.clip(1 - gap / (4 * h), 0, 1))[:, None]
        direction = direction + pull
        direction /= np.maximum(np.linalg.norm(direction, axis=1), 1e-12)[:, None]
        new = nodes[growing] + step * direction
        ok = _inside(poly, new, 0.3 * step)
        if not ok.any():
            break
        blocked = np.isin(near, growing[~ok])  # their node cannot step toward them: drop them
        dist[blocked] = 0.0
        growing, new = growing[ok], new[ok]
        first = len(nodes)
        nodes = np.vstack([nodes, new])
        tree_of = np.r_[tree_of, tree_of[growing]]
        parent = np.r_[parent, growing]
        depth = np.r_[depth, depth[growing] + 1]
        d_new, i_new = cKDTree(new).query(sources)
        closer = d_new < dist
        dist[closer], near[closer] = d_new[closer], first + i_new[closer]
    paths = []
    for k, (station, _start, _) in enumerate(seeds):
        members = np.flatnonzero(tree_of == k)
        # the secondary ends at the node nearest the margin, of those farthest from its station
        reach = np.linalg.norm(nodes[members] - station, axis=1) - poly.gap(nodes[members])
        tip = members[np.argmax(reach)]
        path = []
        while tip >= 0:
            path.append(nodes[tip])
            tip = parent[tip]
        paths.append(_smooth(np.vstack([station[None], *path[::-1]])))
    return paths


def _smooth(path: np.ndarray, passes: int = 3) -> np.ndarray:
    """A path with its zig-zags eased ((1, 2, 1) / 4 averaging, the ends kept)."""
    for _ in range(passes):
        if len(path) < 3:
            break
        inner = 0.25 * path[:-2] + 0.5 * path[1:-1] + 0.25 * path[2:]
        path = np.vstack([path[:1], inner, path[-1:]])
    return path


def _to_margin(poly: Polygon, path: np.ndarray, step: float = STEP) -> np.ndarray:
    """An open secondary continued straight on to just inside the margin (in half `step`s)."""
    if len(path) < 2:
        return path
    d = path[-1] - path[max(len(path) - 4, 0)]
    d /= max(np.linalg.norm(d), 1e-12)
    steps = path[-1] + np.outer(np.arange(1, 80) * step / 2, d)
    ok = _inside(poly, steps, INSET)
    n = np.argmin(ok) if not ok.all() else len(steps)
    path = np.vstack([path, steps[:n]])
    gap, nearest = poly.tree.query(path[-1])
    if gap > 3 * INSET:  # stopped short (its way ahead leaves the blade): turn to the margin
        target = poly.tree.data[nearest]
        share = 1 - INSET / gap
        t = np.linspace(0, share, int(gap / (step / 2)) + 2)[1:]
        path = np.vstack([path, path[-1] + np.outer(t, target - path[-1])])
    return path


def _arch_ring(poly: _Blade, step: float = STEP) -> np.ndarray | None:
    """(r, 2) points along the margin moved inward, in order, at half a step (the arches' way);
    in a narrow blade (growth_step under STEP) halfway between the margin and the midrib."""
    inset = max(2.5 * STEP, 0.02 * np.sqrt(poly.area))
    if step < STEP:
        inset = min(inset, 0.5 * NARROW_STEPS * step)  # half the half-width
    inner = poly.poly.buffer(-inset)
    if inner.is_empty:
        return None
    if not isinstance(inner, Polygon):
        inner = max(inner.geoms, key=lambda g: g.area)
    return shapely.get_coordinates(inner.exterior.segmentize(step / 2))[:-1]


def _arch(
    ring: np.ndarray | None,
    path: np.ndarray,
    owner: int,
    veins: cKDTree,
    owners: np.ndarray,
    h: float,
    step: float = STEP,
) -> np.ndarray:
    """An arcuate secondary continued along the margin toward the apex until it nears another
    vein (`veins` holds all veins' points, `owners` which vein each belongs to)."""
    if ring is None or len(path) < 2:
        return path
    n = len(ring)
    i = int(np.argmin(np.linalg.norm(ring - path[-1], axis=1)))
    sign = 1 if ring[(i + 2) % n, 0] > ring[(i - 2) % n, 0] else -1
    walk = ring[(i + sign * np.arange(1, int(0.35 / (step / 2)))) % n]  # the ring's spacing
    ahead = walk[:, 0] > path[-1][0] - step
    walk = walk[: np.argmin(ahead) if not ahead.all() else len(walk)]
    if len(walk) == 0:
        return path
    dist, index = veins.query(walk, k=min(8, len(owners)))
    near = np.any((dist < 1.5 * h) & (owners[index] != owner), axis=1)
    walk = walk[: np.argmax(near) if near.any() else len(walk)]
    return np.vstack([path, walk]) if len(walk) else path


def _cut_crossings(vein: np.ndarray, laid: list[np.ndarray], step: float = STEP) -> np.ndarray:
    """The vein up to a `step` before it first crosses one already laid (its start may touch)."""
    if len(vein) < 3 or not laid:
        return vein
    rest = LineString(vein[1:])
    cut = rest.intersection(MultiLineString([v for v in laid if len(v) >= 2]))
    if cut.is_empty:
        return vein
    pts = [g.coords[0] for g in getattr(cut, "geoms", [cut]) if not g.is_empty]
    first = min(rest.project(shapely.Point(p)) for p in pts)
    s = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(vein[1:], axis=0), axis=1))])
    keep = int(np.searchsorted(s, first - step))
    return vein[: keep + 1]


def grow_veins(
    boundary: np.ndarray,
    venation: str = "pinnate",
    secondaries: int | None = None,
    base: np.ndarray | None = None,
    seed: int = 0,
    *,
    apex: np.ndarray | None = None,
) -> list[np.ndarray]:
    """Veins of the chosen kind grown inside any outline (see the module docstring for the method).

    Parameters
    ----------
    boundary : (n, 2) or (n, 3) float array
        The outline, in order around the leaf (unordered points are ordered first).
    venation : {"pinnate", "palmate", "parallel", "arcuate"}, default: "pinnate"
    secondaries : int, optional
        Secondary veins on each side of the midrib (parallel: veins either side of the middle
        one); default 6 (palmate: 3 per primary side, parallel: 3).
    base : (2,) or (3,) float array, optional
        Where the midrib meets the blade. Default: an end of the outline's longest axis (the one at
        the origin if there is one, else the wider).
    seed : int, default: 0
        Varies the sources and the seeds' places; the same seed gives the same veins.
    apex : (2,) or (3,) float array, optional
        Where the midrib ends; default the margin point farthest from the base.

    Returns
    -------
    list of (m_i, 3) float arrays
        The midrib first (palmate: then the other primaries), each vein from its start to its
        end, in the boundary's coordinates; z is the height (for a 2D outline, above z = 0).

    Raises
    ------
    LeafError
        For an unknown venation, or an outline too small or degenerate to grow veins in.

    Examples
    --------
    >>> import numpy as np
    >>> from leafstudio.forms import grow_veins
    >>> t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    >>> outline = np.column_stack([0.5 + 0.5 * np.cos(t), 0.25 * np.sin(t)])
    >>> veins = grow_veins(outline, "pinnate", secondaries=4)
    >>> len(veins), veins[0].shape
    (9, (49, 3))
    """
    points = np.asarray(boundary, dtype=float)
    if points.ndim != 2 or points.shape[1] not in (2, 3) or len(points) < 3:
        raise LeafError(
            f"the outline must be an (n, 2) or (n, 3) array, n >= 3, got {points.shape}"
        )
    if not np.all(np.isfinite(points)):
        raise LeafError("the outline contains NaN or infinite coordinates")
    # grown at about unit size whatever the outline's units (1e-90 or 1e300: no overflow), by
    # an exact map, so that a leaf of ordinary size gets the very same veins; then mapped back
    units = Units.exact(points)  # (_grow_unit refuses an outline without area)

    def unit(at: np.ndarray | None) -> np.ndarray | None:
        if at is None:
            return None
        at = np.asarray(at, dtype=float).ravel()
        if not np.all(np.isfinite(at)):
            raise LeafError(f"a point of the midrib's ends is not finite: {at}")
        return (at - units.offset[: len(at)]) / units.scale

    veins = _grow_unit(
        units.to_unit(points), venation, secondaries, unit(base), seed, apex=unit(apex)
    )
    offset = np.r_[units.offset, 0.0][:3]  # a 2D outline: (x, y, 0), z is the height above 0
    return [offset + units.scale * v for v in veins]


def check_seed(seed: object) -> None:
    """LeafError unless `seed` is a whole number numpy's generators take."""
    whole = isinstance(seed, int | np.integer) and not isinstance(seed, bool)
    if not whole or not 0 <= seed <= SEED_MAX:
        raise LeafError(f"the seed must be a whole number from 0 to {SEED_MAX}, got {seed!r}")


def _grow_unit(
    boundary: np.ndarray,
    venation: str,
    secondaries: int | None,
    base: np.ndarray | None,
    seed: int,
    *,
    apex: np.ndarray | None,
) -> list[np.ndarray]:
    """grow_veins on an outline of unit size centred on the origin."""
    if venation not in VENATION_KINDS:
        raise LeafError(f"unknown venation {venation!r}; choose from {', '.join(VENATION_KINDS)}")
    count = DEFAULT_SECONDARIES[venation] if secondaries is None else int(secondaries)
    if not 0 <= count <= 40:
        raise LeafError(f"secondaries must be between 0 and 40, got {count}")
    check_seed(seed)
    rng = np.random.default_rng(seed)
    xy, heights, frame, base_xy = _plane(boundary, base)
    size = float(np.ptp(xy, axis=0).max())
    if size == 0 or Polygon(xy).convex_hull.area <= 1e-9 * size**2:
        raise LeafError("the outline encloses no area (its points lie on one line)")
    poly = _polygon(xy)
    if base_xy is not None and not poly.contains(Point(base_xy)):
        away = poly.exterior.distance(Point(base_xy)) / size
        if not away <= BASE_REACH:  # veins from there would run outside the blade
            how_far = f"{away:.3g} of its size" if np.isfinite(away) else "far"
            raise LeafError(
                f"the base lies outside the outline, {how_far} from the margin; give a point on "
                "the margin"
            )
    origin = None
    if frame is None or not hasattr(frame, "to_plane"):
        origin = np.zeros(2)
    else:
        origin = frame.to_plane(np.zeros((1, 3)))[0][0]
    b, a = find_axis(poly, base_xy, origin)
    if apex is not None:
        a = np.asarray(apex, dtype=float).ravel()[:2]
        if frame is not None and hasattr(frame, "to_plane") and len(np.ravel(apex)) == 3:
            a = frame.to_plane(np.asarray(apex, dtype=float)[None])[0][0]
    length = float(np.linalg.norm(a - b))
    if length <= 0:
        raise LeafError("the outline has no length: base and apex coincide")
    u = (a - b) / length
    v = np.array([-u[1], u[0]])
    local = lambda p: np.column_stack([(p - b) @ u, (p - b) @ v]) / length  # noqa: E731
    world = lambda q: b + length * (q[:, :1] * u + q[:, 1:2] * v)  # noqa: E731
    shape = Polygon(local(np.asarray(poly.exterior.coords)))
    blade = _Blade(shape if shape.is_valid else shape.buffer(0))

    midrib = _midrib(blade)
    veins: list[np.ndarray] = []
    if venation == "parallel":
        veins = _parallel(blade, count)
        veins = [veins[len(veins) // 2]] + [w for i, w in enumerate(veins) if i != len(veins) // 2]
    else:
        primaries = [midrib]
        if venation == "palmate":
            primaries += _palmate_primaries(blade, rng)
        seeds = []
        step = growth_step(blade)
        for k, prim in enumerate(primaries):
            along = np.diff(prim, axis=0)
            along = np.vstack([along, along[-1:]])
            along /= np.maximum(np.linalg.norm(along, axis=1), 1e-12)[:, None]
            if k == 0:
                per, lo, hi = count, 0.03, 0.9
            else:
                per, lo, hi = max(1, (count + 1) // 2), 0.25, 0.9
            for index, side in _stations(prim, per, lo, hi, rng):
                if k > 0 and side * np.sign(prim[-1, 1]) < 0 and venation == "palmate":
                    continue  # a lateral primary's seeds face away from the midrib
                normal = side * np.array([-along[index, 1], along[index, 0]])
                if step < STEP:  # a narrow blade: room for a few steps only, so the secondary
                    # leaves at the angle the tropism gives it in a broad blade, not square
                    normal = np.cos(NARROW_TURN) * normal + np.sin(NARROW_TURN) * along[index]
                turn = np.deg2rad(rng.uniform(-4, 4))
                c, s = np.cos(turn), np.sin(turn)
                tip = along[index] @ np.array([[c, s], [-s, c]])
                seeds.append((prim[index], prim[index] + 0.5 * step * normal, tip))
        tropism = PALMATE_TROPISM if venation == "palmate" else TROPISM
        paths = (
            _colonize(blade, primaries, seeds, venation == "arcuate", rng, tropism) if seeds else []
        )
        h = float(np.sqrt(blade.area / SOURCES))
        veins = list(primaries)
        if venation == "arcuate":
            ring = _arch_ring(blade, step)
            every = [*primaries, *paths]
            owners = np.concatenate([np.full(len(v), k) for k, v in enumerate(every)])
            tree = cKDTree(np.vstack(every))
        for k, path in enumerate(paths):
            if venation == "arcuate":
                path = _arch(ring, path, len(primaries) + k, tree, owners, h, step)
            else:
                path = _to_margin(blade, path, step)
            path = _cut_crossings(path, veins, step)
            reaches = venation == "arcuate" or blade.gap(path[-1:])[0] < 1.25 * step
            if len(path) >= 3 and reaches:  # an open secondary cut short of the margin is dropped
                veins.append(path)
    lift = _lifter(xy, heights, frame, poly)
    return [lift(world(vein), HEIGHT_RATIO * length * blade.gap(vein)) for vein in veins]


def _lifter(xy, heights, frame, poly):
    """Maps plane points and heights above b(x) to the boundary's coordinates."""
    if heights is None:
        z0 = frame if isinstance(frame, float) else 0.0
        return lambda pts, relief: np.column_stack([pts, relief + z0])
    ring = np.asarray(poly.exterior.coords)[:-1]
    near = cKDTree(xy).query(ring)[1]
    base = fit_base(ring, heights[near], float(np.sqrt(poly.area) * 2))
    if base is None:
        return lambda pts, relief: frame.to_world(pts, relief)
    return lambda pts, relief: frame.to_world(pts, relief + base(pts))
