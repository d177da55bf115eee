"""Opening a file in the app, without Qt: the one decision path of the command line and batch
(workflows.open_file, or workflows.open_scan for File > Open scan) followed by what the app
keeps beside the leaf (the project's sketch, the photo the leaf was found in, the scan's
layers). `read_document` runs on the worker's side lane; the session makes its answer the
document (Session.open_path), unless Cancel came first (Session.cancel_open: the job stops at
its next `cancel_point` and its answer is dropped).

Opening lasts until the file's first result is shown: Cancel during that first reconstruction
stops it and brings the previous document back, as a failure would (the first run of a big file
or of a cold kernel cache can take long). The read's progress (_shared/progress.report: the
readers' blocks of lines) reaches the window as `open_progress`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from leafstudio.core.evaluate import MEASURABLE
from leafstudio.core.unfolded import unfolded, unposed_share
from leafstudio.errors import LeafError
from leafstudio.gui.model.jobs import Job, cancel_point, describe
from leafstudio.gui.model.reading import is_big, read_apart
from leafstudio.gui.model.sketch_model import Sketch
from leafstudio.model import Leaf, Params
from leafstudio.sources.leafphoto import LeafPhoto, project_photo
from leafstudio.sources.photo import is_photo
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
    unposed : float or None
        For a leaf in 3D that no pose lays flat (core/unfolded.unposed_share), its margin's
        share off its plane: the document keeps the refusal (history.State.unposed).
    """

    path: str
    leaf: Leaf
    sketch: Sketch | None = None
    params: Params | None = None
    scan: Any = None  # scans.ScanData
    photo: LeafPhoto | None = None
    notice: str = ""
    unposed: float | None = None

    @property
    def title(self) -> str:
        return Path(self.path).name


def read_document(
    path: str,
    as_scan: bool = False,
    length: float | None = None,
    pixel_size: float | None = None,
    base_end: str = "auto",
) -> Document:
    """Open `path` as every command does (`as_scan`: as a scan whatever its points look like;
    `length`: a photo's leaf length, photo_length; `pixel_size`: a photo pixel's, the ruler's in
    photo_import.py; `base_end`: the photo's end the base is at, as `photo --base-end`); a big
    file in a process of its own (reading.py), which Cancel ends at once.

    Raises
    ------
    LeafError
        Naming `path`: unreadable, malformed, a boundary that crosses itself, a bad sketch, a
        scan that is not plausibly one leaf, no leaf in the photo.
    Cancelled
        The job was cancelled (jobs.cancel_point).
    """
    if is_big(path) and not is_photo(path):
        return read_apart(_read_document, path, as_scan)
    return _read_document(path, as_scan, length, pixel_size, base_end)


def _read_document(
    path: str,
    as_scan: bool,
    length: float | None = None,
    pixel_size: float | None = None,
    base_end: str = "auto",
) -> Document:
    try:
        sizes = {"length": length, "pixel_size": pixel_size}  # a photo's only
        options = {key: value for key, value in sizes.items() if value is not None}
        options.update({"base_end": base_end} if base_end != "auto" else {})
        opened = open_scan(path) if as_scan else open_file(path, **options)
    except OSError as exc:
        raise LeafError(exc.strerror or str(exc), path) from None
    cancel_point()  # Cancel while the file was read: no layers, no document
    check_drawable(opened.leaf, path)
    if opened.kind == "scan":
        from leafstudio.gui.model.scans import scan_data  # pyvista (layers): not for every session

        # its notes (NaN points left out: open_scan) said as the CLI says them (review37:
        # extract, reconstruct and batch warned of them, the window said nothing)
        said = f"{Path(path).name}: {'; '.join(opened.notes)}" if opened.notes else ""
        return Document(opened.path, opened.leaf, scan=scan_data(opened), notice=said)
    if opened.kind == "photo":  # its texture, kept when the project is saved
        return Document(opened.path, opened.leaf, photo=LeafPhoto.of(opened.photo, path))
    sketch, photo, notice = None, None, ""
    if opened.kind == "project":
        try:
            sketch = Sketch.from_dict(opened.sketch) if opened.sketch else None
        except (TypeError, ValueError, KeyError) as exc:
            raise LeafError(f"bad sketch ({exc})", path) from None
        photo, notice = _project_photo(path)
    # the file's leaf is unfolded (open_file, but a project's with a sketch: here). A project
    # of curves in 3D saved with their sketch and no pose opened unbent, its run bent, its
    # sliders at 0 (/work/notes/refit39/repro.py): it opens fitted, drawn by the sketch of its
    # flat blade derived from its first run, as a point list is (that sketch draws the curves
    # in 3D: posed, they would be bent twice)
    leaf = unfolded(opened.leaf)
    sketch = sketch if leaf is opened.leaf else None
    unposed = unposed_share(leaf)
    return Document(opened.path, leaf, sketch, opened.params, None, photo, notice, unposed)


def check_drawable(leaf: Any, path: str) -> None:
    """LeafError when the leaf lies beyond what the app draws and measures: coordinates past
    MEASURABLE (about 1e150, where its areas overflow; a leaf under 1e-100 across is refused
    by Leaf itself). The command line's reconstruct takes such a leaf (its mesh alone); the
    window's sketch, texture and camera failed on it with tracebacks (issue 24's audit: a leaf
    at 1e300)."""
    reach = float(max(np.abs(points).max() for points in (leaf.boundary, *leaf.veins)))
    if reach > MEASURABLE:
        raise LeafError(
            f"the leaf's coordinates reach {reach:.3g}: the app draws and measures leaves up to "
            f"about {MEASURABLE:g}; rescale it, or write its mesh alone with `leafstudio "
            "reconstruct`",
            path,
        )


def _project_photo(path: str) -> tuple[LeafPhoto | None, str]:
    """The photo a project remembers (sources/leafphoto.py) or None, and what is wrong with
    its entry ("" if nothing)."""
    try:
        return project_photo(path), ""
    except LeafError as exc:
        return None, f"{exc}: the leaf shows and exports the texture generated from it."


class FileOpening:
    """Session's file opening (a mixin: Session holds the events, `run`, `open_document` and
    `_open_due`, the job reading the file, which another open, a demo or a new sketch
    supersedes)."""

    def open_path(
        self,
        path: str,
        *,
        as_scan: bool = False,
        length: float | None = None,
        pixel_size: float | None = None,
        base_end: str = "auto",
    ) -> Job:
        """Read a file off the main thread (opening.read_document on the side lane: the one
        decision path of the command line and batch; `as_scan`: File > Open scan) and make it
        the document once read, with its saved parameters or the current ones (`length`,
        `pixel_size`: a photo's leaf length or pixel size, `base_end` its base's end,
        photo_import.py). A newer open, a
        demo or a new sketch supersedes it; a failure reports `open_failed` and keeps the
        document."""
        if self._open_due is not None:
            self._open_due.cancel()  # the file being read is superseded
        self._open_run = None  # an earlier file's first run: this file's replaces it
        what = "photo" if is_photo(path) else "scan" if as_scan else "file"
        self.opening.emit(path, what)
        job = self._open_due = self.run(
            "open", read_document, path, as_scan, length, pixel_size, base_end
        )
        job.on_progress(lambda fraction, doing: self._open_progress(job, fraction, doing))
        job.on_done(lambda document: self._opened(job, document))
        job.on_failed(lambda exc: self._open_failed(job, what, exc))
        return job

    def cancel_open(self) -> bool:
        """Stop opening a file (Cancel): while it is read, the reading job is asked to stop at
        its next step and its answer is dropped, the document stays; during its first
        reconstruction, that is stopped and the previous document comes back (none: an empty
        sketch). `open_cancelled` says so. False when no file is being opened."""
        job, self._open_due = self._open_due, None
        if job is not None:
            job.cancel()
        elif self._open_run is not None:
            self._cancel_first_run()
        else:
            return False
        self.open_cancelled.emit()
        self.open_ended.emit()
        return True

    def _cancel_first_run(self) -> None:
        """Stop the opened file's first reconstruction (and any request after it), drop what
        they may still answer, and bring the previous document back."""
        first, self._open_run = self._open_run, None
        for request in [r for r in self._requested if r >= first]:
            self.cancel_request(request)
        self._ignored_upto = self.last_id  # a result already on its way is not shown
        if not self._restore_fallback():
            self.new_sketch()

    def open_settled(self, request_id: int) -> None:
        """Request `request_id` was shown or failed: the opened file's first result, if it is
        (or a later one), ends the opening."""
        if self._open_run is not None and request_id >= self._open_run:
            self._open_run = None
            self.open_ended.emit()

    def _open_progress(self, job: Job, fraction: float | None, doing: str) -> None:
        if job is self._open_due:
            self.open_progress.emit(fraction, doing)

    def _opened(self, job: Job, document: Document) -> None:
        if job is not self._open_due:
            return
        self._open_due = None
        d = document
        params = d.params or self.params
        request = self.open_document(
            d.leaf,
            d.sketch,
            d.title,
            params=params,
            path=d.path,
            scan=d.scan,
            photo=d.photo,
            unposed=d.unposed,
        )
        self.opened.emit(d.path)
        if d.notice:
            self.noticed.emit(d.notice)
        if request and self.shown_id < request:  # Cancel now stops its first reconstruction
            self._open_run = request
            self.open_progress.emit(None, "reconstructing")
        else:
            self.open_ended.emit()

    def _open_failed(self, job: Job, what: str, exc: BaseException) -> None:
        if job is self._open_due:
            self._open_due = None
            self.open_failed.emit(what, describe(exc))
            self.open_ended.emit()


def missing_photo_message(photo: LeafPhoto) -> str:
    """What the window says when a leaf's photo is not where its project says."""
    return (
        f"The photo this leaf was found in is missing ({photo.image}): the leaf shows and exports "
        "the texture generated from it instead. Put the photo back and open the project again "
        "to use it; saving keeps the photo's place in the project."
    )


def photo_length(text: str) -> float | None:
    """The length a photo's leaf is made with, from File > Open photo's field: a length with
    its unit ('8cm', '80mm', '0.08m') gives the leaf in millimetres (what a thickness with a
    unit and Export's real length expect), a bare number the leaf's own units; empty: None
    (length 1). LeafError for anything else.

    Examples
    --------
    >>> photo_length("8cm"), photo_length("2.5"), photo_length(" ")
    (80.0, 2.5, None)
    """
    from leafstudio.assets.placement import parse_length

    text = text.strip()
    if not text:
        return None
    if has_unit(text):
        try:
            return round(parse_length(text) * 1000, 9)
        except LeafError as exc:  # said in the dialog's words, not the command line's
            raise LeafError(exc.problem.replace("--length", "the length")) from None
    value = float(text)
    if not (value > 0 and value != float("inf")):
        raise LeafError(f"the leaf's length must be above 0, got {text}")
    return value


def has_unit(text: str) -> bool:
    """Whether a length field's text is more than a bare number (a real size: '8cm')."""
    try:
        float(text)
    except ValueError:
        return bool(text.strip())
    return False
