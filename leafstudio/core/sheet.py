"""A scan's bend: a smooth sheet fitted to all the blade's points, and the blade unrolled onto it
(issue 21, build item 3).

A curled or rolled real leaf is not a height field over any plane (soybean pot1_1: even a
thin-plate spline fitted to every point over the PCA plane is 2.1% of the length off), so a scan
is first unrolled. The blade's points are flattened near-isometrically (`unroll`: geodesic
distances along a neighbour graph of the points, from a few landmarks, placed in the plane by
landmark MDS, de Silva & Tenenbaum 2003), then a smooth map from the flat blade into 3D is
fitted to them (`Sheet`: a thin-plate spline S(u, v) through the points averaged in cells of
the flat blade, sheet_cells.CELLS across the length, fewer on a sparse scan; first through the
unrolled cube means, then refitted on the flat blade that sheet gives: `refit`). A flat point
(u, v, w) goes to S(u, v) + w n(u, v), n the sheet's unit normal, and a 3D point back to its
nearest sheet point (u, v) and its offset w along n (Gauss-Newton from the nearest point of a
dense sample of the sheet).

The pipeline then runs the paper's steps on the flat blade (core/bend.py), where the relief w
left over by the sheet is the scanner's noise and the veins' own.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import RBFInterpolator, RectBivariateSpline
from scipy.sparse.csgraph import connected_components, dijkstra
from scipy.spatial import cKDTree

from leafstudio._shared import progress
from leafstudio.core.plane import grid_frame
from leafstudio.core.sheet_cells import VOLUME, cubes, cut, mean_errors

REACH = 1.8  # cells: cell means closer than this are neighbours in the graph
MIN_CELLS = 30
LANDMARKS = 120  # geodesic sources for the landmark MDS
MOST_KEPT = 0.8  # the graph's largest piece must hold this share of the points
SMOOTHING = 1e-3  # the thin-plate spline's smoothing, at unit length, for a cell of the typical
# error (refit weighs it by each cell's): at 1e-4 the sheet missed its cell means by 0.07-0.13
# of their noise (a local quadratic's residual through them): it followed the scanner's noise and
# the mesh crinkled; at 1e-3 unweighed by 0.32-0.50; weighed, 2e-3 until soybean pot1_1's base
# was put at its stalk's end (1.00% of its length from the scan there; fit_sheet's Notes)
WEIGHT_RANGE = 30.0  # a cell's smoothing is at most this many times the typical's, or 1/this
# (10 and 100 moved no scan's 99th-percentile dihedral by more than 2 degrees)
FIRST = 1e-3  # the smoothing of the sheet through the cube means, at unit length (`refit`)
NEWTON = 10  # Gauss-Newton steps of `Sheet.flatten`, at most
SETTLED = 1e-9  # ... a point whose step is shorter than this share of the sheet's size settled
HALVINGS = 4  # a step that goes farther is halved at most this many times
SAMPLES = 160  # the spline sampled this many times across the flat blade's extent
PAD = 0.1  # ... and this share of it beyond, on every side
STEP = 1e-4  # fit_sheet's central differences, a share of the flat blade's extent
UNROLLING = "unrolling the blade"  # what fit_sheet's progress reports say it does
CHUNKS = 8  # the spline is sampled in this many parts, its progress reported after each


def unroll(points: np.ndarray, reach: float) -> np.ndarray | None:
    """(n, 2) flat coordinates of (n, 3) points on a bent sheet, near-isometric, or None when
    the points' neighbour graph falls apart (the points are not one sheet).

    Parameters
    ----------
    points : (n, 3) float array
        Points sampling one smooth surface evenly (cell means of a blade's scan points).
    reach : float
        Points closer than this are neighbours (a little over the points' spacing).

    Returns
    -------
    (n, 2) float array or None
        The points unrolled, in the points' units.
    """
    points = np.asarray(points, dtype=float)
    n = len(points)
    if n < MIN_CELLS:
        return None
    tree = cKDTree(points)
    graph = tree.sparse_distance_matrix(tree, reach, output_type="coo_matrix").tocsr()
    _, label = connected_components(graph, directed=False)
    main = label == np.argmax(np.bincount(label))
    if main.mean() < MOST_KEPT:
        return None
    inside = np.flatnonzero(main)
    sources = inside[:: max(1, len(inside) // LANDMARKS)]
    geo = dijkstra(graph, indices=sources)  # (L, n)
    squared = geo[:, sources] ** 2
    mean_rows = squared.mean(1)
    centred = -0.5 * (squared - squared.mean(0) - mean_rows[:, None] + squared.mean())
    values, vectors = np.linalg.eigh(centred)
    top = np.argsort(values)[::-1][:2]
    if values[top[1]] <= 0:
        return None
    flat = np.zeros((n, 2))
    flat[main] = (
        -0.5 * (geo[:, main] ** 2 - mean_rows[:, None]).T @ (vectors[:, top] / np.sqrt(values[top]))
    )
    if not main.all():  # points off the main piece: placed with their nearest main point
        flat[~main] = flat[main][cKDTree(points[main]).query(points[~main])[1]]
    return flat


def spline_on_grid(spline: RBFInterpolator, us: np.ndarray, vs: np.ndarray) -> np.ndarray:
    """(len(us), len(vs), k) a 2D thin-plate RBFInterpolator's values on the grid us x vs.

    The same sum as spline(points) (phi(r) = r^2 log r = r2 log(r2) / 2, plus the polynomial on
    the shifted and scaled points), at 2.5 times less cost: on a grid a row's squared distances
    to the centres are one sum of a row's and the columns' squared offsets, and the kernel is
    taken over whole arrays, not point by point (the Sheet's grid was most of a scan's
    extraction). Its values differ from scipy's by rounding only: at most 2e-11 of the values'
    extent on the shared scans (soybean pot1_1; the others 1e-13 to 1.3e-12), and the extracted
    leaves by at most 5e-9 of their size (where Gauss-Newton stops, SETTLED, moves with it;
    benchmarks/bench_sources.py --compare). Falls back to spline(points) for anything else (a
    kernel other than the thin-plate one, an epsilon other than 1, or a scipy whose
    RBFInterpolator keeps its coefficients elsewhere)."""
    coeffs = getattr(spline, "_coeffs", None)
    shift, scale = getattr(spline, "_shift", None), getattr(spline, "_scale", None)
    centres = spline.y
    if (
        spline.kernel != "thin_plate_spline"
        or getattr(spline, "epsilon", 1.0) != 1.0  # scipy scales the kernel's input by it
        or coeffs is None
        or shift is None
        or scale is None
        or centres.shape[1] != 2
        or coeffs.ndim != 2
        or len(coeffs) != len(centres) + len(spline.powers)
    ):
        grid = np.stack(np.meshgrid(us, vs, indexing="ij"), -1).reshape(-1, 2)
        return spline(grid).reshape(len(us), len(vs), -1)
    weights, poly = coeffs[: len(centres)], coeffs[len(centres) :]
    du2 = (us[:, None] - centres[None, :, 0]) ** 2  # (nu, m)
    dv2 = (vs[:, None] - centres[None, :, 1]) ** 2  # (nv, m)
    out = np.empty((len(us), len(vs), coeffs.shape[1]))
    for a in range(len(us)):
        r2 = du2[a] + dv2
        phi = np.log(r2, out=np.zeros_like(r2), where=r2 > 0)
        phi *= r2
        phi *= 0.5
        out[a] = phi @ weights
    grid = np.stack(np.meshgrid(us, vs, indexing="ij"), -1)
    monomials = np.prod(((grid - shift) / scale)[..., None, :] ** spline.powers, axis=-1)
    return out + monomials @ poly


def _unit_cross(su: np.ndarray, sv: np.ndarray) -> np.ndarray:
    """(n, 3) S_u x S_v of (n, 3) tangents, of unit length."""
    normal = np.cross(su, sv)
    return normal / np.linalg.norm(normal, axis=1, keepdims=True)


@dataclass(frozen=True, eq=False)
class Sheet:
    """The smooth map S(u, v) from a flat blade into 3D, a thin-plate spline through `centers`
    (m, 2) to `values` (m, 3), and the offsets along its normal (module docstring). A Bend
    (model.Bend): flat points (u, v, w) are bent by `apply` and unbent by `flatten`."""

    centers: np.ndarray
    values: np.ndarray
    smoothing: float | np.ndarray  # the spline's, one for all centres or (m,) one each (refit)
    up: np.ndarray  # (3,) the side the blade mostly faces: the normal is on it (`_normal`)
    cell: float = 0.0  # the flat blade's cells' side its centres were averaged in (`refit`; 0:
    # not known, a sheet read from a project)
    _pieces: tuple = field(init=False, repr=False)
    _guess: tuple = field(init=False, repr=False)
    _side: float = field(init=False, repr=False)

    def __post_init__(self) -> None:
        spline = RBFInterpolator(
            self.centers, self.values, kernel="thin_plate_spline", smoothing=self.smoothing
        )
        lo, hi = self.centers.min(axis=0), self.centers.max(axis=0)
        step = float(np.max(hi - lo)) / SAMPLES
        pad = PAD * float(np.max(hi - lo))
        # as many steps as cover the blade and its pad, counted with a tolerance: the longest
        # side spans exactly 2 PAD * SAMPLES + SAMPLES steps, and np.arange(lo, hi + step, step)
        # gave one more or one fewer by the last bit of the centres, moving every sample (a
        # soybean scan scaled by 3 was flattened otherwise: 6 of its points changed sides)
        count = np.floor((hi - lo + 2 * pad) / step + 1e-6).astype(int) + 2
        us, vs = (lo[k] - pad + step * np.arange(count[k]) for k in (0, 1))
        grid = np.stack(np.meshgrid(us, vs, indexing="ij"), -1).reshape(-1, 2)
        parts = []  # in parts: most of a scan's sheet's time, and a Cancel may stop it between
        for k, rows in enumerate(np.array_split(np.arange(len(us)), CHUNKS), start=1):
            parts.append(spline_on_grid(spline, us[rows], vs))
            progress.report(k / CHUNKS, UNROLLING)
        at = np.concatenate(parts)
        # the spline sampled and interpolated bicubically, evaluated in constant time per point
        # (the spline's own sum is over every centre); at its centres it departs from the spline
        # by 1.2e-3 of the blade's size on average (soybean pot1_1; 1.5e-2 at most, where the
        # spline bends sharply), but sampling twice as finely moved no shared scan's fit by more
        # than 0.01% of the length (mean of the eight 0.453% -> 0.452%, at 4 times the cost)
        pieces = tuple(RectBivariateSpline(us, vs, at[:, :, k]) for k in range(3))
        object.__setattr__(self, "_pieces", pieces)
        object.__setattr__(self, "_guess", (cKDTree(at.reshape(-1, 3)), grid))
        # one side for the whole sheet: S_u x S_v turned to `up` where most of the blade's
        # cell means have it (`_normal`)
        ahead = _unit_cross(self(self.centers, du=1), self(self.centers, dv=1)) @ self.up
        object.__setattr__(self, "_side", -1.0 if ahead.sum() < 0 else 1.0)

    @property
    def size(self) -> float:
        """The flat blade's extent."""
        return float(np.ptp(self.centers, axis=0).max())

    def centres_flat(self) -> np.ndarray:
        """(m, 3) the flat points (u, v, 0) of the cell means the sheet was fitted to: where the
        flat blade is known (sources/extract.py keeps the outline near them)."""
        return np.column_stack([self.centers, np.zeros(len(self.centers))])

    def __call__(self, uv: np.ndarray, du: int = 0, dv: int = 0) -> np.ndarray:
        """(n, 3) sheet points (or their derivatives du, dv times along u, v) at (n, 2) flat
        points."""
        uv = np.asarray(uv, dtype=float)
        return np.column_stack([f.ev(uv[:, 0], uv[:, 1], dx=du, dy=dv) for f in self._pieces])

    def frame(self, uv: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """At (n, 2) flat points: the sheet's points, its two tangents S_u, S_v and unit normal,
        each (n, 3)."""
        su, sv = self(uv, du=1), self(uv, dv=1)
        return self(uv), su, sv, self._normal(su, sv)

    def _normal(self, su: np.ndarray, sv: np.ndarray) -> np.ndarray:
        """(n, 3) unit normals from (n, 3) tangents, S_u x S_v on the side of `up` the blade
        mostly faces, the same side everywhere. Turned to `up` point by point, they flipped
        where a blade curls past upright (sugar beet pot1_7's base): the offsets w n there
        changed sides from one mesh vertex to the next, the export's normals with them, and a
        solid's top and bottom sheets crossed (43 pairs of faces at any thickness)."""
        return _unit_cross(su, sv) * self._side

    def apply(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) flat blade points (u, v, w), bent: S(u, v) + w n(u, v)."""
        points = np.asarray(points, dtype=float)
        p, _, _, normal = self.frame(points[:, :2])
        return p + points[:, 2:3] * normal

    def flatten(self, points: np.ndarray, start: np.ndarray | None = None) -> np.ndarray:
        """(n, 3) bent points back on the flat blade: the nearest sheet point's (u, v) and the
        offset along the normal there (from (n, 2) flat points `start`, if given: the sheet point
        Gauss-Newton comes to from there, which need not be the nearest).

        Gauss-Newton from the nearest point of the sampled sheet, each step halved until it
        comes nearer; a point leaves the iteration once its step is below SETTLED of the
        sheet's size or no halving brings it nearer (its next step would be the same): most
        settle in two or three steps, and each step is spent on the points still moving only
        (ten fixed steps over every point of a 2-million-point scan took 100 s)."""
        points = np.asarray(points, dtype=float)
        if start is None:
            tree, grid = self._guess
            uv = grid[tree.query(points)[1]]
        else:
            uv = np.array(start, dtype=float)
        near = self(uv)
        miss = np.linalg.norm(near - points, axis=1)
        moving = np.arange(len(points))
        settled = SETTLED * self.size
        for _ in range(NEWTON):
            if not len(moving):
                break
            at, goal = uv[moving], points[moving]
            jac = np.stack([self(at, du=1), self(at, dv=1)], axis=2)  # (m, 3, 2)
            jtj = np.einsum("nki,nkj->nij", jac, jac)
            jtr = np.einsum("nki,nk->ni", jac, goal - near[moving])
            step = np.linalg.solve(jtj, jtr[..., None])[..., 0]
            big = np.linalg.norm(step, axis=1) >= settled
            trying = np.arange(len(moving))  # indices into moving, not yet nearer
            for _ in range(HALVINGS):
                tried = at[trying] + step[trying]
                there = self(tried)
                now = np.linalg.norm(there - goal[trying], axis=1)
                which = moving[trying]
                better = now < miss[which]
                uv[which[better]], near[which[better]] = tried[better], there[better]
                miss[which[better]] = now[better]
                trying = trying[~better]
                step[trying] *= 0.5
                if not len(trying):
                    break
            stuck = np.zeros(len(moving), dtype=bool)
            stuck[trying] = True
            moving = moving[big & ~stuck]
        normal = self._normal(self(uv, du=1), self(uv, dv=1))
        return np.column_stack([uv, np.einsum("nk,nk->n", points - near, normal)])

    def key(self) -> bytes:
        """Bytes that change with the sheet."""
        smoothing = np.asarray(self.smoothing, dtype=np.float64)
        return self.centers.tobytes() + self.values.tobytes() + smoothing.tobytes()

    def crease(self, points: np.ndarray) -> None:
        """A sheet is smooth: no crease."""
        return None

    def trim(self, points: np.ndarray) -> None:
        """A bare sheet has no holes (`Scaled.trim` has a scan's)."""
        return None


def refit(
    sheet: Sheet,
    points: np.ndarray,
    start: np.ndarray,
    cell: float,
    smoothing: float,
    frame: tuple[np.ndarray, np.ndarray] | None = None,
) -> Sheet:
    """The sheet through (n, 3) points averaged in square cells of side `cell` of the flat
    blade `sheet` puts them on (from their (n, 2) flat places `start`, their cubes' on the
    first sheet): each cell's mean flat point (u, v) to its mean point, the spline's
    `smoothing` there in proportion to the mean's error across the blade (from the cell's own
    points in 3D: sheet_cells.mean_errors), within WEIGHT_RANGE times the typical cell's.
    `frame`: the points' origin (3,) and axes (3, 3) in the world (plane.grid_frame), where the
    sheet returned is (the spline is linear in its values: the same sheet, moved there).

    The first sheet goes through cube means, each at the flat place the neighbour graph gave
    it: a cube of the 3D cloud splits a doubled layer or a scanner's stripe (soybean pot1_1:
    two views 2-3 mm apart), the graph's places are a little off, and the near-interpolating
    spline zigzags between such cubes, crinkling the mesh along the stripes. A cell of the flat
    blade spans the blade's thickness, and each centre is the mean of its points' own (u, v).
    Every cell counts, one point or many: dropping cells of fewer than three points broke the
    thin bridge of blade beside sugar beet pot1_7's hole, which then opened onto the margin.
    Each point is flattened from its cube's place, not from the nearest sheet point: between
    two layers of a curl that one changed with the scan's last bits (soybean pot1_1 scaled by
    0.7 and moved split 34 of its points otherwise between blade and petiole)."""
    flat = sheet.flatten(points, start)
    which, counts = cubes(flat[:, :2], cell)
    centres, values = np.zeros((len(counts), 2)), np.zeros((len(counts), 3))
    np.add.at(centres, which, flat[:, :2])
    np.add.at(values, which, points)
    error = mean_errors(points, which, counts)
    typical = float(np.median(error))
    if typical > 0:  # each cell's smoothing in proportion to its mean's error (module docstring)
        smoothing = smoothing * np.clip(error / typical, 1 / WEIGHT_RANGE, WEIGHT_RANGE)
    counts = counts[:, None]
    values, up = values / counts, sheet.up
    if frame is not None:
        values, up = frame[0] + values @ frame[1], up @ frame[1]
    return Sheet(centres / counts, values, smoothing, up, cell)


def fit_sheet(points: np.ndarray, up: np.ndarray, length: float) -> Sheet | None:
    """The sheet through (n, 3) blade points, or None when they cannot be unrolled (`unroll`).

    Parameters
    ----------
    points : (n, 3) float array
        The blade's scan points.
    up : (3,) float array
        The blade's upper side (the sheet's normal is on it where most of the blade faces it).
    length : float
        The blade's length, roughly (sets the cells' size).

    Returns
    -------
    Sheet or None
        The sheet; `Sheet.flatten` puts the points on their flat blade. None also for points
        that fill a volume (more than sheet_cells.VOLUME times the cells across, squared, cubes).
        A blade rolled into a nearly closed tube (330 degrees and more) gets a sheet a share of
        its points lie off (its margins' cube means are neighbours across the gap and its
        unrolled blade folds): kept, as its flat area was 653-851 against the true 785 (rolled
        320-360 degrees), where the blade laid on its plane had 317-354 (review35).
        Fitted in the points' own frame (plane.grid_frame), the flat blade is the same for a
        turned or mirrored copy of them, and the sheet is moved with them.

    Notes
    -----
    The sheet through the unrolled cube means (smoothing FIRST) is refitted once, through the
    points averaged on its flat blade (`refit`, smoothing SMOOTHING). On the eight shared scans
    that took the 99th percentile of the meshes' interior dihedral angles from 19-138 degrees
    to 9-80 at SMOOTHING 1e-4 (soybean pot1_1's walls and crumples 138 -> 80; the stripes'
    crinkles on soybean pot1_15, 17, 36 and sugar beet pot1_7 45-62 -> 20-29) and their mean
    distance to the scan from 0.45% to 0.53% of the length, none above 0.79% (pot1_1's, from
    0.52%: its surface passes between its doubled layers). That sheet still missed its cell
    means by only 0.07-0.13 of their noise, the residual of a local quadratic through the 24
    nearest (0.11-0.50 cells): it followed the scanner's noise, and the mesh crinkled. At
    SMOOTHING 1e-3, the same for every cell, it missed them by 0.32-0.50 of it, the 99th
    percentiles (margin band / inside) were pot1_1 57.9 / 59.0, pot1_15 20.5 / 20.7, the others
    9.9-17.7, the mean distance 0.56%, none above 0.96% (pot1_1); 3e-3 gave 0.58% (0.97%), 1e-2
    0.63% (1.12%): a stiffer sheet pulls off the scan, and pot1_1 stayed crumpled (2e-3: 72.9 /
    73.9), its cells across the doubled layers as sure as clean ones. Each cell's smoothing is
    now in proportion to its mean's error across the blade (sheet_cells.mean_errors; at 2e-3 for
    the typical cell): pot1_1 46.1 / 39.8 and its edges folded back 0.33% -> 0.12%, pot1_15 12.9
    / 17.6, the others 8.0-13.4, at a mean distance of 0.57%, none above 0.93%. (pot1_1's
    crumples swing with any setting, 39.8-69.5 inside, and its unrolled length 53.2 -> 58.5: its
    doubled layers make its flat blade uncertain.) A refit through the cube means' own sheet
    (FIRST = SMOOTHING, at 1e-4) left pot1_1 at 108 degrees; a stiffer start refitted four times
    (1e-2 down to 1e-4) gave much the same as one refit, at three times the cost
    (benchmarks/bench_bent.py --scan-table). With pot1_1's base at its stalk's end (its length
    51.9 there, not 57.3 to a flap of margin behind the stalk: scan_veins.HALF_STATIONS) it
    stood 1.00% off its scan, 0.93-1.09% over ten 97% resamples, at the noise of its doubled
    layers (a local quadric through each point's 48 nearest: 0.95%); at 1e-3 0.96% but its p99
    inside 75.4, the veins' heights from 32 points (extract.LIFT_NEIGHBOURS) 0.97% and 65.3,
    0.88-0.99% over the resamples, the eight 0.56% on average (0.58%), the others' p99 inside
    6.8-15.3 (/work/notes/base38/README.md).
    """
    progress.report(0.0, UNROLLING)
    # fitted in a frame of the points' own, then moved back: the cubes' grid and order, and so
    # the flat blade, are the same however the scan was turned or mirrored (plane.grid_frame)
    given = np.asarray(points, dtype=float)
    frame = grid_frame(given)
    points = (given - frame[0]) @ frame[1].T
    up = np.asarray(up, dtype=float) @ frame[1].T
    cells, cube, counts = cut(points, length)  # CELLS, fewer on a sparse scan (sheet_cells.py)
    cell = length / cells
    sums = np.zeros((len(counts), 3))
    np.add.at(sums, cube, points)
    means = sums / counts[:, None]
    if len(means) > VOLUME * cells**2:  # a volume of points, not a sheet
        return None
    flat = unroll(means, REACH * cell)
    if flat is None:
        return None
    progress.report(0.1, UNROLLING)
    centre = flat.mean(axis=0)
    axes = np.linalg.svd(flat - centre, full_matrices=False)[2]
    flat = (flat - centre) @ axes.T  # u along the longest spread
    smoothing = FIRST * length**2
    # the graph's paths zigzag, so its distances run a few percent long: the flat blade is
    # scaled to keep the sheet's area (its median area factor |S_u x S_v| made 1, by central
    # differences of the spline at the centres: a Sheet sampled for it cost as much as the last)
    spline = RBFInterpolator(flat, means, kernel="thin_plate_spline", smoothing=smoothing)
    h = STEP * float(np.ptp(flat, axis=0).max())
    du, dv = ((spline(flat + d) - spline(flat - d)) / (2 * h) for d in ([h, 0.0], [0.0, h]))
    stretch = float(np.sqrt(np.median(np.linalg.norm(np.cross(du, dv), axis=1))))
    with progress.share(0.2, 0.6):  # sampling each sheet: the rest of the time
        sheet = Sheet(flat * stretch, means, smoothing, up)
    with progress.share(0.6, 1.0):
        sheet = refit(sheet, points, flat[cube] * stretch, cell, SMOOTHING * length**2, frame)
    return sheet
