"""Which end of a leaf without a petiole is its base: the midline and the cues that orient it.

A photo's outline alone cannot always tell base from apex (an obovate leaf is an ovate one turned
round, but for the end terms), so the ends are found in three steps:

1. The midline: the blade's best mirror axis (the line whose reflection of the outline overlaps
   it most, by IoU), searched over directions through the centroid and refined; of the axes
   within MIRROR_TIE of the best, the one with the longest chord (an elliptic or round leaf is
   symmetric both ways; its length is the long way). The two ends are where the midline leaves
   the blade; on a cordate or sagittate leaf one of them is the bottom of the sinus.
2. The cues, strongest first:
   - a basal notch: the outline reaches back past one end by NOTCH_DEEP of the length or more
     (cordate 0.14, reniform 0.2, sagittate 0.32; an emarginate apex's notch is 0.06 at most)
     and past the other by less than half that: that end is the base;
   - the veins: secondary veins leave the midrib running outward toward the apex, on both sides,
     so the structure tensor of the blade's inner pixels, turned to the midline's frame, has an
     across-along term whose sign (flipped on one side of the midline) points to the apex. Used
     when it is clear (VEIN_CLEAR of the tensor's trace);
   - else the wider end (END_BAND of the length from each end) is the base: right for ovate,
     lanceolate, deltoid leaves, wrong for obovate and spatulate ones, which need their veins.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from shapely import affinity

MIRROR_TIE = 0.015  # axes this close (in IoU) to the best mirror count as equally good
SEARCH_POINTS = 240  # the outline is thinned to this many points for the search
ROUNDISH = 0.8  # mirror axes with chords within this ratio are told apart by the veins
NOTCH_DEEP = 0.08  # of the length: a notch this deep at one end marks the base
VEIN_CLEAR = 0.03  # the veins' cue counts when its share of the tensor's trace is this large
END_BAND = 0.15  # each end's width is measured this share of the length from it
MARGIN_SKIP = 5.0  # pixels: the veins' cue ignores this band inside the outline (its edge)
MIDRIB_SKIP = 3.0  # pixels: and this band either side of the midline (the midrib itself)
TIP_SIDES = (4.0, 16.0)  # pixels along the outline from a pointed end: its sides' straight part
TIP_ANGLE = 100.0  # degrees: ends blunter than this are left as they are
TIP_REACH = 6.0  # pixels: a pointed end moves out at most this far
TIP_CLIMB = 0.1  # of the length: an apex off the midline is looked for this far along the outline
TIP_GAIN = 0.005  # of the length: a climb that gains less is left (a round end)
STALK_JUMP = 2.5  # the blade is this many times wider than a petiole along the midline,
STALK_EVEN_RUN = 1.5  # whose width stays within this factor of its width near its end,
STALK_SLENDER = 1.5  # over at least this many widths; it is looked for within
STALK_REACH = 0.5  # this share of the length from each end
TENSOR_SIGMA = 1.0  # pixels: the structure tensor's window (wider ones reach the outline's edge)


@dataclass(frozen=True)
class Midline:
    """The blade's mirror axis and its two ends.

    Attributes
    ----------
    ends : (2, 2) float array
        Where the midline leaves the blade, (column, row); ends[1] - ends[0] runs along `along`.
    along : (2,) float array
        The midline's unit direction.
    mirror : float
        IoU of the outline with its reflection in the midline (1 for a symmetric blade).
    """

    ends: np.ndarray
    along: np.ndarray
    mirror: float

    @property
    def length(self) -> float:
        return float(np.linalg.norm(self.ends[1] - self.ends[0]))


def _reflect_iou(polygon: shapely.Polygon, centre: np.ndarray, angle: float, shift: float) -> float:
    """IoU of the polygon with its reflection in the line at `angle` (radians) through `centre`
    moved `shift` along its normal."""
    normal = np.array([-np.sin(angle), np.cos(angle)])
    x0, y0 = centre + shift * normal
    c, s = np.cos(2 * angle), np.sin(2 * angle)
    # reflection in a line through (x0, y0) at `angle`: [[c, s], [s, -c]] about that point
    matrix = [c, s, s, -c, x0 - c * x0 - s * y0, y0 - s * x0 + c * y0]
    mirrored = affinity.affine_transform(polygon, matrix)
    # the union's area from the intersection's (A + B - I): shapely's union cost as much again,
    # and this function was 40% of a photo's reading (Nelder-Mead calls it about 250 times)
    common = polygon.intersection(mirrored).area
    union = polygon.area + mirrored.area - common
    return common / union if union > 0 else 0.0


def _chord(polygon: shapely.Polygon, centre: np.ndarray, along: np.ndarray) -> np.ndarray:
    """(2, 2) the ends of the piece of the line through `centre` along `along` that lies in the
    polygon and passes nearest the centre."""
    reach = 4 * np.sqrt(polygon.area) + np.ptp(np.asarray(polygon.exterior.coords), axis=0).sum()
    line = shapely.LineString([centre - reach * along, centre + reach * along])
    cut = polygon.intersection(line)
    pieces = [g for g in getattr(cut, "geoms", [cut]) if g.geom_type == "LineString" and g.length]
    if not pieces:
        return np.array([centre, centre])
    piece = min(pieces, key=lambda g: g.distance(shapely.Point(centre)))
    ends = np.asarray(piece.coords)[[0, -1]]
    return ends if (ends[1] - ends[0]) @ along >= 0 else ends[::-1]


def midline(outline: np.ndarray, veins: VeinField | None = None) -> Midline:
    """The blade's mirror axis (see the module docstring) from its (n, 2) outline; a round
    blade's (every axis a mirror) is the line the veins lean off most, when they show; of axes
    that mirror it about as well (an elliptic blade) the longest, unless they are about as long
    (ROUNDISH: a round blade a little wider than long), then the one the veins lean off most."""
    from scipy.optimize import minimize

    polygon = shapely.Polygon(outline).buffer(0)
    step = max(1, len(outline) // SEARCH_POINTS)
    coarse = shapely.Polygon(outline[::step]).buffer(0)
    centre = np.array(polygon.centroid.coords[0])
    angles = np.deg2rad(np.arange(0.0, 180.0, 3.0))
    scores = np.array([_reflect_iou(coarse, centre, a, 0.0) for a in angles])
    if veins is not None and scores.min() >= scores.max() - MIRROR_TIE:
        along, lean = veins.direction(centre)
        if abs(lean) >= VEIN_CLEAR:
            angle = float(np.arctan2(along[1], along[0]))
            return Midline(_chord(polygon, centre, along), along,
                           _reflect_iou(polygon, centre, angle, 0.0))  # fmt: skip
    # local maxima of the circular scan, best first; a few are refined
    peaks = [i for i in range(len(angles)) if scores[i] >= scores[i - 1]
             and scores[i] >= scores[(i + 1) % len(angles)]]  # fmt: skip
    peaks = sorted(peaks, key=lambda i: -scores[i])[:4]
    candidates = []
    size = np.sqrt(polygon.area)
    for i in peaks:
        result = minimize(
            lambda v: -_reflect_iou(polygon, centre, v[0], v[1] * size),
            [angles[i], 0.0],
            method="Nelder-Mead",
            options={"xatol": 1e-4, "fatol": 1e-5, "initial_simplex": [
                [angles[i], 0.0], [angles[i] + 0.03, 0.0], [angles[i], 0.02]]},
        )  # fmt: skip
        angle, shift = result.x[0], result.x[1] * size
        along = np.array([np.cos(angle), np.sin(angle)])
        through = centre + shift * np.array([-along[1], along[0]])
        ends = _chord(polygon, through, along)
        candidates.append(Midline(ends=ends, along=along, mirror=-float(result.fun)))
    best = max(c.mirror for c in candidates)
    tied = [c for c in candidates if c.mirror >= best - MIRROR_TIE]
    longest = max(c.length for c in tied)
    tied = [c for c in tied if c.length >= ROUNDISH * longest]  # a much longer one wins
    if veins is not None and len(tied) > 1:  # the veins lean off the midline, not off the others
        leans = [abs(veins.lean(c.ends[0], c.along)) for c in tied]
        if max(leans) >= VEIN_CLEAR:
            return tied[int(np.argmax(leans))]
    return max(tied, key=lambda c: c.length)


def notch_depths(outline: np.ndarray, line: Midline) -> np.ndarray:
    """(2,) how far the outline reaches back past each end (outward along the midline) on both
    sides of it (the lesser of the two sides' reach), as a share of the midline's length: the
    basal lobes of a cordate or sagittate leaf; a bay torn into one side is no notch."""
    along = (outline - line.ends[0]) @ line.along
    across = (outline - line.ends[0]) @ np.array([-line.along[1], line.along[0]])
    span = max(line.length, 1e-12)
    depths = []
    for beyond in (-along, along - span):  # outward past end 0, past end 1
        reach = [beyond[side].max() if side.any() else 0.0 for side in (across > 0, across < 0)]
        depths.append(max(min(reach), 0.0))
    return np.array(depths) / span


def end_widths(outline: np.ndarray, line: Midline) -> np.ndarray:
    """(2,) the blade's width END_BAND of the length in from each end."""
    along = (outline - line.ends[0]) @ line.along
    across = (outline - line.ends[0]) @ np.array([-line.along[1], line.along[0]])
    span = line.length
    widths = []
    for at in (END_BAND * span, (1 - END_BAND) * span):
        band = np.abs(along - at) < 0.02 * span
        widths.append(float(np.ptp(across[band])) if band.sum() > 1 else 0.0)
    return np.array(widths)


def window(box: tuple[int, int, int, int], margin: int, shape) -> tuple[slice, slice]:
    """Slices of a (min row, min column, max row, max column) box grown by `margin` pixels,
    within an image of `shape`."""
    r0, c0, r1, c1 = box
    return (slice(max(r0 - margin, 0), min(r1 + margin, shape[0])),
            slice(max(c0 - margin, 0), min(c1 + margin, shape[1])))  # fmt: skip


def mask_window(mask: np.ndarray, margin: int) -> tuple[slice, slice]:
    """Slices of the box of a (rows, columns) mask's pixels grown by `margin` (window): work on
    a photo's leaf there sees the same pixels, sooner."""
    rows, cols = np.nonzero(mask)
    return window((rows.min(), cols.min(), rows.max() + 1, cols.max() + 1), margin, mask.shape)


class VeinField:
    """The structure tensor of a photo's grey levels on the blade's inner pixels (MARGIN_SKIP in
    from the outline, whose own edge would swamp the veins'), for `lean`."""

    def __init__(self, image: np.ndarray, blade: np.ndarray) -> None:
        from scipy.ndimage import distance_transform_edt

        # on the blade's box with a margin wider than the filters' reach (a Sobel pixel and
        # the Gaussian's 4 sigmas): the inner pixels' tensors are the whole photo's, sooner
        box = mask_window(blade, 2 + int(np.ceil(4 * TENSOR_SIGMA)))
        top, left = box[0].start, box[1].start
        grey = image[box][..., :3].astype(float) @ np.array([0.299, 0.587, 0.114])
        arr, arc, acc = structure_tensor(grey, TENSOR_SIGMA)
        rows, cols = np.nonzero(
            distance_transform_edt(np.pad(blade[box], 1))[1:-1, 1:-1] > MARGIN_SKIP
        )
        self.xy = np.column_stack([cols + left, rows + top]) + 0.5  # (column, row) pixel centres
        self.j = np.column_stack([acc[rows, cols], arc[rows, cols], arr[rows, cols]])  # xx xy yy

    def lean(self, through: np.ndarray, along: np.ndarray) -> float:
        """Which way the veins lean off the line through `through` along `along`: > 0 if they
        run toward +along as they leave it (on both sides), < 0 toward -along; a share of the
        tensor's trace, in [-1, 1]."""
        normal = np.array([-along[1], along[0]])
        across = (self.xy - through) @ normal
        keep = np.abs(across) > MIDRIB_SKIP
        j, across = self.j[keep], across[keep]
        total = float(j[:, 0].sum() + j[:, 2].sum())
        if total <= 0:
            return 0.0
        # u^T J n, the gradient's along-across term: a line running (d_a, d_c) gives -d_a d_c
        u, n = along, normal
        cross = (
            u[0] * n[0] * j[:, 0] + (u[0] * n[1] + u[1] * n[0]) * j[:, 1] + u[1] * n[1] * j[:, 2]
        )
        return float(-(np.sign(across) * cross).sum() / total)

    def direction(self, through: np.ndarray) -> tuple[np.ndarray, float]:
        """The direction through `through` along which the veins lean most (a round blade's
        midline; they lean little off any other line), and that lean."""
        best = 0.0
        for step in (5.0, 1.0):  # a coarse scan, then one finer round the best
            angles = np.deg2rad(np.arange(0.0, 180.0, 5.0) if step == 5.0
                                else best + np.arange(-4.0, 5.0))  # fmt: skip
            leans = [self.lean(through, np.array([np.cos(a), np.sin(a)])) for a in angles]
            i = int(np.argmax(np.abs(leans)))
            best, lean = float(np.rad2deg(angles[i])), float(leans[i])
        a = np.deg2rad(best)
        return np.array([np.cos(a), np.sin(a)]), lean


def structure_tensor(grey: np.ndarray, sigma: float) -> list[np.ndarray]:
    """[Arr, Arc, Acc] of an (h, w) float image: scikit-image's `structure_tensor(grey, sigma,
    order="rc")` to the last bit (Sobel derivatives, their products smoothed, both with zeros
    beyond the border), without importing skimage.feature, which imports scipy.stats (0.6 s of
    CPU on every photo read by a fresh process)."""
    from scipy.ndimage import gaussian_filter, sobel

    rows, cols = (sobel(grey, axis=axis, mode="constant", cval=0) for axis in (0, 1))
    return [gaussian_filter(a * b, sigma, mode="constant", cval=0, truncate=4.0)
            for a, b in ((rows, rows), (rows, cols), (cols, cols))]  # fmt: skip


def base_end_index(outline: np.ndarray, line: Midline, veins: VeinField | None) -> tuple[int, str]:
    """0 or 1: which of the midline's ends is the base, and the cue that told (see the module
    docstring)."""
    depths = notch_depths(outline, line)
    deep = int(np.argmax(depths))
    if depths[deep] >= NOTCH_DEEP and depths[1 - deep] < depths[deep] / 2:
        return deep, "notch"
    if veins is not None:
        lean = veins.lean(line.ends[0], line.along)
        if abs(lean) >= VEIN_CLEAR:
            return (0 if lean > 0 else 1), "veins"
    return int(np.argmax(end_widths(outline, line))), "wider end"


def sharpen_end(outline: np.ndarray, index: int, inward: np.ndarray) -> tuple[np.ndarray, int]:
    """The outline with a pointed end (an acute apex, a cuneate base, the bottom of a cordate
    sinus) put back where blur and the threshold rounded it off: the lines through each side's
    points TIP_SIDES pixels along the outline from the end meet at the true point when the
    sides are straight there (outward of a pointed end, inward of a sinus). Only ends sharper
    than TIP_ANGLE (between the sides, both taken toward `inward`, the midline's direction into
    the blade), moved by at most TIP_REACH pixels; the end's points within TIP_SIDES[0] become
    that point and straight sides to it. Returns the outline and the end's index in it (the
    outline then starts there)."""
    n = len(outline)
    step = np.linalg.norm(np.diff(outline, axis=0, append=outline[:1]), axis=1)
    gaps = np.concatenate([[0.0], np.cumsum(step)])
    total = gaps[-1]
    arc = (gaps[:n] - gaps[index]) % total  # forward distance from the end
    arc = np.where(arc > total / 2, arc - total, arc)  # signed: < 0 before, > 0 after
    near, far = TIP_SIDES
    sides = []
    for sign in (1, -1):
        pts = outline[(sign * arc >= near) & (sign * arc <= far)]
        if len(pts) < 3:
            return outline, index
        centre = pts.mean(axis=0)
        direction = np.linalg.eigh(np.cov((pts - centre).T))[1][:, -1]
        if direction @ inward < 0:
            direction = -direction
        sides.append((centre, direction))
    (p, u), (q, v) = sides
    if np.degrees(np.arccos(np.clip(u @ v, -1, 1))) > TIP_ANGLE:
        return outline, index
    try:
        t = np.linalg.solve(np.column_stack([u, -v]), q - p)
    except np.linalg.LinAlgError:
        return outline, index
    tip = p + t[0] * u
    moved = outline[index] - tip
    if np.linalg.norm(moved) > TIP_REACH:
        return outline, index
    # the tip first, then the kept points in order, joined to it by straight sides at the
    # outline's spacing (the texture's edge near the tip stays within a pixel of them)
    kept = np.roll(outline, -index, axis=0)[np.abs(np.roll(arc, -index)) >= near]
    spacing = float(np.median(step))
    sides = []
    for end in (kept[0], kept[-1]):
        count = max(int(np.linalg.norm(end - tip) / spacing), 1)
        sides.append(tip + (end - tip) * (np.arange(1, count) / count)[:, None])
    return np.vstack([tip, sides[0], kept, sides[1][::-1]]), 0


def climb_to_tip(outline: np.ndarray, index: int, base: np.ndarray) -> int:
    """The apex where the midline leaves an asymmetric blade beside its tip: the outline is
    followed from there, away from the base, to the tip (the farthest point from the base
    within TIP_CLIMB of the length along the outline), if that is TIP_GAIN of the length
    farther (a round end is about as far everywhere: the base's own error would steer the
    climb). An end at a tip stays, and so does one in a notch (an emarginate apex: the outline
    runs away from the base on both sides)."""
    n = len(outline)
    far = np.linalg.norm(outline - base, axis=1)
    step = float(np.median(np.linalg.norm(np.diff(outline, axis=0), axis=1)))
    limit = int(TIP_CLIMB * far[index] / max(step, 1e-12))
    rising = [s for s in (1, -1) if far[(index + 2 * s) % n] > far[index]]
    if len(rising) != 1:
        return index
    (s,) = rising
    at = index
    for _ in range(limit):
        if far[(at + 2 * s) % n] <= far[at]:
            break
        at = (at + s) % n
    window = (at + np.arange(-2, 3)) % n  # the top of the climb, to the vertex
    top = int(window[np.argmax(far[window])])
    return top if far[top] - far[index] >= TIP_GAIN * far[index] else index


@dataclass(frozen=True)
class Stalk:
    """A petiole found along the midline: it runs from `tip` to `joint`, `halfwidth` wide."""

    end: int  # which of the midline's ends it is at
    tip: np.ndarray
    joint: np.ndarray
    halfwidth: float


def _widths(polygon: shapely.Polygon, start: np.ndarray, inward: np.ndarray, at: np.ndarray):
    """The blade's width across the midline at distances `at` in from `start`: the piece of
    each cross-line that holds the midline's point (a petiole in a sinus, not the lobes). All
    cross-lines in one call of GEOS's (vectorised shapely)."""
    normal = np.array([-inward[1], inward[0]])
    reach = 2 * np.sqrt(polygon.area) + polygon.length
    centres = np.array([start + t * inward for t in at]).reshape(-1, 2)
    lines = shapely.linestrings(
        np.stack([centres - reach * normal, centres + reach * normal], axis=1)
    )
    pieces, which = shapely.get_parts(shapely.intersection(polygon, lines), return_index=True)
    holding = (shapely.get_type_id(pieces) == 1) & (
        shapely.distance(pieces, shapely.points(centres[which])) < 1.0
    )  # type 1: a LineString
    widths = np.zeros(len(at))
    np.maximum.at(widths, which[holding], shapely.length(pieces[holding]))
    return widths


def find_stalk(outline: np.ndarray, line: Midline) -> Stalk | None:
    """A petiole the openings missed (short beside a large blade, hidden in a sinus, or running
    into a narrow base): at one end of the midline, a run of even width (within STALK_EVEN_RUN
    of its width near the end) STALK_SLENDER times longer than wide, on a blade STALK_JUMP
    times wider; the run ends where the width leaves that band (the blade widens, or narrows
    where the stalk meets a cuneate base). A pointed end widens from nothing at once."""
    polygon = shapely.Polygon(outline).buffer(0)
    span = line.length
    greatest = _widths(polygon, line.ends[0], line.along, np.linspace(0, span, 41)[1:-1]).max()
    found = None
    for end, sign in ((0, 1.0), (1, -1.0)):
        start, inward = line.ends[end], sign * line.along
        at = np.arange(1.0, STALK_REACH * span)
        widths = _widths(polygon, start, inward, at)
        width = float(np.median(widths[1:8]))  # 2 to 8 pixels in: past the blurred tip
        if width <= 0 or greatest < STALK_JUMP * width:
            continue
        inside = (widths <= STALK_EVEN_RUN * width) & (widths >= width / STALK_EVEN_RUN)
        inside[0] = True  # the very end is rounded by blur
        run = int(np.argmin(inside)) if not inside.all() else len(at)
        if run == len(at) or at[run] < STALK_SLENDER * width:
            continue
        candidate = Stalk(end, start, start + at[run] * inward, width / 2)
        if found is None or at[run] > np.linalg.norm(found.joint - found.tip):
            found = candidate
    return found
