"""A scan's plausibility as one leaf: its refusal stays one readable line."""

from __future__ import annotations

import numpy as np

from leafstudio.core.prepare.plausibility import leaf_like_problems


def test_many_separate_clusters_are_counted_but_not_all_listed():
    """A point list with decimal commas read as a scan (2 points a row: '0,25;1,5;0' is 0, 25,
    1, 5, 0) made 252 clusters of 2 points, and the app's refusal listed all 252 sizes."""
    rng = np.random.default_rng(0)
    centres = rng.uniform(0, 100, size=(60, 2))
    pairs = np.repeat(centres, 2, axis=0) + [[0, 0], [0.01, 0]] * 60
    points = np.column_stack([pairs, np.zeros(len(pairs))])
    (problem, *_) = leaf_like_problems(points)
    assert problem.startswith("not one leaf: 60 large separate clusters of points (2, 2, 2, 2, ")
    assert len(problem) < 120


def test_a_scan_with_gross_outliers_is_measured_by_its_leaf():
    """Fuzzing finding (hunt26): 5% of a scan's points thrown up to two lengths away (a
    scanner's stray returns), which the extraction drops as outliers, made the thickness test
    refuse the scan as "not thin: its thickness is 0.67 of its length" (a real scan with 3%
    of its points so: 0.63 to 0.77). The thickness is now the largest cluster's: the leaf's."""
    from tests.leaves import synthetic_scan

    rng = np.random.default_rng(1)
    parts = synthetic_scan(seed=3)
    leaf = np.vstack([parts["blade"], parts["petiole"]])
    strays = rng.uniform(-2, 2, (len(leaf) // 20, 3))
    assert leaf_like_problems(np.vstack([leaf, strays])) == []
    blob = rng.normal(size=(3000, 3)) * [1.0, 0.8, 0.7]  # a volume stays refused
    assert any(p.startswith("not thin") for p in leaf_like_problems(blob))
