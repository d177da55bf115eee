"""Pictures for slides, off screen: a turntable of the leaf (GIF or MP4) and the pipeline's steps
side by side (PNG).

The steps, as the paper takes them: 1. the boundary and veins on the boundary's PCA plane;
2. g, the MPU implicit of the outline (positive inside), with its zero contour (eqs. 1-2);
3. p(x), the height guide from the veins (eqs. 4-5); 4. the points drawn from p for EM;
5. the Gaussian mixture's heights; 6. the mesh, trimmed at the margin. Panels 1-5 are seen from
above the leaf's plane, the mesh from an oblique view; all render with pyvista off screen.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from leafstudio.core.bend import flat_leaf
from leafstudio.core.plane import Frame
from leafstudio.errors import LeafError

TURNTABLE_SUFFIXES = (".gif", ".mp4")
TURNTABLE_FRAMES = 36
TURNTABLE_SIZE = (640, 480)
STEPS_SIZE = (1800, 1000)
BENT_FIRST_TITLE = "1. boundary and veins, unbent, on the blade's plane"  # a bent leaf's
STEP_TITLES = (
    "1. boundary and veins on the PCA plane",
    "2. g(x): the implicit of the outline, 0 on it",
    "3. p(x): the height guide from the veins",
    "4. EM samples drawn from p",
    "5. the Gaussian mixture's heights",
    "6. the mesh, trimmed at the margin",
)


def check_turntable_path(path: str | os.PathLike) -> Path:
    """The path if it names a GIF or MP4 this installation can write, else a LeafError."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in TURNTABLE_SUFFIXES:
        raise LeafError(f"a turntable is a {' or '.join(TURNTABLE_SUFFIXES)} file", str(path))
    if suffix == ".mp4":
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError:
            raise LeafError(
                "MP4 needs imageio-ffmpeg (pip install imageio-ffmpeg); .gif works as is",
                str(path),
            ) from None
    return path


def _mesh_view(plotter: Any, result: Any, clim: tuple[float, float]) -> None:
    plotter.add_mesh(
        result.mesh.copy(),
        scalars="height",
        cmap="viridis",
        clim=clim,
        smooth_shading=True,
        show_scalar_bar=False,
    )


def _iso_camera(result: Any, azimuth: float = 0.0, frame: Frame | None = None):
    """An oblique camera turned `azimuth` degrees about the leaf's normal (from its base side at
    0 on `frame`, by default evaluate.view_frame's)."""
    from leafstudio.core.evaluate import view_frame

    frame = frame or view_frame(result)
    pts = np.asarray(result.triangle_mesh.points)
    centre = (pts.min(axis=0) + pts.max(axis=0)) / 2
    size = float(np.linalg.norm(np.ptp(pts, axis=0)))
    a = np.deg2rad(azimuth - 120.0)
    side = np.cos(a) * frame.u + np.sin(a) * frame.v
    eye = centre + 1.6 * size * (0.8 * side + 0.6 * frame.normal)
    return [tuple(map(float, eye)), tuple(map(float, centre)), tuple(map(float, frame.normal))]


def _clim(result: Any) -> tuple[float, float]:
    h = np.asarray(result.triangle_mesh.point_data["height"])
    lo, hi = float(h.min()), float(h.max())
    return (lo, hi) if hi > lo else (lo - 1e-9, hi + 1e-9)


def render_turntable(
    result: Any, path: str | os.PathLike, frames: int = TURNTABLE_FRAMES, progress: Any = None
) -> Path:
    """Write the mesh turning once about its normal, coloured by height, as a GIF or MP4;
    `progress(fraction, what)`, if given, hears of each frame (the app's progress bar)."""
    import imageio.v3 as iio
    import pyvista as pv

    path = check_turntable_path(path)
    clim = _clim(result)
    images = []
    with pv.vtk_verbosity("off"):
        plotter = pv.Plotter(off_screen=True, window_size=list(TURNTABLE_SIZE))
        plotter.set_background("white")
        _mesh_view(plotter, result, clim)
        for i in range(frames):
            if progress is not None:
                progress(0.9 * i / frames, f"frame {i + 1}/{frames}")
            plotter.camera_position = _iso_camera(result, 360.0 * i / frames)
            plotter.render()
            images.append(plotter.screenshot(return_img=True))
        plotter.close()
    if path.suffix.lower() == ".gif":
        iio.imwrite(path, np.stack(images), extension=".gif", duration=80, loop=0)
    else:
        iio.imwrite(path, np.stack(images), extension=".mp4", fps=12)
    return path


def mesh_image(
    result: Any, size: tuple[int, int] = TURNTABLE_SIZE, frame: Frame | None = None
) -> np.ndarray:
    """The mesh coloured by height from the turntable's first view (its camera on `frame`, as
    _iso_camera), off screen.

    Returns
    -------
    (h, w, 3) uint8 array
        The picture, `size` = (w, h) pixels on white.
    """
    import pyvista as pv

    with pv.vtk_verbosity("off"):
        plotter = pv.Plotter(off_screen=True, window_size=list(size))
        plotter.set_background("white")
        _mesh_view(plotter, result, _clim(result))
        plotter.camera_position = _iso_camera(result, frame=frame)
        plotter.reset_camera()
        image = plotter.screenshot(return_img=True)
        plotter.close()
    return np.asarray(image)[..., :3]


def _grid_mesh(result: Any, values: np.ndarray, inside_only: bool = False):
    """The grid in the leaf's plane (z = 0) as a pyvista grid carrying `values`."""
    import pyvista as pv

    grid = result.grid
    ny, nx = grid.shape
    xs = grid.origin[0] + grid.spacing * np.arange(nx)
    ys = grid.origin[1] + grid.spacing * np.arange(ny)
    image = pv.RectilinearGrid(xs, ys, np.zeros(1))
    image.point_data["value"] = np.asarray(values, dtype=float)
    if inside_only:
        image.point_data["inside"] = result.inside.astype(float)
        return image.threshold(0.5, scalars="inside")
    return image


def render_steps(result: Any, path: str | os.PathLike, size: tuple[int, int] = STEPS_SIZE) -> Path:
    """Write a PNG with the pipeline's six steps side by side (see the module docstring)."""
    import pyvista as pv

    from leafstudio.core.evaluate import view_frame
    from leafstudio.render.figure import check_figure_path  # pyvista and VTK: only when asked for

    path = check_figure_path(path)
    frame = result.frame
    view = view_frame(result)  # the plane's axes turned: its v on the plane is the views' up
    up = (float(view.v @ frame.u), float(view.v @ frame.v), 0.0)
    blade = flat_leaf(result.leaf)  # the flat blade its steps ran on (step_slides.blade_leaf)
    boundary_xy, _ = frame.to_plane(blade.boundary)
    vein_xy = frame.to_plane(blade.vein_points)[0] if len(blade.vein_points) else None
    flat = lambda xy: np.column_stack([xy, np.zeros(len(xy))])  # noqa: E731
    outline = pv.PolyData(flat(boundary_xy))
    g = np.asarray(result.g_grid, dtype=float)
    nodes = result.grid.points
    mixture = np.zeros(len(nodes))
    mixture[result.inside] = result.height(nodes[result.inside])
    clim = _clim(result)
    with pv.vtk_verbosity("off"):
        plotter = pv.Plotter(off_screen=True, shape=(2, 3), window_size=list(size))
        plotter.set_background("white")
        titles = list(STEP_TITLES)
        if result.leaf.bend is not None:
            titles[0] = BENT_FIRST_TITLE
        for k, title in enumerate(titles):
            plotter.subplot(k // 3, k % 3)
            plotter.add_text(title, position="upper_left", font_size=10, color="black")
            if k == 0:
                plane = pv.Plane(
                    center=(*boundary_xy.mean(axis=0), 0),
                    i_size=1.2 * np.ptp(boundary_xy[:, 0]),
                    j_size=1.4 * np.ptp(boundary_xy[:, 1]) + 1e-9,
                )
                plotter.add_mesh(plane, color="#e8efe0")
            elif k == 1:
                grid = _grid_mesh(result, g)
                span = float(np.abs(g).max()) or 1.0
                plotter.add_mesh(
                    grid, scalars="value", cmap="RdBu", clim=(-span, span), show_scalar_bar=False
                )
                zero = grid.contour([0.0], scalars="value")
                if zero.n_points:
                    plotter.add_mesh(zero, color="black", line_width=3)
            elif k == 2:
                p = np.asarray(result.p_grid, dtype=float)
                plotter.add_mesh(
                    _grid_mesh(result, p, inside_only=True),
                    scalars="value",
                    cmap="magma",
                    show_scalar_bar=False,
                )
            elif k == 3 and len(result.em_samples):
                plotter.add_mesh(outline, color="#888888", point_size=3)
                plotter.add_points(
                    flat(np.asarray(result.em_samples)), color="#1f77b4", point_size=3
                )
            elif k == 4:
                plotter.add_mesh(
                    _grid_mesh(result, mixture, inside_only=True),
                    scalars="value",
                    cmap="viridis",
                    clim=clim,
                    show_scalar_bar=False,
                )
            if k in (0, 1, 2, 4):
                plotter.add_points(flat(boundary_xy), color="#202020", point_size=4)
                if vein_xy is not None and k in (0, 2):
                    plotter.add_points(flat(vein_xy), color="#d62728", point_size=5)
            if k == 5:
                _mesh_view(plotter, result, clim)
                plotter.camera_position = _iso_camera(result)
                plotter.reset_camera()
            else:
                plotter.view_xy()
                plotter.set_viewup(up)  # the base left, apex right, as the mesh's view
                plotter.enable_parallel_projection()
                plotter.reset_camera()
        path.parent.mkdir(parents=True, exist_ok=True)
        plotter.screenshot(str(path))
        plotter.close()
    return path
