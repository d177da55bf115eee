"""Cut-out textures keep no stray colour outside the leaf (alpha bleeding, edge padding): every
alpha-0 texel has the colour of the nearest texel inside the leaf, so the bilinear filtering and
mipmaps of 3D engines (which average straight, not premultiplied, colour) draw no halo of the
photo's background at the leaf's edge. Checked on the .glb files as written."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import leafstudio as ls
from leafstudio.assets.asset import leaf_plane
from leafstudio.assets.export import base_color
from leafstudio.assets.texture import outline_mask
from leafstudio.forms import make_form
from leafstudio.sources.leafphoto import PhotoTexture
from leafstudio.sources.photo import leaf_from_photo
from tests.assets.test_assets import gltf_reports, scene_mesh
from tests.photos import BACKGROUND, form_photo

NEAR = 8  # texels outside the outline checked against the nearest leaf texel
LEVELS = 4  # mipmap levels checked (2x2 box averages: 512, 256, 128, 64 texels)


@pytest.fixture(scope="module")
def photo_leaf(tmp_path_factory) -> tuple[ls.Result, Path, np.ndarray]:
    """A serrate leaf found in a photo on a pale background, its photo and pixel map."""
    form = make_form("ovate", margin="serrate", teeth=24)
    image, _, _ = form_photo(form.boundary, form.veins, angle=-40)
    path = tmp_path_factory.mktemp("photo") / "leaf.png"
    Image.fromarray(image).save(path)
    found = leaf_from_photo(image, veins="none")
    result = ls.reconstruct(found.leaf, ls.Params(k=1, grid=48, samples=800))
    return result, path, found.pixel_from_world


@pytest.fixture(scope="module")
def photo_glb(photo_leaf, tmp_path_factory) -> Path:
    """The photo leaf written to .glb with its photo as texture, once for the tests that read it
    (each write resamples and pads the photo: about 1 s)."""
    result, path, pixel_from_world = photo_leaf
    glb = tmp_path_factory.mktemp("glb") / "photo.glb"
    ls.save_mesh(result, glb, texture=PhotoTexture(path, pixel_from_world))
    return glb


def _texture_of(path: Path) -> np.ndarray:
    """The base-colour texture of a .glb, read back (RGBA uint8)."""
    return np.asarray(scene_mesh(path).visual.material.baseColorTexture.convert("RGBA"))


def _glb_texture(result: ls.Result, texture, path: Path) -> np.ndarray:
    """The base-colour texture of the .glb written for `result`, read back (RGBA uint8)."""
    ls.save_mesh(result, path, texture=texture)
    return _texture_of(path)


def _assert_no_bleeding(texture: np.ndarray) -> None:
    """Both checks below."""
    _assert_padded(texture)
    _assert_mipmaps_keep_the_leaf_colour(texture)


def _assert_padded(texture: np.ndarray) -> None:
    """Every alpha-0 texel within NEAR of the leaf has its nearest leaf texel's colour."""
    from scipy.ndimage import distance_transform_edt

    rgb = texture[..., :3].astype(float)
    leaf = texture[..., 3] > 0
    assert leaf.any() and (~leaf).any()
    distance, (rows, cols) = distance_transform_edt(~leaf, return_indices=True)
    near = ~leaf & (distance <= NEAR)
    gap = np.abs(rgb[near] - rgb[rows[near], cols[near]]).max(axis=1)
    assert np.max(gap) <= 3, (np.count_nonzero(gap > 3), int(near.sum()))


def _assert_mipmaps_keep_the_leaf_colour(texture: np.ndarray) -> None:
    """Where the leaf's edge falls in a mipmap's block (2x2 box averages of straight colour, as
    engines make them), the block's colour stays within the range of the leaf's own colours
    there (its texels with alpha > 0 in that block and the blocks around it): it drifts toward
    no hidden colour."""
    from scipy.ndimage import maximum_filter, minimum_filter

    rgb = texture[..., :3].astype(float)
    alpha = texture[..., 3].astype(float) / 255
    leaf = alpha > 0
    for level in range(1, LEVELS + 1):
        size = 2**level
        h, w = (np.array(alpha.shape) // size) * size
        blocks = (h // size, size, w // size, size)
        straight = rgb[:h, :w].reshape(*blocks, 3).mean(axis=(1, 3))
        weight = alpha[:h, :w].reshape(blocks).mean(axis=(1, 3))
        edge = (weight > 0) & (weight < 1)  # blocks the outline crosses
        assert edge.any()
        on = leaf[:h, :w, None]
        low = np.where(on, rgb[:h, :w], np.inf).reshape(*blocks, 3).min(axis=(1, 3))
        high = np.where(on, rgb[:h, :w], -np.inf).reshape(*blocks, 3).max(axis=(1, 3))
        low = minimum_filter(low, size=(3, 3, 1), mode="nearest")
        high = maximum_filter(high, size=(3, 3, 1), mode="nearest")
        drift = np.maximum(low - straight, straight - high).max(axis=2)[edge]
        assert np.max(drift) <= 3, (level, float(np.max(drift)), int(np.sum(drift > 3)))


def test_a_photo_texture_has_the_leaf_colour_outside_its_outline(photo_leaf, photo_glb):
    result, path, pixel_from_world = photo_leaf
    texture = _texture_of(photo_glb)
    _assert_no_bleeding(texture)
    outside = texture[..., 3] == 0
    to_background = np.linalg.norm(texture[..., :3].astype(float) - BACKGROUND, axis=2)
    assert np.count_nonzero(outside & (to_background < 60)) == 0  # no pale photo anywhere
    # the app draws the same image (base_color), alpha untouched: the outline's mask
    assert np.array_equal(np.asarray(base_color(result, PhotoTexture(path, pixel_from_world))),
                          texture)  # fmt: skip


def test_the_generated_texture_has_the_leaf_colour_outside_its_outline(tmp_path):
    # veins reach the margin on this form: the vein colour continues outward there
    result = ls.reconstruct(make_form("ovate", margin="serrate", teeth=24),
                            ls.Params(k=1, grid=48, samples=800))  # fmt: skip
    texture = _glb_texture(result, "auto", tmp_path / "auto.glb")
    _assert_no_bleeding(texture)
    alpha = outline_mask(leaf_plane(result), texture.shape[0])
    assert np.array_equal(texture[..., 3], alpha)  # alpha as it was: the outline's mask
    assert np.array_equal(np.asarray(base_color(result, "auto")), texture)


def test_an_image_with_alpha_is_padded_too(photo_leaf, tmp_path):
    """An RGBA image without a pixel map covers the UV square as it is: its transparent part
    takes the nearest opaque colour (the user's cut-out keeps no hidden background)."""
    result, _, _ = photo_leaf
    image = np.zeros((300, 300, 4), np.uint8)
    image[..., :3] = (255, 0, 255)  # a cut-out's hidden colour
    yy, xx = np.mgrid[:300, :300]
    disk = (yy - 150) ** 2 + (xx - 150) ** 2 < 100**2
    image[disk] = (40, 120, 40, 255)
    path = tmp_path / "cutout.png"
    Image.fromarray(image, "RGBA").save(path)
    texture = _glb_texture(result, str(path), tmp_path / "cutout.glb")
    _assert_no_bleeding(texture)
    opaque = texture[..., 3] == 255
    assert opaque.mean() > 0.2 and np.all(np.abs(texture[opaque][:, :3] - (40, 120, 40)) <= 2)


def test_padded_textures_still_validate(photo_leaf, photo_glb, tmp_path):
    """The Khronos validator: zero errors and warnings (skips without node and the validator)."""
    result, _, _ = photo_leaf
    auto = tmp_path / "auto.gltf"
    ls.save_mesh(result, auto)
    for name, report in gltf_reports(photo_glb, auto).items():
        assert report["numErrors"] == 0 and report["numWarnings"] == 0, (name, report["messages"])


def test_a_photo_leaf_gets_the_normal_map_of_its_veins(photo_leaf, photo_glb):
    """Issue 23: a leaf's own material. A photo mapped back onto the leaf it was found in gets
    the vein relief too (its veins were traced in that photo, so they lie on it); an image that
    is not the leaf's photo (stretched over the UVs) does not."""
    from leafstudio.assets.export import mesh_assets

    result, path, pixel_from_world = photo_leaf
    (asset,) = mesh_assets(result, PhotoTexture(path, pixel_from_world), gltf=True)
    assert asset.normal_map is not None and asset.normal_map.size == asset.texture.size
    (stretched,) = mesh_assets(result, PhotoTexture(path, None), gltf=True)
    assert stretched.normal_map is None
    (obj,) = mesh_assets(result, PhotoTexture(path, pixel_from_world), gltf=False)
    assert obj.normal_map is None  # OBJ holds no normal map
    material = scene_mesh(photo_glb).visual.material
    assert material.normalTexture is not None and material.baseColorTexture is not None
