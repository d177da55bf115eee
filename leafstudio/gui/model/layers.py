"""What the viewport draws for a Result: named datasets with their styles, one list per layer.

Prepared on the worker thread as numpy arrays (normals, contour lines, quads: the costly part),
and wrapped into VTK datasets on the main thread when the viewport first asks for them
(Piece.data), so that VTK objects are made and touched there only. No Qt here.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import cached_property, partial
from typing import Any

import contourpy
import numpy as np
import pyvista as pv

from leafstudio._shared.extras import missing
from leafstudio.assets.asset import leaf_uvs
from leafstudio.core.pipeline import Result
from leafstudio.core.trianglemesh import polydata, vertex_normals
from leafstudio.gui.model.display_mesh import display_subset

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
LAYER_EXTRAS = {"poisson": ("open3d", "The screened Poisson surface")}  # module, feature


def unavailable(key: str) -> str:
    """Why layer `key` cannot be shown (the extra to install), or "" when it can."""
    module, feature = LAYER_EXTRAS.get(key, ("", ""))
    return missing(module, feature) if module else ""


BOUNDARY_COLOR = "#303030"
VEIN_COLORS = ("#d62728", "#1f77b4", "#ff7f0e", "#9467bd", "#17becf", "#e377c2", "#8c564b")
SCALAR_BARS = {"mesh": "height", "probability": "p(x)"}
# what the mesh can be coloured by: point array -> (label, colour map)
MESH_COLORINGS = {
    "height": ("height", "viridis"),
    "mean_curvature": ("mean curvature", "coolwarm"),
    "gaussian_curvature": ("Gaussian curvature", "coolwarm"),
}
# a point layer draws at most this many points: software OpenGL (Mesa llvmpipe) spends main-thread
# time on every point of every render, about 2 µs each here (a 2M-point scan: 7 s a render)
DISPLAY_POINTS = 25_000
SPHERE_POINTS = 10_000  # above this many, points are drawn small and flat: the mesh shows through
CURVATURE_PERCENTILE = 95  # curvature colours span ± this percentile of |value| (margins spike)
MAP_OFFSET = 0.003  # the probability map sits this fraction of the leaf length below the plane


@dataclass(eq=False)
class Piece:
    """One actor: a name unique in the scene, how to make its dataset, and its add_mesh keywords.

    `make` wraps arrays prepared beforehand into a VTK dataset, cheaply; `data` calls it once, on
    the main thread (the viewport), where VTK objects belong.
    """

    name: str
    make: Callable[[], pv.DataSet]
    style: dict[str, Any] = field(default_factory=dict)
    ranges: dict[str, tuple[float, float]] = field(default_factory=dict)  # colour range per array
    make_full: Callable[[], pv.DataSet] | None = None  # the whole dataset, when `make` draws less

    @cached_property
    def data(self) -> pv.DataSet:
        return self.make()

    @cached_property
    def full_data(self) -> pv.DataSet:
        """The whole dataset (a large mesh's every triangle, for its edges); else `data`."""
        return self.make_full() if self.make_full is not None else self.data


def cloud(points: np.ndarray) -> pv.PolyData:
    """Points as a PolyData of vertices (an empty one for no points), copied into VTK."""
    return pv.PolyData(np.asarray(points, dtype=float), deep=True) if len(points) else pv.PolyData()


def thinned(points: np.ndarray, budget: int = DISPLAY_POINTS, ordered: bool = False) -> np.ndarray:
    """At most `budget` of the (n, d) points, to draw (display only: every computation takes
    them all). Along a curve (`ordered`) they are spread evenly by index; from a cloud a fixed
    random subset is drawn (a scan's rows often come in scan lines, which a stride would band),
    in the file's order.
    """
    n = len(points)
    if n <= budget:
        return points
    if ordered:
        return points[np.unique(np.linspace(0, n - 1, budget).round().astype(np.int64))]
    keep = np.random.default_rng(0).choice(n, size=budget, replace=False)
    return points[np.sort(keep)]


def dots(color: str, size: float, count: int = 0) -> dict[str, Any]:
    """The style of `count` points drawn: spheres of `size` pixels, or, for many, flat points of
    at most 2 pixels, which leave the mesh under a dense layer visible."""
    if count > SPHERE_POINTS:
        return {"color": color, "point_size": min(size, 2.0)}
    return {"color": color, "point_size": size, "render_points_as_spheres": True}


def polylines(lines: list[np.ndarray]) -> pv.PolyData:
    """(n_i, 3) polylines as one PolyData of line cells."""
    if not lines:
        return pv.PolyData()
    sizes = [len(line) for line in lines]
    starts = np.cumsum([0, *sizes[:-1]])
    cells = np.concatenate(
        [np.r_[size, start + np.arange(size)] for size, start in zip(sizes, starts, strict=True)]
    )
    return pv.PolyData(np.vstack(lines), lines=cells, deep=True)


def vein_color(index: int) -> str:
    """The colour of vein `index` (0-based), in the 3D view and in the sketch editor alike. The
    midrib's red is its own: side veins go round the other colours (a form's eighth vein was
    red, a second midrib to the eye)."""
    if index == 0:
        return VEIN_COLORS[0]
    return VEIN_COLORS[1 + (index - 1) % (len(VEIN_COLORS) - 1)]


def _color_ranges(point_data: Mapping[str, np.ndarray]) -> dict[str, tuple[float, float]]:
    """Colour range of each array in MESH_COLORINGS the mesh has: height from its least to its
    greatest value, curvature symmetric about 0 (so that 0 is the middle colour)."""
    ranges = {}
    for name in MESH_COLORINGS:
        if name not in point_data:
            continue
        values = np.asarray(point_data[name], dtype=float)
        values = values[np.isfinite(values)]
        if len(values) == 0:
            continue
        if name == "height":
            ranges[name] = (float(values.min()), float(values.max()))
        else:
            bound = float(np.percentile(np.abs(values), CURVATURE_PERCENTILE)) or 1.0
            ranges[name] = (-bound, bound)
    return ranges


def textured(uv: np.ndarray, make: Callable[[], pv.PolyData]) -> pv.PolyData:
    """The dataset `make` returns, with (n, 2) texture coordinates (copied into VTK)."""
    mesh = make()
    mesh.active_texture_coordinates = np.array(uv, dtype=float)
    return mesh


def _mesh_piece(result: Result) -> Piece:
    """The mesh, drawn through a subset of its vertices when large (display_mesh.py); with the
    arrays the view colours by (height, curvatures), its shading normals and UVs."""
    mesh = result.triangle_mesh
    xy = result.frame.to_plane(np.asarray(mesh.points, dtype=float))[0]
    uv = leaf_uvs(result, xy)  # the exports' UVs: the Texture colouring maps their image
    colourings = {k: v for k, v in mesh.point_data.items() if k in MESH_COLORINGS}
    style = {
        "smooth_shading": False,  # the normals above already shade smoothly (no main-thread work)
        "show_edges": False,
        "edge_color": "#2a2a2a",
        "specular": 0.3,
    }
    ranges = _color_ranges(mesh.point_data)
    grid = result.grid
    subset = display_subset(xy, mesh.regular_faces, grid.origin, grid.spacing, len(result.polygon))
    if subset is None:
        normals = vertex_normals(mesh.points, mesh.regular_faces)
        whole = partial(polydata, mesh.points, mesh.regular_faces, colourings, normals)
        return Piece("mesh", partial(textured, uv, whole), style, ranges)
    keep, faces = subset
    points = mesh.points[keep]
    normals = vertex_normals(points, faces)  # of the mesh drawn: a quarter of the work
    some = {k: v[keep] for k, v in colourings.items()}
    make = partial(polydata, points, faces, some, normals)
    # the full mesh, for its edges: made (normals and all) on the main thread if ever shown
    full = partial(_whole_mesh, mesh.points, mesh.regular_faces, colourings, uv)
    return Piece("mesh", partial(textured, uv[keep], make), style, ranges, make_full=full)


def _whole_mesh(
    points: np.ndarray, faces: np.ndarray, colourings: dict[str, np.ndarray], uv: np.ndarray
) -> pv.PolyData:
    """The full mesh as drawn with its edges, with its own shading normals and UVs."""
    normals = vertex_normals(points, faces)
    return textured(uv, partial(polydata, points, faces, colourings, normals))


def _input_pieces(result: Result) -> list[Piece]:
    """The input's points, each curve thinned to a share of DISPLAY_POINTS."""
    curves = [result.leaf.boundary, *result.leaf.veins]
    budget = DISPLAY_POINTS // len(curves)
    shown = [thinned(curve, budget, ordered=True) for curve in curves]
    count = sum(len(points) for points in shown)
    boundary = dots(BOUNDARY_COLOR, 5.0, count)
    pieces = [Piece("points:boundary", partial(cloud, shown[0]), boundary)]
    for i, vein in enumerate(shown[1:]):
        style = dots(vein_color(i), 7.0, count)
        pieces.append(Piece(f"points:vein{i}", partial(cloud, vein), style))
    return pieces


def _curve_pieces(result: Result) -> list[Piece]:
    outline = result.frame.to_world(result.polygon, np.zeros(len(result.polygon)))
    closed = np.vstack([outline, outline[:1]])
    style = {"color": BOUNDARY_COLOR, "line_width": 3}
    pieces = [Piece("curves:boundary", partial(polylines, [closed]), style)]
    for i, vein in enumerate(result.leaf.veins):
        if len(vein) > 1:
            style = {"color": vein_color(i), "line_width": 3}
            pieces.append(Piece(f"curves:vein{i}", partial(polylines, [vein]), style))
    return pieces


def _contour_piece(result: Result) -> Piece:
    """g = 0 on the grid (contourpy), lifted onto the plane in world coordinates."""
    ny, nx = result.grid.shape
    x = result.grid.origin[0] + result.grid.spacing * np.arange(nx)
    y = result.grid.origin[1] + result.grid.spacing * np.arange(ny)
    generator = contourpy.contour_generator(
        x, y, result.g_grid.reshape(ny, nx), line_type=contourpy.LineType.Separate
    )
    lines = [
        result.frame.to_world(line, np.zeros(len(line)))
        for line in generator.lines(0.0)
        if len(line) > 1
    ]
    return Piece("contour", partial(polylines, lines), {"color": "#e6550d", "line_width": 3})


def _probability_piece(result: Result) -> Piece:
    """The grid's quads in world coordinates, just below the plane, with p(x) (NaN outside)."""
    ny, nx = result.grid.shape
    index = np.arange(ny * nx).reshape(ny, nx)
    corners = [index[:-1, :-1], index[:-1, 1:], index[1:, 1:], index[1:, :-1]]
    quads = np.column_stack([c.ravel() for c in corners])
    offset = np.full(ny * nx, -MAP_OFFSET * result.length)
    points = result.frame.to_world(result.grid.points, offset)
    values = {"p(x)": np.where(result.inside, result.p_grid, np.nan)}
    style = {"scalars": "p(x)", "cmap": "magma", "nan_opacity": 0.0, "opacity": 0.9}
    return Piece("probability", partial(polydata, points, quads, values), style)


def _sample_pieces(result: Result) -> tuple[Piece, Piece]:
    surface = thinned(result.surface_points)
    gmm = Piece("samples", partial(cloud, surface), dots("#2ca02c", 3.0, len(surface)))
    em_xy = thinned(result.em_samples)
    em_xyz = result.frame.to_world(em_xy, np.zeros(len(em_xy)))
    em = Piece("em", partial(cloud, em_xyz), dots("#7f7f7f", 2.0, len(em_xy)))
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
