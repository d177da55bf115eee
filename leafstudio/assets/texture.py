"""Textures in the leaf's UV space (asset.py): the generated leaf, a normal map, a mapped photo.

The generated base colour is the blade's colour inside the outline with the veins drawn over it in
their own colour. The midrib (the longest vein) is drawn widest; the other veins are narrower in
proportion to the square root of their length relative to the midrib's (never under a third of
it), and each narrows further toward its far end from the midrib. Outside the outline alpha is 0.

Every RGBA texture made here is padded (`bleed`): a texel with alpha 0 takes the colour of the
nearest texel with alpha > 0. Engines filter textures (bilinear, mipmaps) on straight, not
premultiplied, colour, so whatever colour sat under alpha 0 (a photo's background, the blade's
colour beside a vein reaching the margin) would mix into the leaf's edge as a halo.

The normal map is the veins' relief: a height image (the vein strokes, blurred) turned into
tangent-space normals, with the tangent along s (the leaf's length) and the bitangent along t.
"""

from __future__ import annotations

import numpy as np

from leafstudio.assets.asset import LeafPlane
from leafstudio.core.raster import nearest_set_pixel
from leafstudio.errors import LeafError
from leafstudio.sources.photo import foreground

# A leaf's greens, sRGB: little blue, as a leaf reflects (and transmits) little. Blender's
# Principled BSDF tints transmitted light by the square root of the base colour (a ray crosses
# two interfaces of a solid; a blade is one sheet), so a bluish base colour turns pale against
# the light: (78, 128, 50) transmitted a grey-mint (143, 181, 118), (70, 120, 22) a yellow-green
BLADE = (70, 120, 22)
VEIN = (160, 190, 70)
TEXTURE_PIXELS = 1024
SUPERSAMPLE = 2  # drawn at this multiple, then reduced (anti-aliased edges)
MIDRIB_WIDTH = 0.012  # of the leaf length
THINNEST = 1 / 3  # of the midrib's width
TIP_NARROWING = 0.5  # a secondary's width at its far end, as a fraction of its start's
RELIEF = 2.0  # normal map: slope of the vein relief, in height per vein width
EDGE_PIXELS = 2  # a photo's leaf edge this deep blends with the background (blur, anti-aliasing)
PAD_EXACT = 32  # edge padding: the nearest leaf texel's colour is exact this far out, or farther


def _pixel(plane: LeafPlane, xy: np.ndarray, pixels: int) -> np.ndarray:
    """(n, 2) image column, row of plane points (row 0 at t = 1)."""
    uv = plane.uvmap(xy)
    return np.column_stack([uv[:, 0] * pixels, (1 - uv[:, 1]) * pixels])


def outline_mask(plane: LeafPlane, pixels: int) -> np.ndarray:
    """(pixels, pixels) uint8: 255 inside the outline, anti-aliased at its edge."""
    from PIL import Image, ImageDraw

    big = pixels * SUPERSAMPLE
    mask = Image.new("L", (big, big), 0)
    ImageDraw.Draw(mask).polygon([tuple(p) for p in _pixel(plane, plane.polygon, big)], fill=255)
    return np.asarray(mask.reduce(SUPERSAMPLE))  # box average, 4 times cheaper than resize


def _polyline_length(line: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(line, axis=0), axis=1).sum()) if len(line) > 1 else 0.0


def vein_strokes(plane: LeafPlane, pixels: int) -> np.ndarray:
    """(pixels, pixels) uint8 coverage of the veins drawn with their widths (module docstring)."""
    from PIL import Image, ImageDraw

    big = pixels * SUPERSAMPLE
    image = Image.new("L", (big, big), 0)
    draw = ImageDraw.Draw(image)
    veins = [v for v in plane.veins if len(v) > 1]
    if veins:
        lengths = np.array([_polyline_length(v) for v in veins])
        midrib = int(np.argmax(lengths))
        per_unit = big / (plane.uvmap.size)
        full = MIDRIB_WIDTH * plane.length * per_unit
        for i, vein in enumerate(veins):
            if i != midrib:  # a secondary starts at its end nearer the midrib
                near = np.min(np.linalg.norm(veins[midrib][:, None] - vein[[0, -1]], axis=2), 0)
                vein = vein if near[0] <= near[1] else vein[::-1]
            start = full * max(np.sqrt(lengths[i] / lengths[midrib]), THINNEST)
            along = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(vein, axis=0), axis=1))])
            fraction = along / max(along[-1], 1e-300)
            end = 1.0 if i == midrib else TIP_NARROWING
            widths = start * (1 - (1 - end) * fraction)
            px = _pixel(plane, vein, big)
            for k in range(len(px) - 1):
                w = max(widths[k], 1.0)
                draw.line([tuple(px[k]), tuple(px[k + 1])], fill=255, width=round(w))
                r = w / 2
                x, y = px[k]
                draw.ellipse([x - r, y - r, x + r, y + r], fill=255)
            r = max(widths[-1], 1.0) / 2
            x, y = px[-1]
            draw.ellipse([x - r, y - r, x + r, y + r], fill=255)
    return np.asarray(image.reduce(SUPERSAMPLE))


def leaf_texture(plane: LeafPlane, pixels: int = TEXTURE_PIXELS, strokes: np.ndarray | None = None):
    """The generated base-colour texture: an RGBA PIL image (see the module docstring); pass the
    vein strokes if they are already drawn."""
    from PIL import Image

    strokes = vein_strokes(plane, pixels) if strokes is None else strokes
    # a look-up of whole RGBA texels (one uint32 each): 4 times cheaper than blending per
    # texel, and 9 times cheaper than looking up the three channels (33 -> 3.6 ms at 1024²)
    rgba = np.take(_VEIN_TEXELS, strokes).view(np.uint8).reshape(*strokes.shape, 4)
    rgba[..., 3] = outline_mask(plane, pixels)
    return bleed(Image.fromarray(rgba, "RGBA"))


def _vein_blend() -> np.ndarray:
    """(256, 3) uint8: the blade's colour blended toward the veins' by each stroke coverage."""
    veins = np.arange(256)[:, None] / 255
    rgb = np.asarray(BLADE, float) * (1 - veins) + np.asarray(VEIN, float) * veins
    return np.rint(rgb).astype(np.uint8)


_VEIN_TEXELS = np.pad(_vein_blend(), ((0, 0), (0, 1))).view(np.uint32).ravel()  # RGBA, alpha 0


def normal_map(plane: LeafPlane, pixels: int = TEXTURE_PIXELS, strokes: np.ndarray | None = None):
    """The veins' relief as a tangent-space normal map: an RGB PIL image (+x along s, +y along t,
    the OpenGL convention glTF uses)."""
    from PIL import Image
    from scipy.ndimage import gaussian_filter

    strokes = vein_strokes(plane, pixels) if strokes is None else strokes
    width = MIDRIB_WIDTH * plane.length * pixels / plane.uvmap.size  # the midrib's, in pixels
    height = gaussian_filter(strokes.astype(float) / 255, max(width / 3, 0.5))
    height *= RELIEF * width
    d_row, d_col = np.gradient(height)
    normal = np.dstack([-d_col, d_row, np.ones_like(height)])  # rows run down, t runs up
    normal /= np.linalg.norm(normal, axis=2, keepdims=True)
    return Image.fromarray(np.rint((normal + 1) * 127.5).astype(np.uint8), "RGB")


def photo_texture(
    plane: LeafPlane, photo: np.ndarray, pixel_from_world: np.ndarray, pixels: int = TEXTURE_PIXELS
):
    """The photo resampled into UV space: each texel takes the colour of the photo pixel its leaf
    point came from, so the leaf in the texture is where the mesh's UVs put it. Alpha is the
    outline's mask. Inside the outline, a texel whose photo pixel is background (the smooth
    margin rounding a sinus, the photo's blurred edge: a pale band 1-2 photo pixels deep) takes
    the colour of the nearest texel on the photo's leaf; outside it, the nearest texel inside
    it (`bleed`).

    Parameters
    ----------
    photo : (h, w, 3 or 4) uint8 array
    pixel_from_world : (2, 3) float array
        The affine map from world (x, y) to the photo's (column, row), as `leafstudio photo`
        stores it (photo.py).
    """
    from PIL import Image
    from scipy.ndimage import map_coordinates

    xy = plane.uvmap.texel_plane_points(pixels).reshape(-1, 2)
    where = _photo_rows_columns(plane, pixel_from_world, xy)
    alpha = outline_mask(plane, pixels)
    leaf = _photo_leaf(photo)
    on_leaf = None
    if leaf is not None:
        on_leaf = map_coordinates(leaf.view(np.uint8), where, order=0, mode="constant", cval=0)
        on_leaf = on_leaf.reshape(pixels, pixels).astype(bool)
    # only the texels whose colour is kept or copied are read from the photo: those inside the
    # outline and those on the photo's leaf (the fill's sources); `bleed` gives every other one
    # a colour from inside (half the texels or more: 0.23 -> 0.1 s a texture), unless none is
    seen = alpha > 0
    read = (seen | on_leaf if on_leaf is not None else seen) if seen.any() else ~seen
    at = where[:, read.ravel()]
    rgb = np.zeros((pixels, pixels, 3), np.uint8)
    rgb[read] = np.rint(np.column_stack(
        [map_coordinates(photo[..., c].astype(float), at, order=1, mode="nearest")
         for c in range(3)]
    )).clip(0, 255).astype(np.uint8)  # fmt: skip
    if on_leaf is not None:
        rgb = _nearest_fill(rgb, on_leaf, seen & ~on_leaf)
    return bleed(Image.fromarray(np.dstack([rgb, alpha]), "RGBA"))


def _photo_rows_columns(plane: LeafPlane, pixel_from_world: np.ndarray, xy: np.ndarray):
    """(2, n): the photo's (row, column) of each plane point `xy` (n, 2), pixel centres at
    k + 0.5 made integers, as map_coordinates reads them. The plane to the world's (x, y) and
    the world's to the photo's are both affine: one 2 x 2 map and an offset, applied column by
    column (the world points and a (n, 2) @ (2, 2) product took 0.2 s for a 1024-pixel
    texture, half the photo's resampling)."""
    frame = plane.frame
    linear = pixel_from_world[:, :2]
    m = linear @ np.column_stack([frame.u[:2], frame.v[:2]])  # (column, row) from (x, y)
    c = linear @ frame.origin[:2] + pixel_from_world[:, 2] - 0.5
    x, y = xy[:, 0], xy[:, 1]
    return np.stack([x * m[1, 0] + y * m[1, 1] + c[1], x * m[0, 0] + y * m[0, 1] + c[0]])


def _photo_leaf(photo: np.ndarray) -> np.ndarray | None:
    """(h, w) bool: the photo's leaf pixels as `leafstudio photo` segments them (photo.py), less
    the edge where leaf and background blend (EDGE_PIXELS); None if nothing stands out."""
    from scipy.ndimage import binary_erosion

    try:
        return binary_erosion(foreground(photo), iterations=EDGE_PIXELS)
    except LeafError:
        return None


def _nearest(source: np.ndarray) -> np.ndarray:
    """(h, w) flat index of the `source` texel nearest each texel (some source texel needed).
    Exact for every texel within PAD_EXACT of the sources' bounding box (the feature transform
    runs on that box only: a leaf leaves a third of the square or more empty); farther out a
    texel takes the box's texel nearest it."""
    h, w = source.shape
    used_rows, used_cols = np.flatnonzero(source.any(axis=1)), np.flatnonzero(source.any(axis=0))
    r0, r1 = max(used_rows[0] - PAD_EXACT, 0), min(used_rows[-1] + PAD_EXACT + 1, h)
    c0, c1 = max(used_cols[0] - PAD_EXACT, 0), min(used_cols[-1] + PAD_EXACT + 1, w)
    rows, cols = nearest_set_pixel(source[r0:r1, c0:c1])
    nearest = (rows + r0) * w + (cols + c0)
    return np.pad(nearest, ((r0, h - r1), (c0, w - c1)), mode="edge")


def _nearest_fill(rgb: np.ndarray, source: np.ndarray, fill: np.ndarray) -> np.ndarray:
    """`rgb` with each `fill` texel given the colour of the nearest `source` texel (edge
    padding; unchanged when there is nothing to fill or nothing to fill from)."""
    if not fill.any() or not source.any():
        return rgb
    taken = rgb.reshape(-1, rgb.shape[2])[_nearest(source).ravel()].reshape(rgb.shape)
    return np.where(fill[..., None], taken, rgb)


def bleed(image):
    """An RGBA PIL image with every alpha-0 texel given the colour of the nearest texel with
    alpha > 0, alpha unchanged (alpha bleeding: no hidden colour for filtering and mipmaps to
    mix into the edge); other modes, or an image all or nothing transparent, as they are."""
    from PIL import Image

    if image.mode != "RGBA":
        return image
    rgba = np.ascontiguousarray(np.asarray(image))
    seen = rgba[..., 3] > 0
    if seen.all() or not seen.any():
        return image
    texels = rgba.view(np.uint32).ravel()  # one RGBA texel per element: a single gather
    out = texels[_nearest(seen).ravel()].view(np.uint8).reshape(rgba.shape)
    out[..., 3] = rgba[..., 3]
    return Image.fromarray(out, "RGBA")


def stretched_texture(image: np.ndarray, pixels: int = TEXTURE_PIXELS):
    """Any image as the texture over the whole UV square (a leaf without a photo transform).
    An image with alpha is padded (`bleed`) before it is resized, colour and alpha apart (Pillow
    resizes RGBA premultiplied: a faint texel's colour would come back from a few levels of 8
    bits), and again after (the filter's reach)."""
    from PIL import Image

    size, lanczos = (pixels, pixels), Image.Resampling.LANCZOS
    if image.shape[2] != 4:
        return Image.fromarray(image, "RGB").resize(size, lanczos)
    padded = np.asarray(bleed(Image.fromarray(image, "RGBA")))
    rgb = Image.fromarray(np.ascontiguousarray(padded[..., :3]), "RGB").resize(size, lanczos)
    alpha = Image.fromarray(np.ascontiguousarray(padded[..., 3]), "L").resize(size, lanczos)
    return bleed(Image.merge("RGBA", (*rgb.split(), alpha)))
