"""A triangle mesh cut along straight level lines of a linear function, and values carried to the
new points: the bend's creases and a scan's holes are cut this way before the mesh is bent
(core/bend.py), so no chord crosses a crease.

A cut's new points lie on the mesh's edges; `carried` gives any per-point array (positions,
heights, curvatures) at them by linear interpolation along their edges, in the order they were
made (a `Plan`).
"""

from __future__ import annotations

import numpy as np

Plan = list[tuple[np.ndarray, np.ndarray]]  # per cut: (k, 2) edges cut and (k,) where along them


def cut_levels(faces: np.ndarray, q: np.ndarray, levels: np.ndarray) -> tuple[np.ndarray, Plan]:
    """(f', 3) faces cut along every line where the (n,) values q, linear on each triangle, equal
    one of the (m,) levels, and the plan of the new points (`carried`).

    One level after another, each over the triangles across it only (pieces across a higher one
    wait for it): a roll's 30-odd lines (when a roll was cut every 0.1 radians) cost about what
    one did when each cut went over the whole mesh (a roll took 3.8 times a flat run's time)."""
    faces = np.asarray(faces)
    levels = np.sort(np.asarray(levels, dtype=float))
    waiting: list[list[np.ndarray]] = [[] for _ in levels]
    done = [_sorted_out(faces, q, levels, waiting)]
    plan: Plan = []
    for j, level in enumerate(levels):
        if not waiting[j]:
            continue
        tri = np.vstack(waiting[j])
        signs = np.sign(q[tri] - level)
        crossing = (signs.max(axis=1) > 0) & (signs.min(axis=1) < 0)
        new, keys, t = _split(tri[crossing], signs[crossing], q - level, len(q))
        q = np.concatenate([q, np.full(len(t), level)])  # the new points lie on the level
        plan.append((keys, t))
        pieces = np.vstack([tri[~crossing], new.astype(faces.dtype)])
        done.append(_sorted_out(pieces, q, levels, waiting, j + 1))
    return np.vstack(done), plan


def _sorted_out(
    faces: np.ndarray, q: np.ndarray, levels: np.ndarray, waiting: list, lowest: int = 0
) -> np.ndarray:
    """The faces across no level from the `lowest` on, returned; the others added to `waiting`
    at the lowest such level they cross."""
    a, b, c = q[faces.T]  # each corner's: min and max over 3 columns took 0.97 ms of a
    # 14,000-face mesh's crease, over the three corners 0.05
    first = np.searchsorted(levels, np.minimum(np.minimum(a, b), c), "right")
    first = np.maximum(first, lowest)
    across = first < np.searchsorted(levels, np.maximum(np.maximum(a, b), c), "left")
    if not across.any():
        return faces
    first, crossing = first.compress(across), faces.compress(across, axis=0)
    order = np.argsort(first, kind="stable")
    at, start = np.unique(first[order], return_index=True)
    for j, part in zip(at, np.split(crossing[order], start[1:]), strict=True):
        waiting[j].append(part)
    return faces.compress(~across, axis=0)  # [~across]: 4 times as long


def _split(tri: np.ndarray, s: np.ndarray, side: np.ndarray, first: int) -> tuple:
    """The (t, 3) triangles `tri` crossing 0 of `side` (their corners' signs `s`) cut in two or
    three along it: (the new faces, the (k, 2) edges cut, where along them); the new points are
    numbered from `first`."""
    through = (s == 0).any(axis=1)  # through a vertex (the other two on either side)
    # each triangle turned so that its first corner is the zero (through a vertex) or alone on
    # its side (else): the cut runs through edges (b, c), or (a, b) and (c, a)
    lone = np.where(through, np.argmax(s == 0, axis=1), np.argmax(s * s.sum(1)[:, None] < 0, 1))
    turn = (lone[:, None] + np.arange(3)) % 3
    a, b, c = np.take_along_axis(tri, turn, axis=1).T
    ends = np.vstack([np.column_stack([b, c])[through], np.column_stack([a, b])[~through],
                      np.column_stack([c, a])[~through]])  # fmt: skip
    ends = np.sort(ends, axis=1).astype(np.int64)
    n = int(ends.max()) + 1  # each edge one number: a 1-D unique is several times faster
    codes, at = np.unique(ends[:, 0] * n + ends[:, 1], return_inverse=True)
    keys = np.column_stack([codes // n, codes % n])
    t = side[keys[:, 0]] / (side[keys[:, 0]] - side[keys[:, 1]])
    index = first + at.ravel()
    n_through = int(through.sum())
    m, ab, ca = index[:n_through], index[n_through:][: len(a) - n_through], index[len(a) :]
    a1, b1, c1 = a[through], b[through], c[through]
    a2, b2, c2 = a[~through], b[~through], c[~through]
    new = np.vstack([
        np.column_stack([a1, b1, m]), np.column_stack([a1, m, c1]),
        np.column_stack([a2, ab, ca]), np.column_stack([ab, b2, c2]), np.column_stack([ab, c2, ca]),
    ])  # fmt: skip
    return new, keys, t


def carried(values: np.ndarray, plan: Plan) -> np.ndarray:
    """(n + k, ...) `values` at the mesh's points followed by those at the cuts' new points,
    interpolated linearly along the edges cut (filled in place: one copy for every cut)."""
    n = len(values)
    out = np.empty((n + sum(len(t) for _, t in plan), *values.shape[1:]), dtype=values.dtype)
    out[:n] = values
    for keys, t in plan:
        lo, hi = out[keys[:, 0]], out[keys[:, 1]]
        out[n : n + len(t)] = lo + t.reshape(-1, *([1] * (values.ndim - 1))) * (hi - lo)
        n += len(t)
    return out


def carried_data(point_data: dict[str, np.ndarray], plan: Plan) -> dict[str, np.ndarray]:
    return {name: carried(v, plan) for name, v in point_data.items()}


def carried_outline(n_outline: int, n_points: int, plan: Plan) -> np.ndarray:
    """(n_points + k,) bool: which of a mesh's points, followed by a `plan`'s new points, lie on
    its outline, the ring through its first `n_outline` points (both meshers put the outline
    first, in order): a new point is on it when the edge it cuts is one of the ring's edges or
    of the pieces the cuts before made of them. Not read off the points' places: an edge
    joining two outline points across a narrow tip is no outline edge, and a fold's crease cuts
    it inside the blade."""
    total = n_points + sum(len(t) for _, t in plan)
    flags = np.zeros(total, dtype=bool)
    flags[:n_outline] = True
    ring = np.arange(n_outline, dtype=np.int64)
    codes = _edge_codes(ring, np.roll(ring, -1), total)
    n = n_points
    for keys, t in plan:
        a, b = keys[:, 0].astype(np.int64), keys[:, 1].astype(np.int64)
        on = np.flatnonzero(np.isin(_edge_codes(a, b, total), codes))
        new = n + on
        flags[new] = True
        codes = np.concatenate(
            [codes, _edge_codes(a[on], new, total), _edge_codes(new, b[on], total)]
        )
        n += len(t)
    return flags


def _edge_codes(a: np.ndarray, b: np.ndarray, n: int) -> np.ndarray:
    """One int64 per edge (a, b) of a mesh of `n` points, whichever way it is walked."""
    return np.minimum(a, b) * n + np.maximum(a, b)
