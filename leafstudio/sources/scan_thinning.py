"""A large scan thinned to the centroids of its occupied cubes (sources/extract.py: the steps of
an extraction then cost the same for 1e5 or 1e7 points)."""

from __future__ import annotations

import numpy as np

from leafstudio.core.plane import fixed_sample, grid_frame

THINNING_PASSES = 8
SAMPLE = 50_000  # the voxel size is first sought on this many of the points


def voxel_thinning(points: np.ndarray, budget: int) -> tuple[np.ndarray, np.ndarray | None, float]:
    """Between budget / 2 and `budget` points standing for (n, 3) `points`: the centroids of the
    occupied cubes of a size tried until their count falls in that range, each point's cube
    (n,), and the cubes' side; the points themselves, None and 0 when there are no more than
    `budget`. A few O(n log n) passes: the first size assumes a surface (on a sample of the
    points, then on all of them), each next one scales by the miss."""
    if len(points) <= budget:
        return points, None, 0.0
    # the cubes along a frame of the points' own (plane.grid_frame): the same cubes for a turned
    # or mirrored scan; the centroids are the points' own (2 million points on a bent sheet:
    # 0.40 s of CPU along the world's axes, 0.67-0.92 s so)
    origin, axes = grid_frame(points)
    at_own = (points - origin) @ axes.T
    lo, hi = at_own.min(axis=0), at_own.max(axis=0)
    size = float(np.max(hi - lo)) / np.sqrt(budget)

    def cells_of(at: np.ndarray, size: float) -> tuple[np.ndarray, np.ndarray]:
        cells = np.floor((at - lo) / size).astype(np.int64)
        dims = np.floor((hi - lo) / size).astype(np.int64) + 1
        keys = (cells[:, 0] * dims[1] + cells[:, 1]) * dims[2] + cells[:, 2]
        _, cell, counts = np.unique(keys, return_inverse=True, return_counts=True)
        return cell, counts

    def adjust(size: float, count: int) -> float:
        return size * float(np.clip(np.sqrt(count / (0.75 * budget)), 0.5, 4.0))

    if len(points) > 2 * SAMPLE:  # a cheap first guess from a sample (it finds fewer cubes)
        sample = fixed_sample(at_own, SAMPLE)
        for _ in range(THINNING_PASSES):
            count = len(cells_of(sample, size)[1])
            if budget // 2 <= count <= budget:
                break
            size = adjust(size, count)
    for _ in range(THINNING_PASSES):
        cell, counts = cells_of(at_own, size)
        if budget // 2 <= len(counts) <= budget:
            break
        size = adjust(size, len(counts))
    if len(counts) > budget:  # not settled: a coarser size surely keeps fewer
        return voxel_thinning(points, budget // 2) if budget > 1 else (points[:1], None, 0.0)
    sums = [np.bincount(cell, weights=points[:, k], minlength=len(counts)) for k in range(3)]
    return np.column_stack(sums) / counts[:, None], cell.ravel(), size
