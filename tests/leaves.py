"""Test leaves with known regions: the demos moved in 3D, noisy, lobed and narrow ones."""

from __future__ import annotations

import numpy as np
import shapely
from scipy.spatial.transform import Rotation

from leafstudio.analysis import fidelity
from leafstudio.core.plane import Frame
from leafstudio.model import Leaf
from leafstudio.sources.demos import HALFWIDTH, demo


def halfwidth_region(name: str, n: int = 4000) -> shapely.Polygon:
    """The exact leaf region of a demo, y = ±w(x), as a dense polygon in its own plane."""
    x = np.linspace(0, 1, n)
    w = HALFWIDTH[name](x)
    return shapely.Polygon(np.vstack([np.column_stack([x, -w]), np.column_stack([x, w])[::-1]]))


def moved(leaf: Leaf, seed: int = 1) -> tuple[Leaf, Rotation, np.ndarray]:
    """The leaf under a random rotation and a translation far from the origin."""
    rot = Rotation.random(random_state=seed)
    shift = np.array([12.0, -7.5, 3.25])
    move = lambda p: rot.apply(p) + shift  # noqa: E731
    return Leaf(boundary=move(leaf.boundary), veins=[move(v) for v in leaf.veins]), rot, shift


def noisy(name: str, sigma: float = 5e-4, seed: int = 2) -> Leaf:
    """A demo with shuffled boundary points, 25% of them duplicated, and Gaussian noise."""
    rng = np.random.default_rng(seed)
    leaf = demo(name)
    boundary = leaf.boundary + rng.normal(0, sigma, leaf.boundary.shape)
    dup = boundary[rng.choice(len(boundary), len(boundary) // 4, replace=False)]
    boundary = rng.permutation(np.vstack([boundary, dup]))
    veins = [v + rng.normal(0, sigma, v.shape) for v in leaf.veins]
    return Leaf(boundary=boundary, veins=veins)


def lobed_radius(theta: np.ndarray) -> np.ndarray:
    """A five-lobed, concave outline (a palmate leaf), radius about 0.5."""
    return 0.5 * (1 + 0.3 * np.cos(5 * theta))


def lobed(n: int = 400) -> tuple[Leaf, shapely.Polygon]:
    """Five lobes, one vein from the centre to each lobe tip (palmate venation), heights falling
    from 0.05 at the centre to 0.01 near the lobe tips."""
    theta = np.linspace(0, 2 * np.pi, n, endpoint=False)
    r = lobed_radius(theta)
    outline = np.column_stack([r * np.cos(theta), r * np.sin(theta)])
    boundary = np.column_stack([outline, np.zeros(n)])
    veins = []
    for k in range(5):
        a = 2 * np.pi * k / 5
        s = np.linspace(0.02, 0.85, 30) * lobed_radius(np.array([a]))[0]
        h = 0.05 - 0.04 * s / s.max()
        veins.append(np.column_stack([s * np.cos(a), s * np.sin(a), h]))
    dense = np.linspace(0, 2 * np.pi, 8000, endpoint=False)
    rd = lobed_radius(dense)
    region = shapely.Polygon(np.column_stack([rd * np.cos(dense), rd * np.sin(dense)]))
    return Leaf(boundary=boundary, veins=veins), region


def narrow_halfwidth(x: np.ndarray) -> np.ndarray:
    """A grass-like blade: 0.06 wide at most, rounded base, straight sharp tip at x = 1."""
    return 0.08 * np.sqrt(np.clip(x, 0, None)) * (1 - x)


def narrow(n_side: int = 150) -> tuple[Leaf, shapely.Polygon]:
    """A very narrow leaf (length 1, width at most 0.06) with a sharp tip and a midrib."""
    t = np.linspace(0, 1, n_side)
    lower = np.column_stack([t, -narrow_halfwidth(t)])
    upper = np.column_stack([t[::-1], narrow_halfwidth(t[::-1])])[1:-1]
    xy = np.vstack([lower, upper])
    x = np.linspace(0.03, 0.97, 60)
    midrib = np.column_stack([x, np.zeros_like(x), 0.3 * narrow_halfwidth(x)])
    dense = np.linspace(0, 1, 8000)
    w = narrow_halfwidth(dense)
    region = shapely.Polygon(
        np.vstack([np.column_stack([dense, -w]), np.column_stack([dense, w])[::-1]])
    )
    return Leaf(boundary=np.column_stack([xy, np.zeros(len(xy))]), veins=[midrib]), region


def coverage(
    result, region: shapely.Polygon, rot: Rotation | None = None, shift=None
) -> tuple[float, float]:
    """(covered share of the region, spilled share) of the mesh seen along the region's normal.

    The region lies in its own x-y plane; `rot` and `shift` say how the leaf was moved from it.
    """
    rot = rot or Rotation.identity()
    frame = Frame(
        origin=np.zeros(3) if shift is None else np.asarray(shift, dtype=float),
        u=rot.apply([1.0, 0.0, 0.0]),
        v=rot.apply([0.0, 1.0, 0.0]),
        normal=rot.apply([0.0, 0.0, 1.0]),
    )
    share = fidelity.coverage(result.mesh, frame, np.asarray(region.exterior.coords)[:-1])
    return share["covered"], share["outside"]


def metric_numbers(metrics: dict) -> list[float]:
    """Every number in a Result's (nested) metrics."""
    out: list[float] = []
    for value in metrics.values():
        if isinstance(value, dict):
            out += metric_numbers(value)
        elif isinstance(value, int | float) and not isinstance(value, bool):
            out.append(float(value))
    return out
