"""A form's relief: the smooth dome its veins stand on (veins.py, step 3).

A vein's height used to be HEIGHT_RATIO times its distance to the margin, as the demos' midribs
are: a roof, 14° each side of the midrib, with a crease along it (and along every branch of the
blade's medial axis, into each lobe). A surface that passes within 1e-3 of the length of every
vein point had to follow that crease: the 99th-percentile interior dihedral of a reconstructed
ovate form was 4.6° where the paper's smooth surface, 6.5e-3 off the midrib, had 3.4°.

The dome is the blade as a membrane under an even pressure: ψ with −Δψ = 1 inside and ψ = 0
on the margin (Prandtl's stress function). It is smooth inside whatever the outline and has no
slope where it is highest; on an ellipse ψ is the paraboloid 1 − x²/a² − y²/b² (scaled). With
s = ψ / max ψ the heights are

    h = ratio · R · s (1 + s) / 2,

R the largest distance to the margin, so the highest point stands where and as high as the
roof's; across a strip of half-width w, s = 1 − (v/w)² and h meets the margin at the roof's
slope, ratio (ψ alone, h = ratio R s, twice as steep: a hastate form's narrow veinless lobes
then creased, 99th-percentile margin dihedral 11.6° against the roof's 6.7°; now 4.0°, and
1.3° with the lobes' notches flattened, below).

ψ is solved on a regular grid of about NODES nodes over the blade's bounding box: the
five-point Laplacian, with Shortley-Weller's shorter arms where the margin cuts a grid line
(second order without a mesh of the margin), solved as a banded system; then the grid is
carried EXTENDED nodes past the margin by linear extrapolation and read back with cubic
B-splines (scipy.ndimage), smooth everywhere inside. A few milliseconds: the first dome, P1
elements on a Triangle mesh read back with Clough-Tocher, made a form 10 times slower to build.

At a sinus's notch (cordate, reniform, sagittate, hastate), where the midrib starts, ψ rises
as about the square root of the distance: steeper than a smooth surface through the margin
follows, and the vein correction bent into a bump there. So the dome is multiplied by
1 − exp(−|x − base|² / c²): flat at the base, unchanged a few c away. A base is a sinus when
the blade fills more than SINUS of a small circle around it (the outline turns inward there:
cordate 280°, reniform 264°, sagittate 326°; a round or truncate base about 180°); there c is
SINUS_CALM, wide enough that the correction need not bend the surface down into the notch
(bench_bent --veins, surface through the veins: cordate 99th-percentile margin dihedral
2.01° with c = 0.15, 1.36° with 0.27; reniform inside 1.79° -> 1.42°; sagittate margin
2.14° -> 1.55°; at 0.3 sagittate's inside rose to 3.1°). Part of that is a lower dome: the
wider flattening lowers the veins' top (cordate 0.089 -> 0.080 of the length, reniform
0.125 -> 0.120, sagittate 0.049 -> 0.037); scaled back to its top, 0.27 still beats 0.15 on
cordate (margin 2.02° -> 1.50°, inside 1.99° -> 1.60°) but not on sagittate's inside
(2.93° -> 3.49°). At a truncate or cuneate base c is BASE_CALM: without it the corners
beside a truncate base creased (elliptic truncate's margin band through the veins 1.16° ->
2.30°, ovate truncate's 1.19° -> 1.82°). A rounded base (a smooth arc: the form's base term,
`round_base`) is not flattened: there ψ rises smoothly from the margin, and the flattening
was itself the bend a surface through the midrib had to follow (orbicular's midrib, flat for
0.04 of the length and then turning up, creased its inside 1.29° through the veins against
1.08° on the paper's surface). bench_bent --veins and every shape with each base, K 3, grid
128, through the veins / the paper's surface, p99 margin and inside: orbicular 1.09 / 1.18 and
1.29 / 1.08 -> 0.85 / 0.87 and 0.74 / 0.81; ovate 1.04 / 1.36 and 1.34 / 1.42 -> 1.00 / 1.32
and 1.17 / 1.29; obovate rounded inside 1.21 / 1.15 -> 1.07 / 1.05; spatulate rounded
2.18 / 2.30 -> 2.86 / 3.73 (the dome itself rougher at a narrow base, both surfaces still
under the paper's surface's); no other rounded base rougher than the paper's surface.

A notch between the blade and a lobe (hastate's two, `notches`) is a corner of the outline
turned inward, as a sinus's notch is, and ψ rises as steeply beside it: the side veins that
pass it stood high above what a smooth surface follows, the correction through them (core/
correct.py) spread a bump of 0.004 of the length into the narrow veinless lobe, and the lobe's
ridge creased (99th-percentile margin dihedral 3.98° through the veins, 3.66° on the paper's
surface). The dome is flattened within NOTCH_CALM of each such notch as well: hastate's margin
band 1.28° through the veins, 1.30° on the paper's surface, inside 1.67° and 1.69° (its veins
no longer the same: the paper's surface is smoother too). A notch nearer the blade's axis than
NOTCH_CALM (between the lobes of a lobed margin) is left as it is: flattened, the midrib's dome
went with it (a lobed ovate form's top 0.056 -> 0.012 of the length).

The dome's grid (NODES over the bounding box) is coarser than a drip tip or a tooth: there the
read-back carries ψ past the margin and a vein stood up to 4e-3 of the length above any surface
that meets the margin so close by (an acuminate apex: lanceolate's midrib 1.75e-3 of the length
off the mesh, cordate's 4.2e-3, hastate's 4.3e-3 at grid 128, K 3). A height is therefore never
more than ROOF_CAP times the roof's (the ratio times the distance to the margin): the dome itself
stays under 1.32 times the roof on a strip or a disc, so the cap leaves every gallery form's
default veins as they were and bites only in tips and teeth (84 variants with an acuminate or
retuse apex or a toothed or lobed margin: vein points beyond 1e-3 of the length 5 -> 0; surfaces
through the veins rougher than the paper's surface, 99th-percentile dihedral, 38 -> 27).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import shapely
from scipy.linalg import solve_banded
from scipy.ndimage import distance_transform_edt, gaussian_filter1d, map_coordinates, spline_filter
from shapely.geometry.polygon import orient

from leafstudio.forms.blade import Blade

BASE_CALM = 0.15  # the dome is flattened within about this of a truncate or cuneate base (see
# the module)
SINUS_CALM = 0.27  # ... and within this of a sinus's notch, where ψ rises as about the square
# root of the distance
NOTCH_CALM = 0.22  # ... and within this of a notch between the blade and a lobe (hastate's), see
# the module (hastate's margin band on the paper's surface / through the veins: 0.15, 1.58° /
# 1.59°; 0.27, 1.14° / 1.15°)
ROOF_CAP = 1.5  # a height is at most this times the roof's, ratio x distance to the margin (the
# dome reaches 1.32 times it at most on a strip or a disc, see the module)
NOTCH_SMOOTH = 0.05  # of the length: the outline is smoothed this much along itself (σ) before
# its notches are found, so that a toothed margin's teeth are none
NOTCH_CHORD = 0.1  # of the length: a notch's angle is between the chords this far along each way
NOTCH_STEP = 0.005  # of the length: the outline is resampled this evenly to find its notches
SINUS = 200.0  # degrees of a small circle around the base inside the blade: more is a sinus
AROUND = 0.03  # that circle's radius, of the blade's length
AROUND_POINTS = 720  # points on it
NODES = 1024  # grid nodes over the blade's bounding box, spread as its sides are long
FEWEST = 24  # nodes along either side at least (a grass blade's width)
EXTENDED = 3  # grid rows past the margin filled in for the cubic read-back (its reach is 2)
REFINE = 3  # rounds that refine the inradius around the best node (_inradius)
NEAREST = 1e-3  # of a grid step: an arm to the margin is at least this long
STEPS = ((1, 0), (-1, 0), (0, 1), (0, -1))  # the four neighbours, in grid index steps


def dome(
    blade: Blade, ratio: float, base: np.ndarray, round_base: bool = False
) -> Callable[[np.ndarray], np.ndarray]:
    """The dome over a blade of length about 1, its axis along x: (n, 2) points -> (n,) heights,
    `ratio` times the largest distance to the margin at its top and 0 on the margin, flattened
    around the midrib's `base` (unless `round_base`: a smooth arc, and no sinus) and the notches
    of lobes off the axis (see the module)."""
    poly = blade.poly
    x0, y0, x1, y1 = poly.bounds
    along = int(np.clip(np.sqrt(NODES * (x1 - x0) / (y1 - y0)), FEWEST, NODES // FEWEST))
    counts = np.array([along, max(NODES // along, FEWEST)])
    lower = np.array([x0, y0])
    step = (np.array([x1, y1]) - lower) / (counts - 1)
    pad = EXTENDED + 1
    index = np.stack(np.meshgrid(*(np.arange(-pad, c + pad) for c in counts), indexing="ij"), -1)
    nodes = lower + index * step
    inside = np.zeros(nodes.shape[:2], dtype=bool)  # the padding is outside the bounds
    core = nodes[pad:-pad, pad:-pad]
    inside[pad:-pad, pad:-pad] = shapely.contains_xy(poly, core[..., 0], core[..., 1])
    psi = np.zeros(inside.shape)
    if not inside.any():  # a sliver of a blade between the nodes: flat
        return lambda xy: np.zeros(len(np.atleast_2d(xy)))
    # numbered along the shorter side first: the membrane's system is banded that wide
    cells = np.argwhere(inside) if counts[1] <= counts[0] else np.argwhere(inside.T)[:, ::-1]
    ahead_in = [inside[cells[:, 0] + di, cells[:, 1] + dj] for di, dj in STEPS]
    ring = np.asarray(poly.exterior.coords)
    arms = _arms(ring, (nodes[:, 0, 0], nodes[0, :, 1]), cells, ahead_in)
    psi[cells[:, 0], cells[:, 1]] = _membrane(cells, arms, step, inside.shape)
    _extend(psi, inside, cells, arms)
    top = float(psi[inside].max())
    if top <= 0:
        return lambda xy: np.zeros(len(np.atleast_2d(xy)))
    radius = _inradius(blade, nodes, inside, step)
    sinus = base_angle(blade, base) > SINUS
    reach = SINUS_CALM if sinus else None if round_base else BASE_CALM
    lobes = [p for p in notches(blade) if abs(p[1]) > NOTCH_CALM]  # off the axis y = 0
    coefficients = spline_filter(psi / top, order=3, mode="nearest")

    def heights(xy: np.ndarray) -> np.ndarray:
        xy = np.atleast_2d(np.asarray(xy, dtype=float))[:, :2]
        at = ((xy - lower) / step + pad).T
        read = map_coordinates(coefficients, at, order=3, mode="nearest", prefilter=False)
        calm = np.ones(len(xy))
        if reach is not None:
            calm -= np.exp(-((xy - base) ** 2).sum(axis=1) / reach**2)
        for notch in lobes:
            calm *= 1 - np.exp(-((xy - notch) ** 2).sum(axis=1) / NOTCH_CALM**2)
        share = np.clip(read, 0.0, 1.0)
        height = ratio * radius * 0.5 * share * (1 + share) * calm
        return np.minimum(height, ROOF_CAP * ratio * blade.gap(xy))

    return heights


def base_angle(blade: Blade, base: np.ndarray) -> float:
    """The blade's angle at the midrib's `base`, in degrees: the share of a circle of radius
    AROUND around it that lies inside the blade (about 180 at a round or truncate base, more at
    a sinus, less at a cuneate one)."""
    turn = np.linspace(0.0, 2 * np.pi, AROUND_POINTS, endpoint=False)
    circle = AROUND * np.column_stack([np.cos(turn), np.sin(turn)])
    ring = np.asarray(base, dtype=float)[:2] + circle
    return 360.0 * float(shapely.contains_xy(blade.poly, ring[:, 0], ring[:, 1]).mean())


def notches(blade: Blade) -> np.ndarray:
    """(k, 2) the outline's notches at the scale of a lobe: where, on the outline resampled every
    NOTCH_STEP and smoothed by NOTCH_SMOOTH along itself (a toothed margin's teeth gone), the
    blade's angle between the chords NOTCH_CHORD back and ahead passes SINUS (a sinus's notch at
    the base, hastate's between the blade and each lobe, a lobed margin's between its lobes)."""
    ring = np.asarray(orient(blade.poly, 1.0).exterior.coords)  # counterclockwise
    along = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(ring, axis=0), axis=1))])
    count = max(int(np.ceil(along[-1] / NOTCH_STEP)), 8)
    spacing = along[-1] / count
    even = np.column_stack(
        [np.interp(np.arange(count) * spacing, along, ring[:, k]) for k in (0, 1)]
    )
    smooth = gaussian_filter1d(even, NOTCH_SMOOTH / spacing, axis=0, mode="wrap")
    reach = max(round(NOTCH_CHORD / spacing), 1)
    back = np.roll(smooth, reach, axis=0) - smooth
    ahead = np.roll(smooth, -reach, axis=0) - smooth
    turn = np.arctan2(back[:, 1], back[:, 0]) - np.arctan2(ahead[:, 1], ahead[:, 0])
    angle = np.degrees(np.mod(turn, 2 * np.pi))  # the blade's side, left of the way round
    peak = (angle > SINUS) & (angle >= np.roll(angle, 1)) & (angle > np.roll(angle, -1))
    return even[peak]  # on the outline itself


def _inradius(blade: Blade, nodes: np.ndarray, inside: np.ndarray, step: np.ndarray) -> float:
    """R, the largest distance from the margin inside the blade: from the nodes that may be
    farthest from it (the grid's own distance transform is within a cell's diagonal of the
    margin's distance; a k-d tree query from the middle of a round blade visits every margin
    point, so few are asked), then REFINE rounds of a 5 x 5 pattern around the best point
    found, each a third the size of the last (a node may miss the top by half a cell: an
    ellipse's axis between two rows of nodes, R 4% low)."""
    depth = distance_transform_edt(inside, sampling=step)
    deep = nodes[inside & (depth >= depth.max() - np.hypot(*step))]
    gaps = blade.gap(deep)
    best, radius = deep[np.argmax(gaps)], float(gaps.max())
    pattern = np.stack(np.meshgrid(*2 * [np.linspace(-1, 1, 5)]), -1).reshape(-1, 2)
    for round_ in range(REFINE):
        around = best + pattern * step / 3**round_
        around = around[blade.inside(around)]
        gaps = blade.gap(around)
        if len(gaps) and gaps.max() > radius:
            best, radius = around[np.argmax(gaps)], float(gaps.max())
    return radius


def _arms(
    ring: np.ndarray,
    lines: tuple[np.ndarray, np.ndarray],
    cells: np.ndarray,
    ahead_in: list[np.ndarray],
) -> np.ndarray:
    """(4, n) each inner node's arm towards each neighbour (STEPS), as a share of the grid
    step: 1 to an inner neighbour, else as far as the margin (`ring`, (m, 2), closed) crosses
    the grid line between them (`lines`: the grid's x and y coordinates; `ahead_in`: whether
    each neighbour is inner)."""
    arms = np.ones((len(STEPS), len(cells)))
    for axis in (0, 1):
        at, other = lines[1 - axis], lines[axis]  # the lines run along `axis`, at `at`
        crossing_line, where = _crossings(ring, axis, at)
        if len(where) == 0:
            continue
        spacing = other[1] - other[0]
        key = crossing_line * 2.0 + (where - other[0]) / (other[-1] - other[0])
        order = np.argsort(key)
        key, where = key[order], where[order]
        mine = other[cells[:, axis]]
        query = cells[:, 1 - axis] * 2.0 + (mine - other[0]) / (other[-1] - other[0])
        right = np.minimum(np.searchsorted(key, query, side="right"), len(key) - 1)
        for k, found in ((2 * axis, right), (2 * axis + 1, np.maximum(right - 1, 0))):
            cut = ~ahead_in[k]
            arm = np.abs(where[found[cut]] - mine[cut]) / spacing
            arms[k, cut] = np.clip(arm, NEAREST, 1.0)
    return arms


def _crossings(ring: np.ndarray, axis: int, at: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where the closed polygon `ring` crosses the grid lines that run along `axis` at the
    coordinates `at` (the other axis's, evenly spaced): (line index, coordinate along `axis`)
    of every crossing, each edge taken half-open so a vertex on a line counts once."""
    start, end = ring[:-1], ring[1:]
    spacing = at[1] - at[0]
    lo = np.minimum(start[:, 1 - axis], end[:, 1 - axis])
    hi = np.maximum(start[:, 1 - axis], end[:, 1 - axis])
    first = np.ceil((lo - at[0]) / spacing).astype(int)
    last = np.ceil((hi - at[0]) / spacing).astype(int) - 1  # half-open: [lo, hi)
    many = np.maximum(last - first + 1, 0)
    edge = np.repeat(np.arange(len(start)), many)
    line = np.repeat(first, many) + np.arange(many.sum()) - np.repeat(np.cumsum(many) - many, many)
    p, q = start[edge], end[edge]
    t = (at[line] - p[:, 1 - axis]) / (q[:, 1 - axis] - p[:, 1 - axis])
    return line, p[:, axis] + t * (q[:, axis] - p[:, axis])


def _membrane(
    cells: np.ndarray, arms: np.ndarray, step: np.ndarray, shape: tuple[int, ...]
) -> np.ndarray:
    """ψ at the inner nodes `cells`, numbered along the grid's shorter side so the system is
    banded: −Δψ = 1, ψ = 0 where the arms meet the margin (Shortley-Weller:
    ψ_xx ≈ 2/(a+b) ((ψ_+ − ψ)/b − (ψ − ψ_−)/a) with arms a, b; a = b = h is the five-point
    stencil)."""
    n = len(cells)
    number = -np.ones(shape, dtype=int)
    number[cells[:, 0], cells[:, 1]] = np.arange(n)
    rows, cols, values = [np.arange(n)], [np.arange(n)], []
    diagonal = np.zeros(n)
    for axis in (0, 1):
        for k in (2 * axis, 2 * axis + 1):
            near, far = arms[k] * step[axis], arms[k ^ 1] * step[axis]
            weight = 2 / (near * (near + far))
            diagonal += weight
            ahead = cells + STEPS[k]
            neighbour = number[ahead[:, 0], ahead[:, 1]]
            linked = neighbour >= 0
            rows.append(np.flatnonzero(linked))
            cols.append(neighbour[linked])
            values.append(-weight[linked])
    values.insert(0, diagonal)
    row, col = np.concatenate(rows), np.concatenate(cols)
    width = int(np.abs(row - col).max())
    band = np.zeros((2 * width + 1, n))
    band[width + row - col, col] = np.concatenate(values)
    return solve_banded((width, width), band, np.ones(n), check_finite=False)


def _extend(psi: np.ndarray, inside: np.ndarray, cells: np.ndarray, arms: np.ndarray) -> None:
    """Fills EXTENDED rows of nodes past the margin in place: the first by the line through
    ψ on an inner node and 0 where its arm meets the margin, the next ones linearly from the
    two nodes before them along each grid line (averaged over the lines that reach them)."""
    total, count = np.zeros(psi.shape), np.zeros(psi.shape)
    for k, move in enumerate(STEPS):
        cut = arms[k] < 1
        ahead = cells[cut] + move
        value = psi[cells[cut, 0], cells[cut, 1]] * (1 - 1 / arms[k, cut])
        np.add.at(total, (ahead[:, 0], ahead[:, 1]), value)
        np.add.at(count, (ahead[:, 0], ahead[:, 1]), 1)
    known = inside.copy()
    for _ in range(EXTENDED):
        new = (count > 0) & ~known
        psi[new] = total[new] / count[new]
        known |= new
        total[:], count[:] = 0.0, 0.0
        for axis in (0, 1):
            k, p, t = (psi, known, total) if axis == 0 else (psi.T, known.T, total.T)
            c = count if axis == 0 else count.T
            reach = p[1:-1] & p[:-2]  # two known nodes before, going up the axis
            t[2:] += np.where(reach, 2 * k[1:-1] - k[:-2], 0.0)
            c[2:] += reach
            reach = p[1:-1] & p[2:]  # and going down
            t[:-2] += np.where(reach, 2 * k[1:-1] - k[2:], 0.0)
            c[:-2] += reach
    psi[~known] = psi[known].min()
