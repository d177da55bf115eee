"""View > Compare forms and Help > Glossary of leaf terms (issue 22, "What to build" 4)."""

from __future__ import annotations

import re

import pytest
from PySide6.QtWidgets import QApplication, QLabel

from leafstudio.forms.glossary import COMPARISONS, PICTURED
from leafstudio.gui.qt.compare_view import CompareDialog, comparison_title, export_slides
from leafstudio.gui.qt.glossary_view import GlossaryDialog
from leafstudio.render.lesson import LESSON_STEPS
from tests.gui.qt.conftest import exported, image_pixels


def _open(window, action: str, kind):
    window.actions[action].trigger()
    QApplication.processEvents()
    return next(d for d in window.findChildren(kind) if d.isVisible())


def test_compare_shows_two_or_four_forms_side_by_side_with_their_terms(window, qtbot):
    window.forms_panel.compare_button.click()  # the Forms dock's button, as View > Compare forms
    QApplication.processEvents()
    dialog = next(d for d in window.findChildren(CompareDialog) if d.isVisible())
    assert window.compared == COMPARISONS["ovate beside obovate"]
    leaves = [ax for ax in dialog.figure.axes if ax.patches]
    assert len(leaves) == 2
    assert not dialog.picture.pixmap().isNull()
    dialog.preset.setCurrentText("four margins")
    assert [f.margin for f in window.compared] == ["entire", "serrate", "crenate", "lobed"]
    assert len([ax for ax in dialog.figure.axes if ax.patches]) == 4
    dialog.boxes[1]["margin"].setCurrentText("dentate")  # a term changed in place
    assert window.compared[1].margin == "dentate"
    texts = [t.get_text() for ax in dialog.figure.axes for t in ax.texts]
    assert "dentate margin" in texts
    dialog.close()


def test_a_compared_form_takes_its_shapes_usual_venation_unless_one_is_chosen(window):
    """The venation chooser's "(usual)" is the shape's own (Form.venation None): a form turned
    reniform there was drawn pinnate, the chooser showing its first entry."""
    window.forms_panel.compare_button.click()
    QApplication.processEvents()
    dialog = next(d for d in window.findChildren(CompareDialog) if d.isVisible())
    assert [b["venation"].currentText() for b in dialog.boxes] == ["(usual)", "(usual)"]
    dialog.boxes[1]["shape"].setCurrentText("reniform")
    assert window.compared[1].venation_term == "palmate"
    dialog.boxes[1]["venation"].setCurrentText("pinnate")
    assert window.compared[1].venation_term == "pinnate"
    dialog.close()


def test_the_glossary_draws_every_term(window):
    dialog = _open(window, "help.glossary", GlossaryDialog)
    assert set(dialog.pictures) == {(k, t) for k, terms in PICTURED.items() for t in terms}
    acute, emarginate = (
        image_pixels(dialog.pictures["apex", term].pixmap().toImage())
        for term in ("acute", "emarginate")
    )
    assert (acute != 0).any() and (acute != emarginate).any()
    assert acute.shape[:2] == (96, 96)
    dialog.close()


def test_the_glossarys_pictures_grow_with_the_dialog(window, qtbot):
    """On a projector a class read 96-pixel pictures on a maximised dialog: they grow with it
    (a fifth of its width, a quarter of its height, at most 256 pixels), the words with them,
    and shrink back."""
    dialog = _open(window, "help.glossary", GlossaryDialog)
    size = lambda: dialog.pictures["base", "cuneate"].pixmap().width()  # noqa: E731
    name = next(label for label in dialog.findChildren(QLabel) if label.text() == "<b>cuneate</b>")
    words = name.font().pointSizeF()
    assert size() == 96
    dialog.resize(1400, 1100)
    qtbot.waitUntil(lambda: size() == 256, timeout=5000)
    assert name.font().pointSizeF() == pytest.approx(1.5 * words)
    dialog.resize(1400, 720)  # a projector's height
    qtbot.waitUntil(lambda: size() == 144, timeout=5000)
    drawn = image_pixels(dialog.pictures["base", "cuneate"].pixmap().toImage())
    assert (drawn != 0).mean() > 0.05  # a picture, not an empty square
    dialog.resize(620, 640)  # as it opens (the window, and this dialog, serve other tests)
    qtbot.waitUntil(lambda: size() == 96, timeout=5000)
    dialog.close()


def test_export_slides_writes_the_steps_and_the_forms_compared(window, qtbot, tmp_path):
    window.compared = COMPARISONS["serrate beside dentate"]
    # to a .pdf alone: a folder's PNG per slide drew every slide twice (3-4 s of CPU), and the
    # folder is the same call (tests/render/test_step_slides.py writes one)
    pdf = tmp_path / "lesson.pdf"
    job = export_slides(window, str(pdf))
    assert job is not None and not job.finished  # drawn and written off the main thread
    assert exported(qtbot, job)
    slides = len(LESSON_STEPS) + 1  # every step, then the comparison
    written = pdf.read_bytes()
    assert written.startswith(b"%PDF") and list(tmp_path.iterdir()) == [pdf]
    assert len(re.findall(rb"/Type\s*/Page\b", written)) == slides  # a page each (not /Pages)
    assert comparison_title(window.compared) == "serrate beside dentate"
    assert "file.export_slides" in window.actions


def test_the_glossary_draws_shapes_upright_as_their_words_say(qapp):
    """'ovate: widest in the lower two fifths, rounded below, narrower above' was drawn lying
    on its side, apex right (while Compare forms and the slides draw it upright): the glossary's
    pictures now stand apex up, the widest part of an ovate blade below its middle."""
    import numpy as np

    from leafstudio.gui.qt.glossary_view import term_image

    for term in ("ovate", "lanceolate", "obovate"):
        pixels = image_pixels(term_image("shape", term))
        rows, cols = np.nonzero(pixels.sum(axis=-1) > 0)  # painted (transparent: black)
        assert np.ptp(rows) > 1.2 * np.ptp(cols), term  # taller than wide: standing
        widths = np.bincount(rows, minlength=pixels.shape[0])
        widest = np.argmax(widths)
        below = widest > (rows.min() + rows.max()) / 2  # rows count down
        assert below == (term != "obovate"), term


def test_export_slides_draws_a_drawn_leaf_as_the_lesson_shows_it(window, qtbot, monkeypatch):
    """review35: the lesson shows a leaf drawn at 40° at its angle (the app's view, its
    sketch's frame: step_slides.plan_frame), but File > Export slides, "the lesson's steps on
    the shown leaf", drew them on the result's view frame, the leaf level. The export is given
    the lesson's frame, and its slides are drawn on it."""
    import numpy as np

    from leafstudio.render import step_slides
    from leafstudio.render.step_slides import plan_frame
    from tests.gui.qt.conftest import wait_result
    from tests.leaves import clicked_sketch

    window.session.new_sketch()
    sketch = clicked_sketch(turn=40.0)
    window.session.commit_sketch(sketch, "Draw")
    wait_result(qtbot, window, lambda o: o.result.leaf is window.session.state.leaf)
    result = window.session.result
    runs = []
    monkeypatch.setattr(window, "run_export", lambda _name, *run, **kw: runs.append((run, kw)))
    export_slides(window, "lesson.pdf")
    ((write, *args), given) = runs[0]
    frame = given["frame"]
    np.testing.assert_allclose(frame.u, plan_frame(result, sketch.frame).u)  # the lesson's
    assert abs(frame.u @ plan_frame(result).u - np.cos(np.radians(40.0))) < 0.05  # not level
    drawn = []
    monkeypatch.setattr(step_slides, "lesson_slides", lambda *a: drawn.append(a[2]) or [])
    monkeypatch.setattr(step_slides, "write_slides", lambda *a: [])
    write(*args, progress=lambda *a: None, **given)
    assert drawn == [frame]
