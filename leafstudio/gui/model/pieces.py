"""A layer's drawable piece and the small wrappers that turn arrays into VTK datasets (on the
main thread, when the viewport first asks). No Qt here."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
import pyvista as pv

from leafstudio.gui.model.thinning import DISPLAY_POINTS, thinned

__all__ = ["DISPLAY_POINTS", "Piece", "cloud", "dots", "polylines", "thinned"]

SPHERE_POINTS = 10_000  # above this many, points are drawn small and flat: the mesh shows through


@dataclass(eq=False)
class Piece:
    """One actor: a name unique in the scene, how to make its dataset, and its add_mesh keywords.

    `make` wraps arrays prepared beforehand into a VTK dataset, cheaply; `data` calls it once, on
    the main thread (the viewport), where VTK objects belong.
    """

    name: str
    make: Callable[[], pv.DataSet]
    style: dict[str, Any] = field(default_factory=dict)
    ranges: dict[str, tuple[float, float]] = field(default_factory=dict)  # colour range per array
    make_full: Callable[[], pv.DataSet] | None = None  # the whole dataset, when `make` draws less

    @cached_property
    def data(self) -> pv.DataSet:
        return self.make()

    @cached_property
    def full_data(self) -> pv.DataSet:
        """The whole dataset (a large mesh's every triangle, for its edges); else `data`."""
        return self.make_full() if self.make_full is not None else self.data


def cloud(points: np.ndarray) -> pv.PolyData:
    """Points as a PolyData of vertices (an empty one for no points), copied into VTK."""
    return pv.PolyData(np.asarray(points, dtype=float), deep=True) if len(points) else pv.PolyData()


def dots(color: str, size: float, count: int = 0) -> dict[str, Any]:
    """The style of `count` points drawn: spheres of `size` pixels, or, for many, flat points of
    at most 2 pixels, which leave the mesh under a dense layer visible."""
    if count > SPHERE_POINTS:
        return {"color": color, "point_size": min(size, 2.0)}
    return {"color": color, "point_size": size, "render_points_as_spheres": True}


def polylines(lines: list[np.ndarray]) -> pv.PolyData:
    """(n_i, 3) polylines as one PolyData of line cells."""
    if not lines:
        return pv.PolyData()
    sizes = [len(line) for line in lines]
    starts = np.cumsum([0, *sizes[:-1]])
    cells = np.concatenate(
        [np.r_[size, start + np.arange(size)] for size, start in zip(sizes, starts, strict=True)]
    )
    return pv.PolyData(np.vstack(lines), lines=cells, deep=True)
