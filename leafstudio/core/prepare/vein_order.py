"""The order of a vein's points: kept when they run along the vein, made canonical when not.

The pipeline thins dense veins along their order (polygon.thin_veins, height.height_guide) and
picks vein rows for the surface fit evenly by index, so a shuffled vein used to be thinned to a
random few of its points (a 1e5-point vein's mean distance to the mesh tripled). A vein whose
path through its points in the given order is no longer than a few times its extent is taken as
ordered and kept; any other (shuffled, or dense and noisy) is sorted along its principal axis, a
canonical order of the point set: any shuffle of the same points gives the same order.
"""

from __future__ import annotations

import numpy as np
import shapely

from leafstudio.core.plane import fit_frame

ORDERED_PATH = 4.0  # an ordered vein's path is at most this many times its box's diagonal


def vein_order(xy: np.ndarray) -> np.ndarray:
    """(m,) indices putting a vein's (m, 2) plane points in order along it (see the module)."""
    xy = np.asarray(xy, dtype=float)
    if len(xy) < 3:
        return np.arange(len(xy))
    path = float(np.sqrt((np.diff(xy, axis=0) ** 2).sum(axis=1)).sum())
    if path <= ORDERED_PATH * float(np.hypot(*np.ptp(xy, axis=0))):
        return np.arange(len(xy))
    centred = xy - xy.mean(axis=0)
    axis = np.linalg.eigh(centred.T @ centred)[1][:, -1]
    axis = axis if axis[np.argmax(np.abs(axis))] > 0 else -axis  # a sign of its own
    return np.lexsort((xy[:, 1], xy[:, 0], xy @ axis))


def veins_inside_outline(
    boundary: np.ndarray, veins: list[np.ndarray], gap: float
) -> list[np.ndarray]:
    """The (m_i, 3) veins' points that lie inside the (n, 3) boundary by at least `gap` (or
    outside it by at most -gap, when negative), as the pipeline sees them: on the boundary's own
    PCA plane, where a curled or folded margin moves (a vein drawn inside the flat outline can
    fall outside it there). Veins left with fewer than two points are dropped."""
    if not veins:
        return []
    frame = fit_frame(boundary, np.vstack(veins))
    region = shapely.Polygon(frame.to_plane(boundary)[0]).buffer(-gap)
    kept = []
    for vein in veins:
        xy = frame.to_plane(vein)[0]
        inside = vein[shapely.contains_xy(region, xy[:, 0], xy[:, 1])]
        if len(inside) >= 2:
            kept.append(inside)
    return kept
