"""A bent leaf's curvatures: the bent surface's own, not its flat blade's (issue 21).

A bent run reconstructs the flat blade and carries its mesh into 3D (bend.py). The flat mesh's
curvature arrays are those of the relief alone: a rolled grass blade was coloured as if flat,
and a curled scan's curvature summary ignored its curl. Here each vertex's surface is carried
through the bend to second order: its jet, the point with its first and second derivatives
along the flat run's plane axes, starts from the flat surface's height, ∇z and ∇²z there
(`TriangleMesh.jet`), and the bent surface's fundamental forms give its curvatures.

A pose carries a jet in closed form (Pose.carry_jet: the chain rule through its roll, fold,
twist and curl; exact, and a fold's crease taken from its + side). Any other bend (a scan's
sheet) is differenced: the flat surface's second-order expansion at the vertex is sampled STEP
apart on a stencil, carried, and differenced (central differences, and a one-sided one for
∂uv; for no bend that is the graph's curvature to round-off: the differences of a quadratic).
The points a bend's sag halvings add (bent_mesh.sag_splits) take the surface's own jet there
(bent_result._onto_surface); those of its crease and trim cuts, theirs interpolated along the
edge cut.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from leafstudio.core.buckets import kernel_array
from leafstudio.core.jit import njit
from leafstudio.core.plane import Frame
from leafstudio.core.trianglemesh import CURVATURE_ARRAYS

# a jet: (n, 3) points and (n, 5, 3) their derivatives ∂u, ∂v, ∂uu, ∂uv, ∂vv along the flat
# run's plane axes
Jet = tuple[np.ndarray, np.ndarray]
STEP = 1e-4  # of the mesh's extent: the stencil's spacing (round-off in ∇² about 1e-8 of it)
# the stencil's offsets in steps: the centre (carried already), ±u, ±v, and (1, 1) for ∂uv
# (one-sided: O(STEP) off, and one carried point in six fewer)
OFFSETS = np.array([(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1)], dtype=float)


def jet_of(grad: np.ndarray, hess: np.ndarray) -> np.ndarray:
    """(n, 5) zx, zy, zxx, zxy, zyy from ∇z (n, 2) and ∇²z (n, 2, 2)."""
    return np.column_stack([grad, hess[:, 0, 0], hess[:, 0, 1], hess[:, 1, 1]])


def affine_jet(move: Callable[[np.ndarray], np.ndarray], jet: Jet) -> Jet:
    """`jet` carried by the affine map `move` ((n, 3) points to (n, 3)): its linear part,
    move(v) − move(0), moves the derivatives (to round-off of move(0): 1e-16 of the offset
    over the size, nothing below a leaf 1e11 of its size from the origin)."""
    points, d = jet
    zero = move(np.zeros((1, 3)))
    return move(points), (move(d.reshape(-1, 3)) - zero).reshape(d.shape)


def _flat_jet(frame: Frame, xy: np.ndarray, z: np.ndarray, taylor: np.ndarray) -> Jet:
    """The flat surface's jet at (n, 2) plane points with heights `z` and a jet `taylor`."""
    zx, zy, zxx, zxy, zyy = taylor.T
    along = np.zeros((len(xy), 5, 3))
    along[:, 0, 0] = along[:, 1, 1] = 1.0
    along[:, 0, 2], along[:, 1, 2] = zx, zy
    along[:, 2, 2], along[:, 3, 2], along[:, 4, 2] = zxx, zxy, zyy
    axes = np.stack([frame.u, frame.v, frame.normal])
    return frame.to_world(xy, z), (along.reshape(-1, 3) @ axes).reshape(along.shape)


def _differenced(
    carry: Callable[[np.ndarray], np.ndarray], frame: Frame, xy: np.ndarray, z: np.ndarray,
    taylor: np.ndarray, centre: np.ndarray, h: float,
) -> np.ndarray:  # fmt: skip
    """(n, 5, 3) the carried surface's derivatives at the (n, 2) plane points `xy` (carried
    already: `centre`), from the stencil OFFSETS on z's second-order expansion `taylor`."""
    n = len(xy)
    d = h * OFFSETS[:, None, :]  # (5, 1, 2)
    dx, dy = d[..., 0], d[..., 1]
    zx, zy, zxx, zxy, zyy = taylor.T
    heights = z + zx * dx + zy * dy + 0.5 * (zxx * dx * dx + 2 * zxy * dx * dy + zyy * dy * dy)
    s = carry(frame.to_world((xy + d).reshape(-1, 2), heights.ravel())).reshape(5, n, 3)
    su, sv = (s[0] - s[1]) / (2 * h), (s[2] - s[3]) / (2 * h)
    suu, svv = (s[0] - 2 * centre + s[1]) / h**2, (s[2] - 2 * centre + s[3]) / h**2
    # f(h, h) = f + h (f_u + f_v) + h² (f_uu + 2 f_uv + f_vv) / 2 + O(h³)
    suv = (s[4] - centre - h * (su + sv)) / h**2 - (suu + svv) / 2
    return np.stack([su, sv, suu, suv, svv], axis=1)


@njit(cache=True, nogil=True)
def _curvatures(d: np.ndarray) -> np.ndarray:
    """(4, n) mean, Gaussian, k1 and k2 from a jet's (n, 5, 3) derivatives, on the side of
    ∂u × ∂v (the flat plane's normal for no bend: the graph's convention)."""
    n = d.shape[0]
    out = np.empty((4, n))
    for i in range(n):
        su, sv = d[i, 0], d[i, 1]
        nx = su[1] * sv[2] - su[2] * sv[1]
        ny = su[2] * sv[0] - su[0] * sv[2]
        nz = su[0] * sv[1] - su[1] * sv[0]
        size = max(np.sqrt(nx * nx + ny * ny + nz * nz), 1e-300)
        nx, ny, nz = nx / size, ny / size, nz / size
        e = su[0] * su[0] + su[1] * su[1] + su[2] * su[2]
        f = su[0] * sv[0] + su[1] * sv[1] + su[2] * sv[2]
        g = sv[0] * sv[0] + sv[1] * sv[1] + sv[2] * sv[2]
        ll = d[i, 2, 0] * nx + d[i, 2, 1] * ny + d[i, 2, 2] * nz
        mm = d[i, 3, 0] * nx + d[i, 3, 1] * ny + d[i, 3, 2] * nz
        nn = d[i, 4, 0] * nx + d[i, 4, 1] * ny + d[i, 4, 2] * nz
        area = max(e * g - f * f, 1e-300)
        gauss = (ll * nn - mm * mm) / area
        mean = (e * nn - 2 * f * mm + g * ll) / (2 * area)
        spread = np.sqrt(max(mean * mean - gauss, 0.0))
        out[0, i], out[1, i], out[2, i], out[3, i] = mean, gauss, mean + spread, mean - spread
    return out


def carried_jets(
    carry_jet: Callable[[Jet], Jet], frame: Frame, flat: np.ndarray, taylor: np.ndarray
) -> Jet:
    """The flat surface's jets at (n, 3) points on it, with its ∇z and ∇²z there (`taylor`,
    jet_of), carried by `carry_jet`: the bent points and their (n, 5, 3) derivatives."""
    xy, z = frame.to_plane(flat)
    return carry_jet(_flat_jet(frame, xy, z, taylor))


def bent_curvatures(
    carry: Callable[[np.ndarray], np.ndarray],
    carry_jet: Callable[[Jet], Jet] | None,
    frame: Frame,
    flat: np.ndarray,
    bent: np.ndarray,
    taylor: np.ndarray,
    known: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """The curvature arrays (CURVATURE_ARRAYS) of the bent surface at a bent mesh's vertices.

    Parameters
    ----------
    carry, carry_jet : callables
        The bend: flat points to bent, and a jet to the bent one (None: the stencil is
        differenced instead), as bent_mesh.bent_mesh takes them.
    frame : Frame
        The flat run's plane: the jet's x, y and z are in it.
    flat, bent : (n, 3) float arrays
        The vertices on the flat surface, and carried.
    taylor : (n, 5) float array
        Their flat surface's ∇z and ∇²z there (jet_of).
    known : (m, 5, 3) float array, optional
        The first m vertices' carried derivatives (carried_jets), when carry_jet gave them
        already.
    """
    if not len(flat):  # a mesh trimmed to nothing
        return {name: np.zeros(0) for name in CURVATURE_ARRAYS}
    if carry_jet is not None:
        m = 0 if known is None else len(known)
        d = carried_jets(carry_jet, frame, flat[m:], taylor[m:])[1]
        d = d if known is None else np.concatenate([known, d])
    else:
        xy, z = frame.to_plane(flat)
        h = STEP * max(float(np.ptp(flat, axis=0).max()), 1e-300)
        d = _differenced(carry, frame, xy, z, taylor, bent, h)
    return dict(zip(CURVATURE_ARRAYS, _curvatures(kernel_array(d)), strict=True))
