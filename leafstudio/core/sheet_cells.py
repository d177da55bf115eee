"""How finely a scan's blade is cut for its sheet (core/sheet.py): cubes of the 3D points whose
means are unrolled, then square cells of the flat blade that the sheet is refitted through.

A blade's length is cut in CELLS, or fewer on a sparse scan: at about one point a cube the
cube means are the points themselves, the neighbour graph's paths zigzag between the scanner's
rows, and the unrolled blade comes out long (soybean pot1_15 at 300 of its points: 67.3 mm
against 43.4 scanned whole; sugar beet pot2_3 at 300: 57.7 against 44.6). At least PER_CUBE
points a cube keep it near its whole scan's (42.4 and 45.5 mm); the eight shared scans, whole,
hold 2.9 to 13 and are cut as before.
"""

from __future__ import annotations

import numpy as np

CELLS = 28  # the blade's length is cut in this many cubes; each cube's mean is a centre
# a sheet of length L crosses at most about 2 CELLS**2 of the cubes of side L / CELLS (the eight
# shared scans: 283 to 1,119 cubes); points that fill many more fill a volume, not a sheet (a
# Gaussian blob of 15,000 points: 8,946 cubes, and the spline through them took 17 s)
VOLUME = 3  # ... more than VOLUME cells**2 cubes: a volume
PER_CUBE = 2.5  # a sparser blade is cut in fewer cubes (module docstring)
FEWEST_CELLS = 8
FEW = 4  # a cell of fewer points takes the typical cell's spread across the blade (`mean_errors`)
FLOOR = 0.5  # ... and every cell's spread is taken with this many typical spreads more


def cubes(points: np.ndarray, side: float) -> tuple[np.ndarray, np.ndarray]:
    """Each of the (n, k) points' cube of `side` (n,) and the cubes' counts of points, in the
    order of their first corner (numpy's unique rows)."""
    keys = np.floor((points - points.min(axis=0)) / side).astype(np.int64)
    _, which, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    return which.ravel(), counts


def cut(points: np.ndarray, length: float) -> tuple[int, np.ndarray, np.ndarray]:
    """How many cubes the (n, 3) blade points' `length` is cut in: CELLS, or fewer until they
    hold PER_CUBE points each on average (FEWEST_CELLS at least); with each point's cube and
    the cubes' counts at that cut (`cubes`)."""
    cells = CELLS
    while True:
        cube, counts = cubes(points, length / cells)
        if cells <= FEWEST_CELLS or len(points) >= PER_CUBE * len(counts):
            return cells, cube, counts
        cells = max(FEWEST_CELLS, int(cells * np.sqrt(len(points) / (PER_CUBE * len(counts)))))


def mean_errors(points: np.ndarray, which: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Each cell's mean's variance across the blade, (spread + FLOOR typical) / count, from the
    (n, 3) `points`, their (n,) cells `which` and the cells' `counts`. The spread is the least
    variance of the cell's points in 3D (their covariance's smallest eigenvalue: across their
    own best plane, whatever the sheet they were flattened by): a cell across a doubled layer or
    a scanner's stripe spreads wide and its mean is less sure than a clean patch's, a cell on a
    tight roll's edge does not (refit weighs the spline's smoothing by it). Cells of fewer than
    FEW points take the typical (median) spread.

    Examples
    --------
    >>> x, y = (a.ravel() for a in np.meshgrid([0.0, 3.0, 6.0, 9.0], [0.0, 3.0, 6.0, 9.0]))
    >>> tilted = np.column_stack([x, y, x])  # a plane: no spread across it
    >>> doubled = np.column_stack([x, y, np.tile([-1.0, 1, 1, -1, 1, -1, -1, 1], 2)])  # 2 apart
    >>> which, counts = np.repeat([0, 1], 16), np.array([16, 16])
    >>> mean_errors(np.vstack([tilted, doubled]), which, counts).round(4)  # spread 0 and 1
    array([0.0156, 0.0781])
    """
    cells = len(counts)
    sums, products = np.zeros((cells, 3)), np.zeros((cells, 3, 3))
    np.add.at(sums, which, points)
    np.add.at(products, which, points[:, :, None] * points[:, None, :])
    many = counts >= FEW
    spread = np.zeros(cells)
    if many.any():
        mean = sums[many] / counts[many, None]
        covariance = products[many] / counts[many, None, None] - mean[:, :, None] * mean[:, None]
        spread[many] = np.maximum(np.linalg.eigvalsh(covariance)[:, 0], 0.0)
    typical = float(np.median(spread[many])) if many.any() else 0.0
    spread = np.where(many, spread, typical)
    return (spread + FLOOR * typical) / counts
