"""Opening a file in the app, without Qt: the one decision path of the command line and batch
(workflows.open_file, or workflows.open_scan for File > Open scan) followed by what the app
keeps beside the leaf (the project's sketch, the photo the leaf was found in, the scan's
layers). `read_document` runs on the worker's side lane; the session makes its answer the
document (Session.open_path).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from leafstudio.errors import LeafError
from leafstudio.gui.model.sketch_model import Sketch
from leafstudio.model import Leaf, Params
from leafstudio.sources.leafphoto import LeafPhoto, project_photo
from leafstudio.workflows import open_file, open_scan


@dataclass(frozen=True, eq=False)
class Document:
    """A file read for the app: its leaf and what opens with it.

    Attributes
    ----------
    path : str
        The file as the user named it.
    leaf : Leaf
        Read, extracted from the scan, or found in the photo.
    sketch : Sketch or None
        A project's saved sketch.
    params : Params or None
        A project's saved parameters.
    scan : ScanData or None
        A scan's points and layers.
    photo : LeafPhoto or None
        The photo the leaf was found in (its texture).
    notice : str
        What is wrong beside the leaf ("" if nothing): a project's bad photo entry costs the
        texture, never the leaf.
    """

    path: str
    leaf: Leaf
    sketch: Sketch | None = None
    params: Params | None = None
    scan: Any = None  # scans.ScanData
    photo: LeafPhoto | None = None
    notice: str = ""

    @property
    def title(self) -> str:
        return Path(self.path).name


def read_document(path: str, as_scan: bool = False) -> Document:
    """Open `path` as every command does (`as_scan`: as a scan whatever its points look like).

    Raises
    ------
    LeafError
        Naming `path`: unreadable, malformed, a boundary that crosses itself, a bad sketch, a
        scan that is not plausibly one leaf, no leaf in the photo.
    """
    try:
        opened = open_scan(path) if as_scan else open_file(path)
    except OSError as exc:
        raise LeafError(exc.strerror or str(exc), path) from None
    if opened.kind == "scan":
        from leafstudio.gui.model.scans import scan_data  # pyvista (layers): not for every session

        return Document(opened.path, opened.leaf, scan=scan_data(opened))
    if opened.kind == "photo":  # its texture, kept when the project is saved
        return Document(opened.path, opened.leaf, photo=LeafPhoto.of(opened.photo, path))
    sketch, photo, notice = None, None, ""
    if opened.kind == "project":
        try:
            sketch = Sketch.from_dict(opened.sketch) if opened.sketch else None
        except (TypeError, ValueError, KeyError) as exc:
            raise LeafError(f"bad sketch ({exc})", path) from None
        photo, notice = _project_photo(path)
    return Document(opened.path, opened.leaf, sketch, opened.params, None, photo, notice)


def _project_photo(path: str) -> tuple[LeafPhoto | None, str]:
    """The photo a project remembers (sources/leafphoto.py) or None, and what is wrong with
    its entry ("" if nothing)."""
    try:
        return project_photo(path), ""
    except LeafError as exc:
        return None, f"{exc}: the leaf shows and exports the texture generated from it."


def missing_photo_message(photo: LeafPhoto) -> str:
    """What the window says when a leaf's photo is not where its project says."""
    return (
        f"The photo this leaf was found in is missing ({photo.image}): the leaf shows and exports "
        "the texture generated from it instead. Put the photo back and open the project again "
        "to use it; saving keeps the photo's place in the project."
    )
