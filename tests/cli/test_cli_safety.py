"""No lost data (issue 11): a failed write keeps the old file, an input is never an output, a
failing run changes no output, temporary files never outlive a run; and a command line that
behaves as Python tools do (--version, -v/-q/--debug, a closed pipe)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from leafstudio._shared.safewrite import PART_MARK
from leafstudio.assets.writers import MESH_SUFFIXES
from leafstudio.cli import main
from tests.fifos import released

GRID = ["--grid", "32"]
OLD = b"OLD CONTENT\n"

# Runs command lines in one child process, each after limiting the size of any file it writes
# (the stand-in for a full disk); SIGXFSZ ignored, so a write past the limit fails with EFBIG.
# Each argument is [limit in bytes, command line] as JSON; the child prints [[exit code, stderr],
# ...] as JSON. The limit is the soft one, raised again after each command (one child for many
# commands and limits: a child's start, imports and kernel loading take seconds).
CHILD = """
import io, json, resource, signal, sys
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
_, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
from leafstudio.cli import main
report = []
for line in sys.argv[1:]:
    limit, argv = json.loads(line)
    sys.stderr = io.StringIO()
    resource.setrlimit(resource.RLIMIT_FSIZE, (limit, hard))
    try:
        code = main(argv)
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (hard, hard))
    report.append([code, sys.stderr.getvalue()])
sys.stderr = sys.__stderr__
print(json.dumps(report))
"""


def _cli_many(commands: list[tuple[int, list[str]]], timeout: float = 300) -> list:
    """[exit code, stderr] of each (size limit, command line), all run in one child process."""
    run = subprocess.run(
        [sys.executable, "-c", CHILD, *(json.dumps(c) for c in commands)],
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    assert run.returncode == 0, run.stderr
    return json.loads(run.stdout.strip().splitlines()[-1])


def _one_line(err: str) -> str:
    lines = err.strip().splitlines()
    lines = [line for line in lines if "compiling the numerical kernels" not in line]
    assert len(lines) == 1, lines  # one line, no traceback
    assert "internal error" not in lines[0] and "Traceback" not in err
    return lines[0]


def _leftovers(folder: Path) -> list[str]:
    return [p.name for p in folder.iterdir() if PART_MARK in p.name]


@pytest.fixture(scope="module")
def leaf_csv(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("leaf") / "nested.csv"
    assert main(["demo", "nested", "-o", str(path)]) == 0
    assert main(["reconstruct", str(path), "-o", str(path.with_suffix(".ply")), *GRID]) == 0
    return path  # and the kernels are compiled and cached for the child processes


# --- finding 1: a failed write reports success ---------------------------------------------------


LEAF_SUFFIXES = (".leaf.json", ".csv", ".ply", ".xyz")


@pytest.fixture(scope="module")
def limited(leaf_csv, tmp_path_factory) -> dict[str, tuple[Path, int, str]]:
    """Every output format written under a file-size limit, each over an old file, and a run
    whose figure is past the limit (test_a_failing_figure_write...), all in one child process:
    name -> (output, exit code, stderr)."""
    folder = tmp_path_factory.mktemp("limited")
    jobs: dict[str, tuple[Path, int, list[str]]] = {}
    # 1500 bytes: less than a leaf or a grid-32 mesh in any format
    for suffix in MESH_SUFFIXES:
        out = folder / f"o{suffix}"
        jobs[suffix] = (out, 1500, ["reconstruct", str(leaf_csv), "-o", str(out), *GRID])
    for suffix in LEAF_SUFFIXES:
        out = folder / f"leaf{suffix}"
        jobs[f"leaf{suffix}"] = (out, 1500, ["demo", "nested", "-o", str(out)])
    for out, _, _ in jobs.values():
        out.write_bytes(OLD)
    figure = tmp_path_factory.mktemp("figure")
    mesh, png, metrics = figure / "o.vtp", figure / "f.png", figure / "m.json"
    for path in (mesh, png, metrics):
        path.write_bytes(OLD)
    # the mesh (about 30 kB) and the metrics fit under 100 kB, the figure (about 180 kB) not
    args = ["reconstruct", str(leaf_csv), "-o", str(mesh), "--grid", "8", "--k", "1",
            "--figure", str(png), "--metrics", str(metrics)]  # fmt: skip
    jobs["figure"] = (figure, 100_000, args)
    report = _cli_many([(limit, args) for _, limit, args in jobs.values()])
    return {
        name: (out, code, err)
        for (name, (out, _, _)), (code, err) in zip(jobs.items(), report, strict=True)
    }


def test_a_failing_figure_write_keeps_every_output_it_would_have_replaced(limited):
    folder, code, err = limited["figure"]
    assert code == 2 and "f.png" in _one_line(err)
    for name in ("o.vtp", "f.png", "m.json"):
        assert (folder / name).read_bytes() == OLD
    assert _leftovers(folder) == []


@pytest.mark.parametrize("name", [*MESH_SUFFIXES, *(f"leaf{s}" for s in LEAF_SUFFIXES)])
def test_a_write_past_the_file_size_limit_keeps_the_old_file(limited, name):
    out, code, err = limited[name]
    assert code == 2, err
    line = _one_line(err)
    assert str(out.parent / out.name.split(".")[0]) in line  # o_texture.png may fail first
    assert PART_MARK not in line and out.read_bytes() == OLD
    assert _leftovers(out.parent) == []


def test_a_full_device_or_a_special_file_is_refused_before_any_work(leaf_csv, tmp_path, capsys):
    mesh = tmp_path / "o.ply"
    mesh.write_bytes(OLD)
    if Path("/dev/full").exists():
        code = main(["reconstruct", str(leaf_csv), "-o", str(mesh), "--metrics", "/dev/full"])
        assert code == 2 and "/dev/full" in _one_line(capsys.readouterr().err)
    assert mesh.read_bytes() == OLD


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_a_read_only_folder_is_one_line_and_exit_2(leaf_csv, tmp_path, capsys):
    folder = tmp_path / "ro"
    folder.mkdir()
    out = folder / "o.ply"
    out.write_bytes(OLD)
    folder.chmod(0o555)
    try:
        assert main(["reconstruct", str(leaf_csv), "-o", str(out), *GRID]) == 2
        assert str(out) in _one_line(capsys.readouterr().err)
        assert out.read_bytes() == OLD
    finally:
        folder.chmod(0o755)


def test_an_output_under_a_file_is_one_line_and_exit_2(leaf_csv, tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_bytes(OLD)
    mesh = tmp_path / "o.ply"
    mesh.write_bytes(OLD)
    code = main(["reconstruct", str(leaf_csv), "-o", str(mesh), "--metrics",
                 str(blocker / "m.json"), *GRID])  # fmt: skip
    assert code == 2 and "m.json" in _one_line(capsys.readouterr().err)
    assert mesh.read_bytes() == OLD and blocker.read_bytes() == OLD


# --- finding 2: the output can overwrite the input -----------------------------------------------


def test_an_output_that_is_the_input_is_refused(leaf_csv, tmp_path, capsys):
    leaf_ply = tmp_path / "leaf.ply"
    assert main(["demo", "nested", "-o", str(leaf_ply)]) == 0
    before = leaf_ply.read_bytes()
    assert main(["reconstruct", str(leaf_ply), "-o", str(leaf_ply)]) == 2
    assert "is also an input" in _one_line(capsys.readouterr().err)
    # the same file by another name: a relative path, and a hard link
    os.link(leaf_ply, tmp_path / "link.ply")
    assert main(["reconstruct", str(leaf_ply), "-o", str(tmp_path / "link.ply")]) == 2
    assert "is also an input" in _one_line(capsys.readouterr().err)
    assert leaf_ply.read_bytes() == before
    csv_before = leaf_csv.read_bytes()
    assert main(["reconstruct", str(leaf_csv), "-o", str(tmp_path / "x.ply"), "--metrics",
                 str(leaf_csv)]) == 2  # fmt: skip
    assert "is also an input" in _one_line(capsys.readouterr().err)
    assert leaf_csv.read_bytes() == csv_before and not (tmp_path / "x.ply").exists()
    assert main(["reconstruct", str(leaf_csv), "-o", str(tmp_path / "x.ply"), "--metrics",
                 str(tmp_path / "x.ply")]) == 2  # fmt: skip
    assert "two outputs" in _one_line(capsys.readouterr().err)


def test_extract_refuses_to_overwrite_its_scan(tmp_path, capsys):
    scan = tmp_path / "scan.ply"
    scan.write_bytes(OLD)
    assert main(["extract", str(scan), "-o", str(scan)]) == 2
    assert "is also an input" in _one_line(capsys.readouterr().err)
    assert scan.read_bytes() == OLD


# --- finding 3: a failing run can still change outputs; temporaries left behind ------------------


def test_an_output_folder_is_named_not_its_temporary_file(leaf_csv, tmp_path, capsys):
    folder = tmp_path / "x.ply"
    folder.mkdir()
    assert main(["reconstruct", str(leaf_csv), "-o", str(folder)]) == 2
    line = _one_line(capsys.readouterr().err)
    assert str(folder) in line and "folder" in line and PART_MARK not in line


def test_a_later_write_removes_what_a_killed_run_left(leaf_csv, tmp_path):
    out = tmp_path / "o.ply"
    dead = 2**22 + 12345  # above the usual pid_max: no live process has it
    stale = tmp_path / f".o.ply.{dead}-0badcafe.{PART_MARK}.ply"
    stale.write_bytes(OLD)
    other = tmp_path / f".p.ply.{dead}-0badcafe.{PART_MARK}.ply"  # another target's: kept
    other.write_bytes(OLD)
    assert main(["reconstruct", str(leaf_csv), "-o", str(out), *GRID]) == 0
    assert not stale.exists() and other.exists()


def test_stale_part_names_the_target_of_a_dead_processs_temporary_file():
    """safewrite.stale_part: the one reading of a temporary file's name (remove_stale and
    batch.remove_temporaries both use it)."""
    from leafstudio._shared.safewrite import _temp_name, stale_part

    dead = 2**22 + 12345
    assert stale_part(f".o.ply.{dead}-0badcafe.{PART_MARK}.ply") == "o.ply"
    assert stale_part(f".a.leaf.json.{dead}-0badcafe.{PART_MARK}.leaf.json") == "a.leaf.json"
    assert stale_part(f".plain.{dead}-0badcafe.{PART_MARK}") == "plain"
    live = _temp_name(Path("a.b.ply"))  # this process's own: not stale
    assert stale_part(live) is None
    assert stale_part(live.replace(f".{os.getpid()}-", f".{dead}-")) == "a.b.ply"
    assert stale_part("o.ply") is None and stale_part(f".o.ply.x-1.{PART_MARK}.ply") is None


# Ctrl-C as at a terminal: a suite started in the background (`cmd &`) hands its children SIGINT
# ignored, and Python then leaves it ignored; the child script puts Python's own handler back
# (not a preexec_fn: unsafe in a process with threads, as the suite's worker is, and a child
# forked from one could deadlock before exec)
WRITER = """
import signal, sys, time
signal.signal(signal.SIGINT, signal.default_int_handler)
from pathlib import Path
from leafstudio._shared.safewrite import install_signal_cleanup, replace_atomically
install_signal_cleanup()

def write(tmp):
    Path(tmp).write_bytes(b"x" * 1000)
    print("writing", flush=True)
    time.sleep(60)

replace_atomically(sys.argv[1], write)
"""


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_during_a_write_removes_the_temporary_file(tmp_path, sig):
    out = tmp_path / "o.ply"
    out.write_bytes(OLD)
    child = subprocess.Popen(
        [sys.executable, "-c", WRITER, str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    try:
        assert child.stdout.readline().strip() == b"writing"
        assert len(_leftovers(tmp_path)) == 1
        child.send_signal(sig)
        child.wait(timeout=30)
    finally:
        if child.poll() is None:
            child.kill()
    assert child.returncode != 0
    assert out.read_bytes() == OLD and _leftovers(tmp_path) == []


# --- warnings: on stderr, one line each, and in --metrics ----------------------------------------


def test_veins_far_above_the_leaf_are_a_warning_in_stderr_and_metrics(tmp_path, capsys):
    from leafstudio.model import Leaf
    from leafstudio.sources.demos import demo
    from leafstudio.sources.files import save_leaf

    leaf = demo("nested")
    high = Leaf(leaf.boundary, [v + [0, 0, 1000 * np.ptp(leaf.boundary[:, 0])] for v in leaf.veins])
    path = tmp_path / "high.leaf.json"
    save_leaf(high, path)
    metrics = tmp_path / "m.json"
    code = main(["reconstruct", str(path), "-o", str(tmp_path / "o.ply"), *GRID, "--metrics",
                 str(metrics)])  # fmt: skip
    err = capsys.readouterr().err
    if code == 2:  # refused outright is also an answer
        _one_line(err)
        return
    assert code == 0
    warned = [line for line in err.splitlines() if "from the boundary's plane" in line]
    assert warned and all(line.startswith("leafstudio: warning: ") for line in warned)
    assert any(
        "from the boundary's plane" in w for w in json.loads(metrics.read_text())["warnings"]
    )


# --- findings 4 and 5 at the command line --------------------------------------------------------


def test_seeds_out_of_range_and_long_values_are_one_short_line(leaf_csv, tmp_path, capsys):
    out = str(tmp_path / "o.ply")
    for seed in (str(2**32), "-1", "1_0", "1.5", "9" * 5000):
        assert main(["reconstruct", str(leaf_csv), "-o", out, "--seed", seed]) == 2
        line = _one_line(capsys.readouterr().err)
        assert "--seed" in line and len(line) < 200
    assert main(["reconstruct", str(leaf_csv), "-o", out, "--seed", str(2**32 - 1), *GRID]) == 0


def test_coordinates_near_1e150_or_1e200_are_answered(tmp_path, capsys):
    from leafstudio.sources.demos import demo

    leaf = demo("nested")
    for scale in (1e150, 1e200, 1e300):
        path = tmp_path / "big.csv"
        rows = np.vstack([leaf.boundary, *leaf.veins]) * scale
        labels = np.concatenate([[0] * len(leaf.boundary)] + [[i + 1] * len(v) for i, v in
                                                               enumerate(leaf.veins)])  # fmt: skip
        np.savetxt(path, np.column_stack([rows, labels]), delimiter=",")
        code = main(["reconstruct", str(path), "-o", str(tmp_path / "o.ply"), *GRID])
        err = capsys.readouterr().err
        assert code in (0, 2), err
        if code == 2:
            _one_line(err)


def test_an_open_arc_as_a_boundary_is_answered(tmp_path, capsys):
    t = np.linspace(0, np.pi, 60)
    path = tmp_path / "arc.csv"
    np.savetxt(path, np.column_stack([np.cos(t), np.sin(t), 0 * t]), delimiter=",")
    code = main(["reconstruct", str(path), "-o", str(tmp_path / "o.ply"), *GRID])
    err = capsys.readouterr().err
    assert code in (0, 2), err
    if code == 2:
        _one_line(err)


def _sphere(n: int = 2000) -> np.ndarray:
    v = np.random.default_rng(0).normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1)[:, None]


def _sheet(n: int = 2000, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    xy = rng.uniform(-1, 1, size=(n, 2)) * [1.0, 0.4]
    return np.column_stack([xy, 0.1 * xy[:, 0] ** 2 + 0.002 * rng.normal(size=n)])


@pytest.mark.parametrize(
    ("name", "make", "test"),
    [
        ("sphere", _sphere, "not thin"),
        ("blob", lambda: np.random.default_rng(1).normal(size=(2000, 3)), "not thin"),
        ("random", lambda: np.random.default_rng(2).random((50, 3)), "not thin"),
        ("two", lambda: np.vstack([_sheet(), _sheet(seed=1) + [5, 0, 0]]), "large separate"),
    ],
)
def test_extract_refuses_what_is_not_a_leaf_unless_forced(tmp_path, capsys, name, make, test):
    scan = tmp_path / f"{name}.xyz"
    np.savetxt(scan, make())
    out = tmp_path / "leaf.leaf.json"
    assert main(["extract", str(scan), "-o", str(out)]) == 2
    line = _one_line(capsys.readouterr().err)
    assert "does not look like one leaf" in line and test in line and "--force" in line
    assert not out.exists()
    code = main(["extract", str(scan), "-o", str(out), "--force"])
    err = capsys.readouterr().err
    assert code in (0, 2), err
    warned = [line for line in err.splitlines() if line.startswith(f"leafstudio: warning: {scan}")]
    assert any(test in line for line in warned) or code == 2


def test_extract_takes_a_leaf_like_sheet(tmp_path, capsys):
    scan = tmp_path / "sheet.xyz"
    np.savetxt(scan, _sheet())
    assert main(["extract", str(scan), "-o", str(tmp_path / "leaf.leaf.json")]) == 0
    assert "does not look like" not in capsys.readouterr().err


def test_extract_on_a_noisy_line_or_a_huge_scan_is_answered(tmp_path, capsys):
    rng = np.random.default_rng(0)
    t = np.linspace(0, 1, 300)
    for name, points in (
        ("line", np.column_stack([t, 0.01 * rng.normal(size=300), 0.01 * rng.normal(size=300)])),
        ("huge", _sheet() * 1e200),
    ):
        scan = tmp_path / f"{name}.xyz"
        np.savetxt(scan, points)
        code = main(["extract", str(scan), "-o", str(tmp_path / f"{name}.leaf.json")])
        err = capsys.readouterr().err
        assert code in (0, 2), err
        if code == 2:
            _one_line(err)


# --- finding 6 of the CLI part: a CLI that behaves as Python tools do ----------------------------


def test_version(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out.startswith("leafstudio ")


def test_quiet_hides_warnings_and_verbose_shows_info(tmp_path, capsys):
    path = tmp_path / "flat.csv"  # a boundary without veins: the "flat" warning
    t = np.linspace(0, 2 * np.pi, 80, endpoint=False)
    np.savetxt(path, np.column_stack([np.cos(t), 0.5 * np.sin(t), 0 * t]), delimiter=",")
    out = str(tmp_path / "o.ply")
    assert main(["reconstruct", str(path), "-o", out, *GRID]) == 0
    assert "warning" in capsys.readouterr().err
    assert main(["reconstruct", str(path), "-o", out, *GRID, "-q", "-q"]) == 0
    assert "warning" not in capsys.readouterr().err
    assert main(["-q", "reconstruct", str(path), "-o", out, *GRID, "--k", "auto"]) == 0
    assert "chosen by BIC" not in capsys.readouterr().err
    assert main(["reconstruct", str(path), "-o", out, *GRID, "--k", "auto"]) == 0
    said = capsys.readouterr().err
    # a flat blade fits no mixture: its K of 1 was a placeholder, said "chosen by BIC"
    # (appreview31, finding 8's follow-up); a leaf with relief says it: tests/render/test_figure
    assert "K = unused (the blade is flat)" in said and "chosen by BIC" not in said


@pytest.mark.internal_error
def test_a_bug_is_one_line_and_debug_shows_its_traceback(monkeypatch, capsys):
    import leafstudio.cli as cli

    def broken(args):
        raise RuntimeError("a bug")

    monkeypatch.setitem(cli.COMMANDS, "demo", broken)
    assert main(["demo", "nested", "-o", "x.csv"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "internal error: RuntimeError: a bug" in err
    assert "--debug" in err
    assert main(["demo", "nested", "-o", "x.csv", "--debug"]) == 1
    err = capsys.readouterr().err
    assert "Traceback" in err and "RuntimeError: a bug" in err


def test_a_closed_pipe_ends_quietly():
    read, write = os.pipe()
    os.close(read)
    try:
        run = subprocess.run(
            [sys.executable, "-m", "leafstudio", "reconstruct", "--help"],
            stdout=write,
            stderr=subprocess.PIPE,
            timeout=60,
        )
    finally:
        os.close(write)
    assert run.returncode == 0 and run.stderr == b""


def test_a_fifo_is_refused_at_once_not_read_for_ever(tmp_path, capsys):
    """A FIFO with no writer is refused by its type at once, instead of blocking for ever."""
    fifo = tmp_path / "leaf.csv"
    os.mkfifo(fifo)
    with released([fifo]) as freed:  # in this process: a command that opens it is released
        code = main(["reconstruct", str(fifo), "-o", str(tmp_path / "o.ply")])
    assert not freed, "reconstruct opened the pipe"
    assert code == 2 and "pipe" in _one_line(capsys.readouterr().err)


def test_a_boundary_that_crosses_itself_is_an_error_naming_where(tmp_path, capsys):
    import re

    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    path = tmp_path / "eight.csv"
    eight = np.column_stack([np.sin(t), 0.6 * np.sin(t) * np.cos(t), 0 * t])
    np.savetxt(path, eight, delimiter=",")
    assert main(["reconstruct", str(path), "-o", str(tmp_path / "o.ply"), *GRID]) == 2
    line = _one_line(capsys.readouterr().err)
    where = re.search(r"crosses itself near \(([^)]*)\)", line)
    assert where and np.allclose([float(v) for v in where.group(1).split(",")], 0, atol=1e-6)
    # a plain ellipse in the same order is fine
    ellipse = tmp_path / "ellipse.csv"
    np.savetxt(ellipse, np.column_stack([np.cos(t), 0.6 * np.sin(t), 0 * t]), delimiter=",")
    assert main(["reconstruct", str(ellipse), "-o", str(tmp_path / "o.ply"), *GRID]) == 0


def test_a_boundary_with_a_hole_or_two_loops_keeps_the_largest_and_says_so(tmp_path, capsys):
    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    outer = np.column_stack([np.cos(t), 0.6 * np.sin(t), 0 * t])
    for name, second, what in (
        ("hole", outer * 0.2, "1 hole inside it"),
        ("two", outer * 0.5 + [3, 0, 0], "1 separate loop"),
    ):
        path = tmp_path / f"{name}.csv"
        np.savetxt(path, np.vstack([outer, second]), delimiter=",")
        metrics = tmp_path / f"{name}.json"
        code = main(["reconstruct", str(path), "-o", str(tmp_path / "o.ply"), *GRID,
                     "--metrics", str(metrics)])  # fmt: skip
        assert code == 0
        err = capsys.readouterr().err
        assert f"kept the largest (points 1-200) and dropped {what}" in err
        data = json.loads(metrics.read_text())
        assert any("kept the largest" in w for w in data["warnings"])
        assert abs(data["mesh"]["area"] - np.pi * 0.6) < 0.05  # the outer ellipse's area


def test_veins_refuses_to_overwrite_its_leaf(leaf_csv, tmp_path, capsys):
    before = leaf_csv.read_bytes()
    assert main(["veins", str(leaf_csv), "-o", str(leaf_csv)]) == 2
    assert "is also an input" in _one_line(capsys.readouterr().err)
    assert leaf_csv.read_bytes() == before


def test_a_dense_leaf_like_scan_passes_the_plausibility_tests():
    from leafstudio.core.prepare.plausibility import leaf_like_problems

    dense = _sheet(1_000_000)  # its noise, at this density, once read as "not a surface"
    assert leaf_like_problems(dense) == []
    assert "large separate" in leaf_like_problems(np.vstack([dense, dense + [5, 0, 0]]))[0]
