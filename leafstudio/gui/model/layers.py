"""What the viewport draws for a Result: named datasets with their styles, one list per layer.

Prepared on the worker thread as numpy arrays (normals, contour lines, quads: the costly part),
and wrapped into VTK datasets on the main thread when the viewport first asks for them
(Piece.data), so that VTK objects are made and touched there only. No Qt here.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from functools import partial

import numpy as np
import pyvista as pv

from leafstudio._shared.extras import missing
from leafstudio.assets.asset import leaf_uvs
from leafstudio.core.bend import flat_leaf
from leafstudio.core.pipeline import Result
from leafstudio.core.trianglemesh import colour_range, polydata, vertex_normals
from leafstudio.gui.model.display_mesh import display_subset
from leafstudio.gui.model.fields import LIFT, field_layers
from leafstudio.gui.model.pieces import (
    Piece,
    cloud,
    dots,
    polylines,
    thinned,
)
from leafstudio.gui.model.thinning import INPUT_POINTS

# (key, label shown in the layer list, on by default)
LAYERS: tuple[tuple[str, str, bool], ...] = (
    ("mesh", "Mesh", True),
    ("points", "Input points", True),
    ("curves", "Boundary and vein curves", False),
    ("blade", "Bent leaf laid flat", False),
    ("contour", "Zero contour of g", False),
    ("implicit", "Implicit g(x): + inside, − outside", False),
    ("probability", "Probability map p(x)", False),
    ("samples", "GMM samples", False),
    ("em", "EM samples", False),
    ("scan", "Scan points", True),
    ("poisson", "Screened Poisson surface (beside ours)", False),
)
# the laid-flat blade's outline and dots above the fields drawn on it (g at LIFT, p(x) at 1.4 LIFT,
# the EM samples at 2 LIFT): at the surface, half of each dot was under g's sheet in the lesson
BLADE_LIFT = 3 * LIFT
SIDE_LAYERS = frozenset({"scan", "poisson"})  # not built from a Result (see scans.py)
LAYER_EXTRAS = {"poisson": ("open3d", "The screened Poisson surface")}  # module, feature


def unavailable(key: str) -> str:
    """Why layer `key` cannot be shown (the extra to install), or "" when it can."""
    module, feature = LAYER_EXTRAS.get(key, ("", ""))
    return missing(module, feature) if module else ""


BOUNDARY_COLOR = "#303030"
VEIN_COLORS = ("#d62728", "#1f77b4", "#ff7f0e", "#9467bd", "#17becf", "#e377c2", "#8c564b")
SCALAR_BARS = {"mesh": "height", "implicit": "g(x)", "probability": "p(x)"}
# what the mesh can be coloured by: point array -> (label, colour map)
MESH_COLORINGS = {
    "height": ("height", "viridis"),
    "mean_curvature": ("mean curvature", "coolwarm"),
    "gaussian_curvature": ("Gaussian curvature", "coolwarm"),
}


def vein_color(index: int) -> str:
    """The colour of vein `index` (0-based), in the 3D view and in the sketch editor alike. The
    midrib's red is its own: side veins go round the other colours (a form's eighth vein was
    red, a second midrib to the eye)."""
    if index == 0:
        return VEIN_COLORS[0]
    return VEIN_COLORS[1 + (index - 1) % (len(VEIN_COLORS) - 1)]


def _color_ranges(point_data: Mapping[str, np.ndarray]) -> dict[str, tuple[float, float]]:
    """Colour range of each array in MESH_COLORINGS the mesh has (trianglemesh.colour_range:
    height its full range, a curvature symmetric about 0, so that 0 is the middle colour)."""
    return {
        name: colour_range(name, point_data[name])
        for name in MESH_COLORINGS
        if name in point_data and np.isfinite(np.asarray(point_data[name], dtype=float)).any()
    }


def textured(uv: np.ndarray, make: Callable[[], pv.PolyData]) -> pv.PolyData:
    """The dataset `make` returns, with (n, 2) texture coordinates (copied into VTK)."""
    mesh = make()
    mesh.active_texture_coordinates = np.array(uv, dtype=float)
    return mesh


def _mesh_piece(result: Result) -> Piece:
    """The mesh, drawn through a subset of its vertices when large (display_mesh.py); with the
    arrays the view colours by (height, curvatures), its shading normals and UVs."""
    mesh = result.triangle_mesh
    xy = result.mesh_on_blade()[0]  # where the flat blade's grid and outline are
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
    subset = display_subset(xy, mesh.regular_faces, grid.origin, grid.spacing, result.on_outline())
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


def _input_pieces(curves: list[np.ndarray], layer: str = "points") -> list[Piece]:
    """The (n_i, 3) input `curves` (the boundary first, then each vein) as the dots of `layer`,
    each curve thinned to a share of INPUT_POINTS."""
    budget = INPUT_POINTS // len(curves)
    shown = [thinned(curve, budget, ordered=True) for curve in curves]
    count = sum(len(points) for points in shown)
    boundary = dots(BOUNDARY_COLOR, 5.0, count)
    pieces = [Piece(f"{layer}:boundary", partial(cloud, shown[0]), boundary)]
    for i, vein in enumerate(shown[1:]):
        style = dots(vein_color(i), 7.0, count)
        pieces.append(Piece(f"{layer}:vein{i}", partial(cloud, vein), style))
    return pieces


def _flat_outline(result: Result) -> np.ndarray:
    """(n + 1, 3) the closed outline on the flat blade, in world coordinates, at its heights
    (z = b on the margin: 0 for a planar one)."""
    polygon = result.polygon
    base = result.surface.base
    heights = base(polygon) if base is not None else np.zeros(len(polygon))
    outline = result.frame.to_world(polygon, heights)
    return np.vstack([outline, outline[:1]])


def _curve_pieces(result: Result) -> list[Piece]:
    """The outline and the veins as lines where the input is: a bent leaf's outline bent (drawn
    flat, it crossed a folded blade's mesh beside the folded veins)."""
    outline = _flat_outline(result)
    if result.leaf.bend is not None:
        outline = result.leaf.bend.apply(outline)
    style = {"color": BOUNDARY_COLOR, "line_width": 3}
    pieces = [Piece("curves:boundary", partial(polylines, [outline]), style)]
    for i, vein in enumerate(result.leaf.veins):
        if len(vein) > 1:
            style = {"color": vein_color(i), "line_width": 3}
            pieces.append(Piece(f"curves:vein{i}", partial(polylines, [vein]), style))
    return pieces


def _blade_pieces(result: Result) -> list[Piece]:
    """A bent leaf laid flat, where the method's fields are drawn (g, p(x), the EM samples: the
    flat blade's, fields.py): its outline and its input points laid flat by its bend (the flat
    blade its run kept, `Result.blade`), BLADE_LIFT above. Nothing for an unbent leaf: the input
    layers are it."""
    if result.leaf.bend is None:
        return []
    blade = result.blade if result.blade is not None else flat_leaf(result.leaf)
    lift = BLADE_LIFT * result.length * np.asarray(result.frame.normal)
    style = {"color": BOUNDARY_COLOR, "line_width": 3}
    outline = Piece("blade:outline", partial(polylines, [_flat_outline(result) + lift]), style)
    curves = [curve + lift for curve in (blade.boundary, *blade.veins)]
    return [outline, *_input_pieces(curves, "blade")]


def build_layers(result: Result) -> dict[str, list[Piece]]:
    """Every layer's pieces for `result`, keyed as in LAYERS."""
    return {
        "mesh": [_mesh_piece(result)],
        "points": _input_pieces([result.leaf.boundary, *result.leaf.veins]),
        "curves": _curve_pieces(result),
        "blade": _blade_pieces(result),
        **field_layers(result),  # drawn over the surface (fields.py)
    }
