"""A mesh with what renderers need: closed-form normals, UVs, per-vertex scalars and textures.

Normals. The surface is the graph z(x) over the leaf plane (core/surface.py), so its upward unit
normal at a plane point is (−z_x, −z_y, 1) / √(1 + z_x² + z_y²), from the closed-form gradient
(on the margin, the limit from inside the leaf). The mesh lies in the input's coordinates, so the
plane normal is turned to the world by the frame: n = −z_x u − z_y v + N (u, v, N the frame's
axes). These are the surface's own normals, not averages of the triangles' (only their side is
the triangles': `on_faces_side`).

UVs. A vertex at plane point (x, y) gets

    s = (x − c_x) / S + 1/2,     t = (y − c_y) / S + 1/2,     S = (1 + 2·UV_PAD) · max(w, h)

with c the centre and w × h the size of the outline's bounding box in the plane: one factor for
both axes (no stretch), the leaf centred in [0, 1]² with a margin of UV_PAD · S on the longer
side. s runs along the leaf's length (the frame's u), t across it (v); t = 0 is the bottom row of
the texture image (the OBJ and trimesh convention; glTF's writer flips it). Seen from the normal's
side, the texture is the leaf as it lies: a photo of it maps back onto itself.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from leafstudio.core.bend import flat_leaf
from leafstudio.core.carried import carried_normals
from leafstudio.core.curvature import CURVATURE_ARRAYS
from leafstudio.core.evaluate import triangles_of
from leafstudio.core.plane import Frame, fit_frame
from leafstudio.core.trianglemesh import vertex_normals

if TYPE_CHECKING:
    from PIL import Image

    from leafstudio.core.pipeline import Result

UV_PAD = 1 / 64  # the margin around the leaf in UV space, as a fraction of the square
SCALARS = ("height", *CURVATURE_ARRAYS)  # the per-vertex scalars written where formats hold them
LOD_NAME = re.compile(r"_LOD\d+$")  # a level of detail's name: its leaf's, then _LOD<k>


@dataclass(frozen=True)
class UVMap:
    """Leaf-plane points to UVs by one scale factor (see the module docstring).

    Attributes
    ----------
    centre : (2,) float array
        The plane point mapped to (1/2, 1/2).
    size : float
        The plane length of the UV square's side.

    Examples
    --------
    >>> import numpy as np
    >>> uv = UVMap.around(np.array([[0.0, 0.0], [2.0, 1.0]]))
    >>> uv(np.array([[1.0, 0.5]])).tolist()  # the box's centre
    [[0.5, 0.5]]
    >>> uv.to_plane(uv(np.array([[2.0, 1.0]]))).tolist()
    [[2.0, 1.0]]
    """

    centre: np.ndarray  # (2,) plane point mapped to (1/2, 1/2)
    size: float  # plane length of the UV square's side, S

    @classmethod
    def around(cls, xy: np.ndarray) -> UVMap:
        """The map that centres the (n, 2) plane points' bounding box in [0, 1]²."""
        lo, hi = xy.min(axis=0), xy.max(axis=0)
        size = (1 + 2 * UV_PAD) * max(float(np.max(hi - lo)), 1e-12)
        return cls(centre=(lo + hi) / 2, size=size)

    def __call__(self, xy: np.ndarray) -> np.ndarray:
        """(n, 2) UVs of (n, 2) plane points."""
        return (np.asarray(xy, dtype=float) - self.centre) / self.size + 0.5

    def to_plane(self, uv: np.ndarray) -> np.ndarray:
        """(n, 2) plane points of (n, 2) UVs (the inverse map)."""
        return (np.asarray(uv, dtype=float) - 0.5) * self.size + self.centre

    def texel_plane_points(self, pixels: int) -> np.ndarray:
        """(pixels, pixels, 2) plane points at the centres of a square image's texels, row 0 at
        the top (t = 1)."""
        centres = (np.arange(pixels) + 0.5) / pixels
        s, t = np.meshgrid(centres, 1 - centres)
        return self.to_plane(np.stack([s, t], axis=-1).reshape(-1, 2)).reshape(pixels, pixels, 2)


@dataclass(frozen=True, eq=False)
class MeshAsset:
    """A triangle mesh ready to export.

    Attributes
    ----------
    points, faces : (n, 3) float and (m, 3) int arrays
        Faces wind counter-clockwise seen from the side the normals point to.
    normals : (n, 3) float array
        Unit vertex normals.
    uv : (n, 2) float array
        Texture coordinates in [0, 1]² (see the module docstring).
    point_data : dict of (n,) float arrays
        Height and curvatures, by the names in SCALARS.
    texture, normal_map : PIL images or None
        The base colour (RGBA, alpha 0 outside the leaf) and a tangent-space normal map.
    name : str
        The mesh's name in formats that keep one (glTF's node, mesh and material; OBJ's object
        and material); a level of detail's ends in `_LOD<k>`.
    solid : bool
        A closed solid (solid.py) rather than an open sheet.
    plane_normal, plane_u : (3,) float arrays or None
        The leaf plane's normal (on the normals' side) and its axis along s.
    plane_xy, outline : (n, 2) and (b, 2) float arrays or None
        The vertices, and the leaf's outline if known, in that plane.
    margin : (n,) bool array or None
        Which vertices lie on the leaf's margin, if known (a leaf's: Result.on_outline); a
        trimmed scan's holes are edges of the sheet but no margin (solid.margin_flags).

    Examples
    --------
    >>> import leafstudio as ls
    >>> from leafstudio.assets import leaf_asset
    >>> asset = leaf_asset(ls.reconstruct(ls.demo("nested"), ls.Params(k=3, grid=32)))
    >>> asset.points.shape, asset.faces.shape, asset.normals.shape, asset.uv.shape
    ((372, 3), (504, 3), (372, 3), (372, 2))
    >>> asset.with_(name="oak").name
    'oak'
    """

    points: np.ndarray
    faces: np.ndarray
    normals: np.ndarray
    uv: np.ndarray
    point_data: dict[str, np.ndarray] = field(default_factory=dict)
    texture: Image.Image | None = None
    normal_map: Image.Image | None = None
    name: str = "leaf"
    solid: bool = False  # a closed solid (see solid.py) rather than an open sheet
    plane_normal: np.ndarray | None = None  # (3,) the leaf plane's normal, on the normals' side
    plane_xy: np.ndarray | None = None  # (n, 2) the vertices in the leaf plane
    outline: np.ndarray | None = None  # (b, 2) the leaf's outline in that plane, if known
    plane_u: np.ndarray | None = None  # (3,) the leaf plane's axis along s (the tangents' way)
    margin: np.ndarray | None = None  # (n,) bool: the vertices on the leaf's margin, if known

    @property
    def material_name(self) -> str:
        """The name of its material: one for every level of detail."""
        return LOD_NAME.sub("", self.name) or "leaf"

    def tangents(self) -> np.ndarray | None:
        """(n, 4) glTF tangents: the plane's s axis in each vertex's tangent plane, and w such
        that the bitangent cross(n, t)·w runs along t (+y of the normal map), or None."""
        if self.plane_u is None or self.plane_normal is None:  # a bent leaf: from its UVs
            return uv_tangents(self.points, self.faces, self.uv, self.normals)
        u, n = self.plane_u, self.normals
        tangent = u - (n @ u)[:, None] * n
        tangent /= np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-300)
        along_t = np.cross(self.plane_normal, u)
        w = np.where(np.cross(n, tangent) @ along_t >= 0, 1.0, -1.0)
        return np.column_stack([tangent, w])

    @property
    def n_points(self) -> int:
        return len(self.points)

    def with_(self, **changes: Any) -> MeshAsset:
        return replace(self, **changes)


@dataclass(frozen=True)
class LeafPlane:
    """What the textures need of the leaf: its frame, UV map, outline and veins in the plane."""

    frame: Frame
    uvmap: UVMap
    polygon: np.ndarray  # (b, 2) counter-clockwise outline
    veins: list[np.ndarray]  # (m_i, 2) per vein
    length: float


def uv_tangents(
    points: np.ndarray, faces: np.ndarray, uv: np.ndarray, normals: np.ndarray
) -> np.ndarray:
    """(n, 4) glTF tangents from the UVs (Lengyel's per-face ∂p/∂s and ∂p/∂t, summed at the
    vertices, made perpendicular to the normal; w as `MeshAsset.tangents`): a bent leaf's, whose
    s axis turns with its curl, so no one plane's u is it (without them the Khronos validator
    warns that the normal map's tangent space is left to each viewer)."""
    corners = [points[faces[:, i]] for i in range(3)]
    st = [uv[faces[:, i]] for i in range(3)]
    e1, e2 = corners[1] - corners[0], corners[2] - corners[0]
    d1, d2 = st[1] - st[0], st[2] - st[0]
    det = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    inverse = np.divide(1.0, det, out=np.zeros_like(det), where=np.abs(det) > 1e-300)[:, None]
    along_s = (e1 * d2[:, 1:] - e2 * d1[:, 1:]) * inverse
    along_t = (e2 * d1[:, :1] - e1 * d2[:, :1]) * inverse
    s_sum, t_sum = np.zeros_like(points), np.zeros_like(points)
    for i in range(3):
        np.add.at(s_sum, faces[:, i], along_s)
        np.add.at(t_sum, faces[:, i], along_t)
    tangent = s_sum - np.einsum("ij,ij->i", s_sum, normals)[:, None] * normals
    tangent /= np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-300)
    w = np.where(np.einsum("ij,ij->i", np.cross(normals, tangent), t_sum) >= 0, 1.0, -1.0)
    return np.column_stack([tangent, w])


def surface_normals(result: Result, xy: np.ndarray, margin: np.ndarray) -> np.ndarray:
    """(n, 3) world unit normals of the result's height surface at (n, 2) plane points, in closed
    form (see the module docstring); (n,) bool `margin` flags points on the leaf's edge."""
    grad = result.surface.derivatives(xy, margin)[1]
    frame = result.frame
    normals = np.outer(np.ones(len(xy)), frame.normal)
    normals -= grad[:, :1] * frame.u + grad[:, 1:] * frame.v
    return normals / np.linalg.norm(normals, axis=1, keepdims=True)


def mesh_normals(
    result: Result, xy: np.ndarray, height: np.ndarray, margin: np.ndarray
) -> np.ndarray:
    """(n, 3) unit normals of the result's mesh at its points on the flat blade, (n, 2) `xy` and
    (n,) `height` (Result.on_blade): the surface's (`surface_normals`), carried by the leaf's
    bend when it has one (carried.carried_normals: the flat ones were off by a fold's angle)."""
    normals = surface_normals(result, xy, margin)
    bend = result.leaf.bend
    if bend is not None:
        normals = carried_normals(bend, result.frame.to_world(xy, height), normals)
    return normals


def oriented(faces: np.ndarray, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """The faces wound consistently (each edge walked once each way) and, as a whole, toward the
    side their vertex normals point to.

    Not face by face: where the surface is steep (a blade folded 60 degrees and more) a thin
    facet's own normal can disagree with its corners' closed-form normals, and turning such a
    face alone would break the winding (and a solid made of it would be inside out there).
    """
    faces = consistent(faces, points)
    a, b, c = (points[faces[:, i]] for i in range(3))
    facing = np.einsum("ij,ij->i", np.cross(b - a, c - a), normals[faces].sum(axis=1))
    return faces if facing.sum() >= 0 else faces[:, ::-1].copy()


def on_faces_side(points: np.ndarray, faces: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """(n, 3) the unit `normals`, each turned to the side its (m, 3) `faces` (as `oriented`
    winds them) turn to: the area-weighted mean of their normals.

    A bend carries the surface's normal to one side of the sheet (carried.carried_normals), but
    where a scan's sheet curls tighter than the surface stands off it, w · κ > 1, the bent mesh
    is turned inside out in a narrow pleat, its faces against that side: soybean pot1_1's
    curled margins, the sheet's radius 0.4% of its size and the offsets 0.8% there (median),
    53 of 9,715 vertices' normals against their faces, shaded dark. Turned, every normal shades
    the faces it belongs to; a vertex whose normal agrees, all of them on every leaf that has
    no pleat, keeps it."""
    facing = np.einsum("ij,ij->i", vertex_normals(points, faces), normals)
    used = np.bincount(faces.ravel(), minlength=len(points)) > 0  # a vertex of no face: kept
    return np.where(used & (facing < 0), -1.0, 1.0)[:, None] * normals


def consistent(faces: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The faces with a consistent winding: as they are when no directed edge repeats (the
    meshers' own meshes), else through trimesh's repair (ball pivoting's may mix both ways)."""
    directed = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2).astype(np.int64)
    key = directed[:, 0] * (int(faces.max(initial=0)) + 1) + directed[:, 1]  # an int an edge:
    if len(np.unique(key)) == len(key):  # unique rows (axis=0) took 2-5 times as long
        return faces
    import trimesh

    mesh = trimesh.Trimesh(points, faces, process=False, validate=False)
    trimesh.repair.fix_winding(mesh)
    return np.asarray(mesh.faces, dtype=faces.dtype)


def leaf_plane(result: Result) -> LeafPlane:
    """The result's frame, UV map, outline and veins in the plane."""
    veins = [result.frame.to_plane(v)[0] for v in flat_leaf(result.leaf).veins]  # seams kept
    return LeafPlane(
        frame=result.frame,
        uvmap=UVMap.around(result.polygon),
        polygon=result.polygon,
        veins=veins,
        length=result.length,
    )


def leaf_uvs(result: Result, xy: np.ndarray | None = None) -> np.ndarray:
    """(n, 2) UVs of the result's mesh vertices (or of (n, 2) plane points `xy`): the map every
    export writes (module docstring), also the app's."""
    if xy is None:
        xy = result.mesh_on_blade()[0]
    return UVMap.around(result.polygon)(xy)


def leaf_asset(result: Result) -> MeshAsset:
    """The result's mesh with closed-form normals, UVs and its scalars (no texture yet).

    Parameters
    ----------
    result : Result
        A reconstruction; its surface gives the normals (from z's gradient, not the faces).

    Returns
    -------
    MeshAsset
        (n, 3) points, (m, 3) faces, (n, 3) unit normals, (n, 2) UVs in [0, 1]², and the
        point data height, mean_curvature, gaussian_curvature, k1, k2.

    Examples
    --------
    >>> import leafstudio as ls
    >>> asset = leaf_asset(ls.reconstruct(ls.demo("nested"), ls.Params(k=3, grid=32)))
    >>> sorted(asset.point_data)
    ['gaussian_curvature', 'height', 'k1', 'k2', 'mean_curvature']
    >>> bool(0 < asset.uv.min() and asset.uv.max() < 1)
    True
    """
    mesh = result.triangle_mesh
    points = np.asarray(mesh.points, dtype=float)
    margin = result.on_outline()
    xy, height = result.mesh_on_blade()
    normals = mesh_normals(result, xy, height, margin)
    faces = oriented(triangles_of(mesh).astype(np.int64), points, normals)
    normals = on_faces_side(points, faces, normals)
    data = {k: np.asarray(mesh.point_data[k], float) for k in SCALARS if k in mesh.point_data}
    uv = leaf_uvs(result, xy)
    if result.leaf.bend is not None:  # no one plane: tangents from the UVs (the plane's u did
        # not follow a curl), a solid's offsets carried (solid.bent_offsets)
        return MeshAsset(points, faces, normals, uv, data, plane_xy=xy, outline=result.polygon,
                         margin=margin)  # fmt: skip
    return MeshAsset(points, faces, normals, uv, data, plane_normal=result.frame.normal,
                     plane_xy=xy, outline=result.polygon, plane_u=result.frame.u,
                     margin=margin)  # fmt: skip


def outline_distance(polygon: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """(n,) distance in the plane from each point to the closed outline."""
    import shapely

    return shapely.distance(shapely.LinearRing(polygon), shapely.points(xy))


def mesh_asset(mesh: Any) -> MeshAsset:
    """Any triangle mesh (a TriangleMesh or pyvista.PolyData) without its surface: area-weighted
    vertex normals (toward the side its faces wind counter-clockwise) and UVs in its own PCA
    plane, by the same rule as a leaf's.

    Parameters
    ----------
    mesh : TriangleMesh or pyvista.PolyData
        (n, 3) points and triangles; its point arrays are kept.

    Returns
    -------
    MeshAsset
        Without texture, outline or tangents.

    Examples
    --------
    >>> import leafstudio as ls
    >>> result = ls.reconstruct(ls.demo("nested"), ls.Params(k=3, grid=32))
    >>> asset = mesh_asset(result.triangle_mesh)
    >>> asset.normals.shape, asset.uv.shape
    ((372, 3), (372, 2))
    """
    points = np.asarray(mesh.points, dtype=float)
    faces = triangles_of(mesh).astype(np.int64)
    normals = vertex_normals(points, faces)
    frame = fit_frame(points, np.zeros((0, 3)))
    xy = frame.to_plane(points)[0]
    data = {
        k: np.asarray(mesh.point_data[k], float)
        for k in SCALARS
        if k in mesh.point_data and np.asarray(mesh.point_data[k]).ndim == 1
    }
    up = frame.normal if normals.sum(axis=0) @ frame.normal >= 0 else -frame.normal
    return MeshAsset(points, faces, normals, UVMap.around(xy)(xy), data, plane_normal=up,
                     plane_xy=xy)  # fmt: skip
