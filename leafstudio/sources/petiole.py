"""A photo's petiole, cut off its blade (photo.py, step 3).

A morphological opening by a disk of PETIOLE_RADIUS of the blade's inscribed radius removes thin
parts; of those, a stalk is long (PETIOLE_LENGTH disk radii), slender (STALK_ELONGATION) and of
even width (it fills STALK_FILL of its length times its widest width, where a tapering tip fills
about half, and its width a fifth in from either end is the same within STALK_EVEN, where a
spatulate blade's narrow base widens): teeth are short, tips taper. A second opening, by a disk
just wider than the petiole (PETIOLE_FIT), cuts it off where the blade widens.
"""

from __future__ import annotations

import numpy as np

from leafstudio.sources.leafends import mask_window, window

PETIOLE_RADIUS = 0.3  # the opening disk's radius, as a fraction of the inscribed radius
PETIOLE_LENGTH = 1.0  # a stalk is at least this many disk radii long,
STALK_ELONGATION = 4.0  # this many times longer than wide,
STALK_FILL = 0.65  # and fills more than this share of its length times its widest width,
STALK_EVEN = 0.88  # and is as wide near one end as near the other (_evenness), to this share
PETIOLE_FIT = 1.6  # the second opening's disk, in petiole half-widths


def _opened(leaf: np.ndarray, inside: np.ndarray, radius: float) -> np.ndarray:
    """The mask opened by a disk of `radius`, by distance transforms (a large disk's structuring
    element is slow): the points deeper than r, grown back by r."""
    from scipy.ndimage import distance_transform_edt

    core = inside > radius
    if not core.any():  # nothing deeper (a window of cut_petiole's): nothing grows back
        return np.zeros_like(leaf)
    return leaf & (distance_transform_edt(~core) <= radius)


def _stalk_shape(part: np.ndarray) -> tuple[float, float, float]:
    """Length, elongation (length over widest width) and fill (area over length times widest
    width: about 0.85 for a strip of even width, 0.5 for a tapering tip) of a mask's region."""
    from scipy.ndimage import distance_transform_edt
    from skimage.measure import regionprops

    (props,) = regionprops(part.astype(np.uint8))
    width = max(2 * float(distance_transform_edt(np.pad(part, 1)).max()), 1.0)
    length = props.axis_major_length
    return length, length / width, props.area / max(length * width, 1e-12)


def _evenness(part: np.ndarray, corner: tuple[int, int] = (0, 0)) -> float:
    """How even a region's width is along its long axis: the narrower over the wider of its
    widths a fifth of its length in from each end (0.97-1 for a drawn stalk, about 0.79 for
    the wedge of a spatulate blade's narrow base). `corner`: the (row, column) of the mask's
    first pixel in the photo (a window of it)."""
    rows, cols = np.nonzero(part)
    pts = np.column_stack([cols + corner[1], rows + corner[0]]).astype(float)
    if len(pts) < 10:
        return 0.0
    centre = pts.mean(axis=0)
    axis = np.linalg.eigh(np.cov((pts - centre).T))[1][:, -1]
    along = (pts - centre) @ axis
    edges = np.linspace(along.min(), along.max() + 1e-9, 6)
    counts = np.histogram(along, edges)[0]
    low, high = sorted(counts[[1, 3]])
    return float(low / high) if high else 0.0


def cut_petiole(leaf: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """The blade without the petiole, and where the petiole met it (column, row) or None.

    Two openings: a coarse one (PETIOLE_RADIUS of the inscribed radius) removes the thin parts;
    each long one's half-width w is read on its skeleton, and a second opening by a disk of
    PETIOLE_FIT w cuts it where the blade widens. What that cuts is a stalk if it is slender and
    of even width (_stalk_shape: STALK_ELONGATION, STALK_FILL); the most even one is the
    petiole.

    All on the leaf's box with a margin of background (2 pixels: the joint's dilation), each
    part's second opening on the part's box grown by the disk: the same pixels as on the whole
    photo (a distance transform, an opening, a skeleton or a dilation there sees no farther),
    in a fraction of the time."""
    box = mask_window(leaf, 2)
    blade, joint = _cut_petiole_in(leaf[box], (box[0].start, box[1].start))
    if joint is None:
        return leaf, None
    whole = np.zeros_like(leaf)
    whole[box] = blade
    return whole, joint


def _cut_petiole_in(
    leaf: np.ndarray, corner: tuple[int, int]
) -> tuple[np.ndarray, np.ndarray | None]:
    """cut_petiole on the leaf's box (background all round), whose first pixel is at (row,
    column) `corner` in the photo; the joint in the photo's pixels."""
    from scipy.ndimage import binary_dilation, distance_transform_edt
    from skimage.measure import label, regionprops
    from skimage.morphology import skeletonize

    inside = distance_transform_edt(leaf)
    radius = max(PETIOLE_RADIUS * float(inside.max()), 1.0)
    coarse = label(leaf & ~_opened(leaf, inside, radius), connectivity=2)
    petiole, best = None, STALK_FILL
    for part in regionprops(coarse):
        if part.axis_major_length < PETIOLE_LENGTH * radius:
            continue
        spine = skeletonize(np.pad(part.image, 1))[1:-1, 1:-1]  # the part's box, background round
        halfwidth = float(np.median(inside[part.slice][spine]))
        fine = max(PETIOLE_FIT * halfwidth, 1.5)
        at = window(part.bbox, int(np.ceil(fine)) + 1, leaf.shape)  # what the disk reaches
        region = coarse[at] == part.label
        thin = label(leaf[at] & ~_opened(leaf[at], inside[at], fine) & region, connectivity=2)
        if thin.max() == 0:
            continue
        tight = thin == np.argmax(np.bincount(thin.ravel())[1:]) + 1
        length, elongation, fill = _stalk_shape(tight)
        if (
            length >= PETIOLE_LENGTH * radius / 2
            and elongation >= STALK_ELONGATION
            and fill > best
            and _evenness(tight, (corner[0] + at[0].start, corner[1] + at[1].start)) >= STALK_EVEN
        ):
            petiole, best = np.zeros_like(leaf), fill
            petiole[at] = tight
    if petiole is None:
        return leaf, None
    blade = leaf & ~petiole
    pieces = label(blade, connectivity=2)  # the cut may leave crumbs: keep the blade
    if pieces.max() > 1:
        blade = pieces == np.argmax(np.bincount(pieces.ravel())[1:]) + 1
    joint = binary_dilation(petiole, iterations=2) & blade
    if not joint.any():
        return leaf, None
    rows, cols = np.nonzero(joint)
    rows, cols = rows + corner[0], cols + corner[1]
    return blade, np.array([cols.mean() + 0.5, rows.mean() + 0.5])
