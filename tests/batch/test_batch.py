"""leafstudio batch: failed rows beside good ones, resume after a kill, 1 and 2 workers alike, a
real Dask scheduler and worker, and no progress bar when stderr is piped.

In-process batches run on worker processes kept for the session (`warm_pools`,
tests/batch/pools.py): a test here checks rows, tables and meshes, not a worker's start; the killed
batch runs `leafstudio` itself, in a new process with its own workers. The progress bar's test runs
the command in this process, its stderr a real pipe, then a real terminal (a pty). What a row
says (warnings, lengths, units, K) is test_batch_rows.py's."""

from __future__ import annotations

import fcntl
import json
import os
import pty
import signal
import struct
import subprocess
import sys
import termios
import time
from pathlib import Path

import pytest

import leafstudio as ls
from leafstudio.assets.writers import MESH_SUFFIXES
from leafstudio.batch import (
    FORMATS,
    Batch,
    TraitTable,
    find_inputs,
    remove_temporaries,
)
from leafstudio.cli import main
from leafstudio.errors import LeafError
from tests.batch.pools import use_warm_pools
from tests.batch.tables import GRID, SCANS
from tests.batch.tables import failed_line as _message
from tests.batch.tables import read_rows as _rows

LEAFSTUDIO = [sys.executable, "-m", "leafstudio"]


def _steady(table: Path) -> list[dict[str, str]]:
    """The rows without the time each leaf took (the one column a rerun changes)."""
    return [{k: v for k, v in row.items() if k != "seconds"} for row in _rows(table)]


def _meshes(folder: Path) -> dict[str, bytes]:
    return {
        p.relative_to(folder).as_posix(): p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and p.suffix != ".csv"
    }


def _copy(folder: Path, to: Path) -> Path:
    for src in folder.rglob("*.*"):
        (to / src.relative_to(folder)).parent.mkdir(parents=True, exist_ok=True)
        (to / src.relative_to(folder)).write_bytes(src.read_bytes())
    return to


@pytest.mark.usefixtures("warm_pools")
def test_bad_files_become_failed_rows_and_the_rest_go_on(tmp_path, leaves, capsys):
    inputs = _copy(leaves, tmp_path / "in")
    (inputs / "empty.csv").write_text("")
    (inputs / "b" / "words.txt").write_text("x y z\n1 2 three\n")
    (inputs / "notes.md").write_text("not a leaf")  # not a leaf suffix: not picked from a folder
    missing = tmp_path / "missing.csv"
    out = tmp_path / "out"
    code = main(["batch", str(inputs), str(missing), "-o", str(out), "--grid", GRID,
                 "--jobs", "1"])  # fmt: skip
    assert code == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("leafstudio: batch: 9 inputs: 6 ok, 3 failed")
    rows = _rows(out / "traits.csv")
    assert [r["input"] for r in rows] == sorted(r["input"] for r in rows)
    status = {Path(r["input"]).name: r["status"] for r in rows}
    assert status == {**{f"leaf{i}.csv": "ok" for i in range(6)}, "empty.csv": "failed",
                      "words.txt": "failed", "missing.csv": "failed"}  # fmt: skip
    # each failure's message is the one `leafstudio reconstruct` prints, and is printed too
    for row in rows:
        if row["status"] == "failed":
            line = _message(["reconstruct", row["input"], "-o", str(tmp_path / "x.ply")], capsys)
            assert line == f"leafstudio: error: {row['error']}"
            assert line in err
            assert row["area"] == row["mesh"] == ""
        else:
            assert float(row["area"]) > 0 and int(row["k"]) == 3 and row["grid"] == GRID
            assert (out / row["mesh"]).is_file()
    # the folder structure below the inputs' common folder (here tmp_path) is kept
    assert sorted(_meshes(out)) == [*(f"in/a/leaf{i}.ply" for i in range(3)),
                                    *(f"in/b/c/leaf{i}.ply" for i in range(3, 6))]  # fmt: skip


def test_usage_errors_exit_2(tmp_path, leaves, capsys):
    out = str(tmp_path / "out")
    made = tmp_path / "made"
    inside = made / "a.csv"  # named outright, but in the output folder: left out
    made.mkdir()
    inside.write_text("0 0 0\n")
    assert f"{inside}: lies in the output folder {made}" in _message(
        ["batch", str(inside), "-o", str(made)], capsys
    )  # it said "no input files found in" the file it named
    assert "no input files found" in _message(["batch", str(tmp_path / "*.csv"), "-o", out],
                                              capsys)  # fmt: skip
    assert "--jobs must be 1 or more" in _message(["batch", str(leaves), "-o", out, "--jobs",
                                                   "0"], capsys)  # fmt: skip
    assert "unknown table type" in _message(["batch", str(leaves), "-o", out, "--traits",
                                             "t.xlsx"], capsys)  # fmt: skip
    assert "invalid choice" in _message(["batch", str(leaves), "-o", out, "--format", "stl"],
                                        capsys)  # fmt: skip
    # every mesh format batch offers is one save_mesh writes (review finding: batch checked it
    # again for each run, a check that could not fail)
    assert {f".{f}" for f in FORMATS if f != "none"} <= set(MESH_SUFFIXES)
    (tmp_path / "x.csv").write_text("1 2 3\n")
    (tmp_path / "x.txt").write_text("1 2 3\n")
    both = [str(tmp_path / "x.csv"), str(tmp_path / "x.txt")]
    assert "would both write x.ply" in _message(["batch", *both, "-o", out], capsys)
    assert not Path(out).exists()


def test_without_distributed_the_scheduler_says_how_to_install_it(tmp_path, leaves, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed fails
    with pytest.raises(LeafError, match=r"pip install 'leafstudio\[cluster\]'"):
        ls.batch([leaves], ls.Params(grid=32), tmp_path / "out", scheduler="local")


@pytest.mark.usefixtures("warm_pools")
def test_fail_fast_stops_at_the_first_failure(tmp_path, leaves):
    inputs = _copy(leaves, tmp_path / "in")
    bad = inputs / "a" / "0bad.csv"  # the first input
    bad.write_text("1 2\n")
    run = ls.batch([inputs], ls.Params(grid=32), tmp_path / "out", jobs=1, fail_fast=True)
    rows = list(run)
    assert rows[0]["status"] == "failed" and rows[0]["input"] == str(bad) and run.stopped
    assert len(rows) < run.total == 7  # those in flight when it failed finish
    assert len(_rows(tmp_path / "out" / "traits.csv")) == len(rows)


@pytest.mark.usefixtures("warm_pools")
def test_json_lines_and_parquet_tables_and_no_meshes(tmp_path, leaves):
    table = tmp_path / "t.json"
    run = ls.batch([str(leaves / "a")], ls.Params(grid=32), tmp_path / "out", traits=table,
                   format="none", jobs=1)  # fmt: skip
    rows = list(run)
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").rglob("*.ply"))
    lines = [json.loads(line) for line in table.read_text().splitlines()]
    assert [r["input"] for r in lines] == sorted(r["input"] for r in rows)
    assert all(r["status"] == "ok" and r["mesh"] is None and r["area"] > 0 for r in lines)
    pytest.importorskip("pyarrow")
    import pyarrow.parquet as pq

    parquet = TraitTable(tmp_path / "t.parquet", scans=False)
    parquet.start()
    for row in reversed(lines):
        parquet.add(row)
    assert parquet.journal.exists() and not parquet.path.exists()  # rows journalled till close
    parquet.close()
    assert pq.read_table(parquet.path).to_pylist() == lines
    assert not parquet.journal.exists()


@pytest.fixture(scope="module")
def clean(tmp_path_factory, scans, kept_pools) -> Path:
    """A clean batch of the scans on one worker."""
    out = tmp_path_factory.mktemp("clean")
    with pytest.MonkeyPatch.context() as monkeypatch:
        use_warm_pools(monkeypatch, kept_pools)
        rows = list(ls.batch([scans], ls.Params(grid=32), out, scans=True, jobs=1))
    assert len(rows) == SCANS and all(r["status"] == "ok" for r in rows), rows
    assert all(0 <= r["scan_mean"] < 0.05 * r["length"] for r in rows)
    return out


@pytest.mark.usefixtures("warm_pools")
def test_one_and_two_workers_give_the_same_meshes_and_table(tmp_path, scans, clean):
    rows = list(ls.batch([scans], ls.Params(grid=32), tmp_path, scans=True, jobs=2))
    assert len(rows) == SCANS
    assert _meshes(tmp_path) == _meshes(clean) and len(_meshes(clean)) == SCANS
    assert _steady(tmp_path / "traits.csv") == _steady(clean / "traits.csv")


@pytest.mark.usefixtures("warm_pools")
def test_killed_batch_resumed_is_the_same_as_a_clean_run(tmp_path, scans, clean):
    killed = tmp_path / "killed"
    argv = ["batch", str(scans), "--scans", "--grid", GRID, "--jobs", "2", "-o"]
    # a run killed (SIGKILL, workers too) once a few rows are in its table
    proc = subprocess.Popen([*LEAFSTUDIO, *argv, str(killed)], start_new_session=True,
                            stderr=subprocess.DEVNULL)  # fmt: skip
    table = killed / "traits.csv"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if table.exists() and table.read_text().count("\n") >= 3:  # header and two rows
            break
        time.sleep(0.005)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    done_before = len(list(TraitTable(table, True).rows()))
    if done_before == SCANS:
        pytest.skip("the batch finished before it could be killed")
    # what a kill in the middle of a write leaves: a temporary mesh and half a row
    (killed / f".scan{SCANS - 1}.ply.99999999-0badc0de.leafstudio-part.ply").write_bytes(
        b"ply\nhalf"
    )
    with open(table, "a") as handle:
        handle.write("/half/a/row,ok,,scan")
    run = ls.batch([scans], ls.Params(grid=32), killed, scans=True, jobs=2, resume=True)
    rows = list(run)
    assert run.resumed == done_before >= 1 and len(rows) == SCANS
    assert _meshes(killed) == _meshes(clean)
    assert _steady(table) == _steady(clean / "traits.csv")
    assert not [p for p in killed.rglob(".*")]  # no temporary file left


@pytest.mark.usefixtures("warm_pools")
def test_resume_keeps_only_rows_of_unchanged_inputs_and_settings(tmp_path, leaves):
    inputs = _copy(leaves / "a", tmp_path / "in")
    out = tmp_path / "out"
    list(ls.batch([inputs], ls.Params(grid=32), out, jobs=1))
    (inputs / "leaf1.csv").write_bytes((leaves / "b" / "c" / "leaf4.csv").read_bytes())
    kept = Batch([inputs], ls.Params(grid=32), out, resume=True)._kept()
    assert sorted(Path(k).name for k in kept) == ["leaf0.csv", "leaf2.csv"]
    assert Batch([inputs], ls.Params(grid=36), out, resume=True)._kept() == {}
    assert Batch([inputs], ls.Params(grid=32), out, format="obj", resume=True)._kept() == {}
    (out / "leaf0.ply").unlink()  # a row without its mesh is not kept
    assert sorted(Batch([inputs], ls.Params(grid=32), out, resume=True)._kept()) == [
        str(inputs / "leaf2.csv")
    ]
    # review finding: a mesh damaged after the run (cut short, edited) was kept as done
    (out / "leaf2.ply").write_bytes(b"garbage\n")
    assert Batch([inputs], ls.Params(grid=32), out, resume=True)._kept() == {}


def test_resume_keeps_no_row_of_a_table_written_before_a_column_was(tmp_path, leaves):
    """A table written before a column was added (scan_crumpled, assets33) has rows the same key
    keeps: --resume kept them, that column blank, and a resumed run was no longer a clean one
    (pot1_1's crumpled surface went unsaid). A row missing a column is run again."""
    import csv

    inputs = _copy(leaves / "a", tmp_path / "in")
    out = tmp_path / "out"
    list(ls.batch([inputs], ls.Params(grid=32), out, jobs=1))
    assert len(Batch([inputs], ls.Params(grid=32), out, resume=True)._kept()) == 3
    table = out / "traits.csv"
    with open(table, newline="") as handle:
        rows = list(csv.DictReader(handle))
    with open(table, "w", newline="") as handle:  # as an older LeafStudio wrote it
        older = [name for name in rows[0] if name != "height"]
        writer = csv.DictWriter(handle, older, extrasaction="ignore", lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    assert Batch([inputs], ls.Params(grid=32), out, resume=True)._kept() == {}


def test_resume_runs_again_the_rows_an_older_leafstudio_made_with_the_same_settings(
    tmp_path, leaves, monkeypatch
):
    """A change that moves the figures (the scan sheet weighed per cell, session 33) keeps every
    column: --resume kept an older run's rows beside the new ones (review33: pot1_15's area
    985.63 from the old sheet, 968.59 from the new). The settings key holds settings.RESULTS."""
    import csv

    from leafstudio.batch import settings

    inputs = _copy(leaves / "a", tmp_path / "in")
    out = tmp_path / "out"
    list(ls.batch([inputs], ls.Params(grid=32), out, jobs=1))
    assert len(Batch([inputs], ls.Params(grid=32), out, resume=True)._kept()) == 3
    monkeypatch.setattr(settings, "RESULTS", settings.RESULTS - 1)
    older = settings.Settings(ls.Params(grid=32)).key()  # the key an older LeafStudio wrote
    monkeypatch.undo()
    table = out / "traits.csv"
    with open(table, newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert older != rows[0]["settings"]
    with open(table, "w", newline="") as handle:
        writer = csv.DictWriter(handle, list(rows[0]), lineterminator="\n")
        writer.writeheader()
        writer.writerows([{**row, "settings": older} for row in rows])
    assert Batch([inputs], ls.Params(grid=32), out, resume=True)._kept() == {}


def test_inputs_from_folders_and_patterns_leave_out_the_output_folder(tmp_path, leaves):
    leaves = _copy(leaves, tmp_path / "in")
    out = leaves / "out"
    found = find_inputs([leaves, str(leaves / "a" / "*.csv")], exclude=[out])
    assert len(found) == 6
    (out / "a").mkdir(parents=True)
    (out / "a" / "leaf0.ply").write_text("ply")
    (out / "a" / ".leaf0.ply.99999999-12ab34cd.leafstudio-part.ply").write_text("x")  # dead
    assert len(find_inputs([leaves], exclude=[out])) == 6
    live = out / "a" / f".leaf1.ply.{os.getpid()}-12ab34cd.leafstudio-part.ply"
    live.write_text("x")  # a live process's: left alone
    assert remove_temporaries(out, (".ply",)) == 1 and (out / "a" / "leaf0.ply").exists()
    assert live.exists()
    run = Batch([leaves], None, out, jobs=1)
    assert [j.mesh for j in run.jobs][:1] == ["a/leaf0.ply"]
    # hidden folders are not searched; a link stays where it is listed
    (leaves / ".git").mkdir()
    (leaves / ".git" / "x.csv").write_text("1 2 3\n")
    (tmp_path / "elsewhere.csv").write_bytes((leaves / "a" / "leaf0.csv").read_bytes())
    (leaves / "b" / "linked.csv").symlink_to(tmp_path / "elsewhere.csv")
    run = Batch([leaves], None, out, jobs=1)
    assert [j.mesh for j in run.jobs] == [
        "a/leaf0.ply", "a/leaf1.ply", "a/leaf2.ply", "b/c/leaf3.ply", "b/c/leaf4.ply",
        "b/c/leaf5.ply", "b/linked.ply",
    ]  # fmt: skip


def test_dask_scheduler_and_worker_on_localhost_run_the_tasks(tmp_path, leaves):
    distributed = pytest.importorskip("distributed")
    info = tmp_path / "scheduler.json"
    started = []
    try:
        started.append(subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
             "--port", "0", "--no-dashboard", "--scheduler-file", str(info)],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        ))  # fmt: skip
        started.append(subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_worker", "--scheduler-file", str(info),
             "--nthreads", "1", "--nworkers", "1", "--no-dashboard", "--no-nanny"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        ))  # fmt: skip
        with distributed.Client(scheduler_file=str(info), timeout="60s") as client:
            client.wait_for_workers(1, timeout=60)
            address = client.scheduler.address
            out = tmp_path / "out"
            assert main(["batch", str(leaves), "-o", str(out), "--grid", GRID,
                         "--scheduler", address]) == 0  # fmt: skip
            prefixes = client.run_on_scheduler(
                lambda dask_scheduler: set(dask_scheduler.task_prefixes)
            )
            executed = client.run(
                lambda dask_worker: (os.getpid(), dask_worker.state.executed_count)
            )
        assert "leafstudio-batch" in prefixes
        ((pid, count),) = executed.values()  # the one worker ran every leaf
        assert count == 6 and pid != os.getpid()
        rows = _rows(out / "traits.csv")
        assert len(rows) == 6 and {r["status"] for r in rows} == {"ok"}
        assert len(_meshes(out)) == 6
    finally:
        for proc in reversed(started):
            proc.terminate()
            proc.wait(timeout=30)


def _shown(argv: list[str], monkeypatch, terminal: bool) -> tuple[int, bytes]:
    """Exit code and stderr of `leafstudio argv` run in this process (its rows on the kept
    workers), with stderr a pipe or a 100-column terminal (a pty); read once the command is done
    (a few hundred bytes: less than either buffer holds)."""
    if terminal:
        reader, writer = pty.openpty()
        fcntl.ioctl(writer, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 100, 0, 0))
    else:
        reader, writer = os.pipe()
    shown = b""
    try:
        with open(writer, "w", encoding="utf-8") as stream, monkeypatch.context() as patch:
            assert stream.isatty() == terminal
            patch.setattr(sys, "stderr", stream)
            code = main(argv)
        os.set_blocking(reader, False)
        while True:
            try:
                chunk = os.read(reader, 65536)
            except OSError:  # nothing more (EAGAIN; a pty without a writer: EIO)
                break
            if not chunk:
                break
            shown += chunk
    finally:
        os.close(reader)
    return code, shown


@pytest.mark.usefixtures("warm_pools")
def test_progress_bar_only_on_a_terminal(tmp_path, leaves, monkeypatch):
    args = ["batch", str(leaves / "a"), "--grid", GRID, "--jobs", "1", "-o"]
    code, piped = _shown([*args, str(tmp_path / "piped")], monkeypatch, terminal=False)
    lines = piped.decode().splitlines()
    assert code == 0
    assert len(lines) == 1 and lines[0].startswith("leafstudio: batch: 3 inputs: 3 ok")
    assert "\r" not in piped.decode() and "it/s" not in piped.decode()
    # the same on a terminal shows the bar
    code, shown = _shown([*args, str(tmp_path / "tty")], monkeypatch, terminal=True)
    assert code == 0
    assert b"leaf/s" in shown or b"s/leaf" in shown, shown
    assert b"3/3" in shown
