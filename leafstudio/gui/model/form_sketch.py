"""A form as the app edits it, without Qt: its blade grown (off the main thread), its editable
sketch (control points along its outline and veins), veins grown in a sketch's outline, and the
gallery's canonical leaves. The Forms dock (gui/qt/forms_dock.py) shows and forwards them.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from leafstudio.core.bend import flat_leaf
from leafstudio.core.plane import fit_frame
from leafstudio.core.prepare.polygon import ring_crossings
from leafstudio.forms import Form, grow_veins
from leafstudio.gui.model.curves import closed_curve
from leafstudio.gui.model.sketch_dome import midrib_base
from leafstudio.gui.model.sketch_model import Sketch
from leafstudio.model import Leaf

BOUNDARY_CONTROL = 48  # a form's sketch: about this many boundary control points, plus corners
CORNER_TURN = 0.35  # radians: outline points turning this sharply (tooth tips, notches) are kept
FLAT = 1e-12  # heights under this share of the outline's extent are none: a posed form's flat
# blade, laid flat again by its curl's circle, has margin heights of 1e-17
VEIN_CONTROL = 8


def grow_blade(form: Form) -> tuple[Form, Leaf, str, Sketch]:
    """`form` without its pose, its blade, side-on note (Form.blade_and_note) and the blade's
    sketch, which every pose of it shows: run on the worker's lane, off the main thread."""
    unposed = form.unposed()
    blade, side_on = unposed.blade_and_note()
    return unposed, blade, side_on, leaf_sketch(blade, unposed.teeth_count)


def canonical_leaves(shapes: list[str]) -> dict[str, Leaf]:
    """Each shape's canonical form with its veins (numpy and shapely only: a side job's work,
    50 ms a shape, 0.7 s for the gallery, which the window's first start waited for)."""
    return {shape: Form(shape).leaf() for shape in shapes}


def _turns(xy: np.ndarray) -> np.ndarray:
    a, b = xy - np.roll(xy, 1, axis=0), np.roll(xy, -1, axis=0) - xy
    return np.abs(np.arctan2(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0], (a * b).sum(axis=1)))


def leaf_sketch(leaf: Leaf, teeth: int = 0) -> Sketch:
    """An editable sketch of a leaf that lies in the z = 0 plane apart from its relief (a form):
    boundary control points spread along it with its corners (tooth tips and notches) kept, each
    vein's control points spread along it with their heights, the boundary's heights as relief.
    A posed form's sketch is its flat blade (the pose bends the 3D result only)."""
    leaf = flat_leaf(leaf)
    xy = leaf.boundary[:, :2]
    corners = np.flatnonzero(_turns(xy) > CORNER_TURN)
    count = max(BOUNDARY_CONTROL, 3 * teeth)
    while True:  # more control points until the curve through them does not cross itself
        even = np.unique(np.linspace(0, len(xy), count, endpoint=False).astype(int))
        boundary = xy[np.union1d(even, corners)]
        if count >= len(xy) or not len(ring_crossings(closed_curve(boundary))):
            break
        count *= 2
    veins = []
    for vein in leaf.veins:
        pick = np.unique(np.linspace(0, len(vein) - 1, min(VEIN_CONTROL, len(vein))).astype(int))
        veins.append(vein[pick])
    extent = float(np.ptp(leaf.boundary[:, :2], axis=0).max())
    raised = np.abs(leaf.boundary[:, 2]).max() > FLAT * extent
    relief = leaf.boundary if raised else np.zeros((0, 3))
    return Sketch(boundary=boundary, veins=tuple(veins), relief=relief)


def with_grown_veins(
    sketch: Sketch, venation: str, seed: int = 0, base: np.ndarray | None = None
) -> Sketch:
    """The sketch with its veins replaced by veins grown inside its boundary curve; the base is
    `base` (plane point), else the base of the sketch's first vein (its start, or its end when
    its side veins say it is written apex first: vein_order.midrib_turned), else found by
    grow_veins."""
    outline = sketch.boundary_curve()
    if base is None:
        base = midrib_base(sketch)
    veins = grow_veins(outline, venation, base=base, seed=seed)
    pick = [
        np.unique(np.linspace(0, len(v) - 1, min(VEIN_CONTROL, len(v))).astype(int)) for v in veins
    ]
    # replace, not a new Sketch: the boundary, frame, relief and the saved Mirror flag are kept;
    # the grown veins keep grow_veins' heights (not the replaced veins' auto flags)
    grown = tuple(v[p] for v, p in zip(veins, pick, strict=True))
    return replace(sketch, veins=grown, offsets=())


def outline_sketch(result: Any, leaf: Leaf) -> Sketch:
    """A loaded leaf's sketch to grow veins in (the Forms dock's Grow veins): from its shown
    `result` (None: none shown), else from the leaf itself on the plane of its boundary (its
    heights kept as relief)."""
    if result is not None and getattr(result, "leaf", None) is leaf:
        return Sketch.from_result(result)
    frame = fit_frame(leaf.boundary, leaf.vein_points)
    xy, h = frame.to_plane(leaf.boundary)
    pick = np.unique(np.linspace(0, len(xy), BOUNDARY_CONTROL, endpoint=False).astype(int))
    relief = np.column_stack([xy, h]) if np.any(np.abs(h) > 0) else np.zeros((0, 3))
    return Sketch(boundary=xy[pick], frame=frame, relief=relief)
