"""A form's outline from its terms: shape, apex, base, then the margin (teeth or lobes).

The upper half of the blade is built as a curve from the base (0, 0) to the apex (1, 0) and
mirrored (each half with its own small random variation). The shape gives the half-width w(t)
along the midrib, t from 0 at the base to 1 at the apex: a smooth curve through a few values
(terms.ShapeSpec.body) times an end factor for the apex zone and one for the base zone:

- pointed ends (acute, obtuse, cuneate) are a cubic Hermite E(u) with E(0) = 0, E'(0) = s,
  E(1) = 1, E'(1) = 0, s set for the term's tip angle (acute 60°, obtuse 125°, cuneate 50°);
  acuminate is s = 0 (a drawn-out tip between concave sides);
- rounded ends are a circular arc, truncate a flat quarter ellipse;
- retuse and emarginate notch a rounded tip (2.5% and 6% of the length deep);
- basal lobes (cordate, reniform, sagittate) move the base zone's points back along -x by
  D·φ(y / y_b) (the base zone stays a graph over y, so the outline cannot cross itself); hastate
  adds a pointed lobe to w(t) near the base, flaring sideways.

The margin is then added along the outward normal, tooth by tooth (serrate teeth rise over 3/4 of
their width and fall over the last 1/4, so they point toward the apex; dentate teeth are
symmetric), or cut into lobes by sinuses that pull the margin toward the midrib (toward the base
for palmate venation, as in palmately lobed leaves). Finally the outline is scaled so that its
farthest point along +x is at x = 1.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import PchipInterpolator

from leafstudio.forms.terms import SHAPES, ShapeSpec

DENSE = 3000  # samples along the half-width profile
TIP_HALF_ANGLE = {"acute": 30.0, "obtuse": 62.0, "cuneate": 25.0}  # degrees
NOTCH_DEPTH = {"retuse": 0.025, "emarginate": 0.06}
BASE_LOBE = {"cordate": 0.14, "reniform": 0.2, "sagittate": 0.32}  # D, in leaf lengths
TOOTH = {  # height as a share of the tooth's width, and the share of the width before its tip
    "serrate": (0.42, 0.75),
    "serrulate": (0.4, 0.75),
    "dentate": (0.5, 0.5),
    "crenate": (0.32, 0.5),
    "sinuate": (0.1, 0.5),
}
TOOTH_REGION = 0.15  # teeth where the half-width is at least this share of the greatest
SINUS_REGION = 0.45  # lobe sinuses where the half-width is at least this share of the greatest
SINUS_DEPTH = 0.6  # a sinus pulls the margin this share of the way to its anchor
SINUS_WIDTH = 0.2  # a pinnate sinus's bell, as a share of the spacing between sinuses
PALMATE_ANCHOR = 0.15  # palmate sinuses point at this point of the midrib (x)
PALMATE_ASPECT = 1.7  # leaves at most this long for their width lobe palmately (with palmate veins)
POINTS_PER_TOOTH = 10  # at least
SPACING = 0.005  # the outline's point spacing, in leaf lengths (at most)


@dataclass(frozen=True)
class FormOutline:
    """A form's outline.

    Attributes
    ----------
    xy : (n, 2) float array
        Counter-clockwise, the base (0, 0) first; the apex is `xy[apex_index]`.
    apex_index : int
    halves : (lower, upper) pair of slices of `xy` from base to apex (for margin heights)
    """

    xy: np.ndarray
    apex_index: int

    @property
    def lower(self) -> np.ndarray:
        """The lower half, base to apex (indices into xy)."""
        return np.arange(self.apex_index + 1)

    @property
    def upper(self) -> np.ndarray:
        """The upper half, base to apex (indices into xy, the base included)."""
        return np.r_[0, np.arange(len(self.xy) - 1, self.apex_index - 1, -1)]


def _hermite(u: np.ndarray, slope: float) -> np.ndarray:
    """E(u) with E(0) = 0, E'(0) = slope, E(1) = 1, E'(1) = 0 (monotone for slope in [0, 3])."""
    return slope * u + (3 - 2 * slope) * u**2 + (slope - 2) * u**3


def _arc(u: np.ndarray) -> np.ndarray:
    """A quarter circle (or ellipse) rising from 0 at u = 0 to 1 at u = 1, flat there."""
    return np.sqrt(np.clip(1 - (1 - u) ** 2, 0, None))


def _end_factor(term: str, d: np.ndarray, zone: float, half: float) -> np.ndarray:
    """The end factor at distances d (in lengths) from the end, for an end half-width `half`."""
    if term in TIP_HALF_ANGLE:
        tan = np.tan(np.deg2rad(TIP_HALF_ANGLE[term]))
        slope = tan * zone / half
        if slope > 3:  # a blunt point on a narrow leaf: shorten the zone instead
            zone, slope = 3 * half / tan, 3.0
        return _hermite(np.clip(d / zone, 0, 1), slope)
    if term == "acuminate":
        return _hermite(np.clip(d / max(zone, 0.3), 0, 1), 0.0)
    if term == "truncate":
        return _arc(np.clip(d / min(0.12 * half, zone), 0, 1))
    if term == "hastate":
        return _arc(np.clip(d / min(0.3 * half, zone), 0, 1))
    # rounded, retuse, emarginate, cordate, reniform, sagittate: a circular arc
    return _arc(np.clip(d / min(half, 0.5), 0, 1))


def half_profile(
    spec: ShapeSpec, apex: str, base: str, aspect: float
) -> tuple[np.ndarray, np.ndarray]:
    """(x, y) of the upper half from the base (0, 0) to the apex (1, 0), densely, before the
    margin and before the final scaling."""
    t = 0.5 - 0.5 * np.cos(np.linspace(0, np.pi, DENSE))  # denser at both ends
    knots = np.array(spec.body, dtype=float)
    body = (
        PchipInterpolator(knots[:, 0], knots[:, 1])(t)
        if len(knots) > 2
        else np.interp(t, knots[:, 0], knots[:, 1])
    )
    scale = 0.5 / aspect / body.max()
    apex_factor = _end_factor(apex, 1 - t, spec.apex_zone, scale * body[-1])
    base_factor = _end_factor(base, t, spec.base_zone, scale * body[0])
    w = scale * body * apex_factor * base_factor
    if base == "hastate":
        lobe = np.clip(1 - np.abs(t - 0.07) / 0.07, 0, None) ** 1.3
        w = w + 0.55 * w.max() * lobe
    x = t.copy()
    if base in BASE_LOBE:
        zone = min(scale * body[0], 0.5) if base != "sagittate" else spec.base_zone
        inside = t < zone
        r = np.clip(w / w[inside][-1], 0, 1) if inside.any() else np.zeros_like(w)
        if base == "sagittate":
            phi = np.where(r < 0.55, r / 0.55, (1 - r) / 0.45)
        else:
            phi = np.sin(np.pi * r)
        x = np.where(inside, x - BASE_LOBE[base] * phi, x)
    if apex in NOTCH_DEPTH:
        width = min(0.6 * scale * body[-1], 0.12)
        near = t > 0.5
        x = np.where(near, x - NOTCH_DEPTH[apex] * np.clip(1 - w / width, 0, None) ** 2, x)
    return x, w


def _arc_length(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])


def _normals(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(n, 2) unit normals of the upper half (base to apex), pointing out of the blade."""
    tx, ty = np.gradient(x), np.gradient(y)
    norm = np.hypot(tx, ty)
    norm[norm == 0] = 1.0
    return np.column_stack([-ty / norm, tx / norm])


def _tooth_profile(margin: str, phase: np.ndarray) -> np.ndarray:
    """0 at the sinuses (phase 0 and 1), 1 at the tip."""
    if margin == "crenate":
        return 1 - (2 * phase - 1) ** 2
    if margin == "sinuate":
        return 0.5 - 0.5 * np.cos(2 * np.pi * phase)
    tip = TOOTH[margin][1]
    return np.where(phase < tip, phase / tip, (1 - phase) / (1 - tip))


def _region(s: np.ndarray, y: np.ndarray, share: float) -> tuple[float, float]:
    """The arc-length span where the half-width is at least `share` of the greatest."""
    wide = np.flatnonzero(y >= share * y.max())
    return float(s[wide[0]]), float(s[wide[-1]])


def _toothed_half(
    x: np.ndarray, y: np.ndarray, margin: str, teeth: int, rng: np.random.Generator
) -> np.ndarray:
    """The half with `teeth` teeth along its wide part, sampled tooth by tooth (tips included)."""
    s = _arc_length(x, y)
    lo, hi = _region(s, y, TOOTH_REGION)
    breaks = np.linspace(lo, hi, teeth + 1)
    width = (hi - lo) / max(teeth, 1)
    breaks[1:-1] += rng.uniform(-0.15, 0.15, teeth - 1) * width
    tip = TOOTH[margin][1]
    per_tooth = 4 * max(POINTS_PER_TOOTH, int(np.ceil(width / SPACING)))
    phases = np.unique(np.r_[np.linspace(0, 1, per_tooth, endpoint=False), tip])
    inner = (breaks[:-1, None] + np.diff(breaks)[:, None] * phases).ravel()
    step = min(width / POINTS_PER_TOOTH, SPACING)
    before = np.arange(0, lo, step)
    after = np.arange(hi, s[-1], step)
    samples = np.unique(np.r_[before, inner, after, s[-1]])
    px, py = np.interp(samples, s, x), np.interp(samples, s, y)
    normal = _normals(x, y)
    nx, ny = np.interp(samples, s, normal[:, 0]), np.interp(samples, s, normal[:, 1])
    index = np.clip(np.searchsorted(breaks, samples, side="right") - 1, 0, teeth - 1)
    phase = np.clip((samples - breaks[index]) / np.diff(breaks)[index], 0, 1)
    within = (samples >= lo) & (samples <= hi)
    height = np.minimum(TOOTH[margin][0] * np.diff(breaks)[index], 0.5 * py)
    offset = np.where(within, height * _tooth_profile(margin, phase), 0.0)
    dense = np.column_stack([px + offset * nx, py + offset * ny])
    corner = np.isin(samples, breaks) | (within & np.isclose(phase, tip))
    return _even_between(dense, np.flatnonzero(corner), step)


def _even_between(points: np.ndarray, corners: np.ndarray, step: float) -> np.ndarray:
    """The polyline resampled evenly along its length, piece by piece between the corners (kept
    as vertices): an outline the pipeline takes as clean, its points where the teeth turn."""
    cuts = np.unique(np.r_[0, corners, len(points) - 1])
    out = []
    for a, b in itertools.pairwise(cuts):
        piece = points[a : b + 1]
        s = _arc_length(piece[:, 0], piece[:, 1])
        grid = np.linspace(0, s[-1], max(int(np.ceil(s[-1] / step)), 1) + 1)[:-1]
        out.append(
            np.column_stack([np.interp(grid, s, piece[:, 0]), np.interp(grid, s, piece[:, 1])])
        )
    out.append(points[-1:])
    return np.vstack(out)


def _resampled(x: np.ndarray, y: np.ndarray, count: int) -> np.ndarray:
    s = _arc_length(x, y)
    grid = np.linspace(0, s[-1], count)
    return np.column_stack([np.interp(grid, s, x), np.interp(grid, s, y)])


def _pull(points: np.ndarray, s: np.ndarray, at: float, reach: float, anchor, depth: float):
    """Pull the points within arc distance `reach` of `at` toward `anchor` (a sinus)."""
    weight = np.where(np.abs(s - at) < reach, np.cos(0.5 * np.pi * (s - at) / reach) ** 2, 0.0)
    return points + depth * weight[:, None] * (np.asarray(anchor) - points)


def _lobed_half(
    points: np.ndarray, lobes: int, palmate: bool, apex_depth: float, rng: np.random.Generator
) -> np.ndarray:
    """The half with its share of the sinuses that cut a blade into `lobes` lobes in all: one
    sinus at the apex when `lobes` is even, (lobes - 1) // 2 along each side."""
    x, y = points[:, 0], points[:, 1]
    s = _arc_length(x, y)
    side = (lobes - 1) // 2
    out = points.copy()
    if lobes % 2 == 0:  # a sinus at the apex, between two lobes
        reach = 0.35 * min(s[-1] / (side + 1), 0.6)
        out = _pull(out, s, s[-1], reach, (0.45 * x[-1], 0.0), apex_depth)
    if side:
        lo, hi = _region(s, y, SINUS_REGION)
        if lobes % 2 == 0:
            hi = min(hi, s[-1] - 0.45 * (s[-1] - lo) / (side + 1))
        spacing = (hi - lo) / side
        for j in range(side):
            at = lo + spacing * (j + 0.5 + rng.uniform(-0.08, 0.08))
            k = int(np.searchsorted(s, at))
            depth = SINUS_DEPTH * rng.uniform(0.9, 1.1)
            if palmate:  # sinuses toward one point of the midrib, as in a maple
                reach = float(np.clip(0.3 * spacing, 0.02, 0.6 * depth * y[k] + 0.02))
                out = _pull(out, s, at, reach, (PALMATE_ANCHOR, 0.0), depth)
            else:  # straight toward the midrib, a bell over the spacing: a U-shaped sinus
                # between rounded lobes, as in an oak (a narrow pull toward one point made V
                # sinuses and a zig-zag margin)
                weight = np.exp(-(((s - at) / (SINUS_WIDTH * spacing)) ** 2))
                out[:, 1] *= 1 - depth * weight
    return out


def form_outline(
    shape: str,
    apex: str,
    base: str,
    margin: str,
    teeth: int,
    lobes: int,
    aspect: float,
    palmate: bool,
    rng: np.random.Generator,
) -> FormOutline:
    """The closed outline of a form (terms already checked), base at (0, 0), apex at x = 1."""
    spec = SHAPES[shape]
    x, y = half_profile(spec, apex, base, aspect)
    halves = []
    per_side = (teeth + 1) // 2, teeth // 2
    apex_depth = SINUS_DEPTH * 0.7 * rng.uniform(0.9, 1.1)  # the same on both halves
    for side in range(2):
        if margin in ("entire", "lobed") or per_side[side] == 0:
            points = _resampled(x, y, max(200, int(_arc_length(x, y)[-1] / SPACING)))
            if margin == "lobed":
                radial = palmate and aspect <= PALMATE_ASPECT  # palmately lobed (wide) leaves
                points = _lobed_half(points, lobes, radial, apex_depth, rng)
        else:
            points = _toothed_half(x, y, margin, per_side[side], rng)
        halves.append(points)
    upper, lower = halves
    lower = lower * [1.0, -1.0]
    xy = np.vstack([lower, upper[::-1][1:-1]])
    xy /= xy[:, 0].max()
    return FormOutline(xy=xy, apex_index=len(lower) - 1)
