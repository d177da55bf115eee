"""The lesson's steps in plain words: what each step of the method does, for a first-year
student, with its equation typeset by matplotlib's mathtext. `leafstudio slides` and the app's
slides write them; they sit here, below the app, so that the command line has them too.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class LessonStep:
    """One step of the method.

    Attributes
    ----------
    title : str
        A short title.
    caption : str
        Two or three plain sentences.
    equation : str
        The step's formula as matplotlib mathtext ("" for none).
    layers : tuple of str
        The app's layers that show it (gui/model/layers.LAYERS keys).
    picture : str
        What its picture draws (render/step_slides.step_picture): "points", "plane",
        "implicit", "guide", "em", "heights" or "mesh".
    edges : bool, default: False
        Whether the app's 3D view draws the mesh's triangle edges.
    bent_caption : str, default: ""
        The caption for a bent leaf (folded, curled, rolled or twisted), where the step differs
        ("": the same).
    flat : bool, default: False
        Whether the step works on the blade laid flat: a bent leaf's 3D view then shows its
        outline and input points laid flat (the app's "blade" layer) in place of the bent ones,
        where the step's fields lie (gui/model/lesson.step_layers).
    """

    title: str
    caption: str
    equation: str
    layers: tuple[str, ...]
    picture: str
    edges: bool = False
    bent_caption: str = ""
    flat: bool = False

    def words(self, bent: bool = False) -> str:
        """The caption, for a bent leaf if `bent` (its steps run on the blade laid flat)."""
        return self.bent_caption if bent and self.bent_caption else self.caption


LESSON_STEPS: tuple[LessonStep, ...] = (
    LessonStep(
        "1. Points on the leaf",
        "We start from points measured on the leaf: along its edge (black) and along its veins "
        "(in colour), as a scanner or a drawing gives them. Each point has its own x, y and z.",
        r"$\mathbf{p}_i = (x_i,\ y_i,\ z_i)$",
        ("points",),
        "points",
    ),
    LessonStep(
        "2. The leaf's plane",
        "We lay the points on the flat plane that fits the edge best, like pressing the leaf "
        "onto a table, and join the edge's points into an outline. Every height is then "
        "measured above that plane: the veins' heights are in colour.",
        r"$\mathrm{height} = (\mathbf{p} - \mathbf{o}) \cdot \mathbf{n}$",
        ("points", "curves"),
        "plane",
        bent_caption="This leaf is bent. We first unbend it (its fold, curl, roll or twist, or "
        "a scanned leaf's own curves) and lay the blade flat, like pressing the leaf onto a "
        "table; the edge's points "
        "are joined into an outline. Every height is then measured above that flat blade: the "
        "veins' heights are in colour.",
        flat=True,
    ),
    LessonStep(
        "3. Inside or outside the leaf",
        "A smooth function g tells every point of the plane whether it lies on the leaf: "
        "positive inside (blue), negative outside (red). The line where g is zero is the leaf's "
        "edge.",
        r"$g(\mathbf{x}) > 0$ inside,   $g(\mathbf{x}) = 0$ on the edge",
        ("implicit", "contour", "points"),  # g over the surface (gui/model/fields.py)
        "implicit",
        flat=True,
    ),
    LessonStep(
        "4. Where the leaf rises",
        "Each point of the blade takes the height h of the nearest vein, fading to nothing "
        "at the edge. This map p(x) is a guess of the relief: bright where the leaf stands "
        "high.",
        r"$p(\mathbf{x}) = h_v \, \left(1 - \frac{|v' - \mathbf{x}|}{2\,|v' - v''|}\right)$",
        ("probability", "points"),
        "guide",
        flat=True,
    ),
    LessonStep(
        "5. Points where the leaf is high",
        "We scatter points over the blade, more where p(x) is large. A few bell-shaped hills "
        "(Gaussians) are fitted to them: each colour is the points one hill gathers, and each "
        "ellipse shows the hill's width (one and two standard deviations).",
        r"$\mathbf{x}_i \to \arg\max_k \, \pi_k \, N(\mathbf{x}_i \mid \mu_k, \Sigma_k)$",
        ("em", "points"),
        "em",
        flat=True,
    ),
    LessonStep(
        "6. The hills make the surface",
        "The hills are added up and scaled to the veins' heights. A factor tanh(g/δ) brings "
        "the sum down to zero at the edge, so the surface meets the outline exactly.",
        r"$z(\mathbf{x}) = b(\mathbf{x}) + \tanh(g/\delta) \, \sum_k a_k \, "
        r"N(\mathbf{x} \mid \mu_k, \Sigma_k)$",
        ("mesh",),  # coloured by height (lesson_view.py); the samples layer: a pink mass
        "heights",
        # its plan is z on the flat blade, its 3D view the mesh bent back (closing32: the words
        # told of the flat blade only, beside a folded leaf)
        # (review33: a slide has the map only, and a scan is bent by its sheet, not a pose)
        bent_caption="The hills are added up over the flat blade (the map), and tanh(g/δ) "
        "brings the sum to zero at the edge. The surface is then bent back into the leaf's own "
        "shape, coloured by the same heights.",
    ),
    LessonStep(
        "7. The leaf in 3D",
        "The surface is cut into small triangles and trimmed at the edge: this is the mesh, "
        "coloured by height. With more hills (a larger K) it can follow more veins.",
        "",
        ("mesh", "points"),
        "mesh",
        edges=True,
        # coloured as step 6: by the height above the flat blade, not how high it stands now
        # (qa37: "coloured by height" beside a folded leaf's raised halves, dark, read as low)
        bent_caption="The surface is cut into small triangles and trimmed at the edge, then "
        "bent back into the leaf's own shape: this is the mesh, coloured by its height above "
        "the flat blade, as in step 6. With more hills (a larger K) it can follow more veins.",
    ),
)
