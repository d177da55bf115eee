"""Levels of detail: coarser meshes of the same leaf, each with half the triangles of the one
before, for engines that switch meshes with distance.

Each level is a quadric decimation of the full mesh (open3d, Garland and Heckbert's error
quadrics) to half, a quarter, ... of the full mesh's triangles, with the margin's edges weighted
heavily (BOUNDARY_WEIGHT) so that its vertices stay on the outline and the outline keeps its
shape. The levels' vertices are then given what the full mesh's have: for a Result, the
surface's closed-form normals and curvatures at their plane points, the margin's limits at
those on the margin (a boundary vertex is when the full mesh's nearest boundary vertex is: a
trimmed scan's holes are no margin), and the same UV map (one texture serves all levels).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from leafstudio._shared.extras import require
from leafstudio.assets.asset import (
    SCALARS,
    MeshAsset,
    UVMap,
    mesh_asset,
    mesh_normals,
    on_faces_side,
    oriented,
)
from leafstudio.assets.solid import boundary_edges, margin_flags
from leafstudio.core.curvature import surface_curvatures
from leafstudio.core.trianglemesh import TriangleMesh

if TYPE_CHECKING:
    from leafstudio.core.pipeline import Result

BOUNDARY_WEIGHT = 100.0
FEWEST_TRIANGLES = 8


def decimate(points: np.ndarray, faces: np.ndarray, triangles: int) -> tuple[np.ndarray, ...]:
    """(points, faces) decimated to about `triangles` triangles, the boundary kept."""
    o3d = require("open3d", "levels of detail (--lod)")

    mesh = o3d.geometry.TriangleMesh(
        o3d.utility.Vector3dVector(points), o3d.utility.Vector3iVector(faces)
    )
    out = mesh.simplify_quadric_decimation(triangles, boundary_weight=BOUNDARY_WEIGHT)
    out.remove_unreferenced_vertices()
    return np.asarray(out.vertices, float), np.asarray(out.triangles, np.int64)


def _level(asset: MeshAsset, result: Result | None, points: np.ndarray, faces: np.ndarray):
    if result is None:
        level = mesh_asset(TriangleMesh(points, faces))
        return level.with_(faces=oriented(level.faces, level.points, level.normals))
    xy, z = result.on_blade(points)
    margin = level_margin(asset, points, faces)
    normals = mesh_normals(result, xy, z, margin)
    data = {"height": z, **surface_curvatures(result.surface, xy, margin)}
    faces = oriented(faces, points, normals)
    return asset.with_(
        points=points,
        faces=faces,
        normals=on_faces_side(points, faces, normals),
        uv=UVMap.around(result.polygon)(xy),
        point_data={k: v for k, v in data.items() if k in SCALARS and k in asset.point_data},
        plane_xy=xy,
        margin=margin,
    )


def level_margin(asset: MeshAsset, points: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(n,) bool: which of a level's (n, 3) `points` (its (m, 3) `faces`) lie on the margin:
    its boundary vertices whose nearest boundary vertex of the full `asset` does (margin_flags;
    the decimation keeps the boundary's vertices on it). Every boundary vertex was taken for
    the margin, a trimmed scan's hole edges too."""
    from scipy.spatial import cKDTree

    flags = np.zeros(len(points), dtype=bool)
    rim, full = np.unique(boundary_edges(faces)), np.unique(boundary_edges(asset.faces))
    if len(rim) and len(full):
        nearest = cKDTree(asset.points[full]).query(points[rim])[1]
        flags[rim] = margin_flags(asset)[full[nearest]]
    return flags


def coarser_levels(asset: MeshAsset, result: Result | None, levels: int) -> list[MeshAsset]:
    """`levels` coarser versions of the asset (see the module docstring); fewer if the mesh runs
    out of triangles first."""
    out = []
    for level in range(1, levels + 1):
        target = len(asset.faces) // 2**level
        if target < FEWEST_TRIANGLES:
            break
        # from the full mesh each time: from the level before is quicker, but the margin's
        # vertices then drift off the outline level by level (4 times as far at level 3)
        points, faces = decimate(asset.points, asset.faces, target)
        out.append(_level(asset, result, points, faces))
    return out
