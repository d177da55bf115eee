"""An extracted scan blade's veins, in its flat plane (extract.py, step 4): the base (where the
petiole joins, the end a world axis names, or the wider end), the midrib from the base to the
tip through the middles of the blade's cross-sections (smoothed, as a midrib runs straight on
past a lobe or a bay, but kept on the blade), and side veins straight from the midrib toward the
margin at SIDE_ANGLE, cut where the scan has a gap."""

from __future__ import annotations

import itertools

import numpy as np
import shapely
from scipy.ndimage import gaussian_filter1d
from scipy.spatial import cKDTree
from shapely.geometry import LineString, Point, Polygon

from leafstudio.errors import LeafError

SIDE_STATIONS = (0.2, 0.35, 0.5, 0.65, 0.8)  # where side veins leave the midrib (arc length)
SIDE_ANGLE = np.deg2rad(50.0)
SIDE_REACH = 0.85  # side veins stop at this share of the way to the margin
MIDRIB_REACH = (0.02, 0.98)  # the midrib's span along base -> tip
PETIOLE_SHARE = 0.02  # fewer points than this share of the blade's do not mark the base
HALF_STATIONS = np.linspace(0.1, 0.45, 8)  # the wider end: the mean chord over these shares of the
# length from each end. One chord a quarter from each was a coin's toss on a crumpled flat
# blade: soybean pot1_1's came 0.50-1.57 times apart either way round over the scan and ten 97%
# resamples (its base at one end in 6 of 11); these means, 0.61-0.98, always said the end its
# low stalk-like points come down from, and 1.16-1.34 kept soybean pot1_17's (one chord:
# 1.04-1.10) (/work/notes/base38/ratios_halfmeans.txt)
AXES = {"+x": 0, "-x": 0, "+y": 1, "-y": 1, "+z": 2, "-z": 2}
SIDE_POINTS = 4  # a side vein shorter than this many points (of the outline's spacing) is dropped
MIDRIB_SMOOTH = 0.08  # the middles are smoothed over this share of the span (a Gaussian's sigma)
MIDRIB_INSET = 2.0  # ... and a middle smoothed off its part put back this many spacings in:
# extract.py keeps the veins' points one spacing in (vein_order.veins_inside_outline), and a
# midrib that lost its points beside a bay crossed it (sugar beet pot1_7, 3.2 of its 60 units)


def chord_at(polygon: Polygon, u: float):
    """The polygon's cross-section at plane coordinate x = u (a line or several)."""
    lo, hi = polygon.bounds[1] - 1, polygon.bounds[3] + 1
    return polygon.intersection(LineString([(u, lo), (u, hi)]))


def base_point(
    base_end: str, axes: np.ndarray, outline: np.ndarray, xy: np.ndarray, petiole: np.ndarray
) -> np.ndarray:
    """(2,) the blade's base in the plane: where the petiole joins (auto, if there is one), else
    the outline's extreme along the main axis at the base end (auto: the wider end)."""
    u = outline[:, 0]
    if base_end == "auto":
        if len(petiole) >= PETIOLE_SHARE * len(xy):
            joint = cKDTree(xy).query(petiole)[0]
            attach = petiole[np.argsort(joint)[: max(3, len(petiole) // 10)]].mean(axis=0)
            return outline[np.argmin(np.linalg.norm(outline - attach, axis=1))]
        lo, hi = u.min(), u.max()
        polygon = Polygon(outline)
        width = [
            np.mean([chord_at(polygon, lo + f * (hi - lo)).length for f in stations])
            for stations in (HALF_STATIONS, 1.0 - HALF_STATIONS)
        ]
        side = 1.0 if width[1] > width[0] else -1.0
    elif base_end in AXES:
        sign = 1.0 if base_end[0] == "+" else -1.0
        along = sign * axes[0, AXES[base_end]]
        if abs(along) < 1e-6:
            raise LeafError(f"base end {base_end}: the leaf's length lies across that axis")
        side = float(np.sign(along))
    else:
        raise LeafError(f"base end must be auto or one of {', '.join(AXES)}, got {base_end!r}")
    return outline[np.argmax(side * u)]


def midline(outline: np.ndarray, base: np.ndarray, spacing: float) -> np.ndarray:
    """(m, 2) the midrib in the plane, from the base to the tip (the outline point farthest from
    the base) through the middles of the cross-sections square to the base-tip line."""
    tip = outline[np.argmax(np.linalg.norm(outline - base, axis=1))]
    along = (tip - base) / np.linalg.norm(tip - base)
    across = np.array([-along[1], along[0]])
    rotation = np.column_stack([along, across])  # plane -> (along, across)
    polygon = Polygon((outline - base) @ rotation)
    span = float(np.linalg.norm(tip - base))
    stations = span * np.linspace(*MIDRIB_REACH, max(int(span / spacing), 8))
    sections = []  # (u, (k, 2) the ends across of the chord's parts) at each station
    for u in stations:
        chord = chord_at(polygon, u)
        parts = [g for g in getattr(chord, "geoms", [chord]) if isinstance(g, LineString)]
        ends = [p.bounds[1::2] for p in parts if p.length > 0]
        if ends:
            sections.append((u, np.asarray(ends)))
    if len(sections) < 3:
        raise LeafError("could not trace a midrib across the blade")
    line, part = np.zeros((len(sections), 2)), np.zeros((len(sections), 2))
    previous = 0.0
    for k, ((u, _), parts) in enumerate(zip(sections, through(sections), strict=True)):
        part[k] = parts[np.argmin(np.maximum(parts[:, 0] - previous, previous - parts[:, 1]))]
        previous = part[k].mean()
        line[k] = u, previous
    # the middles step where a lobe or a bay starts beside them (sugar beet pot2_3: 79 degrees
    # between tenths of the midrib): smoothed over MIDRIB_SMOOTH of the span, as a midrib runs;
    # and one smoothed off its part put back on it, MIDRIB_INSET spacings in from its end or at
    # its middle (smoothed, sugar beet pot1_7's cut a bay's corner: 4.5 of its 61 units off the
    # blade; no other shared scan's left its parts)
    step = float(np.median(np.diff(line[:, 0])))  # the stations' spacing
    line[:, 1] = gaussian_filter1d(line[:, 1], MIDRIB_SMOOTH * span / step, mode="nearest")
    line[:, 1] = put_back(line[:, 1], part, MIDRIB_INSET * spacing)
    return base + line @ rotation.T


def put_back(middles: np.ndarray, parts: np.ndarray, inset: float) -> np.ndarray:
    """The (m,) `middles` across, each one outside its (m, 2) part's ends moved back onto it,
    `inset` in from the nearer end or at the part's middle when it is narrower than twice that."""
    inset_each = np.minimum(inset, (parts[:, 1] - parts[:, 0]) / 2)
    off = (middles < parts[:, 0]) | (middles > parts[:, 1])
    back = np.clip(middles, parts[:, 0] + inset_each, parts[:, 1] - inset_each)
    return np.where(off, back, middles)


def through(sections: list[tuple[float, np.ndarray]]) -> list[np.ndarray]:
    """Of each (u, (k, 2) its chord parts' ends across) station, the parts on a way through the
    blade from the first station's part nearest the base-tip line to the last one's: each
    overlapping one such part of the stations before it and one of those after it (all its
    parts where no way goes through). The part of a bay's dead end leads nowhere: sugar beet
    pot1_7's tip, on its sheet at SMOOTHING 1e-3, lay on a strip past a bay, and the midrib,
    taken through the part nearest the middle before, crossed the bay."""

    def overlap(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return (a[:, None, 0] <= b[None, :, 1]) & (b[None, :, 0] <= a[:, None, 1])

    def reach(order: list[np.ndarray]) -> list[np.ndarray]:
        first = order[0]
        seen = [np.arange(len(first)) == np.argmin(np.abs(first.mean(axis=1)))]
        for before, parts in itertools.pairwise(order):
            seen.append(overlap(parts, before[seen[-1]]).any(axis=1))
        return seen

    parts = [p for _, p in sections]
    ways = zip(reach(parts), reach(parts[::-1])[::-1], strict=True)
    return [p[both] if (both := a & b).any() else p for p, (a, b) in zip(parts, ways, strict=True)]


def side_veins(polygon: Polygon, midrib: np.ndarray, covered, spacing: float) -> list[np.ndarray]:
    """(k_i, 2) side veins: from midrib stations toward the margin at SIDE_ANGLE, toward the tip,
    up to SIDE_REACH of the way, cut at the first gap in the scan."""
    steps = np.linalg.norm(np.diff(midrib, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(steps)])
    reach = 4 * float(np.hypot(*np.ptp(midrib, axis=0)))
    veins = []
    for station in SIDE_STATIONS:
        i = int(np.clip(np.searchsorted(arc, station * arc[-1]), 1, len(midrib) - 2))
        tangent = midrib[i + 1] - midrib[i - 1]
        tangent /= np.linalg.norm(tangent)
        for turn in (SIDE_ANGLE, -SIDE_ANGLE):
            c, s = np.cos(turn), np.sin(turn)
            direction = np.array([c * tangent[0] - s * tangent[1], s * tangent[0] + c * tangent[1]])
            ray = LineString([midrib[i], midrib[i] + reach * direction])
            hit = polygon.exterior.intersection(ray)
            if hit.is_empty:
                continue
            distance = min(Point(midrib[i]).distance(p) for p in getattr(hit, "geoms", [hit]))
            count = int(SIDE_REACH * distance / spacing)
            if count < SIDE_POINTS:
                continue
            t = np.linspace(0, SIDE_REACH * distance, count + 1)[1:]
            path = midrib[i] + t[:, None] * direction
            ok = covered(path)
            stop = int(np.argmin(ok)) if not ok.all() else len(path)
            stop = min(stop, _before_crossing(path, [midrib, *veins], spacing))
            if stop >= SIDE_POINTS:
                veins.append(path[:stop])
    return veins


def _before_crossing(path: np.ndarray, veins: list[np.ndarray], spacing: float) -> int:
    """How many of the (m, 2) `path`'s leading points lie `spacing` or more before it first
    crosses one of `veins` (the midrib and the side veins kept so far): straight side veins off
    a bending midrib crossed each other (soybean pot1_17: 5 pairs), and one on the inside of a
    strongly bending midrib crossed the midrib itself (a helper's outline setting, soybean
    pot1_1); a side vein stops at the next vein."""
    if not veins:
        return len(path)
    line = shapely.LineString(path)
    crossing = line.intersection(shapely.MultiLineString(veins))
    if crossing.is_empty:
        return len(path)
    first = min(line.project(p) for p in shapely.points(shapely.get_coordinates(crossing)))
    along = np.linalg.norm(path - path[0], axis=1)
    return int(np.searchsorted(along, first - spacing))
