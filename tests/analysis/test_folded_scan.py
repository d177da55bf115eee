"""A scan's surface that folds back on itself is said (issue 21, finding 2: "curled real leaves
come out wrong, and nothing says so"). Soybean pot1_1's cloud is doubled (two layers 2-3 mm
apart) and V-folded at its base; its mesh crumpled into walls and flaps through that cloud, so
the distances from the scan's points to it stayed small (0.52% of the length on average) and
no warning was given. Its mesh's edges folded past 90°: 3.1%, the other seven scans 0.16% at
most; with the sheet refitted through cell means of the flat blade (core/sheet.py) and the
outline grown to the blade's edge (sources/scan_outline.py), 0.65% and 0.05%; with its smoothing
weighed by each cell's error (core/sheet.py) 0.12% and 0: but pot1_1's surface still crumples,
bending tighter than a radius of 1% of its length over 4.0% of its area (the other seven 0.04%
at most), and that is said too (fidelity.crumpled_share)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import pyvista as pv

import leafstudio as ls
from leafstudio import workflows
from leafstudio.analysis.fidelity import (
    CRUMPLED,
    FOLDED,
    crumpled_share,
    folded_share,
    scan_warnings,
)
from leafstudio.cli import main

SCANS = Path(__file__).resolve().parents[2].parent / "shared" / "realleaves"
POT1_1 = SCANS / "soybean_11_20190508T043118_pot1_1.txt"
needs_scan = pytest.mark.skipif(not POT1_1.exists(), reason="the shared scans are not beside us")


def test_a_flat_mesh_has_no_folds_and_a_folded_one_does():
    assert folded_share(pv.Plane(i_resolution=8, j_resolution=8).triangulate()) == 0.0
    sheet = pv.Plane(i_size=2, j_size=1, i_resolution=40, j_resolution=4).triangulate()
    assert folded_share(sheet) == 0.0
    points = np.asarray(sheet.points).copy()
    back = points[:, 0] > 0  # the right half turned back over the left: a fold of 175°
    angle = np.deg2rad(175.0)
    points[back, 0], points[back, 2] = (
        points[back, 0] * np.cos(angle),
        points[back, 0] * np.sin(angle),
    )
    folded = pv.PolyData(points, sheet.faces)
    share = folded_share(folded)
    assert 0 < share < 0.1  # only the crease's edges


def test_scan_warnings_name_a_far_or_folded_surface():
    fit = {"length": 1.0, "mean": 0.005, "p95": 0.01, "folded": 0.0}
    assert scan_warnings(fit) == []
    assert "does not follow this scan" in scan_warnings({**fit, "mean": 0.02})[0]
    (note,) = scan_warnings({**fit, "folded": 0.02})
    assert "folds back on itself at 2.0% of its edges" in note
    assert scan_warnings({**fit, "folded": FOLDED}) == []
    (note,) = scan_warnings({**fit, "crumpled": 0.05})
    assert "crumples over 5.0% of its area" in note and "folds back" not in note
    (both,) = scan_warnings({**fit, "folded": 0.02, "crumpled": 0.05})  # one note says both
    assert "folds back on itself at 2.0% of its edges" in both and "and crumples over 5.0%" in both
    assert scan_warnings({**fit, "crumpled": CRUMPLED}) == []


def test_a_crumpled_surface_is_told_from_a_smoothly_bent_one():
    """A sheet bent smoothly (a radius of a fifth of its length) is not crumpled however much it
    bends; the same sheet with a ripple of a wavelength of 3% of its length is, all over, and so
    is an egg-box of saddles, whose mean curvature is nothing (review33)."""
    sheet = pv.Plane(i_size=1, j_size=0.5, i_resolution=100, j_resolution=50).triangulate()
    x, y = np.asarray(sheet.points)[:, :2].T
    sheet.point_data["k1"], sheet.point_data["k2"] = np.full(len(x), 1 / 0.2), 0 * x
    assert crumpled_share(sheet, 1.0) == 0.0
    k = 2 * np.pi / 0.03
    sheet.point_data["k1"] = 0.01 * k**2 * np.sin(k * x)  # z = 0.01 sin kx
    assert crumpled_share(sheet, 1.0) > 0.5
    ripple = 0.01 * k**2 * np.sin(k * x) * np.sin(k * y)  # z = 0.01 sin kx sin ky: saddles
    sheet.point_data["k1"], sheet.point_data["k2"] = ripple, -ripple
    assert crumpled_share(sheet, 1.0) > 0.3
    del sheet.point_data["k1"]
    assert crumpled_share(sheet, 1.0) == 0.0  # no curvatures: nothing to say


@needs_scan
def test_a_doubled_scans_folded_surface_is_warned_of_by_the_workflow_and_the_cli(tmp_path, capsys):
    opened = workflows.open_scan(str(POT1_1))
    done = workflows.reconstruct(opened, ls.Params())
    assert done.scan_fit["crumpled"] > CRUMPLED
    assert any("crumples over" in w and "compare it with the scan" in w for w in done.warnings)
    leaf = tmp_path / "pot1_1.leaf.json"
    assert main(["extract", str(POT1_1), "-o", str(leaf), "-q"]) == 0
    code = main(["reconstruct", str(leaf), "-o", str(tmp_path / "m.ply"), "--texture", "none",
                 "--against", str(POT1_1)])  # fmt: skip
    said = capsys.readouterr()
    assert code == 0 and "crumples over" in said.err
    assert "the mesh's edges folded back" in said.out  # beside its distances
    assert "its area crumpled" in said.out


def test_the_crumple_warning_says_the_radius_it_counts():
    """The warning said "bends tighter than 2% of the leaf's length" while a roll to a radius of
    1.5% of it was not counted (review33). The radius the warning names is the one counted."""
    (note,) = scan_warnings({"length": 1.0, "mean": 0.0, "p95": 0.0, "crumpled": 0.05})
    said = re.search(r"tighter than a radius of (\d+(?:\.\d+)?)% of the leaf's length", note)
    assert said is not None
    radius = float(said.group(1)) / 100
    sheet = pv.Plane(i_size=1, j_size=0.5, i_resolution=20, j_resolution=10).triangulate()
    for r, counted in ((0.9 * radius, True), (1.1 * radius, False)):
        sheet.point_data["k1"] = np.full(sheet.n_points, 1 / r)  # rolled
        sheet.point_data["k2"] = np.zeros(sheet.n_points)
        assert (crumpled_share(sheet, 1.0) == 1.0) is counted
