"""The petiole is a strand sticking out of the blade, not whatever the blade test leaves out
(review finding, session 2): `extract` took the largest piece left as the petiole, whatever its
shape. On soybean pot1_1 that was 535 points of blade the scanner saw obliquely (24% of the
blade's area dropped); on sugar beet pot1_7 a piece of the blade became the petiole (the base
put at the wrong end) and the real petiole was called clutter."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely

from leafstudio.sources.extract import clean_scan, extract_leaf
from tests.leaves import extracted_scan, scan_blade_outline, synthetic_scan

REAL = Path(__file__).resolve().parents[3] / "shared" / "realleaves"
SCANS = sorted(REAL.glob("*.txt")) if REAL.is_dir() else []
needs_scans = pytest.mark.skipif(not SCANS, reason=f"no real scans at {REAL}")


def _spreads(points: np.ndarray) -> np.ndarray:
    centred = points - points.mean(axis=0)
    return np.sqrt(np.linalg.eigvalsh(centred.T @ centred / len(points)))[::-1]


def _beyond_outline(points: np.ndarray, found) -> float:
    """The share of the scan's clean points, less its petiole, that lie more than 1% of the
    length outside the extracted outline (on the blade's plane)."""
    unit = (points - points.mean(axis=0)) / np.ptp(points, axis=0).max()
    keep = clean_scan(unit) & ~found.petiole
    boundary = found.leaf.boundary
    if found.leaf.bend is not None:  # a bent blade: on its flat blade (core/sheet.py)
        points, boundary = found.leaf.bend.flatten(points), found.leaf.bend.flatten(boundary)
    centre = points[keep].mean(axis=0)
    axes = np.linalg.svd(points[keep] - centre, full_matrices=False)[2][:2]
    outline = shapely.Polygon((boundary - centre) @ axes.T).buffer(0)
    gap = shapely.distance(outline, shapely.points((points[keep] - centre) @ axes.T))
    return float(np.mean(gap > 0.01 * found.length))


def test_a_blade_part_scanned_sparsely_stays_in_the_blade():
    """A third of the blade with a quarter of the points (seen obliquely): it was the largest
    piece the ball test left, so it was taken as the petiole and cut off the outline."""
    parts = synthetic_scan(candidates=20000)
    blade = parts["blade"]
    sparse = blade[:, 0] > 0.15
    keep = ~sparse | (np.arange(len(blade)) % 4 == 0)
    points = np.vstack([blade[keep], parts["petiole"], parts["outliers"]])
    found = extract_leaf(points)
    known = shapely.Polygon(scan_blade_outline(np.linspace(0, 2 * np.pi, 400, endpoint=False)))
    got = shapely.Polygon(found.leaf.boundary[:, :2])
    # before: 21%; 4.1% with the blade unrolled and bent back by a sheet (core/sheet.py)
    assert known.symmetric_difference(got).area < 0.045 * known.area
    n = int(keep.sum())
    assert found.blade[:n].mean() > 0.99
    assert found.petiole[n : n + len(parts["petiole"])].mean() > 0.5  # the petiole is still it


@needs_scans
@pytest.mark.parametrize("path", SCANS, ids=lambda p: p.stem[-20:])
def test_the_outline_keeps_the_whole_blade_of_a_real_scan(path):
    """Before: 12.6% (soybean pot1_1), 18.2% (sugar beet pot1_7), 0.3-2.4% of the others' clean
    points beyond the outline; then at most 0.04% in the PCA plane. On the unrolled blade (core/
    sheet.py) at most 0.6%: a few points across a tight curl flatten onto the other layer."""
    points, found = extracted_scan(path)
    assert _beyond_outline(points, found) < 0.01


@needs_scans
@pytest.mark.parametrize("path", [p for p in SCANS if p.name.startswith("sugarbeet")])
def test_a_sugar_beets_petiole_is_its_strand(path):
    """Each sugar beet scan has a long petiole: what extract calls the petiole is a strand (its
    second spread under a third of its first), at least 100 points. Before, pot1_7's was a sheet
    of blade (0.64) and its 241-point strand was dropped as clutter."""
    points, found = extracted_scan(path)
    assert found.petiole.sum() >= 100
    spread = _spreads(points[found.petiole])
    assert spread[1] < 0.35 * spread[0]
