"""Coordinates along a curved midrib, for mirror editing (no Qt).

A plane point p is written p = C(s) + d N(s): C is the midrib's curve (a polyline through its
samples, continued straight past both ends along its end tangents), s the arc length of the foot
point, N the left normal and d the signed offset. The tangent, and so N, is interpolated
linearly along each segment from the mean directions at its ends, so it turns smoothly and the
foot is where (p - C(s)) . T(s) = 0 (a quadratic on each segment). The mirror image of p is
C(s) - d N(s): the same place along the midrib, the same distance on the other side. Mirroring
twice gives p back, and about a straight midrib it is the reflection about its line.

The map (s, d) -> C(s) + d N(s) folds where d reaches the radius of curvature on the inside of
a bend (1 - d kappa(s) = 0, kappa the signed curvature, + turning left): a midrib bent more
tightly than the leaf is wide cannot carry a mirror image there (`mirror_reach`).
"""

from __future__ import annotations

import numpy as np

END_REACH = 100.0  # the straight continuations past the ends, in lengths of the midrib's box


def _unit(vectors: np.ndarray) -> np.ndarray:
    return vectors / np.maximum(np.linalg.norm(vectors, axis=-1, keepdims=True), 1e-300)


class Midrib:
    """Signed offsets from, and reflection across, an open plane curve.

    Parameters
    ----------
    curve : (s, 2) float array
        Points along the midrib from its base to its tip (at least two distinct points).
    """

    def __init__(self, curve: np.ndarray) -> None:
        curve = np.asarray(curve, dtype=float)[:, :2]
        keep = np.ones(len(curve), dtype=bool)
        keep[1:] = np.linalg.norm(np.diff(curve, axis=0), axis=1) > 0
        curve = curve[keep]
        if len(curve) < 2:
            raise ValueError("a midrib needs two distinct points")
        directions = _unit(np.diff(curve, axis=0))
        tangents = np.vstack([directions[:1], directions[:-1] + directions[1:], directions[-1:]])
        tangents = _unit(tangents)
        reach = END_REACH * max(float(np.ptp(curve, axis=0).max()), 1e-12)
        self.points = np.vstack(
            [curve[0] - reach * tangents[0], curve, curve[-1] + reach * tangents[-1]]
        )
        self.tangents = np.vstack([tangents[:1], tangents, tangents[-1:]])
        ta, tb = self.tangents[:-1], self.tangents[1:]
        turn = np.arctan2(ta[:, 0] * tb[:, 1] - ta[:, 1] * tb[:, 0], np.einsum("sk,sk->s", ta, tb))
        length = np.linalg.norm(np.diff(self.points, axis=0), axis=1)
        self.curvature = turn / np.maximum(length, 1e-300)  # per segment, + turning left

    def _feet(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Per point: its foot on the curve, the unit normal there, the signed offset (the
        foot with the smallest offset where several segments hold one) and the curvature of
        the foot's segment."""
        a, b = self.points[:-1], self.points[1:]
        ta, tb = self.tangents[:-1], self.tangents[1:]
        e, dt = b - a, tb - ta
        q = points[:, None, :] - a[None, :, :]  # (p, segments, 2)
        # f(u) = (q - u e) . (ta + u dt) = c0 + c1 u + c2 u^2
        c0 = np.einsum("psk,sk->ps", q, ta)
        c1 = np.einsum("psk,sk->ps", q, dt) - np.einsum("sk,sk->s", e, ta)[None]
        c2 = np.broadcast_to(-np.einsum("sk,sk->s", e, dt)[None], c0.shape)
        with np.errstate(divide="ignore", invalid="ignore"):
            root = np.sqrt(np.maximum(c1 * c1 - 4 * c2 * c0, 0.0))
            half = -0.5 * (c1 + np.where(c1 >= 0, root, -root))  # the stable quadratic roots
            real = (c1 * c1 - 4 * c2 * c0) >= 0
            first = np.where(real, half / c2, np.nan)
            second = np.where(real, c0 / half, np.nan)
        best_d = np.full(len(points), np.inf)
        foot = np.zeros((len(points), 2))
        normal = np.zeros((len(points), 2))
        kappa = np.zeros(len(points))
        for u in (first, second):
            ok = np.isfinite(u) & (u >= -1e-9) & (u <= 1 + 1e-9)
            u = np.where(ok, u, 0.0)  # not clipped: a foot a hair past a joint stays exact
            at = a[None] + u[..., None] * e[None]
            tangent = _unit(ta[None] + u[..., None] * dt[None])
            n = np.stack([-tangent[..., 1], tangent[..., 0]], axis=-1)
            d = np.einsum("psk,psk->ps", points[:, None, :] - at, n)
            d = np.where(ok, d, np.inf)
            j = np.argmin(np.abs(d), axis=1)
            rows = np.arange(len(points))
            better = np.abs(d[rows, j]) < np.abs(best_d)
            best_d = np.where(better, d[rows, j], best_d)
            foot = np.where(better[:, None], at[rows, j], foot)
            normal = np.where(better[:, None], n[rows, j], normal)
            kappa = np.where(better, self.curvature[j], kappa)
        lost = ~np.isfinite(best_d)  # no foot on any segment (not met past the long ends)
        if np.any(lost):
            near = np.argmin(np.linalg.norm(points[lost, None] - self.points[None], axis=2), axis=1)
            foot[lost] = self.points[near]
            normal[lost] = np.stack([-self.tangents[near, 1], self.tangents[near, 0]], axis=-1)
            best_d[lost] = np.einsum("pk,pk->p", points[lost] - foot[lost], normal[lost])
            bends = np.concatenate([[0.0], self.curvature, [0.0]])  # the segments at a joint
            kappa[lost] = np.where(
                np.abs(bends[near]) > np.abs(bends[near + 1]), bends[near], bends[near + 1]
            )
        return foot, normal, best_d, kappa

    def offset(self, points: np.ndarray) -> np.ndarray:
        """(n,) signed offsets of (n, 2+) plane points from the midrib (+ left of it)."""
        points = np.asarray(points, dtype=float).reshape(-1, np.shape(points)[-1])[:, :2]
        return self._feet(points)[2]

    def mirror_reach(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """How far each point's mirror image reaches into a bend: (n,) -d kappa, a share of the
        midrib's radius of curvature at its foot (positive: the image falls on the inside of
        the bend; 1 or more: at or past the centre of curvature, where the mirror folds), with
        the (n,) signed offsets d and the (n, 2) feet. 1 / |kappa| is the radius there:
        -d / reach where reach is not 0."""
        points = np.asarray(points, dtype=float).reshape(-1, np.shape(points)[-1])[:, :2]
        foot, _, d, kappa = self._feet(points)
        return -d * kappa, d, foot

    def reflect(self, points: np.ndarray) -> np.ndarray:
        """(n, k) points, k >= 2, with x, y mirrored across the midrib (other columns kept)."""
        out = np.array(points, dtype=float).reshape(-1, np.shape(points)[-1])
        foot, normal, d, _ = self._feet(out[:, :2])
        out[:, :2] = foot - d[:, None] * normal
        return out
