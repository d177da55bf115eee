"""A lesson as slides: one slide per step of the method on a leaf (render/lesson.LESSON_STEPS:
the step's picture, its title, its caption in plain words and its equation), then the forms
compared side by side (render/forms_figure); written as a PNG per slide and one PDF
(matplotlib's PdfPages). `leafstudio slides` and the app's File > Export slides write them.

The steps' pictures are plan views of the leaf's plane, drawn with matplotlib at the result's
unit size (each step's `picture`): the input's points as given, seen from 50° above the plane;
the outline on the plane with the veins' heights above it; g with its zero contour; p(x); the EM
samples coloured by the Gaussian of EM's mixture that owns each, with each Gaussian's 1σ and 2σ
ellipses; the mixture's heights; and the mesh (render/slides.mesh_image, off screen). Each field
has its colour bar, its ticks as many as its length holds apart (FittingTicks).

Every picture is drawn on one frame of the leaf's plane (`plan_frame`), the input's points of
step 1 too (they were drawn in the file's own axes: the nested demo turned 90° in its file ran
55° up step 1's picture and level in the others), as the mesh's picture is, and as the lesson's
3D view looks at the leaf. By default the result's view frame (u along its midrib, base to apex,
a quarter or half turn from the plane's): on soybean pot1_1's lesson the plan had turned its
flat blade by the unbent leaf's midrib (`view_frame` of the result at unit size, whose leaf is
not bent), the 3D view by its flat blade's: the apex at the upper left in one, the right in the
other. The lesson, and the app's File > Export slides, give the frame of the app's main view
instead (a drawn leaf's sketch, at the angle it was drawn), so that a class sees the leaf as it
was drawn, on the screen and on the slides alike.
"""

from __future__ import annotations

import os
import textwrap
from pathlib import Path
from typing import Any

import numpy as np

from leafstudio.core.bend import flat_leaf
from leafstudio.core.evaluate import view_frame
from leafstudio.core.plane import Frame, turned_like
from leafstudio.errors import LeafError
from leafstudio.model import Leaf
from leafstudio.render.lesson import LESSON_STEPS, LessonStep

SLIDE_SIZE = (16.0, 9.0)  # inches
DPI = 100  # 1600 x 900 pixels per slide
TITLE_PT, TEXT_PT, EQUATION_PT = 28, 19, 22
TITLE_CHARS = 26  # characters per title line
CAPTION_CHARS = 40  # characters per caption line in the right-hand column
# a colour per Gaussian, its EM samples' and ellipses' here and in the app's 3D view
# (gui/model/fields.py): matplotlib's tab10 without its orange, the zero contour's there. The
# plan took tab10 whole, so a Gaussian was orange in the plan and green in 3D (closing32)
GAUSSIAN_COLORS = (
    "#1f77b4", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#bcbd22",
)  # fmt: skip
BOUNDARY, VEINS = "#202020", "#d62728"
TICK_PT = TEXT_PT - 4  # a colour bar's tick labels
# step 1's view of the points, degrees above the leaf's plane: the lesson's 3D view's lower
# elevation (gui/qt/lesson_view.ELEVATIONS), so the picture beside it looks as it does (a
# cabinet view, u + 0.35 v across and h + 0.5 v up, drew soybean pot1_1's curled midrib
# diagonally beside the 3D view's upright one)
POINTS_ELEVATION = 50.0


def gaussian_color(k: int) -> str:
    """The colour of Gaussian k: its EM samples and ellipses, in the plan and in 3D."""
    return GAUSSIAN_COLORS[k % len(GAUSSIAN_COLORS)]


def blade_leaf(result: Any) -> Leaf:
    """The leaf on the flat blade its steps ran on, at unit size: a bent leaf's curves laid
    flat by its bend (core/bend.flat_leaf), or a plan view drew them where the bend projects
    them (a fold's veins squeezed to half the blade's width, at the fold's heights) over g, p
    and a mixture made on the flat blade."""
    flat = flat_leaf(result.leaf)
    return flat if result.units is None else result.units.leaf(flat)


def plan_frame(result: Any, like: Frame | None = None) -> Frame:
    """The frame the pictures show `result` on, u to the right, v up, which the lesson's 3D
    view looks at too: the result's plane turned about its normal so that u runs as `like`'s
    (the app's main view's: plane.turned_like), or by default its view frame (evaluate.view_frame:
    u along the midrib of its flat blade, base to apex)."""
    return view_frame(result) if like is None else turned_like(result.frame, like)


def plan_turn(result: Any, shown: Frame | None = None) -> np.ndarray:
    """(2, 2) float array taking the plane's coordinates (unit.frame's, whose axes are the
    result's) to the picture's, on `shown` (default: plan_frame's, a quarter or half turn or
    none; any turn, mirrored where `shown` sees the plane from below)."""
    shown, plane = shown or plan_frame(result), result.frame
    return np.array(
        [[shown.u @ plane.u, shown.u @ plane.v], [shown.v @ plane.u, shown.v @ plane.v]]
    )


def _plane(ax: Any, result: Any, frame: Frame) -> dict[str, Any]:
    """The arrays a plan view draws, at unit size (every array in one frame), "frame", the one
    they are shown on, and "shown", the transform that draws them on `ax` turned as plan_turn
    says."""
    from matplotlib.transforms import Affine2D

    unit = result.unit if result.unit is not None else result
    grid = unit.grid
    ny, nx = grid.shape
    x0, y0 = grid.origin
    extent = (x0, x0 + grid.spacing * (nx - 1), y0, y0 + grid.spacing * (ny - 1))
    points = blade_leaf(result).vein_points
    veins, heights = unit.frame.to_plane(points) if len(points) else (None, None)
    turn = np.eye(3)
    turn[:2, :2] = plan_turn(result, frame)
    return {
        "unit": unit,
        "frame": frame,
        "shape": (ny, nx),
        "extent": extent,
        "veins": veins,
        "heights": heights,
        "turn": turn[:2, :2],
        "shown": Affine2D(turn) + ax.transData,
    }


def _outline(ax: Any, plane: dict[str, Any], veins: bool = False) -> None:
    polygon, shown = plane["unit"].polygon, plane["shown"]
    ax.plot(*np.vstack([polygon, polygon[:1]]).T, color=BOUNDARY, linewidth=1.5, transform=shown)
    if veins and plane["veins"] is not None:
        ax.scatter(*plane["veins"].T, s=10, color=VEINS, zorder=3, transform=shown)


def _field(
    ax: Any, plane: dict[str, Any], values: np.ndarray, cmap: str, label: str, clip=False, **kw
):
    """A field of the grid as an image with its colour bar, labelled with its name; `clip`:
    shown inside the outline only (cut along the outline itself, not the grid's cells)."""
    image = ax.imshow(
        np.ma.masked_invalid(values.reshape(plane["shape"])),
        origin="lower",
        extent=plane["extent"],
        cmap=cmap,
        interpolation="bilinear",
        transform=plane["shown"],
        **kw,
    )
    if clip:
        from matplotlib.patches import Polygon

        image.set_clip_path(Polygon(plane["unit"].polygon, transform=plane["shown"]))
    _colour_bar(ax, image, label)
    return image


def _colour_bar(ax: Any, mappable: Any, label: str) -> None:
    """A horizontal colour bar under the picture, labelled, its ticks never touching."""
    from leafstudio.render.ticks import FittingTicks  # matplotlib: only when drawn

    bar = ax.figure.colorbar(mappable, ax=ax, orientation="horizontal", fraction=0.06, pad=0.04)
    bar.set_label(label, fontsize=TEXT_PT)
    bar.ax.tick_params(labelsize=TICK_PT)
    bar.formatter.set_powerlimits((-3, 4))  # 0.0889, not 8.89e-02; tinier ranges in 10^k
    bar.locator = FittingTicks(TICK_PT)


def _ellipse(
    ax: Any, mean: np.ndarray, cov: np.ndarray, sigmas: float, colour: Any, shown: Any
) -> None:
    from matplotlib.patches import Ellipse

    values, vectors = np.linalg.eigh(cov)
    angle = float(np.degrees(np.arctan2(vectors[1, 1], vectors[0, 1])))
    width, height = 2 * sigmas * np.sqrt(np.maximum(values[::-1], 0))
    ax.add_patch(
        Ellipse(
            mean,
            width,
            height,
            angle=angle,
            fill=False,
            color=colour,
            linewidth=2,
            linestyle="-" if sigmas == 1 else "--",
            transform=shown,
        )
    )


def _cropped(image: np.ndarray, margin: int = 12) -> np.ndarray:
    """The picture cut to what is not white background, with a small margin."""
    rows, cols = np.nonzero((image < 250).any(axis=2))
    if not len(rows):
        return image
    top, left = max(rows.min() - margin, 0), max(cols.min() - margin, 0)
    return image[top : rows.max() + margin, left : cols.max() + margin]


def step_picture(ax: Any, result: Any, index: int, frame: Frame | None = None) -> None:
    """Draw step `index` (LESSON_STEPS, its `picture`) of `result` on the matplotlib axes `ax`,
    on `frame` (default: plan_frame's)."""
    plane = _plane(ax, result, frame or plan_frame(result))
    unit, shown = plane["unit"], plane["shown"]
    picture = LESSON_STEPS[index].picture
    if picture == "implicit":
        g = np.asarray(unit.g_grid, dtype=float)
        span = float(np.abs(g).max()) or 1.0
        _field(ax, plane, g, "RdBu", "g(x): inside > 0 > outside", vmin=-span, vmax=span)
        ax.contour(
            g.reshape(plane["shape"]),
            [0.0],
            origin="lower",
            extent=plane["extent"],
            colors="black",
            linewidths=2.5,
            transform=shown,
        )
    elif picture == "guide":
        p = np.asarray(unit.p_grid, dtype=float)
        _field(ax, plane, p, "magma", "p(x): the height guide", clip=True)
    elif picture == "em":
        mixture = unit.em_mixture  # EM's own: the surface's is refined from it
        samples = np.asarray(unit.em_samples)
        owner = mixture.owners(samples)
        colours = [gaussian_color(k) for k in owner]
        ax.scatter(*samples.T, s=6, c=colours, zorder=2, transform=shown)
        for k, (mean, cov) in enumerate(zip(mixture.means, mixture.covariances, strict=True)):
            for sigmas in (1, 2):
                _ellipse(ax, mean, cov, sigmas, gaussian_color(k), shown)
    elif picture == "heights":
        z = unit.height(unit.grid.points)  # b(x) outside, where tanh(g/δ) is 0: cut off
        inside = z[unit.inside]
        _field(
            ax,
            plane,
            z,
            "viridis",
            "z(x): height above the plane",
            clip=True,
            vmin=float(inside.min()),
            vmax=float(inside.max()),
        )
    elif picture == "plane":
        _heights_on_plane(ax, plane)
    if picture == "mesh":
        from leafstudio.render.slides import mesh_image  # pyvista and VTK: only when asked for

        ax.imshow(_cropped(mesh_image(result, (960, 720), plane["frame"])))
    elif picture == "points":
        _points(ax, plane)
    else:
        if picture != "plane":
            _outline(ax, plane, veins=picture == "guide")
        ax.set_aspect("equal")
        outline = unit.polygon @ plane["turn"].T  # as shown
        lo, hi = outline.min(axis=0), outline.max(axis=0)
        pad = 0.06 * (hi - lo).max()
        ax.set_xlim(lo[0] - pad, hi[0] + pad)  # the leaf fills the picture (a wide Gaussian's
        ax.set_ylim(lo[1] - pad, hi[1] + pad)  # ellipse runs off it)
    ax.set_axis_off()


def _points(ax: Any, plane: dict[str, Any]) -> None:
    """The input's points as given, seen from POINTS_ELEVATION above the pictures' frame,
    from its -v side (u across, as the lesson's 3D view looks): dots, nothing joined."""
    unit, shown = plane["unit"], plane["frame"]
    leaf = unit.leaf
    axes = Frame(unit.frame.origin, shown.u, shown.v, shown.normal)  # at unit size
    rise = np.radians(POINTS_ELEVATION)

    def oblique(points: np.ndarray) -> np.ndarray:
        xy, z = axes.to_plane(points)
        return np.column_stack([xy[:, 0], np.sin(rise) * xy[:, 1] + np.cos(rise) * z])

    ax.scatter(*oblique(leaf.boundary).T, s=12, color=BOUNDARY, zorder=2)
    if len(leaf.vein_points):
        ax.scatter(*oblique(leaf.vein_points).T, s=12, color=VEINS, zorder=3)
    ax.set_aspect("equal")


def _heights_on_plane(ax: Any, plane: dict[str, Any]) -> None:
    """The outline on the leaf's plane (filled), and the vein points at their heights above it
    (in colour, with its bar)."""
    unit, shown = plane["unit"], plane["shown"]
    polygon = np.vstack([unit.polygon, unit.polygon[:1]])
    ax.fill(*polygon.T, color="#e8f3e0", zorder=1, transform=shown)
    ax.plot(*polygon.T, color=BOUNDARY, linewidth=1.5, zorder=2, transform=shown)
    if plane["veins"] is None:
        return
    veins, heights = plane["veins"], plane["heights"]
    dots = ax.scatter(*veins.T, s=14, c=heights, cmap="viridis", zorder=3, transform=shown)
    _colour_bar(ax, dots, "height above the plane")


def step_slide(
    result: Any, index: int, step: LessonStep | None = None, frame: Frame | None = None
) -> Any:
    """One slide: step `index`'s picture (on `frame`, default plan_frame's) on the left, its
    words and equation on the right.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure  # matplotlib: only when slides are asked for

    step = step or LESSON_STEPS[index]
    figure = Figure(figsize=SLIDE_SIZE)
    grid = figure.add_gridspec(1, 2, width_ratios=(1.45, 1.0), left=0.02, right=0.98, wspace=0.05)
    step_picture(figure.add_subplot(grid[0, 0]), result, index, frame)
    words = figure.add_subplot(grid[0, 1])
    words.set_axis_off()
    title = textwrap.fill(step.title, TITLE_CHARS)
    words.text(0, 0.95, title, fontsize=TITLE_PT, weight="bold", va="top")
    caption = textwrap.fill(step.words(bent=result.leaf.bend is not None), CAPTION_CHARS)
    words.text(
        0,
        0.95 - 0.09 * (title.count("\n") + 1),
        caption,
        fontsize=TEXT_PT,
        va="top",
        linespacing=1.4,
    )
    if step.equation:
        words.text(0, 0.12, step.equation, fontsize=EQUATION_PT, va="bottom")
    return figure


def lesson_slides(
    result: Any, comparisons: list[tuple[str, Any]] | tuple = (), frame: Frame | None = None
) -> list[Any]:
    """Every step's slide for `result` (its pictures on `frame`, default plan_frame's: the app
    gives the lesson's, so that its slides show a drawn leaf as the lesson does), then a slide
    per (title, forms) comparison."""
    from leafstudio.render.forms_figure import compare_figure

    slides = [step_slide(result, i, frame=frame) for i in range(len(LESSON_STEPS))]
    slides += [compare_figure(forms, title) for title, forms in comparisons]
    return slides


def slide_paths(out: str | os.PathLike, count: int) -> list[Path]:
    """The files `write_slides` writes for `count` slides to `out`: a .pdf alone, or in a
    folder a PNG per slide (slide_01.png, ...) and lesson.pdf."""
    out = Path(out)
    if out.suffix.lower() == ".pdf":
        return [out]
    if out.suffix and not out.is_dir():
        raise LeafError(
            "slides go to a folder (a PNG per slide and lesson.pdf) or a .pdf", str(out)
        )
    return [out / f"slide_{i + 1:02d}.png" for i in range(count)] + [out / "lesson.pdf"]


def write_slides(slides: list[Any], out: str | os.PathLike) -> list[Path]:
    """Write `slides` (matplotlib Figures) to `out` (see slide_paths), all or none
    (_shared/safewrite); returns the files written."""
    from matplotlib.backends.backend_pdf import PdfPages

    from leafstudio._shared.safewrite import replace_atomically, staged

    paths = slide_paths(out, len(slides))

    def pdf(tmp: str) -> None:
        with PdfPages(tmp) as pages:
            for figure in slides:
                pages.savefig(figure)

    with staged():
        for figure, path in zip(slides, paths[:-1], strict=False):
            replace_atomically(path, lambda tmp, f=figure: f.savefig(tmp, dpi=DPI, format="png"))
        replace_atomically(paths[-1], pdf)
    return paths
