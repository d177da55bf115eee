"""How close a reconstructed surface comes to a real leaf: distances from the scan's points to the
mesh, and how well the mesh covers the leaf's outline."""

from __future__ import annotations

from typing import Any

import numpy as np
import shapely
from scipy.spatial import cKDTree

from leafstudio.core import evaluate
from leafstudio.core.plane import Frame
from leafstudio.core.trianglemesh import MeshLike

NEAR, FAR = 0.01, 0.02  # shares of the leaf length for the "beyond" figures
FAR_FROM_SCAN = 0.01  # of the length: a scan's surface farther on average is warned of
FOLD_ANGLE = 90.0  # degrees: an edge whose two triangles meet more sharply folds the mesh back
FOLDED = 0.0025  # a scan's mesh with more of its edges folded back is warned of (the eight shared
# scans: soybean pot1_1, whose cloud is doubled and V-folded, 0.51% at sheet.SMOOTHING 1e-3
# (0.16% at 2e-3, 0.65% before; bench_bent.py --scan-table); the other seven 0.05% at most;
# before the sheet's second fit, core/sheet.py, 3.1% and 0.16%)
CRUMPLE = 0.01  # of the length: a surface bending tighter than this radius in any direction
# (its largest principal curvature |k1| or |k2| past 1 / (CRUMPLE length)), which no blade makes
# but a surface that chases a doubled or noisy scan does; a saddle counts as a roll or a cup
# does (|mean curvature| past 1 / (2 CRUMPLE length) counted no saddle: review33)
CRUMPLED = 0.01  # a scan's mesh with more of its area so crumpled is warned of (the eight shared
# scans: soybean pot1_1 3.6% of its area, the other seven 0.02% at most; at |H| pot1_1 4.0% and
# 0.04%; before the sheet's smoothing was weighed by each cell's error, core/sheet.py, pot1_1 was
# 8.3% of its vertices by |H|, the others 0.47% at most)
FIN_NEIGHBOURS = 16  # a fin's side: the mean direction to this many nearest scan points ...
ONE_SIDE = 0.85  # ... at least this long (points all round a triangle: a hole it spans)


def scan_distances(mesh: MeshLike, points: np.ndarray, length: float) -> dict[str, Any]:
    """Distances from (n, 3) scan points to the mesh: mean, median, 95th percentile, maximum, and
    the share of points beyond 1% and 2% of the leaf length (all in the scan's units).

    Examples
    --------
    >>> import numpy as np, pyvista as pv
    >>> plane = pv.Plane(i_resolution=4, j_resolution=4).triangulate()
    >>> round(scan_distances(plane, np.array([[0, 0, 0.01], [0.1, 0, 0.03]]), 1.0)["mean"], 6)
    0.02
    """
    return distance_summary(
        evaluate.point_to_mesh_distance(mesh, np.asarray(points, dtype=float)), length
    )


def distance_summary(d: np.ndarray, length: float) -> dict[str, Any]:
    """scan_distances' figures from the (n,) distances themselves (measured once, summarised
    for several subsets of the points)."""
    if len(d) == 0:
        return {"points": 0}
    return {
        "points": len(d),
        "length": float(length),
        "mean": float(d.mean()),
        "median": float(np.median(d)),
        "p95": float(np.percentile(d, 95)),
        "max": float(d.max()),
        "beyond_1pct": float(np.mean(d > NEAR * length)),
        "beyond_2pct": float(np.mean(d > FAR * length)),
    }


def folded_share(mesh: MeshLike) -> float:
    """The share of the mesh's inner edges whose two triangles meet at more than FOLD_ANGLE: where
    the surface folds back on itself (a scan's doubled or curled-under blade), which the
    distances from the scan's points to it do not show (they pass through its cloud).

    Examples
    --------
    >>> import numpy as np, pyvista as pv
    >>> plane = pv.Plane(i_resolution=4, j_resolution=4).triangulate()
    >>> folded_share(plane)
    0.0
    """
    angles, _ = evaluate.dihedral_angles(np.asarray(mesh.points), evaluate.triangles_of(mesh))
    return float(np.mean(angles > FOLD_ANGLE)) if len(angles) else 0.0


def crumpled_share(mesh: MeshLike, length: float) -> float:
    """The share of the mesh's area whose triangles bend tighter than a radius of CRUMPLE of
    `length` (their corners' mean largest |principal curvature|, k1 and k2): a surface crumpled
    between a scan's doubled layers or through its noise, which neither the distances nor the
    folds show (soybean pot1_1's surface crumpled over 3.6% of its area folds back at only 0.12%
    of its edges). 0 for a mesh without curvatures.

    Examples
    --------
    >>> import numpy as np, pyvista as pv
    >>> plane = pv.Plane(i_resolution=4, j_resolution=4).triangulate()
    >>> plane.point_data["k1"] = np.where(plane.points[:, 0] < 0, 0.0, 200.0)
    >>> plane.point_data["k2"] = -plane.point_data["k1"]  # a saddle there: no mean curvature
    >>> round(crumpled_share(plane, 1.0), 2)  # x >= 0: its half and the triangles two corners in
    0.62
    """
    if not {"k1", "k2"} <= set(mesh.point_data.keys()) or length <= 0:
        return 0.0
    k1, k2 = (np.abs(np.asarray(mesh.point_data[k], dtype=float)) for k in ("k1", "k2"))
    bend = np.maximum(k1, k2) * CRUMPLE * length  # past 1: tighter than the radius
    triangles = evaluate.triangles_of(mesh)
    area = _doubled_areas(np.asarray(mesh.points, dtype=float)[triangles])
    tight = np.nan_to_num(bend[triangles].mean(axis=1), nan=0.0) > 1.0
    return float(area[tight].sum() / area.sum()) if area.sum() > 0 else 0.0


def _doubled_areas(corners: np.ndarray) -> np.ndarray:
    """(m,) twice the area of each of the (m, 3, 3) triangles' `corners` (shares of it are
    all crumpled_share and fin_share need)."""
    return np.linalg.norm(
        np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
    )


def with_folds(fit: dict[str, Any], mesh: MeshLike) -> dict[str, Any]:
    """A scan's fit (distance_summary's figures) with the mesh's `folded_share` as "folded" and
    its `crumpled_share` as "crumpled", when it has points (the figures scan_warnings reads)."""
    if not fit.get("points"):
        return fit
    return {
        **fit,
        "folded": folded_share(mesh),
        "crumpled": crumpled_share(mesh, fit.get("length", 0.0)),
    }


def scan_warnings(fit: dict[str, Any]) -> list[str]:
    """What a scan's fit (scan_distances, with "folded": folded_share) says is wrong: a surface
    far from the scan on average, or folding back on itself; [] for neither."""
    notes = []
    length = fit.get("length", 0.0)
    if fit.get("mean", 0.0) > FAR_FROM_SCAN * length:
        notes.append(
            f"the surface is {fit['mean'] / length:.1%} of the leaf's length from the scan on "
            f"average (95% of points within {fit['p95'] / length:.1%}): it does not follow this "
            "scan well"
        )
    folded, crumpled = fit.get("folded", 0.0) > FOLDED, fit.get("crumpled", 0.0) > CRUMPLED
    if folded or crumpled:
        # what is wrong, then how it was measured in one aside: the status line's headline
        # (gui/model/status_line.py) reads up to the first aside, and said "The surface folds
        # back on itself at 1.2% of its edges" of a surface that also crumpled over 3.6%
        said, measured = [], []
        if folded:
            said.append(f"folds back on itself at {fit['folded']:.1%} of its edges")
            measured.append(f"creases past {FOLD_ANGLE:.0f}°")
        if crumpled:
            said.append(f"crumples over {fit['crumpled']:.1%} of its area")
            measured.append(f"bends tighter than a radius of {CRUMPLE:.0%} of the leaf's length")
        notes.append(
            f"the surface {' and '.join(said)} ({'; '.join(measured)}), where the scan is "
            "doubled, noisy or its blade curls under: compare it with the scan's points before "
            "trusting its shape"
        )
    return notes


DISTANCE_FIGURES = ("length", "mean", "median", "p95", "max")  # the rest: a count and shares


def scaled_fit(fit: dict[str, Any], scale: float) -> dict[str, Any]:
    """scan_distances' figures in units `scale` times smaller (millimetres, with --length)."""
    return {k: v * scale if k in DISTANCE_FIGURES else v for k, v in fit.items()}


def coverage(mesh: MeshLike, frame: Frame, outline: np.ndarray) -> dict[str, Any]:
    """How the mesh, seen from along the plane normal, covers the (b, 2) outline in the frame's
    plane: the share of the outline's area covered, the mesh area outside it (as a share of the
    outline's area), and the number of connected pieces."""
    triangles = evaluate.triangles_of(mesh)
    xy, _ = frame.to_plane(np.asarray(mesh.points))
    footprint = shapely.union_all(shapely.polygons(xy[triangles]))
    region = shapely.Polygon(outline)
    area = region.area
    return {
        "covered": float(footprint.intersection(region).area / area),
        "outside": float(footprint.difference(region).area / area),
        "pieces": evaluate.connected_pieces(triangles),
    }


def fin_share(mesh: MeshLike, points: np.ndarray, length: float) -> float:
    """The share of the mesh's area that stands out of a scan as a fin: triangles farther than
    FAR of the length from every one of the (n, 3) scan points, with those points all to one
    side of them (the mean of the unit vectors to the FIN_NEIGHBOURS nearest at least ONE_SIDE
    long). A triangle over a hole in the scan has scan points all round it and is no fin.

    Examples
    --------
    >>> import numpy as np, pyvista as pv
    >>> plane = pv.Plane(i_size=1, j_size=1, i_resolution=8, j_resolution=8).triangulate()
    >>> xy = np.random.default_rng(0).uniform(-0.5, 0.5, (2000, 2))
    >>> scan = np.column_stack([xy, 0 * xy[:, 0]])
    >>> fin_share(plane, scan, 1.0), round(fin_share(plane, scan[xy[:, 0] < 0.2], 1.0), 2)
    (0.0, 0.25)
    """
    points = np.asarray(points, dtype=float)
    corners = np.asarray(mesh.points, dtype=float)[evaluate.triangles_of(mesh)]
    area = _doubled_areas(corners)
    centres = corners.mean(axis=1)
    near, which = cKDTree(points).query(centres, k=min(FIN_NEIGHBOURS, len(points)))
    towards = points[which] - centres[:, None]
    towards /= np.maximum(np.linalg.norm(towards, axis=2, keepdims=True), 1e-300)
    side = np.linalg.norm(towards.mean(axis=1), axis=1)
    fin = (near[:, 0] > FAR * length) & (side >= ONE_SIDE)
    return float(area[fin].sum() / area.sum()) if area.sum() > 0 else 0.0
