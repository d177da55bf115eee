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
import open3d as o3d
import shapely
import triangle
from shapely.geometry import LinearRing

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
    ring = LinearRing(polygon)
    pts = shapely.points(nodes)
    return shapely.distance(ring, pts) > INNER_CLEARANCE * spacing


def conforming_mesh(polygon: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Constrained Delaunay triangulation of the polygon with `nodes` inside it.

    Returns the (n, 2) vertices (the polygon's first, in order) and (m, 3) triangles.
    """
    n = len(polygon)
    segments = np.column_stack([np.arange(n), (np.arange(n) + 1) % n])
    vertices = np.vstack([polygon, nodes])
    # 'p': triangulate the planar straight-line graph and drop triangles outside it
    out = triangle.triangulate({"vertices": vertices, "segments": segments}, "pQ")
    if "triangles" not in out or len(out["triangles"]) == 0:
        raise LeafError("the leaf outline could not be triangulated")
    return out["vertices"], out["triangles"].astype(np.int64)


def ball_pivoting(
    points: np.ndarray, normals: np.ndarray, spacing: float, factor: float
) -> np.ndarray:
    """open3d ball pivoting over (n, 3) points with (n, 3) normals; returns (m, 3) triangles."""
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    cloud.normals = o3d.utility.Vector3dVector(normals)
    radii = o3d.utility.DoubleVector([r * spacing * factor for r in BPA_RADII])
    mesh = o3d.geometry.TriangleMesh.create_from_point_cloud_ball_pivoting(cloud, radii)
    triangles = np.asarray(mesh.triangles, dtype=np.int64)
    if len(triangles) == 0:
        raise LeafError("ball pivoting found no triangles; raise the radius factor")
    return triangles
