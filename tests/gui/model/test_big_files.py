"""Big inputs in the app, without Qt: what is drawn of them is thinned to a budget (a render
costs main-thread time per point), while every computation keeps them whole."""

from __future__ import annotations

import multiprocessing
import os
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from leafstudio._shared import inputs
from leafstudio.core.pipeline import Cancelled
from leafstudio.core.plane import Frame
from leafstudio.errors import LeafError
from leafstudio.gui.model import layers, opening, reading, scans
from leafstudio.gui.model.jobs import Job, cancel_point, running
from leafstudio.gui.model.session import Session
from leafstudio.gui.model.sketch_model import RELIEF_POINTS, Sketch
from leafstudio.gui.model.thinning import DISPLAY_POINTS, INPUT_POINTS, thinned
from leafstudio.model import Leaf
from tests.gui.builders import FAST, Runner, six_column_scan, write_points

ROOT = Path(__file__).resolve().parents[3]


def test_thinned_keeps_few_points_and_caps_many():
    few = np.arange(30.0).reshape(10, 3)
    assert thinned(few, 10) is few
    curve = np.column_stack([np.arange(1000.0), np.zeros(1000)])
    along = thinned(curve, 100, ordered=True)
    assert len(along) == 100 and along[0, 0] == 0 and along[-1, 0] == 999  # ends kept
    assert np.all(np.diff(along[:, 0]) > 0)  # in order, evenly: gaps of 10
    assert np.ptp(np.diff(along[:, 0])) <= 1
    cloud = np.random.default_rng(1).random((5000, 3))
    some = thinned(cloud, 700)
    assert len(some) == 700
    rows = {tuple(p) for p in cloud}
    assert all(tuple(p) in rows for p in some)  # the file's own points
    assert np.array_equal(some, thinned(cloud, 700))  # the same every time


def big_scan(n: int) -> SimpleNamespace:
    """An opened scan of `n` points (workflows.Opened's fields that scan_data reads)."""
    points = np.random.default_rng(0).random((n, 3))
    blade = np.ones(n, dtype=bool)
    blade[: n // 10] = False
    return SimpleNamespace(path="big.xyz", scan=points, extraction=SimpleNamespace(blade=blade))


def test_a_big_scan_draws_a_capped_number_of_points_small_and_flat():
    opened = big_scan(300_000)
    data = scans.scan_data(opened)
    drawn = [piece.data.n_points for piece in data.pieces]
    assert sum(drawn) <= DISPLAY_POINTS
    assert drawn[1] >= 0.09 * sum(drawn)  # the dropped points keep their share
    for piece in data.pieces:
        assert not piece.style.get("render_points_as_spheres")  # spheres would hide the mesh
        assert piece.style["point_size"] <= 2
    assert len(data.points) == 300_000  # the distances are measured from every point


def test_a_small_scan_draws_every_point_as_before():
    data = scans.scan_data(big_scan(2000))
    assert [p.data.n_points for p in data.pieces] == [1800, 200]
    assert data.pieces[0].style["render_points_as_spheres"]


def test_a_big_boundary_draws_a_capped_number_of_its_points():
    t = np.linspace(0, 2 * np.pi, 300_000, endpoint=False)
    boundary = np.column_stack([np.cos(t), 0.4 * np.sin(t), np.zeros_like(t)])
    vein = np.column_stack([np.linspace(-0.9, 0.9, 50), np.zeros((50, 2))])
    pieces = layers._input_pieces([boundary, vein])
    drawn = [piece.data.n_points for piece in pieces]
    assert sum(drawn) <= INPUT_POINTS and drawn[1] == 50  # a short vein whole


def test_a_big_boundary_becomes_a_light_sketch_of_the_same_outline_and_heights():
    t = np.linspace(0, 2 * np.pi, 300_000, endpoint=False)
    xy = np.column_stack([np.cos(t), 0.4 * np.sin(t)])
    height = 0.1 * xy[:, 0]
    frame = Frame(np.zeros(3), np.eye(3)[0], np.eye(3)[1], np.eye(3)[2])
    leaf = Leaf(boundary=np.column_stack([xy, height]))
    result = SimpleNamespace(polygon=xy, frame=frame, leaf=leaf)
    sketch = Sketch.from_result(result)
    assert len(sketch.relief) <= RELIEF_POINTS and len(sketch.boundary) < 100
    curve = sketch.boundary_curve()
    assert np.abs(np.hypot(curve[:, 0], curve[:, 1] / 0.4) - 1).max() < 0.01  # the ellipse
    assert np.allclose(sketch.boundary_heights(curve), 0.1 * curve[:, 0], atol=1e-3)


# --- open returns at once; Cancel stops the read ---------------------------------------------


def test_cancel_drops_the_reading_job_and_keeps_the_document(tmp_path):
    started: list[Job] = []

    def run(kind, function, *args):  # the worker's start: the job runs later
        started.append(Job(len(started) + 1))
        return started[-1]

    session = Session(Runner(), FAST, run=run)
    session.open_demo("nested")
    before = session.state
    seen: list = []
    session.opened.connect(seen.append)
    session.open_cancelled.connect(lambda: seen.append("cancelled"))
    job = session.open_path(str(tmp_path / "big.csv"))
    assert not job.finished  # open returns before the read is done
    assert session.cancel_open() and job.cancelled and seen == ["cancelled"]
    job.finish(object())  # a late answer: dropped
    assert session.state is before and seen == ["cancelled"]
    assert not session.cancel_open()  # nothing left to cancel
    second = session.open_path(str(tmp_path / "a.csv"))
    session.open_path(str(tmp_path / "b.csv"))
    assert second.cancelled  # superseded by the newer open


def test_cancel_point_stops_only_a_cancelled_job():
    cancel_point()  # outside a job: nothing
    with running(lambda: False):
        cancel_point()
    with running(lambda: True), pytest.raises(Cancelled):
        cancel_point()


# --- a big file is read in a process of its own ----------------------------------------------


def test_a_big_file_is_read_apart_and_gives_the_same_document(tmp_path, monkeypatch):
    path = write_points(tmp_path / "scan.txt", six_column_scan())
    here = opening.read_document(path)  # small: in this thread
    assert not opening.is_big(path)
    monkeypatch.setattr(reading, "BIG_FILE_BYTES", 0)
    calls: list = []
    real = opening.read_apart
    monkeypatch.setattr(opening, "read_apart", lambda *a: calls.append(a) or real(*a))
    apart = opening.read_document(path)
    assert len(calls) == 1  # read in a process of its own
    assert apart.path == here.path and apart.scan is not None
    np.testing.assert_array_equal(apart.leaf.boundary, here.leaf.boundary)
    np.testing.assert_array_equal(apart.scan.points, here.scan.points)
    assert [p.data.n_points for p in apart.scan.pieces] == [
        p.data.n_points for p in here.scan.pieces
    ]


def test_reading_apart_says_what_is_wrong_as_in_the_thread(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("1,2,3\nnot,a,number\n")
    with pytest.raises(LeafError) as here:
        opening._read_document(str(bad), False)
    with pytest.raises(LeafError) as apart:
        reading.read_apart(opening._read_document, str(bad), False)
    assert str(apart.value) == str(here.value)


@pytest.mark.skipif(not hasattr(os, "nice"), reason="no process priorities (os.nice)")
@pytest.mark.skipif(hasattr(os, "nice") and os.nice(0) >= 19, reason="run at the lowest priority")
def test_the_reading_process_gives_the_window_the_cores_first():
    """Issue 24: the reading process's start (imports: seconds of CPU) and read took the
    cores the window's main thread waited for (80-400 ms at a time on a 2-core host). (A suite
    run at the lowest priority, `nice -n 19`, has none lower to give its reading process.)"""
    child = reading.read_apart(os.nice, 0)  # os.nice(0): the process's niceness
    assert child == min(os.nice(0) + reading.CHILD_NICENESS, 19) > os.nice(0)


def test_cancel_ends_the_reading_process_at_once(tmp_path):
    before = set(multiprocessing.active_children())  # a first run's compile may have its own
    with running(lambda: True), pytest.raises(Cancelled):
        reading.read_apart(time.sleep, 60)
    assert set(multiprocessing.active_children()) <= before


def test_a_plain_script_opens_a_big_file_through_the_session(tmp_path):
    """Issue 24 (build item 3's spirit): a script without an `if __name__ == "__main__":` guard
    that opened a big file through the session spawned the reading process, which ran the script
    again while importing it and failed ("bootstrapping phase")."""
    path = write_points(tmp_path / "scan.txt", six_column_scan())
    script = tmp_path / "plain.py"
    script.write_text(
        "from leafstudio.gui.model import reading\n"
        "from leafstudio.gui.model.session import Session\n"
        "reading.BIG_FILE_BYTES = 0  # every file is big: read in a process of its own\n"
        "session = Session()\n"
        "session.open_failed.connect(lambda what, why: print('failed', why))\n"
        "session.opened.connect(lambda path: print('opened', len(session.leaf.boundary)))\n"
        f"session.open_path({path!r})\n"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=300, env=env, cwd=tmp_path)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr and "bootstrapping" not in done.stderr
    assert done.stdout.startswith("opened 200"), done.stdout


# --- a read's progress; Cancel stops the first reconstruction too (issue 24, build item 4) ----


def ellipse_file(path: Path, n: int) -> str:
    """A boundary file of `n` points (about 27 characters a line)."""
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    rows = np.column_stack([np.cos(t), 0.4 * np.sin(t), np.zeros(n)])
    np.savetxt(path, rows, delimiter=",", fmt="%.7f")
    return str(path)


def test_reading_a_file_reports_its_fraction_then_its_first_run(tmp_path, monkeypatch):
    """The busy bar showed no fraction: the readers read the whole text at once and said nothing."""
    monkeypatch.setattr(inputs, "BLOCK_CHARS", 8192)  # about 300 lines a block
    path = ellipse_file(tmp_path / "leaf.csv", 3000)
    runner = Runner()
    session = Session(runner, FAST)
    heard: list = []
    session.open_progress.connect(lambda fraction, doing: heard.append((fraction, doing)))
    session.open_ended.connect(lambda: heard.append("ended"))
    session.open_path(path)
    fractions = [f for f, doing in heard[:-1] if doing == "reading"]
    assert len(fractions) >= 9 and fractions == sorted(fractions) and fractions[-1] == 1.0
    assert heard[-1] == (None, "reconstructing")  # opened: its first run is under way
    runner.finish(session)
    assert heard[-1] == "ended"


def test_a_file_read_apart_reports_its_fraction_through_the_pipe(tmp_path):
    path = ellipse_file(tmp_path / "leaf.csv", 100_000)  # 2.7 MB: three blocks
    heard: list = []
    with running(lambda: False, lambda fraction, doing: heard.append((fraction, doing))):
        document = reading.read_apart(opening._read_document, path, False)
    assert len(document.leaf.boundary) == 100_000
    assert [f for f, _ in heard] == sorted(f for f, _ in heard) and len(heard) >= 3
    assert heard[-1] == (1.0, "reading")


def opened_after_demo(tmp_path, cancelled: list) -> tuple[Session, Runner, object]:
    """A session on the nested demo (its result shown), then a file opened: its first run waits."""
    runner = Runner()
    session = Session(runner, FAST, cancel=cancelled.append)
    session.open_demo("nested")
    runner.finish(session)
    before = session.state
    session.open_path(ellipse_file(tmp_path / "leaf.csv", 300))
    assert session.leaf is not before.leaf and session.last_id == 2
    return session, runner, before


def test_cancel_during_the_first_run_stops_it_and_brings_the_previous_leaf_back(tmp_path):
    """Cancel covered only the read: the first reconstruction of a big file (or of a cold kernel
    cache) ran on, and the busy bar had gone."""
    cancelled: list[int] = []
    session, runner, before = opened_after_demo(tmp_path, cancelled)
    heard: list = []
    session.open_cancelled.connect(lambda: heard.append("cancelled"))
    session.open_ended.connect(lambda: heard.append("ended"))
    shown = session.result
    assert session.cancel_open()
    assert cancelled == [2] and heard == ["cancelled", "ended"]
    assert session.state is before and session.result is shown
    assert not session.history.can_undo() and not session.is_modified()
    runner.finish(session, 1)  # its answer, already on its way: dropped
    assert session.state is before and session.result is shown
    assert not session.cancel_open()  # nothing left to cancel


def test_cancel_stops_an_edit_made_during_the_first_run_too(tmp_path):
    cancelled: list[int] = []
    session, _runner, before = opened_after_demo(tmp_path, cancelled)
    session.set_params(session.params.with_(k=4))
    assert session.last_id == 3
    assert session.cancel_open() and cancelled == [2, 3] and session.state is before


def test_the_first_run_shown_ends_the_opening_and_cancel_then_does_nothing(tmp_path):
    cancelled: list[int] = []
    session, runner, _ = opened_after_demo(tmp_path, cancelled)
    runner.finish(session)
    assert not session.cancel_open() and cancelled == []


def test_cancel_of_a_first_file_without_a_previous_leaf_leaves_an_empty_sketch(tmp_path):
    cancelled: list[int] = []
    session = Session(Runner(), FAST, cancel=cancelled.append)
    session.open_path(ellipse_file(tmp_path / "leaf.csv", 300))
    assert session.cancel_open() and cancelled == [1]
    assert session.leaf is None and session.state.sketch is not None
