"""The tests' shared builders: leaves and scans with known answers, one place for all.

- demos moved in 3D, noisy, lobed and narrow leaves with their exact regions (`moved`, `noisy`,
  `lobed`, `narrow`, `coverage`), and every number of a Result's metrics (`metric_numbers`);
- ellipses: as points (`ellipse`), as a scanner's noisy shuffled cloud (`ellipse_cloud`), as a
  sketch's clicks (`sketch_ellipse`, `sketch_clicks`); random star-shaped leaves (`random_leaf`);
  the boundaries no check may refuse (`true_boundaries`);
- points that fill an area: a disc, a sphere's cap, a flattened blob, a form filled (`disc`,
  `cap`, `blob`, `filled_form`);
- narrow bent blades: outlines and filled strips (`bend`, `bent_strap`, `bent_filled_strip`);
- a synthetic scan with a blade of known outline, a petiole and outliers (`synthetic_scan`,
  `scan_blade_outline`, `scan_surface`, `assert_outline_is_the_blades`).

Tests import builders from here (or tests/photos.py for photos), never from another test module.
"""

from __future__ import annotations

import functools
import os
import pickle
from pathlib import Path

import numpy as np
import shapely
from scipy.spatial.transform import Rotation

from leafstudio.analysis import fidelity
from leafstudio.core.plane import Frame
from leafstudio.gui.model.sketch_model import BOUNDARY, Sketch
from leafstudio.model import Leaf
from leafstudio.sources.demos import HALFWIDTH, demo
from tests.conftest import SHARED


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


# --- ellipses ------------------------------------------------------------------------------------


def ellipse(
    n: int = 400,
    a: float = 1.0,
    b: float = 0.4,
    *,
    centre: tuple[float, float] = (0.0, 0.0),
    sigma: float = 0.0,
    seed: int = 0,
    shuffle: bool = False,
    even: bool = True,
) -> np.ndarray:
    """(n, 3) points on the ellipse ((x - cx) / a)² + ((y - cy) / b)² = 1 in z = 0, in order
    counter-clockwise from (cx + a, cy): evenly spaced in angle, or at random angles (`even`
    False), with Gaussian noise `sigma` in x and y, shuffled if asked."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    if not even:
        t = np.sort(rng.uniform(0, 2 * np.pi, n))
    points = np.column_stack([centre[0] + a * np.cos(t), centre[1] + b * np.sin(t), np.zeros(n)])
    points[:, :2] += rng.normal(0, sigma, (n, 2))  # drawn even for sigma 0: same shuffles
    return rng.permutation(points) if shuffle else points


def ellipse_cloud(
    n: int, sigma: float, seed: int = 0, shuffle: bool = True, even: bool = True
) -> np.ndarray:
    """(n, 3) points on the ellipse x²/4 + y² = 1 (area 2π) as a scanner gives a boundary:
    Gaussian noise σ in x and y, shuffled."""
    return ellipse(n, 2.0, 1.0, sigma=sigma, seed=seed, shuffle=shuffle, even=even)


def sketch_ellipse(n: int = 12, a: float = 0.5, b: float = 0.2) -> np.ndarray:
    """(n, 2) sketch clicks round an ellipse centred at (0.5, 0), across the unit leaf."""
    return ellipse(n, a, b, centre=(0.5, 0.0))[:, :2]


def sketch_clicks(n: int = 12) -> np.ndarray:
    """(n, 2) sketch clicks round an ellipse from x = 0.05 to 0.95, 0.4 wide."""
    return sketch_ellipse(n, 0.45, 0.2)


def clicked_outline() -> np.ndarray:
    """The app's drawn leaf's outline, as benchmarks/story_screens.py clicks it: 12 plane points
    around an ovate leaf (base at x = 0.05, tip at x = 0.95), in drawing order
    (counter-clockwise from the tip)."""
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    x = 0.5 + 0.45 * np.cos(t)
    y = 0.22 * np.sin(t) * (1.0 - 0.25 * np.cos(t))  # wider towards the base
    return np.column_stack([x, y])


CLICKED_MIDRIB = np.array([[0.08, 0.0], [0.35, 0.0], [0.62, 0.0], [0.9, 0.0]])
# side veins, two from each of two midrib points: the first click lands on the midrib's own
# control point (issue 12, finding 3: it selected that point and added to the midrib; and two
# veins from one spot merged), then two points outwards
CLICKED_SIDE_VEINS = (
    ((0.35, 0.0), (0.45, 0.1), (0.54, 0.17)),
    ((0.35, 0.0), (0.45, -0.1), (0.54, -0.17)),
    ((0.62, 0.0), (0.71, 0.09), (0.79, 0.13)),
    ((0.62, 0.0), (0.71, -0.09), (0.79, -0.13)),
)


def clicked_sketch(turn: float = 0.0) -> Sketch:
    """The leaf benchmarks/story_screens.py draws in the app, as its clicks make it: its outline,
    a midrib and four side veins started on it and clicked out to near the margin, each new
    vein and point as the editor makes them (Sketch.started_vein, default_height): auto veins,
    on the dome over the outline. `turn`: every click turned that many degrees about (0.5, 0),
    a leaf drawn at an angle."""
    a = np.radians(turn)
    rotation = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])

    def clicks(xy) -> np.ndarray:
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        return xy if turn == 0.0 else (xy - [0.5, 0.0]) @ rotation.T + [0.5, 0.0]

    sketch = Sketch()
    for xy in clicks(clicked_outline()):
        sketch, _ = sketch.inserted(BOUNDARY, xy)
    midrib = clicks(CLICKED_MIDRIB)
    sketch = sketch.started_vein(midrib[0], 0.01)
    for xy in midrib[1:]:
        sketch, _ = sketch.inserted(0, xy, sketch.default_height(0, xy))
    for vein_clicks in CLICKED_SIDE_VEINS:
        start, *rest = clicks(vein_clicks)
        sketch = sketch.started_vein(start, 0.01)
        vein = len(sketch.veins) - 1
        for xy in rest:
            sketch, _ = sketch.inserted(vein, xy, sketch.default_height(vein, xy))
    return sketch


def random_leaf(seed: int, n: int, noise: float, size: float) -> tuple[Leaf, float]:
    """A random star-shaped leaf (a few Fourier modes of the radius), length about `size`,
    rotated in 3D, shuffled, with duplicates and noise of `noise` of its length; its exact area."""
    rng = np.random.default_rng(seed)
    modes = rng.normal(0, 0.08, (3, 2)) / np.arange(2, 5)[:, None]
    t = np.linspace(0, 2 * np.pi, 20000, endpoint=False)
    stretch = rng.uniform(1.2, 2.0)

    def outline(t: np.ndarray) -> np.ndarray:
        r = 1 + sum(a * np.cos(k * t) + b * np.sin(k * t) for k, (a, b) in enumerate(modes, 2))
        return np.column_stack([stretch * r * np.cos(t), r * np.sin(t)])

    exact = shapely.Polygon(outline(t))
    length = float(np.ptp(outline(t)[:, 0]))
    scale = size / length
    xy = outline(rng.uniform(0, 2 * np.pi, n)) + rng.normal(0, noise * length, (n, 2))
    points = np.column_stack([xy, np.zeros(n)])
    points = np.vstack([points, points[rng.choice(n, n // 5)]])  # duplicates
    rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    points = rng.permutation(points) @ rotation.T * scale + rng.uniform(-5, 5, 3) * size
    return Leaf(boundary=points, veins=[]), exact.area * scale**2


def true_boundaries():
    """(name, points) of boundaries no test of a scan or an area may refuse: the demos, the
    gallery's shapes and margins, a folded form, noisy shuffled ellipses (noise up to 2% of the
    length) and random leaves of 20,000 noisy points."""
    from leafstudio.forms import SHAPES, make_form
    from leafstudio.forms.terms import MARGINS

    yield "demo nested", demo("nested").boundary
    yield "demo parallel", demo("parallel").boundary
    for shape in SHAPES:
        yield f"form {shape}", make_form(shape).boundary
    for margin in MARGINS:
        yield f"form {margin}", make_form("elliptic", margin=margin).boundary
    yield "linear serrate", make_form("linear", margin="dentate").boundary
    yield "relief", make_form("ovate", fold=40, curl=0.3, wave=0.05).boundary
    for n, sigma in [(3000, 0.002), (2000, 0.04), (20000, 0.04), (20000, 0.08)]:
        yield f"ellipse {n} σ={sigma}", ellipse_cloud(n, sigma)  # σ 0.08: 2% of the length
    for seed in range(2):
        yield f"random leaf {seed}", random_leaf(seed, 20000, 1e-2, 1e3)[0].boundary


# --- points that fill an area (given as a boundary, they are refused) ----------------------------


def disc(n: int, seed: int = 0) -> np.ndarray:
    """n points spread evenly at random over the unit disc, in z = 0."""
    rng = np.random.default_rng(seed)
    radius, angle = np.sqrt(rng.uniform(size=n)), rng.uniform(0, 2 * np.pi, n)
    return np.column_stack([radius * np.cos(angle), radius * np.sin(angle), np.zeros(n)])


def cap(n: int, height: float = 1.0, seed: int = 0) -> np.ndarray:
    """n points at random on the unit sphere's cap of `height` (1: a hemisphere)."""
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(50 * n, 3))
    points /= np.linalg.norm(points, axis=1)[:, None]
    return points[points[:, 2] >= 1 - height][:n]


def blob(n: int, flat: float = 0.3, seed: int = 0) -> np.ndarray:
    """n points of a Gaussian blob flattened to `flat` of its length."""
    return np.random.default_rng(seed).normal(size=(n, 3)) * [1.0, 0.7, flat]


def filled_form(shape: str, n: int, seed: int = 0) -> np.ndarray:
    """n points at random inside a gallery form's outline, on a gentle curve: a sparse scan."""
    from leafstudio.forms import make_form

    rng = np.random.default_rng(seed)
    outline = shapely.Polygon(make_form(shape).boundary[:, :2])
    x0, y0, x1, y1 = outline.bounds
    points = np.column_stack([rng.uniform(x0, x1, 40 * n), rng.uniform(y0, y1, 40 * n)])
    points = points[shapely.contains_xy(outline, points[:, 0], points[:, 1])][:n]
    return np.column_stack([points, 0.05 * points[:, 0] ** 2])


# --- narrow bent blades --------------------------------------------------------------------------


def bend(along: np.ndarray, across: np.ndarray, bend: float) -> np.ndarray:
    """(n, 3) points of a blade 1 long whose midline is an arc turning `bend` radians (0:
    straight), at `along` (0 to 1) on the midline and `across` off it."""
    turn = bend * (along - 0.5)
    if bend == 0:
        centre = np.column_stack([along - 0.5, 0 * along])
    else:
        centre = np.column_stack([np.sin(turn), 1 - np.cos(turn)]) / bend
    normal = np.column_stack([-np.sin(turn), np.cos(turn)])
    return np.column_stack([centre + across[:, None] * normal, 0 * along])


def bent_strap(points: int, aspect: float, bend_by: float, noise: float = 0.0, seed: int = 0):
    """A narrow outline 1 long, `aspect` times longer than wide, bent `bend_by` radians along its
    midline (a curved grass or iris leaf traced as an outline), `points` points in order, with
    noise of `noise` of its length."""
    t = np.linspace(0, 1, points // 2)
    half = 0.5 / aspect * np.sin(np.pi * t) ** 0.5
    outline = np.vstack([bend(t, half, bend_by), bend(t, -half, bend_by)[::-1]])
    return outline + noise * np.random.default_rng(seed).normal(size=outline.shape)


def bent_filled_strip(points: int, aspect: float, bend_by: float, seed: int = 0) -> np.ndarray:
    """Points all over a bent strip (a scan of a curved grass-like leaf), the strip of
    bent_strap, with the scanner's noise of 0.2% of the length off its plane."""
    rng = np.random.default_rng(seed)
    t = rng.uniform(0, 1, points)
    across = 0.5 / aspect * rng.uniform(-1, 1, points) * np.sin(np.pi * t) ** 0.5
    cloud = bend(t, across, bend_by)
    cloud[:, 2] = 0.05 * t**2 + 0.002 * rng.normal(size=points)
    return cloud


# --- a synthetic scan ----------------------------------------------------------------------------


def scan_blade_outline(t: np.ndarray) -> np.ndarray:
    """The synthetic scan's blade outline (egg-shaped, length 1, wider toward -x) at angles t."""
    return np.column_stack([0.5 * np.cos(t), 0.2 * np.sin(t) * (1 - 0.3 * np.cos(t))])


def scan_surface(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The synthetic scan's blade heights."""
    return 0.3 * x**2 + 0.6 * y**2 - 0.1 * x


def synthetic_scan(
    seed: int = 0,
    candidates: int = 9000,
    blade_points: int | None = None,
    petiole_points: int = 150,
    outlier_points: int = 25,
) -> dict[str, np.ndarray]:
    """A synthetic scan: the blade's surface (the `candidates` uniform points inside its outline,
    at most `blade_points` of them), a petiole sticking out at -x, and outliers; (n_i, 3) points
    under "blade", "petiole" and "outliers"."""
    rng = np.random.default_rng(seed)
    region = shapely.Polygon(scan_blade_outline(np.linspace(0, 2 * np.pi, 400, endpoint=False)))
    xy = rng.uniform([-0.5, -0.27], [0.5, 0.27], size=(candidates, 2))
    xy = xy[shapely.contains_xy(region, xy[:, 0], xy[:, 1])][:blade_points]
    blade = np.column_stack([xy, scan_surface(xy[:, 0], xy[:, 1])])
    along = rng.uniform(-0.8, -0.49, petiole_points)
    petiole = np.column_stack(
        [along, rng.normal(0, 0.004, petiole_points), scan_surface(-0.5, 0) - 0.2 * (along + 0.5)]
    )
    outliers = rng.uniform([-1, -1, -0.5], [1, 1, 0.5], size=(outlier_points, 3))
    return {"blade": blade, "petiole": petiole, "outliers": outliers}


def assert_outline_is_the_blades(found) -> None:
    """The extracted outline is the synthetic scan's blade (scan_blade_outline), to 4% of its
    area and 0.03."""
    known = shapely.Polygon(scan_blade_outline(np.linspace(0, 2 * np.pi, 400, endpoint=False)))
    got = shapely.Polygon(found.leaf.boundary[:, :2])
    assert got.is_valid
    assert known.symmetric_difference(got).area < 0.04 * known.area
    assert shapely.hausdorff_distance(known.exterior, got.exterior) < 0.03


@functools.cache
def extracted_scan(path: Path) -> tuple[np.ndarray, object]:
    """A real scan's (n, 3) points, read-only, and what `extract_leaf` finds in them: extracted
    once per test run (1-2 s a scan) for the tests that only read them. Under pytest-xdist the
    first worker to need a scan leaves its extraction in the run's shared folder for the other
    (a pickle, written whole: at worst both extract it). Extracted on one BLAS thread, as
    workflows.open_scan extracts (the app, `extract`, batch): the same leaf to the bit in a run
    with xdist or without (tests/sources/test_scan_fins.py compares them)."""
    from leafstudio._shared.blas import one_blas_thread
    from leafstudio._shared.safewrite import write_bytes
    from leafstudio.sources.extract import extract_leaf
    from leafstudio.sources.scan import read_scan

    points = read_scan(path)
    points.setflags(write=False)
    folder = os.environ.get(SHARED)
    kept = Path(folder or ".") / f"{Path(path).stem}.extracted.pickle"
    if folder and kept.exists():
        return points, pickle.loads(kept.read_bytes())
    with one_blas_thread():
        found = extract_leaf(points)
    if folder:
        write_bytes(kept, pickle.dumps(found))
    return points, found


def cupped_ovate(depth: float) -> Leaf:
    """The ovate form's curves lifted onto a cup, a quadratic height field `depth` of its length
    deep at a length from its centre (0.3: its margin 0.071 of its width off its plane, 0.6:
    0.142): a bent leaf no pose lays flatter than the quadric (unfold.py refuses it)."""
    from leafstudio.forms.make import Form

    leaf = Form("ovate").leaf()
    length = float(np.ptp(leaf.boundary, axis=0).max())
    centre = leaf.boundary[:, :2].mean(axis=0)

    def cup(points: np.ndarray) -> np.ndarray:
        lifted = points.copy()
        lifted[:, 2] += depth * length * (((points[:, :2] - centre) / length) ** 2).sum(axis=1)
        return lifted

    return Leaf(cup(leaf.boundary), [cup(v) for v in leaf.veins])
