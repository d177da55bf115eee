"""`extract` at scan scale and at any size (issue 10, finding 3): large scans are thinned to voxel
centroids (the work no longer grows with the square of the points), the masks still cover every
point, and degenerate or huge scans end in a LeafError, not a crash."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely

from leafstudio.errors import LeafError
from leafstudio.sources import extract
from leafstudio.sources.extract import extract_leaf
from leafstudio.sources.scan import read_scan
from leafstudio.sources.scan_thinning import voxel_thinning
from tests.leaves import assert_outline_is_the_blades, scan_surface, synthetic_scan

REAL = Path(__file__).resolve().parents[3] / "shared" / "realleaves"
CURLED = REAL / "soybean_11_20190508T043118_pot1_1.txt"  # curled: its sheet folds over


def _big_scan(n: int, seed: int = 3) -> tuple[np.ndarray, int]:
    """n blade points on the known surface, a petiole at -x and a few outliers; and n."""
    parts = synthetic_scan(seed, int(2.2 * n), n, n // 60, n // 400)
    return np.vstack([parts["blade"], parts["petiole"], parts["outliers"]]), n


@pytest.fixture(scope="module")
def big():
    points, n = _big_scan(120_000)
    return points, n, extract_leaf(points)


SMALL_BUDGET = 8000  # a budget and a scan three times it, for the tests that extract it again


@pytest.fixture(scope="module")
def budgeted():
    """A scan three times a smaller BUDGET and its extraction: what the flattening and the
    thinning do does not depend on the budget's size, and each extraction at 40,000 thinned
    points took 8 s (the tests below extract the scan a second time)."""
    points, _ = _big_scan(3 * SMALL_BUDGET)
    with pytest.MonkeyPatch.context() as monkeypatch:
        monkeypatch.setattr(extract, "BUDGET", SMALL_BUDGET)
        found = extract_leaf(points)
    assert found.blade.sum() > SMALL_BUDGET  # thinned, each point mapped to its cube
    return points, found


def test_a_large_scan_is_thinned_and_its_outline_is_the_blade(big):
    points, n, found = big
    assert_outline_is_the_blades(found)
    assert len(found.blade) == len(points) and len(found.petiole) == len(points)
    assert found.blade[:n].mean() > 0.99
    assert not found.blade[n + n // 60 :].any()  # no outlier
    far_petiole = points[n : n + n // 60, 0] < -0.56
    assert not found.blade[n : n + n // 60][far_petiole].any()
    assert found.length == pytest.approx(1.0, abs=0.03)
    b = found.leaf.boundary
    assert np.abs(b[:, 2] - scan_surface(b[:, 0], b[:, 1])).max() < 4e-3


def test_a_large_scan_flattens_only_its_margin_and_ends_and_loses_nothing(budgeted, monkeypatch):
    """Only the points of cubes near the outline or the blade's ends are flattened (issue 24: a
    2-million-point scan spent most of its opening flattening every point): the masks and the
    length are those that flattening every point gives."""
    points, found = budgeted
    monkeypatch.setattr(extract, "BUDGET", SMALL_BUDGET)
    monkeypatch.setattr(extract, "ENDS", 1e9)  # every cube counts as at an end
    every = extract_leaf(points)
    np.testing.assert_array_equal(found.blade, every.blade)
    np.testing.assert_array_equal(found.petiole, every.petiole)
    assert found.length == pytest.approx(every.length, rel=1e-9)


def test_a_large_scan_is_thinned_once_for_its_check_and_its_extraction(budgeted, monkeypatch):
    """Opening a scan thins it once (issue 24): check_scan and extract_leaf both thinned the
    scan's points before, a second each for 2 million; the extraction is the same."""
    from leafstudio import workflows

    points, found = budgeted
    monkeypatch.setattr(extract, "BUDGET", SMALL_BUDGET)
    calls = []

    def counted(at: np.ndarray, budget: int):
        calls.append(len(at))
        return voxel_thinning(at, budget)

    monkeypatch.setattr(extract, "voxel_thinning", counted)
    opened = workflows._scan_opened("big.xyz", points)
    assert calls == [len(points)]
    np.testing.assert_array_equal(opened.extraction.blade, found.blade)
    np.testing.assert_array_equal(opened.leaf.boundary, found.leaf.boundary)


def test_voxel_thinning_keeps_at_most_the_budget_and_maps_every_point():
    rng = np.random.default_rng(0)
    blob = rng.normal(size=(200_000, 3))  # a volume, not a surface: the first guess overshoots
    kept, cell, size = voxel_thinning(blob, 5000)
    assert 2500 <= len(kept) <= 5000
    assert cell is not None and cell.shape == (len(blob),) and cell.max() == len(kept) - 1
    # each centroid is the mean of the points mapped to it
    for c in (0, len(kept) // 2, len(kept) - 1):
        np.testing.assert_allclose(kept[c], blob[cell == c].mean(axis=0), atol=1e-12)
        inside = blob[cell == c]  # one cube's points: within its diagonal (the cubes are
        spread = np.linalg.norm(inside[:, None] - inside[None], axis=2).max()  # turned)
        assert spread <= np.sqrt(3) * size
    same, none, zero = voxel_thinning(blob[:100], 5000)
    assert none is None and zero == 0 and np.array_equal(same, blob[:100])


def test_a_blob_larger_than_the_budget_is_refused_cleanly_or_read(monkeypatch):
    monkeypatch.setattr(extract, "BUDGET", SMALL_BUDGET)  # thinned as a larger one is
    rng = np.random.default_rng(1)
    blob = rng.normal(size=(3 * SMALL_BUDGET, 3))
    try:
        extract_leaf(blob)
    except LeafError as exc:
        assert "\n" not in str(exc)


def test_a_noisy_line_is_a_leaf_error_not_a_crash():
    rng = np.random.default_rng(0)
    t = rng.uniform(0, 1, 2000)
    line = np.column_stack([t, 1e-3 * rng.normal(size=2000), 1e-3 * rng.normal(size=2000)])
    with pytest.raises(LeafError):
        extract_leaf(line)


@pytest.fixture(scope="module")
def unit_scale():
    """A scan of 6000 blade points and its extraction, once for both factors below."""
    points, _ = _big_scan(6000, seed=4)
    return points, extract_leaf(points)


@pytest.mark.parametrize("factor", [1e-9, 1e200])
def test_a_scan_in_any_units_gives_the_same_leaf_scaled(factor, unit_scale):
    points, base = unit_scale
    scaled = extract_leaf(points * factor)
    assert scaled.length == pytest.approx(base.length * factor, rel=1e-9)
    np.testing.assert_allclose(scaled.leaf.boundary / factor, base.leaf.boundary, atol=1e-9)
    np.testing.assert_array_equal(scaled.blade, base.blade)


@pytest.mark.skipif(not CURLED.exists(), reason=f"no real scan at {CURLED}")
def test_a_curled_scans_blade_and_petiole_do_not_depend_on_its_size_or_place():
    """Soybean pot1_1 scaled by 3 split 3103 blade and 180 petiole points, unscaled 3109 and
    174: at unit size the two differ in their last bits, and the sheet its curled blade is
    unrolled onto was sampled on another grid (core/sheet.py), flattening a few points onto
    another layer of the curl."""
    from leafstudio._shared.blas import one_blas_thread

    points = read_scan(CURLED)
    with one_blas_thread():  # as the app and the command line extract
        base = extract_leaf(points)
        for factor, shift in [(1e-3, 0.0), (3.0, 0.0), (1e3, 0.0), (1.0, 1e4), (0.7, -55.5)]:
            moved = extract_leaf(points * factor + shift)
            what = f"x {factor} + {shift}"
            np.testing.assert_array_equal(moved.blade, base.blade, err_msg=what)
            np.testing.assert_array_equal(moved.petiole, base.petiole, err_msg=what)
            assert moved.length == pytest.approx(base.length * factor, rel=1e-5), what


MIRRORED = np.array([1.0, 1.0, -1.0])  # z negated: a left-handed scanner's frame


def test_a_mirrored_scan_gives_the_same_leaf_mirrored(budgeted, monkeypatch):
    """A scan in a left-handed frame (z negated) was thinned in other cubes and its blade
    unrolled from other cube means (both cut along the world's axes from the lowest corner):
    another flat blade. Now both are cut in the scan's own frame (plane.grid_frame)."""
    points, base = budgeted
    monkeypatch.setattr(extract, "BUDGET", SMALL_BUDGET)  # thinned, as `budgeted` was
    mirrored = extract_leaf(points * MIRRORED)
    np.testing.assert_array_equal(mirrored.blade, base.blade)
    np.testing.assert_array_equal(mirrored.petiole, base.petiole)
    assert mirrored.length == pytest.approx(base.length, rel=1e-9)
    size = float(np.ptp(points, axis=0).max())
    np.testing.assert_allclose(
        mirrored.leaf.boundary * MIRRORED, base.leaf.boundary, atol=1e-9 * size
    )


PART_TORN = REAL / "sugarbeet_f00012_20170904T115033_pot1_7.txt"  # a hole torn in its blade


@pytest.mark.skipif(not PART_TORN.exists(), reason=f"no real scan at {PART_TORN}")
def test_a_real_scan_mirrored_gives_the_same_leaf():
    """Sugar beet pot1_7 with z negated unrolled onto another flat blade: 43.0 units long and
    629 in area, not 61.2 and 853 (its petiole took 508 points, not 303); soybean pot1_1 52.1
    long, not 58.6. Turned 180 degrees about x, pot1_7's area was 1098."""
    from leafstudio._shared.blas import one_blas_thread
    from leafstudio.core.evaluate import leaf_blade_length

    def flat_area(found) -> float:
        bend = found.leaf.bend
        return shapely.Polygon(bend.flatten(found.leaf.boundary)[:, :2]).area

    points = read_scan(PART_TORN)
    with one_blas_thread():  # as the app and the command line extract
        base = extract_leaf(points)
        for change in (MIRRORED, np.array([1.0, -1.0, -1.0])):
            moved = extract_leaf(points * change)
            np.testing.assert_array_equal(moved.petiole, base.petiole)
            length = leaf_blade_length(moved.leaf)
            assert length == pytest.approx(leaf_blade_length(base.leaf), rel=1e-6)
            assert flat_area(moved) == pytest.approx(flat_area(base), rel=1e-6)
