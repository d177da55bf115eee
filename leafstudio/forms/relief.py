"""A form's relief: the smooth dome its veins stand on (veins.py, step 3).

A vein's height used to be HEIGHT_RATIO times its distance to the margin, as the demos' midribs
are: a roof, 14° each side of the midrib, with a crease along it (and along every branch of the
blade's medial axis, into each lobe). A surface that passes within 1e-3 of the length of every
vein point had to follow that crease: the 99th-percentile interior dihedral of a reconstructed
ovate form was 4.6° where the paper's smooth surface, 6.5e-3 off the midrib, had 3.4°.

The dome is the blade as a membrane under an even pressure: ψ with −Δψ = 1 inside and ψ = 0
on the margin (Prandtl's stress function). It is smooth inside whatever the outline, has no slope
where it is highest, rises from the margin at a slope proportional to the local width, and on
an ellipse is exactly the paraboloid 1 − x²/a² − y²/b² (scaled). The heights are

    h = HEIGHT_RATIO · R · ψ / max ψ,

R the largest distance to the margin, so the highest point stands where and as high as the
roof's; across a strip of half-width w, h is the parabola H (1 − (v/w)²). ψ is solved with
linear finite elements on a Triangle mesh of the blade and read back with Clough-Tocher's C1
interpolant.

At a sinus's notch (cordate, reniform, sagittate, hastate), where the midrib starts, ψ rises
as about the square root of the distance: steeper than a smooth surface through the margin
follows, and the vein correction bent into a bump there. So the dome is multiplied by
1 − exp(−|x − base|² / BASE_CALM²): flat at the base, unchanged a few BASE_CALM away. The
99th-percentile margin dihedral at grid 128, K 3, roof / bare dome / this: reniform 1.3° /
5.0° / 2.3°, cordate 3.7° / 6.8° / 2.5°.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import shapely
import triangle
from scipy.interpolate import CloughTocher2DInterpolator
from scipy.sparse import coo_matrix
from scipy.sparse.linalg import spsolve
from shapely.geometry import Polygon

BASE_CALM = 0.15  # the dome is flattened within about this of the midrib's base (a sinus's
# notch, where ψ rises as the square root of the distance: see the module)
CELL = 0.012  # the finite elements' size, a share of the blade's length (1 here)


def dome(poly: Polygon, ratio: float, base: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """The dome over a blade of length about 1: (n, 2) points -> (n,) heights, `ratio` times
    the largest distance to the margin at its top and 0 on the margin, flattened around the
    midrib's `base` (see the module)."""
    ring = shapely.get_coordinates(poly.exterior.segmentize(CELL))[:-1]
    segments = np.column_stack([np.arange(len(ring)), np.roll(np.arange(len(ring)), -1)])
    mesh = triangle.triangulate(
        {"vertices": ring, "segments": segments}, f"pq30a{0.5 * CELL**2:.8f}Q"
    )
    points, faces = mesh["vertices"], mesh["triangles"]
    inner = mesh["vertex_markers"].ravel() == 0
    psi = np.zeros(len(points))
    psi[inner] = _membrane(points, faces, inner)
    top = float(psi.max())
    if top <= 0:  # no inner node: a sliver of a blade, flat
        return lambda xy: np.zeros(len(np.atleast_2d(xy)))
    inradius = float(shapely.distance(poly.exterior, shapely.points(points[inner])).max())
    read = CloughTocher2DInterpolator(points, psi * (ratio * inradius / top), fill_value=0.0)

    def heights(xy: np.ndarray) -> np.ndarray:
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        calm = 1 - np.exp(-((xy - base) ** 2).sum(axis=1) / BASE_CALM**2)
        return np.maximum(read(xy), 0.0) * calm

    return heights


def _membrane(points: np.ndarray, faces: np.ndarray, inner: np.ndarray) -> np.ndarray:
    """ψ at the inner nodes: −Δψ = 1, ψ = 0 on the others (P1 elements: the stiffness
    Σ_T |T| ∇φ_i·∇φ_j, the load |T| / 3 at each corner)."""
    corners = points[faces]  # (t, 3, 2)
    edges = np.roll(corners, -1, axis=1) - np.roll(corners, 1, axis=1)  # opposite each corner
    area = 0.5 * np.abs(edges[:, 0, 0] * edges[:, 1, 1] - edges[:, 0, 1] * edges[:, 1, 0])
    # ∇φ_i = perp(edge opposite i) / (2 |T|): the dot products of the edges over 4 |T|
    stiffness = np.einsum("tid,tjd->tij", edges, edges) / (4 * area)[:, None, None]
    rows = np.repeat(faces, 3, axis=1).ravel()
    cols = np.tile(faces, (1, 3)).ravel()
    n = len(points)
    matrix = coo_matrix((stiffness.ravel(), (rows, cols)), shape=(n, n)).tocsr()
    load = np.bincount(faces.ravel(), np.repeat(area / 3, 3), minlength=n)
    index = np.flatnonzero(inner)
    return spsolve(matrix[index][:, index].tocsc(), load[index])
