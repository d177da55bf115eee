"""Framing a leaf in the 3D view, without Qt or VTK: the blade's robust bounds on its plane, and
a camera that shows them filling most of the view in both directions.

Bounds are taken in the view frame (the sketch's plane, else the result's), between low and high
percentiles of the mesh's points, so that a few stray points or a thin petiole do not shrink the
blade. The camera's distance follows from the box's projection on the screen's two axes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from leafstudio.core.plane import Frame

LOW, HIGH = 1.0, 99.0  # percentiles of the blade's points along each frame axis
PAD = 0.04  # each side, as a share of the larger extent
FILL = 0.86  # share of the viewport the framed box fills along its tighter axis
CONTAIN_SLACK = 0.1  # a result still fits the framed box within this share of its size
SAMPLE = 20_000  # points used for the percentiles, at most
OUTLINE = 2_000  # points kept to fit the camera to the leaf's shape, not its box
RECENTRE_STEPS = 4  # rounds of centring and sizing the perspective projection


@dataclass(frozen=True)
class BladeBounds:
    """A box on a frame: lo and hi along (u, v, normal), and the frame; `points` are world
    points of the blade inside the box (the camera fits their projection, tighter than the
    box's when the leaf is not a rectangle)."""

    frame: Frame
    lo: np.ndarray
    hi: np.ndarray
    points: np.ndarray | None = None

    @property
    def size(self) -> float:
        return float(np.max(self.hi - self.lo))

    def contains(self, other: BladeBounds) -> bool:
        """True when `other` lies inside this box (with some slack) along the plane and its
        normal: a curl lifts the apex along the normal and turns it back over the blade, and
        a box held across the plane alone kept the flat blade's framing (6.4% of a drawn leaf
        folded 45° and curled 0.4 out of the view)."""
        slack = CONTAIN_SLACK * self.size
        return bool(np.all(other.lo >= self.lo - slack) and np.all(other.hi <= self.hi + slack))

    def union(self, other: BladeBounds) -> BladeBounds:
        points = [b.points for b in (self, other) if b.points is not None]
        return BladeBounds(
            self.frame,
            np.minimum(self.lo, other.lo),
            np.maximum(self.hi, other.hi),
            np.vstack(points) if points else None,
        )

    def extent_points(self) -> np.ndarray:
        """World points whose projection the camera frames: the blade's, else the corners."""
        return self.points if self.points is not None and len(self.points) else self.corners()

    def corners(self) -> np.ndarray:
        """(8, 3) world points of the box."""
        grid = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], float)
        local = self.lo + grid * (self.hi - self.lo)
        return self.frame.to_world(local[:, :2], local[:, 2])


def blade_bounds(points: np.ndarray, frame: Frame) -> BladeBounds:
    """Robust bounds of (n, 3) world points (a mesh's) on `frame`: between the LOW and HIGH
    percentiles along u, v and the normal, padded by PAD of the larger extent."""
    points = np.asarray(points, dtype=float)
    if len(points) > SAMPLE:
        points = points[:: len(points) // SAMPLE + 1]
    xy, h = frame.to_plane(points)
    local = np.column_stack([xy, h])
    if not len(local):
        return BladeBounds(frame, np.zeros(3), np.zeros(3))
    lo, hi = np.percentile(local, [LOW, HIGH], axis=0)
    pad = PAD * max(float(np.max(hi - lo)), 1e-9)
    lo, hi = lo - pad, hi + pad
    inside = np.all((local >= lo) & (local <= hi), axis=1)
    kept = points[inside][:: max(1, int(inside.sum()) // OUTLINE)]
    return BladeBounds(frame, lo, hi, kept)


def view_direction(preset: str, frame: Frame) -> tuple[np.ndarray, np.ndarray]:
    """From the focus towards the camera, and the view-up, for a preset: "top" looks down the
    normal with u to the right and v up (as the sketch shows the plane); "side" along the width;
    "iso" from above one side and the base, so that the long axis runs across the view."""
    n, u, v = frame.normal, frame.u, frame.v
    if preset == "top":
        return n, v
    if preset == "side":
        return -v, n
    return 0.62 * n - 0.62 * v - 0.48 * u, n


ISO_ELEVATIONS = (35.0, 50.0, 65.0)  # degrees above the plane
ISO_AZIMUTHS = (15.0, 30.0, 45.0, 60.0)  # degrees from the width towards the base
ISO_FILL = 0.42  # an iso view filling this share along both axes is good enough


def iso_direction(elevation: float, azimuth: float, frame: Frame) -> np.ndarray:
    """From the focus towards an iso camera: `elevation` above the plane, `azimuth` turned from
    the leaf's -v side towards its base (-u)."""
    el, az = np.radians(elevation), np.radians(azimuth)
    flat = np.cos(az) * -frame.v + np.sin(az) * -frame.u
    return np.cos(el) * flat + np.sin(el) * frame.normal


def best_iso(
    bounds: BladeBounds,
    view_angle: float,
    aspect: float,
    bottom: float = 0.0,
    azimuths: tuple[float, ...] = ISO_AZIMUTHS,
    elevations: tuple[float, ...] = ISO_ELEVATIONS,
) -> tuple[np.ndarray, np.ndarray]:
    """The iso direction and view-up (the normal): the lowest of `elevations` (the most relief)
    at which some of `azimuths` fills the viewport by ISO_FILL along its less filled axis, else
    the candidate that fills it best; a long leaf in a tall view is turned to run diagonally
    (unless `azimuths` is (0,): the lesson's, from across the blade, u to the right as in its
    plan). `bottom` as in fit_camera."""
    best, best_fill = None, -1.0
    for elevation in elevations:
        for azimuth in azimuths:
            direction = iso_direction(elevation, azimuth, bounds.frame)
            position, focus, up = fit_camera(
                bounds, direction, bounds.frame.normal, view_angle, aspect, bottom=bottom
            )
            fill = min(projected_fill(bounds, position, focus, up, view_angle, aspect))
            if fill > best_fill + 0.02:  # the first (more frontal) of near ties
                best, best_fill = direction, fill
        if best_fill >= ISO_FILL:
            break
    return best, bounds.frame.normal


def fit_camera(
    bounds: BladeBounds,
    direction: np.ndarray,
    up: np.ndarray,
    view_angle: float = 30.0,
    aspect: float = 1.0,
    fill: float = FILL,
    bottom: float = 0.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position, focal point and view-up of a perspective camera (vertical `view_angle` degrees,
    viewport width / height `aspect`) looking along -`direction` at the box, so that the box's
    projection fills `fill` of the view along its tighter axis. `bottom` is a share of the
    view's height kept free along its lower edge (where the colour bars are): the box fills
    and is centred in the rest."""
    direction = np.asarray(direction, float) / np.linalg.norm(direction)
    up = np.asarray(up, float)
    up = up - (up @ direction) * direction
    up /= np.linalg.norm(up)
    right = _cross(up, direction)
    corners = bounds.extent_points()
    focus = 0.5 * (corners.min(axis=0) + corners.max(axis=0))
    rel = corners - focus
    x, y, z = rel @ right, rel @ up, rel @ direction
    focus = focus + 0.5 * (x.max() + x.min()) * right + 0.5 * (y.max() + y.min()) * up
    half_w, half_h = 0.5 * np.ptp(x), 0.5 * np.ptp(y)
    tan = np.tan(np.radians(view_angle) / 2)
    high = 1.0 - bottom  # the free part of the view's height
    distance = max(half_h / (tan * fill * high), half_w / (tan * aspect * fill)) + float(z.max())
    distance = max(distance, 1e-6)
    # centre the projection in the free part (whose centre is `bottom` of the half-height
    # above the view's): near points project larger, so the box's centre is not the middle
    # and fill exactly (the distance above is the safe side of a perspective's, by the depth)
    points = bounds.extent_points()
    nearest = float(z.max())
    for _ in range(RECENTRE_STEPS):
        x, y = project(points, focus + distance * direction, focus, up, view_angle, aspect)
        off_x, off_y = (x.max() + x.min()) / 2, (y.max() + y.min()) / 2 - bottom
        focus = focus + tan * distance * (off_x * aspect * right + off_y * up)
        need = max(np.ptp(x) / (2 * fill), np.ptp(y) / (2 * fill * high))
        distance = max(nearest + (distance - nearest) * need, 1.05 * nearest, 1e-6)
    return focus + distance * direction, focus, up


def projected_fill(
    bounds: BladeBounds,
    position: np.ndarray,
    focus: np.ndarray,
    up: np.ndarray,
    view_angle: float,
    aspect: float,
) -> tuple[float, float]:
    """The share of the viewport's width and height the blade spans (perspective)."""
    sx, sy = project(bounds.extent_points(), position, focus, up, view_angle, aspect)
    return float(np.ptp(sx) / 2), float(np.ptp(sy) / 2)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a × b of two 3-vectors, as np.cross computes it, without its axis handling (most of the
    time best_iso spent on the main thread, which calls it for each camera it tries)."""
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


def project(
    points: np.ndarray,
    position: np.ndarray,
    focus: np.ndarray,
    up: np.ndarray,
    view_angle: float,
    aspect: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Where (n, 3) world points land in the view, x and y from -1 (left, bottom) to 1."""
    direction = (position - focus) / np.linalg.norm(position - focus)
    up = up - (up @ direction) * direction
    up /= np.linalg.norm(up)
    right = _cross(up, direction)
    rel = np.asarray(points, float) - position
    depth = -(rel @ direction)
    tan = np.tan(np.radians(view_angle) / 2)
    return (rel @ right) / (depth * tan * aspect), (rel @ up) / (depth * tan)


@dataclass
class Framing:
    """How the 3D view should frame a result: `reset` (a new document: the iso preset) or
    `refit` (the sketch grew past the view: same direction, the whole leaf in view)."""

    bounds: BladeBounds
    reset: bool
