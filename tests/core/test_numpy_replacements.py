"""Each hand-written replacement of a numpy or scipy call (cpu39) against the call it replaced,
over random and edge inputs: empty, one value, NaN, ±inf, ±0, subnormals, float32, strided and
Fortran-ordered arrays, the per-thread RandomState from several threads (review39: all held to
the bit at 3,000 examples each, /work/notes/review39/test_prop_cpu39.py)."""

from __future__ import annotations

import threading

import numpy as np
import scipy.sparse
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from leafstudio.core import buckets, gmm
from leafstudio.core.bending import SHARP, _percentile, _rows_times
from leafstudio.core.prepare import polygon

SPECIAL = st.sampled_from([0.0, -0.0, np.nan, np.inf, -np.inf, 1e-308, 5e-324, 1e308, -1.0, 1.0])
FLOATS = st.one_of(st.floats(allow_nan=True, allow_infinity=True, width=64), SPECIAL)


def _bits(a: object, b: object) -> bool:
    """The same bytes (a NaN's payload and a zero's sign included)."""
    return np.asarray(a).tobytes() == np.asarray(b).tobytes()


@settings(max_examples=200, deadline=None, derandomize=True)
@given(hnp.arrays(np.float64, st.integers(0, 40), elements=FLOATS))
def test_median(values):
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert _bits(buckets.median(values), float(np.median(values)))
        assert _bits(buckets.median(values[::-2]), float(np.median(values[::-2])))


@settings(max_examples=200, deadline=None, derandomize=True)
@given(
    hnp.arrays(
        st.sampled_from([np.float32, np.float64]),
        st.integers(1, 60),
        elements=st.floats(width=32) | st.sampled_from([0.0, -0.0, 1.0, 2.0]),
    ),
    st.sampled_from([SHARP, 0.0, 50.0, 99.9, 100.0, 37.3]),
)
def test_percentile(a, q):
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        size = np.abs(a)
        got, want = _percentile(size, q), float(np.percentile(size, q))
        # a NaN's payload is not read: sharpest drops any non-finite percentile
        assert _bits(got, want) or (np.isnan(got) and np.isnan(want))


@settings(max_examples=200, deadline=None, derandomize=True)
@given(
    hnp.arrays(
        np.float64,
        hnp.array_shapes(min_dims=2, max_dims=2, min_side=1, max_side=30),
        elements=FLOATS,
    ),
    st.booleans(),
)
def test_bounds(xy, fortran):
    xy = np.asfortranarray(xy) if fortran else xy
    cols = xy.T
    lo, hi = buckets.bounds(xy)
    assert _bits(lo, np.array([c.min() for c in cols]))
    assert _bits(hi, np.array([c.max() for c in cols]))
    lo, hi = buckets.bounds(xy, lambda p: (p.min(axis=0), p.max(axis=0)))
    assert _bits(lo, xy.min(axis=0)) and _bits(hi, xy.max(axis=0))


@settings(max_examples=200, deadline=None, derandomize=True)
@given(
    hnp.arrays(
        np.float64,
        st.tuples(st.integers(1, 80), st.just(2)),
        elements=st.floats(-1e150, 1e150, allow_nan=False),
    )
)
def test_column_variances(x):
    assert _bits(gmm._column_variances(buckets.kernel_array(x)), np.var(x, axis=0))


@settings(max_examples=200, deadline=None, derandomize=True)
@given(st.integers(0, 2**32 - 1), st.integers(1, 6))
def test_seeded_state(seed, k):
    rng = np.random.default_rng(seed)
    x = rng.standard_normal((60, 2))
    gmm._seeded(123).standard_normal()  # leave a cached gauss behind
    a = gmm._kmeans_plus_plus(x, k, gmm._seeded(seed))
    b = gmm._kmeans_plus_plus(x, k, np.random.RandomState(seed))
    assert _bits(a, b)


def test_seeded_per_thread():
    x = np.random.default_rng(0).standard_normal((500, 2))
    want = gmm._kmeans_plus_plus(x, 5, np.random.RandomState(7))
    bad = []

    def lane():
        for _ in range(200):
            if not _bits(gmm._kmeans_plus_plus(x, 5, gmm._seeded(7)), want):
                bad.append(1)

    lanes = [threading.Thread(target=lane) for _ in range(4)]
    for thread in lanes:
        thread.start()
    for thread in lanes:
        thread.join()
    assert not bad


@settings(max_examples=200, deadline=None, derandomize=True)
@given(st.integers(0, 10**6), st.integers(1, 40), st.integers(1, 30), st.integers(1, 5))
def test_rows_times(seed, n, r, m):
    rng = np.random.default_rng(seed)
    d = scipy.sparse.random(r, n, density=0.3, random_state=seed, dtype=np.float32, format="csr")
    x = rng.standard_normal((n, m)).astype(np.float32)
    v = rng.standard_normal(n).astype(np.float32)
    rows = np.flatnonzero(rng.random(r) < 0.5)
    if not len(rows):
        return
    a, b = _rows_times(d.indptr, d.indices, d.data, rows, x, v)
    assert _bits(a, np.asarray(d[rows] @ x)) and _bits(b, np.asarray(d[rows] @ v))


@settings(max_examples=200, deadline=None, derandomize=True)
@given(
    hnp.arrays(
        np.float64,
        st.tuples(st.integers(0, 30), st.just(2)),
        elements=st.floats(-1e6, 1e6) | SPECIAL,
    ),
    st.sampled_from([None, 0.5, 1e-3]),
    st.sampled_from([0.25, 4.0]),
)
def test_bucket_side(xy, size, per):
    xy = buckets.kernel_array(xy)
    lo, hi = buckets.bounds(xy) if len(xy) else (np.zeros(2), np.ones(2))
    side = buckets._side(lo, hi, len(xy), size, per)
    if side is None:
        return
    extent = np.maximum(hi - lo, 1e-300)
    s = size
    if s is None:
        s = float(np.sqrt(extent[0] * extent[1] * per / max(len(xy), 1)))
        s = max(s, float(extent.max()) / 4096)
        if float(extent.max()) <= 1e-300:
            s = 1.0
    nx, ny = (np.floor(extent / s).astype(np.int64) + 1).tolist()
    assert side == (float(s), nx, ny) and _bits(side[0], float(s))


@settings(max_examples=200, deadline=None, derandomize=True)
@given(
    hnp.arrays(
        np.float64,
        st.tuples(st.integers(2, 60), st.just(2)),
        elements=st.sampled_from([0.0, 1e-9, 2e-9, 0.5, 1.0, -0.0, 3e-10]),
    ),
    st.floats(1e-10, 1e-8),
)
def test_apart_in_the_plane(points, reach):
    from scipy.spatial import cKDTree

    if polygon._apart_in_the_plane(points, reach):
        assert not len(cKDTree(points).query_pairs(reach, output_type="ndarray"))
