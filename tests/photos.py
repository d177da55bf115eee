"""Photos with known outlines: generated forms drawn on a plain background, and real scans rendered
from above (pyvista, shaded), both with noise and blur."""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import shapely

REALLEAVES = Path(__file__).resolve().parents[2] / "shared" / "realleaves"
BACKGROUND = (236, 234, 228)


def _finish(rgb: np.ndarray, noise: float, blur: float, seed: int) -> np.ndarray:
    """Blur and sensor noise on an (h, w, 3) float image; uint8 out."""
    from scipy.ndimage import gaussian_filter

    rgb = gaussian_filter(rgb, (blur, blur, 0)) if blur else rgb
    rgb = rgb + _noise(rgb.shape, noise, seed)
    return np.clip(np.rint(rgb), 0, 255).astype(np.uint8)


@functools.lru_cache(maxsize=8)
def _noise(shape: tuple[int, ...], sigma: float, seed: int) -> np.ndarray:
    """The sensor noise of a photo of `shape`: the same for every photo of that size and seed,
    drawn once (40 ms a photo; most are of one size and seed 0), read-only."""
    noise = np.random.default_rng(seed).normal(0, sigma, shape)
    noise.setflags(write=False)
    return noise


def photo_pixels(
    outline: np.ndarray,
    angle: float = 25.0,
    pixels_per_unit: float = 360.0,
    size: tuple[int, int] = (760, 620),
):
    """form_photo's map from the leaf's (x, y) to the photo's (column, row) pixels."""
    width, height = size
    a = np.deg2rad(angle)
    rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    centre_world = (outline[:, :2].min(axis=0) + outline[:, :2].max(axis=0)) / 2

    def to_pixels(xy: np.ndarray) -> np.ndarray:
        turned = (np.asarray(xy)[:, :2] - centre_world) @ rot.T * pixels_per_unit
        return np.column_stack([width / 2 + turned[:, 0], height / 2 - turned[:, 1]])

    return to_pixels


def form_photo(
    outline: np.ndarray,
    veins: list[np.ndarray] = (),
    angle: float = 25.0,
    pixels_per_unit: float = 360.0,
    size: tuple[int, int] = (760, 620),
    petiole: float = 0.0,
    noise: float = 6.0,
    blur: float = 1.0,
    seed: int = 0,
) -> tuple[np.ndarray, shapely.Polygon, np.ndarray]:
    """A photo of a leaf in the forms' convention (base at the origin, apex on +x): the image,
    the outline's polygon in (column, row) pixel coordinates (continuous, pixel centres at
    k + 0.5) and the base's pixel. `petiole` draws a stalk that long behind the base."""
    from PIL import Image, ImageDraw

    width, height = size
    to_pixels = photo_pixels(outline, angle, pixels_per_unit, size)

    ss = 4
    canvas = Image.new("RGB", (width * ss, height * ss), BACKGROUND)
    draw = ImageDraw.Draw(canvas)
    leaf_px = to_pixels(outline)
    draw.polygon([tuple(p * ss) for p in leaf_px], fill=(62, 118, 44))
    for vein in veins:
        draw.line([tuple(p * ss) for p in to_pixels(vein)], fill=(120, 160, 80), width=2 * ss)
    if petiole:
        stalk = to_pixels(np.array([[0.0, 0.0], [-petiole, -0.02]]))
        draw.line([tuple(p * ss) for p in stalk], fill=(80, 110, 50), width=int(0.02 * ss *
                  pixels_per_unit))  # fmt: skip
    rgb = np.asarray(canvas.resize((width, height), Image.Resampling.BOX), float)
    base = to_pixels(np.zeros((1, 2)))[0]
    return _finish(rgb, noise, blur, seed), shapely.Polygon(leaf_px), base


def scan_photo(
    path: Path, pixels: int = 640, noise: float = 5.0, blur: float = 1.0, seed: int = 0
) -> tuple[np.ndarray, shapely.Polygon, np.ndarray | None]:
    """A top view of a real scan's blade (outliers and petiole dropped), shaded by pyvista on a
    plain background, the blade's footprint in (column, row) pixel coordinates, and where the
    scan's petiole met the blade (its points within 3 spacings of the blade's), the base, in
    pixels (None when the scan shows no petiole)."""
    import pyvista as pv
    from scipy.spatial import Delaunay, cKDTree

    from leafstudio.core.plane import fit_frame
    from leafstudio.sources.extract import split_scan
    from leafstudio.sources.scan import read_scan

    points = read_scan(path)
    blade, stalk = split_scan(points)
    stalk_points, points = points[stalk], points[blade]
    frame = fit_frame(points, np.zeros((0, 3)))
    xy, z = frame.to_plane(points)
    tri = Delaunay(xy).simplices
    edges = np.linalg.norm(xy[tri] - xy[np.roll(tri, 1, axis=1)], axis=2).max(axis=1)
    spacing = np.median(np.linalg.norm(xy[tri[:, 0]] - xy[tri[:, 1]], axis=1))
    tri = tri[edges < 4 * spacing]  # bridges scanner stripes, not the margin's bays
    footprint = shapely.union_all(shapely.polygons(xy[tri]))
    if footprint.geom_type == "MultiPolygon":  # the blade is the largest piece
        footprint = max(footprint.geoms, key=lambda g: g.area)
    footprint = shapely.Polygon(footprint.exterior)
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    centre = (lo + hi) / 2
    ppu = 0.8 * pixels / float(np.max(hi - lo))
    mesh = pv.PolyData(
        np.column_stack([xy, z]), np.hstack([np.full((len(tri), 1), 3), tri]).ravel()
    )
    plotter = pv.Plotter(off_screen=True, window_size=(pixels, pixels))
    plotter.set_background([c / 255 for c in BACKGROUND])
    plotter.add_mesh(mesh, color=(0.27, 0.5, 0.2), smooth_shading=True)
    plotter.enable_parallel_projection()
    plotter.camera.focal_point = (*centre, 0.0)
    plotter.camera.position = (*centre, 10.0 * float(np.max(hi - lo)))
    plotter.camera.up = (0.0, 1.0, 0.0)
    plotter.camera.parallel_scale = pixels / 2 / ppu
    plotter.reset_camera_clipping_range()
    rgb = np.asarray(plotter.screenshot(return_img=True), float)[..., :3]
    plotter.close()

    def to_pixels(plane: np.ndarray) -> np.ndarray:
        return np.column_stack(
            [
                pixels / 2 + (plane[:, 0] - centre[0]) * ppu,
                pixels / 2 - (plane[:, 1] - centre[1]) * ppu,
            ]
        )

    base = None
    if len(stalk_points):
        near = frame.to_plane(stalk_points)[0]
        near = near[cKDTree(xy).query(near)[0] < 3 * spacing]
        base = to_pixels(near).mean(axis=0) if len(near) else None
    px = to_pixels(np.asarray(footprint.exterior.coords))
    return _finish(rgb, noise, blur, seed), shapely.Polygon(px), base


@functools.cache
def _form_leaf(terms: tuple[tuple[str, object], ...]) -> tuple[object, int]:
    """The form's leaf and its apex's index on the outline, grown once per form for the angles
    and seeds it is photographed at (the veins' growth: most of a form's 0.08 s)."""
    from leafstudio.forms import Form

    form = Form(**dict(terms))
    leaf = form.leaf()
    for array in (leaf.boundary, *leaf.veins):
        array.setflags(write=False)  # shared: a test that wrote to it would fail, not the next
    return leaf, form.outline().apex_index


def leaf_frame_match(
    terms: dict, angle: float, seed: int = 0, draw_veins: bool = True, **found_options
) -> dict:
    """A form (make_form's terms) photographed at `angle` without a petiole, found again: the IoU
    with the known outline in the forms' convention (base at the origin, apex on +x, both at the
    known base-to-apex length: a wrong base turns the outline round), the IoU in the photo's
    pixels (the segmentation alone), the base's distance from the known one (share of the
    length) and the cue that told the base (PhotoLeaf.base_cue). `draw_veins` False draws the
    blade plain."""
    from leafstudio.sources.photo import leaf_from_photo

    leaf, apex = _form_leaf(tuple(sorted(terms.items())))
    known = leaf.boundary[:, :2]
    length = float(np.linalg.norm(known[apex]))  # base to apex, as `--length` means it
    veins = leaf.veins if draw_veins else []
    image, known_px, base_px = form_photo(leaf.boundary, veins, angle=angle, seed=seed)
    found = leaf_from_photo(image, length=length, veins="none", **found_options)
    xy = found.leaf.boundary[:, :2]
    pixel_length = np.linalg.norm(found.pixel_from_world[:, 0]) * length
    base_error = np.linalg.norm(found.pixel_from_world @ [0, 0, 1] - base_px) / pixel_length
    return {
        "iou_leaf_frame": round(iou(shapely.Polygon(xy).buffer(0), shapely.Polygon(known)), 4),
        "iou_pixels": round(iou(shapely.Polygon(found.outline_px).buffer(0), known_px), 4),
        "base_error": round(float(base_error), 4),
        "base_cue": found.base_cue,
    }


def iou(a: shapely.Polygon, b: shapely.Polygon) -> float:
    """Intersection over union of two polygons."""
    return a.intersection(b).area / a.union(b).area


def error_lines(stderr: str) -> int:
    """Lines of a command's stderr that report an error (notes such as the first run's kernel
    compilation may come before them)."""
    return sum("error:" in line for line in stderr.strip().splitlines())


def exif_turned(image: np.ndarray, path: Path) -> Path:
    """`image` saved as a phone saves a portrait photo: its pixels turned a quarter turn
    counter-clockwise, with EXIF orientation 6 ("turn a quarter clockwise to show")."""
    from PIL import Image

    exif = Image.Exif()
    exif[0x0112] = 6
    Image.fromarray(np.ascontiguousarray(np.rot90(image))).save(path, exif=exif)
    return path
