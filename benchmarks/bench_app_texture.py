"""The app's texture view (Layers > "Show the texture"): what it costs and where.

Run under a display (`xvfb-run -a .venv/bin/python benchmarks/bench_app_texture.py`). For grid
128 and 512 it opens the nested demo, switches the mesh to the texture and then, five times each,
times: making the 1024² image (gui/textures.texture_image, the work done on the worker's side
lane), putting it on the mesh (Viewport.set_texture: the pyvista Texture and the actor, on the
main thread) and one render (the texture's upload to OpenGL, main thread). Wall-clock medians
and this thread's CPU time per step; the host's load average with them (a shared host moves the
wall-clock figures). Prints JSON.
"""

from __future__ import annotations

import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

from PySide6.QtCore import QSettings
from PySide6.QtWidgets import QApplication

REPEATS = 5


def _wait(app: QApplication, condition, seconds: float = 300) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        app.processEvents()
        time.sleep(0.01)
        if condition():
            return
    raise SystemExit("timed out")


def _timed(times: list, step, *args):
    """step(*args), its wall-clock and this thread's CPU seconds appended to `times`."""
    wall, cpu = time.perf_counter(), time.thread_time()
    value = step(*args)
    times.append((time.perf_counter() - wall, time.thread_time() - cpu))
    return value


def measure(app: QApplication, grid: int, folder: Path) -> dict:
    from leafstudio.gui.model.textures import TEXTURE, texture_image
    from leafstudio.gui.qt.main_window import MainWindow
    from leafstudio.model import Params

    window = MainWindow(QSettings(str(folder / f"s{grid}.ini"), QSettings.Format.IniFormat))
    window.show()
    window.panel.set_params(Params(k=3, grid=grid))
    window.open_demo("nested")
    _wait(app, lambda: window.session.shown.outcome is not None and window.worker.is_idle())
    window.coloring.setCurrentIndex(window.coloring.findData(TEXTURE))
    _wait(app, lambda: window.viewport.texture_key is not None and window.worker.is_idle())
    result = window.session.result
    steps: dict[str, list[tuple[float, float]]] = {"image": [], "set_texture": [], "render": []}
    for i in range(REPEATS):
        image = _timed(steps["image"], texture_image, result, "auto")
        _timed(steps["set_texture"], window.viewport.set_texture, image, ("bench", i))
        _timed(steps["render"], window.viewport.plotter.render)
    window.session.history.set_clean()
    window.close()
    out = {"grid": grid, "mesh_points": int(result.triangle_mesh.n_points)}
    for name, values in steps.items():
        out[f"{name}_ms"] = round(1000 * statistics.median(v[0] for v in values), 1)
        out[f"{name}_cpu_ms"] = round(1000 * statistics.median(v[1] for v in values), 1)
    return out


def main() -> None:
    app = QApplication.instance() or QApplication(sys.argv)
    with tempfile.TemporaryDirectory() as folder:
        rows = [measure(app, grid, Path(folder)) for grid in (128, 512)]
    print(
        json.dumps(
            {
                "where": {"image": "worker side lane", "set_texture": "main", "render": "main"},
                "rows": rows,
                "load_average": [round(x, 2) for x in os.getloadavg()],
                "command": "xvfb-run -a .venv/bin/python benchmarks/bench_app_texture.py",
            },
            indent=1,
        )
    )


if __name__ == "__main__":
    main()
