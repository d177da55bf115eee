"""The midrib a photo shows, followed along its ridges (photo.py's ends and the traced midrib).

ridge_midline: the strong ridges' skeleton (photo_veins.find_ridges) followed from its deepest
pixels, straight on through junctions where secondaries branch off, on past a hooked end while
the skeleton stays one line, each end carried on to the outline. along_midrib: that path as the
traced midrib when its ends are the leaf's base and apex; where following straight on crossed
onto a straight vein and jumped back over a gap, the cheapest path between its ends instead.

All in pixels, (column, row) as the outline.
"""

from __future__ import annotations

import numpy as np

from leafstudio.sources.leafends import Midline
from leafstudio.sources.photo_veins import (
    MARGIN_SKIP,
    MIN_VEIN,
    RIDGE_HIGH,
    RIDGE_LOW,
    Ridges,
    cheapest_path,
)

FOLLOW_SEEDS = 6  # the midrib is followed from this many of the deepest ridge pixels
FOLLOW_AHEAD = (2.0, 5.0)  # pixels: the next step is to a skeleton pixel this far ahead
FOLLOW_TURN = 55.0  # degrees: the most a step turns from the path's heading
FOLLOW_HEADING = 12.0  # pixels: the heading is the path's direction over this much of it
END_RUN = 0.08  # of the midrib's length: the direction an end is carried on to the outline
CHAIN_STEP = 2.9  # pixels: past its last step, a path runs on along a skeleton this tight
RIDGE_ENDS = 0.1  # of the length: a followed path whose ends lie this near is the midrib


def along_midrib(
    ridge: tuple[Midline, np.ndarray] | None,
    ridges: Ridges | None,
    base: np.ndarray,
    apex: np.ndarray,
) -> np.ndarray | None:
    """ridge_midline's path (its `ridge`), base end first, when its ends lie within RIDGE_ENDS
    of the midrib's length of `base` and `apex` (it is the midrib), with fewer gaps
    (_fewer_gaps); else None. In pixels (column, row), as trace_veins takes it."""
    if ridge is None or ridges is None:
        return None
    line, path = ridge
    length = float(np.linalg.norm(np.asarray(apex) - np.asarray(base)))
    for ends, way in ((line.ends, 1), (line.ends[::-1], -1)):
        gaps = np.linalg.norm(ends - np.array([base, apex]), axis=1)
        if gaps.max() <= RIDGE_ENDS * length:
            local = path[::way] - ridges.corner
            return _fewer_gaps(local, ridges.strength, ridges.blade) + ridges.corner
    return None


def _fewer_gaps(ridge: np.ndarray, strength: np.ndarray, blade: np.ndarray) -> np.ndarray:
    """The followed ridge (n, 2), or the cheapest path between its ends when the ridge jumps a
    gap (a step over FOLLOW_AHEAD) and the cheapest path runs off the ridges less: following
    straight on can cross onto a straight vein that cuts across a bend of the midrib and jump
    back to the midrib where that vein stops."""
    steps = np.linalg.norm(np.diff(ridge, axis=0), axis=1)
    if not len(steps) or steps.max() <= FOLLOW_AHEAD[1]:
        return ridge
    cheapest = cheapest_path(strength, blade, ridge[0], ridge[-1])
    return cheapest if _off_ridge(cheapest, strength) < _off_ridge(ridge, strength) else ridge


def _off_ridge(path: np.ndarray, strength: np.ndarray) -> float:
    """How many pixels of a path (n, 2) run off the strong ridges."""
    import shapely

    dense = shapely.get_coordinates(shapely.segmentize(shapely.LineString(path), 1.0))
    at = dense.astype(int)
    return float(np.count_nonzero(strength[at[:, 1], at[:, 0]] < RIDGE_LOW))


def ridge_midline(ridges: Ridges | None, outline: np.ndarray) -> tuple[Midline, np.ndarray] | None:
    """The midrib the photo shows: a Midline with its two ends where it meets the outline, and
    the ridge's own (n, 2) path in pixels (column, row); None when the photo shows no clear
    ridges.

    The strong ridges (hysteresis, as the secondaries) are thinned to skeletons. The midrib is
    followed from the skeleton's deepest pixel in the blade (the midrib runs down the middle,
    secondaries out to the margin) both ways, each step to the skeleton pixel a few pixels ahead
    that turns least (under FOLLOW_TURN; across gaps up to MARGIN_SKIP ridge widths, where the
    filter loses the midrib at a junction), so it goes straight through junctions where a
    secondary branches off. Each end is carried on along the path's last END_RUN of its length
    to the outline (the margin band has no ridges).

    Parameters
    ----------
    ridges : Ridges or None
        find_ridges on the photo and its blade.
    outline : (n, 2) float array
        The blade's outline, (column, row).
    """
    from scipy.ndimage import convolve, distance_transform_edt
    from skimage.filters import apply_hysteresis_threshold
    from skimage.morphology import skeletonize

    if ridges is None or not ridges.any:
        return None
    strength, blade, corner, widths = ridges.strength, ridges.blade, ridges.corner, ridges.widths
    size = float(np.hypot(*blade.shape))
    skeleton = skeletonize(apply_hysteresis_threshold(strength, RIDGE_LOW, RIDGE_HIGH))
    neighbours = convolve(skeleton.astype(int), np.ones((3, 3), int), mode="constant") - 1
    knots = skeleton & (neighbours != 2)  # junctions and ends
    simple = skeleton & (distance_transform_edt(~knots) > FOLLOW_AHEAD[1])  # on a clear line
    if not simple.any():
        return None
    depth = ridges.depth
    srow, scol = np.nonzero(skeleton)
    pixels = np.column_stack([scol, srow]) + 0.5
    gap = MARGIN_SKIP * float(widths.max())
    best, best_weight = None, 0.0
    for seed in _seeds(simple, depth, FOLLOW_SEEDS, MIN_VEIN * size):
        near = pixels[np.linalg.norm(pixels - seed, axis=1) <= FOLLOW_AHEAD[1]]
        heading = np.linalg.eigh(np.cov((near - seed).T))[1][:, -1]
        halves = [_follow(pixels, seed, way * heading, gap) for way in (-1, 1)]
        path = np.vstack([halves[0][::-1], halves[1][1:]])
        weight = _weight(path, depth)
        if weight > best_weight:
            best, best_weight = path, weight
    if best is None or float(np.linalg.norm(best[-1] - best[0])) < MIN_VEIN * size:
        return None
    path = best
    local = outline - corner
    ends = np.array([_to_outline(path, local), _to_outline(path[::-1], local)]) + corner
    span = float(np.linalg.norm(ends[1] - ends[0]))
    line = Midline(ends=ends, along=(ends[1] - ends[0]) / max(span, 1e-12), mirror=0.0)
    return line, path + corner


def _seeds(simple: np.ndarray, depth: np.ndarray, count: int, apart: float) -> list[np.ndarray]:
    """Up to `count` pixels of `simple`, deepest first, at least `apart` from each other,
    (column, row) pixel centres."""
    rows, cols = np.nonzero(simple)
    order = np.argsort(depth[rows, cols])[::-1]
    seeds: list[np.ndarray] = []
    for i in order:
        at = np.array([cols[i], rows[i]]) + 0.5
        if all(np.linalg.norm(at - s) >= apart for s in seeds):
            seeds.append(at)
            if len(seeds) == count:
                break
    return seeds


def _weight(path: np.ndarray, depth: np.ndarray) -> float:
    """A path's length, each step weighed by its depth in the blade."""
    steps = np.linalg.norm(np.diff(path, axis=0), axis=1)
    at = np.clip(path[1:].astype(int), 0, [depth.shape[1] - 1, depth.shape[0] - 1])
    return float(np.sum(steps * depth[at[:, 1], at[:, 0]]))


def _follow(pixels: np.ndarray, start: np.ndarray, heading: np.ndarray, gap: float) -> np.ndarray:
    """The path from `start` along skeleton `pixels` (m, 2), each step the one that turns least
    from the heading (FOLLOW_AHEAD, FOLLOW_TURN), across gaps up to `gap` pixels; (n, 2)."""
    from scipy.spatial import cKDTree

    tree = cKDTree(pixels)
    used = np.zeros(len(pixels), dtype=bool)
    path = [start]
    steps: list[float] = []  # each step's length, for _back_along
    cos_turn = np.cos(np.deg2rad(FOLLOW_TURN))
    for _ in range(len(pixels)):
        here = path[-1]
        used[tree.query_ball_point(here, FOLLOW_AHEAD[0])] = True
        step = None
        for reach in (FOLLOW_AHEAD[1], gap):
            ahead = np.asarray(tree.query_ball_point(here, reach), dtype=np.intp)
            ahead = ahead[~used[ahead]]
            if not len(ahead):
                continue
            offsets = pixels[ahead] - here
            lengths = np.linalg.norm(offsets, axis=1)
            cosines = offsets @ heading / np.maximum(lengths, 1e-12)
            ok = (cosines >= cos_turn) & (lengths >= FOLLOW_AHEAD[0] * (reach == gap))
            if ok.any():
                pick = np.flatnonzero(ok)[np.argmax(cosines[ok] - 0.01 * lengths[ok])]
                step = pixels[ahead[pick]]
                break
        if step is None:
            break
        steps.append(float(np.linalg.norm(step - here)))
        path.append(step)
        direction = step - _back_along(path, steps, FOLLOW_HEADING)
        norm = np.linalg.norm(direction)
        if norm > 0:
            heading = direction / norm
    return _chain_on(pixels, tree, np.array(path))


def _chain_on(pixels: np.ndarray, tree, path: np.ndarray) -> np.ndarray:
    """The path carried on along the skeleton past a turn too sharp to follow (a hooked base)
    while the skeleton ahead is one line (its next pixels within CHAIN_STEP of each other; a
    junction ends it); (n, 2)."""
    import shapely

    dense = shapely.get_coordinates(shapely.segmentize(shapely.LineString(path), 1.0))
    used = np.zeros(len(pixels), dtype=bool)
    for near in tree.query_ball_point(dense, 1.5):  # the pixels next to it
        used[near] = True
    out = list(path)
    while True:
        ahead = [i for i in tree.query_ball_point(out[-1], CHAIN_STEP) if not used[i]]
        if not ahead:
            break
        spots = pixels[ahead]
        spread = np.linalg.norm(spots[:, None] - spots[None], axis=2).max()
        if spread > CHAIN_STEP:  # two ways on: a junction
            break
        used[ahead] = True
        out.append(spots[np.argmax(np.linalg.norm(spots - out[-1], axis=1))])
    return np.array(out)


def _back_along(path: list[np.ndarray], steps: list[float], distance: float) -> np.ndarray:
    """The point `distance` back along the path from its last point (its first if shorter);
    `steps`: the path's step lengths, steps[k - 1] from path[k - 1] to path[k]."""
    total = 0.0
    for k in range(len(path) - 1, 0, -1):
        total += steps[k - 1]
        if total >= distance:
            return path[k - 1]
    return path[0]


def _to_outline(path: np.ndarray, outline: np.ndarray) -> np.ndarray:
    """Where the path, carried on from its first point backwards (along its first END_RUN),
    meets the outline; the nearest outline point if the line misses it."""
    import shapely

    steps = np.linalg.norm(np.diff(path, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(steps)])
    back = path[min(int(np.searchsorted(arc, END_RUN * arc[-1])), len(path) - 1)]
    direction = path[0] - back
    norm = float(np.linalg.norm(direction))
    ring = shapely.LinearRing(outline)
    if norm > 0:
        reach = float(np.ptp(outline, axis=0).sum())
        ray = shapely.LineString([path[0], path[0] + direction / norm * reach])
        hits = shapely.get_coordinates(ray.intersection(ring))
        if len(hits):
            return hits[np.argmin(np.linalg.norm(hits - path[0], axis=1))]
    return outline[np.argmin(np.linalg.norm(outline - path[0], axis=1))]
