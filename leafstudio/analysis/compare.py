"""The paper's comparison (Fig. 10): screened Poisson reconstruction of the same input points.

Screened Poisson (Kazhdan & Hoppe 2013, open3d's implementation) fits an indicator function to
oriented points and extracts its level set. Given only a leaf's boundary and vein points it makes
a closed blob that runs far past the margin; the paper shows this spill, and `spill_area`
measures it: the part of a mesh's area whose projection onto the leaf plane lies outside the
leaf region.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np
import shapely

from leafstudio._shared.extras import LazyModule
from leafstudio.core.evaluate import table_metrics, triangles_of
from leafstudio.core.pipeline import Pipeline
from leafstudio.core.prepare.units import Units
from leafstudio.core.trianglemesh import MeshLike, TriangleMesh
from leafstudio.errors import LeafError
from leafstudio.model import Leaf, Params

o3d = LazyModule("open3d", "the screened Poisson comparison")  # an extra: leafstudio[open3d]

ToPlane = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]
POISSON_DEPTH = 8
NORMAL_NEIGHBOURS = 16


def poisson_surface(leaf: Leaf, normal: np.ndarray, depth: int = POISSON_DEPTH) -> TriangleMesh:
    """Screened Poisson surface of the leaf's boundary and vein points.

    Parameters
    ----------
    leaf : Leaf
    normal : (3,) float array
        The leaf plane's normal; the estimated point normals are turned to agree with it.
    depth : int, default: 8
        Octree depth (the paper's comparison uses open3d's default, 8).

    Returns
    -------
    TriangleMesh
        The triangle mesh, in the input's coordinates. One thread: open3d's default threading
        has crashed on small machines.
    """
    points = np.vstack([leaf.boundary, leaf.vein_points])
    # at about unit size: open3d's Poisson crashed (SIGSEGV) on leaves scaled by 1e-90 or 1e300
    # (fuzzing, issue 24)
    units = Units.exact(points)
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(units.to_unit(points)))
    cloud.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(NORMAL_NEIGHBOURS))
    cloud.orient_normals_to_align_with_direction(np.asarray(normal, dtype=float))
    mesh, _ = o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(
        cloud, depth=depth, n_threads=1
    )
    triangles = np.asarray(mesh.triangles, dtype=np.int64)
    if len(triangles) == 0:
        raise LeafError("screened Poisson made no surface from these points")
    return TriangleMesh(points=units.to_world(np.asarray(mesh.vertices)), regular_faces=triangles)


def spill_area(mesh: MeshLike, to_plane: ToPlane, polygon: np.ndarray) -> float:
    """Area of the mesh outside the leaf region.

    Each triangle counts with the fraction of its projection onto the plane (`to_plane`: (n, 3)
    points -> (n, 2) plane coordinates and heights, a Frame's; a bent leaf's lays them flat by
    its bend first) that lies outside the (b, 2) polygon (plane coordinates); triangles standing
    edge-on to the plane (no projected area) count whole when their centroid is outside. What
    Poisson closes over or under the blade (its underside; inside a rolled tube) projects inside
    the outline and is not counted.
    """
    triangles = triangles_of(mesh)
    if len(triangles) == 0:
        return 0.0
    points = np.asarray(mesh.points)
    a, b, c = (points[triangles[:, i]] for i in range(3))
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    xy, _ = to_plane(points)
    corners = xy[triangles]
    region = shapely.Polygon(polygon)
    shapes = shapely.polygons(np.concatenate([corners, corners[:, :1]], axis=1))
    projected = shapely.area(shapes)
    flat = projected <= 1e-12 * max(region.area, 1e-300)
    fraction = np.empty(len(triangles))
    solid = ~flat
    fraction[solid] = shapely.area(shapely.difference(shapes[solid], region)) / projected[solid]
    fraction[flat] = ~shapely.covers(region, shapely.points(corners[flat].mean(axis=1)))
    fraction[fraction < 1e-9] = 0.0  # shapely's rounding on triangles inside the edge
    return float(np.sum(area * np.clip(fraction, 0.0, 1.0)))


def compare(leaf: Leaf, params: Params | None = None) -> dict[str, Any]:
    """Our reconstruction and screened Poisson side by side on one leaf.

    Returns
    -------
    dict
        "ours" and "poisson", each with the Table-1 distances ("boundary", "veins"), the mesh's
        facts ("mesh"), "spill" (spill_area) and "seconds" (the wall time of the
        reconstruction; ours a steady run's, after one that loads the compiled kernels);
        "ours" also has "k", the K used (None: a flat blade fits no mixture); "meshes" holds
        both (TriangleMesh).
    """
    params = params or Params()
    Pipeline(leaf).run(params)  # a process's first run loads the compiled kernels: time the next
    start = time.perf_counter()
    pipeline = Pipeline(leaf)  # a bent leaf (a posed form) with its own bend, as reconstruct
    world = pipeline.run(params)
    ours_seconds = time.perf_counter() - start
    # at about unit size, the pipeline's own (an exact map): distances and areas of a leaf at
    # 1e150 overflow float64 squares, so both meshes are measured there and the figures mapped
    # back. (The leaf was mapped there without its bend, Units.leaf: a posed form's curves were
    # unfolded by a fit, or refused: ovate fold 45 twist 0.5 roll 0.5.)
    units, result = pipeline.units, world.unit if world.unit is not None else world
    leaf = units.leaf(pipeline.leaf)
    start = time.perf_counter()
    poisson = poisson_surface(leaf, result.frame.normal)
    poisson_seconds = time.perf_counter() - start

    def to_plane(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Unit-size points on the flat blade's plane: a bent leaf's laid flat by its bend."""
        if world.leaf.bend is None:
            return result.frame.to_plane(points)
        xy, height = world.on_blade(units.to_world(points))
        return xy / units.scale, height / units.scale

    def report(mesh: MeshLike, seconds: float) -> dict[str, Any]:
        table = table_metrics(mesh, leaf)
        scale = units.scale
        for part in ("boundary", "veins"):
            table[part] = {k: None if v is None else v * scale for k, v in table[part].items()}
        area = scale * scale  # not scale**2, which raises past 1e154 (inf: said by the caller)
        table["mesh"]["area"] *= area
        spill = spill_area(mesh, to_plane, result.polygon) * area
        return {**table, "spill": spill, "seconds": seconds}

    def in_world(mesh: TriangleMesh) -> TriangleMesh:
        return TriangleMesh(points=units.to_world(mesh.points), regular_faces=mesh.regular_faces)

    return {
        "ours": {**report(result.triangle_mesh, ours_seconds), "k": result.fitted_k},
        "poisson": report(poisson, poisson_seconds),
        "meshes": {"ours": in_world(result.triangle_mesh), "poisson": in_world(poisson)},
    }


def format_comparison(report: dict[str, Any]) -> str:
    """A compare() report as an aligned text table, one column per method."""
    rows = [
        ("boundary -> mesh mean", lambda r: r["boundary"]["mean"]),
        ("boundary -> mesh max", lambda r: r["boundary"]["max"]),
        ("veins -> mesh mean", lambda r: r["veins"]["mean"]),
        ("veins -> mesh max", lambda r: r["veins"]["max"]),
        ("surface area", lambda r: r["mesh"]["area"]),
        ("spill (area outside the leaf)", lambda r: r["spill"]),
        ("triangles", lambda r: r["mesh"]["triangles"]),
        ("time (s)", lambda r: r["seconds"]),
    ]

    def cell(value: float | None) -> str:
        return "-" if value is None else f"{value:.4g}"

    label_width = max(len(label) for label, _ in rows)
    k = report["ours"]["k"]
    ours = "ours (K unused)" if k is None else f"ours (K = {k})"
    width = max(14, len(ours))  # "ours (K unused)" is 15: at 14 it pushed Poisson's title out
    lines = [f"{'':<{label_width}}  {ours:>{width}}  {'Poisson':>14}"]
    for label, get in rows:
        lines.append(
            f"{label:<{label_width}}  {cell(get(report['ours'])):>{width}}  "
            f"{cell(get(report['poisson'])):>14}"
        )
    return "\n".join(lines)
