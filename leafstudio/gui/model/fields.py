"""The method's layers drawn where they can be read with the mesh shown (issue 22): the fields of
the plane (g and the height guide p(x)) draped over the surface, the zero contour of g as a band
on top, the EM samples coloured by the Gaussian that owns them with each Gaussian's 1σ and 2σ
ellipses, all lifted a little above the surface so that the mesh never hides them.

Arrays only, prepared on the worker; the VTK datasets are made on the main thread (Piece.make).
Also the readable colour ranges of the colour bars. No Qt here.
"""

from __future__ import annotations

import math
from functools import partial

import contourpy
import numpy as np
import pyvista as pv

from leafstudio.core.pipeline import Result
from leafstudio.core.trianglemesh import polydata
from leafstudio.gui.model.pieces import Piece, cloud, dots, polylines, thinned
from leafstudio.render.step_slides import gaussian_color  # the plan view's colours too

LIFT = 0.0025  # fields sit this fraction of the leaf's length above the surface
LIFT_P = 0.0035  # p(x) a little higher, so that it reads above g where both are shown
CONTOUR_RADIUS = 0.009  # the zero contour's tube, in leaf lengths (seen at any zoom)
ZERO_COLOR = "#ff7f0e"
ELLIPSE_POINTS = 96
SIGMAS = (1.0, 2.0)
EM_POINT_SIZE = 6.0
SAMPLE_POINT_SIZE = 8.0
SAMPLE_COLOR = "#ff4fd8"  # bright pink: apart from every colour map and the background


def nice_range(low: float, high: float) -> tuple[float, float, str]:
    """A colour range that reads well on a bar: `low` and `high` widened to round numbers (a
    tiny start such as 7.37e-06 becomes 0) and the printf format that writes them whole.

    Parameters
    ----------
    low, high : float
        The values' least and greatest.

    Returns
    -------
    low, high : float
        Rounded outward to a multiple of a step of 1, 2 or 5 times a power of ten.
    fmt : str
        "%.Nf" with as many decimals as the step needs.

    Examples
    --------
    >>> nice_range(7.37e-06, 0.0889)
    (0.0, 0.1, '%.2f')
    >>> nice_range(-0.327, 0.378)
    (-0.4, 0.4, '%.1f')
    """
    low, high = float(low), float(high)
    if not (math.isfinite(low) and math.isfinite(high)) or high <= low:
        return low, high if high > low else low + 1.0, "%.3g"
    power = 10.0 ** math.floor(math.log10(high - low))
    step = next(f * power for f in (0.1, 0.2, 0.5, 1.0, 2.0) if (high - low) / (f * power) <= 5)
    lo, hi = math.floor(low / step + 1e-9) * step, math.ceil(high / step - 1e-9) * step
    decimals = max(0, -math.floor(math.log10(step) + 1e-9))
    return round(lo, decimals) + 0.0, round(hi, decimals) + 0.0, f"%.{decimals}f"


def bar_format(low: float, high: float) -> str:
    """The printf format of a colour bar's end labels for a range `low` to `high` as it is (the
    mesh's: its heights' own ends, not rounded): nice_range's, with more decimals until each
    end is written within BAR_LABEL_SLACK of the span of its value. nice_range's alone wrote
    the soybean pot1_1 scan's heights, -1.14 to 1.39, as "-1" and "1" (qa37); a rounded range
    keeps its format."""
    fmt = nice_range(low, high)[2]
    if not fmt.endswith("f"):
        return fmt  # an empty or non-finite range: "%.3g"
    decimals, slack = int(fmt[2:-1]), BAR_LABEL_SLACK * (high - low)
    while decimals < 12 and any(abs(round(v, decimals) - v) > slack for v in (low, high)):
        decimals += 1
    return f"%.{decimals}f"


BAR_LABEL_SLACK = 0.02  # of a bar's span: 8 pixels of a 400-pixel bar


def node_heights(result: Result) -> np.ndarray:
    """(ny * nx,) the surface's height at every grid node: z(x) at the kept nodes (computed by
    the run), the base b(x) elsewhere (0 for a planar margin), continuous across the margin
    because the taper makes z = b there."""
    heights = np.zeros(len(result.grid.points))
    base = result.surface.base
    if base is not None:
        heights[:] = base(result.grid.points)
    heights[result.inside] = result.on_blade(result.surface_points)[1]  # a bent leaf's: flat
    return heights


def _grid_quads(shape: tuple[int, int], keep: np.ndarray | None = None) -> np.ndarray:
    """(m, 4) the grid's quads; with the (ny * nx,) bool `keep`, only those whose four corners
    it keeps (an opaque map with no blank cells: blank ones would make VTK blend the actor)."""
    ny, nx = shape
    index = np.arange(ny * nx).reshape(ny, nx)
    corners = [index[:-1, :-1], index[:-1, 1:], index[1:, 1:], index[1:, :-1]]
    quads = np.column_stack([c.ravel() for c in corners])
    return quads if keep is None else quads[keep[quads].all(axis=1)]


def _grid_normals(result: Result, heights: np.ndarray) -> np.ndarray:
    """(ny * nx, 3) unit normals of the height sheet over the grid, in world coordinates (the
    fields shade as the surface does)."""
    ny, nx = result.grid.shape
    dz_dy, dz_dx = np.gradient(heights.reshape(ny, nx), result.grid.spacing)
    frame = result.frame
    normals = (
        -dz_dx.reshape(-1, 1) * np.asarray(frame.u)
        - dz_dy.reshape(-1, 1) * np.asarray(frame.v)
        + np.asarray(frame.normal)
    )
    return normals / np.linalg.norm(normals, axis=1, keepdims=True)


def field_piece(
    result: Result,
    key: str,
    name: str,
    values: np.ndarray,
    cmap: str,
    lift: float,
    heights: np.ndarray,
    symmetric: bool = False,
) -> Piece:
    """The grid's quads draped over the surface (`lift` leaf lengths above it), as the actor
    `key`, carrying `values` under the array name `name` (quads with a NaN corner left out);
    its colour range rounded (nice_range), symmetric about 0 when asked (a signed field, 0 the
    middle colour)."""
    points = result.frame.to_world(result.grid.points, heights + lift * result.length)
    finite = np.isfinite(values)
    low, high = (
        (float(values[finite].min()), float(values[finite].max())) if finite.any() else (0, 1)
    )
    if symmetric:
        low, high = -max(abs(low), abs(high)), max(abs(low), abs(high))
    low, high, _ = nice_range(low, high)
    style = {"scalars": name, "cmap": cmap, "clim": (low, high), "smooth_shading": False}
    quads = _grid_quads(result.grid.shape, None if finite.all() else finite)
    filled = np.where(finite, values, low)
    normals = _grid_normals(result, heights)
    make = partial(polydata, points, quads, {name: filled}, normals)
    return Piece(key, make, style, {name: (low, high)})


def zero_contour(result: Result) -> list[np.ndarray]:
    """g = 0 on the grid (contourpy): (n_i, 2) lines in the plane."""
    ny, nx = result.grid.shape
    x = result.grid.origin[0] + result.grid.spacing * np.arange(nx)
    y = result.grid.origin[1] + result.grid.spacing * np.arange(ny)
    generator = contourpy.contour_generator(
        x, y, result.g_grid.reshape(ny, nx), line_type=contourpy.LineType.Separate
    )
    return [line for line in generator.lines(0.0) if len(line) > 1]


def _tubes(lines: list[np.ndarray], radius: float) -> pv.PolyData:
    """Polylines as tubes of a radius in world units (a band seen at any zoom)."""
    data = polylines(lines)
    return data.tube(radius=radius, n_sides=10, capping=False) if data.n_points else data


def contour_piece(result: Result) -> Piece:
    """The zero contour of g as a tube lying on the surface (z = b there), on top of the mesh
    and the boundary's dots."""
    lift = LIFT * result.length
    lines = []
    for line in zero_contour(result):
        height = result.surface(line) if result.surface.base is not None else np.zeros(len(line))
        lines.append(result.frame.to_world(line, height + lift))
    make = partial(_tubes, lines, CONTOUR_RADIUS * result.length)
    return Piece("contour", make, {"color": ZERO_COLOR, "smooth_shading": True})


def owners(result: Result) -> np.ndarray:
    """(s,) the index of the Gaussian of EM's mixture that owns each EM sample (Mixture.owners;
    not the refined mixture of the surface, whose Gaussians moved off the samples)."""
    return result.em_mixture.owners(np.asarray(result.em_samples, dtype=float).reshape(-1, 2))


def ellipse(mean: np.ndarray, covariance: np.ndarray, sigmas: float) -> np.ndarray:
    """(ELLIPSE_POINTS + 1, 2) the closed ellipse of Gaussian (mean, covariance) at `sigmas`
    standard deviations (Mahalanobis distance)."""
    values, vectors = np.linalg.eigh(covariance)
    angle = np.linspace(0.0, 2.0 * np.pi, ELLIPSE_POINTS + 1)
    circle = np.column_stack([np.cos(angle), np.sin(angle)])
    return mean + sigmas * (circle * np.sqrt(np.maximum(values, 0.0))) @ vectors.T


def _within(result: Result, line: np.ndarray) -> list[np.ndarray]:
    """The runs of `line` inside the leaf (g >= 0): an elongated Gaussian's 2σ ellipse can
    reach far past it, and off the surface a ring only crosses the view."""
    inside = result.surface.implicit(line) >= 0.0
    edges = np.flatnonzero(np.diff(np.r_[0, inside.astype(int), 0]))
    return [line[a:b] for a, b in zip(edges[::2], edges[1::2], strict=True) if b - a > 1]


def em_pieces(result: Result) -> list[Piece]:
    """The EM samples, a piece per Gaussian in its colour, lifted above the surface, and each
    Gaussian's 1σ and 2σ ellipses on the surface, within the leaf (2σ thinner)."""
    lift = 2 * LIFT * result.length
    xy = np.asarray(result.em_samples, dtype=float).reshape(-1, 2)
    owner = owners(result)
    keep = thinned(np.arange(len(xy)))  # at most DISPLAY_POINTS drawn (pieces.py)
    xy, owner = xy[keep], owner[keep]
    mixture = result.em_mixture
    pieces = []
    for k in range(len(mixture.weights)):
        mine = xy[owner == k]
        world = result.frame.to_world(mine, result.height(mine) + lift) if len(mine) else mine
        style = dots(gaussian_color(k), EM_POINT_SIZE, len(xy))
        pieces.append(Piece(f"em:{k}", partial(cloud, world), style))
    # the ellipses at unit size, scaled (plane coordinates scale by the factor alone): the
    # mixture in the leaf's units has infinite covariances past about 1e154 (gmm.scaled)
    unit, factor = (result.unit, result.units.scale) if result.unit is not None else (result, 1.0)
    for sigmas, width in zip(SIGMAS, (4.0, 2.0), strict=True):
        for k in range(len(mixture.weights)):
            gaussian = unit.em_mixture.means[k], unit.em_mixture.covariances[k]
            runs = _within(result, factor * ellipse(*gaussian, sigmas))
            world = [result.frame.to_world(run, result.height(run) + lift) for run in runs]
            style = {"color": gaussian_color(k), "line_width": width}
            pieces.append(Piece(f"em:ellipse{sigmas:g}:{k}", partial(polylines, world), style))
    return pieces


def samples_piece(result: Result) -> Piece:
    """The GMM samples (kept grid nodes on z(x)), lifted a little so that the mesh never
    covers half of each."""
    points = thinned(result.surface_points)  # at most DISPLAY_POINTS drawn (pieces.py)
    points = points + 2 * LIFT * result.length * np.asarray(result.frame.normal)
    style = dots(SAMPLE_COLOR, SAMPLE_POINT_SIZE, len(points))
    return Piece("samples", partial(cloud, points), style)


def field_layers(result: Result) -> dict[str, list[Piece]]:
    """The layers of the plane's fields, keyed as in layers.LAYERS."""
    heights = node_heights(result)
    g = np.asarray(result.g_grid, dtype=float)
    p = np.where(result.inside, np.asarray(result.p_grid, dtype=float), np.nan)
    return {
        "implicit": [
            field_piece(result, "implicit", "g(x)", g, "RdBu", LIFT, heights, symmetric=True)
        ],
        "probability": [field_piece(result, "probability", "p(x)", p, "magma", LIFT_P, heights)],
        "contour": [contour_piece(result)],
        "samples": [samples_piece(result)],
        "em": em_pieces(result),
    }
