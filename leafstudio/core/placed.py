"""A pose placed on a leaf's own blade: a drawn or loaded leaf bent in the app (issue 21, build
item 6).

`bend.Pose` works in the blade's coordinates (the base at the origin, the midrib along +x, the
relief on +z), which are a form's world coordinates. A drawn leaf lies anywhere, its midrib any
way round: `PlacedPose` carries the pose's `frame` with it (origin at the midrib's base, u along
the midrib, v across it, the normal the relief's side), maps points into that frame, poses them
and maps them back. It is a `model.Bend`, so the pipeline flattens and bends it as a form's.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from leafstudio.core.bend import Pose
from leafstudio.core.bent_curvature import Jet, affine_jet
from leafstudio.core.plane import Frame, fit_frame
from leafstudio.core.prepare.vein_order import midrib_turned
from leafstudio.model import Leaf


@dataclass(frozen=True, eq=False)
class PlacedPose:
    """`pose` in the blade coordinates `frame` (world points to blade points and back)."""

    pose: Pose
    frame: Frame

    def _blade(self, points: np.ndarray) -> np.ndarray:
        xy, z = self.frame.to_plane(points)
        return np.column_stack([xy, z])

    def _world(self, blade: np.ndarray) -> np.ndarray:
        return self.frame.to_world(blade[:, :2], blade[:, 2])

    def apply(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) flat blade points, bent."""
        return self._world(self.pose.apply(self._blade(points)))

    def carry_jet(self, jet: Jet) -> Jet:
        """A jet of flat points, bent (Pose.carry_jet, in the pose's frame)."""
        return affine_jet(self._world, self.pose.carry_jet(affine_jet(self._blade, jet)))

    def flatten(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) bent points back on the flat blade (the inverse of `apply`)."""
        return self._world(self.pose.flatten(self._blade(points)))

    def flat_curve(self, points: np.ndarray, ring: bool = False) -> np.ndarray:
        """`flatten` for a curve's (n, 3) points in order along it (`ring`: closed), a rolled
        tube's points near its seam kept on their side (`Pose.flat_curve`)."""
        return self._world(self.pose.flat_curve(self._blade(points), ring))

    def unseam(self, flat: np.ndarray, ring: bool = False) -> np.ndarray:
        """A curve's (n, 3) flattened points with those near a rolled tube's seam on their side
        (`Pose.unseam`, in the pose's frame)."""
        return self._world(self.pose.unseam(self._blade(flat), ring))

    def trim(self, points: np.ndarray) -> None:
        """A pose cuts nothing out of the blade (model.Bend.trim)."""
        return None

    def on_midrib(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) flat points moved to the midrib's height over the blade (`Pose.on_midrib`, in
        the pose's frame)."""
        return self._world(self.pose.on_midrib(self._blade(points)))

    def off_hinge(self, points: np.ndarray) -> np.ndarray:
        """(n,) heights of flat points over the pose's hinge (`Pose.off_hinge`, in its frame)."""
        return self.pose.off_hinge(self._blade(points))

    def key(self) -> bytes:
        """Bytes that change with the pose or its frame (Leaf.fingerprint)."""
        f = self.frame
        return self.pose.key() + np.concatenate([f.origin, f.u, f.v, f.normal]).tobytes()

    def crease(self, points: np.ndarray) -> np.ndarray | None:
        """(n,) signed distances of flat points from the pose's crease (the midrib), or None."""
        return self.pose.crease(self._blade(points))

    def crease_side(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """The pose's (Pose.crease_side), its vectors in the world."""
        side = self.pose.crease_side(self._blade(points))
        if side is None:
            return None
        f = self.frame
        return side[0], side[1] @ np.array([f.u, f.v, f.normal])

    def sag_tolerance(self, extent: float) -> float:
        """The pose's (Pose.sag_tolerance): its frame keeps lengths."""
        return self.pose.sag_tolerance(extent)


def blade_frame(leaf: Leaf, plane: Frame | None = None) -> Frame:
    """The blade coordinates of a flat `leaf` on `plane` (default: its boundary's PCA plane): the
    origin at the base of its first vein (the midrib), u along that vein's chord from base to
    tip; without veins, the base is the boundary's end farthest back along the plane's u."""
    if plane is None:
        plane = fit_frame(leaf.boundary, leaf.vein_points)
    xy = plane.to_plane(leaf.boundary)[0]
    midrib = leaf.veins[0] if leaf.veins else None
    if midrib is not None and midrib_turned(list(leaf.veins)):
        midrib = midrib[::-1]  # written apex first: its base is its last point (blade_midrib)
    if midrib is not None and len(midrib) > 1:
        ends = plane.to_plane(midrib[[0, -1]])[0]
        chord = ends[1] - ends[0]
    else:
        chord = np.zeros(2)
    if np.linalg.norm(chord) <= 1e-9 * max(float(np.ptp(xy, axis=0).max()), 1e-300):
        ends = np.array([[xy[:, 0].min(), 0.0], [xy[:, 0].max(), 0.0]])
        chord = np.array([1.0, 0.0])
    along = chord / np.linalg.norm(chord)
    u = along[0] * plane.u + along[1] * plane.v
    origin = plane.to_world(ends[:1], np.zeros(1))[0]
    return Frame(origin=origin, u=u, v=np.cross(plane.normal, u), normal=plane.normal)


def fitted(bend: Any) -> bool:
    """Whether `bend` is a pose fitted to curves in 3D about its midrib (core/unfold.py): a
    PlacedPose whose relief says its sheet is the margin's plane (Relief.on_margin, set by
    margin_relief). Read off the means, a drawn blade with a flat midrib curled 0.5 was one,
    and its apex dragged 30% out, it read a curl of 0.575 (test_bending)."""
    relief = getattr(getattr(bend, "pose", None), "relief", None)
    return isinstance(bend, PlacedPose) and relief is not None and relief.on_margin
