"""Step 1 (section 3.1): the PCA plane of the boundary, the 2D frame on it, and signed vein heights
(eq. 3)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from leafstudio.errors import LeafError


@dataclass(frozen=True)
class Frame:
    """An orthonormal frame on the boundary's PCA plane.

    Attributes
    ----------
    origin : (3,) float array
        Mean of the boundary points; the plane passes through it.
    u, v : (3,) float arrays
        In-plane axes: u along the leaf's length (largest variance), v across it.
    normal : (3,) float array
        Plane normal, oriented so that the veins' mean height is positive.
    """

    origin: np.ndarray
    u: np.ndarray
    v: np.ndarray
    normal: np.ndarray

    def to_plane(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Project (n, 3) points: their (n, 2) plane coordinates and (n,) signed heights (eq. 3)."""
        rel = np.asarray(points, dtype=float) - self.origin
        return np.column_stack([rel @ self.u, rel @ self.v]), rel @ self.normal

    def to_world(self, xy: np.ndarray, z: np.ndarray) -> np.ndarray:
        """Map plane coordinates (n, 2) and heights (n,) back to (n, 3) world points."""
        xy, z = np.asarray(xy, dtype=float), np.asarray(z, dtype=float)
        out = np.empty((len(xy), 3))
        # column by column: numpy's (n, 2) @ (2, 3) is several times slower; from x and y copied
        # out once, into two buffers (0.068 -> 0.047 ms at 7,268 points; the same sums)
        x, y = xy[:, 0].copy(), xy[:, 1].copy()
        column, term = np.empty(len(xy)), np.empty(len(xy))
        for k in range(3):  # origin + x u + y v + z n, added in that order
            np.multiply(x, self.u[k], out=column)
            column += self.origin[k]
            column += np.multiply(y, self.v[k], out=term)
            column += np.multiply(z, self.normal[k], out=term)
            out[:, k] = column
        return out


def fixed_sample(points: np.ndarray, most: int) -> np.ndarray:
    """At most `most` of the points, drawn at random without repeats, the same ones every time
    (seed 0): the tests and guesses that run on a sample of a large cloud stay reproducible."""
    if len(points) <= most:
        return points
    return points[np.random.default_rng(0).choice(len(points), most, replace=False)]


def principal_spreads(points: np.ndarray) -> np.ndarray:
    """Standard deviations of the (n, 3) points along their principal axes, largest first."""
    centred = points - points.mean(axis=0)
    return np.sqrt(np.maximum(np.linalg.eigvalsh(centred.T @ centred / len(points))[::-1], 0.0))


def principal_extents(points: np.ndarray) -> np.ndarray:
    """The (n, 3) points' extent (max - min) along each of their principal axes, the first
    axis's first: their length, then their width."""
    centred = points - points.mean(axis=0)
    axes = np.linalg.svd(centred, full_matrices=False)[2]
    return np.ptp(centred @ axes.T, axis=0)


# the points' principal axes in the grid_frame's coordinates (rows; its columns are the grid's
# axes in the principal ones): each grid axis turned off all three, the blade's normal along
# the grid's diagonal (1, 1, 1). Cubes along a blade's own axes stack a
# near-flat blade on their faces: its points split into two layers of cube means, and the
# unrolled blades came out less isometric (pairs 2-4 mm apart on the eight shared scans, flat
# over 3D distance: interquartile range 0.043-0.217, sugar beet pot1_1 10% too wide; turned so,
# 0.031-0.162, as with the world's axes before: 0.033-0.158)
GRID_TURN = np.array([[1.0, -1.0, 0.0], [1.0, 1.0, -2.0], [1.0, 1.0, 1.0]])
GRID_TURN /= np.linalg.norm(GRID_TURN, axis=1, keepdims=True)


def grid_frame(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A frame of the (n, 3) points' own to cut them in cubes along: their centroid (3,) and
    axes (3, 3, rows), their principal axes each signed so that the points' third moment along
    it is positive, then turned by GRID_TURN.

    A turned or mirrored copy of the points has the same coordinates in it, so cubes cut there
    (and their order) are the same whatever frame the scanner used. Cut along the world's axes
    from the points' lowest corner, they were not: sugar beet pot1_7 with z negated (a
    left-handed scanner's frame) unrolled into another flat blade, 43 units long instead of 61
    (core/sheet.py). The frame is left-handed for a mirrored copy of a right-handed one's.
    Not where two spreads are equal or a third moment is nil, as across a blade symmetric about
    its midrib: that axis, or its sign, is rounding's (such a blade turned at random took
    another frame 23 times in 40, its flat places then 1e-3 apart, Procrustes disparity)."""
    origin = points.mean(axis=0)
    centred = points - origin
    axes = np.linalg.eigh(centred.T @ centred)[1][:, ::-1].T  # SVD: 3.9 s at 2e6 points
    along = centred @ axes.T
    skew = np.einsum("ij,ij,ij->j", along, along, along)  # along ** 3: 1 s at 2e6 points
    return origin, GRID_TURN.T @ (axes * np.where(skew < 0, -1.0, 1.0)[:, None])


def _distinct_count_up_to_3(points: np.ndarray) -> int:
    """The number of distinct rows of (n, 3) `points`, counted up to 3 (no sort: O(n))."""
    if len(points) == 0:
        return 0
    count, others = 1, np.ones(len(points), dtype=bool)
    for _ in range(2):
        others &= np.any(points != points[np.argmax(others)], axis=1)
        if not others.any():
            return count
        count += 1
    return count


TIE = 1e-9  # two sides this close, as a share of the leaf's length, are a tie (fit_frame)


def _world_sign(axis: np.ndarray) -> float:
    """+1 if the (3,) axis's largest component is positive, else -1."""
    return 1.0 if axis[np.argmax(np.abs(axis))] >= 0 else -1.0


def fit_frame(boundary: np.ndarray, vein_points: np.ndarray) -> Frame:
    """PCA plane of the boundary points (paper, step 1), normal oriented toward the veins.

    Parameters
    ----------
    boundary : (n, 3) float array
    vein_points : (m, 3) float array
        May be empty; then, or when they lie in the boundary's plane (TIE), the normal points
        along the world axis it is closest to, positively. u points toward the boundary's
        farther extreme, and for a symmetric boundary along its closest world axis.

    Raises
    ------
    LeafError
        If there are fewer than 3 distinct boundary points, or they lie on one line.
    """

    def degenerate() -> LeafError:
        distinct = _distinct_count_up_to_3(np.round(boundary, 12))
        if distinct < 3:
            return LeafError(f"the boundary needs at least 3 distinct points, got {distinct}")
        return LeafError("the boundary points lie on one line (or one point): no leaf plane")

    if len(boundary) < 3:
        raise degenerate()
    origin = boundary.mean(axis=0)
    centred = boundary - origin
    # the 3 x 3 scatter's eigenvectors are the principal axes, several times faster than an SVD
    # of the (n, 3) points; the scatter squares the spread's ratios, so a slender boundary (its
    # axes less precise that way) takes the SVD
    variances, axes = np.linalg.eigh(centred.T @ centred)  # ascending
    if variances[2] <= 0 or variances[1] <= 1e-12 * variances[2]:
        raise degenerate()
    u, normal = axes[:, 2].copy(), axes[:, 0].copy()
    if variances[1] < 1e-6 * variances[2]:
        u, normal = np.linalg.svd(centred, full_matrices=False)[2][[0, 2]]
    along = centred @ u
    tie = TIE * float(along.max() - along.min())
    # the normal toward the veins' side; u toward the boundary's farther extreme. Where the two
    # sides are a tie (no veins or veins in the plane; a symmetric outline), rounding must not
    # choose (moving or scaling the leaf would mirror its frame): the world axes do
    side = float(np.mean((vein_points - origin) @ normal)) if len(vein_points) else 0.0
    if (side if abs(side) > tie else _world_sign(normal)) < 0:
        normal = -normal
    reach = float(along.max() + along.min())
    if (reach if abs(reach) > tie else _world_sign(u)) < 0:
        u = -u
    v = np.cross(normal, u)
    return Frame(origin=origin, u=u, v=v, normal=normal)


def turned_like(frame: Frame, like: Frame) -> Frame:
    """`frame`'s plane seen as `like` sees its own: turned about its normal by any angle so that
    u runs as `like`'s u projected into it, from `like`'s side (the normal flipped where they
    face apart), with `like`'s handedness (v across u on the side of `like`'s v). A drawn leaf's
    result on its sketch's frame (the app's main view). `frame` itself where `like`'s u is
    within 1e-6 of its normal."""
    normal = np.asarray(frame.normal, float)
    if normal @ like.normal < 0:
        normal = -normal
    u = like.u - (like.u @ normal) * normal
    if np.linalg.norm(u) < 1e-6:
        return frame
    u = u / np.linalg.norm(u)
    v = np.cross(normal, u)
    if v @ like.v < 0:  # `like` is left-handed
        v = -v
    return Frame(frame.origin, u, v, normal)


def turned_along(frame: Frame, direction: np.ndarray) -> Frame:
    """`frame` turned about its normal by the quarter or half turn that brings u nearest the
    (2,) in-plane `direction` (a midrib's, base to apex: evaluate.view_frame), its axes still
    the outline's principal ones; no mirror."""
    u, v = np.asarray(frame.u, float), np.asarray(frame.v, float)
    turns = [(u, v), (v, -u), (-u, -v), (-v, u)]  # rotations about the normal
    best = int(np.argmax([direction[0], direction[1], -direction[0], -direction[1]]))
    return Frame(frame.origin, *turns[best], frame.normal)
