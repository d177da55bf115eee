"""Scans and the Poisson comparison in the app, without Qt: what the task worker computes.

A scan (a point cloud of a leaf's whole surface) opens as its extracted leaf (sources/extract.py),
with its points as a layer and its distances to each new mesh in the measurements panel. The
Poisson layer is open3d's screened Poisson surface of the same input (analysis/compare.py), drawn
beside our mesh. Everything here runs on the task thread, with numpy only; the main thread
makes the VTK datasets from it (Piece.data) and draws.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np

from leafstudio.analysis.compare import poisson_surface
from leafstudio.analysis.fidelity import FAR, NEAR, distance_summary, scan_warnings, with_folds
from leafstudio.core.evaluate import point_to_mesh_distance
from leafstudio.core.pipeline import Result
from leafstudio.core.trianglemesh import polydata, vertex_normals
from leafstudio.gui.model.pieces import Piece, cloud, dots
from leafstudio.gui.model.thinning import DISPLAY_POINTS, thinned
from leafstudio.sources.extract import Extraction
from leafstudio.workflows import Opened

BLADE_COLOR, DROPPED_COLOR, POISSON_COLOR = "#2e7d32", "#c62828", "#e08a1e"
POISSON_GAP = 0.15  # the Poisson surface sits this share of the leaf length beside our mesh
POISSON_OPACITY = 0.6


@dataclass(frozen=True, eq=False)
class ScanData:
    """An opened scan: its points, what extraction found, and the scan layer's pieces."""

    path: str
    points: np.ndarray  # (n, 3)
    extraction: Extraction
    pieces: list[Piece]


def scan_data(opened: Opened) -> ScanData:
    """An opened scan (workflows.open_scan: read, checked, extracted) with its blade and
    dropped points as layers, thinned to DISPLAY_POINTS together (layers.thinned)."""
    points, extraction = opened.scan, opened.extraction
    blade = extraction.blade
    share = DISPLAY_POINTS * np.count_nonzero(blade) // max(len(points), 1)
    kept = thinned(points[blade], share)
    dropped = thinned(points[~blade], DISPLAY_POINTS - share)
    count = len(kept) + len(dropped)
    pieces = [
        Piece("scan:blade", partial(cloud, kept), dots(BLADE_COLOR, 3.0, count)),
        Piece("scan:dropped", partial(cloud, dropped), dots(DROPPED_COLOR, 4.0, count)),
    ]
    return ScanData(opened.path, points, extraction, pieces)


def fidelity_sections(
    result: Result, scan: ScanData
) -> tuple[list[tuple[str, list[tuple[str, str]]]], list[str]]:
    """Measurements-panel sections: distances from the scan's blade points (and from all its
    points) to the result's mesh, as `leafstudio reconstruct --against` reports them, with the
    share of the mesh's edges folded back; and what they warn of (fidelity.scan_warnings), for
    the window to say as the CLI and batch do."""
    d = point_to_mesh_distance(result.triangle_mesh, scan.points)  # the blade's are among them
    length = result.blade_length
    blade = with_folds(distance_summary(d[scan.extraction.blade], length), result.triangle_mesh)
    sections = [
        ("Scan → mesh distance (blade points)", _fidelity_rows(blade)),
        ("Scan → mesh distance (all points)", _fidelity_rows(distance_summary(d, length))),
    ]
    return sections, scan_warnings(blade)


def _fidelity_rows(f: dict[str, Any]) -> list[tuple[str, str]]:
    if not f.get("points"):
        return [("Points", "0")]
    return [
        ("Points", str(f["points"])),
        ("Mean", f"{f['mean']:.4g}"),
        ("Median", f"{f['median']:.4g}"),
        ("95th percentile", f"{f['p95']:.4g}"),
        ("Max", f"{f['max']:.4g}"),
        (f"Beyond {NEAR:.0%} of length", f"{f['beyond_1pct']:.1%}"),
        (f"Beyond {FAR:.0%} of length", f"{f['beyond_2pct']:.1%}"),
        ("Leaf length", f"{f['length']:.4g}"),
        *([("Mesh edges folded back", f"{f['folded']:.1%}")] if "folded" in f else []),
        *([("Mesh area crumpled", f"{f['crumpled']:.1%}")] if "crumpled" in f else []),
    ]


def poisson_piece(result: Result) -> Piece:
    """The screened Poisson surface of the result's input, moved beside our mesh along the leaf's
    width (its spill would hide our mesh in place), semi-transparent."""
    poisson = poisson_surface(result.leaf, result.frame.normal)
    side = result.frame.v
    ours = result.triangle_mesh.points @ side
    theirs = poisson.points @ side
    points = poisson.points + (ours.max() - theirs.min() + POISSON_GAP * result.length) * side
    normals = vertex_normals(points, poisson.regular_faces)
    style = {"color": POISSON_COLOR, "opacity": POISSON_OPACITY, "smooth_shading": False}
    return Piece("poisson", partial(polydata, points, poisson.regular_faces, {}, normals), style)
