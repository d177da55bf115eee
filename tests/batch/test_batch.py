"""leafstudio batch: failed rows beside good ones, resume after a kill, 1 and 2 workers alike, a
real Dask scheduler and worker, and no progress bar when stderr is piped.

In-process batches run on worker processes kept for the session (`warm_pools`,
tests/batch/pools.py): a test here checks rows, tables and meshes, not a worker's start; the killed
batch runs `leafstudio` itself, in a new process with its own workers. The progress bar's test runs
the command in this process, its stderr a real pipe, then a real terminal (a pty)."""

from __future__ import annotations

import csv
import fcntl
import hashlib
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

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.assets.writers import MESH_SUFFIXES
from leafstudio.batch import (
    FORMATS,
    Batch,
    Settings,
    TraitTable,
    find_inputs,
    plan,
    remove_temporaries,
    run_job,
)
from leafstudio.cli import main
from leafstudio.errors import LeafError
from leafstudio.forms import make_form
from leafstudio.sources.extract import OUTLINE_POINTS
from tests.batch.pools import use_warm_pools

REAL = Path(__file__).resolve().parents[3] / "shared" / "realleaves"
LEAFSTUDIO = [sys.executable, "-m", "leafstudio"]
GRID = "32"
SCANS = 4  # real scans in a batch: two workers get two each, and a kill after two rows leaves two


def _rotation(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@pytest.fixture(scope="module")
def leaves(tmp_path_factory) -> Path:
    """Six leaf files in two folders: the nested demo moved and turned."""
    root = tmp_path_factory.mktemp("leaves")
    demo = ls.demo("nested")
    for i in range(6):
        turn = _rotation(0.4 * i)
        leaf = ls.Leaf(
            boundary=demo.boundary @ turn.T + i, veins=[v @ turn.T + i for v in demo.veins]
        )
        ls.save_leaf(leaf, root / ("a" if i < 3 else "b/c") / f"leaf{i}.csv")
    return root


@pytest.fixture(scope="module")
def scans(tmp_path_factory) -> Path:
    """SCANS real scans (x y z only), each subsampled to 40%, moved and turned."""
    if not REAL.is_dir():
        pytest.skip(f"no real scans at {REAL}")
    root = tmp_path_factory.mktemp("scans")
    rng = np.random.default_rng(1)
    for i, path in enumerate(sorted(REAL.glob("*.txt"))[1 : 1 + SCANS]):
        xyz = np.loadtxt(path, delimiter=",", usecols=(0, 1, 2))
        keep = rng.random(len(xyz)) < 0.4
        moved = xyz[keep] @ _rotation(0.3 * i).T + [10.0 * i, -5.0, 2.0]
        np.savetxt(root / f"scan{i}.txt", moved, fmt="%.6f")
    return root


def _rows(table: Path) -> list[dict[str, str]]:
    with open(table, newline="", encoding="utf-8") as handle:
        return list(csv.DictReader(handle))


def _steady(table: Path) -> list[dict[str, str]]:
    """The rows without the time each leaf took (the one column a rerun changes)."""
    return [{k: v for k, v in row.items() if k != "seconds"} for row in _rows(table)]


def _meshes(folder: Path) -> dict[str, bytes]:
    return {
        p.relative_to(folder).as_posix(): p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and p.suffix != ".csv"
    }


def _message(argv: list[str], capsys) -> str:
    """The one line `leafstudio` prints for a failing command."""
    capsys.readouterr()
    assert main(argv) == 2
    return capsys.readouterr().err.strip()


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


def test_the_trait_table_never_replaces_an_input_or_a_users_file(tmp_path, leaves, capsys):
    """Review finding: `batch DIR -o out --traits DIR/a.leaf.json` left that leaf out of the
    inputs, wrote the table over it and exited 0. A --traits path that holds anything but a
    trait table is refused before any work."""
    leaf = sorted(leaves.rglob("*.csv"))[0]
    before = leaf.read_bytes()
    out = tmp_path / "out"
    text = _message(["batch", str(leaves), "-o", str(out), "--traits", str(leaf)], capsys)
    assert str(leaf) in text and "not a trait table" in text
    assert leaf.read_bytes() == before and not out.exists()
    own = tmp_path / "mine.csv"
    own.write_text("x,y,z\n1,2,3\n")
    assert "not a trait table" in _message(
        ["batch", str(leaves), "-o", str(out), "--traits", str(own)], capsys
    )
    assert own.read_text() == "x,y,z\n1,2,3\n"


def _warned(err: str, source: str) -> list[str]:
    """The warnings `leafstudio` printed about `source`, without their prefix."""
    lead = f"leafstudio: warning: {source}: "
    return [line[len(lead) :] for line in err.splitlines() if line.startswith(lead)]


@pytest.mark.usefixtures("warm_pools")
def test_a_scan_row_fails_and_warns_as_extract_and_reconstruct_do(tmp_path, scans, capsys):
    """Issue 15: `batch --scans` did not run extract's plausibility check (check_leaf_like), so
    a cloud of two leaves became an `ok` row. Its row now fails with extract's line, and with
    --force it is reconstructed, its warnings those of `extract --force` then `reconstruct`."""
    inputs = tmp_path / "in"
    inputs.mkdir()
    good = (scans / "scan0.txt").read_bytes()
    (inputs / "good.txt").write_bytes(good)
    xyz = np.loadtxt(scans / "scan1.txt")
    two = inputs / "two.txt"
    np.savetxt(two, np.vstack([xyz, xyz + [3 * np.ptp(xyz[:, 0]), 0.0, 0.0]]), fmt="%.6f")
    leaf = tmp_path / "two.leaf.json"
    refused = _message(["extract", str(two), "-o", str(leaf)], capsys)
    assert "does not look like one leaf" in refused
    argv = ["batch", str(inputs), "--scans", "--grid", GRID, "--jobs", "1", "-o"]
    assert main([*argv, str(tmp_path / "out")]) == 1
    assert refused in capsys.readouterr().err
    rows = {Path(r["input"]).name: r for r in _rows(tmp_path / "out" / "traits.csv")}
    assert rows["good.txt"]["status"] == "ok" and rows["good.txt"]["warnings"] == ""
    assert rows["two.txt"]["status"] == "failed"
    assert f"leafstudio: error: {rows['two.txt']['error']}" == refused
    # --force: the problems become the row's warnings, followed by reconstruct's
    assert main(["extract", str(two), "-o", str(leaf), "--force"]) == 0
    warned = _warned(capsys.readouterr().err, str(two))
    assert main(["reconstruct", str(leaf), "-o", str(tmp_path / "two.ply"), "--grid", GRID]) == 0
    warned += _warned(capsys.readouterr().err, str(leaf))
    assert any("not one leaf" in w for w in warned)
    assert main([*argv, str(tmp_path / "forced"), "--force"]) == 0
    rows = {Path(r["input"]).name: r for r in _rows(tmp_path / "forced" / "traits.csv")}
    assert rows["two.txt"]["status"] == "ok" and rows["two.txt"]["warnings"] == "; ".join(warned)


def test_a_leaf_row_warns_as_reconstruct_does(tmp_path, capsys):
    """A leaf whose vein lies far off the boundary's plane: reconstruct warns about it
    (plausibility.leaf_warnings), and so does the batch row."""
    demo = ls.demo("nested")
    far = demo.veins[0] + [0.0, 0.0, 5 * np.ptp(demo.boundary[:, 0])]
    path = tmp_path / "far.csv"
    ls.save_leaf(ls.Leaf(boundary=demo.boundary, veins=[far, *demo.veins[1:]]), path)
    assert main(["reconstruct", str(path), "-o", str(tmp_path / "far.ply"), "--grid", GRID]) == 0
    warned = _warned(capsys.readouterr().err, str(path))
    assert any("from the boundary's plane" in w for w in warned)
    settings = Settings(ls.Params(grid=int(GRID)))
    row = run_job(plan([path], tmp_path / "out", settings)[0])
    assert row["status"] == "ok" and row["warnings"] == "; ".join(warned)


def test_a_job_run_in_the_callers_process_gives_its_threads_back(tmp_path):
    """run_job pins one BLAS and one numba thread while it runs; in the caller's own process it
    gave them back never, so later fits there differed (a scan's far-area 0.02% -> 0.098%)."""
    from threadpoolctl import threadpool_info

    numba = pytest.importorskip("numba")
    path = tmp_path / "nested.csv"
    ls.save_leaf(ls.demo("nested"), path)
    jobs = plan([path], tmp_path / "out", Settings(ls.Params(grid=int(GRID))))
    # numba's threads launched (they load libgomp, whose pool is then in `before` too; a job
    # launches them when no test before it in this process has)
    numba.set_num_threads(numba.get_num_threads())
    before = ([pool["num_threads"] for pool in threadpool_info()], numba.get_num_threads())
    row = run_job(jobs[0])
    assert row["status"] == "ok"
    assert ([pool["num_threads"] for pool in threadpool_info()], numba.get_num_threads()) == before


def test_a_millimetre_leaf_written_to_gltf_without_a_length_is_noted_as_reconstruct_notes_it(
    tmp_path, capsys
):
    """A leaf 60 units long (a photo's or a scan's millimetres) written to glTF, which reads
    units as metres: reconstruct notes it would arrive 60 m long; the batch row did not."""
    demo = ls.demo("nested")
    scale = 60.0 / np.ptp(demo.boundary[:, 0])
    path = tmp_path / "mm.csv"
    ls.save_leaf(ls.Leaf(demo.boundary * scale, [vein * scale for vein in demo.veins]), path)
    out = tmp_path / "mm.glb"
    assert main(["reconstruct", str(path), "-o", str(out), "--grid", GRID]) == 0
    noted = [w for w in _warned(capsys.readouterr().err, str(path)) if "--length" in w]
    assert len(noted) == 1
    params = ls.Params(grid=int(GRID))
    row = run_job(plan([path], tmp_path / "out", Settings(params, format="glb"))[0])
    assert row["status"] == "ok" and noted[0] in (row["warnings"] or "")
    sized = Settings(params, format="glb", length=0.06)  # given its real length: nothing to say
    row = run_job(plan([path], tmp_path / "sized", sized)[0])
    assert row["status"] == "ok" and "--length" not in (row["warnings"] or "")


def test_the_length_a_batch_is_given_is_the_length_its_table_reads(tmp_path):
    """`batch --length 80mm` placed each leaf 80 mm from base to apex but its table measured the
    length along the outline's main axis: 77 mm for a soybean scan, 111 mm for a kidney-shaped
    leaf (wider than long, so its width was read as its length). The table's length is the
    blade's, base to apex, so it reads what was given."""
    form = make_form("reniform")
    path = tmp_path / "kidney.csv"
    ls.save_leaf(form, path)
    settings = Settings(ls.Params(grid=int(GRID)), format="none", length=0.08)
    row = run_job(plan([path], tmp_path / "out", settings)[0])
    assert row["status"] == "ok"
    assert row["length"] == pytest.approx(80, rel=1e-9)
    assert row["width"] == pytest.approx(80 / 0.72, rel=1e-2)


def test_a_batch_given_the_real_length_measures_in_millimetres(tmp_path):
    """`batch --length 8cm` wrote the meshes 80 mm long but kept the traits in the input's units
    (a form 37 units long: length 37, not 80): they are in millimetres now, areas in mm² and
    curvatures in 1/mm and 1/mm²."""
    form = make_form("ovate")
    path = tmp_path / "ovate.csv"
    ls.save_leaf(ls.Leaf(form.boundary * 37, [vein * 37 for vein in form.veins]), path)
    params = ls.Params(grid=int(GRID))
    own, real = (
        run_job(plan([path], tmp_path / name, Settings(params, format="none", length=length))[0])
        for name, length in (("own", None), ("real", 0.08))
    )
    assert own["status"] == real["status"] == "ok"
    assert own["length"] == pytest.approx(37, rel=0.01)
    assert real["length"] == pytest.approx(80, rel=1e-9)
    scale = real["length"] / own["length"]
    for name, power in [("area", 2), ("perimeter", 1), ("height", 1), ("aspect_ratio", 0)]:
        assert real[name] == pytest.approx(own[name] * scale**power, rel=1e-9), name
    for stat in ("mean", "min", "max"):
        assert real[f"mean_curvature_{stat}"] == pytest.approx(
            own[f"mean_curvature_{stat}"] / scale, rel=1e-9
        )
        assert real[f"gaussian_curvature_{stat}"] == pytest.approx(
            own[f"gaussian_curvature_{stat}"] / scale**2, rel=1e-9
        )


def test_a_length_run_does_not_resume_rows_measured_in_the_inputs_units():
    """A --length table written while its traits stayed in the input's units had the same
    settings key: resumed, one table held a length of 37 beside one of 80 (mm)."""
    before = {"format": "none", "force": False, "points": OUTLINE_POINTS, "scans": False}
    for length in (None, 0.08):
        settings = Settings(ls.Params(grid=64), format="none", length=length)
        text = json.dumps(
            {"params": settings.params.to_dict(), **before}
            | ({"length": length} if length is not None else {}),
            sort_keys=True,
        )
        old_key = hashlib.sha256(text.encode()).hexdigest()[:16]
        assert (settings.key() == old_key) == (length is None)  # without a length: unchanged


def test_a_scan_batch_given_the_real_length_gives_its_distances_in_millimetres(scans, tmp_path):
    """The scan columns scan_mean and scan_p95 are distances (the scan's units): in a --length
    table in millimetres they stayed in the scan's own units beside the traits in mm."""
    params = ls.Params(grid=int(GRID))
    path = scans / "scan0.txt"
    own, real = (
        run_job(plan([path], tmp_path / name, Settings(params, True, "none", length=length))[0])
        for name, length in (("own", None), ("real", 0.08))
    )
    assert own["status"] == real["status"] == "ok"
    scale = real["length"] / own["length"]
    assert scale > 1  # a soybean leaf of about 63 mm given 8 cm
    for name in ("scan_mean", "scan_p95"):
        assert real[name] == pytest.approx(own[name] * scale, rel=1e-9)
    for name in ("scan_points", "scan_beyond_1pct", "scan_beyond_2pct", "scan_folded"):
        assert real[name] == own[name]  # counts and shares
    assert 0 <= own["scan_folded"] < 0.01  # the share of the mesh's edges folded back


def test_a_flat_blades_k_is_empty_in_csv_and_null_in_json_not_its_placeholder_1(tmp_path):
    """A blade with its veins in its plane fits no mixture (Result.fits_no_mixture): its
    placeholder Gaussian's K of 1 was the row's "k", a K that did nothing. The table leaves it
    empty (CSV) or null (JSON lines), as the README says; a relief's K stays."""
    t = np.linspace(0, 2 * np.pi, 80, endpoint=False)
    boundary = np.column_stack([np.cos(t), 0.4 * np.sin(t), 0 * t])
    x = np.linspace(-0.9, 0.9, 20)
    flat = ls.Leaf(boundary, [np.column_stack([x, 0 * x, 0 * x])])
    ls.save_leaf(flat, tmp_path / "flat.csv")
    ls.save_leaf(ls.demo("nested"), tmp_path / "nested.csv")
    settings = Settings(ls.Params(k=3, grid=int(GRID)), format="none")
    jobs = plan([tmp_path / "flat.csv", tmp_path / "nested.csv"], tmp_path / "out", settings)
    rows = {Path(row["input"]).stem: row for row in map(run_job, jobs)}
    assert rows["flat"]["k"] is None and rows["nested"]["k"] == 3
    for name in ("t.csv", "t.json"):
        table = TraitTable(tmp_path / name, scans=False)
        table.start()
        for row in rows.values():
            table.add(row)
        table.close()
    by_input = {Path(r["input"]).stem: r for r in _rows(tmp_path / "t.csv")}
    assert by_input["flat"]["k"] == "" and by_input["nested"]["k"] == "3"
    lines = [json.loads(line) for line in (tmp_path / "t.json").read_text().splitlines()]
    assert {Path(r["input"]).stem: r["k"] for r in lines} == {"flat": None, "nested": 3}
