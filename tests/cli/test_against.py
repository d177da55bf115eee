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
    extracted = int(re.search(r"blade of (\d+) of", capsys.readouterr().out).group(1))
    mesh = tmp_path / "s.ply"
    args = ["reconstruct", str(leaf), "-o", str(mesh), "--grid", "64", "--against", str(SCAN)]
    assert main(args) == 0
    out = capsys.readouterr().out
    measured = re.search(r"blade \(no outliers, no petiole\): (\d+) points", out)
    assert int(measured.group(1)) == extracted
