"""Step 5's output (section 3.5), the reconstructed mesh as plain arrays, and what the measurements
read of any triangle mesh.

The pipeline builds its mesh as numpy arrays and only wraps them in a pyvista.PolyData when one is
asked for (Result.mesh). A run then never imports VTK (about 60 MB and a third of a second), and
the app's worker threads never create a VTK object: they hand arrays to the main thread, which
makes the datasets it draws (gui/model/layers.py).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

# the curvatures a mesh's vertices carry (core/curvature.py): here, with no kernels, for the
# command line's `--colour-by` choices (render/figure.FIGURE_SCALARS)
CURVATURE_ARRAYS = ("mean_curvature", "gaussian_curvature", "k1", "k2")
CURVATURE_PERCENTILE = 95  # a curvature's colours span ± this percentile of |value| (the
# margins and a narrow tip, where the taper is steep, spike)


def colour_range(name: str, values: np.ndarray) -> tuple[float, float]:
    """The range a point array's colours span (the app's mesh and `--figure`): height its
    finite values' full range, a curvature symmetric about 0 (its middle colour) to ±
    CURVATURE_PERCENTILE of |value|; an array of one value, that value ± 1.

    Examples
    --------
    >>> colour_range("mean_curvature", np.array([-1.0, 0.5, 2.0, np.nan]))
    (-1.9, 1.9)
    >>> colour_range("height", np.zeros(3))
    (-1.0, 1.0)
    """
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values)]
    if len(values) == 0:
        return -1.0, 1.0
    if name in CURVATURE_ARRAYS:
        hi = float(np.percentile(np.abs(values), CURVATURE_PERCENTILE))
        lo = -hi
    else:
        lo, hi = float(values.min()), float(values.max())
    if hi - lo <= 1e-12 * max(abs(hi), 1.0):
        lo, hi = lo - 1.0, hi + 1.0  # one value: any range shows one colour
    return lo, hi


if TYPE_CHECKING:
    import pyvista as pv


class MeshLike(Protocol):
    """What the measurements read of a triangle mesh: a TriangleMesh or an all-triangle
    pyvista.PolyData both have it."""

    @property
    def points(self) -> Any: ...  # (n, 3)

    @property
    def regular_faces(self) -> Any: ...  # (m, 3) vertex indices

    @property
    def point_data(self) -> Any: ...  # name -> (n,) array; supports `in`

    @property
    def n_points(self) -> int: ...


@dataclass(frozen=True, eq=False)
class TriangleMesh:
    """(n, 3) points, (m, 3) triangles and named (n,) point arrays; the mesh stage's (a run at
    unit size, steps.compute_mesh) also has its surface's jet, (n, 5) ∇z and ∇²z at each point
    in the run's plane (zx, zy, zxx, zxy, zyy): what a bend takes the bent surface's curvatures
    from (core/bent_curvature.py); never exported, and None on every mesh made from it."""

    points: np.ndarray
    regular_faces: np.ndarray
    point_data: dict[str, np.ndarray] = field(default_factory=dict)
    jet: np.ndarray | None = field(default=None, repr=False)

    @property
    def n_points(self) -> int:
        return len(self.points)

    def to_pyvista(self) -> pv.PolyData:
        """A pyvista.PolyData of the mesh with its point arrays (see polydata)."""
        return polydata(self.points, self.regular_faces, self.point_data)


def polydata(
    points: np.ndarray,
    faces: np.ndarray,
    point_data: Mapping[str, np.ndarray] | None = None,
    normals: np.ndarray | None = None,
) -> pv.PolyData:
    """A pyvista.PolyData of (m, k) faces of the same size (an (m, k) array: VTK's padded flat
    format is refused) over (n, 3) points, with point arrays and, given, the (n, 3) shading
    normals (VTK imported here, on first use).

    Every array is copied into VTK's own memory, cells as offsets and connectivity (VTK's usual
    storage): the dataset then owes nothing to numpy arrays that may be freed before it, and the
    copies cost about a millisecond at grid 512, where VTK's legacy (k, a, b, ...) face import
    took 7-30.
    """
    import pyvista as pv

    faces = np.asarray(faces)
    if faces.ndim != 2:
        raise ValueError(f"faces must be an (m, k) array, got shape {faces.shape}")
    offsets = np.arange(0, faces.size + 1, max(faces.shape[1], 1))
    cells = pv.CellArray.from_arrays(offsets, faces.ravel(), deep=True)
    mesh = pv.PolyData(np.asarray(points, dtype=float), faces=cells, deep=True)
    for name, values in (point_data or {}).items():
        mesh.point_data.set_array(values, name, deep_copy=True)
    if normals is not None and len(normals):
        mesh.point_data.set_array(normals, "Normals", deep_copy=True)
        mesh.point_data.active_normals_name = "Normals"
    return mesh


def vertex_normals(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(n, 3) unit normals at the vertices: the area-weighted mean of their triangles' normals
    (each triangle's turning sense sets its side; a vertex without triangles gets 0, 0, 1)."""
    a, b, c = (points[triangles[:, i]] for i in range(3))
    face = np.cross(b - a, c - a)  # its length is twice the area: area-weighted as it stands
    corners = triangles.ravel()
    normals = np.column_stack(
        [np.bincount(corners, np.repeat(face[:, k], 3), minlength=len(points)) for k in range(3)]
    )
    length = np.linalg.norm(normals, axis=1)
    normals[length == 0] = (0.0, 0.0, 1.0)
    return normals / np.where(length == 0, 1.0, length)[:, None]
