"""Fuzzing findings of issue 24 answered in one line at the command line (exit 2) or done
right, not an internal error or a crash."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image, ImageDraw

import leafstudio as ls
from leafstudio.cli import main
from tests.leaves import metric_numbers


def _error_line(capsys) -> str:
    """The one error line on stderr (a first run's "compiling" note may come before it)."""
    err = capsys.readouterr().err.strip().splitlines()
    errors = [line for line in err if "error:" in line]
    assert len(errors) == 1 and "internal error" not in errors[0], err
    assert len(err) - len(errors) <= 1, err  # at most the compiling note besides it
    return errors[0]


@pytest.fixture
def photo(tmp_path):
    image = Image.new("RGB", (400, 240), "white")
    ImageDraw.Draw(image).ellipse((40, 40, 360, 200), fill=(40, 140, 40))
    path = tmp_path / "leaf.png"
    image.save(path)
    return path


def test_a_negative_seed_for_veins_and_photo_is_one_line(tmp_path, photo, capsys):
    leaf = tmp_path / "n.leaf.json"
    ls.save_leaf(ls.demo("nested"), leaf)
    assert main(["veins", str(leaf), "-o", str(tmp_path / "v.leaf.json"), "--seed", "-1"]) == 2
    assert "seed" in _error_line(capsys)
    assert main(["photo", str(photo), "-o", str(tmp_path / "p.leaf.json"), "--seed", "-1"]) == 2
    assert "seed" in _error_line(capsys)


@pytest.mark.parametrize("base", ["1e308,0", "5,5"])
def test_a_base_outside_the_outline_is_one_line(tmp_path, base, capsys):
    leaf = tmp_path / "n.leaf.json"
    ls.save_leaf(ls.demo("nested"), leaf)
    out = tmp_path / "v.leaf.json"
    assert main(["veins", str(leaf), "-o", str(out), f"--base={base}"]) == 2
    assert "outside the outline" in _error_line(capsys)
    assert not out.exists()


def test_a_huge_photo_length_is_one_line(tmp_path, photo, capsys):
    out = tmp_path / "p.leaf.json"
    assert main(["photo", str(photo), "-o", str(out), "--length", "1e308"]) == 2
    _error_line(capsys)
    assert not out.exists()


@pytest.mark.parametrize("scale", [1e-90, 1e150])
def test_compare_at_extreme_scales_answers(tmp_path, scale, capsys):
    pytest.importorskip("open3d")
    leaf = ls.demo("nested")
    path = tmp_path / "s.leaf.json"
    ls.save_leaf(ls.Leaf(leaf.boundary * scale, [v * scale for v in leaf.veins]), path)
    code = main(["compare", str(path), "--grid", "48", "--json"])
    assert code in (0, 2)
    if code == 2:
        _error_line(capsys)
    else:  # ran to the end (open3d's Poisson crashed here before), with finite figures
        numbers = metric_numbers(json.loads(capsys.readouterr().out))
        assert numbers and np.all(np.isfinite(numbers))


@pytest.mark.parametrize("command", [["measure"], ["reconstruct", "-o", "o.ply", "--metrics"]])
def test_a_leaf_whose_area_overflows_is_one_line_not_infinity(tmp_path, command, capsys):
    leaf = ls.demo("nested")
    path = tmp_path / "huge.leaf.json"
    ls.save_leaf(ls.Leaf(leaf.boundary * 1e160, [v * 1e160 for v in leaf.veins]), path)
    args = [command[0], str(path), "--grid", "32", *command[1:]]
    if command[0] == "reconstruct":
        args = [*args[:-3], "-o", str(tmp_path / "o.ply"), "--metrics", str(tmp_path / "m.json")]
    assert main(args) == 2
    assert "too large" in _error_line(capsys)
    assert not (tmp_path / "m.json").exists()
