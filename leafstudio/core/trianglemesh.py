"""The reconstructed mesh as plain arrays, and what the measurements read of any triangle mesh.

The pipeline builds its mesh as numpy arrays and only wraps them in a pyvista.PolyData when one is
asked for (Result.mesh). The core then never imports VTK (about 60 MB and a third of a second),
and a worker thread never creates a VTK object: the app asks for the PolyData on its main thread.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

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


@dataclass(frozen=True)
class TriangleMesh:
    """(n, 3) points, (m, 3) triangles and named (n,) point arrays."""

    points: np.ndarray
    regular_faces: np.ndarray
    point_data: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def n_points(self) -> int:
        return len(self.points)

    def to_pyvista(self) -> pv.PolyData:
        """A pyvista.PolyData of the mesh with its point arrays (VTK imported here, on first
        use)."""
        import pyvista as pv

        # regular faces: VTK's legacy (3, a, b, c) import took 7-30 ms at grid 512, this under 1
        mesh = pv.PolyData.from_regular_faces(self.points, self.regular_faces)
        mesh.point_data.update(self.point_data)
        return mesh
