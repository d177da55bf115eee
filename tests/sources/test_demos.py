"""The built-in demos: the paper's Figs. 8 and 9, and their copies in resources/demos."""

from pathlib import Path

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.sources.demos import HALFWIDTH

RESOURCES = Path(__file__).resolve().parents[2] / "resources" / "demos"


@pytest.mark.parametrize("name", ["nested", "parallel"])
def test_resource_files_match_the_generators(name):
    np.testing.assert_allclose(
        ls.load_leaf(RESOURCES / f"{name}.leaf.json").boundary, ls.demo(name).boundary
    )


@pytest.mark.parametrize("name", ["nested", "parallel"])
def test_boundary_follows_the_papers_equation(name):
    boundary = ls.demo(name).boundary
    x, y = boundary[:, 0], boundary[:, 1]
    np.testing.assert_allclose(np.abs(y), HALFWIDTH[name](x), atol=1e-12)
    assert x.min() == 0 and x.max() == 1  # leaf length 1
    assert np.all(boundary[:, 2] == 0)


def test_veins_lie_inside_and_above_the_leaf():
    for name in ("nested", "parallel"):
        for vein in ls.demo(name).veins:
            assert np.all(np.abs(vein[:, 1]) < HALFWIDTH[name](vein[:, 0]))
            assert np.all(vein[:, 2] > 0)
