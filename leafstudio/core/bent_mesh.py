"""A flat run's mesh carried into 3D by a bend (bend.py): cut along its crease, trimmed, its
chords halved where the bend sags them, and its curvatures the bent surface's
(bent_curvature.py)."""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from leafstudio.core.bent_curvature import Jet, bent_curvatures, carried_jets
from leafstudio.core.buckets import bounds, kernel_array
from leafstudio.core.cuts import Plan, carried, carried_data, cut_levels
from leafstudio.core.edges import edge_table
from leafstudio.core.jit import njit
from leafstudio.core.plane import Frame
from leafstudio.core.trianglemesh import TriangleMesh

ROUND_OFF = 1e-12  # of the mesh's extent: a point this near a crease lies on it
SAG_ROUNDS = 6  # sag_splits halves the edges that sag too far this many rounds at most (each
# round a quarter of the sag)

# points onto a surface, with their heights and jets there (bent_curvature.jet_of)
Lift = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]


def _extent(points: np.ndarray) -> float:
    """The (n, 3) points' largest side (buckets.bounds: np.ptp over axis 0 is slow)."""
    lo, hi = bounds(points)
    return float((hi - lo).max())


def _crease_cuts(mesh: TriangleMesh, crease, trim) -> tuple[np.ndarray, Plan, bool]:
    """The mesh's faces cut along the bend's crease (where `crease` is zero: a fold's midrib),
    the plan of the new points, and whether `trim` cut any. `trim` (model.Bend.trim: a scan's
    holes): the faces also cut where it is zero, and those where it is negative dropped."""
    side = crease(mesh.points)
    faces, plan = mesh.regular_faces, []
    if side is not None:  # a point within round-off of the crease is on it: cut beside it, a
        # form's tip 3e-20 off left a face of no area (its UVs none, no tangent in a glTF)
        extent = _extent(mesh.points) if len(mesh.points) else 0.0
        side = np.where(np.abs(side) <= ROUND_OFF * extent, 0.0, side)
        faces, plan = cut_levels(faces, side, np.zeros(1))
    cut = trim(carried(mesh.points, plan))
    if cut is None:
        return faces, plan, False
    faces, more = cut_levels(faces, cut, np.zeros(1))
    return faces[carried(cut, more)[faces].mean(axis=1) >= 0], plan + more, True


def sag_splits(
    points: np.ndarray, faces: np.ndarray, carry, tolerance: float, bent: np.ndarray | None = None
) -> tuple[np.ndarray, Plan, np.ndarray]:
    """(f', 3) faces with every edge halved whose midpoint the bend `carry` takes farther than
    `tolerance` from the bent chord, the plan of the new points (`carried`), SAG_ROUNDS
    times at most, and every point carried (the new ones from their flat chord; `bent`: the
    points carried already, else carried here).

    The flat mesh is fine for the flat surface, but a strong bend curves each of its triangles:
    a fold of 75° on a rolled, twisted oblong blade bent the chords of a grid-128 mesh 1.4e-3
    of the length off the bent surface. A face is cut in as many pieces as it has edges halved,
    plus one (a conforming mesh, its winding kept). An edge of a face left whole passed: each
    later round looks at the new faces' edges only. bent_mesh then puts the new points on the
    flat surface (`bent_result._onto_surface`) rather than on the flat chord, which the bend
    stretches (up to 3 times on a folded tube: the last 1.03-1.05e-3 of the pose grid)."""
    points, faces = np.asarray(points, dtype=float), np.asarray(faces)
    bent, plan, done = carry(points) if bent is None else bent, [], []
    for _ in range(SAG_ROUNDS):  # after the first, over the faces the last one made only
        n = len(points)
        # each side's edge among the sorted edges (edges.edge_table: a stable argsort of the
        # sides' codes with its inverse took 1.1-1.4 ms of a grid-128 mesh's 14,500 faces)
        keys, _, edge = edge_table(faces, n)
        # np.take: rows gathered 3 times as fast as by indexing (0.46 ms of 22,000 edges)
        middle = 0.5 * (np.take(points, keys[:, 0], axis=0) + np.take(points, keys[:, 1], axis=0))
        there = carry(middle)
        marked = _sagging(kernel_array(there), kernel_array(bent), keys, tolerance)
        if not marked.any():
            break
        # the new points are numbered in the edges' order
        hit = marked[edge].reshape(faces.shape)  # (a, b), (b, c), (c, a) halved
        touched = hit[:, 0] | hit[:, 1] | hit[:, 2]  # few faces: the others kept whole (any
        # over 3 columns took 0.19 ms of 14,500 faces, this 0.015)
        done.append(faces.compress(~touched, axis=0))  # [~touched]: 4 times as long
        rank = (np.cumsum(marked) - 1)[edge].reshape(faces.shape).compress(touched, axis=0)
        halved = np.where(hit.compress(touched, axis=0), n + rank, -1)
        faces = _halved(faces.compress(touched, axis=0), halved)
        points = np.vstack([points, middle.compress(marked, axis=0)])
        bent = np.vstack([bent, there.compress(marked, axis=0)])
        plan.append((keys.compress(marked, axis=0), np.full(np.count_nonzero(marked), 0.5)))
    return np.vstack([*done, faces]) if done else faces, plan, bent


@njit(cache=True, nogil=True)
def _sagging(there: np.ndarray, bent: np.ndarray, keys: np.ndarray, tolerance: float) -> np.ndarray:
    """(e,) whether each edge's (e, 2) `keys` bent midpoint `there` stands farther than
    `tolerance` off the chord between its ends' `bent` points: twice its offset from the chord's
    midpoint, in tolerances (squared in the leaf's units, a leaf at 1e300 overflowed), over 2
    (numpy's five passes over 22,000 edges took 0.38 ms)."""
    marked = np.empty(len(keys), np.bool_)
    for e in range(len(keys)):
        a, b = keys[e, 0], keys[e, 1]
        size = 0.0
        for k in range(3):
            off = (((there[e, k] - bent[a, k]) - bent[b, k]) + there[e, k]) / tolerance
            size += off * off
        marked[e] = size > 4.0
    return marked


def _halved(faces: np.ndarray, middle: np.ndarray) -> np.ndarray:
    """(f', 3) faces with the (f, 3) `middle` points of their edges (a, b), (b, c), (c, a)
    (-1: not halved) put in: one edge halved cuts a face in two, two in three, three in four,
    each piece wound as the face."""
    count = (middle >= 0).sum(axis=1)
    pieces = [faces[count == 0]]
    for halved in (1, 2):  # turned so the halved edges are (a, b), then (b, c)
        these = count == halved
        first = np.argmax(middle[these] >= 0, axis=1)
        if halved == 2:  # the edge after the whole one comes first
            first = (np.argmax(middle[these] < 0, axis=1) + 1) % 3
        turn = (first[:, None] + np.arange(3)) % 3
        a, b, c = np.take_along_axis(faces[these], turn, axis=1).T
        ab, bc, _ = np.take_along_axis(middle[these], turn, axis=1).T
        if halved == 1:
            pieces += [np.column_stack([a, ab, c]), np.column_stack([ab, b, c])]
        else:
            pieces += [np.column_stack([ab, b, bc]), np.column_stack([a, ab, bc]),
                       np.column_stack([a, bc, c])]  # fmt: skip
    a, b, c = faces[count == 3].T
    ab, bc, ca = middle[count == 3].T
    pieces += [np.column_stack([a, ab, ca]), np.column_stack([ab, b, bc]),
               np.column_stack([ca, bc, c]), np.column_stack([ab, bc, ca])]  # fmt: skip
    return np.vstack(pieces).astype(faces.dtype)


Tolerance = Callable[[float], float]  # a mesh's extent -> how far its bent chords may sag
JET = "_jet"  # the mesh's jet, carried through the cuts as a point array


class BentBy(NamedTuple):
    """A bend as bent_mesh takes it, in the mesh's units: flat points to bent (`carry`), the
    crease's signed distance and the trim (model.Bend's), the flat run's plane, and a jet to the
    bent one (bent_curvature.py; None: differenced)."""

    carry: Callable[[np.ndarray], np.ndarray]
    crease: Callable[[np.ndarray], np.ndarray | None]
    trim: Callable[[np.ndarray], np.ndarray | None]
    frame: Frame
    carry_jet: Callable[[Jet], Jet] | None


def bent_mesh(
    mesh: TriangleMesh, bend: BentBy, sag: Tolerance | None, lift: Lift | None
) -> tuple[TriangleMesh, np.ndarray]:
    """The mesh cut along the bend's creases (`crease`, in its units), trimmed (`trim`, see
    _crease_cuts; the points no face keeps dropped), its edges halved where the bend sags them
    by more than `sag` of its extent (`sag_splits`) and carried into 3D by `carry`, with its
    points before they were carried (Result.blade_xy: laid flat again, a tube's seam is
    ambiguous), and the bent surface's curvatures (bent_curvature.py) where the mesh has its
    surface's jet."""
    faces, plan, trimmed = _crease_cuts(mesh, bend.crease, bend.trim)
    extra = {} if mesh.jet is None else {JET: mesh.jet}
    points, data = carried(mesh.points, plan), carried_data(mesh.point_data | extra, plan)
    first, jets, bent = len(points), None, None
    if extra and bend.carry_jet is not None and not trimmed:  # the points' jets first: their
        # bent points are those sag_splits' chords end at (carried again: 0.7 ms of a four-term
        # pose's grid-128 run)
        jets = carried_jets(bend.carry_jet, bend.frame, points, data[JET])
    if sag is not None and len(points):
        tolerance = sag(_extent(mesh.points))
        known = None if jets is None else jets[0]
        faces, more, bent = sag_splits(points, faces, bend.carry, tolerance, known)
        points, data, bent = carried(points, more), carried_data(data, more), bent[:first]
    if lift is not None and first < len(points):  # the halvings' points on the surface
        points[first:], heights, taylor = lift(points[first:])
        if "height" in data:
            data["height"][first:] = heights
        if JET in data:  # the surface's own, not the halved edge's ends' mean
            data[JET][first:] = taylor
    # the points before the halvings were carried by sag_splits already
    carried_points = (
        bend.carry(points) if bent is None else np.vstack([bent, bend.carry(points[first:])])
    )
    if trimmed and len(used := np.unique(faces)) < len(points):
        index = np.zeros(len(points), dtype=faces.dtype)
        index[used] = np.arange(len(used))
        points, carried_points, faces = points[used], carried_points[used], index[faces]
        data = {name: values[used] for name, values in data.items()}
    if extra:
        taylor = data.pop(JET)
        known = None if jets is None else jets[1]
        data |= bent_curvatures(
            bend.carry, bend.carry_jet, bend.frame, points, carried_points, taylor, known
        )
    return TriangleMesh(carried_points, faces, data), points
