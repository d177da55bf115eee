"""Step 5: sample z on the grid, keep g >= 0, and mesh (section 3.5).

Two meshers, both returning plane coordinates, heights and triangles:

- ``conforming`` (ours, the default): a constrained Delaunay triangulation (Shewchuk's Triangle)
  of the leaf polygon, whose vertices are the boundary points on g ≈ 0, with the kept grid nodes
  inside. Its outer edge is the margin itself, so thin tips are covered and nothing spills out.
- ``bpa`` (the paper's): open3d ball pivoting on the kept grid points lifted by z, plus the
  boundary points, with radii derived from the grid spacing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import triangle
from numba import njit

from leafstudio.core.buckets import bucket_points
from leafstudio.core.grid import Grid
from leafstudio.core.outline import contains
from leafstudio.errors import LeafError

INNER_CLEARANCE = 0.4  # grid nodes nearer the margin than this many spacings are left out
BPA_RADII = (0.8, 1.2, 1.8, 2.7)  # ball radii, in grid spacings


@dataclass(frozen=True)
class PlaneMesh:
    """A triangle mesh over the plane: (n, 2) xy, (n,) z, (m, 3) int triangles."""

    xy: np.ndarray
    z: np.ndarray
    triangles: np.ndarray


def inner_nodes(polygon: np.ndarray, nodes: np.ndarray, spacing: float) -> np.ndarray:
    """(n,) bool: grid nodes kept by the conforming mesher, at a clearance from the margin."""
    nodes = np.ascontiguousarray(nodes, dtype=float)
    if len(nodes) == 0:
        return np.zeros(0, dtype=bool)
    b = bucket_points(nodes)
    near = np.zeros(len(nodes), dtype=bool)
    polygon = np.ascontiguousarray(polygon, dtype=float)
    _mark_near_edges(polygon, nodes, INNER_CLEARANCE * spacing, b.lo, b.size, b.nx, b.ny,
                     b.starts, b.order, near)  # fmt: skip
    return ~near


@njit(cache=True)
def _mark_near_edges(polygon, xy, radius, lo, size, nx, ny, starts, order, near):
    """Set near[i] for the points within `radius` of an edge of the closed polygon."""
    n = len(polygon)
    for e in range(n):
        ax, ay = polygon[e, 0], polygon[e, 1]
        bx, by = polygon[(e + 1) % n, 0], polygon[(e + 1) % n, 1]
        ex, ey = bx - ax, by - ay
        length2 = ex * ex + ey * ey
        x0 = max(int(np.floor((min(ax, bx) - radius - lo[0]) / size)), 0)
        x1 = min(int(np.floor((max(ax, bx) + radius - lo[0]) / size)), nx - 1)
        y0 = max(int(np.floor((min(ay, by) - radius - lo[1]) / size)), 0)
        y1 = min(int(np.floor((max(ay, by) + radius - lo[1]) / size)), ny - 1)
        for cy in range(y0, y1 + 1):
            for cx in range(x0, x1 + 1):
                k = cy * nx + cx
                for j in range(starts[k], starts[k + 1]):
                    i = order[j]
                    px, py = xy[i, 0] - ax, xy[i, 1] - ay
                    t = (px * ex + py * ey) / length2 if length2 > 0 else 0.0
                    t = min(max(t, 0.0), 1.0)
                    if (px - t * ex) ** 2 + (py - t * ey) ** 2 <= radius * radius:
                        near[i] = True


def _triangulate(vertices: np.ndarray, segments: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Constrained Delaunay triangulation (Triangle, 'p': of the planar straight-line graph, with
    the triangles outside its outer segments dropped)."""
    out = triangle.triangulate({"vertices": vertices, "segments": segments}, "pQ")
    if "triangles" not in out or len(out["triangles"]) == 0:
        raise LeafError("the leaf outline could not be triangulated")
    return out["vertices"], out["triangles"].astype(np.int64)


def _ring(n: int) -> np.ndarray:
    """(n, 2) segments joining vertices 0..n-1 in a closed loop."""
    return np.column_stack([np.arange(n), (np.arange(n) + 1) % n])


def conforming_mesh(polygon: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Constrained Delaunay triangulation of the polygon with `nodes` inside it.

    Returns the (n, 2) vertices (the polygon's first, in order) and (m, 3) triangles.
    """
    return _triangulate(np.vstack([polygon, nodes]), _ring(len(polygon)))


def conforming_grid_mesh(
    polygon: np.ndarray, grid: Grid, inside: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The conforming mesh of the leaf over a grid, built in two parts.

    Same vertices as `conforming_mesh` of the kept nodes (grid nodes with g >= 0, inside the
    polygon, farther than INNER_CLEARANCE spacings from it), but only the band along the margin is
    triangulated by Triangle: every grid cell whose four corners are kept and which no edge of the
    polygon crosses is split into two triangles directly, and the constrained Delaunay
    triangulation fills the band between the margin and those cells, whose outline it takes as
    segments. Triangle's time grows with the number of points it gets, so this keeps the mesh
    linear in the grid's node count at a small constant.

    Parameters
    ----------
    polygon : (b, 2) float array
        The leaf outline, counter-clockwise.
    grid : Grid
    inside : (ny * nx,) bool array
        Grid nodes with g >= 0.

    Returns
    -------
    xy : (b + n, 2) float array
        The polygon's vertices, then the kept grid nodes in grid order.
    triangles : (m, 3) int array
        Counter-clockwise.
    kept : (ny * nx,) bool array
        The kept grid nodes (a subset of `inside`).
    """
    ny, nx = grid.shape
    b = len(polygon)
    candidates = np.flatnonzero(inside)
    nodes = grid.points[candidates]
    ok = inner_nodes(polygon, nodes, grid.spacing)
    ok[ok] = contains(polygon, nodes[ok])
    kept = np.zeros(ny * nx, dtype=bool)
    kept[candidates[ok]] = True
    vertex = np.full(ny * nx, -1, dtype=np.int64)
    vertex[kept] = b + np.arange(int(kept.sum()))

    k2 = kept.reshape(ny, nx)
    cells = k2[:-1, :-1] & k2[:-1, 1:] & k2[1:, :-1] & k2[1:, 1:]
    cells &= ~_crossed_cells(polygon, grid)
    # grid triangles of the full cells
    iy, ix = np.nonzero(cells)
    a = iy * nx + ix
    quads = vertex[np.column_stack([a, a + 1, a + nx + 1, a + nx])]
    grid_tris = np.vstack([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])

    # the band: the polygon, the kept nodes not surrounded by full cells, the full cells' outline
    padded = np.zeros((ny + 1, nx + 1), dtype=bool)
    padded[1:-1, 1:-1] = cells
    surrounded = padded[:-1, :-1] & padded[:-1, 1:] & padded[1:, :-1] & padded[1:, 1:]
    band = np.flatnonzero(kept & ~surrounded.ravel())
    horizontal = padded[:-1, 1:-1] != padded[1:, 1:-1]  # (ny, nx - 1): edge (i, j)-(i, j + 1)
    vertical = padded[1:-1, :-1] != padded[1:-1, 1:]  # (ny - 1, nx): edge (i, j)-(i + 1, j)
    hy, hx = np.nonzero(horizontal)
    vy, vx = np.nonzero(vertical)
    outline = np.vstack(
        [
            np.column_stack([hy * nx + hx, hy * nx + hx + 1]),
            np.column_stack([vy * nx + vx, (vy + 1) * nx + vx]),
        ]
    )
    local = np.full(ny * nx, -1, dtype=np.int64)
    local[band] = b + np.arange(len(band))
    segments = np.vstack([_ring(b), local[outline]])
    xy_band, tris = _triangulate(np.vstack([polygon, grid.points[band]]), segments)
    if len(xy_band) != b + len(band):
        raise LeafError("the leaf outline crosses itself: it could not be triangulated")
    # drop the band triangulation's triangles inside the full cells (they are meshed above)
    centroid = xy_band[tris].mean(axis=1)
    cx, cy = ((centroid - grid.origin) / grid.spacing).T.astype(np.int64)
    in_cells = (cx >= 0) & (cy >= 0) & (cx < nx - 1) & (cy < ny - 1)
    in_cells[in_cells] = cells[cy[in_cells], cx[in_cells]]
    to_mesh = np.concatenate([np.arange(b), vertex[band]])
    triangles = np.vstack([to_mesh[tris[~in_cells]], grid_tris])
    return np.vstack([polygon, grid.points[kept]]), triangles, kept


def _crossed_cells(polygon: np.ndarray, grid: Grid) -> np.ndarray:
    """(ny - 1, nx - 1) bool: grid cells an edge of the closed polygon may pass through.

    Points every half spacing along each edge, and the 3 x 3 cells around each: any cell an
    edge crosses holds a point within a quarter spacing of one of them, so none is missed."""
    ny, nx = grid.shape
    ends = np.roll(polygon, -1, axis=0)
    steps = np.maximum(np.ceil(np.linalg.norm(ends - polygon, axis=1) / (0.5 * grid.spacing)), 1)
    steps = steps.astype(np.int64)
    edge = np.repeat(np.arange(len(polygon)), steps)
    t = (np.arange(len(edge)) - np.repeat(np.cumsum(steps) - steps, steps)) / steps[edge]
    points = polygon[edge] + t[:, None] * (ends - polygon)[edge]
    cell = np.floor((points - grid.origin) / grid.spacing).astype(np.int64)
    crossed = np.zeros((ny + 1, nx + 1), dtype=bool)  # one cell of padding all round
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            cy = np.clip(cell[:, 1] + dy + 1, 0, ny)
            cx = np.clip(cell[:, 0] + dx + 1, 0, nx)
            crossed[cy, cx] = True
    return crossed[1:-1, 1:-1]


def ball_pivoting(
    points: np.ndarray, normals: np.ndarray, spacing: float, factor: float
) -> np.ndarray:
    """open3d ball pivoting over (n, 3) points with (n, 3) normals; returns (m, 3) triangles."""
    import open3d as o3d  # here, not at the top: it takes seconds and 250 MB to import

    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    cloud.normals = o3d.utility.Vector3dVector(normals)
    radii = o3d.utility.DoubleVector([r * spacing * factor for r in BPA_RADII])
    mesh = o3d.geometry.TriangleMesh.create_from_point_cloud_ball_pivoting(cloud, radii)
    triangles = np.asarray(mesh.triangles, dtype=np.int64)
    if len(triangles) == 0:
        raise LeafError("ball pivoting found no triangles; raise the radius factor")
    return triangles
