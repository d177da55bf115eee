"""The shown result's side jobs, without Qt: the scan's distances (the measurements panel), the
Poisson surface (its layer) and the texture image (the Texture colouring).

Each starts on the side lane through the session's `run` when it is wanted and not there yet,
and answers through its own job handle (jobs.Job); an answer for a leaf no longer shown is
dropped. The window says what is wanted (`set_poisson`, `set_texture_shown`) and draws what the
events hand it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from leafstudio._shared.inputs import read_image
from leafstudio.assets.export import TEXTURES
from leafstudio.errors import LeafError
from leafstudio.gui.model.history import Event
from leafstudio.gui.model.jobs import Job, describe
from leafstudio.gui.model.textures import texture_image, texture_key
from leafstudio.model import Leaf
from leafstudio.sources.leafphoto import PhotoTexture

if TYPE_CHECKING:
    from leafstudio.gui.model.session import Session

FIDELITY_FAILED = "Scan → mesh distance"


class SideJobs:
    """The side jobs of a session's shown result.

    Events
    ------
    fidelity_shown()
        The scan's distances to the shown result are in (or failed): the panel refills.
    poisson_shown(list)
        The Poisson layer's pieces ([] when the layer is off or its surface no longer fits).
    texture_shown(ndarray, tuple)
        The texture image, (h, w, 3 or 4) uint8, and its key (textures.texture_key).
    note(str)
        A side job failed without harm, or the scan's distances warn: a few words the status
        line appends.
    """

    def __init__(self, session: Session) -> None:
        self.session = session
        self.poisson_on = False  # the Poisson layer is switched on
        self.texture_on = False  # the mesh shows the texture
        self.texture_key: tuple | None = None  # what the image on the mesh shows
        self._poisson_leaf: Leaf | None = None  # the leaf of the Poisson surface drawn or due
        self._texture_due: tuple[Job, tuple] | None = None  # the texture being made, its key
        self.fidelity_shown, self.poisson_shown = Event(), Event()
        self.texture_shown, self.note = Event(), Event()
        self._warnings: tuple[int, list[str]] = (-1, [])  # the scan's, for a result (request id)
        session.state_changed.connect(self._on_state)

    def _on_state(self, _state: object, reason: str) -> None:
        if reason in ("document", "undo", "fallback"):
            self.update_texture()

    def result_shown(self, outcome: Any) -> None:
        """A result is on screen: its scan distances, Poisson surface and texture as wanted."""
        session, result = self.session, outcome.result
        scan = session.state.scan
        if scan is not None:
            from leafstudio.gui.model.scans import fidelity_sections  # pyvista: scans only

            request = outcome.request.id
            job = session.run("fidelity", fidelity_sections, result, scan)
            job.on_done(lambda answer: self._fidelity(request, *answer))
            job.on_failed(self._fidelity_failed)
        self.update_poisson()
        self.update_texture()

    def _fidelity(self, request: int, sections: list, warnings: list[str]) -> None:
        if self.session.accept_fidelity(request, sections):
            self._warnings = (request, list(warnings))
            self.fidelity_shown.emit()
            for warning in warnings:  # the surface far from the scan, or folded back on itself
                self.note.emit(warning)  # a note of the status line's (status_line.py) as is

    def warnings_of(self, request: int) -> list[str]:
        """The scan's warnings about result `request` once its distances are in, [] before: the
        window says them with the result's own (its status line, set when the result is drawn,
        replaced a note that came in first; a `note` says those that come in later)."""
        shown, warnings = self._warnings
        return warnings if shown == request else []

    def _fidelity_failed(self, exc: BaseException) -> None:
        session = self.session
        if session.state.scan is not None:
            rows = [(FIDELITY_FAILED, [("Failed", describe(exc))])]
            session.accept_fidelity(session.shown_id, rows)
            self.fidelity_shown.emit()

    # --- the Poisson layer ---------------------------------------------------------------------
    def set_poisson(self, on: bool) -> None:
        """The Poisson layer switched on or off."""
        self.poisson_on = on
        self.update_poisson()

    def update_poisson(self) -> None:
        """Compute the Poisson surface of the shown leaf when its layer is on and it is not
        there yet; when the layer is off, forget a surface that no longer fits the leaf."""
        result = self.session.result
        leaf = result.leaf if result is not None else None
        if leaf is self._poisson_leaf:
            return
        if self.poisson_on and result is not None:
            from leafstudio.gui.model.scans import poisson_piece  # pyvista: the layer's only

            self._poisson_leaf = leaf
            job = self.session.run("poisson", poisson_piece, result)
            job.on_done(lambda piece: self._poisson(leaf, piece))
            job.on_failed(self._poisson_failed)
        else:
            self._poisson_leaf = None
            self.poisson_shown.emit([])

    def _poisson(self, leaf: Leaf | None, piece: Any) -> None:
        if leaf is self._poisson_leaf:
            self.poisson_shown.emit([piece])

    def _poisson_failed(self, exc: BaseException) -> None:
        self._poisson_leaf = None
        self.note.emit(f"Poisson failed: {describe(exc)}")

    # --- the texture ---------------------------------------------------------------------------
    def set_texture_shown(self, on: bool) -> None:
        """The mesh's colouring became, or stopped being, the texture."""
        self.texture_on = on
        self.update_texture()

    def update_texture(self) -> None:
        """Have the texture of the shown leaf made off the main thread when the mesh shows the
        texture and the one on it is not the leaf's (textures.py); `texture_shown` brings it."""
        session = self.session
        result = session.result
        if not self.texture_on or result is None:
            return
        source = session.texture()
        key = texture_key(result, source)
        if key == self.texture_key:  # on the mesh already: an image still being made is stale
            self._texture_due = None
            return
        if self._texture_due and self._texture_due[1] == key:
            return
        job = session.run("texture", texture_image, result, source)
        self._texture_due = (job, key)
        job.on_done(lambda image: self._texture(job, key, image))
        job.on_failed(lambda exc: self._texture_failed(job, exc))

    def new_leaf(self, result: Any) -> None:
        """A new document's first result: the image on the mesh is another leaf's, and goes,
        unless it shows this very leaf (the same key: a demo chosen again, a file reopened),
        which keeps it rather than making it again (about 0.3 s of CPU at a small grid)."""
        key = self.texture_key
        if key is not None and texture_key(result, self.session.texture()) != key:
            self.texture_key = None

    def _texture(self, job: Job, key: tuple, image: Any) -> None:
        if self._texture_due is None or self._texture_due[0] is not job:
            return
        self._texture_due = None
        self.texture_key = key
        self.texture_shown.emit(image, key)

    def _texture_failed(self, job: Job, exc: BaseException) -> None:
        if self._texture_due is None or self._texture_due[0] is not job:
            return
        self._texture_due = None
        message = describe(exc)
        session = self.session
        if session.texture() != "auto":  # an unreadable image: the generated texture
            session.chosen_texture = "auto"
            session.noticed.emit(f"Cannot show the texture: {message}. The generated one is shown.")
            self.update_texture()
        else:
            # a sentence before its aside: the status line's headline (status_line.py) read
            # "Texture (more under ⚠)" of "texture: {message}"
            self.note.emit(f"the generated texture could not be made: {message}")

    def texture_option(self, texture: Any) -> Any:
        """assets.export's `texture` for a choice: None is the session's (Session.texture);
        "photo" the photo the leaf was found in; an image is mapped through that photo's pixel
        map when the leaf has one (as `reconstruct PROJECT --texture IMAGE`), else stretched over
        the UV square. LeafError for a missing photo or an unreadable image."""
        session = self.session
        photo = session.state.photo
        if texture is None:
            return session.texture()
        if isinstance(texture, PhotoTexture) or texture in TEXTURES:
            return texture
        if texture == "photo":
            if photo is None or not photo.exists():
                where = photo.image if photo is not None else session.state.title
                raise LeafError("the photo this leaf was found in is missing", str(where))
            return photo.texture()
        read_image(str(texture))  # refused before any work
        return PhotoTexture(str(texture), photo.pixel_from_world if photo is not None else None)
