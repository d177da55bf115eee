"""The nearest set pixel of a mask (core/raster.py), the textures' edge padding: exact, and the
very pixels scipy's feature transform picks, so that textures are what they were, whether the
kernel answers (measuring's kernels compiled) or scipy does (before they are)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.ndimage import distance_transform_edt

from leafstudio.core import raster
from leafstudio.core.raster import nearest_set_pixel


@pytest.fixture(params=["kernel", "scipy"], autouse=True)
def answered_by(request, monkeypatch):
    """Each test twice: by the compiled kernel, and by scipy as on a cold cache."""
    monkeypatch.setattr(raster, "compiled", lambda table: request.param == "kernel")
    return request.param


def _same(mask: np.ndarray) -> bool:
    """Whether nearest_set_pixel gives the rows and columns scipy's feature transform gives."""
    want = distance_transform_edt(~mask, return_distances=False, return_indices=True)
    return all(np.array_equal(got, w) for got, w in zip(nearest_set_pixel(mask), want, strict=True))


@pytest.mark.parametrize("share", [0.002, 0.02, 0.3, 0.95])
def test_the_nearest_set_pixel_is_the_one_scipy_finds(share):
    rng = np.random.default_rng(int(share * 1000))
    for _ in range(40):
        h, w = rng.integers(1, 60, 2)
        mask = rng.random((h, w)) < share
        mask[rng.integers(h), rng.integers(w)] = True
        assert _same(mask), (h, w)


def test_ties_and_a_leaf_shape_match_scipy():
    rows, cols = np.mgrid[:300, :400]
    leaf = ((cols - 200) / 150) ** 2 + ((rows - 150) / 90) ** 2 < 1
    leaf[150, :] = True  # a midrib running out to both sides: many equal distances
    for mask in (leaf, ~leaf, leaf[::-1].copy(), np.eye(7, dtype=bool)):
        assert _same(mask)


def test_the_kernel_answers_once_measurings_kernels_are_compiled(answered_by, monkeypatch):
    called = []
    kernel = raster._feature_transform
    monkeypatch.setattr(raster, "_feature_transform", lambda m: called.append(1) or kernel(m))
    nearest_set_pixel(np.eye(5, dtype=bool))
    assert called == ([1] if answered_by == "kernel" else [])


def test_an_empty_mask_has_no_nearest_pixel_and_3d_is_refused():
    rows, cols = nearest_set_pixel(np.zeros((3, 4), bool))
    assert (rows == -1).all() and (cols == -1).all() and rows.shape == (3, 4)
    assert nearest_set_pixel(np.zeros((0, 5), bool))[0].shape == (0, 5)
    with pytest.raises(ValueError, match="2D"):
        nearest_set_pixel(np.ones((2, 2, 2), bool))
