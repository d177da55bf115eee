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
