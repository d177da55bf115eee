"""Every bad input answered (issue 11, findings 4, 5 and 7): one LeafError (or TypeError) naming the
file and the problem, never a library's exception, a hang or a silently wrong leaf."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import leafstudio as ls
from leafstudio._shared.inputs import json_depth, parse_number
from leafstudio.cli import main
from leafstudio.errors import LeafError, shorten
from leafstudio.model import Leaf, Params
from leafstudio.sources.files import load_leaf, load_project
from leafstudio.sources.scan import read_scan

SQUARE = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]


def _project(tmp_path: Path, **fields) -> Path:
    data = {"format": "leafstudio", "version": 1, "boundary": SQUARE, **fields}
    path = tmp_path / "p.leaf.json"
    path.write_text(json.dumps(data))
    return path


def _refused(path: Path, match: str) -> str:
    with pytest.raises(LeafError, match=match) as caught:
        load_leaf(path)
    message = str(caught.value)
    assert message.startswith(str(path)) and "\n" not in message and len(message) < 400
    return message


# --- finding 4: internal errors on bad files -----------------------------------------------------


@pytest.mark.parametrize("version", ['"1"', "null", "[1]", "true", "1.5", "0"])
def test_a_project_version_that_is_not_a_whole_number_is_refused(tmp_path, version):
    path = tmp_path / "p.leaf.json"
    path.write_text(f'{{"format": "leafstudio", "version": {version}, "boundary": {SQUARE}}}')
    _refused(path, '"version" must be a whole number')


@pytest.mark.parametrize(
    ("fields", "match"),
    [
        ({"params": "k=3"}, '"params" must be an object'),
        ({"params": [3]}, '"params" must be an object'),
        ({"sketch": "x"}, '"sketch" must be an object'),
        ({"sketch": [1]}, '"sketch" must be an object'),
        ({"boundary": "square"}, '"boundary" must be a list'),
        ({"boundary": [0, 0, 0, 1, 0, 0, 1, 1, 0]}, "boundary must be a list of"),
        ({"boundary": [[0, 0, "a"]] * 3}, "boundary must be a list of"),
        ({"veins": [[0.5, 0.5, 0.1], [0.6, 0.5, 0.1]]}, "one vein is"),
        ({"veins": "v"}, '"veins" must be a list'),
        ({"params": {"seed": 1.5}}, "seed must be a whole number"),
        ({"params": {"seed": 10**400}}, r"seed must be between 0 and 4294967295, got 9999|1000"),
        ({"params": {"refine": "no"}}, "refine must be true or false"),
        ({"params": {"grid": 100.5}}, "grid must be a whole number"),
        ({"params": {"grid": "128"}}, "grid must be a whole number"),
        ({"boundary": [[10**400, 0, 0], [1, 0, 0], [0, 1, 0]]}, "too large"),
    ],
)
def test_a_malformed_project_is_one_clear_error(tmp_path, fields, match):
    path = _project(tmp_path, **fields)
    with pytest.raises(LeafError, match=match) as caught:
        load_project(path)
    assert str(caught.value).startswith(str(path)) and len(str(caught.value)) < 400


def test_deep_nesting_and_huge_integers_in_json_are_refused(tmp_path):
    path = tmp_path / "deep.leaf.json"
    path.write_text('{"format": "leafstudio", "boundary": ' + "[" * 1000 + "]" * 1000 + "}")
    _refused(path, "nested 1001 levels deep")
    path.write_text('{"format": "leafstudio", "boundary": [[' + "9" * 5000 + ", 0, 0]]}")
    _refused(path, "not valid JSON")
    assert json_depth('{"a": "[[[[", "b": [[1]]}') == 3  # brackets in strings do not count


def test_a_ply_header_declaring_more_than_the_file_holds_is_refused(tmp_path):
    path = tmp_path / "big.ply"
    header = "ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\n"
    header += "property float x\nproperty float y\nproperty float z\nend_header\n"
    path.write_bytes(header.encode() + b"\0" * 120)
    message = _refused(path, "declares 2000000000")
    assert "holds 120" in message
    with pytest.raises(LeafError, match="declares"):
        read_scan(path)


def test_a_ply_label_that_is_a_list_is_refused(tmp_path):
    path = tmp_path / "lab.ply"
    rows = "".join(f"{x} {y} 0 1 1\n" for x, y, _ in SQUARE[:3])
    header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
    header += "property float z\nproperty list uchar int label\nend_header\n"
    path.write_text(header + rows)
    _refused(path, "label must be a number, not a list")


@pytest.mark.parametrize("device", ["/dev/zero", "/dev/urandom", "/dev/null"])
def test_devices_are_refused_by_their_type(tmp_path, device):
    if not Path(device).exists():
        pytest.skip(f"no {device}")
    link = tmp_path / "leaf.csv"
    link.symlink_to(device)
    _refused(link, "is a device, not a file")
    scan = tmp_path / "scan.xyz"
    scan.symlink_to(device)
    with pytest.raises(LeafError, match="is a device, not a file"):
        read_scan(scan)


def test_binary_data_in_a_point_list_is_refused(tmp_path):
    path = tmp_path / "leaf.csv"
    path.write_bytes(b"0 0 0\n\0\1\2\3")
    _refused(path, "not a text file")


# --- finding 5: silently accepted or wrong -------------------------------------------------------


def test_numbers_with_underscores_are_not_read_as_numbers(tmp_path):
    path = tmp_path / "leaf.csv"
    path.write_text("0,0,0\n1_0,0,0\n0,1,0\n")
    _refused(path, r"line 2: not a number in '1_0,0,0'")
    assert parse_number("-1.5e3") == -1500.0
    for text in ("1_0", "0x10", "١", "1e", "--1"):
        with pytest.raises(ValueError):
            parse_number(text)


def test_a_huge_label_is_refused_not_dropped(tmp_path):
    path = tmp_path / "leaf.csv"
    rows = [[*p, 0] for p in SQUARE] + [[0.5, 0.5, 0.1, 1e300], [0.6, 0.5, 0.1, 1e300]]
    np.savetxt(path, rows, delimiter=",")
    _refused(path, "labels must be whole numbers from 0 to")


def test_a_long_bad_line_is_cut_in_the_message(tmp_path):
    path = tmp_path / "leaf.csv"
    path.write_text("0,0,0\n1,0,0\n0,1,0\n" + "x" * 5000 + "\n")
    message = _refused(path, "line 4: not a number")
    assert len(message) < 300 and "5000 characters" in message
    assert shorten("abc", 10) == "abc"


def test_load_leaf_takes_one_vein_file_given_alone(tmp_path):
    leaf_path = tmp_path / "b.csv"
    np.savetxt(leaf_path, SQUARE, delimiter=",")
    vein = tmp_path / "abc.csv"
    np.savetxt(vein, [[0.2, 0.5, 0.1], [0.8, 0.5, 0.1]], delimiter=",")
    assert len(load_leaf(leaf_path, veins=str(vein)).veins) == 1
    with pytest.raises(LeafError, match=r"missing\.csv: no such file"):
        load_leaf(leaf_path, veins=str(tmp_path / "missing.csv"))


# --- finding 7: the Python API -------------------------------------------------------------------


def test_reconstruct_says_what_it_expects():
    with pytest.raises(TypeError, match=r"expected a leafstudio\.Leaf"):
        ls.reconstruct(None)
    with pytest.raises(TypeError, match=r"expected leafstudio\.Params"):
        ls.reconstruct(ls.demo("nested"), 3)
    with pytest.raises(LeafError, match="unknown parameter 'kk'"):
        ls.reconstruct(ls.demo("nested"), {"kk": 3})
    result = ls.reconstruct(ls.demo("nested"), {"k": 2, "grid": 32})
    assert result.params.k == 2


@pytest.mark.parametrize(
    ("values", "match"),
    [
        ({"seed": 2**40}, "seed must be between 0 and 4294967295"),
        ({"seed": -1}, "seed must be between 0"),
        ({"seed": 1.5}, "seed must be a whole number"),
        ({"seed": None}, "seed must be a whole number, got None"),
        ({"samples": 100.5}, "EM sample count must be a whole number"),
        ({"grid": 64.7}, "grid must be a whole number"),
        ({"grid": 64.0}, "grid must be a whole number"),
        ({"grid": "128"}, "grid must be a whole number, got '128'"),
        ({"grid": True}, "grid must be a whole number"),
        ({"refine": "no"}, "refine must be true or false"),
        ({"refine": 1}, "refine must be true or false"),
        ({"taper": "0.3"}, "taper must be a number"),
        ({"taper": float("nan")}, "taper must be between"),
        ({"mpu_tolerance": 1j}, "MPU tolerance must be a number"),
        ({"mesher": 3}, "mesher must be one of"),
        ({"k": 2.0}, "K must be a whole number or 'auto'"),
    ],
)
def test_params_check_types_as_well_as_ranges(values, match):
    with pytest.raises(LeafError, match=match):
        Params(**values)


def test_params_keep_plain_python_values():
    params = Params(grid=np.int64(64), seed=np.uint32(7), refine=np.bool_(False))
    assert type(params.grid) is int and type(params.seed) is int and params.refine is False
    assert json.dumps(params.to_dict())


def test_leaf_checks_its_inputs():
    assert Leaf(np.eye(3), veins=None).veins == []
    with pytest.raises(LeafError, match="veins must be a list"):
        Leaf(np.eye(3), veins="abc")
    with pytest.raises(LeafError, match="not complex"):
        Leaf(np.eye(3) * (1 + 1j))
    with pytest.raises(LeafError, match="boundary must be a list of x, y, z points"):
        Leaf(None)
    with pytest.raises(LeafError, match="points"):
        Leaf([["a", "b", "c"]] * 3)
    assert Leaf(np.eye(3) * 1e200).boundary.max() == 1e200  # the pipeline runs at unit size
    with pytest.raises(LeafError, match="rescale"):
        Leaf(np.eye(3) * 1e305)  # its extent would overflow
    with pytest.raises(LeafError, match="spans only 1e-300; rescale"):
        Leaf(np.eye(3) * 1e-300)  # its curvatures would overflow


# --- the command line: one line, exit 2 ----------------------------------------------------------


def test_every_bad_file_at_the_command_line_is_one_line_and_exit_2(tmp_path, capsys):
    cases = {
        "v.leaf.json": '{"format": "leafstudio", "version": "1", "boundary": []}',
        "deep.leaf.json": "[" * 100_000 + "]" * 100_000,
        "lab.csv": "0,0,0,0\n1,0,0,0\n0,1,0,0\n0.2,0.2,0,1e300\n",
        "under.csv": "0,0,0\n1_0,0,0\n0,1,0\n",
    }
    for name, text in cases.items():
        path = tmp_path / name
        path.write_text(text)
        assert main(["reconstruct", str(path), "-o", str(tmp_path / "o.ply")]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and str(path) in err[0], (name, err)


def test_a_pcd_header_declaring_more_than_the_file_holds_is_refused(tmp_path):
    path = tmp_path / "big.pcd"
    path.write_text(
        "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2000000000\n"
        "HEIGHT 1\nPOINTS 2000000000\nDATA binary\n" + "x" * 100
    )
    with pytest.raises(LeafError, match="declares 2000000000 points"):
        read_scan(path)
    path.write_bytes(b"\x00\x01 not a pcd")
    with pytest.raises(LeafError, match="no POINTS"):
        read_scan(path)


def test_the_api_refuses_a_crossing_boundary_and_keeps_the_largest_loop():
    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    eight = np.column_stack([np.sin(t), 0.6 * np.sin(t) * np.cos(t), 0 * t]) * 1e6 + [5e6, 0, 0]
    with pytest.raises(LeafError, match=r"crosses itself near \(5e\+06, "):
        ls.reconstruct(Leaf(eight), Params(grid=32))  # the place in the caller's coordinates
    outer = np.column_stack([np.cos(t), 0.6 * np.sin(t), 0 * t])
    with pytest.warns(UserWarning, match=r"kept the largest \(points 1-200\)"):
        result = ls.reconstruct(Leaf(np.vstack([outer, 0.2 * outer])), Params(grid=32))
    assert len(result.leaf.boundary) == 400  # the input as given; the outline is the outer loop
    assert abs(result.metrics["mesh"]["area"] - np.pi * 0.6) < 0.05


def test_an_outline_given_closed_or_with_a_point_twice_opens_as_it_does_open(tmp_path):
    """Many tools write a closed polyline (its first point again at the end); the app's open
    (workflows.open_file) read the zero-length step as a crossing and refused the file."""
    from leafstudio.workflows import open_file

    t = np.linspace(0, 2 * np.pi, 60, endpoint=False)
    outline = np.column_stack([2 * np.cos(t), np.sin(t), 0.05 * np.cos(t) ** 2])
    midrib = np.column_stack([np.linspace(-1.6, 1.6, 9), np.zeros(9), np.zeros(9)])
    rings = {
        "open": outline,
        "closed": np.vstack([outline, outline[:1]]),
        "doubled": np.insert(outline, 20, outline[20], axis=0),
    }
    for name, ring in rings.items():
        path = tmp_path / f"{name}.csv"
        np.savetxt(path, np.vstack([np.c_[ring, np.zeros(len(ring))], np.c_[midrib, np.ones(9)]]),
                   delimiter=",")  # fmt: skip
        opened = open_file(path)
        assert len(opened.leaf.boundary) == len(ring), name


def test_a_photo_given_where_a_leaf_file_goes_names_the_command_that_reads_it(tmp_path, capsys):
    """`reconstruct photo.png` (the app opens photos) said only 'unknown file type'."""
    from PIL import Image

    photo = tmp_path / "leaf.jpg"
    Image.new("RGB", (40, 30), "white").save(photo)
    assert main(["reconstruct", str(photo), "-o", str(tmp_path / "o.ply")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "`leafstudio photo`" in err
    with pytest.raises(LeafError, match=r"unknown file type '\.stl'") as refused:
        load_leaf(tmp_path / "leaf.stl")
    assert "leafstudio photo" not in str(refused.value)
