"""`reconstruct --against SCAN` measures the blade that `extract` finds (issue 24, finding 13:
it counted 3,283 blade points on a scan where extract counted 3,268)."""

from __future__ import annotations

import re

import pytest

from leafstudio.cli import main
from tests.photos import REALLEAVES

SCAN = REALLEAVES / "soybean_11_20190508T043118_pot1_1.txt"


@pytest.mark.skipif(not SCAN.exists(), reason="the shared scans are not beside the checkout")
def test_against_counts_the_blade_extract_found(tmp_path, capsys):
    leaf = tmp_path / "s.leaf.json"
    assert main(["extract", str(SCAN), "-o", str(leaf)]) == 0
    said = capsys.readouterr().err  # extract's closing line is on stderr
    extracted = int(re.search(r"blade of (\d+) of", said).group(1))
    about = float(re.search(r"length about ([\d.]+) \(base to apex\)", said).group(1))
    mesh = tmp_path / "s.ply"
    args = ["reconstruct", str(leaf), "-o", str(mesh), "--grid", "64", "--against", str(SCAN)]
    assert main(args) == 0
    out = capsys.readouterr().out
    measured = re.search(r"blade \(no outliers, no petiole\): (\d+) points", out)
    assert int(measured.group(1)) == extracted
    # one leaf length: extract's (its points') and the reconstruction's (its smoothed outline)
    # within 2% (extract said 66.56, the scan's extent along its main axis, for 65.47)
    length = float(re.search(r"\(leaf length ([\d.]+)\)", out).group(1))
    assert about == pytest.approx(length, rel=0.02)
