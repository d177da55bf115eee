"""The vein side view's main-thread cost: one repaint, and one move of a handle drag (the new
heights worked out, the signal sent, the view repainted), on veins of 8 and 40 points.

Run under a display (here: `xvfb-run -a .venv/bin/python benchmarks/bench_side_view.py`). The
view stands alone (no window, no pipeline), at 420 x 120 logical pixels. Prints JSON: the median
and maximum CPU time (process time, which other work on a shared host inflates least) and wall
time per repaint and per drag move, over REPEATS of each, and the load average.
"""

from __future__ import annotations

import json
import os
import statistics
import time

import numpy as np
from PySide6.QtCore import QPoint, Qt
from PySide6.QtTest import QTest
from PySide6.QtWidgets import QApplication

from leafstudio.gui.model.sketch_model import Sketch
from leafstudio.gui.qt.profile_view import ProfileView

REPEATS = 40
POINTS = (8, 40)


def leaf(points: int) -> Sketch:
    t = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    boundary = np.column_stack([0.5 + 0.45 * np.cos(t), 0.2 * np.sin(t)])
    x = np.linspace(0.05, 0.95, points)
    vein = np.column_stack([x, 0.05 * np.sin(3 * x), 0.03 + 0.05 * x * (1 - x)])
    return Sketch(boundary=boundary, veins=(vein,))


def timed(action) -> tuple[float, float]:
    """(CPU ms, wall ms) of one call."""
    cpu, wall = time.process_time(), time.perf_counter()
    action()
    return 1000 * (time.process_time() - cpu), 1000 * (time.perf_counter() - wall)


def summary(samples: list[tuple[float, float]]) -> dict[str, float]:
    cpu, wall = zip(*samples, strict=True)
    return {
        "cpu_ms_median": round(statistics.median(cpu), 2),
        "cpu_ms_max": round(max(cpu), 2),
        "wall_ms_median": round(statistics.median(wall), 2),
        "wall_ms_max": round(max(wall), 2),
    }


def main() -> None:
    app = QApplication.instance() or QApplication([])
    view = ProfileView()
    view.resize(420, 120)
    view.show()
    app.processEvents()
    out: dict[str, object] = {"repeats": REPEATS, "load_average": os.getloadavg()}
    for points in POINTS:
        view.set_vein(leaf(points), 0)
        view.grab()  # warm up
        repaint = [timed(view.grab) for _ in range(REPEATS)]
        handle = len(view.profile.t) // 2
        press = view.to_view(view.profile.t[handle], view.profile.h[handle]).toPoint()
        QTest.mousePress(view, Qt.MouseButton.LeftButton, pos=press)
        moves = []
        for i in range(REPEATS):
            to = press + QPoint(0, -(i % 20))

            def move(to: QPoint = to) -> None:
                QTest.mouseMove(view, to)
                view.repaint()

            moves.append(timed(move))
        QTest.mouseRelease(view, Qt.MouseButton.LeftButton, pos=press)
        out[f"vein_{points}_points"] = {"repaint": summary(repaint), "drag_move": summary(moves)}
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
