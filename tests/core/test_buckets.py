"""buckets.bounds: the compiled path gives numpy's own bounds, bit for bit."""

from __future__ import annotations

import numpy as np

from leafstudio.core.buckets import _bounds, bounds


def _numpys(xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    columns = np.asarray(xy).T
    return np.array([c.min() for c in columns]), np.array([c.max() for c in columns])


def test_bounds_are_numpys_to_the_bit():
    """Ties, ±0, NaN and infinities, 2 and 3 columns, C and Fortran order: the same bit patterns
    as numpy's column reductions (a ±0 or NaN bound is left to them: _bounds says so)."""
    rng = np.random.default_rng(2)
    for trial in range(3000):
        n, d = int(rng.integers(1, 200)), int(rng.choice([2, 3]))
        xy = rng.standard_normal((n, d)) * rng.choice([1e-300, 1.0, 1e300])
        if trial % 3 == 0:
            xy = np.round(xy)
        if trial % 7 == 0:
            xy[rng.integers(n), rng.integers(d)] = rng.choice([np.nan, np.inf, -np.inf, -0.0])
        if trial % 11 == 0:
            xy = np.asfortranarray(xy)
        for got, expected in zip(bounds(xy), _numpys(xy), strict=True):
            assert got.tobytes() == expected.tobytes()


def test_a_zero_or_nan_bound_goes_to_numpy():
    assert _bounds(np.array([[0.0, 1.0], [2.0, 3.0]]))[2]
    assert _bounds(np.array([[np.nan, 1.0], [2.0, 3.0]]))[2]
    assert not _bounds(np.array([[1.0, 1.0], [2.0, 3.0]]))[2]


def test_a_callers_own_reduction_takes_a_zero_bound():
    """bounds(xy, numpys) hands a ±0 bound to the caller's numpy expression (min(axis=0) may
    give a zero the other sign than a column's min), and no other."""
    calls = []

    def own(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        calls.append(len(p))
        return p.min(axis=0), p.max(axis=0)

    lo = bounds(np.array([[-0.0, 1.0], [0.0, 2.0]]), own)[0]
    assert calls == [2] and lo.tobytes() == np.array([[-0.0, 1.0], [0.0, 2.0]]).min(0).tobytes()
    bounds(np.array([[-1.0, 1.0], [3.0, 2.0]]), own)
    assert calls == [2]


def test_median_is_numpys_to_the_bit():
    """buckets.median gives np.median's value, ties, zeros, -0, NaN and infinities among them."""
    from leafstudio.core.buckets import median

    rng = np.random.default_rng(6)
    for trial in range(2000):
        n = int(rng.integers(1, 40 if trial % 2 else 2000))
        x = np.abs(rng.standard_normal(n)) * rng.choice([1e-300, 1.0, 1e300])
        if trial % 3 == 0:
            x = np.round(x, 1)
        if trial % 5 == 0:
            x = -x
        if trial % 13 == 0:
            x[rng.integers(n)] = rng.choice([np.nan, np.inf, -np.inf, -0.0, 0.0])
        got, expected = np.float64(median(x)), np.float64(np.median(x))
        assert got.tobytes() == expected.tobytes()


def test_buckets_sides_in_python_floats_are_numpys():
    """bucket_points' side and counts (buckets._side, Python floats) are numpy's figures."""
    from leafstudio.core.buckets import PER_BUCKET, _side

    rng = np.random.default_rng(9)
    for trial in range(500):
        n = int(rng.integers(1, 300))
        xy = rng.standard_normal((n, 2)) * rng.choice([1e-300, 1e-5, 1.0, 1e100])
        if trial % 7 == 0:
            xy[:] = xy[0]
        lo, hi = bounds(xy)
        extent = np.maximum(hi - lo, 1e-300)
        size = float(np.sqrt(extent[0] * extent[1] * PER_BUCKET / n))
        size = max(size, float(extent.max()) / 4096)
        if float(extent.max()) <= 1e-300:
            size = 1.0
        nx, ny = (np.floor(extent / size).astype(np.int64) + 1).tolist()
        assert _side(lo, hi, n, None, PER_BUCKET) == (size, nx, ny)
