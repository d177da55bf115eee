"""A bent leaf's result: the flat blade's run carried into 3D by its bend (issue 21, build
item 1; core/bend.py has the bends): the mesh bent once, at unit size, its sag halvings put on
the flat surface, and the result measured against the bent leaf."""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from leafstudio.core.bend import Pose
from leafstudio.core.bent_curvature import Jet, jet_of
from leafstudio.core.bent_mesh import BentBy, Lift, bent_mesh
from leafstudio.model import Leaf

if TYPE_CHECKING:
    from leafstudio.core.pipeline import Result
    from leafstudio.core.prepare.units import Units


def _onto_surface(result: Result) -> Lift:
    """A function taking (n, 3) points of the flat run's mesh onto its surface along the
    plane's normal: the points, their heights and their jets (sag_splits' new points, on the
    surface, not on the flat mesh's chord, which the bend stretches: up to 3 times on a folded
    tube; their jets interpolated along the edge moved a crease's curvatures 5% with the leaf's
    size, where the halvings differ); those flagged in the (n,) bool `margin`, on the outline,
    the surface's limits from inside, as the mesh's own outline points have them."""
    frame, surface = result.frame, result.surface

    def lift(points: np.ndarray, margin: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        xy = frame.to_plane(points)[0]
        z, grad, hess = surface.derivatives(xy, margin)
        return frame.to_world(xy, z), z, jet_of(grad, hess)

    return lift


def bent_result(result: Result, leaf: Leaf, units: Units) -> Result:
    """The flat blade's `result` (its leaf the flat blade, kept as `Result.blade`) carried into
    3D by `leaf.bend`, measured against `leaf` (its unit-size run as well, through `units`);
    `result` itself when the leaf has no bend. The mesh is bent once, at unit size, and put in
    the input's units as in_world puts every run's (bent at both sizes, the cuts, the carry and
    the halvings' lift ran twice: a quarter of a bent run's time over the flat one's)."""
    bend = leaf.bend
    if bend is None:
        return result
    sag = getattr(bend, "sag_tolerance", None)
    # a pose's chords are kept on it (`sag`); a scan's sheet (core/sheet.py) has none: its fit is
    # at the scanner's noise (0.5% of the length), and halving the edges its spline's relief
    # curves gave soybean pot1_1 30 times the faces for 0.04% of the length
    carry_jet = getattr(bend, "carry_jet", None)  # a pose's; a scan's sheet is differenced
    carry = getattr(bend, "carry", bend.apply)  # a pose's apply in one kernel (bend.Pose.carry)
    unit = result.unit
    if unit is None:  # a run at its own size
        lift = None if sag is None else _onto_surface(result)
        by = BentBy(carry, bend.crease, bend.trim, result.frame, carry_jet)
        mesh, flat, outline = bent_mesh(result.triangle_mesh, by, sag, lift, len(result.polygon))
        return replace(
            result,
            leaf=leaf,
            blade=result.leaf,
            surface_points=carry(result.surface_points),
            triangle_mesh=mesh,
            blade_xy=result.frame.to_plane(flat)[0],
            outline_points=outline,
        )

    def in_units(points: np.ndarray) -> np.ndarray:
        if isinstance(bend, Pose):  # in its kernel (Pose.carry)
            return bend.carry(points, units)
        return units.to_unit(carry(units.to_world(points)))

    def jet_in_units(jet: Jet) -> Jet:
        if isinstance(bend, Pose):
            return bend.carry_jet(jet, units)
        # the units' linear part is their scale: the derivatives scaled, not moved and moved
        # back (bent_curvature.affine_jet: 0.9 ms for a grid-128 mesh's 7,500 jets, this 0.2)
        points, d = jet
        bent, derivatives = bend.carry_jet((units.to_world(points), d * units.scale))
        return units.to_unit(bent), derivatives / units.scale

    mesh, flat, outline = bent_mesh(
        unit.triangle_mesh,
        BentBy(
            in_units,
            lambda points: bend.crease(units.to_world(points)),
            lambda points: bend.trim(units.to_world(points)),
            unit.frame,
            None if carry_jet is None else jet_in_units,
        ),
        None if sag is None else lambda extent: sag(extent * units.scale) / units.scale,
        None if sag is None else _onto_surface(unit),
        len(unit.polygon),
    )
    surface_points = in_units(unit.surface_points)
    unit = replace(
        unit,
        leaf=units.leaf(leaf),
        surface_points=surface_points,
        triangle_mesh=mesh,
        blade_xy=unit.frame.to_plane(flat)[0],
        outline_points=outline,
    )
    return replace(
        result,
        leaf=leaf,
        blade=result.leaf,
        surface_points=units.to_world(surface_points),
        triangle_mesh=units.mesh(mesh),
        unit=unit,
        blade_xy=result.frame.to_plane(units.to_world(flat))[0],
        outline_points=outline,
    )
