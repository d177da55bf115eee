"""The nearest set pixel of a mask: an exact Euclidean feature transform, compiled.

The textures' edge padding (assets/texture.bleed: every texel outside the leaf takes the colour
of the nearest texel on it) needs, for every pixel of a 1024² image, the index of the nearest
pixel of a mask. scipy's `distance_transform_edt(..., return_indices=True)` spent 40-80 ms on it,
half of the app's texture and the largest piece of its GUI tests' texture CPU (py-spy: 21 s of
their 312 s); this kernel, the same transform for 2D booleans only, takes a fifth of that (the same
pixels: below), and holds no GIL.

Felzenszwalb and Huttenlocher's two passes ("Distance transforms of sampled functions", 2012):
down each column the nearest set pixel in that column, then along each row the lower envelope
of the parabolas those columns' distances make. In that order and breaking ties as it does, it
picks the very pixels scipy picks (compared on random masks and textures).
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import distance_transform_edt

from leafstudio.core.jit import njit
from leafstudio.core.kernels import MEASURE, compiled

_NONE = np.int64(-1)


def nearest_set_pixel(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The row and the column ((h, w) int64 each) of the set pixel of the 2D boolean `mask`
    nearest each pixel (Euclidean distance), as scipy's `return_indices` gives them; -1
    everywhere when none is set.

    The kernel is compiled with measuring's (core/kernels.MEASURING); until they are (a first
    run, before anything was measured) scipy's transform answers, with the same pixels, rather
    than a texture waiting seconds for a compile."""
    mask = np.ascontiguousarray(mask, dtype=np.bool_)
    if mask.ndim != 2:
        raise ValueError(f"a 2D mask is needed, not {mask.ndim}D")
    if mask.size == 0 or not mask.any():
        return np.full(mask.shape, _NONE), np.full(mask.shape, _NONE)
    if not compiled(MEASURE):
        rows, cols = distance_transform_edt(~mask, return_distances=False, return_indices=True)
        return rows.astype(np.int64), cols.astype(np.int64)
    return _feature_transform(mask)


@njit(cache=True, nogil=True)
def _feature_transform(mask):
    h, w = mask.shape
    far = h * h + w * w + 1  # more than any squared distance in the image
    # down each column: the row of the nearest set pixel in it (-1: none); row by row, all
    # columns at once, so that memory is read in order
    row = np.empty((h, w), np.int64)
    last = np.full(w, -1)
    for y in range(h):
        for x in range(w):
            if mask[y, x]:
                last[x] = y
            row[y, x] = last[x]
    last[:] = -1
    for y in range(h - 1, -1, -1):
        for x in range(w):
            if mask[y, x]:
                last[x] = y
            above = row[y, x]
            if last[x] >= 0 and (above < 0 or last[x] - y < y - above):  # a tie: the row above
                row[y, x] = last[x]
    # along each row: the column whose nearest pixel (from the first pass) is nearest overall,
    # from the lower envelope of the parabolas (x - q)^2 + height[q]
    out_rows = np.empty((h, w), np.int64)
    out_columns = np.empty((h, w), np.int64)
    columns = np.empty(w, np.int64)  # the columns on the envelope
    starts = np.empty(w + 1)  # where each one's stretch of the envelope starts
    height = np.empty(w, np.int64)  # each column's squared distance down it
    for y in range(h):
        for x in range(w):
            r = row[y, x]
            height[x] = far if r < 0 else (r - y) * (r - y)
        k = -1
        for q in range(w):
            if height[q] >= far:
                continue
            lift = height[q] + q * q
            cross = -np.inf
            while k >= 0:
                p = columns[k]
                cross = (lift - (height[p] + p * p)) / (2.0 * (q - p))
                if cross <= starts[k]:
                    k -= 1
                else:
                    break
            k += 1
            columns[k] = q
            starts[k] = -np.inf if k == 0 else cross
            starts[k + 1] = np.inf
        j = 0
        for x in range(w):
            while starts[j + 1] < x:
                j += 1
            q = columns[j]
            out_rows[y, x] = row[y, q]
            out_columns[y, x] = q
    return out_rows, out_columns
