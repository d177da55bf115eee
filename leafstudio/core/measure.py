"""Leaf measurements from a reconstruction: sizes, areas, height, curvature and Table-1 distances.

Lengths are in the input's units. The main axis is the frame's u axis (the boundary's direction of
largest variance, see plane.py); width is measured across it, along v. Both meshers put the
outline first among the mesh's vertices, in order, so the margin's 3D length (the perimeter) is
that closed polyline's.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from leafstudio.core.analysis import surface_area, triangles_of
from leafstudio.core.curvature import CURVATURE_ARRAYS
from leafstudio.core.plane import Frame
from leafstudio.core.trianglemesh import MeshLike

#: (key, label) of the scalar measurements, in the order a table shows them
FIELDS = (
    ("area", "surface area (3D)"),
    ("projected_area", "projected area"),
    ("perimeter", "perimeter"),
    ("length", "length (main axis)"),
    ("width", "greatest width"),
    ("aspect_ratio", "aspect ratio (length / width)"),
    ("height", "greatest height"),
)


def vertex_areas(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(n,) area around each vertex: a third of the area of every triangle it belongs to."""
    a, b, c = (points[triangles[:, i]] for i in range(3))
    third = np.linalg.norm(np.cross(b - a, c - a), axis=1) / 6
    return np.bincount(triangles.ravel(), np.repeat(third, 3), minlength=len(points))


def curvature_summary(mesh: MeshLike) -> dict[str, dict[str, float]]:
    """min, max and area-weighted mean of each curvature array the mesh carries."""
    weights = vertex_areas(np.asarray(mesh.points), triangles_of(mesh))
    summary = {}
    for name in CURVATURE_ARRAYS:
        if name in mesh.point_data:
            values = np.asarray(mesh.point_data[name])
            summary[name] = {
                "min": float(values.min()),
                "max": float(values.max()),
                "mean": float(np.average(values, weights=weights)),
            }
    return summary


def shape_measurements(
    mesh: MeshLike, frame: Frame, polygon: np.ndarray, area: float | None = None
) -> dict[str, float]:
    """The FIELDS measurements of a leaf mesh.

    Parameters
    ----------
    mesh : TriangleMesh or pyvista.PolyData
        The leaf's triangle mesh in world coordinates, its first len(polygon) vertices the
        outline in order (as both meshers make it), with the point array "height".
    frame : Frame
        The leaf's plane frame (u: the main axis).
    polygon : (b, 2) float array
        The outline in plane coordinates.
    area : float, optional
        The mesh's surface area, when it is known already (analysis.mesh_facts has it).

    Returns
    -------
    dict
        The FIELDS keys as floats (aspect_ratio None for an outline of no width).
    """
    points = np.asarray(mesh.points)
    triangles = triangles_of(mesh)
    plane_xy, _ = frame.to_plane(points)
    outline = points[: len(polygon)]
    length = float(np.ptp(polygon[:, 0]))
    width = float(np.ptp(polygon[:, 1]))
    return {
        "area": surface_area(points, triangles) if area is None else area,
        "projected_area": surface_area(plane_xy, triangles),
        "perimeter": float(np.linalg.norm(outline - np.roll(outline, 1, axis=0), axis=1).sum()),
        "length": length,
        "width": width,
        "aspect_ratio": length / width if width > 0 else None,
        "height": float(np.ptp(np.asarray(mesh.point_data["height"]))),
    }


def leaf_measurements(result: Any) -> dict[str, Any]:
    """Every measurement of a Result: its shape (FIELDS), the K used, its curvature ranges and
    the Table-1 distances, all from `result.metrics` (which holds them; see Result.metrics).

    Returns
    -------
    dict
        The FIELDS keys, "k", "curvature" (curvature_summary) and "boundary"/"veins" (the
        Table-1 min, max and mean distances).
    """
    metrics = result.metrics
    return {
        **metrics["leaf"],
        "curvature": metrics["curvature"],
        "boundary": metrics["boundary"],
        "veins": metrics["veins"],
    }


def format_table(values: dict[str, Any]) -> str:
    """The measurements as an aligned two-column text table."""

    def number(x: float | None) -> str:
        return "-" if x is None else f"{x:.6g}"

    rows = [(label, number(values[key])) for key, label in FIELDS]
    rows.append(("K (Gaussians)", str(values["k"])))
    for name, stats in values["curvature"].items():
        rows.append(
            (
                f"{name.replace('_', ' ')} min / mean / max",
                " / ".join(number(stats[s]) for s in ("min", "mean", "max")),
            )
        )
    for part in ("boundary", "veins"):
        stats = values[part]
        rows.append(
            (
                f"distance {part} -> mesh min / mean / max",
                " / ".join(number(stats[s]) for s in ("min", "mean", "max")),
            )
        )
    width = max(len(label) for label, _ in rows)
    return "\n".join(f"{label:<{width}}  {value}" for label, value in rows)
