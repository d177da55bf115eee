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

A height set by hand then turned the vein into the spline through its control points' heights,
and its whole curve jumped off the dome (up to 0.0091 of the length on the clicked midrib, 16% of
its peak, as a user started dragging one point). So a drawn vein's heights are offsets from the
dome (Sketch.offsets): at each sample, the dome's height plus its control points' offsets joined
span by span with a smoothstep (`blended`), which is local: a point's offset moves the curve only
between its neighbouring control points, and joins them with no crease (zero slope there). An auto
vein is one with no offset yet. Loaded leaves, grown veins and projects written before keep their
heights as they are (no offsets: the spline through the control points' heights).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np
import shapely
from shapely.geometry import Polygon

from leafstudio.core.prepare.vein_order import midrib_turned
from leafstudio.forms.blade import Blade
from leafstudio.forms.relief import dome
from leafstudio.forms.veins import HEIGHT_RATIO
from leafstudio.gui.model.curves import SAMPLES_PER_SPAN, distinct, nearest_on_polyline, open_curve

if TYPE_CHECKING:  # for the hints only: sketch_model imports this module
    from leafstudio.gui.model.sketch_model import Sketch

Heights = Callable[[np.ndarray], np.ndarray]
BRANCH_REACH = 2e-3  # of the sketch's size: a vein starting this near a drawn vein's curve
# branches from it (`carried`). Its curve in the plane moves a little when the dome under its
# control points does or a point is added: an outline edited moved it 3e-6 to 6e-5, a point
# added at the midrib's end up to 9e-4, and its side veins were no longer carried (review)


def sketch_dome(sketch: Sketch) -> Heights | None:
    """(n, 2) plane points -> (n,) heights of the dome over a drawn sketch's outline, based
    where its midrib starts (`midrib_base`, `outline_dome`); None for a loaded leaf (its margin
    has heights of its own: a relief) or a sketch without an outline. Made once a sketch."""
    made = sketch.__dict__.setdefault("_curves", {})  # frozen: its one cache, as sketch_model's
    if "dome" not in made:  # its key, not the dome: a sketch pickles (a big project is read
        # in another process, sources/reading.py), and a dome's functions do not (review)
        outline = sketch.boundary_curve()
        made["dome"] = None
        if len(outline) >= 3 and not len(sketch.relief):
            base = midrib_base(sketch)
            key = None if base is None else (float(base[0]), float(base[1]))
            made["dome"] = (np.ascontiguousarray(outline, dtype=float).tobytes(), key)
    return None if made["dome"] is None else _cached_dome(*made["dome"])


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
    if not isinstance(region, Polygon):  # a crossed outline: the dome over its largest piece
        # (none at all hid the dome while a point was dragged past its neighbour, and a height
        # typed meanwhile was an offset from 0: 0.05 typed became 0.0938; review)
        parts = [part for part in shapely.get_parts(region) if isinstance(part, Polygon)]
        region = max(parts, key=lambda part: part.area) if parts else Polygon()
    if region.area <= 0:
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


def dome_at(sketch: Sketch, xy: np.ndarray) -> np.ndarray:
    """(n,) heights of the sketch's dome at (n, 2) plane points: 0 without one (no outline yet,
    where a drawn vein stands at its offsets; or a loaded leaf, whose veins have none)."""
    xy = np.asarray(xy, dtype=float).reshape(len(xy), -1)[:, :2]
    heights = sketch_dome(sketch)
    return np.zeros(len(xy)) if heights is None else heights(xy)


def offsets_of(sketch: Sketch, points: np.ndarray) -> np.ndarray:
    """(n,) offsets from the sketch's dome of (n, 3) points' heights."""
    return points[:, 2] - dome_at(sketch, points)


def on_dome(
    sketch: Sketch, veins: tuple[np.ndarray, ...], offsets: tuple[np.ndarray | None, ...]
) -> tuple[tuple[np.ndarray, ...], tuple[np.ndarray | None, ...]]:
    """`veins` (the sketch's control points) with each drawn vein's heights the dome's plus its
    `offsets` (what the editor shows: absolute heights), and the offsets read-only, one a
    point: none (None) past the given ones and on a loaded leaf. A vein whose points were added
    or dropped without their offsets takes them from the heights given."""
    out_veins, out_offsets = list(veins), []
    made = sketch.__dict__.setdefault("_curves", {})  # the dome under each, for `_drawn`
    for i, vein in enumerate(veins):
        given = offsets[i] if i < len(offsets) and not len(sketch.relief) else None
        if given is None:
            out_offsets.append(None)
            continue
        under = made["under", i] = dome_at(sketch, vein)
        given = np.asarray(given, dtype=float).reshape(-1)
        if len(given) != len(vein):
            given = vein[:, 2] - under
        if given.flags.writeable:
            given = given.copy()
            given.setflags(write=False)
        out_veins[i] = np.column_stack([vein[:, :2], under + given])
        out_offsets.append(given)
    return tuple(out_veins), tuple(out_offsets)


def vein_curve(sketch: Sketch, vein: int) -> np.ndarray:
    """(s, 3) points along vein `vein`, a new array. A vein with heights of its own: the spline
    through its control points. A drawn vein: at the dome's heights plus its offsets
    `blended` (`_drawn`)."""
    offsets = sketch.offsets[vein]
    if offsets is None:
        return np.array(open_curve(sketch.veins[vein]))
    xy, keep = _drawn(sketch, vein)
    return np.column_stack([xy, dome_at(sketch, xy) + blended(offsets[keep], SAMPLES_PER_SPAN)])


def _drawn(sketch: Sketch, vein: int) -> tuple[np.ndarray, np.ndarray]:
    """(s, 2) plane points along drawn vein `vein` and the (m,) mask of the control points its
    curve keeps (`distinct`): the spline through them as they stand on the dome (an auto
    vein's own; its offsets not part of it: a nudge moves no point sideways)."""
    control = sketch.veins[vein]
    under = sketch.__dict__.get("_curves", {}).get(("under", vein))  # made with the sketch
    on = np.column_stack([control[:, :2], dome_at(sketch, control) if under is None else under])
    keep = distinct(on, closed=False)
    return np.asarray(open_curve(on[keep]), dtype=float).reshape(-1, 3)[:, :2], keep


def branch_offset(sketch: Sketch, vein: int, xy: np.ndarray) -> np.ndarray | None:
    """(1,) offsets of a vein branching from vein `vein` at plane point `xy`: a drawn vein's
    where its curve passes nearest (0 on an auto vein, exactly: not its height less the
    dome's); None from a vein with heights of its own (the branch keeps its height)."""
    offsets = sketch.offsets[vein]
    if offsets is None:
        return None
    along, keep = _drawn(sketch, vein)
    curve = np.column_stack([along, blended(offsets[keep], SAMPLES_PER_SPAN)])
    point, _ = nearest_on_polyline(curve, np.asarray(xy, dtype=float)[:2])
    return np.array([0.0 if point is None else point[2]])


def carried(
    sketch: Sketch, vein: int, control: np.ndarray, offsets: np.ndarray | None
) -> tuple[np.ndarray | None, ...]:
    """The sketch's offsets with drawn vein `vein`'s new (m,) `offsets` for its (m, 3) `control`
    points (None: from their heights, over the sketch's dome: a point whose height is as it was
    keeps its offset). When only its heights changed, each drawn vein that branches from it
    (started on its curve: `Sketch.started_vein`; not where `vein` starts: one started with it
    from a third) is raised or lowered at its first point as `vein` was there, so the two
    still meet: the clicked midrib's point raised by 2% of the size left the side veins
    started there under it, and the surface through them creased at the junction (K 3, grid
    128: p99 interior dihedral 7.2°; carried, 3.1°)."""
    kept, before = list(sketch.offsets), sketch.offsets[vein]
    offsets = kept[vein] = offsets_of(sketch, control) if offsets is None else offsets
    same = before is not None and np.array_equal(control[:, :2], sketch.veins[vein][:, :2])
    if not same or np.array_equal(offsets, before):
        return tuple(kept)
    along, keep = _drawn(sketch, vein)  # the same curve in the plane before and after
    change = np.column_stack([along, blended((offsets - before)[keep], SAMPLES_PER_SPAN)])
    _lift_branches(sketch, vein, change, lambda on, _start: on[2], kept)
    return tuple(kept)


def _lift_branches(
    sketch: Sketch,
    vein: int,
    path: np.ndarray,
    rise: Callable[[np.ndarray, np.ndarray], float],
    offsets: list[np.ndarray | None],
) -> None:
    """Raise, in `offsets` (the sketch's, one a vein), the first offset of each drawn vein that
    starts on vein `vein`'s (s, 3) `path` (within BRANCH_REACH of the size; not where the path
    starts: a vein started with it from a third) by `rise(its nearest path point, its start)`."""
    reach = BRANCH_REACH * sketch.extent()
    for other, start in enumerate(sketch.veins):
        given = offsets[other] if other < len(offsets) else None
        if other == vein or given is None or not len(start):
            continue
        on, gap = nearest_on_polyline(path, start[0, :2])
        if gap <= reach and np.linalg.norm(start[0, :2] - path[0, :2]) > reach:
            offsets[other] = np.concatenate([given[:1] + rise(on, start[0, :2]), given[1:]])


def own(sketch: Sketch, vein: int, heights: np.ndarray) -> Sketch:
    """The sketch with vein `vein`'s control points at (m,) `heights`, its own (no offsets: the
    spline through them, off the dome). A vein profile is so: linear along the vein, where as
    offsets it ran over the dome between its points (set 0 to 0, the clicked midrib stood up to
    0.0077 high; review)."""
    veins, offsets = list(sketch.veins), list(sketch.offsets)
    veins[vein] = np.column_stack([veins[vein][:, :2], np.asarray(heights, dtype=float)])
    offsets[vein] = None
    return rebranched(sketch, replace(sketch, veins=tuple(veins), offsets=tuple(offsets)), vein)


def rebranched(before: Sketch, after: Sketch, vein: int) -> Sketch:
    """`after` (`before` with vein `vein` changed in shape or made its own) with each drawn vein
    started on its curve (within BRANCH_REACH, not where it starts) raised or lowered at its
    first point as the curve was there, so the two still meet (`carried` does so for a change
    of heights alone): a raised midrib point deleted left the side veins started there 0.018
    of the size above it (review)."""
    offsets, now = list(after.offsets), after.vein_curve(vein)

    def rise(was: np.ndarray, start: np.ndarray) -> float:
        return float(nearest_on_polyline(now, start)[0][2] - was[2])

    _lift_branches(before, vein, before.vein_curve(vein), rise, offsets)
    return replace(after, offsets=tuple(offsets))


def blended(offsets: np.ndarray, per_span: int) -> np.ndarray:
    """(s,) offsets along a curve of `per_span` samples a span: between two control points,
    their (m,) offsets joined by a smoothstep, 3u^2 - 2u^3 of the span's parameter u. Local, as a
    nudge should be (a natural spline through them moved every span, the next ones by about a
    quarter), and C1: no crease at a control point, where its slope is 0."""
    if len(offsets) < 2:
        return np.array(offsets, dtype=float)
    u = np.arange(per_span) / per_span
    rise = u * u * (3.0 - 2.0 * u)
    steps = offsets[:-1, None] + np.diff(offsets)[:, None] * rise
    return np.append(steps.ravel(), offsets[-1])


def stored_offsets(data: dict[str, Any]) -> list[np.ndarray | None]:
    """Per vein of a project's "sketch" (Sketch.to_dict), its offsets: "offsets", a list (or
    null) a vein, as written (JSON keeps floats exactly, so a project opens to the heights it
    was saved with); else "auto" (before offsets: on, a vein on the dome, offsets 0; off, its
    heights its own); else none (older projects: every vein keeps its heights). Tolerant as
    from_dict is: a vein past the list keeps its heights, and a list of offsets not one a point
    is taken from the vein's stored heights (Sketch: `on_dome`).

    Raises
    ------
    ValueError
        If "offsets" is not a list of lists of numbers (or nulls), or "auto" not a list of true
        or false.
    """
    veins = data.get("veins", [])
    if "offsets" not in data:
        auto = data.get("auto", [])
        if not isinstance(auto, list) or not all(isinstance(a, bool) for a in auto):
            raise ValueError(f'"auto" must be a list of true or false, got {auto!r:.40}')
        flags = [i < len(auto) and auto[i] for i in range(len(veins))]
        return [np.zeros(len(v)) if on else None for v, on in zip(veins, flags, strict=True)]
    stored = data["offsets"]
    number = lambda o: isinstance(o, int | float) and not isinstance(o, bool)  # noqa: E731
    if not isinstance(stored, list) or not all(
        o is None or (isinstance(o, list) and all(map(number, o))) for o in stored
    ):
        raise ValueError(f'"offsets" must be a list of lists of numbers, got {stored!r:.40}')
    stored = stored[: len(veins)] + [None] * (len(veins) - len(stored))
    return [None if o is None else np.asarray(o, dtype=float) for o in stored]


def default_height(sketch: Sketch, vein: int, xy: np.ndarray) -> float:
    """Height for a new point of vein `vein` (any index past the last: a new vein) at plane
    point `xy`. A drawn vein's: the dome's there plus its nearest control point's offset, held
    as below (an auto vein's: the dome's). Else that of the vein's nearest control point, else
    (a new vein) 5% of the sketch's size. On a drawn leaf (its margin on the plane) a
    point stands no higher or lower than HEIGHT_RATIO times its distance inside the outline
    (forms/veins.py: the roof relief's slope, 14°): the surface comes down to the margin, and
    the app's drawn leaf (every point at 5%) had vein points 0.019 of its length off the
    surface. A vein's only point held down so (a midrib started by the base) passes on the
    5%, not its own height (the whole midrib stood 0.007 high)."""
    xy = np.asarray(xy, dtype=float)
    ours = 0 <= vein < len(sketch.veins)
    control = sketch.veins[vein] if ours else np.zeros((0, 3))
    offsets = sketch.offsets[vein] if ours else None
    if offsets is not None:
        offset = 0.0
        if len(control):
            offset = float(offsets[np.argmin(np.linalg.norm(control[:, :2] - xy, axis=1))])
            cap = _margin_cap(sketch, xy)
            offset = offset if cap is None else float(np.sign(offset) * min(abs(offset), cap))
        return float(dome_at(sketch, xy[None, :2])[0]) + offset
    level = 0.05 * sketch.extent()
    height = level
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
