"""The data the pipeline works on: a Leaf (boundary and veins in 3D) and validated Params."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, fields, replace
from typing import Any

import numpy as np

from leafstudio.errors import LeafError

MESHERS = ("conforming", "bpa")
K_MAX = 64
K_AUTO = "auto"  # Params.k: choose K by BIC (core/autok.py)
GRID_MIN, GRID_MAX = 8, 2048


def _as_points(values: Any, what: str) -> np.ndarray:
    """Return `values` as a finite (n, 3) float array, or raise LeafError naming `what`."""
    try:
        points = np.asarray(values, dtype=float)
    except (TypeError, ValueError) as exc:
        raise LeafError(f"{what} must be a list of x, y, z points") from exc
    if points.size == 0:
        return np.zeros((0, 3))
    if points.ndim != 2 or points.shape[1] != 3:
        raise LeafError(
            f"{what} must be an (n, 3) array of x, y, z points, got shape {points.shape}"
        )
    if not np.all(np.isfinite(points)):
        raise LeafError(f"{what} contains NaN or infinite coordinates")
    return points


@dataclass(frozen=True, eq=False)
class Leaf:
    """A leaf as the paper takes it: 3D boundary points and one 3D point set per vein.

    Parameters
    ----------
    boundary : (n, 3) float array
        Points on the leaf margin, in any order; duplicates and mild noise are fine.
    veins : list of (m_i, 3) float arrays, default: []
        Points along each vein, ordered from its start to its end where known.
    """

    boundary: np.ndarray
    veins: list[np.ndarray] = field(default_factory=list)

    def __post_init__(self) -> None:
        object.__setattr__(self, "boundary", _as_points(self.boundary, "boundary"))
        veins = [_as_points(v, f"vein {i + 1}") for i, v in enumerate(self.veins)]
        object.__setattr__(self, "veins", [v for v in veins if len(v)])

    @property
    def vein_points(self) -> np.ndarray:
        """All vein points stacked, (m, 3)."""
        return np.vstack(self.veins) if self.veins else np.zeros((0, 3))

    def fingerprint(self) -> bytes:
        """Bytes that change whenever any coordinate changes (for caches)."""
        parts = [self.boundary.tobytes()] + [b"|" + v.tobytes() for v in self.veins]
        return b"".join(parts)


@dataclass(frozen=True)
class Params:
    """Reconstruction settings, checked on creation.

    Parameters
    ----------
    k : int or "auto", default: 3
        Number of Gaussian components (the paper's K); "auto" chooses 1 to 12 by BIC
        (Result.chosen_k says which).
    grid : int, default: 128
        Grid nodes along the leaf's longer side.
    mpu_tolerance : float, default: 1e-3
        MPU fit tolerance, as a fraction of the leaf length.
    samples : int, default: 4000
        Points drawn from the height guide p(x) for the EM fit.
    seed : int, default: 0
        Random seed of the sampling and EM, so that results repeat.
    mesher : {"conforming", "bpa"}, default: "conforming"
        Our boundary-conforming triangulation, or open3d ball pivoting as in the paper.
    radius_factor : float, default: 1.0
        Scales the ball-pivoting radii (which derive from the grid spacing).
    taper : float, default: 0.35
        Width of the boundary taper, as a fraction of the leaf's inscribed radius.
    refine : bool, default: True
        Refine the whole mixture by least squares after EM (the paper stops after EM).
    """

    k: int | str = 3
    grid: int = 128
    mpu_tolerance: float = 1e-3
    samples: int = 4000
    seed: int = 0
    mesher: str = "conforming"
    radius_factor: float = 1.0
    taper: float = 0.35
    refine: bool = True

    def __post_init__(self) -> None:
        if self.k == K_AUTO:
            pass
        elif isinstance(self.k, bool) or not isinstance(self.k, (int, np.integer)):
            raise LeafError(f"K must be a whole number or {K_AUTO!r}, got {self.k!r}")
        elif not 1 <= self.k <= K_MAX:
            raise LeafError(f"K must be between 1 and {K_MAX}, got {self.k}")
        if not GRID_MIN <= self.grid <= GRID_MAX:
            raise LeafError(f"grid must be between {GRID_MIN} and {GRID_MAX}, got {self.grid}")
        if not 1e-6 <= self.mpu_tolerance <= 0.1:
            raise LeafError(f"MPU tolerance must be between 1e-6 and 0.1, got {self.mpu_tolerance}")
        if not 100 <= self.samples <= 1_000_000:
            raise LeafError(f"EM sample count must be between 100 and 1000000, got {self.samples}")
        if self.seed < 0:
            raise LeafError(f"seed must be zero or positive, got {self.seed}")
        if self.mesher not in MESHERS:
            raise LeafError(f"mesher must be one of {', '.join(MESHERS)}, got {self.mesher!r}")
        if not 0.25 <= self.radius_factor <= 8:
            raise LeafError(f"radius factor must be between 0.25 and 8, got {self.radius_factor}")
        if not 0.01 <= self.taper <= 5:
            raise LeafError(f"taper must be between 0.01 and 5, got {self.taper}")

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready dict."""
        return asdict(self)

    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> Params:
        """Params from a dict, ignoring unknown keys (files from newer versions still open)."""
        known = {f.name for f in fields(cls)}
        return cls(**{k: v for k, v in values.items() if k in known})

    def with_(self, **changes: Any) -> Params:
        """A copy with some values changed (validated again)."""
        return replace(self, **changes)
