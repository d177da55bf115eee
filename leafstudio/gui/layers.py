"""What the viewport draws for a Result: named datasets with their styles, one list per layer.

Built on the worker thread (VTK data objects only, no rendering), so that the main thread only
hands finished datasets to the renderer. No Qt here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pyvista as pv

from leafstudio.core.pipeline import Result

# (key, label shown in the layer list, on by default)
LAYERS: tuple[tuple[str, str, bool], ...] = (
    ("mesh", "Mesh", True),
    ("points", "Input points", True),
    ("curves", "Boundary and vein curves", False),
    ("contour", "Zero contour of g", False),
    ("probability", "Probability map p(x)", False),
    ("samples", "GMM samples", False),
    ("em", "EM samples", False),
    ("scan", "Scan points", True),
    ("poisson", "Screened Poisson surface (beside ours)", False),
)
SIDE_LAYERS = frozenset({"scan", "poisson"})  # not built from a Result (see scans.py)
BOUNDARY_COLOR = "#303030"
VEIN_COLORS = ("#d62728", "#1f77b4", "#ff7f0e", "#9467bd", "#17becf", "#e377c2", "#8c564b")
SCALAR_BARS = {"mesh": "height", "probability": "p(x)"}
# what the mesh can be coloured by: point array -> (label, colour map)
MESH_COLORINGS = {
    "height": ("height", "viridis"),
    "mean_curvature": ("mean curvature", "coolwarm"),
    "gaussian_curvature": ("Gaussian curvature", "coolwarm"),
}
CURVATURE_PERCENTILE = 95  # curvature colours span ± this percentile of |value| (margins spike)
MAP_OFFSET = 0.003  # the probability map sits this fraction of the leaf length below the plane


@dataclass
class Piece:
    """One actor: a name unique in the scene, a dataset and its add_mesh keywords."""

    name: str
    data: pv.DataSet
    style: dict[str, Any] = field(default_factory=dict)
    ranges: dict[str, tuple[float, float]] = field(default_factory=dict)  # colour range per array


def vein_color(index: int) -> str:
    """The colour of vein `index` (0-based), in the 3D view and in the sketch editor alike."""
    return VEIN_COLORS[index % len(VEIN_COLORS)]


def _points(color: str, size: float) -> dict[str, Any]:
    return {"color": color, "point_size": size, "render_points_as_spheres": True}


def _polyline(points: np.ndarray, closed: bool) -> pv.PolyData:
    return pv.lines_from_points(np.vstack([points, points[:1]]) if closed else points)


def _color_ranges(mesh: pv.PolyData) -> dict[str, tuple[float, float]]:
    """Colour range of each array in MESH_COLORINGS the mesh has: height from its least to its
    greatest value, curvature symmetric about 0 (so that 0 is the middle colour)."""
    ranges = {}
    for name in MESH_COLORINGS:
        if name not in mesh.point_data:
            continue
        values = np.asarray(mesh.point_data[name], dtype=float)
        values = values[np.isfinite(values)]
        if len(values) == 0:
            continue
        if name == "height":
            ranges[name] = (float(values.min()), float(values.max()))
        else:
            bound = float(np.percentile(np.abs(values), CURVATURE_PERCENTILE)) or 1.0
            ranges[name] = (-bound, bound)
    return ranges


def _mesh_piece(result: Result) -> Piece:
    mesh = result.mesh.compute_normals(
        point_normals=True, cell_normals=False, split_vertices=False, auto_orient_normals=False
    )
    style = {
        "smooth_shading": False,  # the normals above already shade smoothly (no main-thread work)
        "show_edges": False,
        "edge_color": "#2a2a2a",
        "specular": 0.3,
    }
    return Piece("mesh", mesh, style, _color_ranges(mesh))


def _input_pieces(result: Result) -> list[Piece]:
    size = 7.0
    pieces = [
        Piece("points:boundary", pv.PolyData(result.leaf.boundary), _points(BOUNDARY_COLOR, 5.0))
    ]
    for i, vein in enumerate(result.leaf.veins):
        pieces.append(Piece(f"points:vein{i}", pv.PolyData(vein), _points(vein_color(i), size)))
    return pieces


def _curve_pieces(result: Result) -> list[Piece]:
    outline = result.frame.to_world(result.polygon, np.zeros(len(result.polygon)))
    pieces = [
        Piece(
            "curves:boundary", _polyline(outline, True), {"color": BOUNDARY_COLOR, "line_width": 3}
        )
    ]
    for i, vein in enumerate(result.leaf.veins):
        if len(vein) > 1:
            pieces.append(
                Piece(
                    f"curves:vein{i}",
                    _polyline(vein, False),
                    {"color": vein_color(i), "line_width": 3},
                )
            )
    return pieces


def _plane_image(result: Result, name: str, values: np.ndarray) -> pv.ImageData:
    ny, nx = result.grid.shape
    image = pv.ImageData(
        dimensions=(nx, ny, 1),
        spacing=(result.grid.spacing, result.grid.spacing, 1.0),
        origin=(*result.grid.origin, 0.0),
    )
    image.point_data[name] = values
    return image


def _to_world(result: Result, lines: pv.PolyData) -> pv.PolyData:
    """`lines` with their plane points (x, y, 0) moved to world coordinates on the plane."""
    xy = np.asarray(lines.points)[:, :2]
    lines.points = result.frame.to_world(xy, np.zeros(len(xy)))
    return lines


def _contour_piece(result: Result) -> Piece:
    lines = _plane_image(result, "g", result.g_grid).contour([0.0], scalars="g")
    return Piece("contour", _to_world(result, lines), {"color": "#e6550d", "line_width": 3})


def _probability_piece(result: Result) -> Piece:
    """The grid's quads in world coordinates, just below the plane, with p(x) (NaN outside)."""
    ny, nx = result.grid.shape
    index = np.arange(ny * nx).reshape(ny, nx)
    corners = [index[:-1, :-1], index[:-1, 1:], index[1:, 1:], index[1:, :-1]]
    quads = np.column_stack([np.full(corners[0].size, 4), *(c.ravel() for c in corners)])
    offset = np.full(ny * nx, -MAP_OFFSET * result.length)
    surface = pv.PolyData(result.frame.to_world(result.grid.points, offset), faces=quads.ravel())
    surface.point_data["p(x)"] = np.where(result.inside, result.p_grid, np.nan)
    style = {"scalars": "p(x)", "cmap": "magma", "nan_opacity": 0.0, "opacity": 0.9}
    return Piece("probability", surface, style)


def _sample_pieces(result: Result) -> tuple[Piece, Piece]:
    gmm = Piece("samples", pv.PolyData(result.surface_points), _points("#2ca02c", 3.0))
    em_xyz = result.frame.to_world(result.em_samples, np.zeros(len(result.em_samples)))
    em = Piece("em", pv.PolyData(em_xyz) if len(em_xyz) else pv.PolyData(), _points("#7f7f7f", 2.0))
    return gmm, em


def build_layers(result: Result) -> dict[str, list[Piece]]:
    """Every layer's pieces for `result`, keyed as in LAYERS."""
    gmm, em = _sample_pieces(result)
    return {
        "mesh": [_mesh_piece(result)],
        "points": _input_pieces(result),
        "curves": _curve_pieces(result),
        "contour": [_contour_piece(result)],
        "probability": [_probability_piece(result)],
        "samples": [gmm],
        "em": [em],
    }
