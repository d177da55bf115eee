"""The batch tests' inputs: leaf files and real scans, made once per test file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import leafstudio as ls
from tests.batch.tables import REAL, SCANS


def _rotation(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@pytest.fixture(scope="module")
def leaves(tmp_path_factory) -> Path:
    """Six leaf files in two folders: the nested demo moved and turned."""
    root = tmp_path_factory.mktemp("leaves")
    demo = ls.demo("nested")
    for i in range(6):
        turn = _rotation(0.4 * i)
        leaf = ls.Leaf(
            boundary=demo.boundary @ turn.T + i, veins=[v @ turn.T + i for v in demo.veins]
        )
        ls.save_leaf(leaf, root / ("a" if i < 3 else "b/c") / f"leaf{i}.csv")
    return root


@pytest.fixture(scope="module")
def scans(tmp_path_factory) -> Path:
    """SCANS real scans (x y z only), each subsampled to 40%, moved and turned."""
    if not REAL.is_dir():
        pytest.skip(f"no real scans at {REAL}")
    root = tmp_path_factory.mktemp("scans")
    rng = np.random.default_rng(1)
    for i, path in enumerate(sorted(REAL.glob("*.txt"))[1 : 1 + SCANS]):
        xyz = np.loadtxt(path, delimiter=",", usecols=(0, 1, 2))
        keep = rng.random(len(xyz)) < 0.4
        moved = xyz[keep] @ _rotation(0.3 * i).T + [10.0 * i, -5.0, 2.0]
        np.savetxt(root / f"scan{i}.txt", moved, fmt="%.6f")
    return root
