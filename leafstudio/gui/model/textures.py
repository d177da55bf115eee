"""The leaf as it exports, in the 3D view: the base-colour texture an export writes (generated
blade and veins, the photo the leaf came from, or an image picked for the export), mapped through
the mesh's UVs (assets/asset.py).

Two colourings show it: "texture (as exported)" as it is, and the Leaf look (LEAF), the same
image lit as a leaf (the viewport's LEAF_LOOK), the first colouring and the one every leaf opens
in but a scan (coloring_for).

The image is made on the worker's side lane (texture_image, a numpy array); the viewport wraps it
into a pyvista Texture on the main thread. texture_key names what the image depends on (the
texture option and the leaf plane: outline, veins, frame), so that a parameter change that keeps
the plane keeps the image, and the images last made are kept by it (KEPT_TEXTURES), as the
worker's store keeps the pipeline's stages: a leaf shown again (an undo, a demo or form chosen
again, another window) gets its image without it being made again. No Qt here.
"""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from pathlib import Path
from typing import Any

import numpy as np

from leafstudio.assets.export import base_color
from leafstudio.sources.leafphoto import PhotoTexture

TEXTURE = "texture"  # the mesh colouring that shows the texture
TEXTURE_LABEL = "texture (as exported)"
LEAF = "leaf"  # the Leaf look: the same texture, lit as a leaf (the default but for scans)
LEAF_LABEL = "Leaf (lit, veins, translucent)"
SHOWS_TEXTURE = (LEAF, TEXTURE)  # the colourings that map the texture image
SCAN_COLORING = "height"  # a scan's: its relief, judged against the scan
# images kept by key: 4 MB each at 1024² RGBA; each made again costs the side lane 0.1-0.3 s
KEPT_TEXTURES = 4
_kept: OrderedDict[tuple, np.ndarray | None] = OrderedDict()
_kept_lock = threading.Lock()  # the side lane makes them; any thread may ask


def coloring_for(is_scan: bool, current: str, automatic: bool) -> tuple[str, bool]:
    """The mesh colouring for a newly opened leaf, and whether it was chosen here: a scan
    turns the Leaf look into colour by height (a scan is judged by its relief); the next leaf
    that is not a scan gets the Leaf look back, unless the user picked height meanwhile. Any
    other colouring the user picked is kept.

    Examples
    --------
    >>> coloring_for(True, LEAF, False)
    ('height', True)
    >>> coloring_for(False, "height", True)
    ('leaf', False)
    >>> coloring_for(False, "height", False)  # the user's own choice
    ('height', False)
    """
    if is_scan and current == LEAF:
        return SCAN_COLORING, True
    if not is_scan and current == SCAN_COLORING and automatic:
        return LEAF, False
    return current, automatic and current == SCAN_COLORING


def _file_stamp(path: Any) -> tuple:
    """A file's name, size and modification time (a replaced image is made again)."""
    try:
        stat = Path(path).stat()
        return (str(path), stat.st_size, stat.st_mtime_ns)
    except OSError:
        return (str(path), None, None)


def texture_key(result: Any, texture: Any) -> tuple:
    """What the texture image of `result` under the export option `texture` depends on."""
    digest = hashlib.sha1()
    frame = result.frame
    for array in (result.polygon, frame.origin, frame.u, frame.v, *result.leaf.veins):
        digest.update(np.ascontiguousarray(array, dtype=float).tobytes())
        digest.update(b"|")
    if isinstance(texture, PhotoTexture):
        mapping = None if texture.pixel_from_world is None else texture.pixel_from_world.tobytes()
        option: tuple = ("photo", _file_stamp(texture.image), mapping)
    elif texture in ("auto", "none"):
        option = (texture,)
    else:
        option = ("image", _file_stamp(texture))
    return (option, digest.hexdigest())


def texture_image(result: Any, texture: Any) -> np.ndarray | None:
    """The (h, w, 3 or 4) uint8 base-colour image an export writes (row 0 at t = 1, read-only:
    it may be shared), or None for no texture; LeafError for an image that cannot be read.
    Runs off the main thread; an image made for the same key lately is given again."""
    key = texture_key(result, texture)
    with _kept_lock:
        if key in _kept:
            _kept.move_to_end(key)
            return _kept[key]
    image = base_color(result, texture)
    array = None if image is None else np.asarray(image)
    if array is not None:
        array.flags.writeable = False
    with _kept_lock:
        _kept[key] = array
        while len(_kept) > KEPT_TEXTURES:
            _kept.popitem(last=False)
    return array


def forget_textures() -> None:
    """Drop the images kept (tests that count how many are made start from none)."""
    with _kept_lock:
        _kept.clear()
