"""Small command-line messages (review findings, session 2): a usage error of the main parser said
"see leafstudio leafstudio --help"; a folder given as the input said "unknown file type '(none)'";
a scan with normals and colours given as a leaf said only how many columns it has; an output's
missing folder was created without a word."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from leafstudio.cli import main


def _error(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    errors = [line for line in err if line.startswith("leafstudio: error:")]
    assert len(errors) == 1, err
    return errors[0]


@pytest.mark.parametrize(
    ("argv", "hint"),
    [
        (["forms"], "(see leafstudio --help)"),
        (["form", "--margin", "wavy"], "(see leafstudio form --help)"),
        (["reconstruct", "leaf.csv"], "(see leafstudio reconstruct --help)"),
    ],
)
def test_a_usage_error_names_the_command_once(capsys, argv, hint):
    assert main(argv) == 2
    line = _error(capsys)
    assert line.endswith(hint) and "leafstudio leafstudio" not in line


@pytest.mark.parametrize("command", ["reconstruct", "measure", "compare", "extract", "veins"])
def test_a_folder_given_as_the_input_is_said_to_be_a_folder(tmp_path, capsys, command):
    out = ["-o", str(tmp_path / "out.ply" if command == "reconstruct" else tmp_path / "o.csv")]
    argv = [command, str(tmp_path), *(out if command not in ("measure", "compare") else [])]
    assert main(argv) == 2
    line = _error(capsys)
    assert f"{tmp_path}: is a folder, not a file" in line and "leafstudio batch" in line
    assert "unknown" not in line


def test_a_scan_with_normals_given_as_a_leaf_points_to_extract(tmp_path, capsys):
    path = tmp_path / "scan.txt"
    np.savetxt(path, np.random.default_rng(0).normal(size=(100, 10)), delimiter=",")
    assert main(["measure", str(path)]) == 2
    line = _error(capsys)
    assert "got 10" in line and "leafstudio extract" in line


def test_a_vein_file_with_a_label_gets_no_scan_hint(tmp_path, capsys):
    leaf, vein = tmp_path / "leaf.leaf.json", tmp_path / "vein.csv"
    assert main(["demo", "nested", "-o", str(leaf)]) == 0
    np.savetxt(vein, np.zeros((5, 4)), delimiter=",")
    assert main(["measure", str(leaf), "--vein", str(vein)]) == 2
    line = _error(capsys)
    assert "expected 2 or 3 columns" in line and "extract" not in line


def test_an_outputs_missing_folder_is_created_and_said(tmp_path, capsys):
    target = tmp_path / "new" / "deeper" / "leaf.leaf.json"
    assert main(["demo", "nested", "-o", str(target)]) == 0
    assert target.is_file()
    err = capsys.readouterr().err
    assert f"created the folder {tmp_path / 'new'} for {target}" in err
    assert main(["demo", "nested", "-o", str(target)]) == 0  # it exists now: nothing said
    assert "created" not in capsys.readouterr().err


def _special_files(tmp_path) -> dict[str, tuple[str, str]]:
    """A named pipe with no suffix and one named leaf.csv, a device behind a .xyz name, a socket:
    each path with what the one line says it is."""
    import os
    import socket

    os.mkfifo(tmp_path / "pipe")
    os.mkfifo(tmp_path / "leaf.csv")
    (tmp_path / "zero.xyz").symlink_to("/dev/zero")
    listening = socket.socket(socket.AF_UNIX)
    listening.bind(str(tmp_path / "sock.csv"))
    listening.close()
    return {
        "pipe": (str(tmp_path / "pipe"), "is a named pipe, not a file"),
        "pipe.csv": (str(tmp_path / "leaf.csv"), "is a named pipe, not a file"),
        "device": (str(tmp_path / "zero.xyz"), "is a device, not a file"),
        "socket": (str(tmp_path / "sock.csv"), "is a socket, not a file"),
    }


@pytest.mark.parametrize("kind", ["pipe", "pipe.csv", "device", "socket"])
@pytest.mark.parametrize(
    "command", ["gui", "reconstruct", "measure", "compare", "extract", "veins", "photo", "slides"]
)
def test_a_pipe_a_device_or_a_socket_given_as_the_input_is_said_to_be_one(
    tmp_path, capsys, command, kind
):
    """Issue 24: `gui FIFO` (and every command) said "unknown file type '(none)'", and `gui`
    given a pipe named leaf.csv waited for ever (the app sniffed it for a scan); now one line
    that says what it is, exit 2, before anything opens it."""
    path, said = _special_files(tmp_path)[kind]
    outputs = {"reconstruct": "o.ply", "extract": "o.leaf.json", "veins": "o.leaf.json",
               "photo": "o.leaf.json", "slides": "slides"}  # fmt: skip
    out = ["-o", str(tmp_path / outputs[command])] if command in outputs else []
    assert main([command, path, *out]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"leafstudio: error: {path}: {said}"]


@pytest.mark.parametrize(
    "argv",
    [
        ["form", "ovate", "-o", "{tmp}/leaf.glb"],
        ["compare", "{tmp}/leaf.leaf.json", "--grid", "32"],
    ],
)
def test_every_command_that_reconstructs_says_a_first_run_compiles(tmp_path, capsys, monkeypatch,
                                                                  argv):  # fmt: skip
    """`form NAME -o x.glb` and `compare` reconstruct too: on a cold cache they said nothing for
    the compile's 20-30 s, where `reconstruct` says it compiles (issue 24, first hour)."""
    from leafstudio._shared.kernelcache import NOTICE
    from leafstudio.cli import options

    assert main(["demo", "nested", "-o", str(tmp_path / "leaf.leaf.json")]) == 0
    stamped = []
    monkeypatch.setattr(options, "kernels_cached", lambda: bool(stamped))  # cold, until marked
    monkeypatch.setattr(options, "mark_cached", lambda: stamped.append(True))
    capsys.readouterr()
    assert main([a.format(tmp=tmp_path) for a in argv]) == 0
    assert NOTICE in capsys.readouterr().err
    assert stamped  # once it ran, the next run says nothing


def test_a_local_batch_says_a_first_run_compiles(tmp_path, capsys, monkeypatch):
    """`batch`'s pool compiles both tables before its first row: 28 s of silence on a cold
    cache without a terminal (no progress bar), where `reconstruct` says it compiles."""
    from types import SimpleNamespace

    from leafstudio._shared.kernelcache import NOTICE
    from leafstudio.batch import run as batch_run
    from leafstudio.cli import options

    table = SimpleNamespace(path=tmp_path / "out")
    ran = SimpleNamespace(
        total=1, ok=0, failed=0, resumed=0, stopped=False, table=table, run=lambda: iter(())
    )
    monkeypatch.setattr(batch_run, "batch", lambda *args, **kwargs: ran)  # the command's own
    monkeypatch.setattr(options, "kernels_cached", lambda: False)
    assert main(["batch", str(tmp_path), "-o", str(tmp_path / "out")]) == 0
    assert NOTICE in capsys.readouterr().err
    monkeypatch.setattr(options, "kernels_cached", lambda: True)  # compiled: nothing said
    assert main(["batch", str(tmp_path), "-o", str(tmp_path / "out")]) == 0
    assert "ompiling" not in capsys.readouterr().err


def test_a_batch_of_scans_without_scans_says_so_once(tmp_path, capsys, monkeypatch):
    """`batch FOLDER` on a folder of scans (no --scans) failed every row with reconstruct's
    hint, `leafstudio extract SCAN -o LEAF`, which a batch user cannot follow for hundreds of
    files: the summary now names --scans."""
    from types import SimpleNamespace

    from leafstudio.batch import run as batch_run

    scan = "a.txt: ...: this looks like a scan of the whole leaf; `leafstudio extract SCAN -o LEAF`"
    rows = [{"status": "failed", "error": scan}, {"status": "failed", "error": "b.csv: bad"}]
    table = SimpleNamespace(path=tmp_path / "out")
    ran = SimpleNamespace(
        total=2, ok=0, failed=2, resumed=0, stopped=False, table=table, run=lambda: iter(rows)
    )
    monkeypatch.setattr(batch_run, "batch", lambda *args, **kwargs: ran)  # the command's own
    assert main(["batch", str(tmp_path), "-o", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err
    assert "1 of the inputs look like scans of whole leaves: --scans" in err
    assert main(["batch", str(tmp_path), "-o", str(tmp_path / "out"), "--scans"]) == 1
    assert "--scans" not in capsys.readouterr().err


def test_a_demo_written_as_a_mesh_says_which_files_take_a_leaf_and_how_to_mesh_it(tmp_path, capsys):
    """`demo nested -o x.glb` said only "cannot write a leaf as '.glb'", where `form` writes a
    mesh (bug hunt, session 27): the message names a leaf's files and `reconstruct`."""
    assert main(["demo", "nested", "-o", str(tmp_path / "x.glb")]) == 2
    line = _error(capsys)
    assert ".leaf.json" in line and ".csv" in line and "leafstudio reconstruct" in line
    assert not (tmp_path / "x.glb").exists()


def test_a_form_with_its_midrib_alone_says_one_vein(tmp_path, capsys):
    """`form ovate --secondaries 0` said "1 veins" (bug hunt, session 27)."""
    assert main(["form", "ovate", "--secondaries", "0", "-o", str(tmp_path / "x.csv")]) == 0
    assert capsys.readouterr().err.rstrip().endswith("502 boundary points, 1 vein")


def test_a_posed_form_written_as_a_point_list_says_its_pose_is_not_kept(tmp_path, capsys):
    """`form lanceolate --twist 1 -o x.csv` wrote the bent points without a word of the pose
    they lose, where `extract` says so of a scan's sheet (review appreview31, finding 10): one
    warning line, none for a project or a flat form."""
    assert main(["form", "lanceolate", "--twist", "1", "-o", str(tmp_path / "x.csv")]) == 0
    warned = [line for line in capsys.readouterr().err.splitlines() if "warning" in line]
    assert len(warned) == 1
    assert "x.csv: a point list keeps the bent points, not its pose" in warned[0]
    assert "a .leaf.json keeps it" in warned[0]
    for argv in (["lanceolate", "--twist", "1", "-o", "x.leaf.json"], ["ovate", "-o", "y.csv"]):
        assert main(["form", *argv[:-1], str(tmp_path / argv[-1])]) == 0
        assert "warning" not in capsys.readouterr().err


def test_a_bent_point_list_refused_says_it_may_have_lost_its_pose(tmp_path, capsys):
    """`reconstruct` of a CSV of lanceolate twisted 1 was refused, "vein 1: 2 of 49 points lie
    outside the boundary"; the message now says the leaf is bent and no pose lays it flat, as a
    posed leaf saved as a point list would be. That twist is now unfolded (core/unfold.py,
    unfold33); rolled 0.8 as well, which the fit does not take (a roll and a twist together),
    it is refused as its outline crosses itself on its plane, with the same hint. A flat leaf's
    stray vein is refused without that hint."""
    from leafstudio.model import Leaf
    from leafstudio.sources.files import save_leaf

    argv = ["form", "lanceolate", "--roll", "0.8", "--twist", "1", "-o", str(tmp_path / "x.csv")]
    assert main(argv) == 0
    capsys.readouterr()
    assert main(["reconstruct", str(tmp_path / "x.csv"), "-o", str(tmp_path / "x.ply")]) == 2
    line = _error(capsys)
    assert "the boundary crosses itself" in line
    assert "bent in 3D and no pose lays it flat" in line and "its .leaf.json does" in line
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    stray = np.column_stack([np.linspace(0.2, 1.6, 20), np.full(20, 0.5), np.zeros(20)])
    save_leaf(Leaf(square, [stray]), tmp_path / "flat.csv")
    assert main(["reconstruct", str(tmp_path / "flat.csv"), "-o", str(tmp_path / "f.ply")]) == 2
    line = _error(capsys)
    assert "lie outside the boundary" in line and "no pose" not in line


def _closing_line_args(command: str, tmp_path: Path) -> tuple[list[str], str]:
    """A `command` line that succeeds, and the name its closing line says it wrote."""
    from leafstudio.forms import make_form
    from tests.leaves import synthetic_scan

    leaf = tmp_path / "f.leaf.json"
    if command == "form":
        return ["form", "ovate", "-o", str(leaf)], leaf.name
    if command == "extract":
        scan = tmp_path / "scan.xyz"
        np.savetxt(scan, synthetic_scan(seed=4)["blade"])
        return ["extract", str(scan), "-o", str(leaf), "--points", "150"], leaf.name
    form = make_form("ovate")
    if command == "photo":
        from PIL import Image

        from tests.photos import form_photo

        image = tmp_path / "leaf.png"
        Image.fromarray(form_photo(form.boundary, form.veins)[0]).save(image)
        return ["photo", str(image), "-o", str(leaf), "--veins", "none"], leaf.name
    import leafstudio as ls

    given = tmp_path / "given.csv"
    ls.save_leaf(form, given)
    if command == "veins":
        return ["veins", str(given), "-o", str(leaf)], leaf.name
    pdf = tmp_path / "lesson.pdf"
    return ["slides", str(given), "-o", str(pdf), "--grid", "32"], pdf.name


@pytest.mark.parametrize("command", ["form", "extract", "veins", "photo", "slides"])
def test_quiet_silences_a_commands_closing_line(tmp_path, capsys, command):
    """`form … -q` and `extract … -q` printed their closing line ("f.leaf.json: ovate leaf
    (…)", "scan.xyz: blade of … wrote …") all the same (appreview31); -q hides it as it hides
    reconstruct's notes. Without -q it is said on stderr, as those notes are: extract's and
    slides' were on stdout, the others' on stderr (assets33); stdout is for what a command is
    asked to print (measure's table). photo, veins and slides had no -q test of their own."""
    args, wrote = _closing_line_args(command, tmp_path)
    assert main(args) == 0
    said = capsys.readouterr()
    assert said.out == "" and wrote in said.err, said
    for quiet in (["-q"], ["-q", "-q"]):
        assert main([*args, *quiet]) == 0
        said = capsys.readouterr()
        assert said.out == "" and said.err == "", (quiet, said)
    assert main(["-q", *args]) == 0
    said = capsys.readouterr()
    assert said.out == "" and said.err == ""


def test_quiet_silences_a_batchs_closing_line(tmp_path, capsys):
    """`batch -q` printed its closing line ("leafstudio: batch: 1 inputs: 1 ok, …") though
    `form -q` and `extract -q` no longer print theirs (cli/options.summary, review32b); without
    -q it is still said on stderr."""
    leaf = str(tmp_path / "f.leaf.json")
    assert main(["form", "ovate", "-o", leaf, "-q"]) == 0
    args = ["batch", leaf, "-o", str(tmp_path / "out"), "--grid", "32", "--format", "none"]
    assert main(args) == 0
    assert "1 ok, 0 failed" in capsys.readouterr().err
    assert main([*args, "-q"]) == 0
    said = capsys.readouterr()
    assert said.out == "" and "1 ok" not in said.err, said
