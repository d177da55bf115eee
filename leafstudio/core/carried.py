"""Directions carried by a bend (a model.Bend: a form's pose, a scan's sheet): its Jacobian
by central differences, for a bent surface's normals (an export's shading, a solid's offsets)
and for how far a point off the flat blade stands off the bent one (the vein correction's
tolerances, core/correct.py)."""

from __future__ import annotations

import numpy as np

STRETCH_STEP = 1e-6  # the differences' step, of the points' largest coordinate


def carried_vectors(bend, points: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """(n, 3) each of the (n, 3) `vectors` at (n, 3) flat points carried by `bend`'s Jacobian
    (a model.Bend), by central differences (STRETCH_STEP of the points' extent)."""
    return _carried(bend, points, np.asarray(vectors, dtype=float)[None])[0]


def _carried(bend, points: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """(k, n, 3) `carried_vectors` of each of the (k, n, 3) `vectors`, the 2 k points either
    side carried in one call of the bend (a pose's apply: six calls for a leaf's 212 vein points'
    frames took 0.71 ms of a four-term pose's run, one 0.29: its per-call cost)."""
    points = np.asarray(points, dtype=float)
    step = STRETCH_STEP * max(float(np.abs(points).max()), 1e-12)
    either = np.stack([points + step * vectors, points - step * vectors])  # (2, k, n, 3)
    bent = bend.apply(either.reshape(-1, 3)).reshape(either.shape)
    return (bent[0] - bent[1]) / (2 * step)


def _carried_frames(bend, points: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Each of the (n, 3, 3) `directions` (three per point) carried (`carried_vectors`):
    (3, n, 3)."""
    return _carried(bend, points, np.moveaxis(directions, 1, 0))


def normal_stretch(bend, points: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """(n,) how many times `bend` (a model.Bend) lengthens a short distance off a surface at
    (n, 3) flat points: `directions` (n, 3, 3) holds two tangents and the unit normal of the
    surface at each. A point δ off the surface stands δ · stretch off it bent: the bent normal's
    share along the bent surface's normal, |(J t₁ × J t₂) · J n| / |J t₁ × J t₂|. A fold on a
    rolled tube turns the rolled section's halves about the midrib as if they were flat: where
    the section leans against the fold it reaches 1.4 at 75° (3.9 when the fold was a shear,
    z += |y| tan fold); a fold alone, which lifts the relief straight up, or a roll alone keeps
    it 1 or less."""
    points = np.asarray(points, dtype=float)
    if not len(points):
        return np.ones(0)
    j = _carried_frames(bend, points, directions)
    across = np.cross(j[0], j[1])
    area = np.linalg.norm(across, axis=1)
    return np.abs((across * j[2]).sum(axis=1)) / np.maximum(area, 1e-300)


def carried_normals(bend, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """(n, 3) unit normals of the bent surface at (n, 3) flat points whose flat surface has the
    unit `normals` there: the bent tangents' cross product, on the side `bend` carries the
    normal to (an export's shading and a solid's offsets; the flat normals were off by the
    fold's angle)."""
    points, normals = np.asarray(points, dtype=float), np.asarray(normals, dtype=float)
    if not len(points):
        return normals.copy()
    helper = np.where(np.abs(normals[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    first = np.cross(normals, helper)
    first /= np.linalg.norm(first, axis=1, keepdims=True)
    second = np.cross(normals, first)
    j = _carried_frames(bend, points, np.stack([first, second, normals], axis=1))
    bent = np.cross(j[0], j[1])
    bent *= np.sign((bent * j[2]).sum(axis=1))[:, None]
    return bent / np.maximum(np.linalg.norm(bent, axis=1, keepdims=True), 1e-300)
