"""Start-up: a clear one-line message without a display, and --screenshot under Xvfb."""

from __future__ import annotations

import os
import subprocess
import sys

from PySide6.QtGui import QImage

from leafstudio.gui.qt.app import display_problem, run_app
from leafstudio.sources.demos import demo
from leafstudio.sources.files import save_leaf
from tests.gui.builders import FAST

from .conftest import coloured_share, image_pixels


def test_without_a_display_the_app_says_how_to_run_it(monkeypatch, capsys):
    for name in ("DISPLAY", "WAYLAND_DISPLAY", "QT_QPA_PLATFORM"):
        monkeypatch.delenv(name, raising=False)
    assert run_app(None, None) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "DISPLAY" in err[0]
    assert "xvfb-run -a leafstudio" in err[0] and "leafstudio reconstruct" in err[0]


def test_a_display_that_does_not_answer_is_reported(monkeypatch):
    monkeypatch.delenv("QT_QPA_PLATFORM", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setenv("DISPLAY", ":4321")
    assert "does not answer" in display_problem()
    monkeypatch.setenv("QT_QPA_PLATFORM", "offscreen")
    assert display_problem() is None


def test_screenshot_saves_the_whole_window_and_exits(tmp_path):
    project = tmp_path / "leaf.leaf.json"
    save_leaf(demo("nested"), project, FAST)
    png = tmp_path / "window.png"
    env = {**os.environ, "XDG_CONFIG_HOME": str(tmp_path), "HOME": str(tmp_path)}
    # and says whether it loaded every VTK module (`import vtk`: 0.75 s on the main thread at
    # its first result, when the height stretch's matrix imported it)
    code = (
        "import sys; from leafstudio.cli import main; code = main(); "
        "print('vtk' in sys.modules, file=sys.stderr); raise SystemExit(code)"
    )
    done = subprocess.run(
        [sys.executable, "-c", code, "gui", str(project), "--screenshot", str(png)],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert done.stderr.splitlines()[-1] == "False"  # only the VTK modules the view uses
    image = QImage(str(png))
    assert image.width() >= 1000 and image.height() >= 600
    # the 3D view in the middle shows the leaf in its height colours: not a blank or black view
    # (Qt cannot grab a native view: its pixels come from VTK, gui/viewport.grab_window)
    pixels = image_pixels(image)
    height, width = pixels.shape[:2]
    middle = pixels[height // 5 : 4 * height // 5, 3 * width // 10 : 6 * width // 10]
    assert coloured_share(middle) > 0.03
