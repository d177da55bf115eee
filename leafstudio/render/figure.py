"""Off-screen figures of a reconstruction, in the spirit of the paper's Figs. 8-10.

An iso view and a top view side by side: the mesh coloured by height or a curvature, the input
boundary and vein points drawn over it, and one colour bar. Renders with pyvista off screen, so
no display is needed.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from leafstudio.core.trianglemesh import CURVATURE_ARRAYS, colour_range
from leafstudio.errors import LeafError

FIGURE_SCALARS = ("height", *CURVATURE_ARRAYS)
FIGURE_SUFFIX = ".png"
WINDOW_SIZE = (1800, 800)
POINT_SIZE = 7  # pixels
ISO_ZOOM = 1.25  # beyond the view that fits the leaf's bounding sphere
MARGIN = 1.12  # room around the leaf in the top view
BOUNDARY_COLOUR, VEIN_COLOUR = "#202020", "#d62728"
TITLES = {
    "height": "height",
    "mean_curvature": "mean curvature",
    "gaussian_curvature": "Gaussian curvature",
    "k1": "principal curvature k1",
    "k2": "principal curvature k2",
}


def check_figure_path(path: str | os.PathLike) -> Path:
    """The figure's path, or a LeafError if it is not a .png."""
    path = Path(path)
    if path.suffix.lower() != FIGURE_SUFFIX:
        raise LeafError("a figure must be a .png file", str(path))
    return path


def _top_scale(result: Any, window_size: tuple[int, int]) -> float:
    """Half the visible height of the top view that shows the whole leaf with a margin."""
    from leafstudio.core.evaluate import view_frame  # heavy (numba): not for the parser's choices

    xy, _ = view_frame(result).to_plane(result.triangle_mesh.points)
    half_length, half_width = np.ptp(xy, axis=0) / 2
    aspect = (window_size[0] / 2) / window_size[1]  # one panel's width / height
    return float(MARGIN * max(half_length / aspect, half_width * 1.6))


def _cameras(result: Any) -> dict[str, list[tuple[float, float, float]]]:
    """iso and top camera positions (position, focal point, view up) from the leaf's frame."""
    from leafstudio.core.evaluate import view_frame  # heavy (numba): not for the parser's choices

    frame = view_frame(result)
    mesh = result.mesh
    centre = np.asarray(mesh.center)
    size = float(np.linalg.norm(np.ptp(np.asarray(mesh.points), axis=0)))
    iso = -0.55 * frame.u - 0.8 * frame.v + 0.75 * frame.normal
    iso /= np.linalg.norm(iso)
    as_tuples = lambda *vs: [tuple(map(float, v)) for v in vs]  # noqa: E731
    return {
        "iso": as_tuples(centre + 2.2 * size * iso, centre, frame.normal),
        "top": as_tuples(centre + 2.2 * size * frame.normal, centre, frame.v),
    }


def render_figure(
    result: Any,
    path: str | os.PathLike,
    scalars: str = "height",
    window_size: tuple[int, int] = WINDOW_SIZE,
) -> Path:
    """Write a PNG: iso and top views of the result with the input points and a colour bar.

    Parameters
    ----------
    result : Result
        A reconstruction (its mesh must carry the `scalars` point array).
    path : str or PathLike
        A .png file; its folder is created.
    scalars : {"height", "mean_curvature", "gaussian_curvature", "k1", "k2"}, default: "height"
        The point array the mesh is coloured by.
    window_size : (int, int), default: (1800, 800)

    Returns
    -------
    Path
        The file written.
    """
    import pyvista as pv

    path = check_figure_path(path)
    if scalars not in FIGURE_SCALARS:
        raise LeafError(f"cannot colour by {scalars!r}; use one of {', '.join(FIGURE_SCALARS)}")
    mesh = result.mesh.copy()
    values = np.asarray(mesh.point_data[scalars])
    clim = colour_range(scalars, values)
    cmap = "viridis" if scalars == "height" else "coolwarm"
    clouds = [(result.leaf.boundary, BOUNDARY_COLOUR, "boundary")]
    if len(result.leaf.vein_points):
        clouds.append((result.leaf.vein_points, VEIN_COLOUR, "veins"))
    path.parent.mkdir(parents=True, exist_ok=True)
    with pv.vtk_verbosity("off"):
        plotter = pv.Plotter(off_screen=True, shape=(1, 2), window_size=list(window_size))
        plotter.set_background("white")
        for column, (view, camera) in enumerate(_cameras(result).items()):
            plotter.subplot(0, column)
            plotter.add_mesh(
                mesh,
                scalars=scalars,
                cmap=cmap,
                clim=clim,
                smooth_shading=True,
                show_scalar_bar=column == 1,
                scalar_bar_args={
                    "title": "",  # drawn above the bar instead: VTK sets it among the labels
                    "color": "black",
                    "vertical": False,
                    "position_x": 0.2,
                    "position_y": 0.1,
                    "width": 0.6,
                    "height": 0.08,
                    "fmt": "%.3g",
                    "title_font_size": 20,
                    "label_font_size": 16,
                },
            )
            if column == 1:
                plotter.scalar_bar.SetTextPositionToPrecedeScalarBar()  # labels under the bar
                plotter.add_text(
                    TITLES[scalars],
                    position=(int(0.2 * window_size[0] / 2), int(0.19 * window_size[1])),
                    font_size=12,
                    color="black",
                )
            for points, colour, label in clouds:
                plotter.add_points(
                    pv.PolyData(points),
                    color=colour,
                    point_size=POINT_SIZE,
                    render_points_as_spheres=True,
                    label=label,
                )
            plotter.add_text(f"{view} view", position="upper_left", font_size=14, color="black")
            if column == 0:
                plotter.add_legend(
                    bcolor="white", border=False, size=(0.14, 0.1), loc="lower left", face="circle"
                )
            plotter.camera_position = camera
            plotter.reset_camera()
            if view == "top":  # parallel projection, scaled so the leaf fills the panel's width
                plotter.enable_parallel_projection()
                plotter.camera.parallel_scale = _top_scale(result, window_size)
            else:
                plotter.camera.zoom(ISO_ZOOM)
        plotter.screenshot(str(path))
        plotter.close()
    return path
