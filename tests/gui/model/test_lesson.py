"""The lesson mode's walk and pictures, without Qt (issue 22, "What to build" 2)."""

from __future__ import annotations

import io
import re

import numpy as np
import pytest
from PIL import Image

from leafstudio.gui.model.layers import LAYERS
from leafstudio.gui.model.lesson import Lesson, equation_png, plan_png
from leafstudio.render.lesson import LESSON_STEPS


def test_every_step_shows_layers_the_app_has_in_two_or_three_plain_sentences():
    keys = {key for key, _, _ in LAYERS}
    for step in LESSON_STEPS:
        assert step.layers and set(step.layers) <= keys, step.title
        sentences = [s for s in re.split(r"(?<=[.!?])\s+", step.caption) if s]
        assert 2 <= len(sentences) <= 3, step.title
        for jargon in ("MPU", "PCA", "eq.", "eqs."):  # the paper's language stays in the paper
            assert jargon not in step.caption, (step.title, jargon)


def test_the_lesson_moves_and_stops_at_its_ends():
    lesson = Lesson()
    assert not lesson.back() and lesson.index == 0
    assert lesson.next() and lesson.progress() == f"Step 2 of {len(LESSON_STEPS)}"
    lesson.go(99)
    assert lesson.step is LESSON_STEPS[-1] and not lesson.next()


@pytest.mark.parametrize("index", range(len(LESSON_STEPS)))
def test_each_step_has_a_plan_view_and_its_equation_typeset(demo_result, index):
    result = demo_result("nested")
    image = Image.open(io.BytesIO(plan_png(result, index, (480, 360))))
    assert image.size == (480, 360)
    assert len(np.unique(np.asarray(image.convert("L")))) > 20  # drawn, not blank
    tex = LESSON_STEPS[index].equation
    if tex:
        equation = Image.open(io.BytesIO(equation_png(tex, dpi=96)))
        assert equation.size[0] > 100 and equation.size[1] >= 22  # at EQUATION_PT points
    else:
        assert equation_png(tex) == b""
