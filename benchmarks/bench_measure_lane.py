"""How long a request made while the shown result is being measured waits for the measuring.

Run under a display: `xvfb-run -a .venv/bin/python benchmarks/bench_measure_lane.py [--grid N]
[--trials N] [--measure-on-side-lane]`. On the nested demo (grid 512 by default) each trial
moves K, waits until that result is on screen (the end of the render that first shows it, as
bench_gui's ScreenLog), waits a few ms more (the offsets below; the worker starts measuring a
result at most ~10 ms after it is drawn), then changes K once more through the session, as a
typed value does. It reports, for the trials whose request came before the measuring ended:
- from the request to its pipeline run's first stage (on the worker's thread), and to its
  result on screen: wall times (ms);
- the pipeline lane's CPU time from the request to its first stage (what it spent on something
  else before starting: the rest of the measuring), and both lanes' and the whole process's
  CPU time from the request to the result on screen (ms; the host's load inflates these least).
`--measure-on-side-lane` is the alternative weighed for issue 12: the worker is patched so that
measuring runs as its own job on the side lane, beside the next run (it competes with it for
the host's cores). Shared host: the load average is printed; quote it with the figures.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

from bench_gui import ScreenLog, wait_until_idle  # a sibling script: benchmarks/ is on sys.path
from PySide6.QtCore import QEventLoop, QSettings, Qt, QTimer
from PySide6.QtWidgets import QApplication

from leafstudio.core import evaluate
from leafstudio.core.pipeline import Cancelled
from leafstudio.gui.qt.main_window import MainWindow
from leafstudio.gui.qt.worker import PIPELINE, Worker
from leafstudio.model import Params

OFFSETS_MS = (15, 30, 45, 60)  # after the result is on screen, when the next request comes
# the moves that put a result on screen, each next request K + 1: every move changes K, and
# stays within 2 to 7 (K = 9 to 11 spend several times longer in the surface stage)
KS = (2, 4, 6, 3, 5)
ROW_KEYS = ("offset_ms", "during_measuring", "to_start_ms", "to_screen_ms")


def lane_clocks(worker: Worker) -> dict[str, float]:
    """CPU seconds so far of each lane's thread, and of the whole process."""
    clocks = {
        thread.name.removeprefix("leafstudio-"): time.clock_gettime(
            time.pthread_getcpuclockid(thread.ident)
        )
        for thread in worker._threads
    }
    clocks["process"] = time.process_time()
    return clocks


def measure_on_side_lane(worker: Worker) -> None:
    """The alternative: the pipeline job ends once its outcome is reported, and a job of its
    own ("measure", on the side lane) waits until it is drawn and measures it there, beside any
    next run; it reports as the pipeline job did (done: request id, seconds)."""
    worker.lanes["measure"] = "side"
    reconstruct = worker._reconstruct

    def measure(context, outcome):
        if worker.measure_after_drawn:
            worker._wait_drawn(outcome, context)
        start = time.perf_counter()
        outcome.result.measure(context.newer_waiting)  # only a newer "measure" job stops it
        worker.done.emit(PIPELINE, outcome.request.id, time.perf_counter() - start)
        return None, None  # the window's side-task reports are (token, value)

    def pipeline_job(context, request):
        steps = reconstruct(context, request)
        outcome = next(steps)
        steps.close()
        yield outcome
        worker.submit("measure", measure, outcome)
        raise Cancelled  # no `done` for the pipeline job: the measure job sends it

    worker._reconstruct = pipeline_job


def wait_ms(ms: float) -> None:
    """Run the event loop for `ms` milliseconds."""
    loop, timer = QEventLoop(), QTimer()
    timer.setTimerType(Qt.TimerType.PreciseTimer)
    timer.setSingleShot(True)
    timer.timeout.connect(loop.quit)
    timer.start(max(0, round(ms)))
    loop.exec()


def trial(window: MainWindow, screen: ScreenLog, log: dict, k: int, offset_ms: float) -> dict:
    """One K move to the screen, then a request `offset_ms` after it is on screen."""
    session = window.session
    wait_until_idle(window)
    assert session.params.k != k
    session.set_params(session.params.with_(k=k))
    shown_id = session.last_id
    on_screen = screen.wait_shown(shown_id)
    wait_ms(offset_ms - 1000 * (time.perf_counter() - on_screen))
    before = lane_clocks(window.worker)
    submitted = time.perf_counter()
    session.set_params(session.params.with_(k=k + 1))
    request = session.last_id
    end = screen.wait_shown(request)
    after = lane_clocks(window.worker)
    wait_until_idle(window)
    started, pipeline_cpu = log["started"][request]
    measured = log["measured"].get(shown_id)
    measuring = any(on_screen <= t <= submitted for t in log["measuring"])
    return {
        "offset_ms": round(1000 * (submitted - on_screen), 1),
        "during_measuring": measuring and (measured is None or measured > submitted),
        "to_start_ms": 1000 * (started - submitted),
        "to_screen_ms": 1000 * (end - submitted),
        "pipeline_lane_cpu_to_start_ms": 1000 * (pipeline_cpu - before["pipeline"]),
        "cpu_to_screen_ms": {name: 1000 * (after[name] - before[name]) for name in before},
    }


def summary(values: list[float]) -> dict[str, float]:
    return {"median": round(statistics.median(values), 1), "max": round(max(values), 1)}


def run(grid: int, trials: int, side_lane: bool) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        settings = QSettings(str(Path(tmp) / "bench.ini"), QSettings.Format.IniFormat)
        window = MainWindow(settings)
        if side_lane:
            measure_on_side_lane(window.worker)
        window.show()
        log: dict = {"started": {}, "measured": {}, "measuring": []}
        distances = evaluate.point_to_mesh_distance  # measuring's first step, old code or new

        def logged(mesh, points):
            log["measuring"].append(time.perf_counter())
            return distances(mesh, points)

        evaluate.point_to_mesh_distance = logged

        def on_stage(kind: str, job_id: int, _name: str) -> None:
            if kind == PIPELINE and job_id not in log["started"]:
                log["started"][job_id] = (time.perf_counter(), time.thread_time())

        def on_done(kind: str, job_id: int, _value: object) -> None:
            if kind == PIPELINE:
                log["measured"][job_id] = time.perf_counter()

        direct = Qt.ConnectionType.DirectConnection  # on the worker's thread, when it happens
        window.worker.stage_started.connect(on_stage, direct)
        window.worker.done.connect(on_done, direct)
        window.panel.set_params(Params(k=3, grid=grid))
        window.open_demo("nested")
        screen = ScreenLog(window)
        screen.wait_shown(window.session.last_id)
        rows = [
            trial(window, screen, log, KS[i % len(KS)], OFFSETS_MS[i % len(OFFSETS_MS)])
            for i in range(trials)
        ]
        window.session.history.set_clean()
        window.close()
        evaluate.point_to_mesh_distance = distances
    during = [r for r in rows if r["during_measuring"]]
    figures: dict = {"trials": len(rows), "trials_during_measuring": len(during)}
    if during:
        for key in ("to_start_ms", "to_screen_ms", "pipeline_lane_cpu_to_start_ms"):
            figures[key] = summary([r[key] for r in during])
        figures["cpu_to_screen_ms_median"] = {
            name: round(statistics.median(r["cpu_to_screen_ms"][name] for r in during), 1)
            for name in during[0]["cpu_to_screen_ms"]
        }
    figures["rows"] = [
        {k: round(v, 1) if isinstance(v, float) else v for k, v in r.items() if k in ROW_KEYS}
        for r in rows
    ]
    return figures


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grid", type=int, default=512)
    parser.add_argument("--trials", type=int, default=10)
    parser.add_argument("--measure-on-side-lane", action="store_true")
    args = parser.parse_args()
    app = QApplication.instance() or QApplication(sys.argv[:1])
    load = round(os.getloadavg()[0], 2)
    report = {
        f"grid_{args.grid}": run(args.grid, args.trials, args.measure_on_side_lane),
        "measuring": "side lane" if args.measure_on_side_lane else "pipeline lane",
        "environment": {
            "platform": app.platformName(),
            "cpus": os.cpu_count(),
            "load_average_1min_at_start": load,
            "load_average_1min": round(os.getloadavg()[0], 2),
        },
    }
    print(json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
