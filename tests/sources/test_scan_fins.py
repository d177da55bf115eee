"""No fin on a scan's surface (issue 21): soybean pot1_1's blade, unrolled onto its sheet
(core/sheet.py), had its outline bridge bays of the flat blade that hold no scan point; the sheet
there is extrapolated and folds, and the app showed thin flaps standing out of the scan at the
leaf's top (0.29% of the mesh's area by `fin_share`). The eight shared scans, extracted and
reconstructed with the defaults as `extract` then `reconstruct`, batch and the app do. Nor does a
surface span a real hole (tests/sources/test_scan_holes.py): sugar beet pot1_7's is kept open,
and no other scan gains one."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import leafstudio as ls
from leafstudio import workflows
from leafstudio.analysis.fidelity import fin_share
from leafstudio.core.evaluate import margin_creases
from tests.leaves import extracted_scan
from tests.sources.test_scan_holes import far_share

REAL = Path(__file__).resolve().parents[3] / "shared" / "realleaves"
SCANS = sorted(REAL.glob("*.txt")) if REAL.is_dir() else []
pytestmark = pytest.mark.skipif(not SCANS, reason=f"no real scans at {REAL}")


@pytest.fixture(scope="module")
def scans() -> dict[str, tuple[float, float, float, int, float]]:
    """Each scan's fin share, mean distance over the length, share of the mesh's area farther
    than 3% of the length from every blade point, number of holes, and the 99th percentile of
    the mesh's interior dihedral angles (degrees)."""
    found = {}
    for path in SCANS:
        # the run's shared extraction (tests/leaves.py): open_scan's own, as the test below shows
        points, extraction = extracted_scan(path)
        opened = workflows.Opened(str(path), "scan", extraction.leaf, scan=points,
                                  extraction=extraction)  # fmt: skip
        done = workflows.reconstruct(opened, ls.Params())
        blade = opened.scan[opened.extraction.blade]
        fit = done.scan_fit
        fin = fin_share(done.result.triangle_mesh, blade, fit["length"])
        far = far_share(done.result.triangle_mesh, blade, fit["length"])
        crumple = margin_creases(done.result)["interior_p99"]
        found[path.stem] = (
            fin, fit["mean"] / fit["length"], far, len(opened.leaf.bend.holes), crumple
        )  # fmt: skip
    return found


def test_the_shared_extraction_is_what_the_app_opens():
    """The scans above are the run's shared extractions (extract_leaf on the scan's points,
    tests/leaves.extracted_scan) instead of eight more openings: open_scan, the path of
    `extract`, batch and the app, checks the scan and finds the very same leaf in it."""
    path = REAL / "sugarbeet_f00012_20170829T010129_pot1_1.txt"
    opened = workflows.open_scan(str(path))
    points, extraction = extracted_scan(path)
    np.testing.assert_array_equal(opened.scan, points)
    np.testing.assert_array_equal(opened.extraction.blade, extraction.blade)
    leaf, shared = opened.leaf, extraction.leaf
    np.testing.assert_array_equal(leaf.boundary, shared.boundary)
    assert len(leaf.veins) == len(shared.veins)
    for vein, same in zip(leaf.veins, shared.veins, strict=True):
        np.testing.assert_array_equal(vein, same)
    assert leaf.bend.key() == shared.bend.key()  # the sheet, its place and scale, the holes


def test_no_scan_grows_a_fin(scans):
    fins = {name: fin for name, (fin, *_) in scans.items()}
    assert max(fins.values()) <= 1e-3, fins


def test_the_scans_stay_close_to_their_surfaces(scans):
    means = [mean for _, mean, *_ in scans.values()]
    assert np.mean(means) <= 0.006 and max(means) <= 0.01, means


def test_a_real_hole_stays_open_and_no_other_scan_gains_one(scans):
    """pot1_7: 1.97% of the mesh's area spanned its hole, now none; the other seven have no hole
    and keep at most 0.1% of their area that far (triangles along the margin), but soybean
    pot1_1 0.75%: its surface, refitted on the flat blade (core/sheet.py), passes between its
    doubled layers and under its curl, 3.2% of the length from the nearest scan point (4.1%
    at most) but spanning no hole: on the flat blade each such triangle lies within 2.3 point
    gaps of a blade point (a hole is 4: sources/scan_holes.py). pot1_7's tear is two holes
    that meet at a point since its whole blade is unrolled (core/sheet.py: the cubes in the
    scan's own frame; a strip of blade beyond the tear was cut off as petiole before)."""
    holes = {name[-12:]: count for name, (_, _, _, count, _) in scans.items()}
    spans = {name[-12:]: far for name, (_, _, far, _, _) in scans.items()}
    assert holes.pop("15033_pot1_7") >= 1
    assert not any(holes.values()), holes
    assert spans["15033_pot1_7"] <= 5e-4 and spans["43118_pot1_1"] <= 1e-2, spans
    assert max(far for name, far in spans.items() if name != "43118_pot1_1") <= 2e-3, spans


def test_no_scan_crumples_or_crinkles_along_its_stripes(scans):
    """The 99th percentile of the interior dihedral angles: soybean pot1_1's mesh walled and
    crumpled (138 degrees), pot1_15, 17, 36 and sugar beet pot1_7 crinkled along the scanner's
    stripes (45-62), from a sheet through the cube means (core/sheet.py); refitted on the flat
    blade, 80 and 20-29, still crinkled: that sheet (SMOOTHING 1e-4) missed the cell means by
    a tenth of the scanner's noise; at 1e-3, 60 and 12-21."""
    crumples = {name[-12:]: crumple for name, (*_, crumple) in scans.items()}
    assert crumples["43118_pot1_1"] <= 70.0, crumples
    assert max(c for name, c in crumples.items() if name != "43118_pot1_1") <= 24.0, crumples
