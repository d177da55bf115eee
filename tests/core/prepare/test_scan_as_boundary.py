"""A whole 3D scan given where a boundary belongs (review finding, session 2): the real scans passed
as a leaf's boundary gave a meaningless leaf without a word (a polygon snaking through the points:
perimeter 3 to 14 times their hull's, sugar beet pot1_1 "measured" 80 mm² of a 1,650 mm² hull).
Now the pipeline refuses them in one line pointing to `leafstudio extract`, and true boundaries
(demos, gallery forms, noisy, unordered and dense clouds) never get that error."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely

import leafstudio as ls
from leafstudio.cli import main
from leafstudio.core.plane import fit_frame
from leafstudio.core.prepare.cover import COVER_SPREAD, surface_spread
from leafstudio.core.prepare.outline import trace_outline
from leafstudio.errors import LeafError
from leafstudio.forms import make_form
from leafstudio.forms.make import seen_on_edge
from leafstudio.sources.scan import read_scan
from tests.leaves import bend as _bend
from tests.leaves import bent_filled_strip, bent_strap, true_boundaries

REAL = Path(__file__).resolve().parents[4] / "shared" / "realleaves"
SCANS = sorted(REAL.glob("*.txt")) if REAL.is_dir() else []
needs_scans = pytest.mark.skipif(not SCANS, reason=f"no real scans at {REAL}")


@needs_scans
@pytest.mark.parametrize("path", SCANS, ids=lambda p: p.stem[-20:])
def test_a_real_scan_given_as_the_boundary_is_refused(path):
    scan = read_scan(path)
    with pytest.raises(LeafError, match=r"cover a surface.*leafstudio extract"):
        ls.reconstruct(ls.Leaf(scan, []), ls.Params(grid=48))


@needs_scans
def test_the_command_line_refuses_a_scan_as_a_leaf_in_one_line(tmp_path, capsys):
    """The sugar beet scans are x, y, z lists: `measure` read them as boundaries (exit 0)."""
    for path in [p for p in SCANS if p.name.startswith("sugarbeet")]:
        assert main(["measure", str(path)]) == 2
        err = [line for line in capsys.readouterr().err.splitlines() if "error" in line]
        assert len(err) == 1 and str(path) in err[0] and "leafstudio extract" in err[0]
        assert "Traceback" not in err[0]


@needs_scans
@pytest.mark.parametrize("path", SCANS, ids=lambda p: p.stem[-20:])
def test_a_scans_outline_is_the_region_not_a_path_through_its_points(path):
    """trace_outline of a filled cloud: the region its points cover, never a concave hull that
    snakes to every point (3 to 14 times its convex hull's perimeter on 6 of the 8 scans)."""
    scan = read_scan(path)
    xy, h = fit_frame(scan, np.zeros((0, 3))).to_plane(scan)
    outline = shapely.Polygon(trace_outline(xy, h).polygon)
    assert outline.length < 2 * shapely.MultiPoint(xy).convex_hull.length


def test_true_boundaries_are_never_taken_for_a_surface():
    spreads = {name: surface_spread(points) for name, points in true_boundaries()}
    assert max(spreads.values()) < 0.8 * COVER_SPREAD, spreads


def test_a_sketch_sparse_boundary_is_not_measured():
    """A few clicks: too few points near each to tell a curve from a surface, so no error."""
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    assert surface_spread(np.column_stack([np.cos(t), 0.4 * np.sin(t), 0 * t])) == 0.0


def _strap(points: int, noise: float, seed: int = 0) -> np.ndarray:
    """A strap-shaped outline 1 long and 0.04 wide (25 times longer than wide, as grass and iris
    leaves are), densely sampled, with noise of `noise` of its length."""
    t = np.linspace(0, 1, points // 2)
    half = 0.02 * np.sin(np.pi * t) ** 0.5
    outline = np.vstack(
        [np.column_stack([t, half, 0 * t]), np.column_stack([t, -half, 0 * t])[::-1]]
    )
    return outline + noise * np.random.default_rng(seed).normal(size=outline.shape)


@pytest.mark.parametrize("aspect", [20, 22, 25, 28, 30])
@pytest.mark.parametrize("shape", ["linear", "lanceolate"])
def test_a_narrow_blade_is_a_boundary_not_a_surface(shape, aspect):
    """Review finding: at 20-30 times longer than wide (the range `form --aspect` allows), both
    margins fell in one neighbourhood of 5% of the length and read as a surface (spread 0.43 to
    0.79): every such form was refused as a scan."""
    leaf = make_form(shape, aspect=aspect)
    assert surface_spread(leaf.boundary) < COVER_SPREAD
    ls.reconstruct(leaf, ls.Params(grid=48))  # no "cover a surface" error


@pytest.mark.parametrize(("points", "noise"), [(2000, 0.0), (10000, 0.001), (20000, 0.004)])
def test_a_dense_noisy_narrow_outline_is_a_boundary(points, noise):
    assert surface_spread(_strap(points, noise)) < 0.8 * COVER_SPREAD


def test_a_narrow_filled_cloud_is_still_a_surface():
    """Points all over a strip 25 times longer than wide: a scan of a grass-like leaf."""
    rng = np.random.default_rng(0)
    x = rng.uniform(0, 1, 20000)
    y = rng.uniform(-0.02, 0.02, x.size) * np.sin(np.pi * x) ** 0.5
    z = 0.05 * x**2 + 0.002 * rng.normal(size=x.size)
    assert surface_spread(np.column_stack([x, y, z])) > COVER_SPREAD


def striped_scan(spacing: float) -> np.ndarray:
    """A laser-line scanner's cloud of a leaf 1 long and 0.6 wide: dense along its lines (a
    point every 0.001), `spacing` of the length between them."""
    rng = np.random.default_rng(1)
    stripes = []
    for y in np.arange(-0.3, 0.3, spacing):
        x = np.arange(0, 1, 0.001)
        x = x[np.abs(y) < 0.3 * np.sin(np.pi * x)]
        stripes.append(
            np.column_stack(
                [
                    x,
                    y + 0.0003 * rng.normal(size=x.size),
                    0.05 * np.sin(np.pi * x) + 0.0005 * rng.normal(size=x.size),
                ]
            )
        )
    return np.vstack(stripes)


@pytest.mark.parametrize("spacing", [0.003, 0.01, 0.02])
def test_a_dense_striped_scan_is_a_surface(spacing):
    """Looked at closer than the spacing it reads as lines (a finer second look tried in
    session 2 accepted it as a boundary), so the neighbourhood stays wider than the stripes."""
    assert surface_spread(striped_scan(spacing)) > COVER_SPREAD


def narrow_striped_scan(spacing: float, along: bool = True, bend: float = 0.0) -> np.ndarray:
    """A laser-line scan of the strip of bent_filled_strip (25 times longer than wide), its
    lines `spacing` apart along its length (`along`) or across it, a point every 0.001."""
    rng = np.random.default_rng(2)
    half = 0.5 / 25
    parts = []
    if along:
        for y in np.arange(-half, half, spacing) + spacing / 2:
            t = np.arange(0, 1, 0.001)
            t = t[np.abs(y) < half * np.sin(np.pi * t) ** 0.5]
            parts.append(np.column_stack([t, np.full(t.size, y)]))
    else:
        for t in np.arange(0, 1, spacing):
            w = half * np.sin(np.pi * t) ** 0.5
            y = np.arange(-w, w, 0.001)
            parts.append(np.column_stack([np.full(y.size, t), y]))
    t, y = np.vstack(parts).T
    cloud = _bend(t, y + 0.0003 * rng.normal(size=y.size), bend)
    cloud[:, 2] = 0.05 * t**2 + 0.0005 * rng.normal(size=t.size)
    return cloud


@pytest.mark.filterwarnings("ignore:no veins given")
@pytest.mark.parametrize(("aspect", "bend"), [(25, 1.0), (25, 2.0), (30, 1.0), (30, 3.0)])
@pytest.mark.parametrize(("points", "noise"), [(2000, 0.0), (5000, 0.002), (10000, 0.004)])
def test_a_bent_narrow_outline_is_a_boundary(aspect, bend, points, noise):
    """Review finding (session 2, known limit): the neighbourhood's cap at a quarter of the
    width is the blade's straight extent across, which for a bent blade is far more than its
    width, so both margins fell in one neighbourhood and read as a surface (0.46 to 0.59)."""
    boundary = bent_strap(points, aspect, bend, noise)
    assert surface_spread(boundary) < COVER_SPREAD
    leaf = ls.Leaf(boundary * 100, [])
    ls.reconstruct(leaf, ls.Params(grid=48))  # no "cover a surface" error


@pytest.mark.parametrize("spacing", [0.003, 0.005])
@pytest.mark.parametrize("along", [True, False], ids=["lines-along", "lines-across"])
def test_a_narrow_striped_scan_is_still_a_surface(spacing, along):
    """A straight grass leaf scanned in lines 0.3-0.5% of its length apart (8 to 13 across its
    width): a neighbourhood holds several lines, never just two, so it is not read as two
    margins (0.60-0.74 before and after the two-strand test)."""
    assert surface_spread(narrow_striped_scan(spacing, along)) > COVER_SPREAD


@needs_scans
def test_a_real_scan_thinned_or_turned_is_still_a_surface():
    """Half of each scan's points, and each scan turned in space: the two-strand test lowers
    none of them to a boundary (0.58-0.86)."""
    rng = np.random.default_rng(0)
    turn = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    for path in SCANS:
        scan = read_scan(path)
        half = scan[rng.choice(len(scan), len(scan) // 2, replace=False)]
        assert surface_spread(half) > COVER_SPREAD, path.name
        assert surface_spread(scan @ turn.T * 3 + 7) > COVER_SPREAD, path.name


@pytest.mark.parametrize(
    ("shape", "aspect", "curl", "fold", "margin"),
    [
        ("linear", 25, 1.0, 0.0, "entire"),
        ("linear", 20, -1.0, 60.0, "entire"),
        ("lanceolate", 25, -1.0, 30.0, "serrate"),
        ("lanceolate", 30, 1.0, 60.0, "entire"),
    ],
)
def test_a_curled_narrow_form_is_a_boundary(shape, aspect, curl, fold, margin):
    """Found this session: a narrow gallery form bent out of its plane (`form --curl`) has the
    same trouble as a bent outline, its straight extent across being its bend's, not its width
    (0.50-0.67 before: refused as a scan, as were 68 of 288 narrow forms, aspect 20-30, with a
    curl, fold or wave)."""
    leaf = make_form(shape, aspect=aspect, curl=curl, fold=fold, margin=margin)
    assert surface_spread(leaf.boundary) < COVER_SPREAD
    if not seen_on_edge(leaf):
        ls.reconstruct(leaf, ls.Params(grid=48))  # no "cover a surface" error
        return
    # posed so far that the boundary's PCA plane sees it side-on (forms.make.seen_on_edge): the
    # pipeline may refuse it for its veins, but never as a whole scan
    try:
        ls.reconstruct(leaf, ls.Params(grid=48))
    except LeafError as error:
        assert "surface" not in str(error) and "outside the boundary" in str(error)


@pytest.mark.parametrize(("aspect", "bend"), [(25, 1.0), (25, 3.0), (30, 2.0)])
@pytest.mark.parametrize("points", [5000, 20000])
def test_a_bent_narrow_filled_cloud_is_a_surface(aspect, bend, points):
    """Known limit of session 2: points all over a bent strip (a curved grass leaf's scan) have
    the straight extent across of the bend, so its neighbourhoods are wider than the strip and
    read as a curve (0.12-0.28: passed as a boundary). They fill a band narrower than the
    neighbourhood evenly, and are measured again at the band's scale."""
    assert surface_spread(bent_filled_strip(points, aspect, bend)) > COVER_SPREAD


@pytest.mark.parametrize("along", [True, False], ids=["lines-along", "lines-across"])
def test_a_bent_narrow_striped_scan_is_a_surface(along):
    """The bent strip scanned in lines 0.5% of its length apart (0.20-0.23 before)."""
    assert surface_spread(narrow_striped_scan(0.005, along, bend=2.0)) > COVER_SPREAD


def _dense_noisy(boundary: np.ndarray, points: int, noise: float, seed: int = 0) -> np.ndarray:
    """The outline through `boundary`'s points, `points` points evenly along it, with noise of
    `noise` of its length in its plane."""
    closed = np.vstack([boundary, boundary[:1]])
    along = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(closed, axis=0), axis=1))])
    at = np.linspace(0, along[-1], points, endpoint=False)
    outline = np.column_stack([np.interp(at, along, closed[:, i]) for i in range(3)])
    jitter = np.random.default_rng(seed).normal(size=(points, 2)) * noise * np.ptp(outline[:, 0])
    return outline + np.column_stack([jitter, np.zeros(points)])


@pytest.mark.parametrize("noise", [0.001, 0.003, 0.005])
@pytest.mark.parametrize("margin", ["dentate", "serrate", "crenate"])
def test_a_noisy_toothed_outline_is_not_taken_for_a_band(margin, noise):
    """Teeth spread a margin's points evenly across a band as wide as they are tall, as a
    filled strip's are: with noise of 0.1-0.5% of the length, looking closer reads noise there.
    The band look must leave such outlines well clear of the threshold (at most 0.16, as before
    it; a looser flatness, kurtosis up to 2.4 or 2.6, gave 0.36-0.41)."""
    for shape in ("elliptic", "ovate"):
        boundary = _dense_noisy(make_form(shape, margin=margin).boundary, 5000, noise)
        assert surface_spread(boundary) < 0.6 * COVER_SPREAD, shape


def random_narrow_outline(rng: np.random.Generator, aspect=(25, 30), bend=(1, 3), noise=0.004):
    """A narrow outline 1 long: `aspect` and `bend` drawn from their ranges, its midline an arc
    or an S (turning one way, then the other, up to 3 times), its width profile sin^p (p 0.3-1),
    2,000-10,000 points, evenly or randomly along it, noise up to `noise` of its length, a curl
    out of its plane in 3 of 10, shuffled and turned in space."""
    n, turns = int(rng.uniform(2000, 10000)) // 2, int(rng.integers(4))
    a, b, p = rng.uniform(*aspect), rng.uniform(*bend), rng.uniform(0.3, 1.0)
    t = np.sort(rng.uniform(0, 1, n)) if rng.random() < 0.5 else np.linspace(0, 1, n)
    fine = np.linspace(0, 1, 4001)
    turn = b * (fine - 0.5) if turns == 0 else b / 2 * np.sin(2 * np.pi * turns * fine)
    heading = np.column_stack([np.cos(turn), np.sin(turn)])
    step = (heading[1:] + heading[:-1]) / 2 * np.diff(fine)[:, None]
    midline = np.vstack([[0, 0], np.cumsum(step, axis=0)])
    centre = np.column_stack([np.interp(t, fine, midline[:, i]) for i in range(2)])
    angle = np.interp(t, fine, turn)
    normal = np.column_stack([-np.sin(angle), np.cos(angle)])
    half = (0.5 / a * np.sin(np.pi * t) ** p)[:, None] * normal
    xy = np.vstack([centre + half, (centre - half)[::-1]])
    z = (rng.uniform(-1, 1) if rng.random() < 0.3 else 0.0) * (xy[:, 0] - xy[:, 0].mean()) ** 2
    points = np.column_stack([xy, z]) + rng.uniform(0, noise) * rng.normal(size=(2 * n, 3))
    return rng.permutation(points) @ np.linalg.qr(rng.normal(size=(3, 3)))[0].T


def test_random_bent_narrow_outlines_are_boundaries():
    """30 drawn within the range asked for (aspect 25-30, bend 1-3 rad, noise up to 0.4%), arcs
    and S-bends: before the two-strand test 2 of them were refused (0.60); now at most 0.17.
    (Of 300 drawn wider, aspect 20-35, bend 0-3.5, noise up to 0.5%: 30 before, 1 now.)"""
    rng = np.random.default_rng(7)
    spreads = [surface_spread(random_narrow_outline(rng)) for _ in range(30)]
    assert max(spreads) < COVER_SPREAD, np.round(spreads, 2)


@pytest.mark.parametrize(("aspect", "bend"), [(25, 2.0), (30, 1.0), (30, 3.0)])
def test_a_bent_narrow_leaf_traced_from_an_image_is_a_boundary(aspect, bend):
    """A curved grass leaf drawn 400 pixels long in an image and traced (marching squares, as
    photo outlines are): 0.47-0.53 before the two-strand test, refused as a scan."""
    from skimage.measure import find_contours

    outline = bent_strap(4000, aspect, bend)[:, :2]
    outline = (outline - outline.min(axis=0)) / np.ptp(outline, axis=0).max() * 400 + 2
    rows, cols = np.mgrid[0 : int(outline[:, 1].max()) + 4, 0 : int(outline[:, 0].max()) + 4]
    image = shapely.contains_xy(shapely.Polygon(outline), cols + 0.5, rows + 0.5)
    traced = max(find_contours(image.astype(float), 0.5), key=len)
    assert surface_spread(np.column_stack([traced, np.zeros(len(traced))])) < COVER_SPREAD


@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize(("aspect", "bend"), [(25, 2.0), (30, 3.0)])
def test_a_photo_of_a_bent_grass_leaf_makes_a_leaf(aspect, bend):
    """End to end: a curved grass leaf photographed, its outline found (leafstudio photo) and
    reconstructed; before the two-strand test the pipeline refused it as a whole scan."""
    from leafstudio.sources.photo import leaf_from_photo
    from tests.photos import form_photo

    outline = bent_strap(2000, aspect, bend)
    image = form_photo(outline - outline[0], angle=10, pixels_per_unit=700, size=(900, 500))[0]
    leaf = leaf_from_photo(image).leaf
    result = ls.reconstruct(leaf, ls.Params(grid=48))  # no "cover a surface", no warning
    flat, _ = result.frame.to_plane(leaf.boundary)
    outline_area = shapely.Polygon(flat).buffer(0).area
    assert result.warnings == []
    assert abs(result.metrics["leaf"]["area"] - outline_area) < 0.05 * outline_area  # whole blade
