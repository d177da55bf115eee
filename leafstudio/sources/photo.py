"""A leaf from a photo or a scan on a plain background: its outline, base and apex, and veins.

1. Segment (scikit-image): each pixel's colour distance from the background (the median colour
   of the image's border), smoothed, split by Otsu's threshold; an image with an alpha channel
   that varies uses its alpha instead. Keep the largest component, fill its holes.
2. Refuse bad photos with one clear message: no leaf (nothing stands out, or the background is
   not plain), several leaves (a second object at least SECOND_OBJECT of the largest's size), a
   leaf cut by the image border.
3. The petiole (petiole.py): a morphological opening removes thin parts; of those, a long,
   slender stalk of even width is the petiole, and a second opening cuts it off where the blade
   widens. Where it met the blade is the base. A petiole these miss (short beside a large
   blade, or running into a narrow base) is looked for along the blade's midline
   (leafends.find_stalk) and cut off square at its joint.
4. The outline: the zero contour of the (slightly smoothed) blade mask, at sub-pixel precision,
   resampled evenly.
5. Base and apex: the petiole's end when there is one (the apex is then the outline point
   farthest from it); otherwise the two ends of the blade's midline, its best mirror axis
   (leafends.py), of which the base is the one `base_end` names (left, right, top, bottom) or, by
   default, the one with a basal notch (cordate, sagittate), else the one the veins lean away
   from, else the wider one. When the photo shows a midrib (photo_midrib.ridge_midline) whose ends
   lie elsewhere than the mirror axis's (ENDS_AGREE), its ends are taken instead: a lopsided or
   unrolled blade's mirror axis can run across it. The traced midrib stops where its ridge does.
6. The leaf follows the forms' convention (docs/architecture.md): the base at the origin, the apex
   on +x at `length` (base to apex), z = 0. The affine map from those coordinates back to the
   photo's pixels is kept (in the project, "photo": {"pixel_from_world": ...}) so that `reconstruct
   --texture PHOTO` maps each pixel back where it was.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from leafstudio._shared.inputs import PHOTO_SUFFIXES, read_image
from leafstudio.errors import LeafError
from leafstudio.forms import grow_veins
from leafstudio.forms.veins import check_seed
from leafstudio.model import Leaf
from leafstudio.sources.files import save_leaf
from leafstudio.sources.leafends import (
    VeinField,
    base_end_index,
    climb_to_tip,
    find_stalk,
    mask_window,
    midline,
    sharpen_end,
)
from leafstudio.sources.leafphoto import BASE_ENDS, VEIN_CHOICES, LeafPhoto
from leafstudio.sources.petiole import cut_petiole
from leafstudio.sources.photo_midrib import along_midrib, ridge_midline
from leafstudio.sources.photo_veins import Ridges, find_ridges, lifted, smoothed, trace_veins

if TYPE_CHECKING:
    from leafstudio.sources.leafends import Midline, VeinField

SECOND_OBJECT = 0.25  # a second object this large (of the largest) means several leaves
SMALLEST_LEAF = 0.002  # of the image's pixels: less is no leaf
LARGEST_LEAF = 0.9  # of the image's pixels: more means no plain background
SMOOTHING = 1.0  # pixels: the colour distance is smoothed this much before the threshold
STALK_MARGIN = 1.5  # pixels: a petiole found along the midline is cut this much wider
ENDS_AGREE = 0.05  # the photo's midrib moves the outline's ends when farther than this (of length)


@dataclass(frozen=True)
class PhotoLeaf:
    """What `leaf_from_photo` found.

    Attributes
    ----------
    leaf : Leaf
        Boundary (and veins) in the forms' convention, z = 0 on the boundary.
    pixel_from_world : (2, 3) float array
        (column, row) = A @ (x, y, 1): from the leaf's coordinates to the photo's pixels.
    outline_px : (n, 2) float array
        The outline in the photo, (column, row), pixel centres at integer + 0.5.
    blade : (h, w) bool array
        The blade's pixels (petiole cut off).
    petiole : bool
        Whether a petiole was found and cut off.
    base_cue : str
        What told the base: "petiole", "given" (base_end), "notch", "veins" or "wider end"
        (leafends.base_end_index); the last is a guess.
    veins_from : str
        "photo" (traced in the photo: photo_veins.py), "grown" (forms.grow_veins: none
        visible, or asked for) or "none".
    length : float
        Base to apex, in the leaf's units.
    scale : str
        What set the length: "" (none: length 1), "given" (`length`), "pixel size"
        (`pixel_size`: a ruler), or "the photo's N DPI" (read_photo_leaf, photo_scale.py).
    """

    leaf: Leaf
    pixel_from_world: np.ndarray
    outline_px: np.ndarray
    blade: np.ndarray
    petiole: bool
    base_cue: str = "petiole"
    veins_from: str = "none"
    length: float = 1.0
    scale: str = ""


def foreground(image: np.ndarray) -> np.ndarray:
    """(h, w) bool: pixels that stand out from the background (see the module docstring)."""
    from scipy.ndimage import gaussian_filter
    from skimage.filters import threshold_otsu

    if image.shape[2] == 4:
        alpha = image[..., 3]
        if alpha.min() < 128 <= alpha.max():
            return alpha >= 128
    rgb = image[..., :3].astype(float)
    border = np.concatenate([rgb[0], rgb[-1], rgb[:, 0], rgb[:, -1]])
    background = np.median(border, axis=0)
    distance = gaussian_filter(np.linalg.norm(rgb - background, axis=2), SMOOTHING)
    if np.ptp(distance) < 10:  # under 4% of the colour range: nothing stands out
        raise LeafError("no leaf found: nothing stands out from the background")
    return distance > threshold_otsu(distance)


def _leaf_component(mask: np.ndarray) -> np.ndarray:
    """The largest component, holes filled; LeafError for no leaf, several, or one cut off."""
    from scipy.ndimage import binary_fill_holes
    from skimage.measure import label

    labels, count = label(mask, return_num=True, connectivity=2)
    if count == 0:
        raise LeafError("no leaf found: nothing stands out from the background")
    sizes = np.bincount(labels.ravel())[1:]
    order = np.argsort(sizes)[::-1]
    largest = sizes[order[0]]
    if largest < SMALLEST_LEAF * mask.size:
        raise LeafError("no leaf found: the largest object is a speck")
    if largest > LARGEST_LEAF * mask.size:
        raise LeafError("no leaf found: the background is not plain (it covers too little)")
    others = int(np.count_nonzero(sizes[order[1:]] >= SECOND_OBJECT * largest))
    if others:
        raise LeafError(
            f"several leaves: {others + 1} objects of similar size; photograph one leaf at a time"
        )
    leaf = labels == order[0] + 1
    # its holes lie in its box, and a ring of background round the box joins the rest of the
    # photo's: filled there, they are filled as in the whole photo (in a sixth of the time)
    box = mask_window(leaf, 1)
    leaf[box] = binary_fill_holes(leaf[box])
    if leaf[0].any() or leaf[-1].any() or leaf[:, 0].any() or leaf[:, -1].any():
        raise LeafError("the leaf is cut by the image border: leave a margin around it")
    return leaf


def _outline(blade: np.ndarray, points: int | None) -> np.ndarray:
    """(n, 2) evenly spaced (column, row) points on the blade's contour, counter-clockwise as
    seen with y up (rows run down)."""
    from scipy.ndimage import gaussian_filter
    from skimage.measure import find_contours

    field = gaussian_filter(np.pad(blade, 2).astype(float), 0.7)
    contours = find_contours(field, 0.5)
    ring = max(contours, key=len)[:, ::-1] - 2 + 0.5  # (column, row), pixel centres at k + 0.5
    if np.allclose(ring[0], ring[-1]):
        ring = ring[:-1]
    step = np.linalg.norm(np.diff(np.vstack([ring, ring[:1]]), axis=0), axis=1)
    along = np.concatenate([[0], np.cumsum(step)])
    n = points or int(np.clip(along[-1] / 2, 200, 2000))
    at = np.linspace(0, along[-1], n, endpoint=False)
    closed = np.vstack([ring, ring[:1]])
    out = np.column_stack([np.interp(at, along, closed[:, k]) for k in range(2)])
    x, y = out[:, 0], -out[:, 1]
    if 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) < 0:  # clockwise with y up
        out = out[::-1]
    return out


BASE_DIRECTIONS = {"left": (-1, 0), "right": (1, 0), "top": (0, -1), "bottom": (0, 1)}  # pixels


def _at_base_end(joint: np.ndarray | None, base_end: str, mask: np.ndarray) -> bool:
    """Whether a petiole's joint lies on the half of the leaf (a boolean mask) that `base_end`
    names (always, for "auto"): one at the other end is a drawn-out apex (acuminate), kept."""
    if joint is None or base_end == "auto":
        return True
    rows, cols = np.nonzero(mask)
    centre = np.array([cols.mean(), rows.mean()]) + 0.5
    return float((np.asarray(joint) - centre) @ np.array(BASE_DIRECTIONS[base_end], float)) > 0


def _cut_stalk(
    outline: np.ndarray, image: np.ndarray, blade: np.ndarray, base_end: str = "auto"
) -> tuple[np.ndarray, np.ndarray | None, VeinField, Midline]:
    """A petiole the openings missed, found along the blade's midline (leafends.find_stalk), cut
    off square at its joint: (blade, joint or None, veins, midline); the last two serve _ends
    when there is no petiole. One away from `base_end` is not cut (_at_base_end)."""
    from skimage.measure import label

    veins = VeinField(image, blade)
    line = midline(outline, veins)
    stalk = find_stalk(outline, line)
    if stalk is None or not _at_base_end(stalk.joint, base_end, blade):
        return blade, None, veins, line
    rows, cols = np.nonzero(blade)
    xy = np.column_stack([cols, rows]) + 0.5
    inward = (stalk.joint - stalk.tip) / np.linalg.norm(stalk.joint - stalk.tip)
    along = (xy - stalk.tip) @ inward
    across = (xy - stalk.tip) @ np.array([-inward[1], inward[0]])
    cut = (along <= np.linalg.norm(stalk.joint - stalk.tip)) & (
        np.abs(across) <= stalk.halfwidth + STALK_MARGIN
    )
    rest = blade.copy()
    rest[rows[cut], cols[cut]] = False
    pieces = label(rest, connectivity=2)
    if pieces.max() == 0:
        return blade, None, veins, line
    rest = pieces == np.argmax(np.bincount(pieces.ravel())[1:]) + 1
    return rest, stalk.joint, veins, line


def _photo_midline(
    ridges: Ridges | None, outline: np.ndarray, line: Midline
) -> tuple[Midline, tuple[Midline, np.ndarray] | None]:
    """The outline's midline, or the midrib the photo shows (photo_midrib.ridge_midline) when its
    ends lie elsewhere (farther than ENDS_AGREE of the length from the midline's); and what
    ridge_midline found (None if nothing)."""
    found = ridge_midline(ridges, outline)
    if found is None:
        return line, None
    ridge = found[0]
    ends, other = ridge.ends, line.ends
    gap = min(np.linalg.norm(ends - other, axis=1).max(),
              np.linalg.norm(ends - other[::-1], axis=1).max())  # fmt: skip
    return (line if gap <= ENDS_AGREE * max(line.length, ridge.length) else ridge), found


def _ends(
    outline: np.ndarray,
    base_end: str,
    joint: np.ndarray | None,
    veins: VeinField | None,
    line: Midline | None,
) -> tuple[np.ndarray, int, int, str]:
    """The outline (its pointed ends sharpened when no petiole shows the base), the indices of
    the base and apex on it, and what told the base (see the module docstring)."""
    if joint is not None:
        base = int(np.argmin(np.linalg.norm(outline - joint, axis=1)))
        apex = int(np.argmax(np.linalg.norm(outline - outline[base], axis=1)))
        return outline, base, apex, "petiole"
    if base_end == "auto":
        first, cue = base_end_index(outline, line, veins)
    else:
        direction = np.array(BASE_DIRECTIONS[base_end], float)
        first, cue = int(np.argmax(line.ends @ direction)), "given"
    ends = line.ends[[first, 1 - first]]  # base, apex
    tip = climb_to_tip(outline, int(np.argmin(np.linalg.norm(outline - ends[1], axis=1))), ends[0])
    ends[1] = outline[tip]
    inward = (ends[1] - ends[0]) / max(np.linalg.norm(ends[1] - ends[0]), 1e-12)
    for k, direction in ((0, inward), (1, -inward)):  # pointed ends put back where blur cut them
        at = int(np.argmin(np.linalg.norm(outline - ends[k], axis=1)))
        outline, at = sharpen_end(outline, at, direction)
        ends[k] = outline[at]
    base, apex = (int(np.argmin(np.linalg.norm(outline - end, axis=1))) for end in ends)
    return outline, base, apex, cue


def leaf_from_photo(
    image: np.ndarray,
    length: float | None = None,
    base_end: str = "auto",
    veins: str = "auto",
    venation: str = "pinnate",
    points: int | None = None,
    seed: int = 0,
    pixel_size: float | None = None,
) -> PhotoLeaf:
    """The leaf in an (h, w, 3 or 4) uint8 photo (see the module docstring).

    Parameters
    ----------
    length : float, optional
        Base to apex in the output's units; default 1.
    base_end : {"auto", "left", "right", "top", "bottom"}, default: "auto"
        Where the base is when no petiole shows it; a stalk found at the other end is a
        drawn-out apex, kept (_at_base_end).
    veins : {"auto", "trace", "grow", "none"}, default: "auto"
        "trace": the veins the photo shows (photo_veins.py: the midrib and the secondaries
        that stand out), or none if it shows none; "grow": veins grown inside the outline
        (leafstudio.forms.grow_veins); "auto": traced where the photo shows a midrib, else
        grown; "none": no veins. PhotoLeaf.veins_from says which.
    points : int, optional
        Boundary points; default one per 2 pixels of outline, 200 to 2000.
    pixel_size : float, optional
        The length of one pixel in the output's units (the photo's own scale: its DPI, a
        ruler); used when `length` is not given, so the leaf comes out at its real size.
    """
    if base_end not in BASE_ENDS:
        raise LeafError(f"unknown base end {base_end!r}; use one of {', '.join(BASE_ENDS)}")
    if veins not in VEIN_CHOICES:
        raise LeafError(f"--veins must be one of {', '.join(VEIN_CHOICES)}, got {veins!r}")
    if veins in ("auto", "grow"):
        check_seed(seed)
    if length is not None and not (np.isfinite(length) and length > 0):
        raise LeafError(f"--length must be a number above 0, got {length}")
    if pixel_size is not None and not (np.isfinite(pixel_size) and pixel_size > 0):
        raise LeafError(f"a pixel's size must be a number above 0, got {pixel_size}")
    if image.ndim != 3 or min(image.shape[:2]) < 16:
        raise LeafError("the image is too small (under 16 pixels a side)")
    leaf_mask = _leaf_component(foreground(image))
    blade, joint = cut_petiole(leaf_mask)
    if not _at_base_end(joint, base_end, leaf_mask):  # the given base end wins over a stalk
        blade, joint = leaf_mask, None
    outline = _outline(blade, points)
    field = line = ridge = ridges = None
    if joint is None:
        blade, joint, field, line = _cut_stalk(outline, image, blade, base_end)
        if joint is not None:
            outline = _outline(blade, points)
        elif veins in ("auto", "trace"):
            ridges = find_ridges(image, blade)  # once: the veins below use it too
            line, ridge = _photo_midline(ridges, outline, line)
    outline, base, apex, cue = _ends(outline, base_end, joint, field, line)
    start = np.array([outline[base, 0], -outline[base, 1]])  # y up
    axis = np.array([outline[apex, 0], -outline[apex, 1]]) - start
    pixels_long = float(np.linalg.norm(axis))
    if pixels_long < 8:
        raise LeafError("no leaf found: the object is too small")
    if length is not None:
        length, how = float(length), "given"
    elif pixel_size is not None:
        length, how = float(pixel_size) * pixels_long, "pixel size"
    else:
        length, how = 1.0, ""
    scale = length / pixels_long
    c, s = axis / pixels_long
    rotate = np.array([[c, s], [-s, c]])  # turns the base-to-apex axis onto +x
    q = np.column_stack([outline[:, 0], -outline[:, 1]]) - start
    xy = scale * q @ rotate.T
    # back: q = rotate.T @ xy / scale; (column, row) = (q_x + start_x, -(q_y + start_y))
    back = rotate.T / scale
    pixel_from_world = np.array(
        [[back[0, 0], back[0, 1], start[0]], [-back[1, 0], -back[1, 1], -start[1]]]
    )
    boundary = np.column_stack([xy, np.zeros(len(xy))])

    def to_world(px: np.ndarray) -> np.ndarray:
        return scale * (np.column_stack([px[:, 0], -px[:, 1]]) - start) @ rotate.T

    found: list[np.ndarray] = []
    veins_from = "none"
    if veins in ("auto", "trace"):
        if ridges is None:  # a petiole told the ends: the visible midrib is looked for now
            ridges = find_ridges(image, blade)
            ridge = ridge_midline(ridges, outline)
        path = along_midrib(ridge, ridges, outline[base], outline[apex])
        traced = trace_veins(ridges, outline[base], outline[apex], path)
        if traced.seen:
            found = [lifted(to_world(smoothed(v)), xy) for v in traced.veins]
            veins_from = "photo"
    if veins == "grow" or (veins == "auto" and not found):
        found = grow_veins(boundary, venation, base=np.zeros(2), seed=seed, apex=xy[apex])
        veins_from = "grown"
    return PhotoLeaf(
        leaf=Leaf(boundary=boundary, veins=found),
        pixel_from_world=pixel_from_world,
        outline_px=outline,
        blade=blade,
        petiole=joint is not None,
        base_cue=cue,
        veins_from=veins_from,
        length=length,
        scale=how,
    )


def save_photo_leaf(found: PhotoLeaf, image_path: str | Path, path: str | Path) -> None:
    """Write the leaf; a .leaf.json also keeps the photo (its path relative to the project) and
    its pixel map, which the texture of `reconstruct --texture PHOTO` and the app need
    (sources/leafphoto.py)."""
    if not str(path).lower().endswith(".json"):
        save_leaf(found.leaf, path)
        return
    save_leaf(found.leaf, path, photo=LeafPhoto.of(found, image_path).entry(path))


def is_photo(path: str | Path) -> bool:
    """Whether a path names an image the photo reader takes (by its suffix)."""
    return Path(path).suffix.lower() in PHOTO_SUFFIXES


def read_photo_leaf(path: str | Path, **options) -> PhotoLeaf:
    """leaf_from_photo on an image file; LeafError naming the file (the app opens photos so).
    Without a length or a pixel size, the file's own resolution, when it records one that is a
    scale (photo_scale.py), makes the leaf its real size in millimetres (`scale` says so)."""
    from dataclasses import replace

    from leafstudio.sources.photo_scale import dpi_pixel_size

    image = read_image(path)
    dpi = None
    if options.get("length") is None and options.get("pixel_size") is None:
        dpi = dpi_pixel_size(path)
        if dpi is not None:
            options["pixel_size"] = dpi[0]
    try:
        found = leaf_from_photo(image, **options)
    except LeafError as exc:
        raise LeafError(exc.problem, str(path)) from None
    return found if dpi is None else replace(found, scale=f"the photo's {dpi[1]:g} DPI")
