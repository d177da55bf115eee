"""Steps 3-5, where they sample: the regular grid over the leaf's bounding box in the plane
(p(x), the EM samples' cells and z are taken at its nodes; the pipeline's grid stage)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np


@dataclass(frozen=True)
class Grid:
    """A square-celled grid: `shape` = (ny, nx) nodes from `origin` with spacing `spacing`."""

    origin: np.ndarray
    spacing: float
    shape: tuple[int, int]

    @cached_property
    def points(self) -> np.ndarray:
        """(ny * nx, 2) node coordinates, x varying fastest (computed once: read-only)."""
        ny, nx = self.shape
        xs = self.origin[0] + self.spacing * np.arange(nx)
        ys = self.origin[1] + self.spacing * np.arange(ny)
        gx, gy = np.meshgrid(xs, ys)
        points = np.column_stack([gx.ravel(), gy.ravel()])
        points.flags.writeable = False
        return points


def make_grid(points: np.ndarray, resolution: int) -> Grid:
    """A grid with `resolution` nodes along the longer side of the points' box, plus one cell of
    margin all round so that the zero level of g never touches the grid's edge."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    spacing = float((hi - lo).max()) / (resolution - 1)
    lo = lo - spacing
    counts = np.ceil((hi + spacing - lo) / spacing).astype(int) + 1
    return Grid(origin=lo, spacing=spacing, shape=(int(counts[1]), int(counts[0])))
