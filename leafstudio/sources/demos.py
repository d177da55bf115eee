"""Built-in leaves: the paper's two examples, rebuilt from its equations (leaf length 1).

- ``nested`` (Fig. 8): boundary y = ±x²(1 − x), x in [0, 1]; a midrib along y = 0 and three pairs
  of straight side veins leaving it at 40° toward the tip.
- ``parallel`` (Fig. 9): boundary y = ±x√(1 − x); two veins running from the base to the tip at
  ±0.4 of the half-width (K = 2 in the paper: one Gaussian per vein).

Vein heights (our choice; the paper does not give them): along the midrib, and along the parallel
veins, the height follows the leaf's half-width w(x): h = 0.25 · w(x) (times 1 − f² for a vein at
fraction f of the half-width), so the blade slopes about 14° from the margin up to the veins (at
most 0.037 high for nested, 0.081 for parallel). Side veins of ``nested`` fall linearly from the
midrib's height where they start to a quarter of it at their outer end.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from leafstudio.errors import LeafError
from leafstudio.model import Leaf

HEIGHT_RATIO = 0.25
PARALLEL_FRACTIONS = (0.4, -0.4)


def _nested_halfwidth(x: np.ndarray) -> np.ndarray:
    return x**2 * (1 - x)


def _parallel_halfwidth(x: np.ndarray) -> np.ndarray:
    return x * np.sqrt(np.clip(1 - x, 0, None))


def _outline(halfwidth: Callable[[np.ndarray], np.ndarray], n_side: int) -> np.ndarray:
    """Closed outline, counter-clockwise, from base (0, 0) along y = -w to the tip and back."""
    t = 0.5 - 0.5 * np.cos(np.linspace(0, np.pi, n_side))  # denser at base and tip
    lower = np.column_stack([t, -halfwidth(t)])
    upper = np.column_stack([t[::-1], halfwidth(t[::-1])])[1:-1]
    xy = np.vstack([lower, upper])
    return np.column_stack([xy, np.zeros(len(xy))])


def nested(n_side: int = 120) -> Leaf:
    """The paper's Fig. 8 leaf: nested (pinnate) veins."""
    boundary = _outline(_nested_halfwidth, n_side)
    x = np.linspace(0.02, 0.98, 49)
    midrib = np.column_stack([x, np.zeros_like(x), HEIGHT_RATIO * _nested_halfwidth(x)])
    veins = [midrib]
    angle = np.deg2rad(40)
    for x0 in (0.35, 0.55, 0.75):
        h0 = HEIGHT_RATIO * _nested_halfwidth(x0)
        for side in (1, -1):
            # walk at 40° from the midrib until 80% of the way to the margin
            s = np.linspace(0, 1, 400)
            px = x0 + s * np.cos(angle)
            py = side * s * np.sin(angle)
            inside = np.abs(py) < 0.8 * _nested_halfwidth(np.clip(px, 0, 1))
            end = s[np.argmin(inside)]
            t = np.linspace(0, 1, 16)[1:]
            vx, vy = x0 + t * end * np.cos(angle), side * t * end * np.sin(angle)
            veins.append(np.column_stack([vx, vy, h0 * (1 - 0.75 * t)]))
    return Leaf(boundary=boundary, veins=veins)


def parallel(n_side: int = 120) -> Leaf:
    """The paper's Fig. 9 leaf: parallel veins from base to tip."""
    boundary = _outline(_parallel_halfwidth, n_side)
    x = np.linspace(0.03, 0.97, 48)
    veins = []
    for frac in PARALLEL_FRACTIONS:
        w = _parallel_halfwidth(x)
        h = HEIGHT_RATIO * w * (1 - frac**2)
        veins.append(np.column_stack([x, frac * w, h]))
    return Leaf(boundary=boundary, veins=veins)


DEMOS: dict[str, Callable[[], Leaf]] = {"nested": nested, "parallel": parallel}
PAPER_K = {"nested": 3, "parallel": 2}
HALFWIDTH = {"nested": _nested_halfwidth, "parallel": _parallel_halfwidth}


def demo(name: str) -> Leaf:
    """A built-in leaf by name: the paper's two examples, rebuilt from its equations.

    Parameters
    ----------
    name : {"nested", "parallel"}
        "nested": Fig. 8's pinnate veins (a midrib and three pairs of side veins); "parallel":
        Fig. 9's two parallel veins. Both have length 1, base at the origin, apex on +x.

    Returns
    -------
    Leaf
        238 boundary points in z = 0 and the veins with their heights.

    Raises
    ------
    LeafError
        For an unknown name.

    Examples
    --------
    >>> import leafstudio as ls
    >>> leaf = ls.demo("nested")
    >>> leaf.boundary.shape, len(leaf.veins)
    ((238, 3), 7)
    >>> len(ls.demo("parallel").veins)
    2
    """
    if name not in DEMOS:
        raise LeafError(f"unknown demo {name!r}; choose from {', '.join(DEMOS)}")
    return DEMOS[name]()
