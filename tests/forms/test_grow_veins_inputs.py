"""grow_veins answers bad input in one LeafError and grows the same veins at any scale
(fuzzing, issue 24)."""

from __future__ import annotations

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.forms import grow_veins

OUTLINE = ls.demo("nested").boundary


@pytest.mark.parametrize("seed", [-1, 2**32, 1.5, True, "3"])
def test_a_seed_out_of_range_is_a_leaf_error(seed):
    with pytest.raises(ls.LeafError, match="seed"):
        grow_veins(OUTLINE, seed=seed)


@pytest.mark.parametrize("base", [(5.0, 5.0), (1e308, 0.0)])
def test_a_base_far_outside_the_outline_is_refused(base):
    with pytest.raises(ls.LeafError, match="base lies outside the outline"):
        grow_veins(OUTLINE, base=np.array(base))


def test_a_base_on_the_margin_is_taken():
    veins = grow_veins(OUTLINE, base=OUTLINE[0, :2])
    assert len(veins) > 1


def test_a_power_of_two_scale_gives_the_very_same_veins_scaled():
    plain = grow_veins(OUTLINE, seed=2)
    scaled = grow_veins(OUTLINE * 8.0, seed=2)
    assert len(plain) == len(scaled)
    for a, b in zip(plain, scaled, strict=True):
        np.testing.assert_array_equal(a * 8.0, b)


@pytest.mark.parametrize("scale", [1e-90, 1e150])
def test_veins_grow_at_any_scale(scale):
    plain = grow_veins(OUTLINE, seed=2)
    scaled = grow_veins(OUTLINE * scale, seed=2)
    assert len(plain) == len(scaled)
    for a, b in zip(plain, scaled, strict=True):
        np.testing.assert_allclose(b / scale, a, atol=1e-9)
