"""The photo a leaf was found in, as a project remembers it.

A `.leaf.json` made from a photo (`leafstudio photo`, or the app's File > Open photo then Save)
holds

    "photo": {"image": "leaf.png", "pixel_from_world": [[a, b, c], [d, e, f]], "petiole_cut": b}

`image` is the photo's path relative to the project's folder (so a folder moved or copied as a
whole keeps working; an absolute path is read as it is), `pixel_from_world` the affine map from
the leaf's coordinates to the photo's (column, row), pixel centres at integer + 0.5. Projects
without the entry load as before; the entry is what lets `reconstruct --texture PHOTO` and the
app's texture put each pixel back where it was in the photo. The map is into the photo as
read_image shows it, upright (`"upright": true`); an entry without that key was saved when the
photo's EXIF orientation was ignored, and its map is turned with the photo (upright_map).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from leafstudio._shared.inputs import load_json
from leafstudio.errors import LeafError

# what `leafstudio photo` and the app's photo dialog offer (sources/photo.py reads the photo);
# here, with no scipy nor skimage, for the command line's parser
BASE_ENDS = ("auto", "left", "right", "top", "bottom")  # where the base is in the photo
VEIN_CHOICES = ("auto", "trace", "grow", "none")  # the veins: traced, grown, either, none


@dataclass(frozen=True)
class PhotoTexture:
    """A photo and the affine map (2, 3) from world (x, y) to its (column, row).

    The `texture` of `save_mesh`: with a map, each pixel lands on the mesh where it was in the
    photo the leaf came from (`leafstudio photo`); without one, the image covers the UV square.

    Attributes
    ----------
    image : str or path-like
        The image file.
    pixel_from_world : (2, 3) float array or None
        A leaf point's (x, y, 1) to the photo's (column, row); see `assets.photo_transform`.

    Examples
    --------
    >>> from leafstudio.assets import PhotoTexture
    >>> PhotoTexture("leaf.png").pixel_from_world is None
    True
    """

    image: str | os.PathLike
    pixel_from_world: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class LeafPhoto:
    """A photo (its absolute path) and the map from the leaf's (x, y, 1) to its pixels."""

    image: Path
    pixel_from_world: np.ndarray  # (2, 3)
    petiole_cut: bool | None = None

    @classmethod
    def of(cls, found: Any, image: str | os.PathLike) -> LeafPhoto:
        """The photo a leaf was just found in (a photo.PhotoLeaf, read from `image`)."""
        return cls(Path(image).resolve(), np.asarray(found.pixel_from_world, float), found.petiole)

    def exists(self) -> bool:
        """Whether the photo is still where the project says (moved or deleted files are not)."""
        return self.image.is_file()

    def texture(self) -> PhotoTexture:
        """The export option that maps this photo onto the leaf (assets/export.py)."""
        return PhotoTexture(self.image, self.pixel_from_world)

    def entry(self, project: str | os.PathLike) -> dict[str, Any]:
        """The project's "photo" entry, the image relative to the project's folder."""
        folder = Path(project).resolve().parent
        try:
            image = Path(os.path.relpath(self.image, folder)).as_posix()
        except ValueError:  # another drive (Windows): no relative path
            image = str(self.image)
        entry: dict[str, Any] = {"image": image, "pixel_from_world": self.pixel_from_world.tolist()}
        entry["upright"] = True  # the map is into the photo as read_image shows it (upright)
        if self.petiole_cut is not None:
            entry["petiole_cut"] = bool(self.petiole_cut)
        return entry


def pixel_map(entry: Any, source: str) -> np.ndarray:
    """The (2, 3) world-to-pixel map of a "photo" entry; LeafError if malformed."""
    try:
        affine = np.asarray(entry["pixel_from_world"], dtype=float).reshape(2, 3)
    except (TypeError, KeyError, ValueError):
        raise LeafError('bad "photo" entry: "pixel_from_world" must be 2 rows of 3 numbers',
                        source) from None  # fmt: skip
    if not np.all(np.isfinite(affine)) or abs(np.linalg.det(affine[:, :2])) == 0:
        raise LeafError('bad "photo" entry: "pixel_from_world" is not an invertible map', source)
    return affine


def from_entry(entry: Any, project: str | os.PathLike) -> LeafPhoto:
    """The LeafPhoto of a project's "photo" entry (the image resolved against the project's
    folder); LeafError if the entry is malformed. The image need not exist (see exists)."""
    source = str(project)
    affine = pixel_map(entry, source)
    image = entry.get("image")
    if not isinstance(image, str) or not image.strip():
        raise LeafError('bad "photo" entry: "image" must name the photo file', source)
    petiole = entry.get("petiole_cut")
    path = (Path(project).resolve().parent / image).resolve()  # an absolute one stays
    if entry.get("upright") is not True:  # saved before read_image turned photos upright
        affine = upright_map(affine, path)
    return LeafPhoto(path, affine, petiole if isinstance(petiole, bool) else None)


def upright_map(affine: np.ndarray, image: Path) -> np.ndarray:
    """A (2, 3) world-to-pixel map into the photo's stored pixels made one into its pixels as
    read_image gives them, upright (its EXIF orientation applied); `affine` as it is for a photo
    without one, or one that cannot be read. Projects saved before the orientation was applied
    hold maps of the first kind."""
    from PIL import Image

    try:
        with Image.open(image) as photo:
            orientation, (w, h) = photo.getexif().get(0x0112, 1), photo.size
    except Exception:  # missing or unreadable: read_image says so when the texture is made
        return affine
    turns = {  # stored (column, row, 1) -> upright (column, row), as ImageOps.exif_transpose
        2: [[-1, 0, w], [0, 1, 0]],  # mirrored left to right
        3: [[-1, 0, w], [0, -1, h]],  # a half turn
        4: [[1, 0, 0], [0, -1, h]],  # mirrored top to bottom
        5: [[0, 1, 0], [1, 0, 0]],  # transposed
        6: [[0, -1, h], [1, 0, 0]],  # a quarter turn clockwise
        7: [[0, -1, h], [-1, 0, w]],  # transversed
        8: [[0, 1, 0], [-1, 0, w]],  # a quarter turn counter-clockwise
    }
    if orientation not in turns:
        return affine
    return np.asarray(turns[orientation], float) @ np.vstack([affine, [0.0, 0.0, 1.0]])


def project_photo(project: str | os.PathLike) -> LeafPhoto | None:
    """The photo a .leaf.json project remembers, or None (another file type, or no entry);
    LeafError for an unreadable project or a malformed entry."""
    if not str(project).lower().endswith(".json"):
        return None
    data = load_json(project)
    entry = data.get("photo") if isinstance(data, dict) else None
    return None if entry is None else from_entry(entry, project)


def photo_path(project: str | os.PathLike | None) -> Path | None:
    """The image a .leaf.json project was traced from (project_photo's), or None: another file,
    no entry, or one that cannot be read (the command says so where it uses it). An input of a
    command that opens the project (its texture, the app's backdrop), which no output may
    replace: `reconstruct p.leaf.json -o x.glb --figure PHOTO` replaced it."""
    if project is None:
        return None
    try:
        found = project_photo(project)
    except LeafError:
        return None
    return None if found is None else found.image
