"""The veins' growth in a blade (veins.py, method steps 1-2): the primaries laid first, then the
secondaries by space colonization from seeds along them, each continued to the margin (open) or
along it (arcuate) and cut where it would cross a vein already laid. Works in the blade's own
frame: base at (0, 0), apex at (1, 0).
"""

from __future__ import annotations

import numpy as np
import shapely
from scipy.spatial import cKDTree
from shapely.geometry import LineString, MultiLineString, Polygon

from leafstudio.forms.blade import Blade, cross_sections

BROAD_STEP = 0.035  # the growth step of a broad blade, as a share of the square root of its area
STEP = 0.02  # growth step D, in leaf lengths
NARROW_STEPS = 2  # a blade's half-width holds at least this many growth steps (see growth_step)
SOURCES = 350  # auxin sources scattered over the blade
KILL = 1.2  # kill distance, in growth steps
MAX_ITERATIONS = 80
TROPISM = 0.6  # pull toward the apex added to each growth direction
INSET = 0.006  # open secondaries end this far (leaf lengths) inside the margin
MIDRIB_SPAN = (0.01, 0.99)  # the midrib's share of base -> apex


def lay_midrib(poly: Polygon) -> np.ndarray:
    """Base (0, 0) to apex (1, 0): straight if that stays inside, else through the middle of the
    cross-sections."""
    x = np.linspace(*MIDRIB_SPAN, max(int((MIDRIB_SPAN[1] - MIDRIB_SPAN[0]) / STEP), 8))
    straight = np.column_stack([x, np.zeros_like(x)])
    if poly.inside(straight).all():
        return straight
    chords = cross_sections(poly, x, np.zeros_like(x))
    y = chords.mean(axis=1)
    y = np.convolve(np.pad(y, 2, mode="edge"), np.ones(5) / 5, mode="valid")
    return np.column_stack([x, y])


def _ray_end(poly: Polygon, start: np.ndarray, target: np.ndarray, share: float) -> np.ndarray:
    """Points from `start` toward `target`, up to `share` of the way, cut where they leave."""
    t = np.linspace(0, share, max(int(share * np.linalg.norm(target - start) / STEP), 4))
    pts = start + t[:, None] * (target - start)
    inside = poly.inside(pts)
    inside[0] = True
    stop = np.argmin(inside) if not inside.all() else len(pts)
    return pts[:stop]


def palmate_primaries(poly: Blade, rng: np.random.Generator) -> list[np.ndarray]:
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


def parallel_veins(poly: Polygon, count: int) -> list[np.ndarray]:
    """2 * count + 1 veins through fixed fractions of every cross-section, base to apex."""
    x = np.linspace(0.015, 0.985, 70)
    chords = cross_sections(poly, x, np.zeros_like(x))
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
    return pts[poly.inside(pts, 0.3 * h)], h


def stations(vein: np.ndarray, count: int, lo: float, hi: float, rng) -> list[tuple[int, int]]:
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
    tolerance = 0.01 * step
    if isinstance(poly, Blade) and poly.radius_below() - tolerance >= NARROW_STEPS * step:
        return step  # broad enough for certain: the inscribed circle (8 ms a form) not needed
    shape = getattr(poly, "poly", poly)  # a Blade's polygon
    half = float(shapely.maximum_inscribed_circle(shape, tolerance).length)
    return min(step, half / NARROW_STEPS)


def colonize(
    poly: Polygon,
    primaries: list[np.ndarray],
    seeds: list[tuple[np.ndarray, np.ndarray, np.ndarray]],
    arcuate: bool,
    rng: np.random.Generator,
    tropism: float = TROPISM,
    step: float | None = None,
) -> list[np.ndarray]:
    """Space colonization from the seeds (station, start, preferred direction): each seed's
    longest path, beginning at its station on a primary, in steps of growth_step (`step`: the
    caller's, when it has it: the inscribed circle is most of the step's cost)."""
    step = growth_step(poly) if step is None else step
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
        ok = poly.inside(new, 0.3 * step)
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


def to_margin(poly: Polygon, path: np.ndarray, step: float = STEP) -> np.ndarray:
    """An open secondary continued straight on to just inside the margin (in half `step`s)."""
    if len(path) < 2:
        return path
    d = path[-1] - path[max(len(path) - 4, 0)]
    d /= max(np.linalg.norm(d), 1e-12)
    steps = path[-1] + np.outer(np.arange(1, 80) * step / 2, d)
    ok = poly.inside(steps, INSET)
    n = np.argmin(ok) if not ok.all() else len(steps)
    path = np.vstack([path, steps[:n]])
    gap, nearest = poly.tree.query(path[-1])
    if gap > 3 * INSET:  # stopped short (its way ahead leaves the blade): turn to the margin
        target = poly.tree.data[nearest]
        share = 1 - INSET / gap
        t = np.linspace(0, share, int(gap / (step / 2)) + 2)[1:]
        path = np.vstack([path, path[-1] + np.outer(t, target - path[-1])])
    return path


def arch_ring(poly: Blade, step: float = STEP) -> np.ndarray | None:
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


def arch(
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
    # the path up to where it first reaches the ring: run on past it toward the margin, the arch
    # walked back from the ring's nearest point, a Z at the start of every arch
    reached = np.flatnonzero(cKDTree(ring).query(path[1:])[0] < 0.5 * step)
    if len(reached):
        path = path[: reached[0] + 2]
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
    return _smooth(np.vstack([path, walk])) if len(walk) else path  # the turn onto the ring eased


def cut_crossings(vein: np.ndarray, laid: list[np.ndarray], step: float = STEP) -> np.ndarray:
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
