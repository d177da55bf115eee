"""The app's responsiveness: slider-to-screen latency and main-thread stalls, at grid 128 and 512.

Run under a display (here: `xvfb-run -a .venv/bin/python benchmarks/bench_gui.py`). For each grid
it opens the nested demo, then moves the K slider several times; for each move it measures the
time from the slider's new value to the new mesh rendered on screen, and, with a 5 ms QTimer that
records how late it fires, the longest stall of the main thread's event loop while the
worker computes the new mesh, and until the worker has also measured it (which includes drawing
the result, done by VTK on the main thread). Each move starts from an idle app. "On screen" is
the end of the first render of the viewport that shows the move's request (a ScreenLog of
renders). It also counts the renders of the 3D view per result (one is all it takes).

Then a storm: 50 slider moves 5 ms apart between K = 2 and 7, the last one to a K the storm
does not use (so that none of its results can stand for it; K = 4, 3 or 6, whose pipeline costs
what 2 to 7 cost: K = 9 to 11 take several times longer in the surface stage); it reports the
time from the last move to its result on screen, and the longest stall of the event loop during
the storm and until the app is idle.
`--start` measures only a first start: the window's build, then the stalls until its first
result is shown and measured (imports, shaders and the gallery's thumbnails included).
Big files (`--big` runs only these): a 300,000-point boundary and a 2,000,000-point scan, written
to a temporary folder; each opens in a new window showing the nested demo (as the app starts: the
first render's shader set-up is not the file's). For each, the longest main-thread stall while it
opens (from the open call until the app is idle with its leaf on screen and measured), while a
layer is switched off and on, while the camera goes through its presets, while K changes, and
while the window closes during a computation (with the close call's time).
`--forms` measures only the Forms dock: for a few shapes, the longest stall and main-thread CPU in
one piece from choosing the form until its leaf is on screen and measured, then the same for a
change of the fold slider (the blade kept, posed again).
`LEAFSTUDIO_3D=opengl` measures the 3D view as pyvistaqt's QOpenGLWidget instead of the native
window (gui/qt/native_view.py). Prints JSON. Timings here are shared-host figures: other work on
the machine moves them; the main thread's CPU time in one piece is the figure load inflates least.
"""

from __future__ import annotations

import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from PySide6.QtCore import QEventLoop, QSettings, Qt, QTimer
from PySide6.QtWidgets import QApplication

from leafstudio.forms import SHAPES
from leafstudio.gui.qt.main_window import MainWindow
from leafstudio.gui.qt.view_camera import CAMERAS
from leafstudio.model import Params

GRIDS = (128, 512)
MOVES = (4, 5, 3, 6, 2, 5)  # K values, each different from the one before
TICK_MS = 5
STORM_MOVES, STORM_GAP_MS = 50, 5


class StallMeter:
    """A QTimer that records how late each of its ticks fires (the main thread's stalls)."""

    def __init__(self) -> None:
        self.timer = QTimer()
        self.timer.setTimerType(Qt.TimerType.PreciseTimer)
        self.timer.setInterval(TICK_MS)
        self.timer.timeout.connect(self._tick)
        self.reset()

    def reset(self) -> None:
        self.last = time.perf_counter()
        self.last_cpu = time.thread_time()
        # (tick time, lateness, main-thread CPU time since the last tick) in seconds
        self.samples: list[tuple[float, float, float]] = []

    def _tick(self) -> None:
        now, cpu = time.perf_counter(), time.thread_time()
        late = max(0.0, now - self.last - TICK_MS / 1000)
        self.samples.append((now, late, cpu - self.last_cpu))
        self.last, self.last_cpu = now, cpu

    def worst(self, until: float = float("inf"), since: float = 0.0) -> float:
        """The longest stall among ticks from `since` to `until` (a tick's stall ends at it)."""
        return max((late for t, late, _ in self.samples if since < t <= until), default=0.0)

    def busiest(self, until: float = float("inf"), since: float = 0.0) -> float:
        """The most main-thread CPU time between two ticks from `since` to `until`: the work
        done in one piece, which the host's load does not inflate as it does wall time."""
        return max((busy for t, _, busy in self.samples if since < t <= until), default=0.0)


class ScreenLog:
    """When each render of the 3D view ended and which request the session showed then; and
    what each render cost: wall time, the main thread's CPU time, and the whole process's CPU
    time (software OpenGL rasterizes on its own threads: on a quiet host of n cores a render
    takes about the process's CPU time over n, whatever the load was when it was measured)."""

    def __init__(self, window: MainWindow) -> None:
        self.window = window
        self.renders: list[tuple[float, int]] = []  # (time, id of the request shown)
        self.costs: list[tuple[float, float, float]] = []  # (wall, main thread, process) in s
        self._start = (0.0, 0.0, 0.0)
        window.viewport.plotter.render_window.AddObserver("StartEvent", self._on_start)
        window.viewport.plotter.render_window.AddObserver("EndEvent", self._on_render)

    def _on_start(self, *_: object) -> None:
        self._start = (time.perf_counter(), time.thread_time(), time.process_time())

    def _on_render(self, *_: object) -> None:
        now = (time.perf_counter(), time.thread_time(), time.process_time())
        self.costs.append(tuple(b - a for a, b in zip(self._start, now, strict=True)))
        self.renders.append((now[0], self.window.session.shown_id))

    def cost_of_first(self, request_id: int) -> tuple[float, float, float] | None:
        """What the render that first showed request `request_id` cost, if there was one."""
        i = next((i for i, (_, shown) in enumerate(self.renders) if shown >= request_id), None)
        return None if i is None else self.costs[i]

    def shown(self, request_id: int) -> float | None:
        """When request `request_id` (or a newer one) was first on screen, if it was."""
        return next((t for t, shown in self.renders if shown >= request_id), None)

    def wait_shown(self, request_id: int, timeout_s: float = 600.0) -> float:
        """Run the event loop until request `request_id` is on screen; when it got there."""
        deadline = time.perf_counter() + timeout_s
        while self.shown(request_id) is None and time.perf_counter() < deadline:
            wait_for(self.window.viewport.rendered, timeout_s=0.05)
        return self.shown(request_id) or time.perf_counter()


def wait_requested(window: MainWindow, k: int) -> int:
    """Run the event loop until the session has asked for K = `k` (the slider's throttle sends
    its last value late); the id of that request."""
    while window.session.params.k != k:
        wait_for(window.panel.changed, timeout_s=0.05)
    return window.session.last_id


def wait_for(signal, timeout_s: float = 600.0) -> list:
    """Run the event loop until `signal` fires; return its arguments."""
    loop, got = QEventLoop(), []
    signal.connect(lambda *args: (got.extend(args), loop.quit()))
    QTimer.singleShot(int(timeout_s * 1000), loop.quit)
    loop.exec()
    return got


def measure(window: MainWindow, grid: int) -> dict:
    """Latency and stalls for K slider moves on the nested demo at `grid`."""
    meter = StallMeter()
    window.panel.set_params(Params(k=3, grid=grid))
    window.session.history.set_clean()  # no question about unsaved parameter changes
    window.open_demo("nested")
    wait_for(window.result_shown)
    ready: dict[str, float] = {}
    window.worker.yielded.connect(
        lambda *_: ready.__setitem__("t", time.perf_counter()),
        Qt.ConnectionType.DirectConnection,  # on the worker thread, the moment the result is ready
    )
    screen = ScreenLog(window)
    meter.timer.start()
    latencies, computing, after, busy, total, draws, stages = [], [], [], [], [], [], []
    renders, costs = [], []
    for k in MOVES:
        wait_until_idle(window)  # the previous move's measurements are done
        meter.reset()
        start = time.perf_counter()
        window.panel.k.setValue(k)
        request = wait_requested(window, k)
        end = screen.wait_shown(request)
        wait_until_idle(window)
        wait_for_ticks(meter, time.perf_counter() + 0.2)  # and any render queued behind it
        renders.append(sum(t > ready["t"] for t, _ in screen.renders))
        costs.append(screen.cost_of_first(request))
        latencies.append(end - start)
        computing.append(meter.worst(until=ready["t"]))
        after.append(meter.worst(since=ready["t"]))
        busy.append(meter.busiest(since=ready["t"]))
        total.append(meter.worst())
        draws.append(window.session.shown.outcome.timings["draw"])
        stages.append(window.session.shown.outcome.timings)
    storm = measure_storm(window, meter, screen)
    meter.timer.stop()
    ms = lambda seconds: round(1000 * seconds, 1)  # noqa: E731
    return {
        "slider_to_screen_ms": {
            "median": ms(statistics.median(latencies)),
            "max": ms(max(latencies)),
        },
        "max_stall_while_computing_ms": ms(max(computing)),
        "max_stall_after_result_ms": ms(max(after)),
        "max_main_thread_cpu_in_one_piece_after_result_ms": ms(max(busy)),
        "max_stall_until_measured_ms": ms(max(total)),
        "renders_per_result_max": max(renders),
        "render_of_result_ms_median": {
            name: ms(statistics.median(c[i] for c in costs if c is not None))
            for i, name in enumerate(("wall", "main_thread_cpu", "process_cpu"))
        },
        "storm": storm,
        "draw_ms_median": ms(statistics.median(draws)),
        "stage_ms_median": {
            name: ms(statistics.median(s.get(name, 0.0) for s in stages)) for name in stages[0]
        },
        "mesh_triangles": int(window.session.result.mesh.n_cells),
    }


def measure_storm(window: MainWindow, meter: StallMeter, screen: ScreenLog) -> dict:
    """50 K moves 5 ms apart from an idle app: last move to its result on screen, and the
    longest stall from the first move until the app is idle again."""
    wait_until_idle(window)
    values = [2 + (5 * i) % 10 for i in range(STORM_MOVES - 1)]  # 2 and 7
    # last, a value the storm does not use (no result of the storm stands for it), of a typical cost
    # (the surface stage takes several times longer at K = 9 to 11 than at 2 to 7)
    values.append(next(k for k in (4, 3, 6) if k != window.panel.k.value()))
    meter.reset()
    moved: dict[str, float] = {}
    loop = QEventLoop()
    timer = QTimer()
    timer.setTimerType(Qt.TimerType.PreciseTimer)
    timer.setInterval(STORM_GAP_MS)
    pending = list(values)

    def move() -> None:
        window.panel.k.setValue(pending.pop(0))
        if not pending:
            timer.stop()
            moved["t"] = time.perf_counter()
            loop.quit()

    timer.timeout.connect(move)
    timer.start()
    loop.exec()
    end = screen.wait_shown(wait_requested(window, values[-1]))
    wait_until_idle(window)
    wait_for_ticks(meter, time.perf_counter())
    return {
        "moves": STORM_MOVES,
        "gap_ms": STORM_GAP_MS,
        "last_move_to_screen_ms": round(1000 * (end - moved["t"]), 1),
        "max_stall_ms": round(1000 * meter.worst(), 1),
        "max_main_thread_cpu_in_one_piece_ms": round(1000 * meter.busiest(), 1),
    }


def wait_until_idle(window: MainWindow) -> None:
    """Run the event loop until the worker has nothing running or waiting."""
    loop = QEventLoop()
    timer = QTimer()
    timer.timeout.connect(lambda: window.worker.is_idle() and loop.quit())
    timer.start(10)
    loop.exec()
    timer.stop()


def wait_for_ticks(meter: StallMeter, after: float) -> None:
    """Let the meter tick once more after `after`, so that a stall ending then is counted."""
    loop = QEventLoop()
    meter.timer.timeout.connect(loop.quit)
    while meter.last <= after:
        loop.exec()
    meter.timer.timeout.disconnect(loop.quit)


LOAD_AT_START = round(os.getloadavg()[0], 2)
BIG_BOUNDARY, BIG_SCAN = 300_000, 2_000_000


def write_big_files(folder: Path) -> dict[str, tuple[Path, str]]:
    """The big inputs: a boundary of BIG_BOUNDARY points (an egg-shaped outline, CSV) and a scan
    of BIG_SCAN points (a curved blade's surface with a petiole and outliers, XYZ); each with
    the layer the toggle switches."""
    rng = np.random.default_rng(0)
    t = np.linspace(0, 2 * np.pi, BIG_BOUNDARY, endpoint=False)
    outline = np.column_stack([0.5 * np.cos(t), 0.2 * np.sin(t) * (1 - 0.3 * np.cos(t))])
    boundary = folder / "boundary_300k.csv"
    np.savetxt(boundary, np.column_stack([outline, np.zeros(len(t))]), delimiter=",", fmt="%.7f")
    r, a = np.sqrt(rng.random(BIG_SCAN - 10_000)), 2 * np.pi * rng.random(BIG_SCAN - 10_000)
    x, y = 0.5 * r * np.cos(a), 0.2 * r * np.sin(a) * (1 - 0.3 * np.cos(a))
    blade = np.column_stack([x, y, 0.3 * x**2 + 0.6 * y**2 - 0.1 * x])
    along = rng.uniform(-0.8, -0.49, 9800)
    petiole = np.column_stack([along, rng.normal(0, 0.004, 9800), 0.13 - 0.2 * (along + 0.5)])
    outliers = rng.uniform([-1, -1, -0.5], [1, 1, 0.5], size=(200, 3))
    scan = folder / "scan_2m.xyz"
    np.savetxt(scan, np.vstack([blade, petiole, outliers]), fmt="%.6f")
    return {"boundary_300k": (boundary, "points"), "scan_2m": (scan, "scan")}


def settle(window: MainWindow, meter: StallMeter, seconds: float = 0.3) -> None:
    """Run the event loop until the worker is idle and `seconds` more (a render queued last)."""
    wait_until_idle(window)
    wait_for_ticks(meter, time.perf_counter() + seconds)


def measure_big(window: MainWindow, path: Path, layer: str) -> dict:
    """The longest main-thread stall while `path` opens, a layer toggles, the camera presets are
    chosen in turn, K changes and the window closes during the computation K's change started."""
    meter, ms = StallMeter(), lambda seconds: round(1000 * seconds, 1)
    window.open_demo("nested")  # as the app starts: its first render (shaders) is not the file's
    wait_for(window.result_shown)
    wait_until_idle(window)
    meter.timer.start()
    window.session.history.set_clean()
    meter.reset()
    start = time.perf_counter()
    window.open_path(str(path))
    open_call = time.perf_counter() - start
    wait_for(window.session.opened)
    wait_for(window.result_shown)
    settle(window, meter)
    report = {
        "open_call_ms": ms(open_call),
        "open_to_idle_s": round(time.perf_counter() - start, 1),
        "open_max_stall_ms": ms(meter.worst()),
        "open_max_main_thread_cpu_in_one_piece_ms": ms(meter.busiest()),
    }
    item = next(
        window.layer_list.item(i)
        for i in range(window.layer_list.count())
        if window.layer_list.item(i).data(Qt.ItemDataRole.UserRole) == layer
    )
    meter.reset()
    for state in (Qt.CheckState.Unchecked, Qt.CheckState.Checked):
        item.setCheckState(state)
        settle(window, meter)
    report[f"toggle_{layer}_max_stall_ms"] = ms(meter.worst())
    report[f"toggle_{layer}_max_main_thread_cpu_in_one_piece_ms"] = ms(meter.busiest())
    meter.reset()
    for preset in (*CAMERAS, CAMERAS[0]):  # each preset, back to the first
        window.viewport.camera(preset)
        settle(window, meter)
    report["camera_presets_max_stall_ms"] = ms(meter.worst())
    report["camera_presets_max_main_thread_cpu_in_one_piece_ms"] = ms(meter.busiest())
    k = window.panel.k.value() + 1
    meter.reset()
    window.panel.k.setValue(k)
    wait_for(window.result_shown)
    settle(window, meter)
    report["change_k_max_stall_ms"] = ms(meter.worst())
    report["change_k_max_main_thread_cpu_in_one_piece_ms"] = ms(meter.busiest())
    window.panel.k.setValue(k + 1)  # a computation under way
    wait_requested(window, k + 1)
    window.session.history.set_clean()
    meter.reset()
    start = time.perf_counter()
    window.close()
    report["close_during_computation_ms"] = ms(time.perf_counter() - start)
    meter.timer.stop()
    return report


def measure_start(settings: QSettings) -> dict:
    """A first start in this process (`--start`): the window's build (wall and main-thread CPU,
    before it shows), then the longest stall from its show until its first result (the nested
    demo) is on screen and measured; the first result's imports and shaders count here."""
    meter, ms = StallMeter(), lambda seconds: round(1000 * seconds, 1)
    start, cpu = time.perf_counter(), time.thread_time()
    window = MainWindow(settings)
    report = {
        "build_ms": ms(time.perf_counter() - start),
        "build_main_thread_cpu_ms": ms(time.thread_time() - cpu),
    }
    meter.timer.start()
    meter.reset()
    shown = time.perf_counter()
    window.show()
    window.open_demo("nested")
    wait_for(window.result_shown)
    settle(window, meter)
    meter.timer.stop()
    report["show_to_idle_s"] = round(time.perf_counter() - shown, 2)
    report["first_result_max_stall_ms"] = ms(meter.worst())
    report["first_result_max_main_thread_cpu_in_one_piece_ms"] = ms(meter.busiest())
    window.session.history.set_clean()
    window.close()
    return report


FORM_SHAPES = ("ovate", "cordate", "linear", "orbicular", "lanceolate")
SHAPE_ROWS = {shape: row for row, shape in enumerate(SHAPES)}  # the gallery's rows


def measure_forms(window: MainWindow) -> dict:
    """The longest stall while a form is chosen in the Forms dock and shown, then while its fold
    changes (`--forms`); the nested demo on screen first, as the app starts."""
    meter, ms = StallMeter(), lambda seconds: round(1000 * seconds, 1)
    panel = window.forms_panel
    window.open_demo("nested")
    wait_for(window.result_shown)
    wait_until_idle(window)
    meter.timer.start()
    report = {}
    for shape in FORM_SHAPES:
        for what, change in (
            ("choose", lambda shape=shape: panel.gallery.setCurrentRow(SHAPE_ROWS[shape])),
            ("fold_40", lambda: panel.fold.setValue(40.0)),
        ):
            settle(window, meter)
            meter.reset()
            change()
            panel.choose_now()
            wait_for(window.result_shown)
            settle(window, meter)
            report[f"{shape}_{what}_max_stall_ms"] = ms(meter.worst())
            report[f"{shape}_{what}_max_main_thread_cpu_in_one_piece_ms"] = ms(meter.busiest())
        panel.fold.setValue(0.0)
    meter.timer.stop()
    window.session.history.set_clean()
    return report


def main() -> int:
    app = QApplication.instance() or QApplication(sys.argv[:1])
    report = {}
    with tempfile.TemporaryDirectory() as tmp:
        settings = QSettings(str(Path(tmp) / "bench.ini"), QSettings.Format.IniFormat)
        if "--start" in sys.argv:  # a fresh process's first window, then nothing else
            print(json.dumps({"first_start": measure_start(settings)}, indent=2))
            return 0
        window = MainWindow(settings)
        window.show()
        app.processEvents()
        if "--forms" in sys.argv:  # the Forms dock only
            print(json.dumps({"forms": measure_forms(window)}, indent=2))
            window.close()
            return 0
        if "--big" not in sys.argv:
            report = {f"grid_{grid}": measure(window, grid) for grid in GRIDS}
        window.session.history.set_clean()
        window.close()
        for name, (path, layer) in write_big_files(Path(tmp)).items():
            window = MainWindow(settings)
            window.show()
            window.panel.set_params(Params(k=3, grid=128))
            report[name] = measure_big(window, path, layer)
    report["environment"] = {
        "platform": QApplication.platformName(),
        "display": os.environ.get("DISPLAY", ""),
        "cpus": os.cpu_count(),
        "load_average_1min_at_start": LOAD_AT_START,
        "load_average_1min": round(os.getloadavg()[0], 2),
        "window": [window.width(), window.height()],
        # the 3D view's widget: "native" (an X child window) or "opengl" (pyvistaqt's
        # QOpenGLWidget, LEAFSTUDIO_3D=opengl), gui/qt/native_view.py
        "view_widget": type(window.viewport.plotter).__name__,
    }
    print(json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
