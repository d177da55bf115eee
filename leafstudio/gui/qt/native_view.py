"""The 3D view's widget: pyvista's Plotter in a native child window where the platform allows.

pyvistaqt's QtInteractor draws through a QOpenGLWidget. Qt then composes the whole window with
OpenGL whenever any widget repaints (a status text, a slider's handle): under software OpenGL
that is 15-20 ms of main-thread stall per repaint at 1500x920, on top of every render
(measured: /work/notes/s2/native.md; `benchmarks/bench_gui.py`, grid 512: the stall after a
result 95 -> 50 ms). VTK's own QVTKRenderWindowInteractor on a plain QWidget renders into a
native X child window instead, so other widgets repaint without touching OpenGL.

`make_plotter` picks that native view on X11 (Qt's "xcb" platform) and pyvistaqt's QtInteractor
elsewhere (Wayland, the headless platforms, or `LEAFSTUDIO_3D=opengl`). Both are pyvista
Plotters; the one difference callers see is `Viewport.image()` (a native window cannot be
grabbed by Qt: its pixels come from VTK's own frame buffer). Main thread only.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator

import vtkmodules.qt  # VTK's Qt widget; it uses PySide6 (loaded already, and its first choice)
import vtkmodules.vtkInteractionStyle  # the trackball style
import vtkmodules.vtkRenderingOpenGL2  # the OpenGL render window classes
from PySide6.QtCore import Qt
from PySide6.QtGui import QGuiApplication
from PySide6.QtWidgets import QWidget
from pyvista import global_theme
from pyvista.plotting import BasePlotter
from pyvista.plotting.render_window_interactor import RenderWindowInteractor
from vtkmodules.qt.QVTKRenderWindowInteractor import QVTKRenderWindowInteractor

WIDGET_ENV = "LEAFSTUDIO_3D"  # "native" or "opengl": which widget the 3D view uses
NATIVE, OPENGL = "native", "opengl"


def widget_kind() -> str:
    """NATIVE on X11 (unless the environment asks for OPENGL), else OPENGL."""
    asked = os.environ.get(WIDGET_ENV, "").strip().lower()
    if asked == OPENGL or QGuiApplication.platformName() != "xcb":
        return OPENGL
    return NATIVE


def make_plotter(parent: QWidget) -> BasePlotter:
    """A pyvista Plotter widget for the 3D view, without multisampling (under software OpenGL
    it multiplies the cost of every frame) and without pyvistaqt's auto-update timer."""
    # VTK's widget on QOpenGLWidget (vtkmodules.qt.QVTKRWIBase) draws nothing: never that one
    if widget_kind() == NATIVE and vtkmodules.qt.QVTKRWIBase == "QWidget":
        # a native widget makes its ancestors native, and by default their siblings too (the
        # docks, the menu and status bars): keep those ordinary widgets
        QGuiApplication.setAttribute(Qt.ApplicationAttribute.AA_DontCreateNativeWidgetSiblings)
        try:
            return NativePlotter(parent)
        except ImportError:  # a VTK built without X11 (vtkXOpenGLRenderWindow)
            pass
    from pyvistaqt import QtInteractor

    plotter = QtInteractor(parent, auto_update=False, multi_samples=1)
    plotter.setAcceptDrops(False)  # a file dropped on the view opens in the window, not the scene
    return plotter


@contextlib.contextmanager
def _base_plotter_init_skipped() -> Iterator[None]:
    """PySide6 calls every base's __init__ cooperatively: keep it from running BasePlotter's
    (without its arguments) inside the Qt widget's, as pyvistaqt does."""
    init = BasePlotter.__init__
    BasePlotter.__init__ = lambda *args, **kwargs: None  # type: ignore[method-assign]
    try:
        yield
    finally:
        BasePlotter.__init__ = init  # type: ignore[method-assign]


class _FakeInteractor:
    """Stands in for the VTK interactor once the view is closed (Qt may still send events)."""

    def __getattr__(self, name: str) -> object:
        return lambda *args, **kwargs: None


class NativePlotter(QVTKRenderWindowInteractor, BasePlotter):
    """pyvista's Plotter on VTK's native-window Qt widget (the 3D view on X11)."""

    def __init__(self, parent: QWidget | None = None) -> None:
        # the X11 window class made directly: VTK's factory (vtkRenderWindow()) would open and
        # keep an X connection of its own just to choose between X11 and EGL
        from vtkmodules.vtkRenderingOpenGL2 import vtkXOpenGLRenderWindow

        with _base_plotter_init_skipped():
            QVTKRenderWindowInteractor.__init__(self, parent, rw=vtkXOpenGLRenderWindow())
        BasePlotter.__init__(self)
        self.interactor = self
        self.ren_win = self.GetRenderWindow()
        self.ren_win.SetMultiSamples(0)
        # the frame goes to the window's back buffer as colour only: VTK's default for its own
        # windows also writes the depth buffer there through a full-window shader pass, which
        # nothing reads, about half of an empty frame's cost under software OpenGL (empty view
        # 1500x920: 39 -> 20 ms of process CPU; the pixels on screen the same)
        self.ren_win.SetFrameBlitModeToBlitToCurrent()
        for renderer in self.renderers:
            renderer.view_isometric()
            self.ren_win.AddRenderer(renderer)
        self.background_color = global_theme.background
        self._off_screen = False
        self.iren = RenderWindowInteractor(self, interactor=self.ren_win.GetInteractor())
        self.iren.interactor.RemoveObservers("MouseMoveEvent")  # Qt sends the moves
        self.iren.initialize()
        self.enable_trackball_style()
        self._first_time = False

    def render(self) -> None:
        """Render now (QWidget.update() renders at the next paint instead)."""
        if getattr(self, "_closed", False):
            return
        self._rendered = True
        BasePlotter.render(self)

    def close(self) -> None:  # type: ignore[override]
        """Release the render window now, while the X server still answers: VTK closes its X
        connections when the window is destroyed, and Xlib ends the process when that happens
        after the server has gone (a test run's virtual display stops before the interpreter)."""
        if getattr(self, "_closed", True):
            return
        BasePlotter.close(self)
        QVTKRenderWindowInteractor.close(self)
        self._Iren = _FakeInteractor()
        self._RenderWindow = None

    def closeEvent(self, event) -> None:
        if self._RenderWindow is not None:
            self._RenderWindow.Finalize()
        event.accept()
