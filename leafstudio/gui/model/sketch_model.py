"""The sketch behind a drawn leaf: control points on the leaf plane, and the curves through them.

A sketch is an immutable snapshot, so undo and redo simply swap snapshots. The boundary is a closed
curve (a periodic cubic spline through its control points); each vein is an open curve through its
control points, each carrying a height above the plane; the splines are curves.py's. A vein
drawn on a drawn leaf stands on the dome over the outline, raised or lowered by offsets its
heights set by hand give it (sketch_dome.py); mirror editing is sketch_mirror.py's. No Qt
here: the editor in gui/qt/sketch.py draws it.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from leafstudio.core.bend import flat_leaf
from leafstudio.core.evaluate import view_frame
from leafstudio.core.plane import Frame
from leafstudio.core.sheet_bend import Scaled
from leafstudio.gui.model import sketch_dome as dome
from leafstudio.gui.model import sketch_mirror as mirror
from leafstudio.gui.model.curves import (
    SAMPLES_PER_SPAN,
    closed_curve,
    even_by_length,
    insert_index,
    nearest_on_polyline,
    outline_controls,
    plane_arc_lengths,
)
from leafstudio.gui.model.midrib import Midrib
from leafstudio.gui.model.sketch_mirror import MirrorFold
from leafstudio.gui.model.thinning import thinned
from leafstudio.model import Leaf
from leafstudio.sources.sketch_entry import sketch_plane, world_frame

BOUNDARY = -1  # curve index of the boundary; veins are 0, 1, ...
DERIVED_VEIN_POINTS = 8
RELIEF_POINTS = 4000  # a derived sketch keeps at most this many boundary points as its relief
OUTLINE_POINTS = 4000  # and follows at most this many of the outline's
RELIEF_NEIGHBOURS = 4  # a boundary point's height: inverse-distance mean of this many relief points


@dataclass(frozen=True, eq=False)
class Sketch:
    """Control points of a leaf drawn on a plane.

    Parameters
    ----------
    boundary : (n, 2) float array
        Boundary control points, in order around the leaf.
    veins : tuple of (m_i, 3) float arrays
        Per vein, its control points in order: x, y and the height above the plane.
    frame : Frame
        The plane the sketch lies on, mapping it to world coordinates.
    relief : (p, 3) float array
        x, y and height of a loaded leaf's boundary points (a scan's margin curls off the plane):
        the boundary curve takes its heights from the nearest of them, wherever its control points
        are moved. Empty for a drawn leaf, whose boundary lies on the plane.
    symmetric : bool
        Mirror editing is on: each edit is reflected across the midrib (`mirrored`). A property
        of the drawing, saved with it (a project's "sketch" without it: off).
    offsets : tuple of (m_i,) float arrays or None
        Per vein drawn on a drawn leaf, its control points' heights above the dome over the
        outline (sketch_dome.py), which make its curve and `veins`' heights. None (and missing):
        heights of its own (a loaded leaf's, always; grown veins; projects written before).
    bend : Bend or None
        A scan's sheet (core/sheet_bend.Scaled) the sketch's leaf was derived from, kept by the
        leaves it draws (not saved with the sketch: the project keeps the leaf's). A pose is the
        session's (gui/model/bending.py).
    """

    boundary: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    veins: tuple[np.ndarray, ...] = ()
    frame: Frame = field(default_factory=world_frame)
    relief: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    symmetric: bool = False
    offsets: tuple[np.ndarray | None, ...] = ()
    bend: Any = None

    def __post_init__(self) -> None:
        boundary = np.asarray(self.boundary, dtype=float).reshape(-1, 2)
        veins = tuple(np.asarray(v, dtype=float).reshape(-1, 3) for v in self.veins)
        object.__setattr__(self, "boundary", boundary)
        object.__setattr__(self, "relief", np.asarray(self.relief, dtype=float).reshape(-1, 3))
        object.__setattr__(self, "veins", veins)  # on_dome reads the outline and midrib's base
        veins, offsets = dome.on_dome(self, veins, self.offsets)
        object.__setattr__(self, "veins", veins)
        object.__setattr__(self, "offsets", offsets)

    @property
    def auto(self) -> tuple[bool, ...]:
        """Per vein, on the dome over a drawn leaf's outline (offsets, all 0)."""
        return tuple(o is not None and not np.any(o) for o in self.offsets)

    # --- reading -------------------------------------------------------------------------------
    def control(self, curve: int) -> np.ndarray:
        """Control points of a curve: (n, 2) for the boundary, (m, 3) for vein `curve`."""
        return self.boundary if curve == BOUNDARY else self.veins[curve]

    def boundary_curve(self) -> np.ndarray:
        """(s, 2) points along the closed boundary curve (empty below 3 control points); made
        once per sketch, read-only, as vein_curve's."""
        return self._curve(BOUNDARY)

    def vein_curve(self, index: int) -> np.ndarray:
        """(s, 3) points along vein `index`: x, y, height. Made once per sketch (which never
        changes), read-only: the editor, its profile and the session ask for each curve several
        times an edit (a scan's derived sketch: 3.6 ms of splines on the main thread)."""
        return self._curve(index)

    def _curve(self, curve: int) -> np.ndarray:
        made = self.__dict__.setdefault("_curves", {})  # frozen: no attribute set but this
        if curve not in made:
            if curve != BOUNDARY:
                points = dome.vein_curve(self, curve)  # a copy: never a vein's own
            elif len(self.boundary) >= 3:
                points = np.array(closed_curve(self.boundary))
            else:
                points = np.zeros((0, 2))
            points.setflags(write=False)
            made[curve] = points
        return made[curve]

    def to_leaf(self) -> Leaf | None:
        """The leaf this sketch draws, in world coordinates; None below 3 boundary points."""
        outline = self.boundary_curve()
        if len(outline) < 3:
            return None
        boundary = self.frame.to_world(outline, self.boundary_heights(outline))
        veins = []
        for i, vein in enumerate(self.veins):
            if len(vein):
                curve = self.vein_curve(i)
                veins.append(self.frame.to_world(curve[:, :2], curve[:, 2]))
        if self.bend is None:
            return Leaf(boundary=boundary, veins=veins)
        bent = getattr(self.bend, "bent", self.bend.apply)  # a sheet remembers what it bent
        return Leaf(boundary=bent(boundary), veins=[bent(v) for v in veins], bend=self.bend)

    def boundary_heights(self, xy: np.ndarray) -> np.ndarray:
        """(s,) heights of (s, 2) plane points on the boundary, from the relief (0 without)."""
        if len(self.relief) == 0:
            return np.zeros(len(xy))
        k = min(RELIEF_NEIGHBOURS, len(self.relief))
        dist, index = cKDTree(self.relief[:, :2]).query(xy, k=k)
        dist, index = dist.reshape(len(xy), k), index.reshape(len(xy), k)
        weight = 1.0 / np.maximum(dist, 1e-12 * self.extent()) ** 2
        return np.sum(weight * self.relief[index, 2], axis=1) / weight.sum(axis=1)

    def extent(self) -> float:
        """Largest side of the control points' box (1 for an empty sketch)."""
        points = np.vstack([self.boundary, *(v[:, :2] for v in self.veins)])
        size = float(np.ptp(points, axis=0).max()) if len(points) > 1 else 0.0
        return size if size > 0 else 1.0

    # --- editing: each returns a new sketch ---------------------------------------------------
    def _with_curve(
        self, curve: int, control: np.ndarray, offsets: np.ndarray | None = None
    ) -> Sketch:
        """A drawn vein's `offsets` for its new `control` points: by default from their heights
        (over this sketch's dome: a point whose height is as it was keeps its offset)."""
        if curve == BOUNDARY:
            return replace(self, boundary=control)
        veins, kept = list(self.veins), self.offsets
        veins[curve] = control
        if kept[curve] is not None:  # a drawn vein's, and those of the veins started on it
            kept = dome.carried(self, curve, control, offsets)
        return replace(self, veins=tuple(veins), offsets=kept)

    def moved(self, curve: int, index: int, xy: np.ndarray) -> Sketch:
        """The sketch with one control point moved to plane point `xy`."""
        control = self.control(curve).copy()
        control[index, :2] = xy
        return self._with_curve(curve, control, self._offsets(curve))

    def _offsets(self, curve: int) -> np.ndarray | None:
        return None if curve == BOUNDARY else self.offsets[curve]  # a drawn vein's, else None

    def inserted(self, curve: int, xy: np.ndarray, height: float = 0.0) -> tuple[Sketch, int]:
        """The sketch with a control point added where it fits best, and the point's index."""
        control = self.control(curve)
        index = insert_index(control, np.asarray(xy, dtype=float), closed=curve == BOUNDARY)
        row = np.asarray(xy, dtype=float) if curve == BOUNDARY else np.array([*xy, height])
        offsets = self._offsets(curve)
        if offsets is not None:  # the new point's offset; the others keep theirs
            offsets = np.insert(offsets, index, dome.offsets_of(self, row[None, :]))
        return self._with_curve(curve, np.insert(control, index, row, axis=0), offsets), index

    def deleted(self, curve: int, index: int) -> Sketch:
        """The sketch without one control point; a vein left without points goes (veins keep
        their numbers and colours only if no empty one is kept)."""
        control, offsets = np.delete(self.control(curve), index, axis=0), self._offsets(curve)
        if curve != BOUNDARY and len(control) == 0:
            veins, kept = self.veins[:curve] + self.veins[curve + 1 :], self.offsets
            return replace(self, veins=veins, offsets=(*kept[:curve], *kept[curve + 1 :]))
        kept = None if offsets is None else np.delete(offsets, index)
        after = self._with_curve(curve, control, kept)  # veins started on a drawn one follow it
        return after if kept is None else dome.rebranched(self, after, curve)

    def with_height(self, vein: int, index: int, height: float) -> Sketch:
        """The sketch with a vein control point's height set by hand: a drawn vein's offset
        there (its others, and its curve beyond its neighbouring points, stay as they were)."""
        control, offsets = self.veins[vein].copy(), self.offsets[vein]
        control[index, 2] = height
        if offsets is not None:
            offsets = offsets.copy()
            offsets[index] = dome.offsets_of(self, control[index : index + 1])[0]
        return self._with_curve(vein, control, offsets)

    def with_vein(self, points: np.ndarray, offsets: np.ndarray | None = None) -> Sketch:
        """The sketch with a vein of (m, 3) control points appended (index len(veins) - 1);
        with (m,) `offsets`, a drawn vein, its heights the dome's plus them (see `offsets`)."""
        vein = np.asarray(points, dtype=float).reshape(-1, 3)
        return replace(self, veins=(*self.veins, vein), offsets=(*self.offsets, offsets))

    def started_vein(self, xy: np.ndarray, tolerance: float) -> Sketch:
        """The sketch with a new vein started at plane point `xy`, as a click makes it: snapped
        onto a vein within `tolerance` (it branches there, at that vein's height) or at the
        default height. On a drawn leaf it is drawn (on the dome, at the offset there of a
        drawn vein it branches from), unless it branches from a vein with heights of its own."""
        xy = np.asarray(xy, dtype=float)
        snapped = self._snap(xy, tolerance)
        if snapped is None:
            return self.with_vein(np.array([[*xy, self.default_height(-1, xy)]]), np.zeros(1))
        point, vein = snapped
        return self.with_vein(point[None], dome.branch_offset(self, vein, point))

    def with_heights(self, vein: int, heights: np.ndarray) -> Sketch:
        """The sketch with a vein's control point heights set by hand ((m,); offsets if drawn)."""
        control = self.veins[vein].copy()
        control[:, 2] = np.asarray(heights, dtype=float).reshape(len(control))
        return self._with_curve(vein, control)

    def vein_fractions(self, vein: int) -> np.ndarray:
        """(m,) shares of vein `vein`'s length (along its curve, in the plane) at its control
        points: 0 at the first, 1 at the last (all 0 for a vein of no length)."""
        control = self.veins[vein]
        curve = self.vein_curve(vein)
        arc = plane_arc_lengths(curve)
        if len(control) < 2 or arc[-1] <= 0:
            return np.zeros(len(control))
        if len(curve) == (len(control) - 1) * SAMPLES_PER_SPAN + 1:  # control i is sample i*span
            at = arc[::SAMPLES_PER_SPAN]
        else:  # repeated control points were dropped from the curve: lengths along the polygon
            at = plane_arc_lengths(control)
        return at / at[-1]

    def with_profile(self, vein: int, start: float, end: float) -> Sketch:
        """The sketch with a whole vein's heights set at once: linear from `start` at its first
        point to `end` at its last, by length along the vein, its own (sketch_dome.own)."""
        return dome.own(self, vein, start + self.vein_fractions(vein) * (end - start))

    def snap_to_vein(self, xy: np.ndarray, tolerance: float) -> np.ndarray | None:
        """The point (x, y, height) on the nearest vein curve within `tolerance` of plane point
        `xy`, or None: a new vein started there branches from that vein."""
        snapped = self._snap(xy, tolerance)
        return None if snapped is None else snapped[0]

    def _snap(self, xy: np.ndarray, tolerance: float) -> tuple[np.ndarray, int] | None:
        """`snap_to_vein`'s point and the vein it lies on."""
        best, best_d, vein = None, tolerance, -1
        for i in range(len(self.veins)):
            point, d = nearest_on_polyline(self.vein_curve(i), xy)
            if d < best_d or (best is None and d <= best_d):  # a tie: the earlier vein's
                best, best_d, vein = point, d, i
        return None if best is None else (np.asarray(best, dtype=float), vein)

    def midrib(self) -> Midrib | None:
        """The midrib (vein 1) as mirror editing follows it, or None below two points (made
        once per sketch: a mirrored edit asks for it several times)."""
        return self._midrib

    @cached_property
    def _midrib(self) -> Midrib | None:
        if not self.veins or len(self.veins[0]) < 2:
            return None
        try:
            return Midrib(self.vein_curve(0)[:, :2])
        except ValueError:  # its points all in one place
            return None

    def midrib_side(self, xy: np.ndarray) -> float:
        """Signed offset of plane point `xy` from the midrib curve (+ left, - right; 0 without
        a midrib): the side an edit at `xy` was made on."""
        midrib = self.midrib()
        return 0.0 if midrib is None else float(midrib.offset(np.reshape(xy, (1, -1))[:, :2])[0])

    def mirror_fold(self, source_side: float) -> MirrorFold | None:
        """Where mirroring from `source_side` would fold, or None (sketch_mirror.mirror_fold)."""
        return mirror.mirror_fold(self, source_side)

    def mirror_edit(self, xy: np.ndarray) -> tuple[Sketch, MirrorFold | None]:
        """An edit at plane point `xy` with Mirror on: the sketch made symmetric from that side
        of the midrib, or, where the mirror would fold, the sketch as it is and the fold."""
        side = 1.0 if self.midrib_side(xy) >= 0 else -1.0
        fold = self.mirror_fold(side)
        return (self, fold) if fold is not None else (self.mirrored(side), None)

    def mirrored(self, source_side: float) -> Sketch:
        """The sketch made symmetric about the midrib from `source_side` (+1: left of it, -1:
        right; sketch_mirror.mirrored)."""
        return mirror.mirrored(self, source_side)

    def default_height(self, vein: int, xy: np.ndarray) -> float:
        """Height for a new point of vein `vein` (past the last: a new vein) at plane point
        `xy`: the dome's and its nearest point's offset, or by its nearest point (sketch_dome)."""
        return dome.default_height(self, vein, xy)

    # --- files ---------------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form, stored as a project's "sketch"."""
        return {
            "plane": {
                "origin": self.frame.origin.tolist(),
                "u": self.frame.u.tolist(),
                "v": self.frame.v.tolist(),
                "normal": self.frame.normal.tolist(),
            },
            "boundary": self.boundary.tolist(),
            "veins": [v.tolist() for v in self.veins],
            "relief": self.relief.tolist(),
            "symmetric": self.symmetric,
            "offsets": [None if o is None else o.tolist() for o in self.offsets],
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Sketch:
        """The sketch stored by `to_dict`.

        Raises
        ------
        ValueError
            If the stored arrays have the wrong shape, or "symmetric" is not true or false
            (absent, as in projects written before it: false), or "offsets" (or "auto") not
            as sketch_dome.stored_offsets reads them.
        """
        symmetric = data.get("symmetric", False)
        if not isinstance(symmetric, bool):
            raise ValueError(f'"symmetric" must be true or false, got {symmetric!r:.40}')
        frame = sketch_plane(data) or world_frame()
        veins = data.get("veins", [])
        kept, offsets = [i for i, v in enumerate(veins) if len(v)], dome.stored_offsets(data)
        return cls(
            boundary=np.asarray(data.get("boundary", []), dtype=float).reshape(-1, 2),
            veins=tuple(np.asarray(veins[i], dtype=float).reshape(-1, 3) for i in kept),
            frame=frame,
            relief=np.asarray(data.get("relief", []), dtype=float).reshape(-1, 3),
            symmetric=symmetric,
            offsets=tuple(offsets[i] for i in kept),
        )

    def hole_curves(self) -> list[np.ndarray]:
        """(k, 2) rings, on the sketch's plane, of the real holes of the scan its leaf came from
        (core/sheet_bend.Scaled.flat_holes): the mesh leaves them open, so the flat blade shows
        them."""
        rings = self.bend.flat_holes() if hasattr(self.bend, "flat_holes") else []
        return [self.frame.to_plane(r)[0] for r in rings]

    @classmethod
    def from_result(cls, result: Any) -> Sketch:
        """A sketch approximating a reconstructed leaf: control points spread along its outline
        and along each vein, on the leaf's own plane (the pipeline's frame, turned so that the
        midrib runs along u: evaluate.view_frame), the boundary's heights kept as its relief.
        A long outline (a 300,000-point boundary) is followed through OUTLINE_POINTS of its
        points and its relief kept at RELIEF_POINTS: the editor queries them on the main thread
        (thinning.py). Its curves are made with it."""
        leaf = flat_leaf(result.leaf)  # a bent leaf's flat blade: the sketch draws the blade
        frame = view_frame(result)
        outline = thinned(result.polygon, OUTLINE_POINTS, ordered=True)
        outline = frame.to_plane(result.frame.to_world(outline, np.zeros(len(outline))))[0]
        boundary = outline_controls(outline)
        relief = thinned(leaf.boundary, RELIEF_POINTS, ordered=True)
        relief = np.column_stack(frame.to_plane(relief))
        veins = []
        for vein in leaf.veins:
            xy, h = frame.to_plane(vein)
            points = np.column_stack([xy, h])
            veins.append(even_by_length(points, min(DERIVED_VEIN_POINTS, len(points)), False))
        sketch = cls(
            boundary=boundary,
            veins=tuple(veins),
            frame=frame,
            relief=relief,
            bend=result.leaf.bend if isinstance(result.leaf.bend, Scaled) else None,
        )
        for curve in (BOUNDARY, *range(len(veins))):
            sketch._curve(curve)  # made now: the worker derives it (Worker.derives), not the editor
        return sketch
