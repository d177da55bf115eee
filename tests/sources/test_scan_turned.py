"""A scan's traits do not depend on how the scanner had it turned (session 27's bug hunt: sugar
beet pot2_3's projected area was 568.5 as scanned and 308.6 turned): a rolled blade scanned,
then turned and moved rigidly, gives the same figures."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from leafstudio import workflows
from leafstudio.model import Params
from tests.core.test_sheet import rolled


def _figures(points: np.ndarray, path) -> dict[str, float]:
    np.savetxt(path, points)
    done = workflows.reconstruct(workflows.open_scan(path), Params(grid=64))
    return done.result.metrics["leaf"]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The leaf figures of a rolled blade's scan (millimetres) as scanned and turned."""
    rng = np.random.default_rng(5)
    uv = rng.uniform([-0.5, -0.2], [0.5, 0.2], (12000, 2))
    uv = uv[(uv[:, 0] / 0.5) ** 2 + (uv[:, 1] / 0.2) ** 2 < 1][:5000]
    points = 40.0 * (rolled(uv, radius=0.3) + rng.normal(0, 5e-4, (len(uv), 3)))
    folder = tmp_path_factory.mktemp("turned")
    turned = Rotation.from_euler("xyz", [30, 50, 70], degrees=True).apply(points) + [100, -50, 20]
    return _figures(points, folder / "scanned.xyz"), _figures(turned, folder / "turned.xyz")


def test_a_turned_scans_projected_area_is_its_own(runs):
    """The projected area was the mesh's shadow on its flat blade's plane, which a scan's sheet
    lays on the world's x-y plane: the scanner's, not the leaf's (evaluate.facing_area)."""
    scanned, turned = runs
    assert turned["projected_area"] == pytest.approx(scanned["projected_area"], rel=0.02)
    assert scanned["projected_area"] < 0.99 * scanned["area"]  # the roll is seen, not flattened
