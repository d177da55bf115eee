"""The lesson mode's walk and pictures, without Qt (issue 22, "What to build" 2)."""

from __future__ import annotations

import io
import re

import numpy as np
import pytest
from PIL import Image

from leafstudio.gui.model.layers import LAYERS
from leafstudio.gui.model.lesson import Lesson, bent_notes, equation_png, plan_png, step_layers
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


@pytest.fixture(scope="module")
def folded():
    """An ovate form folded 60° along its midrib, reconstructed (FAST)."""
    from leafstudio.core.pipeline import Pipeline
    from leafstudio.forms.make import Form
    from tests.gui.builders import FAST

    return Pipeline(Form("ovate", fold=60.0).leaf()).run(FAST)


def _drawn_points(result, keys) -> tuple[np.ndarray, np.ndarray]:
    """The input's dots the 3D view draws among layers `keys` (as given or laid flat): (n, 3)
    the boundary's and (m, 3) the veins'."""
    from leafstudio.gui.model.layers import build_layers

    layers = build_layers(result)
    inputs = [p for key in keys if key in ("points", "blade") for p in layers[key]]
    dots = [p for p in inputs if "point_size" in p.style]
    boundary = [np.asarray(p.data.points) for p in dots if p.name.endswith("boundary")]
    veins = [np.asarray(p.data.points) for p in dots if not p.name.endswith("boundary")]
    return np.vstack(boundary), np.vstack(veins)


@pytest.mark.parametrize("picture", ["implicit", "guide", "em"])
def test_a_folded_leafs_flat_steps_draw_its_points_laid_flat_on_the_blade(folded, picture):
    """Steps 3-5 drew g, p(x) and the EM samples on the flat blade and the folded input points
    over them: an ovate form folded 60° had its margin's dots up to 0.095 of its length off the
    outline in the blade's plane, its dots up to 0.28 of it off the flat blade's surface. Drawn
    laid flat (the "blade" layer), each boundary dot is on the outline and each dot on the flat
    blade's surface (BLADE_LIFT above it, over the fields), and the lesson says so once."""
    from leafstudio.gui.model.layers import BLADE_LIFT

    step = next(s for s in LESSON_STEPS if s.picture == picture)
    boundary, veins = _drawn_points(folded, step_layers(step, bent=True))
    frame, polygon, length = folded.frame, folded.polygon, folded.length
    for points in (boundary, veins):
        xy, height = frame.to_plane(points)
        off = height - folded.height(xy) - BLADE_LIFT * length
        assert np.abs(off).max() < 2e-3 * length, np.abs(off).max() / length  # measured 7e-4
    xy, _ = frame.to_plane(boundary)
    gap = _distance_to_ring(xy, np.vstack([polygon, polygon[:1]]))
    assert gap.max() < 1e-3 * length, gap.max() / length
    assert bent_notes()[0].startswith("Steps 2–5 work on the leaf laid flat; from step 6 on")


def _distance_to_ring(xy: np.ndarray, ring: np.ndarray) -> np.ndarray:
    """(n,) each point's distance to the closed polyline `ring` ((m + 1, 2), first point last)."""
    a, b = ring[:-1], ring[1:]
    d = b - a
    t = np.clip(((xy[:, None] - a) * d).sum(-1) / np.maximum((d * d).sum(-1), 1e-30), 0, 1)
    return np.linalg.norm(xy[:, None] - (a + t[..., None] * d), axis=2).min(axis=1)


def test_a_folded_leafs_lesson_frames_it_laid_flat_and_bent_alike(folded):
    """Framed on its folded mesh alone, the laid-flat blade of steps 2-5 reached past the 3D
    view's box across the blade (1/cos 30° of the folded width); one framing holds both."""
    from leafstudio.gui.model.framing import blade_bounds
    from leafstudio.gui.model.lesson import lesson_bounds

    frame, width = folded.frame, np.ptp(folded.polygon[:, 1])
    alone = blade_bounds(folded.triangle_mesh.points, frame)
    both = lesson_bounds(folded, frame)
    assert alone.hi[1] - alone.lo[1] < width  # the flat blade did not fit
    assert both.lo[1] < folded.polygon[:, 1].min() and both.hi[1] > folded.polygon[:, 1].max()
    assert both.hi[2] - both.lo[2] > 0.95 * (alone.hi[2] - alone.lo[2])  # the fold's height kept


def test_a_bent_leafs_step_6_says_its_surface_is_bent_back_beside_the_flat_map():
    """closing32: step 6's words told of z on the flat blade beside a folded leaf in 3D (its
    plan is z on the flat blade, its 3D view the mesh bent back, coloured by the same z)."""
    step = next(s for s in LESSON_STEPS if s.picture == "heights")
    assert not step.flat and "bent" not in step.words(bent=False)
    words = step.words(bent=True)
    assert "flat blade" in words and "bent back" in words and "tanh" in words
    # review33: a slide of step 6 has the map only (no "In 3D"), and a scan is bent by its own
    # sheet, not by a pose: the words name a pose's terms only beside a scan's
    assert "In 3D" not in words
    for each in LESSON_STEPS:
        said = each.words(bent=True)
        assert "or twist" not in said or "scanned leaf" in said, each.title


def test_a_bent_leafs_step_7_says_its_colours_are_the_relief_not_how_high_it_stands(folded):
    """qa37: step 7 said "this is the mesh, coloured by height" beside an ovate form folded
    45°, whose colours are its height above the flat blade (0 to 0.078 of its length, yellow at
    the midrib) while its halves stand up to 0.244: a class reads the raised halves, dark, as
    low. The words say which height the colours are."""
    heights = np.asarray(folded.triangle_mesh.point_data["height"])
    assert np.allclose(heights, folded.mesh_on_blade()[1])  # the colours: the flat blade's
    step = next(s for s in LESSON_STEPS if s.picture == "mesh")
    assert "above the flat blade" in step.words(bent=True)
    assert "flat blade" not in step.words(bent=False)


def test_step_5s_gaussians_have_one_colour_in_the_plan_and_in_3d(folded):
    """closing32: the plan coloured Gaussian k with tab10's k-th colour, the 3D view with
    tab10 less its orange: the second hill was orange in the plan and green in 3D."""
    from matplotlib.colors import to_hex
    from matplotlib.figure import Figure

    from leafstudio.gui.model.fields import em_pieces
    from leafstudio.render.step_slides import step_picture

    index = next(i for i, s in enumerate(LESSON_STEPS) if s.picture == "em")
    ax = Figure().add_subplot()
    step_picture(ax, folded, index)
    plan = {to_hex(c) for c in ax.collections[0].get_facecolors()}
    shown = {p.style["color"] for p in em_pieces(folded) if not p.name.startswith("em:ellipse")}
    ellipses = {to_hex(p.get_edgecolor()) for p in ax.patches}
    k = len(folded.em_mixture.weights)
    assert k >= 2 and plan == shown and ellipses == shown and len(shown) == k
