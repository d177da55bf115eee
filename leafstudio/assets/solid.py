"""A leaf sheet made a closed solid of a given thickness, for printing and thick-leaf renders.

Each vertex p with unit normal n gives a top vertex p + t/2 n and a bottom one p − t/2 n; the top
sheet keeps the faces, the bottom sheet has them reversed, and every boundary edge of the sheet
(the margin) becomes a quad of two triangles joining the two. The result is closed and
consistently oriented with outward normals, and its volume is area × thickness to first order
(offsets along the surface's own normals keep the thickness perpendicular to it).

Offsets along normals can cross, and are kept from it by one rule: each offset keeps its reach
t/2 along the surface's normal, but its part along the leaf plane (which is what can carry one
vertex past another) is cut, and the part along the plane's normal grows to make up for it:
- where the leaf is narrower than the thickness (a thin tip, a deep sinus), a tilted normal would
  carry the margin's offsets across the outline and past each other: the in-plane part is at
  most MARGIN_SHIFT of the vertex's distance from the outline, so the margin's offsets are
  perpendicular to the plane, the walls stand on the outline itself and the sheets meet there
  rather than cross;
- where the surface bends tighter than the thickness, offsets along the normals would fold over
  (past the centre of curvature): the in-plane part moves by about t/2 · |k| per unit of length
  (k the larger principal curvature), which is kept under FOLD_GRADIENT, so each sheet stays a
  graph over the plane, one above the other.
Offsets straight along the plane's normal never cross (the sheets are graphs of z ± t/(2 cos θ)),
so the thickness itself is never narrowed. Where the mesh is coarse across a strongly curved
leaf, the offsets also reach t/2 along the facets' mean normal (the solid between the facets
would be thinner otherwise).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from leafstudio.assets.asset import MeshAsset, outline_distance, surface_normals
from leafstudio.assets.units import METRES, split_length, unit_metres
from leafstudio.core.carried import carried_normals, carried_vectors
from leafstudio.core.trianglemesh import vertex_normals
from leafstudio.errors import LeafError

if TYPE_CHECKING:
    from leafstudio.core.result import Result

MARGIN_SHIFT = 0.5  # an offset moves along the plane at most this fraction of its distance
CREASE_SHIFT = 0.9  # an offset moves at most this share of its vertex's distance toward a
# fold's midplane: the inner sheets of a fold about the midrib meet there, mitred (_crease)
MIN_COSINE = 0.2  # the margin's offsets grow by 1/cos(tilt), at most by 1/MIN_COSINE
FOLD_GRADIENT = 0.5  # the in-plane offset moves at most this much per unit of length
# a solid's thickness in leaf lengths: thinner, 32-bit floats (STL, 3MF) cannot part its two
# sheets (1e-9 wrote a solid that was not closed); thicker, it is no leaf (1e308mm wrote ±inf)
MIN_THICKNESS, MAX_THICKNESS = 1e-5, 10.0


def parse_thickness(text: str) -> tuple[float, str | None]:
    """'0.01' -> (0.01, None): a fraction of the leaf length; '0.4mm' -> (0.4, 'mm')."""
    found = split_length(text)
    if found is None:
        raise LeafError(
            f"--thickness must be a number (a fraction of the leaf length) or a length with its "
            f"unit ({', '.join(METRES)}), got {text!r}"
        )
    value, unit = found[0], found[1] or None
    if unit is not None:
        unit_metres(unit, "--thickness")
    if not value > 0:
        raise LeafError(f"--thickness must be above 0, got {text!r}")
    if unit is None and value >= 1:
        raise LeafError(f"--thickness without a unit is a fraction of the leaf length (< 1), got "
                        f"{text!r}")  # fmt: skip
    return value, unit


def thickness_in_mesh_units(
    text: str, length: float, metres_per_unit: float | None = None
) -> float:
    """The thickness `text` means (parse_thickness) in the mesh's units: a fraction times the
    leaf length, or a length converted from its unit: to metres over `metres_per_unit` when the
    leaf's real size is known (--length), else to millimetres, the unit a leaf's coordinates are
    then taken to be in (as scans and 3MF files are)."""
    value, unit = parse_thickness(text)
    if unit is None:
        thickness = value * length
    elif metres_per_unit is not None:
        thickness = value * METRES[unit] / metres_per_unit
    else:
        thickness = value * METRES[unit] * 1e3
    if not MIN_THICKNESS <= thickness / length <= MAX_THICKNESS:  # also inf and NaN
        raise LeafError(
            f"--thickness {text.strip()} is {thickness / length:.3g} of the leaf's length; a "
            f"solid needs from {MIN_THICKNESS:g} to {MAX_THICKNESS:g} of it"
        )
    return thickness


def boundary_edges(faces: np.ndarray) -> np.ndarray:
    """(e, 2) directed edges that belong to one face only, in that face's winding."""
    directed = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    key = np.sort(directed, axis=1)
    base = int(faces.max(initial=0)) + 1
    _, inverse, counts = np.unique(
        key[:, 0] * base + key[:, 1], return_inverse=True, return_counts=True
    )
    return directed[counts[inverse] == 1]


def margin_flags(asset: MeshAsset) -> np.ndarray:
    """(n,) bool: the asset's vertices on the leaf's margin, where the surface takes its limits
    from inside (surface.HeightSurface.derivatives): its `margin` when known (a leaf's,
    Result.on_outline), else every boundary edge's vertices (a bare mesh's). A trimmed scan's
    holes are edges of the sheet but no margin: sugar beet pot1_7's 185 hole vertices were
    given the margin's normals (its taper's g = 0 where g is well inside)."""
    if asset.margin is not None:
        return np.asarray(asset.margin, dtype=bool)
    flags = np.zeros(asset.n_points, dtype=bool)
    flags[np.unique(boundary_edges(asset.faces))] = True
    return flags


def margin_distance(asset: MeshAsset) -> np.ndarray:
    """(n,) each vertex's distance in the leaf plane from the outline (the asset's, else its
    boundary vertices); 0 on the boundary, a hole's edge too: the walls stand on every edge of
    the sheet (module docstring), a hole's as the outline's."""
    from scipy.spatial import cKDTree

    edges = boundary_edges(asset.faces)
    rim = np.unique(edges)
    if asset.outline is not None:
        distance = outline_distance(asset.outline, asset.plane_xy)
        distance = np.minimum(distance, _hole_distance(asset, edges))
    elif len(rim):
        distance = cKDTree(asset.plane_xy[rim]).query(asset.plane_xy)[0]
    else:
        return np.full(asset.n_points, np.inf)
    distance[rim] = 0.0
    return distance


def _hole_distance(asset: MeshAsset, edges: np.ndarray) -> np.ndarray:
    """(n,) each vertex's distance in the leaf plane from the sheet's edges that are not on the
    margin (a trimmed scan's holes), inf without any. Measured from the outline alone, a
    vertex one cell from a hole's wall could move sideways half its distance to the far margin
    and through the wall (sugar beet pot1_7: 321 vertices allowed over 1.5 times their room)."""
    import shapely

    margin = margin_flags(asset)
    holes = edges[~(margin[edges[:, 0]] & margin[edges[:, 1]])]
    if not len(holes):
        return np.full(asset.n_points, np.inf)
    walls = shapely.multilinestrings(asset.plane_xy[holes])
    return shapely.distance(walls, shapely.points(asset.plane_xy))


def offsets(asset: MeshAsset, thickness: float) -> np.ndarray:
    """(n, 3) half-thickness offsets: t/2 across the surface, their part along the leaf plane cut
    near the outline and where the surface bends tightly (module docstring)."""
    half = np.full(asset.n_points, float(thickness) / 2)
    if asset.plane_normal is None or asset.plane_xy is None:
        return half[:, None] * asset.normals
    plane = asset.plane_normal
    up = asset.normals @ plane
    across = asset.normals - up[:, None] * plane
    shift = half * np.linalg.norm(across, axis=1)  # how far the offset moves along the plane
    allowed = MARGIN_SHIFT * margin_distance(asset)
    keep = np.where(shift > allowed, allowed / np.where(shift > 0, shift, 1), 1.0)
    data = asset.point_data
    if "k1" in data and "k2" in data:
        gradient = half * np.maximum(np.abs(data["k1"]), np.abs(data["k2"]))
        fold = FOLD_GRADIENT / np.where(gradient > 0, gradient, 1)
        keep = np.minimum(keep, np.where(gradient > FOLD_GRADIENT, fold, 1.0))
    # the part along the plane's normal grows so that the offset still reaches t/2 along the
    # surface's normal: o·n = keep sin²θ t/2 + β cos θ t/2 = t/2
    beta = (1 - keep * (1 - up**2)) / np.maximum(up, MIN_COSINE)
    in_plane = (half * keep)[:, None] * across
    vertical = half * beta
    # and along the facets' mean normal f too: in_plane·f + g·vertical·(N·f) >= t/2
    facets = vertex_normals(asset.points, asset.faces)
    # on the normals' side, however the faces wind: a scan's flat blade (bent_offsets) winds
    # against its plane's normal, and its offsets took the gain's cap, 1/MIN_COSINE (sugar beet
    # pot1_7's solid was 4.98 times as thick as asked)
    if np.einsum("ij,ij->", facets, asset.normals) < 0:  # as a whole: a thin facet may
        facets = -facets  # disagree with its corners' normals where the blade is steep
    lift = np.maximum(vertical * (facets @ plane), 1e-300)
    reach = half - np.einsum("ij,ij->i", in_plane, facets)
    gain = np.clip(reach / lift, 1.0, 1 / MIN_COSINE)
    return in_plane + (vertical * gain)[:, None] * plane


def _outward(
    points: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    normals: np.ndarray,
    plane: np.ndarray | None = None,
) -> np.ndarray:
    """(n, 3) unit outward directions at the boundary vertices (0 elsewhere): each boundary edge
    a -> b (counter-clockwise seen from the normals' side) points out along (b − a) × n; along
    the leaf plane when it is known (the walls stand on the outline)."""
    edge = np.cross(points[b] - points[a], (normals[a] + normals[b]) / 2)
    out = np.zeros_like(points)
    np.add.at(out, a, edge)
    np.add.at(out, b, edge)
    if plane is not None:
        out -= (out @ plane)[:, None] * plane
    length = np.linalg.norm(out, axis=1, keepdims=True)
    return np.where(length > 0, out / np.where(length > 0, length, 1), 0.0)


def pinches_split(asset: MeshAsset) -> MeshAsset:
    """The sheet with each pinched vertex (two fans of faces touching at one margin vertex, as
    ball pivoting leaves) made one vertex per fan: each fan then gets its own wall edge, and the
    solid stays manifold there."""
    rim = boundary_edges(asset.faces)
    pinched = np.flatnonzero(np.bincount(rim[:, 0], minlength=asset.n_points) > 1)
    if not len(pinched):
        return asset
    faces = asset.faces.copy()
    copies: list[int] = []
    for vertex in pinched:
        around = np.flatnonzero((faces == vertex).any(axis=1))
        fans = _fans(faces[around], vertex)
        for fan in fans[1:]:
            rows = around[fan]
            faces[rows] = np.where(faces[rows] == vertex, asset.n_points + len(copies), faces[rows])
            copies.append(int(vertex))
    take = np.concatenate([np.arange(asset.n_points), copies])

    def grown(values: np.ndarray | None) -> np.ndarray | None:
        return None if values is None else np.asarray(values)[take]

    return asset.with_(
        points=asset.points[take],
        faces=faces,
        normals=asset.normals[take],
        uv=asset.uv[take],
        point_data={k: v[take] for k, v in asset.point_data.items()},
        plane_xy=grown(asset.plane_xy),
        margin=grown(asset.margin),
    )


def _fans(faces: np.ndarray, vertex: int) -> list[np.ndarray]:
    """The (k, 3) faces around `vertex` grouped into fans (faces joined by an edge at it), as
    index arrays."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    others = [set(face) - {vertex} for face in faces.tolist()]
    rows, cols = [], []
    for i in range(len(faces)):
        for j in range(i + 1, len(faces)):
            if others[i] & others[j]:
                rows.append(i)
                cols.append(j)
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(len(faces), len(faces)))
    count, labels = connected_components(graph, directed=False)
    return [np.flatnonzero(labels == k) for k in range(count)]


def bent_offsets(result: Result, asset: MeshAsset, thickness: float = 0.0) -> np.ndarray:
    """(n, 3) half-thickness offsets per unit of thickness at the vertices of a bent leaf's
    sheet (`asset`, of `result`'s bent mesh), or (2, n, 3) its top's and bottom's apart with a
    fold's crease (`_crease`): `offsets` on the flat blade, where the leaf is a
    height field over its plane and the rules above hold, carried by the bend (its Jacobian)
    and lengthened to reach as far along the bent surface's normal as along the flat one's.
    Offsets along the bent normals crossed each other inside a fold's crease and brought a
    cordate blade's basal lobes, folded 60°, through each other (507 crossing faces); the
    fold carries the flat blade's upright offsets upright, as a height field's solid. A fold
    about the midrib's hinge turns them, and they keep off its midplane for a solid
    `thickness` thick (`_crease`)."""
    bend = result.leaf.bend
    if asset.plane_xy is not None and "height" in asset.point_data:  # leaf_asset's: kept flat
        xy, height = asset.plane_xy, asset.point_data["height"]
    else:
        xy, height = result.on_blade(asset.points)
    flat_points = result.frame.to_world(xy, height)
    normals = surface_normals(result, xy, margin_flags(asset))
    flat = asset.with_(points=flat_points, normals=normals, plane_normal=result.frame.normal,
                       plane_xy=xy, outline=result.polygon)  # fmt: skip
    offset = offsets(flat, 1.0)
    bent = carried_vectors(bend, flat_points, offset)
    bent_normals = carried_normals(bend, flat_points, normals)
    wanted = np.einsum("ij,ij->i", offset, normals)
    reach = np.einsum("ij,ij->i", bent, bent_normals)
    gain = np.clip(wanted / np.where(reach > 0, reach, np.inf), 1.0, 1 / MIN_COSINE)
    bent = bent * gain[:, None]
    # what the gain's cap leaves short is made up along the bent normal: a rolled blade's
    # fold lifts heights straight up (hinge_fold.py, w = 0), and where the rolled tube stands
    # steeper than the cap's 78° (or past upright) the carried offsets barely left the sheet
    # (ovate folded 75° and rolled 1: 18% of vertices short, curled and twisted too 39% and
    # the solid 0.849 of area x T)
    short = wanted - np.einsum("ij,ij->i", bent, bent_normals)
    bent = bent + np.maximum(short, 0.0)[:, None] * bent_normals
    crease = _crease(bend, flat_points, thickness)
    if crease is None:
        return bent
    across, most = crease  # each side's move toward the midplane held (`_crease`)
    part = np.einsum("ij,ij->i", bent, across)
    top = bent + (np.maximum(part, -most) - part)[:, None] * across
    bottom = bent + (np.minimum(part, most) - part)[:, None] * across
    on_crease = most < 1e-6  # its vertices on the midplane, to round-off
    return _outer_corner(asset, np.stack([top, bottom]), bent_normals, on_crease)


def _crease(
    bend, flat_points: np.ndarray, thickness: float
) -> tuple[np.ndarray, np.ndarray] | None:
    """(n, 3) the unit vectors across a fold's midplane at the (n, 3) flat points, pointing
    away from it on each vertex's side, and (n,) how far an offset (per unit of `thickness`)
    may move toward it: CREASE_SHIFT of its vertex's distance from the midplane
    (`bend.crease_side`, a pose's), as the margin's are held off the outline; None without a
    fold or a thickness. A fold that turns each half rigidly about the midrib
    (core/hinge_fold.py) turns its offsets too, and the two halves' inner sheets crossed within
    T / (2 sin(opening / 2)) of the crease (a hastate blade folded 75°, 626 crossing faces).
    Held so, they meet there as a mitre. Only the side moving toward the midplane is held
    (`bent_offsets` gives each side its own offset): held on both, the outer sheets were drawn
    in too (ovate folded 75° and curled 1: 0.957 of area x T, 0.980 held on the inner side,
    1.001 with the outer corner made sharp, `_outer_corner`). Lengthened along the midplane to
    make up for the mitre, the held offsets folded the inner sheets over (609 faces)."""
    side = getattr(bend, "crease_side", None)
    crease = None if side is None or not thickness > 0 else side(flat_points)
    if crease is None:
        return None
    distance, across = crease
    toward = np.where(distance < 0, -1.0, 1.0)[:, None] * across  # away from the midplane
    return toward, CREASE_SHIFT * np.abs(distance) / thickness


def _outer_corner(
    asset: MeshAsset, sides: np.ndarray, normals: np.ndarray, near: np.ndarray
) -> np.ndarray:
    """The (2, n, 3) top and bottom offsets `sides` (per unit of thickness) with the `near`
    vertices' outer side (the convex one: their faces bend away from it) lengthened along their
    (n, 3) `normals` to reach 1/2 along every face around them. A fold's crease is a sharp V:
    one normal there cut its outer corner off, and with the inner corner mitred (`_crease`)
    that chamfer is what a steep fold's solid lacked (`_crease` for the figures). Only the
    crease's own vertices (the mesh is cut along it, bent_mesh._crease_cuts): grown on every
    vertex within T / CREASE_SHIFT of the midplane, ovate folded 75° overshot to 1.016 of area
    x T and its solid crossed itself (577 face pairs)."""
    faces, points = asset.faces, asset.points
    a, b, c = (points[faces[:, i]] for i in range(3))
    facet = np.cross(b - a, c - a)
    facet /= np.maximum(np.linalg.norm(facet, axis=1, keepdims=True), 1e-300)
    corner = faces.ravel()
    if np.einsum("ij,ij->", np.repeat(facet, 3, axis=0), normals[corner]) < 0:
        facet = -facet  # on the normals' side, however the faces wind (`offsets`)
    facets = np.repeat(facet, 3, axis=0)
    # which side is convex: the faces' centres stand off a vertex toward its concave side
    rel = np.repeat((a + b + c) / 3, 3, axis=0) - points[corner]
    bow = np.zeros(len(points))
    np.add.at(bow, corner, np.einsum("ij,ij->i", rel, normals[corner]))
    outer = np.where(bow > 0, 1, 0)  # 0: the top (+ normal) is convex, 1: the bottom
    offset = sides[outer, np.arange(len(points))]
    need = (0.5 - np.einsum("ij,ij->i", offset[corner], facets)) / np.maximum(
        np.einsum("ij,ij->i", normals[corner], facets), MIN_COSINE
    )
    grow = np.zeros(len(points))
    np.maximum.at(grow, corner, need)
    grow = np.where(near, np.clip(grow, 0.0, 0.5 / MIN_COSINE), 0.0)
    sides = sides.copy()
    sides[outer, np.arange(len(points))] += grow[:, None] * normals
    return sides


def thicken(
    asset: MeshAsset,
    thickness: float,
    along: Callable[[MeshAsset], np.ndarray] | None = None,
) -> MeshAsset:
    """The closed solid of an open sheet (see the module docstring); `thickness` in the mesh's
    units; `along` gives the offsets per unit of thickness instead of `offsets` (a bent leaf's:
    `bent_offsets`)."""
    if not thickness > 0:
        raise LeafError(f"the thickness must be above 0, got {thickness}")
    if asset.solid:
        return asset
    asset = pinches_split(asset)
    n = asset.n_points
    offset = offsets(asset, thickness) if along is None else thickness * along(asset)
    top, bottom = (offset, offset) if offset.ndim == 2 else offset
    points = np.vstack([asset.points + top, asset.points - bottom])
    a, b = boundary_edges(asset.faces).T
    walls = np.vstack(
        [np.column_stack([b, a, a + n]), np.column_stack([b, a + n, b + n])]
    )  # the sheet's edge a -> b is walked b -> a here, so the wall agrees with the top
    faces = np.vstack([asset.faces, asset.faces[:, ::-1] + n, walls])
    normals = np.vstack([asset.normals, -asset.normals])
    # the rim's vertices are shared by a sheet and the wall: their normals lean outward halfway
    # (a rounded edge to a renderer, rather than a wall shaded as if it faced up and down)
    out = _outward(asset.points, a, b, asset.normals, asset.plane_normal)
    rim = np.unique(np.concatenate([a, b]))
    for side in (0, n):
        bevel = normals[rim + side] + out[rim]
        normals[rim + side] = bevel / np.linalg.norm(bevel, axis=1, keepdims=True)
    return asset.with_(
        points=points,
        faces=faces,
        normals=normals,
        uv=np.vstack([asset.uv, asset.uv]),
        point_data={k: np.concatenate([v, v]) for k, v in asset.point_data.items()},
        margin=None if asset.margin is None else np.concatenate([asset.margin, asset.margin]),
        solid=True,
    )
