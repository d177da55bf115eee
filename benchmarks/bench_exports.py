"""The app's exports: the longest main-thread stall while each kind of export runs (issue 23,
finding 4: File > Export as .glb froze the window for 2.2 s; the target is no stall over 50 ms).

Run under a display (`xvfb-run -a .venv/bin/python benchmarks/bench_exports.py`). It opens the
window on the nested demo at the app's default parameters (grid 128), then for each kind (glTF,
glTF with 4 levels of detail, USD .usdz with 4, OBJ, an STL solid, a turntable GIF, the steps
figure) starts the export
as File > Export does and, with bench_gui's 5 ms QTimer, records the longest stall of the main
thread's event loop and its busiest piece of CPU time until the file is written. Beside it,
"before": the same export run on the main thread (what the window did until now), wall time.
"idle" is the longest stall over 5 s with nothing exporting: what the host's load alone does.
Prints JSON. Shared-host figures: load inflates wall time; the CPU time in one piece least.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
import time
from pathlib import Path

from bench_gui import StallMeter
from PySide6.QtCore import QEventLoop, QSettings, QTimer
from PySide6.QtWidgets import QApplication

import leafstudio as ls
from leafstudio.gui.qt import explain
from leafstudio.gui.qt.main_window import MainWindow
from leafstudio.render.slides import render_steps, render_turntable

KINDS = {  # name: (file, save_mesh options)
    "glb": ("leaf.glb", {}),
    "glb, 4 levels of detail": ("lod.glb", {"lod": 4}),
    "usdz, 4 levels of detail": ("lod.usdz", {"lod": 4}),
    "obj": ("leaf.obj", {}),
    "stl solid": ("solid.stl", {"thickness": "0.01"}),
}


def run_until(done, timeout_s: float = 900.0) -> None:
    """Run the event loop until done() is true."""
    deadline = time.perf_counter() + timeout_s
    while not done() and time.perf_counter() < deadline:
        loop = QEventLoop()
        QTimer.singleShot(20, loop.quit)
        loop.exec()


def _total(meter: StallMeter, until: float, since: float) -> float:
    """All the main thread's CPU time between two ticks from `since` to `until`."""
    return sum(busy for t, _, busy in meter.samples if since < t <= until)


def measure(meter: StallMeter, start) -> dict:
    """The stall while the export `start()` begins runs, until its job has ended."""
    meter.reset()
    t0 = time.perf_counter()
    job = start()
    run_until(lambda: job is None or job.finished)
    t1 = time.perf_counter()
    ok = job is not None and job.succeeded
    return {
        "longest_stall_ms": round(1000 * meter.worst(t1 + 0.05, t0), 1),
        "busiest_main_thread_cpu_ms": round(1000 * meter.busiest(t1 + 0.05, t0), 1),
        "main_thread_cpu_ms": round(1000 * _total(meter, t1 + 0.05, t0), 1),
        "export_s": round(t1 - t0, 2),
        "written": ok,
    }


def main() -> dict:
    app = QApplication.instance() or QApplication(sys.argv)
    folder = Path(tempfile.mkdtemp())
    window = MainWindow(QSettings(str(folder / "settings.ini"), QSettings.Format.IniFormat))
    window.show()
    window.open_demo("nested")
    run_until(lambda: window.session.result is not None and window.worker.is_idle())
    result = window.session.result
    meter = StallMeter()
    meter.timer.start()
    report: dict = {"vertices": int(result.triangle_mesh.points.shape[0]), "kinds": {}}
    meter.reset()  # the stalls the host's load makes with nothing exporting, for comparison
    t0 = time.perf_counter()
    run_until(lambda: time.perf_counter() > t0 + 5)
    report["idle, 5 s"] = {"longest_stall_ms": round(1000 * meter.worst(), 1)}
    for name, (file, options) in KINDS.items():
        target = folder / file
        after = measure(meter, lambda t=target, o=options: window.save_mesh(str(t), **o))
        t0 = time.perf_counter()
        thickness = options.get("thickness")
        solid = None if thickness is None else float(thickness) * result.blade_length
        ls.save_mesh(result, folder / f"before_{file}", thickness=solid, lod=options.get("lod", 0))
        after["before_main_thread_s"] = round(time.perf_counter() - t0, 2)
        report["kinds"][name] = after
    for kind, file, render in (
        ("turntable gif", "turn.gif", render_turntable),
        ("steps figure", "steps.png", render_steps),
    ):
        out = str(folder / file)
        after = measure(meter, lambda k=kind, o=out: explain.export_slide(window, k.split()[0], o))
        t0 = time.perf_counter()
        render(result, folder / f"before_{file}")
        after["before_main_thread_s"] = round(time.perf_counter() - t0, 2)
        report["kinds"][kind] = after
    meter.timer.stop()
    window.session.history.set_clean()
    window.close()
    app.processEvents()
    return report


if __name__ == "__main__":
    os.environ.setdefault("QT_QPA_PLATFORM", "xcb")
    print(json.dumps(main(), indent=1))
