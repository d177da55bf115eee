"""The veins a photo shows: traced, not invented.

1. Ridges: scikit-image's Sato filter (the Hessian's eigenvalues, several widths) on the grey
   levels of the blade, for light veins and for dark ones; the stronger kind is kept. The
   outline's own edge is left out: the grey levels beyond EDGE pixels in from it are the
   blade's own carried out, so a vein is seen up to the margin and the margin is not one. It
   is run once per photo (find_ridges) and its Ridges shared by the steps below and by
   photo_midrib.py: it is most of a photo's time.
2. The midrib: the ridge the photo shows running down the blade (photo_midrib.along_midrib),
   carried on towards the base and the apex as far as the ridges go, so it stops where the
   visible midrib stops; without one, the cheapest path from the base to the apex where a pixel
   costs the inverse of its ridge strength (skimage.graph.route_through_array), trimmed where
   it runs off the ridges. It is taken as seen when the ridge along it is clearly stronger
   than the blade's typical pixel (MIDRIB_CLEAR); a blade without visible veins has no such
   path and the veins are grown instead (photo.py).
3. Secondaries: the strong ridges (hysteresis between RIDGE_LOW and RIDGE_HIGH) away from the
   midrib, thinned to one-pixel skeletons; each piece longer than MIN_VEIN of the blade's
   length is one vein, its longest path, from the end nearer the midrib (joined to the midrib
   when it stops short of it by less than JOIN of the length).

All in pixels, (column, row) as the outline; photo.py maps them to the leaf's coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

RIDGE_WIDTHS = (1.0, 2.0, 3.0)  # Sato sigmas, in pixels, for a blade box LENGTH_PIXELS across
LENGTH_PIXELS = 500.0  # the widths scale with the blade box's diagonal beyond this
MARGIN_SKIP = 3.0  # ridge widths: the gaps a path crosses, the margin band it may run through
EDGE = 3.0  # pixels in from the outline (its blur) where ridges are not looked for
MIDRIB_CLEAR = 3.0  # the midrib's median ridge strength over the blade's median, at least
RIDGE_LOW, RIDGE_HIGH = 0.2, 0.4  # hysteresis, as shares of the blade's strongest ridges
STRONGEST = 99.5  # percentile of the blade's ridge strength taken as 1
MIN_CONTRAST = 0.01  # that percentile's Sato response (grey levels 0-1) below which none is seen
MIN_VEIN = 0.06  # a secondary is at least this share of the blade's length
JOIN = 0.05  # a secondary stopping this share of the length short of the midrib is joined to it
MIDRIB_BAND = 2.5  # ridge widths either side of the midrib that belong to it


@dataclass(frozen=True)
class TracedVeins:
    """Veins seen in a photo, in (column, row) pixels: the midrib from base to apex first."""

    veins: list[np.ndarray] = field(default_factory=list)
    midrib_strength: float = 0.0  # the midrib's median ridge over the blade's median

    @property
    def seen(self) -> bool:
        """Whether the photo shows a midrib (else nothing here is to be trusted)."""
        return bool(self.veins) and self.midrib_strength >= MIDRIB_CLEAR


def ridge_strength(image: np.ndarray, blade: np.ndarray, widths: np.ndarray) -> np.ndarray:
    """(h, w) ridge strength in [0, 1] on the blade's inner pixels, 0 elsewhere.

    The outline's own edge would read as a ridge: the grey levels beyond EDGE pixels in from it
    are replaced by the blade's own, carried out smoothly (a normalised convolution over twice
    the widest width), so a vein is seen up to the margin and the margin is not one."""
    from scipy.ndimage import distance_transform_edt, gaussian_filter

    grey = image[..., :3].astype(float) @ np.array([0.299, 0.587, 0.114]) / 255
    inner = distance_transform_edt(blade) > EDGE
    if inner.sum() < 16:
        return np.zeros(blade.shape)
    reach = 2.0 * float(widths.max())
    weight = gaussian_filter(inner.astype(float), reach)
    carried = gaussian_filter(np.where(inner, grey, 0.0), reach) / np.maximum(weight, 1e-12)
    carried = np.where(weight > 1e-3, carried, float(np.median(grey[inner])))
    grey = np.where(inner, grey, carried)
    best, best_level = None, -1.0
    for response in _sato_light_and_dark(grey, widths):
        response[~inner] = 0.0
        level = float(np.percentile(response[inner], STRONGEST))
        if level > best_level:
            best, best_level = response, level
    assert best is not None
    if best_level < MIN_CONTRAST:  # an even blade: what stands out is sensor noise
        return np.zeros(blade.shape)
    return np.clip(best / best_level, 0.0, 1.0)


def _sato_light_and_dark(grey: np.ndarray, widths: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """scikit-image's Sato filter for light ridges and for dark ones (`sato(grey, widths,
    black_ridges=False)`, then True, mode "reflect"), equal to the last bit, from one Hessian
    per width instead of two: in 2D, sato keeps sigma² max(λ1, 0) of the larger eigenvalue λ1
    of the (dark-ridge) image's Hessian, and the negated image's Hessian is the negated one
    (the filters are linear, rounding symmetric), whose larger eigenvalue is -λ2. The Hessians
    are most of a photo's reading time."""
    light, dark = np.zeros_like(grey), np.zeros_like(grey)
    for sigma in widths:
        larger, smaller = eigenvalues(*hessian(grey, float(sigma)))
        dark = np.maximum(dark, sigma**2 * np.maximum(larger, 0))
        light = np.maximum(light, sigma**2 * np.maximum(-smaller, 0))
    return light, dark


def hessian(grey: np.ndarray, sigma: float) -> list[np.ndarray]:
    """[Hrr, Hrc, Hcc] of an (h, w) float image: scikit-image's `hessian_matrix(grey, sigma,
    mode="reflect", use_gaussian_derivatives=True)` to the last bit, in half the time at
    sigma <= 1. There it widens its Gaussians to 100 of their sigmas (sigma / sqrt 2 each:
    71 pixels either side), to keep aliasing off the edges, but the kernels' taps past 27
    pixels are exactly 0 in floating point: its same two first-derivative passes are run here
    with those taps left out (adding 0 products changes no sum)."""
    from scipy.ndimage import correlate1d, gaussian_filter1d

    truncate = 8 if sigma > 1 else 100
    scaled = 1 / np.sqrt(2) * sigma  # as scikit-image scales it (1 / math.sqrt(2) * sigma)
    radius = int(truncate * scaled + 0.5)
    impulse = np.zeros(2 * radius + 1)
    impulse[radius] = 1.0
    weights = []  # gaussian_filter1d's correlation weights, of order 0 and 1, exactly
    for order in (0, 1):
        w = gaussian_filter1d(impulse, scaled, order=order, mode="constant", truncate=truncate)
        w = w[::-1]
        nonzero = np.flatnonzero(w)
        cut = min(nonzero[0], len(w) - 1 - nonzero[-1])
        weights.append(w[cut : len(w) - cut])

    def derivative(image: np.ndarray, axis: int) -> np.ndarray:
        """gaussian_filter(image, scaled, order 1 along `axis`, 0 along the other)."""
        row_order, col_order = (1, 0) if axis == 0 else (0, 1)
        along_rows = correlate1d(image, weights[row_order], axis=0, mode="reflect")
        return correlate1d(along_rows, weights[col_order], axis=1, mode="reflect")

    rows, cols = derivative(grey, 0), derivative(grey, 1)
    return [derivative(rows, 0), derivative(rows, 1), derivative(cols, 1)]


def eigenvalues(m00: np.ndarray, m01: np.ndarray, m11: np.ndarray) -> np.ndarray:
    """(2, h, w) the larger and the smaller eigenvalue of the symmetric 2x2 matrices [[m00, m01],
    [m01, m11]] at each pixel: scikit-image's hessian_matrix_eigvals to the last bit (the same
    formula), without importing skimage.feature, which imports scipy.stats (0.6 s of CPU on
    every photo read by a fresh process: the command line's, a batch worker's)."""
    eigs = np.empty((2, *m00.shape), m00.dtype)
    eigs[:] = (m00 + m11) / 2
    half_gap = np.sqrt(m01**2 + ((m00 - m11) / 2) ** 2)
    eigs[0] += half_gap
    eigs[1] -= half_gap
    return eigs


@dataclass(frozen=True)
class Ridges:
    """The ridge filter run once on a photo's blade, shared by the midrib's ends (ridge_midline)
    and the veins (trace_veins): the filter is most of a photo's reading time.

    Attributes
    ----------
    strength : (h, w) float array
        ridge_strength on the blade's box.
    blade : (h, w) bool array
        The blade's pixels in its box.
    corner : (2,) float array
        The box's first pixel in the photo, (column, row).
    widths : (k,) float array
        The filter's widths in pixels (RIDGE_WIDTHS, scaled with the blade box's diagonal).
    """

    strength: np.ndarray
    blade: np.ndarray
    corner: np.ndarray
    widths: np.ndarray

    @property
    def any(self) -> bool:
        """Whether the blade shows any ridge."""
        return bool(np.any(self.strength > 0))

    @cached_property
    def depth(self) -> np.ndarray:
        """(h, w) each pixel's distance in pixels from the nearest one off the blade, made once
        (the midrib's seeds and both its carried ends use it)."""
        from scipy.ndimage import distance_transform_edt

        return distance_transform_edt(self.blade)


def find_ridges(image: np.ndarray, blade: np.ndarray) -> Ridges | None:
    """The ridges of an (h, w, 3 or 4) uint8 photo on its (h, w) bool blade, on the blade's box
    alone; None when the blade is empty."""
    rows, cols = np.nonzero(blade)
    if not len(rows):
        return None
    (r0, c0), (r1, c1) = (rows.min(), cols.min()), (rows.max() + 1, cols.max() + 1)
    box = blade[r0:r1, c0:c1]
    size = float(np.hypot(*box.shape))  # the box's diagonal: about the length, or more
    widths = np.asarray(RIDGE_WIDTHS) * max(1.0, size / LENGTH_PIXELS)
    strength = ridge_strength(image[r0:r1, c0:c1], box, widths)
    return Ridges(strength, box, np.array([c0, r0], dtype=float), widths)


def trace_veins(
    ridges: Ridges | None,
    base: np.ndarray,
    apex: np.ndarray,
    ridge: np.ndarray | None = None,
) -> TracedVeins:
    """The veins the photo shows (see the module docstring).

    Parameters
    ----------
    ridges : Ridges or None
        find_ridges on the photo and its blade (petiole cut off).
    base, apex : (2,) float arrays
        The midrib's ends, (column, row).
    ridge : (n, 2) float array, optional
        The midrib's visible ridge, base end first (along_midrib): the midrib is that ridge,
        carried on towards the base and the apex as far as the ridges go. Without it, the
        cheapest base-to-apex path, trimmed where it runs off the ridges.

    Returns
    -------
    TracedVeins
    """
    if ridges is None or not ridges.any:
        return TracedVeins()
    strength, blade, corner, widths = ridges.strength, ridges.blade, ridges.corner, ridges.widths
    base, apex = np.asarray(base) - corner, np.asarray(apex) - corner
    length = float(np.linalg.norm(apex - base))
    inside = strength[blade]
    if ridge is None:
        midrib = cheapest_path(strength, blade, base, apex)
        along = strength[midrib[:, 1].astype(int), midrib[:, 0].astype(int)]
        band = 2 * MARGIN_SKIP * float(widths.max())
        midrib, along = _trimmed(midrib, along, strength > 0, band)
    else:
        ridge = np.asarray(ridge) - corner
        gap = float(widths.max())  # a ridge fading at its end, not a gap to the margin
        ends = [_carried(cheapest_path(strength, blade, ridge[k], end)[1:], ridges, gap)
                for k, end in ((0, base), (-1, apex))]  # fmt: skip
        midrib = np.vstack([ends[0][::-1], ridge, ends[1]])
        along = strength[midrib[:, 1].astype(int), midrib[:, 0].astype(int)]
    core = along[len(along) // 10 : max(len(along) - len(along) // 10, 1)]
    typical = float(np.median(inside[inside > 0]))
    clear = float(np.median(core)) / max(typical, 1e-12)
    veins = [midrib, *_secondaries(strength, midrib, widths, length)]
    return TracedVeins(veins=[v + corner for v in veins], midrib_strength=clear)


def _carried(piece: np.ndarray, ridges: Ridges, gap: float) -> np.ndarray:
    """The start of a path (m, 2) out from a ridge's end, as far as the ridge goes on: each
    point on a ridge or in the EDGE band reached from one, across gaps up to `gap` pixels."""
    if not len(piece):
        return piece
    rows, cols = piece[:, 1].astype(int), piece[:, 0].astype(int)
    edge = ridges.depth[rows, cols] <= EDGE
    good = (ridges.strength[rows, cols] >= RIDGE_LOW) | edge
    steps = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(piece, axis=0), axis=1))])
    keep, last = 0, -np.inf  # points kept; where the last good one lies along the piece
    for k in range(len(piece)):
        if steps[k] - (last if np.isfinite(last) else 0.0) > gap:
            break
        if good[k]:
            keep, last = k + 1, steps[k]
    return piece[:keep]


def cheapest_path(
    strength: np.ndarray, blade: np.ndarray, base: np.ndarray, apex: np.ndarray
) -> np.ndarray:
    """The cheapest base-to-apex path, (n, 2) pixel centres (column, row)."""
    from skimage.graph import route_through_array

    cost = 1.0 / (strength + 0.02)
    cost[~blade] = 1e3  # the path may touch the margin at its ends, never leave the blade
    h, w = blade.shape

    def pixel(at: np.ndarray) -> tuple[int, int]:
        col, row = np.clip(np.floor(at), 0, [w - 1, h - 1]).astype(int)
        return int(row), int(col)

    path, _ = route_through_array(cost, pixel(base), pixel(apex), geometric=True)
    rows, cols = np.asarray(path).T
    return np.column_stack([cols, rows]) + 0.5


def _trimmed(
    path: np.ndarray, along: np.ndarray, inner: np.ndarray, band: float
) -> tuple[np.ndarray, np.ndarray]:
    """The path without the ends where it runs off any ridge through the blade's inner part
    (the base and apex found from the outline need not be where the photo's midrib ends), or
    runs on longer than `band` pixels through the margin band (where no ridge is looked for:
    crossing it is kept, running along a narrow stalk's stub is not)."""
    rows, cols = path[:, 1].astype(int), path[:, 0].astype(int)
    off_ridge = inner[rows, cols] & (along < RIDGE_LOW)
    on_ridge = np.flatnonzero(along >= RIDGE_LOW)
    if not len(on_ridge):
        return path, along
    first, last = int(on_ridge[0]), int(on_ridge[-1])
    steps = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
    start = first if off_ridge[:first].any() or steps[first] > band else 0
    long_tail = steps[-1] - steps[last] > band
    end = last + 1 if off_ridge[last + 1 :].any() or long_tail else len(path)
    return path[start:end], along[start:end]


def _secondaries(
    strength: np.ndarray, midrib: np.ndarray, widths: np.ndarray, length: float
) -> list[np.ndarray]:
    """Long skeleton branches of the strong ridges off the midrib, each from its midrib end."""
    from scipy.ndimage import distance_transform_edt
    from scipy.spatial import cKDTree
    from skimage.filters import apply_hysteresis_threshold
    from skimage.measure import label
    from skimage.morphology import skeletonize

    near_midrib = np.ones(strength.shape, dtype=bool)
    near_midrib[midrib[:, 1].astype(int), midrib[:, 0].astype(int)] = False
    near_midrib = distance_transform_edt(near_midrib) <= MIDRIB_BAND * widths.max()
    ridges = apply_hysteresis_threshold(strength, RIDGE_LOW, RIDGE_HIGH) & ~near_midrib
    skeleton = skeletonize(ridges)
    pieces = label(skeleton, connectivity=2)
    midrib_tree = cKDTree(midrib)
    veins = []
    for piece in range(1, int(pieces.max()) + 1):
        rows, cols = np.nonzero(pieces == piece)
        if len(rows) < MIN_VEIN * length:
            continue
        path = _longest_path(np.column_stack([cols, rows]) + 0.5)
        gaps, nearest = midrib_tree.query(path[[0, -1]])
        if gaps[1] < gaps[0]:
            path, gaps, nearest = path[::-1], gaps[::-1], nearest[::-1]
        if float(np.linalg.norm(path[-1] - path[0])) < MIN_VEIN * length:
            continue  # a tight curl or a blob, not a vein
        if gaps[0] <= JOIN * length:
            path = np.vstack([midrib[nearest[0]], path])
        veins.append(path)
    return veins


def _longest_path(pixels: np.ndarray) -> np.ndarray:
    """The longest shortest path through 8-connected skeleton pixels (two sweeps of Dijkstra),
    in order."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra
    from scipy.spatial import cKDTree

    pairs = cKDTree(pixels).query_pairs(1.5, output_type="ndarray")
    steps = np.linalg.norm(pixels[pairs[:, 0]] - pixels[pairs[:, 1]], axis=1)
    n = len(pixels)
    graph = coo_matrix((steps, (pairs[:, 0], pairs[:, 1])), shape=(n, n)).tocsr()
    first = np.nan_to_num(dijkstra(graph, directed=False, indices=0), posinf=-1.0)
    start = int(np.argmax(first))
    dist, previous = dijkstra(graph, directed=False, indices=start, return_predecessors=True)
    end = int(np.argmax(np.nan_to_num(dist, posinf=-1.0)))
    order = [end]
    while order[-1] != start and previous[order[-1]] >= 0:
        order.append(int(previous[order[-1]]))
    return pixels[order[::-1]]


def smoothed(path: np.ndarray, spacing: float = 3.0) -> np.ndarray:
    """A traced pixel path without its staircase: resampled every `spacing` pixels along its
    length and smoothed over a few samples, its ends kept."""
    from scipy.ndimage import gaussian_filter1d

    steps = np.linalg.norm(np.diff(path, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(steps)])
    count = max(int(arc[-1] / spacing) + 1, 2)
    at = np.linspace(0.0, arc[-1], count)
    even = np.column_stack([np.interp(at, arc, path[:, i]) for i in range(2)])
    if len(even) < 5:
        return even
    smooth = gaussian_filter1d(even, 1.0, axis=0, mode="nearest")
    smooth[[0, -1]] = even[[0, -1]]
    return smooth


def lifted(vein_xy: np.ndarray, outline_xy: np.ndarray) -> np.ndarray:
    """A traced vein with the forms' relief: HEIGHT_RATIO times its distance to the margin."""
    import shapely

    from leafstudio.forms.veins import HEIGHT_RATIO

    margin = shapely.LinearRing(outline_xy)
    gap = shapely.distance(margin, shapely.points(vein_xy))
    return np.column_stack([vein_xy, HEIGHT_RATIO * gap])
