"""A sparse scan's blade is cut in fewer cubes for its sheet (core/sheet_cells.py): at about one
point a cube, its unrolled blade came out long (the bug hunt of session 26: soybean pot1_15 at
300 of its points measured 67.3 mm against 43.4 scanned whole)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from leafstudio.core.sheet_cells import CELLS, FEWEST_CELLS, cut
from leafstudio.sources.scan import read_scan
from leafstudio.workflows import _scan_opened

REAL = Path(__file__).resolve().parents[3] / "shared" / "realleaves"


def _scan(name: str) -> np.ndarray:
    paths = sorted(REAL.glob(f"*{name}.txt"))
    if not paths:
        pytest.skip("the shared real scans are not beside the repository")
    return read_scan(str(paths[0]))


@pytest.mark.parametrize("name", ["pot1_15", "pot2_3"])
def test_a_sparse_scan_is_about_as_long_as_the_whole(name):
    whole = _scan(name)
    sparse = whole[np.random.default_rng(0).choice(len(whole), 300, replace=False)]
    full = _scan_opened(name, whole).extraction.length
    thin = _scan_opened(name, sparse, force=True).extraction.length
    assert abs(thin / full - 1) < 0.1, (thin, full)


def test_a_dense_blade_keeps_every_cube_and_a_sparse_one_fewer():
    """A blade dense enough keeps CELLS; one of 300 points is cut until its cubes hold PER_CUBE
    points each on average."""
    from leafstudio.core.sheet_cells import PER_CUBE

    rng = np.random.default_rng(1)
    blade = np.column_stack([rng.uniform(0, 1, (20_000, 2)), np.zeros(20_000)])
    assert cut(blade, 1.0)[0] == CELLS
    sparse = blade[:300]
    few, cube, counts = cut(sparse, 1.0)
    assert FEWEST_CELLS <= few < CELLS
    assert len(sparse) >= PER_CUBE * len(counts) and counts.sum() == len(sparse)
    assert cube.max() == len(counts) - 1
