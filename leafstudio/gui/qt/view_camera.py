"""How the 3D view places its camera: the presets (top, side, iso) and the fit of the blade's
robust bounds (gui/model/framing.py), above the band the colour bars keep at the bottom. A mixin
of Viewport (viewport.py), which holds the plotter, the blade's frame and bounds and the bars.
Main thread only (VTK).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from leafstudio.gui.model.framing import (
    ISO_AZIMUTHS,
    ISO_ELEVATIONS,
    BladeBounds,
    best_iso,
    fit_camera,
    view_direction,
)

if TYPE_CHECKING:
    from leafstudio.core.plane import Frame

CAMERAS = ("iso", "top", "side")
BAR_BAND = 0.13  # the colour bars' share of the view's height, at its bottom, with their titles


class CameraPlacing:
    """Camera presets and the blade's framing, over the Viewport's state below."""

    plotter: object  # pyvista's Plotter
    _frame: Frame
    _bounds: BladeBounds | None
    _bars: dict[str, tuple]
    _placed: tuple | None  # the preset and camera the view last framed with
    # the iso preset's azimuths and elevations (framing.best_iso); the lesson's view looks from
    # across the blade only, so that it shows the leaf as its plan does, base left, apex right
    iso_azimuths: tuple[float, ...] = ISO_AZIMUTHS
    iso_elevations: tuple[float, ...] = ISO_ELEVATIONS

    redraw: Callable[[], None]  # a render in a later turn

    def camera(self, preset: str, render: bool = True) -> None:
        """Look at the blade from the top (along its normal, u to the right and v up, as in the
        sketch), the side (along its width) or iso, filling most of the view."""
        direction, up = view_direction(preset, self._frame)
        if preset == "iso" and self._bounds is not None:
            direction, up = best_iso(
                self._bounds,
                self.plotter.camera.view_angle,
                self._aspect(),
                self._bottom(),
                self.iso_azimuths,
                self.iso_elevations,
            )
        self._place(direction, up)
        self._placed = (preset, self._camera_now())
        if render:
            self.redraw()

    def refit(self, render: bool = True) -> None:
        """Frame the blade again (the sketch grew past the view): from the current direction,
        or, while the camera is still where the iso preset put it, from the iso direction
        that suits the grown leaf (a few first points are a sliver, turned another way)."""
        if self._placed is not None and self._placed == ("iso", self._camera_now()):
            self.camera("iso", render)
            return
        camera = self.plotter.camera
        direction = np.asarray(camera.position) - np.asarray(camera.focal_point)
        self._place(direction, np.asarray(camera.up))
        self._placed = None
        if render:
            self.redraw()

    def _camera_now(self) -> tuple:
        camera = self.plotter.camera
        return tuple(np.round([*camera.position, *camera.focal_point, *camera.up], 9))

    def _bottom(self) -> float:
        """The share of the view's height kept free for the colour bars (none: 0)."""
        return BAR_BAND if self._bars else 0.0

    def _aspect(self) -> float:
        size = self.plotter.interactor.size()
        return size.width() / max(size.height(), 1)

    def _place(self, direction: np.ndarray, up: np.ndarray) -> None:
        if self._bounds is None:
            self.plotter.reset_camera(render=False)
            return
        camera = self.plotter.camera
        position, focus, up = fit_camera(
            self._bounds, direction, up, camera.view_angle, self._aspect(), bottom=self._bottom()
        )
        self.plotter.camera_position = [tuple(position), tuple(focus), tuple(up)]
        self.plotter.renderer.ResetCameraClippingRange()

    def display_points(self, points: np.ndarray) -> np.ndarray:
        """(n, 2) display positions (device pixels, y up) of (n, 3) world points in the view,
        with the camera as it is (for checks of the framing)."""
        renderer = self.plotter.renderer
        out = np.empty((len(points), 2))
        for i, point in enumerate(np.asarray(points, float)):
            renderer.SetWorldPoint(*point, 1.0)
            renderer.WorldToDisplay()
            out[i] = renderer.GetDisplayPoint()[:2]
        return out
