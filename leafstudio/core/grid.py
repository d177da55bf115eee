"""Steps 3-5, where they sample: the regular grid over the leaf's bounding box in the plane
(p(x), the EM samples' cells and z are taken at its nodes; the pipeline's grid stage)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Grid:
    """A square-celled grid: `shape` = (ny, nx) nodes from `origin` with spacing `spacing`.

    `points`, the (ny * nx, 2) node coordinates (x varying fastest, read-only), are made with
    the grid: the grid stage's output holds them, so they live in the pipeline's one cache with
    it (store.py) instead of a cache of their own.
    """

    origin: np.ndarray
    spacing: float
    shape: tuple[int, int]
    points: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        ny, nx = self.shape
        points = np.empty((ny, nx, 2))
        points[:, :, 0] = self.origin[0] + self.spacing * np.arange(nx)
        points[:, :, 1] = (self.origin[1] + self.spacing * np.arange(ny))[:, None]
        points = points.reshape(-1, 2)
        points.flags.writeable = False
        object.__setattr__(self, "points", points)  # frozen: set once, here


def make_grid(points: np.ndarray, resolution: int) -> Grid:
    """A grid with `resolution` nodes along the longer side of the points' box, plus one cell of
    margin all round so that the zero level of g never touches the grid's edge."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    spacing = float((hi - lo).max()) / (resolution - 1)
    lo = lo - spacing
    counts = np.ceil((hi + spacing - lo) / spacing).astype(int) + 1
    return Grid(origin=lo, spacing=spacing, shape=(int(counts[1]), int(counts[0])))
