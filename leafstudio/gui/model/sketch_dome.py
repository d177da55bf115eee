"""The dome a drawn leaf's veins follow until their heights are set by hand (Sketch.auto).

A vein clicked out in the editor used to take its nearest control point's height (5% of the
sketch's size for a new vein), held under the roof, HEIGHT_RATIO times its distance inside the
outline. A side vein so left the rising midrib falling at the roof's slope, and a surface through
both creased along the midrib past every junction (the app's clicked leaf, tests/leaves.
clicked_sketch, K 3, grid 128: 99th-percentile interior dihedral 2.65° through the veins, 2.03°
on the paper's surface). The forms left the roof for a membrane's dome for the same reason
(forms/relief.py); a drawn leaf's veins follow the same dome over its outline. Setting only each
control point on the dome was not enough (branch experiment/sketch-dome: inside 2.07°, margin
band 1.34° -> 1.68°: a spline through three control points does not follow the dome between
them), so an auto vein's whole sampled curve takes the dome's heights (Sketch.vein_curve).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
import shapely
from shapely.geometry import Polygon

from leafstudio.core.prepare.vein_order import midrib_turned
from leafstudio.forms.blade import Blade
from leafstudio.forms.relief import dome
from leafstudio.forms.veins import HEIGHT_RATIO

if TYPE_CHECKING:  # for the hints only: sketch_model imports this module
    from leafstudio.gui.model.sketch_model import Sketch

Heights = Callable[[np.ndarray], np.ndarray]


def sketch_dome(sketch: Sketch) -> Heights | None:
    """(n, 2) plane points -> (n,) heights of the dome over a drawn sketch's outline, based
    where its midrib starts (`midrib_base`, `outline_dome`); None for a loaded leaf (its margin
    has heights of its own: a relief) or a sketch without an outline. Made once a sketch."""
    made = sketch.__dict__.setdefault("_curves", {})  # frozen: its one cache, as sketch_model's
    if "dome" in made:
        return made["dome"]
    outline = sketch.boundary_curve()
    heights = None
    if len(outline) >= 3 and not len(sketch.relief):
        base = midrib_base(sketch)
        key = None if base is None else (float(base[0]), float(base[1]))
        heights = _cached_dome(np.ascontiguousarray(outline, dtype=float).tobytes(), key)
    made["dome"] = heights
    return heights


def midrib_base(sketch: Sketch) -> np.ndarray | None:
    """(2,) plane point where the sketch's midrib (its first vein) meets the blade: its start,
    or its end when its side veins say it is written apex first (vein_order.midrib_turned, as
    every reader of a leaf's base decides it); None without a midrib."""
    if not sketch.veins or not len(sketch.veins[0]):
        return None
    flat = [np.pad(np.asarray(v, dtype=float)[:, :2], ((0, 0), (0, 1))) for v in sketch.veins]
    return flat[0][-1 if midrib_turned(flat) else 0, :2]


@functools.lru_cache(maxsize=8)
def _cached_dome(outline: bytes, base: tuple[float, float] | None) -> Heights:
    """`outline_dome` once per outline and base: every edit makes a new sketch, most with the
    outline of the one before (a dome: 3 ms for the clicked leaf's 192 outline points)."""
    points = np.frombuffer(outline, dtype=float).reshape(-1, 2)
    region = shapely.make_valid(Polygon(points))
    return outline_dome(region, None if base is None else np.array(base))


def outline_dome(region: shapely.Geometry, base: np.ndarray | None) -> Heights:
    """(n, 2) plane points -> (n,) heights of the forms' dome (forms/relief.dome) over a drawn
    leaf's `region` (its outline made valid): HEIGHT_RATIO times the largest distance to the
    margin at its top, 0 on the margin and outside. `base`: where the midrib starts (its
    nearest outline point is the blade's base, flattened as a form's is, and a sinus's notch
    found), or None before there is a midrib (a rounded base: nothing flattened).

    The dome is made in the blade's own frame, base at the origin and the outline's farthest
    point from it at (1, 0), as a form's is (forms/veins.grow_veins), and scaled back.
    """
    if not isinstance(region, Polygon) or region.area <= 0:  # a crossed outline: no one blade
        return lambda xy: np.zeros(len(np.atleast_2d(xy)))
    ring = region.exterior
    coords = np.asarray(ring.coords)
    if base is None:
        start = coords[np.argmin(coords[:, 0])]
    else:
        start = np.asarray(ring.interpolate(ring.project(shapely.Point(base[:2]))).coords)[0]
    tip = coords[np.argmax(np.linalg.norm(coords - start, axis=1))]
    length = float(np.linalg.norm(tip - start))
    along = (tip - start) / length
    across = np.array([-along[1], along[0]])

    def local(xy: np.ndarray) -> np.ndarray:
        shifted = np.atleast_2d(np.asarray(xy, dtype=float))[:, :2] - start
        return np.column_stack([shifted @ along, shifted @ across]) / length

    rise = dome(Blade(Polygon(local(coords))), HEIGHT_RATIO, np.zeros(2), base is None)

    def heights(xy: np.ndarray) -> np.ndarray:
        xy = np.atleast_2d(np.asarray(xy, dtype=float))[:, :2]
        inside = shapely.contains_xy(region, xy[:, 0], xy[:, 1])
        return np.where(inside, length * rise(local(xy)), 0.0)

    return heights


def on_dome(sketch: Sketch, veins: tuple[np.ndarray, ...]) -> tuple[np.ndarray, ...]:
    """`veins` (the sketch's control points) with each auto vein's heights the dome's at its
    points: what the editor shows and keeps when the vein's heights are then set by hand. As
    they are without a dome (no outline yet, or a loaded leaf)."""
    heights = sketch_dome(sketch) if any(sketch.auto) else None
    if heights is None:
        return veins
    out = list(veins)
    for i, auto in enumerate(sketch.auto):
        if auto and len(out[i]):
            out[i] = out[i].copy()
            out[i][:, 2] = heights(out[i][:, :2])
    return tuple(out)


def default_height(sketch: Sketch, vein: int, xy: np.ndarray) -> float:
    """Height for a new point of vein `vein` (any index past the last: a new vein) at plane
    point `xy`. An auto vein's: the dome's there. Else that of the vein's nearest control point,
    else (a new vein) 5% of the sketch's size. On a drawn leaf (its margin on the plane) a
    point stands no higher or lower than HEIGHT_RATIO times its distance inside the outline
    (forms/veins.py: the roof relief's slope, 14°): the surface comes down to the margin, and
    the app's drawn leaf (every point at 5%) had vein points 0.019 of its length off the
    surface. A vein's only point held down so (a midrib started by the base) passes on the
    5%, not its own height (the whole midrib stood 0.007 high)."""
    xy = np.asarray(xy, dtype=float)
    auto = 0 <= vein < len(sketch.veins) and sketch.auto[vein]
    heights = sketch_dome(sketch) if auto else None
    if heights is not None:
        return float(heights(xy[None, :2])[0])
    level = 0.05 * sketch.extent()
    height = level
    control = sketch.veins[vein] if 0 <= vein < len(sketch.veins) else np.zeros((0, 3))
    if len(control):
        nearest = control[np.argmin(np.linalg.norm(control[:, :2] - xy, axis=1))]
        height = float(nearest[2])
        cap = _margin_cap(sketch, nearest[:2])
        held = cap is not None and abs(abs(height) - cap) <= 1e-9 * sketch.extent()
        if len(control) == 1 and held and abs(height) < level:
            height = level if height >= 0 else -level
    cap = _margin_cap(sketch, xy)
    return height if cap is None else float(np.sign(height) * min(abs(height), cap))


def _margin_cap(sketch: Sketch, xy: np.ndarray) -> float | None:
    """How high (or low) a new vein point at plane point `xy` may stand on a drawn leaf:
    HEIGHT_RATIO times its distance inside the outline, 0 outside; None for a sketch with a
    relief (a loaded leaf whose margin has heights of its own: its veins keep theirs) or
    without an outline."""
    outline = sketch.boundary_curve()
    if len(outline) < 3 or len(sketch.relief):
        return None
    made = sketch.__dict__.setdefault("_curves", {})  # the outline's shapes, once a sketch
    if "margin" not in made:
        made["margin"] = (
            shapely.make_valid(shapely.Polygon(outline)),
            shapely.LinearRing(outline),
        )
    region, ring = made["margin"]
    point = shapely.Point(xy)
    return HEIGHT_RATIO * ring.distance(point) if region.covers(point) else 0.0
