"""Step 5: sample z on the grid, keep g >= 0, and mesh (section 3.5).

Two meshers, both returning plane coordinates, heights and triangles:

- ``conforming`` (ours, the default): a constrained Delaunay triangulation (Shewchuk's Triangle)
  of the leaf polygon (the outline's vertices: the boundary points, or a noisy boundary's smooth
  mean, outline.py), with the kept grid nodes inside, and points added where the band would hold
  long slivers (MAX_EDGE). Its outer edge is the margin itself, so thin tips are covered and
  nothing spills out.
- ``bpa`` (the paper's): open3d ball pivoting on the kept grid points lifted by z, plus the
  boundary points, with radii derived from the grid spacing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import triangle

from leafstudio._shared.extras import require
from leafstudio.core.buckets import kernel_array, near_edges
from leafstudio.core.grid import Grid
from leafstudio.core.jit import njit
from leafstudio.errors import LeafError

INNER_CLEARANCE = 0.4  # grid nodes nearer the margin than this many spacings are left out
BPA_RADII = (0.8, 1.2, 1.8, 2.7)  # ball radii, in grid spacings
MAX_EDGE = 3.0  # band triangles' edges (other than the outline's) longer than this many spacings
MAX_REFINEMENTS = 8  # ... are split at most this many times over


@dataclass(frozen=True)
class PlaneMesh:
    """A triangle mesh over the plane: (n, 2) xy, (n,) z, (m, 3) int triangles."""

    xy: np.ndarray
    z: np.ndarray
    triangles: np.ndarray


def inner_nodes(polygon: np.ndarray, nodes: np.ndarray, spacing: float) -> np.ndarray:
    """(n,) bool: grid nodes kept by the conforming mesher, at a clearance from the margin."""
    return ~near_edges(polygon, nodes, INNER_CLEARANCE * spacing)


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

    Where the band would hold triangles with an edge over MAX_EDGE spacings (a sinus or a lobe
    narrower than the grid, where no node is kept), the midpoints of those edges are added and
    the band triangulated again (at most MAX_REFINEMENTS times): no slivers across the blade.

    Returns
    -------
    xy : (b + e + n, 2) float array
        The polygon's vertices, the e points added in the band, then the kept grid nodes in grid
        order.
    triangles : (m, 3) int array
        Counter-clockwise.
    kept : (ny * nx,) bool array
        The kept grid nodes (a subset of `inside`).
    """
    ny, nx = grid.shape
    b = len(polygon)
    polygon = kernel_array(polygon)
    candidates = np.flatnonzero(inside & _grid_inside(polygon, grid.origin, grid.spacing, ny, nx))
    kept = np.zeros(ny * nx, dtype=bool)
    # rows of (n, 2) arrays picked by take and compress: numpy's fancy and boolean index took
    # ten times as long (this function 2.22 -> 2.01 ms on a flat ovate at grid 128, best of 60)
    near = inner_nodes(polygon, grid.points.take(candidates, axis=0), grid.spacing)
    kept[candidates[near]] = True
    cells = ~_crossed_cells(polygon, grid.origin, grid.spacing, ny, nx)
    vertex, grid_tris, band, n_band, outline, n_out = _split_cells(kept.reshape(ny, nx), cells, b)
    band, outline = band[:n_band], outline[:n_out]

    # the band: the polygon, the kept nodes not surrounded by full cells, the full cells' outline,
    # and points added where the band would have long triangles (_long_edge_midpoints)
    extra = np.zeros((0, 2))
    for refinement in range(MAX_REFINEMENTS + 1):
        e = len(extra)
        segments = np.vstack([_ring(b), np.where(outline >= b, outline + e, outline)])
        band_xy = np.vstack([polygon, extra, grid.points.take(band, axis=0)])
        xy_band, tris = _triangulate(band_xy, segments)
        if len(xy_band) != b + e + len(band):
            raise LeafError("the leaf outline crosses itself: it could not be triangulated")
        # drop the band triangulation's triangles inside the full cells (they are meshed above)
        tris = tris[_outside_cells(xy_band, tris, cells, grid.origin, grid.spacing)]
        if refinement == MAX_REFINEMENTS:
            break
        more = _long_edge_midpoints(xy_band, tris, b, MAX_EDGE * grid.spacing)
        if len(more) == 0:
            break
        extra = np.vstack([extra, more])
    to_mesh = np.concatenate([np.arange(b + len(extra)), vertex[band] + len(extra)])
    triangles = np.concatenate([to_mesh[tris], grid_tris + len(extra)])
    return np.concatenate([polygon, extra, grid.points.compress(kept, axis=0)]), triangles, kept


@njit(cache=True, nogil=True)
def _outside_cells(xy, triangles, cells, origin, spacing):
    """(t,) bool: the triangles whose centroid lies in no full cell (`cells`, (ny - 1, nx - 1)
    bool), the centroid's cell by truncation, as numpy's mean over the corners and astype
    took it (array expressions before: 0.10 -> 0.015 ms on a flat ovate at grid 128, best of
    40; the same triangles)."""
    n_rows, n_columns = cells.shape
    keep = np.empty(len(triangles), np.bool_)
    for t in range(len(triangles)):
        a, b, c = triangles[t, 0], triangles[t, 1], triangles[t, 2]
        cx = int(((xy[a, 0] + xy[b, 0] + xy[c, 0]) / 3 - origin[0]) / spacing)
        cy = int(((xy[a, 1] + xy[b, 1] + xy[c, 1]) / 3 - origin[1]) / spacing)
        inside = 0 <= cx < n_columns and 0 <= cy < n_rows
        keep[t] = not (inside and cells[cy, cx])
    return keep


def _long_edge_midpoints(
    xy: np.ndarray, triangles: np.ndarray, b: int, longest: float
) -> np.ndarray:
    """Midpoints of the triangles' edges longer than `longest`, and than 1.5 times the outline's
    edges at their ends, other than the outline's own (vertices 0..b-1 in a ring): where a sinus
    or a lobe leaves no grid node, Delaunay would join far points of a dense margin by slivers
    across the blade (a sparse margin's long edges are the input's and stay). The edges are
    found in a compiled loop (_long_edges: 0.35 -> 0.025 ms on a flat ovate at grid 128, best of
    40, array expressions before; the same midpoints)."""
    long = _long_edges(xy, triangles, b, longest)
    if len(long) == 0:
        return np.zeros((0, 2))
    long = np.unique(long, axis=0)  # each shared by two triangles
    return 0.5 * (xy[long[:, 0]] + xy[long[:, 1]])


@njit(cache=True, nogil=True)
def _long_edges(xy, triangles, b, longest):
    """(e, 2) the edges _long_edge_midpoints splits, each as (lower, higher) vertex index, in
    the triangles' order (once for each triangle that has it)."""
    reach = np.empty(b)  # 1.5 times each outline vertex's longer side
    for i in range(b):
        j = (i + 1) % b
        h = (i - 1 + b) % b
        ax, ay = xy[i, 0] - xy[j, 0], xy[i, 1] - xy[j, 1]
        bx, by = xy[h, 0] - xy[i, 0], xy[h, 1] - xy[i, 1]
        reach[i] = 1.5 * max(np.sqrt(ax * ax + ay * ay), np.sqrt(bx * bx + by * by))
    out = np.empty((3 * len(triangles), 2), np.int64)
    count = 0
    for t in range(len(triangles)):
        for k in range(3):
            p, q = triangles[t, k], triangles[t, (k + 1) % 3]
            low, high = min(p, q), max(p, q)
            step = high - low
            if high < b and (step == 1 or step == b - 1):
                continue  # the outline's own edge
            limit = longest
            if low < b:
                limit = max(limit, reach[low])
            if high < b:
                limit = max(limit, reach[high])
            dx, dy = xy[low, 0] - xy[high, 0], xy[low, 1] - xy[high, 1]
            if np.sqrt(dx * dx + dy * dy) > limit:
                out[count, 0], out[count, 1] = low, high
                count += 1
    return out[:count]


@njit(cache=True, nogil=True)
def _split_cells(kept, cells, b):
    """From the (ny, nx) kept nodes and the (ny - 1, nx - 1) cells no polygon edge crosses:

    - vertex (ny * nx,): each kept node's vertex index (b, b + 1, ... in grid order), else -1;
    - the two counter-clockwise triangles of each full cell (four kept corners, not crossed;
      `cells` is narrowed to those in place);
    - band: the kept nodes not surrounded by four full cells, in grid order (the first n_band);
    - outline (s, 2): the full cells' outline edges as indices into [polygon, band nodes] (the
      first n_out rows).

    No np.full and no slices: each compiles code of its own (the first run's compile).
    """
    ny, nx = kept.shape
    vertex = np.empty(ny * nx, np.int64)
    local = np.empty(ny * nx, np.int64)
    count = b
    for i in range(ny):
        for j in range(nx):
            local[i * nx + j] = -1
            vertex[i * nx + j] = -1
            if kept[i, j]:
                vertex[i * nx + j] = count
                count += 1
    n_full = 0
    for i in range(ny - 1):
        for j in range(nx - 1):
            full = cells[i, j] and kept[i, j] and kept[i, j + 1]
            cells[i, j] = full and kept[i + 1, j] and kept[i + 1, j + 1]
            n_full += cells[i, j]
    tris = np.empty((2 * n_full, 3), np.int64)
    t = 0
    for i in range(ny - 1):
        for j in range(nx - 1):
            if cells[i, j]:
                a = i * nx + j
                v0, v1, v2, v3 = vertex[a], vertex[a + 1], vertex[a + nx + 1], vertex[a + nx]
                tris[t, 0], tris[t, 1], tris[t, 2] = v0, v1, v2
                tris[t + 1, 0], tris[t + 1, 1], tris[t + 1, 2] = v0, v2, v3
                t += 2
    band = np.empty(count - b, np.int64)
    n_band = 0
    for i in range(ny):
        for j in range(nx):
            if not kept[i, j]:
                continue
            surrounded = (
                0 < i < ny - 1 and 0 < j < nx - 1 and cells[i - 1, j - 1] and cells[i - 1, j]
                and cells[i, j - 1] and cells[i, j]
            )  # fmt: skip
            if not surrounded:
                local[i * nx + j] = b + n_band
                band[n_band] = i * nx + j
                n_band += 1
    outline = np.empty((4 * n_full, 2), np.int64)  # each full cell has at most 4 outline edges
    n_out = 0
    for i in range(ny):
        for j in range(nx):
            if j < nx - 1:  # edge (i, j)-(i, j + 1) between cells (i - 1, j) and (i, j)
                below = i > 0 and cells[i - 1, j]
                above = i < ny - 1 and cells[i, j]
                if below != above:
                    outline[n_out, 0], outline[n_out, 1] = local[i * nx + j], local[i * nx + j + 1]
                    n_out += 1
            if i < ny - 1:  # edge (i, j)-(i + 1, j) between cells (i, j - 1) and (i, j)
                left = j > 0 and cells[i, j - 1]
                right = j < nx - 1 and cells[i, j]
                if left != right:
                    outline[n_out, 0], outline[n_out, 1] = local[i * nx + j], local[i * nx + nx + j]
                    n_out += 1
    return vertex, tris, band, n_band, outline, n_out


@njit(cache=True, nogil=True)
def _grid_inside(polygon, origin, spacing, ny, nx):
    """(ny * nx,) bool: grid nodes inside the closed polygon, by the crossing rule along each
    row (a node on an edge may go either way; the mesher's clearance drops those anyway)."""
    # node j of a row is inside when an odd number of the row's crossings lie right of it; a
    # crossing at x flips the parity of the nodes left of x (no sort: numba's compiles for
    # seconds at the first run)
    n = len(polygon)
    flips = np.zeros((ny, nx + 1), np.bool_)
    for e in range(n):
        ax, ay = polygon[e, 0], polygon[e, 1]
        bx, by = polygon[(e + 1) % n, 0], polygon[(e + 1) % n, 1]
        if ay == by:
            continue
        first = max(math.ceil((min(ay, by) - origin[1]) / spacing) - 1, 0)
        last = min(math.floor((max(ay, by) - origin[1]) / spacing) + 1, ny - 1)
        for i in range(first, last + 1):
            y = origin[1] + i * spacing
            if (ay > y) != (by > y):
                x = ax + (y - ay) * (bx - ax) / (by - ay)
                guess = (x - origin[0]) / spacing
                m = 0 if guess <= 0 else nx if guess >= nx else math.ceil(guess)
                while m > 0 and origin[0] + (m - 1) * spacing >= x:
                    m -= 1
                while m < nx and origin[0] + m * spacing < x:  # m: the nodes left of x
                    m += 1
                flips[i, m] = not flips[i, m]
    out = np.zeros(ny * nx, np.bool_)
    for i in range(ny):
        odd = False
        for j in range(nx - 1, -1, -1):
            odd = odd != flips[i, j + 1]
            out[i * nx + j] = odd
    return out


@njit(cache=True, nogil=True)
def _crossed_cells(polygon, origin, spacing, ny, nx):
    """(ny - 1, nx - 1) bool: grid cells an edge of the closed polygon may pass through.

    Points every half spacing along each edge, and the 3 x 3 cells around each: any cell an
    edge crosses holds a point within a quarter spacing of one of them, so none is missed.
    Compiled (0.19 -> 0.033 ms on a flat ovate at grid 128, best of 40; numpy's expressions of
    the same points before, the same cells)."""
    crossed = np.zeros((ny - 1, nx - 1), np.bool_)
    n = len(polygon)
    for e in range(n):
        ax, ay = polygon[e, 0], polygon[e, 1]
        dx, dy = polygon[(e + 1) % n, 0] - ax, polygon[(e + 1) % n, 1] - ay
        steps = max(math.ceil(np.sqrt(dx * dx + dy * dy) / (0.5 * spacing)), 1)
        for k in range(steps):
            t = k / steps
            cx = math.floor((ax + t * dx - origin[0]) / spacing)
            cy = math.floor((ay + t * dy - origin[1]) / spacing)
            for iy in range(max(cy - 1, 0), min(cy + 1, ny - 2) + 1):
                for ix in range(max(cx - 1, 0), min(cx + 1, nx - 2) + 1):
                    crossed[iy, ix] = True
    return crossed


def ball_pivoting(
    points: np.ndarray, normals: np.ndarray, spacing: float, factor: float
) -> np.ndarray:
    """open3d ball pivoting over (n, 3) points with (n, 3) normals; returns (m, 3) triangles."""
    o3d = require("open3d", "the ball-pivoting mesher (mesher bpa)")  # seconds and 250 MB

    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    cloud.normals = o3d.utility.Vector3dVector(normals)
    radii = o3d.utility.DoubleVector([r * spacing * factor for r in BPA_RADII])
    mesh = o3d.geometry.TriangleMesh.create_from_point_cloud_ball_pivoting(cloud, radii)
    triangles = np.asarray(mesh.triangles, dtype=np.int64)
    if len(triangles) == 0:
        raise LeafError("ball pivoting found no triangles; raise the radius factor")
    return triangles
