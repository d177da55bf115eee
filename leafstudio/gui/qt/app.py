"""Start-up: check that a display can be opened, create the QApplication and the main window.

`run_app(path, screenshot)` is what `leafstudio` and `leafstudio gui` call (see cli/).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import importlib
import os
import pkgutil
import sys

NO_DISPLAY = (
    "leafstudio: cannot open a display ({why}); run the app under a virtual display with "
    "`xvfb-run -a leafstudio`, or use `leafstudio reconstruct` without a window"
)
HEADLESS_PLATFORMS = ("offscreen", "minimal", "vnc", "eglfs", "linuxfb")
SETTINGS = ("LeafStudio", "LeafStudio")  # organisation, application


def display_problem() -> str | None:
    """Why no window can be shown here, or None when one can (checked before Qt, which would
    abort the process instead)."""
    platform = os.environ.get("QT_QPA_PLATFORM", "").split(":")[0]
    if platform in HEADLESS_PLATFORMS or not sys.platform.startswith("linux"):
        return None
    if platform == "wayland" or (not platform and os.environ.get("WAYLAND_DISPLAY")):
        return None if os.environ.get("WAYLAND_DISPLAY") else "WAYLAND_DISPLAY is not set"
    display = os.environ.get("DISPLAY")
    if not display:
        return "DISPLAY is not set"
    name = ctypes.util.find_library("X11")
    if name is None:
        return None  # cannot check without libX11; let Qt try
    xlib = ctypes.CDLL(name)
    xlib.XOpenDisplay.restype = ctypes.c_void_p
    xlib.XOpenDisplay.argtypes = [ctypes.c_char_p]
    handle = xlib.XOpenDisplay(display.encode())
    if not handle:
        return f"the X display {display!r} does not answer"
    xlib.XCloseDisplay.argtypes = [ctypes.c_void_p]
    xlib.XCloseDisplay(handle)
    return None


def import_before_qt() -> None:
    """Import the window's modules that do without Qt (the app's model, gui/model, the pipeline's
    kernels, pyvista's plotting) before PySide6, which replaces Python's `__import__` with its own
    hook (`__feature_import__`) and so makes every later import slower: the window's imports took
    1.70 s of CPU so, 1.91 s in the order the window names them (5 runs each, gc off)."""
    import pyvista.plotting  # noqa: F401 - heavy (VTK, matplotlib): the 3D view's

    from leafstudio.core import kernels  # noqa: F401 - heavy (numba, scipy): the worker's
    from leafstudio.gui import model

    for module in pkgutil.iter_modules(model.__path__):
        importlib.import_module(f"{model.__name__}.{module.name}")


def run_app(path: str | None = None, screenshot: str | None = None, lesson: bool = False) -> int:
    """Open the main window on `path` (or the nested demo) and run until it closes.

    Parameters
    ----------
    path : str, optional
        A leaf file or project to open.
    screenshot : str, optional
        Save the whole window as this PNG once the first result and its measurements are
        shown, then exit.
    lesson : bool
        Open the lesson over the window, full screen (lesson_view.py); a screenshot is then
        the lesson's first step.

    Returns
    -------
    int
        The exit code: 0, or 2 when no display can be opened or the file cannot be read.
    """
    problem = display_problem()
    if problem is not None:
        print(NO_DISPLAY.format(why=problem), file=sys.stderr)
        return 2
    import_before_qt()
    from PySide6.QtCore import QSettings, QTimer
    from PySide6.QtWidgets import QApplication

    from leafstudio.gui.qt.main_window import MainWindow  # Qt: after the display check
    from leafstudio.gui.qt.viewport import grab_window  # Qt: after the display check

    app = QApplication.instance() or QApplication(sys.argv[:1])
    app.setApplicationName("LeafStudio")
    app.setOrganizationName(SETTINGS[0])
    window = MainWindow(QSettings(*SETTINGS))
    status: dict[str, int] = {"code": 0}

    def failed(message: str) -> None:
        """The file given (or the demo) cannot be shown: one line, exit 2, as the CLI says it."""
        where = path or "demo"
        text = message if message.startswith(f"{where}: ") else f"{where}: {message}"
        print(f"leafstudio: error: {text}", file=sys.stderr)
        status["code"] = 2
        window.close()

    if path is None:
        window.open_demo("nested")
    else:  # read off the main thread like any open
        window.open_path(path)
    if screenshot is None and path is not None:  # a file that cannot be read ends the app
        opened = {"done": False}
        window.session.opened.connect(lambda _path: opened.update(done=True))
        window.session.open_failed.connect(lambda _what, text: opened["done"] or failed(text))
    app.aboutToQuit.connect(window.worker.shutdown)
    window.show()
    shown = window
    if lesson:
        from leafstudio.gui.qt.lesson_view import open_lesson  # Qt: after the display check

        shown = open_lesson(window)
    if screenshot is not None:

        def grab(*_: object) -> None:
            if window.forms_panel.veins_due():  # the Forms gallery's veins still to come
                QTimer.singleShot(50, grab)
                return
            app.processEvents()
            image = shown.grab_all() if lesson else grab_window(window, window.viewport)
            if not image.save(screenshot):
                print(f"leafstudio: error: {screenshot}: cannot write the PNG", file=sys.stderr)
                status["code"] = 2
            window.session.history.set_clean()
            window.close()
            shown.close()  # the lesson too: the app ends with its last window

        window.measurements_shown.connect(lambda: QTimer.singleShot(100, grab))
        window.failure_shown.connect(failed)
        app.exec()
        return status["code"]
    code = app.exec()
    return status["code"] or code
