"""The app tells a scan from a boundary as the pipeline does (review finding, session 2): its own
test (12 nearest neighbours) took a dense noisy boundary for a scan, so opening one extracted a
leaf from it instead of reconstructing the boundary given."""

from __future__ import annotations

from pathlib import Path

import pytest

from leafstudio.gui import scans
from leafstudio.model import Leaf
from leafstudio.scan import read_scan
from tests.test_clouds import _ellipse, _random_leaf

REAL = Path(__file__).resolve().parents[3] / "shared" / "realleaves"


@pytest.mark.parametrize("noise", [1e-3, 1e-2])
def test_a_dense_noisy_boundary_opens_as_a_boundary(noise):
    assert not scans.looks_like_scan(_random_leaf(0, 20000, noise, 1.0)[0])
    assert not scans.looks_like_scan(Leaf(_ellipse(20000, 0.04), []))


@pytest.mark.skipif(not REAL.is_dir(), reason=f"no real scans at {REAL}")
def test_the_real_scans_open_as_scans():
    assert all(scans.looks_like_scan(Leaf(read_scan(p), [])) for p in sorted(REAL.glob("*.txt")))
