"""A flat run's mesh carried into 3D by a bend (bend.py): cut along its crease, trimmed, its
chords halved where the bend sags them, and its curvatures the bent surface's
(bent_curvature.py)."""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from leafstudio.core.bent_curvature import Jet, bent_curvatures, carried_jets
from leafstudio.core.buckets import bounds, kernel_array
from leafstudio.core.cuts import Plan, carried, carried_data, carried_outline, cut_levels
from leafstudio.core.edges import edge_table
from leafstudio.core.jit import njit
from leafstudio.core.plane import Frame
from leafstudio.core.trianglemesh import CURVATURE_ARRAYS, TriangleMesh

ROUND_OFF = 1e-12  # of the mesh's extent: a point this near a crease lies on it
SAG_ROUNDS = 6  # sag_splits halves the edges that sag too far this many rounds at most (each
# round a quarter of the sag)

# points onto a surface, with their heights and jets there (bent_curvature.jet_of); the (n,)
# bool flags those on the outline, whose jets are the limits from inside (Result.on_outline)
Lift = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]


def _extent(points: np.ndarray) -> float:
    """The (n, 3) points' largest side (buckets.bounds: np.ptp over axis 0 is slow)."""
    lo, hi = bounds(points)
    return float((hi - lo).max())


def _crease_cuts(mesh: TriangleMesh, crease, trim) -> tuple[np.ndarray, Plan, bool, np.ndarray]:
    """The mesh's faces cut along the bend's crease (where `crease` is zero: a fold's midrib),
    the plan of the new points, whether `trim` cut any, and the points with the new ones (a
    copy: carried). `trim` (model.Bend.trim: a scan's holes): the faces also cut where it is
    zero, and those where it is negative dropped."""
    side = crease(mesh.points)
    faces, plan = mesh.regular_faces, []
    if side is not None:  # a point within round-off of the crease is on it: cut beside it, a
        # form's tip 3e-20 off left a face of no area (its UVs none, no tangent in a glTF)
        extent = _extent(mesh.points) if len(mesh.points) else 0.0
        side = np.where(np.abs(side) <= ROUND_OFF * extent, 0.0, side)
        faces, plan = cut_levels(faces, side, np.zeros(1))
    points = carried(mesh.points, plan)
    cut = trim(points)
    if cut is None:
        return faces, plan, False, points
    faces, more = cut_levels(faces, cut, np.zeros(1))
    kept = faces[carried(cut, more)[faces].mean(axis=1) >= 0]
    return kept, plan + more, True, carried(points, more)


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
    points, faces = kernel_array(points), kernel_array(faces, np.int64)
    bent, plan, done = carry(points) if bent is None else bent, [], []
    for _ in range(SAG_ROUNDS):  # after the first, over the faces the last one made only
        n = len(points)
        # each side's edge among the sorted edges (edges.edge_table: a stable argsort of the
        # sides' codes with its inverse took 1.1-1.4 ms of a grid-128 mesh's 14,500 faces)
        keys, _, edge = edge_table(faces, n)
        middle = _middles(points, keys)
        there = carry(middle)
        marked = _sagging(kernel_array(there), kernel_array(bent), keys, tolerance)
        if not marked.any():
            break
        whole, faces = _halvings(faces, edge, marked, n)  # the others kept whole
        done.append(whole)
        points = np.vstack([points, middle.compress(marked, axis=0)])
        bent = np.vstack([bent, there.compress(marked, axis=0)])
        plan.append((keys.compress(marked, axis=0), np.full(np.count_nonzero(marked), 0.5)))
    return np.vstack([*done, faces]) if done else faces, plan, bent


@njit(cache=True, nogil=True)
def _middles(points: np.ndarray, keys: np.ndarray) -> np.ndarray:
    """(e, 3) the midpoints of the (e, 2) `keys` edges between (n, 3) points, 0.5 (a + b) (by
    np.take, rows gathered 3 times as fast as by indexing: 0.46 ms of 22,000 edges, then
    0.125 of 21,300 with the sum's two temporaries; here 0.04, best of 100 alternated)."""
    middle = np.empty((len(keys), 3))
    for e in range(len(keys)):
        a, b = keys[e, 0], keys[e, 1]
        for k in range(3):
            middle[e, k] = 0.5 * (points[a, k] + points[b, k])
    return middle


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


@njit(cache=True, nogil=True)
def _halvings(
    faces: np.ndarray, edge: np.ndarray, marked: np.ndarray, n: int
) -> tuple[np.ndarray, np.ndarray]:
    """The (f, 3) faces none of whose sides (a, b), (b, c), (c, a) is a `marked` edge (`edge`:
    each side's, edges.edge_table), and the others with those halved: the marked edges' new
    points numbered from `n` in the edges' order; one edge halved cuts a face in two, two in
    three, three in four, each piece wound as the face, the pieces of each kind together (numpy's
    gathers over the sides and its turned faces took 0.25-0.27 ms of a grid-128 ovate form's
    14,500 faces with 13-22 edges halved, this 0.065; 1.04 and 0.11 with 3,392)."""
    new = np.empty(len(marked), np.int64)  # each marked edge's new point
    k = n
    for e in range(len(marked)):
        new[e] = k
        k += 1 if marked[e] else 0
    count = np.zeros(len(faces), np.int64)
    kinds = np.zeros(4, np.int64)
    for t in range(len(faces)):
        for side in range(3):
            count[t] += 1 if marked[edge[3 * t + side]] else 0
        kinds[count[t]] += 1
    whole = np.empty((kinds[0], 3), np.int64)
    one, two, three = kinds[1], kinds[2], kinds[3]
    pieces = np.empty((2 * one + 3 * two + 4 * three, 3), np.int64)
    at = np.array([0, 0, 2 * one, 2 * one + 3 * two])  # each kind's first piece
    kept = 0
    for t in range(len(faces)):
        c = count[t]
        if c == 0:
            whole[kept, 0], whole[kept, 1], whole[kept, 2] = faces[t, 0], faces[t, 1], faces[t, 2]
            kept += 1
            continue
        if c == 1:  # turned so the halved edge is (a, b)
            first = 0 if marked[edge[3 * t]] else (1 if marked[edge[3 * t + 1]] else 2)
        elif c == 2:  # turned so the halved ones are (a, b) and (b, c): after the whole one
            first = 1 if not marked[edge[3 * t]] else (2 if not marked[edge[3 * t + 1]] else 0)
        else:
            first = 0
        a, b, cc = faces[t, first], faces[t, (first + 1) % 3], faces[t, (first + 2) % 3]
        ab = new[edge[3 * t + first]]
        bc = new[edge[3 * t + (first + 1) % 3]]
        ca = new[edge[3 * t + (first + 2) % 3]]
        i = at[c]
        if c == 1:
            pieces[i, 0], pieces[i, 1], pieces[i, 2] = a, ab, cc
            i += one
            pieces[i, 0], pieces[i, 1], pieces[i, 2] = ab, b, cc
        elif c == 2:
            pieces[i, 0], pieces[i, 1], pieces[i, 2] = ab, b, bc
            i += two
            pieces[i, 0], pieces[i, 1], pieces[i, 2] = a, ab, bc
            i += two
            pieces[i, 0], pieces[i, 1], pieces[i, 2] = a, bc, cc
        else:
            pieces[i, 0], pieces[i, 1], pieces[i, 2] = a, ab, ca
            i += three
            pieces[i, 0], pieces[i, 1], pieces[i, 2] = ab, b, bc
            i += three
            pieces[i, 0], pieces[i, 1], pieces[i, 2] = ca, bc, cc
            i += three
            pieces[i, 0], pieces[i, 1], pieces[i, 2] = ab, bc, ca
        at[c] += 1
    return whole, pieces


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


class Bent(NamedTuple):
    """bent_mesh's answer: the bent mesh, its points before they were carried (Result.blade_xy:
    laid flat again, a tube's seam is ambiguous), and which of them lie on the outline
    (Result.outline_points)."""

    mesh: TriangleMesh
    flat: np.ndarray
    outline: np.ndarray


def bent_mesh(
    mesh: TriangleMesh, bend: BentBy, sag: Tolerance | None, lift: Lift | None, n_outline: int
) -> Bent:
    """The mesh cut along the bend's creases (`crease`, in its units), trimmed (`trim`, see
    _crease_cuts; the points no face keeps dropped), its edges halved where the bend sags them
    by more than `sag` of its extent (`sag_splits`) and carried into 3D by `carry`, with the
    bent surface's curvatures (bent_curvature.py) where the mesh has its surface's jet. The
    mesh's first `n_outline` points are its outline's (the meshers put it first): the cuts' and
    halvings' points on its edges are too, and the trim drops some (cuts.carried_outline: the
    first len(polygon) of a trimmed mesh were not the outline, sugar beet pot1_7's 7 of them up
    to 0.63 mm inside it, and 2 new points on it were left out)."""
    faces, plan, trimmed, points = _crease_cuts(mesh, bend.crease, bend.trim)
    extra = {} if mesh.jet is None else {JET: mesh.jet}
    # with a jet, the flat curvature arrays are not carried: the bent surface's replace them
    # (bent_curvatures), and the points are carried once (_crease_cuts): bent_mesh of a grid-128
    # ovate form rolled 0.5 took 3.67-3.85 ms, now 3.56-3.65 (best of 60, alternated)
    flat = {k: v for k, v in mesh.point_data.items() if not (extra and k in CURVATURE_ARRAYS)}
    data = carried_data(flat | extra, plan)
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
        plan = plan + more
    outline = carried_outline(n_outline, len(mesh.points), plan)
    if lift is not None and first < len(points):  # the halvings' points on the surface, those
        # on the outline with its limits: without, a linear blade rolled 1 had their mean
        # curvatures 1.17 off their outline neighbours' (median; the others' 0.016)
        points[first:], heights, taylor = lift(points[first:], outline[first:])
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
        outline = outline[used]
        data = {name: values[used] for name, values in data.items()}
    if extra:
        taylor = data.pop(JET)
        known = None if jets is None else jets[1]
        data |= bent_curvatures(
            bend.carry, bend.carry_jet, bend.frame, points, carried_points, taylor, known
        )
        data = {k: data[k] for k in mesh.point_data if k in data} | data  # the flat mesh's order
    return Bent(TriangleMesh(carried_points, faces, data), points, outline)
