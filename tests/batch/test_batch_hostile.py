"""Issue 24, batch's findings: `ls.batch` from a plain script (no `__main__` guard), a batch whose
every input failed, a refused --scheduler leaving a table behind, scheduler addresses and a
damaged --resume table answered in one line, and inputs that are pipes or endless devices."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

import leafstudio as ls
from leafstudio.cli import main
from leafstudio.errors import LeafError
from tests.fifos import released

ROOT = Path(__file__).resolve().parents[2]
LEAFSTUDIO = [sys.executable, "-m", "leafstudio"]


@pytest.fixture(scope="module")
def leaves(tmp_path_factory) -> Path:
    """Two leaf files."""
    root = tmp_path_factory.mktemp("two")
    demo = ls.demo("nested")
    for i in range(2):
        ls.save_leaf(ls.Leaf(boundary=demo.boundary + i, veins=[v + i for v in demo.veins]),
                     root / f"leaf{i}.csv")  # fmt: skip
    return root


def _script(
    tmp_path: Path, inputs: str, scheduler: str | None = None
) -> subprocess.CompletedProcess:
    """The README's `ls.batch` example saved as a plain script (no __main__ guard), and run."""
    script = tmp_path / "plain.py"
    script.write_text(
        "import leafstudio as ls\n"
        f"for row in ls.batch([{inputs!r}], ls.Params(grid=32), {str(tmp_path / 'out')!r}, "
        f"jobs=1, scheduler={scheduler!r}):\n"
        "    print(row['input'], row['status'], row['error'])\n"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=300, env=env, cwd=tmp_path)  # fmt: skip


def test_a_plain_script_without_a_main_guard_runs_its_batch(tmp_path, leaves):
    """Finding 2: every row failed with "the worker process died" (each spawned worker ran the
    script again while importing it), a bootstrapping traceback was printed, and it exited 0."""
    done = _script(tmp_path, str(leaves))
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr
    lines = done.stdout.splitlines()
    assert len(lines) == 2 and all(line.split()[1] == "ok" for line in lines), done.stdout


def test_a_plain_script_runs_its_batch_on_a_local_dask_cluster(tmp_path, leaves):
    """As finding 2, on `scheduler="local"`: each Dask worker, spawned, ran the script again
    while importing it and started a cluster of its own ("Nanny failed to start")."""
    pytest.importorskip("distributed")
    done = _script(tmp_path, str(leaves), scheduler="local")
    assert done.returncode == 0, done.stderr[-2000:]
    lines = done.stdout.splitlines()
    assert len(lines) == 2 and all(line.split()[1] == "ok" for line in lines), done.stdout


@pytest.mark.usefixtures("warm_pools")
def test_a_batch_whose_every_input_failed_raises(tmp_path):
    """Finding 3: a script whose every input failed exited 0; ls.batch now raises LeafError once
    every row is yielded and written, so the script exits non-zero."""
    bad = tmp_path / "bad.csv"
    bad.write_text("1 2\n")
    rows = []
    with pytest.raises(LeafError, match="every input failed"):
        rows.extend(ls.batch([bad], ls.Params(grid=32), tmp_path / "out", jobs=1))
    assert [r["status"] for r in rows] == ["failed"]
    assert (tmp_path / "out" / "traits.csv").read_text().count("\n") == 2  # the row is written
    done = _script(tmp_path, str(bad))
    assert done.returncode != 0 and "every input failed" in done.stderr
    assert "bad.csv failed" in done.stdout


def _line(argv: list[str], capsys) -> str:
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    return err.strip()


def test_a_scheduler_refused_for_a_missing_extra_leaves_no_table(tmp_path, leaves, monkeypatch,
                                                                 capsys):  # fmt: skip
    """Finding 12: exit 2, but OUTDIR/traits.csv was left behind."""
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed fails
    out = tmp_path / "out"
    line = _line(["batch", str(leaves), "-o", str(out), "--scheduler", "local"], capsys)
    assert "pip install 'leafstudio[cluster]'" in line
    assert not out.exists()


@pytest.mark.parametrize(
    "address",
    ["foo://127.0.0.1:8786", "tcp://127.0.0.1", "not an address", "tcp://[::1", "inproc://nothing",
     "LOCAL"],
)  # fmt: skip
def test_a_bad_scheduler_address_is_one_line(tmp_path, leaves, capsys, address):
    """Finding 16: these ended in "internal error" (only OSError was caught)."""
    pytest.importorskip("distributed")
    out = tmp_path / "out"
    line = _line(["batch", str(leaves), "-o", str(out), "--scheduler", address], capsys)
    assert line.startswith(f"leafstudio: error: {address}: ")
    assert not out.exists()


@pytest.mark.usefixtures("warm_pools")
def test_resume_over_a_table_with_a_damaged_field_is_one_line(tmp_path, leaves, capsys):
    """Finding 16: `--resume` over a table whose `k` is not a whole number was an internal error."""
    out = tmp_path / "out"
    argv = ["batch", str(leaves / "leaf0.csv"), "-o", str(out), "--grid", "32", "--jobs", "1"]
    assert main(argv) == 0
    table = out / "traits.csv"
    header, row = table.read_text().splitlines()
    names = header.split(",")
    cells = row.split(",")
    cells[names.index("k")] = "three"
    damaged = f"{header}\n{','.join(cells)}\n"
    table.write_text(damaged)
    line = _line([*argv, "--resume"], capsys)
    assert line.startswith(f"leafstudio: error: {table}: ") and "'three'" in line
    assert table.read_text() == damaged  # left as it was


@pytest.mark.usefixtures("warm_pools")
def test_resume_over_a_json_table_with_a_damaged_field_is_one_line_too(tmp_path, leaves, capsys):
    """As the CSV table's: a JSON lines row whose `k` was "three" was resumed as done and
    written back as it was."""
    import json

    out = tmp_path / "out"
    table = out / "traits.json"
    argv = ["batch", str(leaves / "leaf0.csv"), "-o", str(out), "--grid", "32", "--jobs", "1",
            "--traits", str(table)]  # fmt: skip
    assert main(argv) == 0
    row = json.loads(table.read_text())
    row["k"] = "three"
    damaged = json.dumps(row) + "\n"
    table.write_text(damaged)
    line = _line([*argv, "--resume"], capsys)
    assert line.startswith(f"leafstudio: error: {table}: ") and "'three'" in line
    assert table.read_text() == damaged  # left as it was


@pytest.mark.usefixtures("warm_pools")
def test_pipes_and_endless_devices_are_refused_in_one_line(tmp_path, capsys):
    """Finding 17: batch hashed each input before checking what it was: a FIFO blocked for ever,
    a link to /dev/zero read for ever, named outright or inside a folder. Run in this process,
    its rows on the kept workers (tests/fifos.py: a pipe opened by either is released after a
    while, and the test fails)."""
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    zero = tmp_path / "zero.csv"
    zero.symlink_to("/dev/zero")
    folder = tmp_path / "folder"
    folder.mkdir()
    os.mkfifo(folder / "inner.csv")
    (folder / "endless.xyz").symlink_to("/dev/zero")
    capsys.readouterr()
    with released([fifo, folder / "inner.csv"]) as freed:
        code = main(["batch", str(fifo), str(zero), str(folder), "-o", str(tmp_path / "out"),
                     "--jobs", "1"])  # fmt: skip
    err = capsys.readouterr().err
    assert not freed, "batch opened a pipe"
    assert code == 1, err
    errors = [line for line in err.splitlines() if line.startswith("leafstudio: error:")]
    pipe, device = "is a named pipe, not a file", "is a device, not a file"
    assert sorted(errors) == sorted(
        f"leafstudio: error: {path}: {said}"
        for path, said in ((fifo, pipe), (zero, device), (folder / "inner.csv", pipe),
                           (folder / "endless.xyz", device))
    )  # fmt: skip
    assert "4 inputs: 0 ok, 4 failed" in err


def test_a_scheduler_port_that_speaks_http_is_one_line(tmp_path, leaves):
    """Finding 17: `--scheduler` at a web server's port ran past 200 s (distributed's timeout
    covers connecting, not the handshake); now one line, exit 2, after CONNECT_S."""
    pytest.importorskip("distributed")
    import http.server
    import threading

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), http.server.SimpleHTTPRequestHandler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    address = f"tcp://127.0.0.1:{server.server_address[1]}"
    try:
        done = subprocess.run(
            [*LEAFSTUDIO, "batch", str(leaves), "-o", str(tmp_path / "out"), "--scheduler",
             address],
            capture_output=True, text=True, timeout=120, cwd=tmp_path,
        )  # fmt: skip
    finally:
        server.shutdown()
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        f"leafstudio: error: {address}: no Dask scheduler answered within 8 s (is this a Dask "
        "scheduler's address?)"
    ]
    assert not (tmp_path / "out").exists()


def test_an_input_named_with_a_line_break_is_refused_in_one_line(tmp_path, capsys):
    """Finding 15: its table row named 'we ird.csv' and 'we ird.ply', files that do not exist
    (a cell is one line); the batch now refuses it before any work."""
    folder = tmp_path / "in"
    folder.mkdir()
    named = folder / "we\nird.csv"
    ls.save_leaf(ls.demo("nested"), named)
    out = tmp_path / "out"
    line = _line(["batch", str(folder), "-o", str(out), "--grid", "32", "--jobs", "1"], capsys)
    assert line == (
        f"leafstudio: error: {str(named)!r}: a file name with a line break "
        "cannot be a row of the trait table; rename it"
    )
    assert not out.exists()


@pytest.mark.usefixtures("warm_pools")
def test_a_leaf_too_large_to_measure_is_a_row_naming_it(tmp_path):
    """Finding 16: a batch row for a leaf scaled by 1e160 said "internal error: LinAlgError" and
    did not name the input; now the line `measure` gives, naming it."""
    folder = tmp_path / "in"
    folder.mkdir()
    leaf = ls.demo("nested")
    ls.save_leaf(ls.Leaf(leaf.boundary * 1e160, [v * 1e160 for v in leaf.veins]),
                 folder / "huge.leaf.json")  # fmt: skip
    rows = []
    with pytest.raises(LeafError, match="every input failed"):
        rows.extend(ls.batch([folder], ls.Params(grid=32), tmp_path / "out", jobs=1))
    assert [r["status"] for r in rows] == ["failed"]
    assert rows[0]["error"].startswith(f"{folder / 'huge.leaf.json'}: the leaf is too large")


@pytest.mark.usefixtures("warm_pools")
def test_a_tiny_leaf_measure_takes_is_an_ok_row_with_its_figures(tmp_path):
    """A leaf scaled by 1e-90, which `reconstruct` and `measure` take, was a batch row "internal
    error: ZeroDivisionError: Weights sum to zero" (its facets' areas underflowed when batch
    measured the mesh in the input's units); now the row holds measure's figures."""
    leaf = ls.demo("nested")
    tiny = ls.Leaf(leaf.boundary * 1e-90, [v * 1e-90 for v in leaf.veins])
    path = tmp_path / "tiny.leaf.json"
    ls.save_leaf(tiny, path)
    params = ls.Params(grid=32)
    rows = list(ls.batch([path], params, tmp_path / "out", jobs=1))
    assert [r["status"] for r in rows] == ["ok"], rows[0]["error"]
    measured = ls.reconstruct(tiny, params).metrics
    assert rows[0]["area"] == pytest.approx(measured["leaf"]["area"], rel=1e-9)
    curvature = measured["curvature"]["mean_curvature"]["mean"]
    assert rows[0]["mean_curvature_mean"] == pytest.approx(curvature, rel=1e-9)
