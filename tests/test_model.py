"""The API's types refuse bad input with one LeafError (fuzzing, issue 24)."""

from __future__ import annotations

import pytest

import leafstudio as ls


@pytest.mark.parametrize("boundary", [[[0.0], []], [[0, 0, 0], [1, 0]], [[0, 0, 0], "ab"]])
def test_ragged_points_are_a_leaf_error_not_numpys(boundary):
    with pytest.raises(ls.LeafError, match="x, y, z points"):
        ls.Leaf(boundary)
