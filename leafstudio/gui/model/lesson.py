"""The lesson mode's walk through the method (issue 22): where the class is among the steps
(render/lesson.LESSON_STEPS, the one list the slides share: title, plain caption, equation, the
app's layers that show the step), and each step's pictures as PNG bytes for the window: the plan
view (render/step_slides.step_picture, the slides' own drawing) and the equation typeset with
matplotlib's mathtext. No Qt here.
"""

from __future__ import annotations

import io

import numpy as np

from leafstudio.core.pipeline import Result
from leafstudio.core.plane import Frame
from leafstudio.gui.model.framing import BladeBounds, blade_bounds
from leafstudio.render.lesson import LESSON_STEPS, LessonStep

EQUATION_PT = 22  # the equation's size in points (the lesson's words are 18)
# the layers a bent leaf's flat steps show instead: its input laid flat on the blade (layers.py)
LAID_FLAT = {"points": "blade", "curves": "blade"}


def step_layers(step: LessonStep, bent: bool) -> tuple[str, ...]:
    """The layers the 3D view shows for `step`: its own, but on a bent leaf (`bent`) a step
    that works on the blade laid flat (`LessonStep.flat`) shows the input laid flat there,
    where its fields are (steps 3-5 drew g, p(x) and the EM samples on the flat blade under the
    folded points: an ovate form folded 60° had its margin's dots 0.095 of its length off the
    outline they belong on)."""
    if not (bent and step.flat):
        return step.layers
    return tuple(dict.fromkeys(LAID_FLAT.get(key, key) for key in step.layers))


def bent_notes(steps: tuple[LessonStep, ...] = LESSON_STEPS) -> tuple[str, ...]:
    """A bent leaf's lesson's note in plain words, fullest first (the lesson's footer shows the
    first that fits its column on one line, as it does its keys: lesson_view.FOOTERS): the
    steps that show it laid flat, then bent back, its relief unstretched (lesson_view's STRETCH
    is off for a bent leaf). The fullest alone made the footer 4 lines tall at 960 x 600 and 3
    at 1280 x 720 (soybean pot1_1, an ovate form folded 45°); under Xvfb's 14-point Sans the
    second takes 624 pixels (a 1920 wide lesson's column: 796), the third 465 (1280: 515), the
    last 323 (960: 374)."""
    flat = [i + 1 for i, step in enumerate(steps) if step.flat]
    if not flat or flat[-1] == len(steps):
        return (
            "The 3D leaf is drawn as it is bent, its relief not stretched.",
            "The 3D leaf is drawn as it is bent.",
        )
    laid, after = _span(flat[0], flat[-1]), flat[-1] + 1
    back = _span(after, len(steps))
    return (
        f"Steps {laid} work on the leaf laid flat; from step {after} on, it is bent back, its "
        "relief not stretched.",
        f"Steps {laid} on the leaf laid flat; {back} bent back, relief not stretched.",
        f"Steps {laid} laid flat; {back} bent, relief not stretched.",
        f"Steps {laid} laid flat; {back} bent back.",
    )


def _span(first: int, last: int) -> str:
    """Steps `first` to `last` as a class reads them: "2–5", or "7" alone."""
    return f"{first}–{last}" if last > first else f"{first}"


def lesson_bounds(result: Result, frame: Frame) -> BladeBounds:
    """The lesson's 3D framing of `result` on `frame` (framing.blade_bounds): its mesh's, and a
    bent leaf's mesh laid flat as well, so that one camera holds the blade both laid flat (the
    flat steps) and bent, and the class sees it unbend and bend back in place. Framed on the
    bent mesh alone, an ovate form folded 60° laid flat reached the 3D view's edges: its flat
    blade is 1/cos 30° = 1.15 times the folded one's width."""
    points = result.triangle_mesh.points
    if result.leaf.bend is not None:
        xy, height = result.mesh_on_blade()
        points = np.vstack([points, result.frame.to_world(xy, height)])
    return blade_bounds(points, frame)


class Lesson:
    """Where the class is in `steps`: `index`, moved by next/back/go (clamped)."""

    def __init__(self, steps: tuple[LessonStep, ...] = LESSON_STEPS) -> None:
        self.steps = steps
        self.index = 0

    @property
    def step(self) -> LessonStep:
        return self.steps[self.index]

    def go(self, index: int) -> bool:
        """Move to step `index` (clamped); True when the step changed."""
        index = max(0, min(index, len(self.steps) - 1))
        changed = index != self.index
        self.index = index
        return changed

    def next(self) -> bool:
        return self.go(self.index + 1)

    def back(self) -> bool:
        return self.go(self.index - 1)

    def progress(self) -> str:
        """ "Step 2 of 6", for the footer."""
        return f"Step {self.index + 1} of {len(self.steps)}"


def plan_png(
    result: Result,
    index: int,
    size: tuple[float, float],
    dpi: float = 96.0,
    frame: Frame | None = None,
) -> bytes:
    """Step `index`'s plan view of `result` as PNG bytes of `size` pixels.

    Parameters
    ----------
    result : Result
        The reconstruction the lesson shows.
    index : int
        The step (0-based, in LESSON_STEPS).
    size : (float, float)
        Width and height in pixels.
    dpi : float
        Pixels per inch (the screen's), so that the labels keep their point sizes.
    frame : Frame, optional
        The frame it is drawn on (step_slides.plan_frame), by default the result's view frame.

    Returns
    -------
    bytes
        A PNG image on white.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from leafstudio.render.step_slides import step_picture  # matplotlib: only when shown

    width, height = max(int(size[0]), 50), max(int(size[1]), 50)
    figure = Figure(figsize=(width / dpi, height / dpi), dpi=dpi, layout="constrained")
    FigureCanvasAgg(figure)
    step_picture(figure.add_subplot(), result, index, frame)
    out = io.BytesIO()
    figure.savefig(out, format="png", dpi=dpi, facecolor="white")
    return out.getvalue()


def equation_png(tex: str, dpi: float = 96.0, color: str = "black") -> bytes:
    """The mathtext `tex` typeset at EQUATION_PT points as PNG bytes ("" for none)."""
    if not tex:
        return b""
    from matplotlib.font_manager import FontProperties
    from matplotlib.mathtext import math_to_image

    out = io.BytesIO()
    math_to_image(
        tex, out, prop=FontProperties(size=EQUATION_PT), dpi=dpi, format="png", color=color
    )
    return out.getvalue()
