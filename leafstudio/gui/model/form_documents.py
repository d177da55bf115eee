"""The Forms dock's documents, without Qt: which documents the gallery made, whether each is still
the form as made, and what a change of the dock's terms does to the open document
(appreview31, finding 2).

A form the gallery made stays the form while its flat blade (its sketch) is the one the gallery
drew: a change of any term makes the form anew, its pose the dock's (one undo step, "New leaf:
...": a pose alone only poses the blade kept, `Form.leaf(blade)`). Once the sketch is edited (a
point moved, veins grown), the document is the user's work: the dock's Fold, Curl, Roll and Twist
bend it as the Parameters panel's sliders do (`Session.set_bend`, one undo step, the edits kept),
and its other terms apply to the next shape picked in the gallery (a new leaf, one undo step), as
Blender's "Adjust last operation" panel stops applying once the mesh is edited. The pose terms
bend any other document too (a loaded or drawn leaf), and they show the document's pose, as the
Parameters panel's sliders do (`Session.pose` in the sliders' terms, `bending.pose_terms`).
Before, a pose term on an edited form made the form anew from its pristine blade: the edits and
the Parameters panel's curl were gone, and the dock's Curl read 0 while the leaf was curled 0.5.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from leafstudio.gui.model.history import State
from leafstudio.gui.model.sketch_model import Sketch


@dataclass(frozen=True)
class Made:
    """A document the gallery made: its form's shape and the sketch of the blade it drew."""

    shape: str
    sketch: Sketch


class GalleryForms:
    """The documents the Forms gallery made, by serial (Session's `State.serial`)."""

    def __init__(self) -> None:
        self._made: dict[int, Made] = {}

    def record(self, state: State, shape: str) -> None:
        """`state` is a form of `shape` the gallery just made the document."""
        if state.sketch is not None:
            self._made[state.serial] = Made(shape, state.sketch)

    def shape(self, state: State) -> str | None:
        """The shape of the form `state` is (edited or not), None for another document."""
        made = self._made.get(state.serial)
        return None if made is None else made.shape

    def is_form(self, state: State) -> bool:
        """Whether `state` is a form as the gallery made it, its pose aside: its flat blade
        unedited (the Parameters panel's sliders and the dock's pose keep the sketch)."""
        made = self._made.get(state.serial)
        return made is not None and state.sketch is made.sketch

    def edited(self, state: State) -> bool:
        """Whether `state` is a form the gallery made whose sketch was edited since."""
        return state.serial in self._made and not self.is_form(state)

    def action(self, state: State, picked: bool) -> Literal["form", "bend"]:
        """What a change in the dock does with `state` open: "form" makes the dock's form the
        document (a shape picked, or the document is the form unedited); "bend" bends the
        document by the dock's pose terms, its other terms kept for the next shape picked."""
        return "form" if picked or self.is_form(state) else "bend"
