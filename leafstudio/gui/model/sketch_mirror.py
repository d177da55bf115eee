"""Mirror editing of a drawn leaf: the sketch made symmetric about its midrib, followed along
its curve (gui/model/midrib.py), and where a mirror image would fold over itself instead. The
Sketch's `mirrored` and `mirror_fold` (sketch_model.py) call these, and its `mirror_edit`
chooses between them. No Qt.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from leafstudio.gui.model.curves import closed_curve, open_curve

if TYPE_CHECKING:
    from leafstudio.gui.model.sketch_model import Sketch

FOLD_REACH = 1.0  # a mirror image this far into a bend (in radii of curvature) is folded over
FOLD_SAMPLES = 4  # curve points per span where a fold is looked for (it runs on every drag move)


@dataclass(frozen=True)
class MirrorFold:
    """Where a mirror image would fold: the midrib bends more tightly than the leaf is wide.

    where : (2,) plane point on the midrib; radius : its radius of curvature there; reach : how
    far from the midrib the half being mirrored reaches there (more than `radius`).
    """

    where: tuple[float, float]
    radius: float
    reach: float

    def message(self) -> str:
        """What the editor tells the user (the edit itself is kept, not mirrored)."""
        x, y = self.where
        return (
            f"Not mirrored: the midrib bends with a radius of {self.radius:.3g} near "
            f"({x:.3g}, {y:.3g}), less than the {self.reach:.3g} the leaf reaches from it there, "
            "so the mirror half would fold over itself. Bend the midrib less or narrow the leaf "
            "there; Mirror resumes with the next edit that fits."
        )


def mirror_fold(sketch: Sketch, source_side: float) -> MirrorFold | None:
    """Where mirroring from `source_side` would fold (see MirrorFold), or None. Checked on
    the curves that `mirrored` reflects (the boundary curve on that side and the side
    veins there, as spline samples, so a bend between two control points is seen): a
    point whose image would reach the centre of the midrib's curvature (1 - d kappa <= 0
    on the inside of the bend, gui/model/midrib.py) folds. One pass over all the points."""
    midrib = sketch.midrib()
    if midrib is None:
        return None
    outline = closed_curve(sketch.boundary, FOLD_SAMPLES) if len(sketch.boundary) >= 3 else []
    outline = np.asarray(outline, dtype=float).reshape(-1, 2)
    side_veins = range(1, len(sketch.veins))
    controls = [sketch.veins[i][:, :2] for i in side_veins]
    curves = [open_curve(sketch.veins[i], FOLD_SAMPLES)[:, :2] for i in side_veins]
    points = np.vstack([outline.reshape(-1, 2), *controls, *curves])
    if not len(points):
        return None
    reach, offset, feet = midrib.mirror_reach(points)
    eps = 1e-9 * sketch.extent()
    mirrored = np.zeros(len(points), dtype=bool)
    mirrored[: len(outline)] = offset[: len(outline)] * source_side > eps
    starts = np.cumsum([len(outline), *map(len, controls), *map(len, curves)])
    for k in range(len(controls)):  # a side vein goes over whole, by its points' mean side
        if float(np.mean(offset[starts[k] : starts[k + 1]])) * source_side > eps:
            at = len(controls) + k
            mirrored[starts[at] : starts[at + 1]] = True
    reach = np.where(mirrored, reach, -np.inf)
    worst = int(np.argmax(reach))
    if reach[worst] < FOLD_REACH:
        return None
    radius = float(-offset[worst] / reach[worst])
    return MirrorFold(tuple(map(float, feet[worst])), radius, abs(float(offset[worst])))


def mirrored(sketch: Sketch, source_side: float) -> Sketch:
    """The sketch made symmetric about the midrib (vein 1, followed along its curve, see
    gui/model/midrib.py): the half of the boundary on `source_side` (+1: left of the midrib,
    -1: right) is kept and reflected onto the other, and each side vein there replaces its
    nearest counterpart on the other side (or gains one). Unchanged without a midrib of
    two points or more."""
    midrib = sketch.midrib()
    if midrib is None:
        return sketch
    side = lambda points: midrib.offset(points) * source_side  # noqa: E731
    reflect = midrib.reflect

    boundary = sketch.boundary
    eps = 1e-9 * sketch.extent()
    keep = side(boundary) > eps
    if 0 < keep.sum() < len(boundary):
        start = int(np.flatnonzero(keep & ~np.roll(keep, 1))[0])  # where the kept arc begins
        order = np.roll(np.arange(len(boundary)), -start)
        loop, kept = boundary[order], keep[order]
        arc = loop[kept]
        axis_at = np.flatnonzero(np.abs(side(loop)) <= eps)
        last_kept = int(np.flatnonzero(kept)[-1])
        after = loop[[i for i in axis_at if i > last_kept][:1]]  # where the arc meets the axis
        before = loop[[i for i in axis_at if i > last_kept][-1:]] if len(axis_at) > 1 else []
        before = np.asarray(before).reshape(-1, 2)
        if len(before) and len(after) and np.allclose(before, after):
            before = before[:0]
        boundary = np.vstack([arc, after, reflect(arc)[::-1], before])
        boundary = boundary.reshape(-1, 2)
    veins, offsets = list(sketch.veins), list(sketch.offsets)
    sides = [float(np.mean(side(v))) for v in veins]
    targets = [i for i in range(1, len(veins)) if sides[i] < -eps]
    for i in range(1, len(sketch.veins)):
        if sides[i] <= eps:
            continue
        mirror = reflect(sketch.veins[i])
        if targets:
            j = min(targets, key=lambda t: float(np.linalg.norm(veins[t][0, :2] - mirror[0, :2])))
            targets.remove(j)
            veins[j], offsets[j] = mirror, sketch.offsets[i]
        else:
            veins.append(mirror)
            offsets.append(sketch.offsets[i])
    for j in sorted(targets, reverse=True):
        del veins[j], offsets[j]
    return replace(sketch, boundary=boundary, veins=tuple(veins), offsets=tuple(offsets))
