"""The data the pipeline works on: a Leaf (boundary and veins in 3D) and validated Params."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, fields, replace
from typing import Any

import numpy as np

from leafstudio.errors import LeafError

MESHERS = ("conforming", "bpa")
MARGINS = ("auto", "exact", "smooth")  # Params.margin (core/outline.py)
K_MAX = 64
K_AUTO = "auto"  # Params.k: choose K by BIC (core/autok.py)
GRID_MIN, GRID_MAX = 8, 2048
SEED_MAX = 2**32 - 1  # numpy's legacy seeds and most tools take 32 bits
COORDINATE_LIMIT = 1e300  # larger coordinates overflow a leaf's extent (the pipeline runs at unit
SMALLEST_EXTENT = 1e-100  # size, core/units.py); a smaller leaf's curvatures (1/size²) overflow


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else f"{text[:30]}… ({len(text)} characters)"


def _whole_number(value: Any, what: str, low: int, high: int) -> int:
    """`value` as an int in [low, high]; a bool, a float (even 100.0) or a string is refused."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise LeafError(f"{what} must be a whole number, got {_short(value)}")
    if not low <= value <= high:
        raise LeafError(f"{what} must be between {low} and {high}, got {_short(value)}")
    return int(value)


def _real_number(value: Any, what: str, low: float, high: float) -> float:
    """`value` as a finite float in [low, high]; a bool or a string is refused."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.number)):
        raise LeafError(f"{what} must be a number, got {_short(value)}")
    if isinstance(value, (complex, np.complexfloating)):
        raise LeafError(f"{what} must be a real number, got {_short(value)}")
    number = float(value)
    if not low <= number <= high:  # NaN fails this too
        raise LeafError(f"{what} must be between {low:g} and {high:g}, got {_short(value)}")
    return number


def _as_points(values: Any, what: str) -> np.ndarray:
    """Return `values` as a finite (n, 3) float array, or raise LeafError naming `what`."""
    if values is None or isinstance(values, (str, bytes)):
        raise LeafError(f"{what} must be a list of x, y, z points, got {_short(values)}")
    raw = np.asarray(values) if not isinstance(values, np.ndarray) else values
    if raw.dtype.kind == "c":
        raise LeafError(f"{what} must be real numbers, not complex ones")
    if raw.dtype.kind not in "biuf" and raw.size:
        try:
            raw = np.asarray(values, dtype=float)
        except (TypeError, ValueError, OverflowError) as exc:
            raise LeafError(f"{what} must be a list of x, y, z points (numbers)") from exc
        if raw.dtype.kind != "f":
            raise LeafError(f"{what} must be a list of x, y, z points (numbers)")
    try:
        points = np.asarray(raw, dtype=float)
    except (TypeError, ValueError, OverflowError) as exc:
        raise LeafError(f"{what} must be a list of x, y, z points (numbers)") from exc
    if points.size == 0:
        return np.zeros((0, 3))
    if points.ndim != 2 or points.shape[1] != 3:
        raise LeafError(
            f"{what} must be an (n, 3) array of x, y, z points, got shape {points.shape}"
        )
    if not np.all(np.isfinite(points)):
        raise LeafError(f"{what} contains NaN or infinite coordinates")
    if np.abs(points).max() > COORDINATE_LIMIT:
        raise LeafError(
            f"{what} has coordinates as large as {np.abs(points).max():.3g}; rescale the input "
            f"(coordinates up to {COORDINATE_LIMIT:g} are taken)"
        )
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
        extent = float(np.ptp(self.boundary, axis=0).max()) if len(self.boundary) else 0.0
        if 0.0 < extent < SMALLEST_EXTENT:
            raise LeafError(
                f"the boundary spans only {extent:.3g}; rescale the input (a leaf of at least "
                f"{SMALLEST_EXTENT:g} is taken)"
            )
        if self.veins is None:
            object.__setattr__(self, "veins", [])
        if isinstance(self.veins, (str, bytes, np.ndarray)) or not hasattr(self.veins, "__iter__"):
            raise TypeError(
                f"veins must be a list of (m, 3) point arrays, one per vein, got "
                f"{type(self.veins).__name__}"
            )
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
    margin : {"auto", "exact", "smooth"}, default: "auto"
        The margin through the boundary points themselves ("exact"), through their smoothed
        mean position ("smooth", for noisy scans), or chosen by the points' measured noise.
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
    margin: str = "auto"

    def __post_init__(self) -> None:
        checked: dict[str, Any] = {}
        if self.k == K_AUTO:
            checked["k"] = K_AUTO
        elif isinstance(self.k, (bool, np.bool_)) or not isinstance(self.k, (int, np.integer)):
            raise LeafError(f"K must be a whole number or {K_AUTO!r}, got {_short(self.k)}")
        else:
            checked["k"] = _whole_number(self.k, "K", 1, K_MAX)
        checked["grid"] = _whole_number(self.grid, "grid", GRID_MIN, GRID_MAX)
        checked["mpu_tolerance"] = _real_number(self.mpu_tolerance, "MPU tolerance", 1e-6, 0.1)
        checked["samples"] = _whole_number(self.samples, "EM sample count", 100, 1_000_000)
        checked["seed"] = _whole_number(self.seed, "seed", 0, SEED_MAX)
        if not isinstance(self.mesher, str) or self.mesher not in MESHERS:
            raise LeafError(
                f"mesher must be one of {', '.join(MESHERS)}, got {_short(self.mesher)}"
            )
        checked["radius_factor"] = _real_number(self.radius_factor, "radius factor", 0.25, 8)
        checked["taper"] = _real_number(self.taper, "taper", 0.01, 5)
        if not isinstance(self.refine, (bool, np.bool_)):
            raise LeafError(f"refine must be true or false, got {_short(self.refine)}")
        checked["refine"] = bool(self.refine)
        if not isinstance(self.margin, str) or self.margin not in MARGINS:
            raise LeafError(
                f"margin must be one of {', '.join(MARGINS)}, got {_short(self.margin)}"
            )
        for name, value in checked.items():  # plain Python values: JSON-ready, equal as expected
            object.__setattr__(self, name, value)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready dict."""
        return asdict(self)

    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> Params:
        """Params from a dict, ignoring unknown keys (files from newer versions still open)."""
        if not isinstance(values, dict):
            raise LeafError(
                f"parameters must be a mapping of names to values, got {_short(values)}"
            )
        known = {f.name for f in fields(cls)}
        return cls(**{k: v for k, v in values.items() if k in known})

    def with_(self, **changes: Any) -> Params:
        """A copy with some values changed (validated again)."""
        return replace(self, **changes)


def as_leaf(value: Any) -> Leaf:
    """`value` if it is a Leaf; a TypeError that says what is expected otherwise (the API's
    entry points call this, so `reconstruct(None)` says what went wrong)."""
    if isinstance(value, Leaf):
        return value
    raise TypeError(
        f"expected a leafstudio.Leaf (from ls.load_leaf, ls.demo or ls.Leaf(boundary, veins)), "
        f"got {type(value).__name__}"
    )


def as_params(value: Any) -> Params:
    """`value` as Params: Params, None (the defaults) or a dict of parameter names and values
    (an unknown name is an error here, where from_dict ignores it for newer files)."""
    if value is None:
        return Params()
    if isinstance(value, Params):
        return value
    if isinstance(value, dict):
        known = {f.name for f in fields(Params)}
        unknown = sorted(str(k) for k in value if k not in known)
        if unknown:
            raise LeafError(
                f"unknown parameter {_short(unknown[0])}; known: {', '.join(sorted(known))}"
            )
        return Params(**value)
    raise TypeError(f"expected leafstudio.Params, a dict or None, got {type(value).__name__}")
