"""The command line: outputs, metrics, and one clear line with exit code 2 for each bad input."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from leafstudio.cli import main


@pytest.fixture(scope="module")
def nested_csv(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("leaf") / "nested.csv"
    assert main(["demo", "nested", "-o", str(path)]) == 0
    return path


def _error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err  # one line, no traceback
    return err[0]


def test_reconstruct_writes_mesh_and_table1_metrics(tmp_path: Path, nested_csv: Path, capsys):
    mesh, metrics = tmp_path / "leaf.vtp", tmp_path / "m.json"
    code = main(["reconstruct", str(nested_csv), "-o", str(mesh), "--k", "3", "--grid", "64",
                 "--metrics", str(metrics)])  # fmt: skip
    assert code == 0
    assert mesh.stat().st_size > 0
    data = json.loads(metrics.read_text())
    assert data["params"]["k"] == 3 and data["params"]["grid"] == 64
    assert data["boundary"]["mean"] <= 1e-3 and data["veins"]["mean"] <= 5e-3
    assert data["mesh"]["components"] == 1 and data["mesh"]["boundary_loops"] == 1
    assert data["mesh"]["non_manifold_edges"] == 0 and data["mesh"]["area"] > 0.16


@pytest.mark.open3d
def test_bpa_mesher_and_seed_from_the_command_line(tmp_path: Path, nested_csv: Path):
    metrics = tmp_path / "m.json"
    code = main(["reconstruct", str(nested_csv), "-o", str(tmp_path / "a.ply"), "--mesher", "bpa",
                 "--seed", "4", "--grid", "48", "--metrics", str(metrics)])  # fmt: skip
    assert code == 0
    params = json.loads(metrics.read_text())["params"]
    assert params["mesher"] == "bpa" and params["seed"] == 4


def test_unlabelled_boundary_with_vein_files(tmp_path: Path):
    from leafstudio.sources.demos import demo

    leaf = demo("parallel")
    boundary = tmp_path / "b.txt"
    np.savetxt(boundary, leaf.boundary)
    veins = []
    for i, v in enumerate(leaf.veins):
        veins += ["--vein", str(tmp_path / f"v{i}.xyz")]
        np.savetxt(veins[-1], v)
    metrics = tmp_path / "m.json"
    assert main(["reconstruct", str(boundary), *veins, "-o", str(tmp_path / "m.obj"), "--k", "2",
                 "--metrics", str(metrics)]) == 0  # fmt: skip
    assert json.loads(metrics.read_text())["veins"]["mean"] <= 5e-3


def test_leaf_without_veins_warns_and_is_flat(tmp_path: Path, capsys):
    from leafstudio.sources.demos import demo

    boundary = tmp_path / "b.csv"
    np.savetxt(boundary, demo("nested").boundary, delimiter=",")
    assert main(["reconstruct", str(boundary), "-o", str(tmp_path / "m.ply"), "--grid", "32"]) == 0
    assert "warning" in capsys.readouterr().err and "flat" in "flat"


def _write(tmp_path: Path, name: str, content: str) -> Path:
    path = tmp_path / name
    path.write_text(content)
    return path


@pytest.mark.parametrize(
    "content, args, message",
    [
        (None, [], "no such file"),
        ("", [], "holds no points"),
        ("0 0\n1 1\n", [], "at least 3 boundary points"),
        ("0 0 0 0 0 0 0\n", [], "expected 2, 3 or 4 columns"),
        ("0 0 0\n1 nan 0\n1 1 0\n", [], "NaN or infinite"),
        ("0 0 0\n1 0 0\n", [], "at least 3 boundary points"),
        ("0 0 0\n1 1 1\n2 2 2\n3 3 3\n", [], "lie on one line"),
        ("1 1 1\n1 1 1\n1 1 1\n", [], "at least 3 distinct"),
        ("demo", ["--k", "999"], "K must be between 1 and"),
        ("demo", ["--grid", "4"], "grid must be between 8 and 2048"),
        ("demo", ["--grid", "4096"], "grid must be between 8 and 2048"),
        ("demo", ["--k", "64", "--grid", "8"], "more than the data supports"),
        ("demo", ["--k", "three"], "K must be a whole number"),
        ("demo", ["--mesher", "poisson"], "invalid choice"),
    ],
)
def test_bad_input_is_one_line_and_exit_code_2(
    tmp_path, nested_csv, capsys, content, args, message
):
    if content == "demo":
        source = nested_csv
    elif content is None:
        source = tmp_path / "missing.csv"
    else:
        source = _write(tmp_path, "bad.csv", content)
    code = main(["reconstruct", str(source), "-o", str(tmp_path / "m.ply"), *args])
    line = _error_line(capsys)
    assert code == 2
    assert line.startswith("leafstudio: error:")
    assert message in line
    if not args or "64" in args:
        assert str(source) in line  # names the file
    else:  # a bad flag is the command line's, not the file's (review finding)
        assert str(source) not in line


def test_veins_outside_the_boundary(tmp_path: Path, capsys):
    from leafstudio.sources.demos import demo

    leaf = demo("nested")
    boundary = tmp_path / "b.csv"
    np.savetxt(boundary, leaf.boundary, delimiter=",")
    vein = tmp_path / "v.csv"
    np.savetxt(vein, leaf.veins[0] + [0, 0.6, 0], delimiter=",")
    code = main(["reconstruct", str(boundary), "--vein", str(vein), "-o", str(tmp_path / "m.ply")])
    assert code == 2 and "outside the boundary" in _error_line(capsys)


def test_unknown_output_type_and_demo(tmp_path: Path, nested_csv: Path, capsys):
    assert main(["reconstruct", str(nested_csv), "-o", str(tmp_path / "m.dae")]) == 2
    assert "unknown mesh type" in _error_line(capsys)
    assert main(["demo", "maple", "-o", str(tmp_path / "x.csv")]) == 2
    assert "unknown demo 'maple'" in _error_line(capsys)


def test_console_script_never_shows_a_traceback(tmp_path: Path):
    bad = _write(tmp_path, "bad.txt", "1 2 3\n4 5\n")
    command = [sys.executable, "-m", "leafstudio", "reconstruct", str(bad), "-o", "m.ply"]
    run = subprocess.run(command, capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert run.returncode == 2
    assert "Traceback" not in run.stderr
    assert (
        run.stderr.strip()
        == f"leafstudio: error: {bad}: line 2: 2 columns where earlier lines have 3"
    )


@pytest.mark.parametrize(("length", "expected"), [("6cm", 60.0), ("60mm", 60.0), ("3", 3.0)])
def test_photo_length_takes_units_as_form_and_reconstruct_do(tmp_path: Path, length, expected):
    """`photo --length 6cm` was refused ("invalid float value") where `form` and `reconstruct`
    take it: with a unit, the leaf is written in millimetres (a photo's own scale, its DPI); a
    bare number stays the leaf's length in its own units."""
    from PIL import Image

    import leafstudio as ls
    from leafstudio.forms import make_form
    from tests.photos import form_photo

    form = make_form("ovate")
    photo = tmp_path / "photo.png"
    Image.fromarray(form_photo(form.boundary, form.veins)[0]).save(photo)
    out = tmp_path / "leaf.leaf.json"
    assert main(["photo", str(photo), "-o", str(out), "--length", length, "--veins", "none"]) == 0
    boundary = ls.load_leaf(out).boundary
    assert np.ptp(boundary, axis=0).max() == pytest.approx(expected, rel=0.03)


def test_photo_bad_length_is_one_line_exit_2(tmp_path: Path, capsys):
    code = main(["photo", str(tmp_path / "x.png"), "-o", str(tmp_path / "x.leaf.json"),
                 "--length", "6 inches"])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and "--length" in err and err.count("\n") == 1


def test_veins_grow_from_the_base_of_a_midrib_written_apex_first(tmp_path: Path):
    """`leafstudio veins` without --base grew its veins from vein 1's first point: a midrib
    written apex first (taken base first for the length, the export and the view) had the new
    midrib grown from the apex; it now grows from the base, as for the midrib written base
    first."""
    import leafstudio as ls
    from leafstudio.forms import make_form

    leaf = make_form("ovate", venation="pinnate")
    backward = ls.Leaf(leaf.boundary, [leaf.veins[0][::-1], *leaf.veins[1:]])
    starts = []
    for name, given in (("forward", leaf), ("backward", backward)):
        ls.save_leaf(given, tmp_path / f"{name}.leaf.json")
        out = tmp_path / f"{name}_grown.leaf.json"
        assert main(["veins", str(tmp_path / f"{name}.leaf.json"), "-o", str(out)]) == 0
        starts.append(ls.load_leaf(out).veins[0][0])
    np.testing.assert_allclose(starts[1], starts[0], atol=1e-9)
