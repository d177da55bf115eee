"""A scan's sheet (core/sheet.py) as a Bend in the world's units: what the pipeline carries the
flat blade's mesh into 3D with (core/bend.py), and what a project keeps of it (sources/files.py).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
import shapely

from leafstudio.core.sheet import MIN_CELLS, Sheet


@dataclass(frozen=True, eq=False)
class Scaled:
    """`sheet`, fitted at unit size, as a Bend in the world's units: world = centre + scale ·
    unit, for the flat points and the bent ones alike.

    `flatten` is the nearest sheet point, found by Gauss-Newton; near a tight curl or the
    sheet's edge it can settle on another sheet point than the one a point was bent from, so
    the points this bend made (`bent`: the extraction's boundary and veins) are remembered and
    flattened exactly. `holes`: the blade's real holes (sources/scan_holes.py), (k, 2) rings in
    the sheet's (u, v), which `trim` cuts out of the mesh."""

    sheet: Sheet
    centre: np.ndarray
    scale: float
    made: dict = field(default_factory=dict, repr=False)
    holes: tuple[np.ndarray, ...] = ()
    # the flat blade lies on the world's x-y plane, however the scan was turned, not on the
    # leaf's own (a pose's blade frame): its projected area is taken face-on (evaluate.facing_area)
    own_plane: ClassVar[bool] = False

    def bent(self, points: np.ndarray) -> np.ndarray:
        """`apply`, remembering each bent point's flat one for `flatten`."""
        points = np.asarray(points, dtype=float)
        bent = self.apply(points)
        self.made.update(zip(map(bytes, bent), points, strict=True))
        return bent

    def apply(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) flat blade points, bent (`Sheet.apply`)."""
        return self.centre + self.scale * self.sheet.apply((points - self.centre) / self.scale)

    def flatten(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) bent points back on the flat blade (`Sheet.flatten`)."""
        points = np.asarray(points, dtype=float)
        known = np.array([bytes(p) in self.made for p in points], dtype=bool)
        flat = np.empty_like(points)
        if known.any():
            flat[known] = [self.made[bytes(p)] for p in points[known]]
        if not known.all():
            unit = (points[~known] - self.centre) / self.scale
            flat[~known] = self.centre + self.scale * self.sheet.flatten(unit)
        return flat

    def key(self) -> bytes:
        """Bytes that change with the bend."""
        rings = b"".join(np.asarray(r, dtype=float).tobytes() + b"|" for r in self.holes)
        return self.sheet.key() + np.append(self.centre, self.scale).tobytes() + rings

    def trim(self, points: np.ndarray) -> np.ndarray | None:
        """(n,) signed distances of (n, 3) flat blade points from the holes' edges, negative
        inside a hole (core/bend.py cuts the mesh there and drops what is inside), or None when
        the blade has none."""
        if not self.holes:
            return None
        uv = (np.asarray(points, dtype=float)[:, :2] - self.centre[:2]) / self.scale
        # one polygon per ring: shapely.polygons(list) stacks them, so rings of different
        # lengths failed ("inhomogeneous shape")
        cut = shapely.union_all([shapely.Polygon(r) for r in self.holes])
        distance = shapely.distance(shapely.boundary(cut), shapely.points(uv))
        inside = shapely.contains_xy(cut, uv[:, 0], uv[:, 1])
        return self.scale * np.where(inside, -distance, distance)

    def flat_holes(self) -> list[np.ndarray]:
        """(k, 3) rings of the holes on the flat blade, in the world's units (what `trim` cuts
        out of the mesh; the app's sketch of the flat blade shows them)."""
        return [self.centre + self.scale * np.pad(np.asarray(r, dtype=float), ((0, 0), (0, 1)))
                for r in self.holes]  # fmt: skip

    def entry(self, points: np.ndarray) -> dict:
        """The bend as a project keeps it (sources/files.py): the sheet, and the flat points of
        the (n, 3) bent `points` (the leaf's boundary and veins, stacked)."""
        sheet = self.sheet
        return {
            "sheet": {
                "centers": sheet.centers.tolist(),
                "values": sheet.values.tolist(),
                "smoothing": np.asarray(sheet.smoothing, dtype=float).tolist(),
                "up": sheet.up.tolist(),
                "centre": self.centre.tolist(),
                "scale": self.scale,
                "flat": self.flatten(points).tolist(),
                "holes": [np.asarray(r).tolist() for r in self.holes],
            }
        }

    @classmethod
    def from_entry(cls, entry: dict, points: np.ndarray) -> Scaled:
        """The bend `entry` wrote, its flat points paired with the (n, 3) bent `points` again.

        Raises
        ------
        ValueError, TypeError, KeyError
            For an entry that does not read whole (the caller names the file).
        """
        sheet = entry["sheet"]
        centers, values = np.array(sheet["centers"], float), np.array(sheet["values"], float)
        flat = np.array(sheet["flat"], float).reshape(-1, 3)
        smoothing = np.array(sheet["smoothing"], float)  # one for all (older projects) or each
        if (
            centers.shape != (len(values), 2)
            or values.shape[1:] != (3,)
            or len(centers) < MIN_CELLS
            or smoothing.shape not in ((), (len(centers),))
        ):
            raise ValueError("the sheet's centres, values and smoothing do not match")
        if len(flat) != len(points):
            raise ValueError("the sheet's flat points do not match the leaf's")
        up = np.array(sheet["up"], float).reshape(3)
        rings = tuple(np.array(r, float).reshape(-1, 2) for r in sheet.get("holes", []))
        if any(len(r) < 4 for r in rings):
            raise ValueError("a hole's outline has fewer than three corners")
        bend = cls(
            Sheet(centers, values, float(smoothing) if smoothing.ndim == 0 else smoothing, up),
            np.array(sheet["centre"], float).reshape(3),
            float(sheet["scale"]),
            holes=rings,
        )
        bend.made.update(zip(map(bytes, np.asarray(points, dtype=float)), flat, strict=True))
        return bend

    def crease(self, points: np.ndarray) -> None:
        """A sheet is smooth: no crease."""
        return None
