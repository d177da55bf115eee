"""The Forms dock's documents without Qt (gui/model/form_documents.py): a form the gallery made
stays the form while its blade is unedited, its pose aside; edited, the dock's pose terms bend it
(appreview31, finding 2). And the sliders' terms through the units and back (bending.py)."""

from __future__ import annotations

import numpy as np

from leafstudio.core.bend import Pose
from leafstudio.forms import Form
from leafstudio.gui.model.bending import pose_terms, terms_pose
from leafstudio.gui.model.form_documents import GalleryForms
from leafstudio.gui.model.form_sketch import grow_blade
from leafstudio.gui.model.session import Session
from tests.gui.builders import FAST, Runner


def ovate_document() -> tuple[Session, GalleryForms]:
    """A session whose document is ovate folded 45, made as the Forms dock makes it."""
    form = Form("ovate", fold=45.0)
    _unposed, blade, _note, sketch = grow_blade(form)
    session, gallery = Session(Runner(), FAST), GalleryForms()
    session.new_document(form.leaf(blade), sketch, "ovate form")
    gallery.record(session.state, "ovate")
    return session, gallery


def test_a_form_bent_stays_the_form_and_edited_is_bent_by_the_docks_pose():
    session, gallery = ovate_document()
    assert gallery.action(session.state, picked=False) == "form"
    session.set_bend(Pose(fold=45.0, curl=0.5))  # the Parameters panel keeps the blade
    assert gallery.is_form(session.state) and gallery.shape(session.state) == "ovate"
    sketch = session.state.sketch
    session.commit_sketch(sketch.moved(-1, 5, sketch.boundary[5] * 1.05), "Move point")
    assert gallery.edited(session.state) and gallery.shape(session.state) == "ovate"
    assert gallery.action(session.state, picked=False) == "bend"
    assert gallery.action(session.state, picked=True) == "form"  # a shape picked: a new leaf
    session.undo()
    assert gallery.is_form(session.state)


def test_the_sliders_terms_keep_an_untouched_terms_exact_value():
    """A term at the figure shown keeps the pose's own value: a curl of 0.4996 shown as 0.5
    stays 0.4996 when only the roll moves; the roll moved is its share of a half turn."""
    pose, width = Pose(fold=45.0, curl=0.4996, roll=0.0), 0.35
    figures = {name: round(value, 2) for name, value in pose_terms(pose, width).items()}
    moved = terms_pose({**figures, "roll": 0.3}, width, (pose, figures))
    assert moved.curl == 0.4996 and moved.fold == 45.0
    assert np.isclose(moved.roll, 0.3 * np.pi / width)
    assert np.isclose(pose_terms(moved, width)["roll"], 0.3)
