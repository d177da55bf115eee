"""The data the pipeline works on: a Leaf (boundary and veins in 3D) and validated Params."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, fields, replace
from typing import Any, Protocol

import numpy as np

from leafstudio.errors import LeafError
from leafstudio.paramspec import Choice, Param, Real, Switch, Whole, declared, numpy_doc
from leafstudio.paramspec import short as _short

MESHERS = ("conforming", "bpa")
MARGINS = ("auto", "exact", "smooth")  # Params.margin (core/prepare/outline.py)
K_MAX = 64
K_AUTO = "auto"  # Params.k: choose K by BIC (core/autok.py)
K_AUTO_MAX = 12  # auto chooses K from 1 to this; the panel's K slider covers the same
GRID_MIN, GRID_MAX = 8, 2048
SEED_MAX = 2**32 - 1  # numpy's legacy seeds and most tools take 32 bits
# larger coordinates overflow a leaf's extent (the pipeline runs at unit size,
# core/prepare/units.py); a smaller leaf's curvatures (1/size²) overflow
COORDINATE_LIMIT = 1e300
SMALLEST_EXTENT = 1e-100


def _as_points(values: Any, what: str) -> np.ndarray:
    """Return `values` as a finite (n, 3) float array, or raise LeafError naming `what`."""
    if values is None or isinstance(values, (str, bytes)):
        raise LeafError(f"{what} must be a list of x, y, z points, got {_short(values)}")
    try:
        raw = np.asarray(values) if not isinstance(values, np.ndarray) else values
    except (TypeError, ValueError, OverflowError) as exc:  # ragged rows: numpy's ValueError
        raise LeafError(
            f"{what} must be an (n, 3) array of x, y, z points (rows of three numbers)"
        ) from exc
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
    top = np.abs(points).max()  # NaN if any is, inf if any is: one pass for the usual case
    if not top <= COORDINATE_LIMIT:
        if not np.all(np.isfinite(points)):
            raise LeafError(f"{what} contains NaN or infinite coordinates")
        raise LeafError(
            f"{what} has coordinates as large as {top:.3g}; rescale the input "
            f"(coordinates up to {COORDINATE_LIMIT:g} are taken)"
        )
    return points


class Bend(Protocol):
    """A smooth bend that carries a flat blade into 3D (core/bend.py: Pose)."""

    def apply(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) flat blade points, bent."""
        ...

    def flatten(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) bent points back on the flat blade."""
        ...

    def key(self) -> bytes:
        """Bytes that change with the bend."""
        ...

    def crease(self, points: np.ndarray) -> np.ndarray | None:
        """(n,) signed distances of flat points from the line the bend creases along ((m, n) for
        m parallel lines, each row the first's less a constant), or None."""
        ...

    def trim(self, points: np.ndarray) -> np.ndarray | None:
        """(n,) signed distances of (n, 3) flat points from the edges of the blade's holes,
        negative inside one (core/bend.py cuts them out of the mesh), or None without holes."""
        ...


@dataclass(frozen=True, eq=False)
class Leaf:
    """A leaf as the paper takes it: 3D boundary points and one 3D point set per vein.

    Parameters
    ----------
    boundary : (n, 3) float array
        Points on the leaf margin, in any order; duplicates and mild noise are fine.
    veins : list of (m_i, 3) float arrays, default: []
        Points along each vein, ordered from its start to its end where known.
    bend : Bend, optional
        How the points were bent from a flat blade (a form's fold and curl): reconstruction runs
        on the flat blade and bends the mesh (core/bend.py). None: the leaf is taken as it is.

    Raises
    ------
    LeafError
        For points that are not finite (n, 3) numbers, or a leaf too large or too small to
        measure in float64.

    Examples
    --------
    >>> import numpy as np
    >>> import leafstudio as ls
    >>> t = np.linspace(0, 2 * np.pi, 100, endpoint=False)
    >>> boundary = np.column_stack([np.cos(t), 0.4 * np.sin(t), np.zeros(100)])
    >>> midrib = np.column_stack([np.linspace(-0.9, 0.9, 20), np.zeros(20), np.full(20, 0.05)])
    >>> leaf = ls.Leaf(boundary, [midrib])
    >>> leaf.boundary.shape, leaf.vein_points.shape
    ((100, 3), (20, 3))
    """

    boundary: np.ndarray
    veins: list[np.ndarray] = field(default_factory=list)
    bend: Bend | None = None

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
            raise LeafError(
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
        if self.bend is not None:
            parts.append(b"~" + self.bend.key())
        return b"".join(parts)


@dataclass(frozen=True)
class Params:
    """Reconstruction settings, checked on creation.

    Each field is declared once, here: its kind and range, default, help, the pipeline stage it
    invalidates and its command-line flag (paramspec.py). Validation, the stage cache's keys
    (core/stages.py), the parameter panel (gui/qt/controls.py) and the CLI flags (cli/) are
    derived from these declarations (`PARAMS`).

    A `slider` range is what the panel's slider offers, inside the valid range: what is worth
    exploring by hand. K goes up to what auto tries; grid to 512, as a run's time grows with its
    square (2048 takes 16 times as long); samples, tolerance, radius and taper over what changes
    a leaf visibly. A project, the command line or the API may hold any valid value; the panel
    widens its slider to show it and gives it back unchanged.
    """

    k: int | str = Whole(
        default=3, low=1, high=K_MAX, special=K_AUTO, slider=(1, K_AUTO_MAX),
        what="K", label="K (Gaussians)", stage="gmm", flag="--k", metavar="K|auto",
        help="How many Gaussian bumps (the paper's K) make up the leaf's surface. One bump per "
        "main vein region is a good start; more bumps follow the veins more closely. auto "
        f"chooses K from 1 to {K_AUTO_MAX} by the Bayesian information criterion",
    ).field()  # fmt: skip
    grid: int = Whole(
        default=128, low=GRID_MIN, high=GRID_MAX, slider=(16, 512), step=16,
        what="grid", label="Grid", stage="grid", flag="--grid", metavar="N",
        help="How finely the leaf is sampled: grid nodes along the leaf's longer side. Higher is "
        "smoother and slower (the time grows with the square of this number)",
    ).field()  # fmt: skip
    mpu_tolerance: float = Real(
        default=1e-3, low=1e-6, high=0.1, slider=(1e-4, 0.02), decimals=4,
        what="MPU tolerance", label="MPU tolerance", stage="implicit", flag="--mpu-tolerance",
        metavar="F",
        help="How closely the leaf's outline function (the MPU implicit) must follow the "
        "boundary points, as a fraction of the leaf's length. Smaller follows every wiggle; "
        "larger smooths noise",
    ).field()  # fmt: skip
    samples: int = Whole(
        default=4000, low=100, high=1_000_000, slider=(500, 20_000), step=500,
        what="EM sample count", label="EM samples", stage="samples", flag="--samples", metavar="N",
        help="How many random points, drawn where the height guide p(x) is high, the Gaussian "
        "mixture is fitted to by EM. More points give a steadier fit",
    ).field()  # fmt: skip
    seed: int = Whole(
        default=0, low=0, high=SEED_MAX,
        what="seed", label="Seed", stage="samples", flag="--seed", metavar="S",
        help="The random seed of the sampling and of EM: the same seed always gives the same leaf",
    ).field()  # fmt: skip
    mesher: str = Choice(
        default="conforming", choices=MESHERS,
        what="mesher", label="Mesher", stage="mesh", flag="--mesher",
        help="How the surface becomes triangles: conforming follows the outline exactly (our "
        "boundary-conforming triangulation); bpa is the paper's ball pivoting (open3d), which "
        "may leave gaps at thin tips",
    ).field()  # fmt: skip
    radius_factor: float = Real(
        default=1.0, low=0.25, high=8, slider=(0.5, 4.0), decimals=2,
        what="radius factor", label="Ball radius ×", stage="mesh", flag="--radius-factor",
        metavar="F",
        help="Ball pivoting only: scales the ball radii (which follow the grid spacing). Larger "
        "balls close gaps but can bridge notches in the outline",
    ).field()  # fmt: skip
    taper: float = Real(
        default=0.35, low=0.01, high=5, slider=(0.05, 1.0), decimals=2,
        what="taper", label="Margin taper", stage="bending", flag="--taper", metavar="F",
        help="How wide the band along the margin is where the surface bends down to the "
        "outline, as a fraction of the leaf's inscribed radius",
    ).field()  # fmt: skip
    refine: bool = Switch(
        default=True,
        what="refine", label="Refine after EM", stage="surface", flag="--refine",
        help="After the EM fit, adjust all bumps together by least squares so that the surface "
        "passes closer to the veins (the paper stops after EM)",
    ).field()  # fmt: skip
    through_veins: bool = Switch(
        default=True,
        what="through veins", label="Surface through veins", stage="surface",
        flag="--through-veins",
        help="After the fit, bend the surface smoothly onto every vein point (tapering to "
        "nothing at the margin), so the drawn veins lie on the leaf; off keeps the paper's pure "
        "Gaussian-mixture surface, which follows the veins only on average",
    ).field()  # fmt: skip
    margin: str = Choice(
        default="auto", choices=MARGINS,
        what="margin", label="Margin", stage="frame", flag="--margin",
        help="The margin through the boundary points themselves (exact), through their smoothed "
        "mean position (smooth, for noisy scans), or chosen by the points' measured noise (auto)",
    ).field()  # fmt: skip

    def __post_init__(self) -> None:
        checked = {name: p.check(getattr(self, name)) for name, p in PARAMS.items()}
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


PARAMS: dict[str, Param] = declared(Params)  # each field's declaration, in field order
_PARAMS_EXAMPLES = """
    Raises
    ------
    LeafError
        For a value out of its range or of the wrong kind, naming the parameter.

    Examples
    --------
    >>> import leafstudio as ls
    >>> params = ls.Params(k=3, grid=64)
    >>> params.with_(k="auto").k
    'auto'
    >>> ls.Params(k=0)
    Traceback (most recent call last):
    leafstudio.errors.LeafError: K must be between 1 and 64, got 0
"""
Params.__doc__ = f"{Params.__doc__}{numpy_doc(PARAMS)}{_PARAMS_EXAMPLES}"


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
