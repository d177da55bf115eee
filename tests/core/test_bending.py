"""The lattice whose bending the vein correction's values are chosen for (core/bending.py)."""

from __future__ import annotations

import numpy as np
import pytest

from leafstudio.core import correct
from leafstudio.core.bending import FINE, HEAVIEST, OWN_BENDING, SHARP, lattice, sharpest
from leafstudio.core.buckets import kernel_array
from leafstudio.core.grid import make_grid


@pytest.mark.parametrize("resolution", [40, 128])
def test_the_lattices_rows_are_second_differences_of_its_nodes(resolution):
    """Each row of D is a second difference of the lattice's nodes (stride 1 at grid 40, coarser
    at 128; finer in the margin band): it takes a plane to 0, x² and y² to a positive constant
    on its straight rows and xy to one on its cross rows, and every node it reaches is kept."""
    grid = make_grid(np.array([[-1.0, -0.7], [1.0, 0.7]]), resolution)
    x, y = grid.points.T
    g = 1 - (x / 0.9) ** 2 - (y / 0.6) ** 2  # an ellipse, T = tanh(g / 0.1)
    index = np.flatnonzero(g > 0)
    taper = np.tanh(g[index] / 0.1)
    assert np.any(taper < FINE) and np.any(taper >= FINE)
    on, d, _ = lattice(grid, index, taper)
    xy = grid.points[index[on]]
    assert d.shape == (d.shape[0], len(on)) and d.shape[0] > len(on) // 2
    sizes = np.diff(d.indptr)
    assert set(sizes) <= {3, 4}
    np.testing.assert_allclose(d @ (0.3 + 2.0 * xy[:, 0] - 1.5 * xy[:, 1]), 0, atol=1e-5)
    straight, cross = sizes == 3, sizes == 4
    for values, rows in (
        (xy[:, 0] ** 2 + xy[:, 1] ** 2, straight),
        (xy[:, 0] * xy[:, 1], cross),
    ):
        bent = d @ values
        assert np.all(bent[rows] > 0)
    np.testing.assert_allclose((d @ (xy[:, 0] * xy[:, 1]))[straight], 0, atol=1e-5)


def test_cs_own_energy_is_weighed_as_the_lattice_measures_c():
    """bending.own_weight: c's own energy (2π/ℓ²) wᵀΦw in the lattice's units, h² ∫ (Δc)² +
    c²/ℓ⁴, against the lattice's sum |D c|² for the same c (three centres, all inside): the same
    share of it at two grids (the lattice's h² taken right: 0.50 at grid 128, 0.54 at 256), a
    share near 1 (the lattice weighs the cross difference twice as the thin plate does, and
    under-reads the log-singular bend at each centre)."""
    centers = kernel_array(np.array([[0.0, 0.0], [0.05, 0.02], [-0.04, 0.03]]))
    weights = np.array([1.0, -0.5, 0.7])
    shares = []
    for resolution in (128, 256):
        grid = make_grid(np.array([[-0.6, -0.6], [0.6, 0.6]]), resolution)
        inside = np.ones(len(grid.points), dtype=bool)
        bending = correct.lattice_bending(centers, 1.0, grid, inside, np.ones(len(inside)))
        c = (bending.phi @ weights).astype(np.float32)
        measured = float(np.sum((bending.differences @ c) ** 2))
        shares.append(measured / (bending.own / OWN_BENDING * (weights @ bending.among @ weights)))
    assert abs(shares[0] - shares[1]) <= 0.1 * shares[0]
    assert 0.3 <= shares[0] <= 1.5


def test_only_the_sharpest_rows_weigh_more_and_no_row_past_the_cap():
    """bending.sharpest: the rows bending more than the SHARP-th percentile s take (b/s)² more
    weight, the others none; the mean weight's growth is the sum over all rows; one row bending
    a hundred times s weighs no more than HEAVIEST times the rows' mean weight."""
    rng = np.random.default_rng(1)
    bends = rng.normal(size=1000).astype(np.float32)
    bends[7] = 100.0 * np.percentile(np.abs(bends), SHARP)
    rows, extra, more = sharpest(bends)
    s = np.percentile(np.abs(bends), SHARP)
    assert set(rows) == set(np.flatnonzero(np.abs(bends) > s))
    assert len(rows) == pytest.approx((100 - SHARP) / 100 * len(bends), abs=2)
    raw = (bends[rows].astype(float) / s) ** 2
    assert more == pytest.approx(raw.sum() / len(bends))
    assert np.all(1 + extra <= HEAVIEST * (1 + more) + 1e-12)
    np.testing.assert_allclose(extra[rows != 7], raw[rows != 7])
    assert extra[rows == 7][0] < raw[rows == 7][0]
    flat = sharpest(np.zeros(10, dtype=np.float32))
    assert len(flat[0]) == 0 and flat[2] == 0.0


def test_sharpest_reads_numpys_own_percentile():
    """bending._percentile (sharpest's threshold) is np.percentile's 'linear' value to the bit,
    ties and a NaN among the values too, in single precision as the lattice's bends are."""
    from leafstudio.core.bending import _percentile

    rng = np.random.default_rng(3)
    for trial in range(600):
        n = int(rng.integers(1, 40 if trial % 2 else 5000))
        a = np.abs(rng.standard_normal(n) * rng.choice([1e-3, 1.0, 1e4])).astype(np.float32)
        if trial % 3 == 0:
            a = np.round(a, 1)
        if trial % 97 == 0:
            a[rng.integers(n)] = np.nan
        expected = float(np.percentile(a, SHARP))
        got = _percentile(a, SHARP)
        assert got == expected or (np.isnan(got) and np.isnan(expected)), (n, got, expected)


def test_the_sharpest_rows_products_are_scipys():
    """bending._rows_times (least_bending's second solve) gives scipy's D[rows] @ X and
    D[rows] @ v to the bit, in single precision, on a lattice's D."""
    from leafstudio.core.bending import _rows_times

    grid = make_grid(np.array([[-1.0, -0.7], [1.0, 0.7]]), 128)
    x, y = grid.points.T
    g = 1 - (x / 0.9) ** 2 - (y / 0.6) ** 2
    index = np.flatnonzero(g > 0)
    d = lattice(grid, index, np.tanh(g[index] / 0.1))[1]
    rng = np.random.default_rng(5)
    many = rng.standard_normal((d.shape[1], 37)).astype(np.float32)
    one = rng.standard_normal(d.shape[1]).astype(np.float32)
    rows = np.sort(rng.choice(d.shape[0], d.shape[0] // 10, replace=False))
    got_many, got_one = _rows_times(d.indptr, d.indices, d.data, rows, many, one)
    assert got_many.dtype == got_one.dtype == np.float32
    np.testing.assert_array_equal(got_many, d[rows] @ many)
    np.testing.assert_array_equal(got_one, d[rows] @ one)
