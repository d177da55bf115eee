"""Issue 24, finding 14: outputs that overwrite inputs. The overlap check compared the outputs
only with the leaf, --vein and --against: a --texture image given again as --figure, --metrics,
--steps-figure or --turntable was replaced, and --lod N wrote NAME_lodK over an input of that
name; `gui FILE --screenshot FILE` replaced the file. Each is refused, in one line with exit 2,
before anything is written."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import leafstudio as ls
from leafstudio.cli import main


@pytest.fixture
def leaf(tmp_path) -> Path:
    path = tmp_path / "leaf.csv"
    ls.save_leaf(ls.demo("nested"), path)
    return path


def _image(path: Path) -> bytes:
    pixels = np.random.default_rng(0).integers(0, 255, (16, 16, 3), dtype=np.uint8)
    Image.fromarray(pixels).save(path)
    return path.read_bytes()


def _refused(argv: list[str], capsys) -> str:
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    return err


@pytest.mark.parametrize("flag", ["--figure", "--metrics", "--steps-figure"])
def test_a_texture_image_given_again_as_an_output_is_refused(tmp_path, leaf, capsys, flag):
    photo = tmp_path / "photo.png"
    before = _image(photo)
    out = tmp_path / "out.glb"
    err = _refused(["reconstruct", str(leaf), "-o", str(out), "--texture", str(photo), flag,
                    str(photo), "--grid", "32"], capsys)  # fmt: skip
    assert f"{photo}: is also an input" in err
    assert photo.read_bytes() == before and not out.exists()


def test_a_turntable_over_its_texture_is_refused(tmp_path, leaf, capsys):
    gif = tmp_path / "t.gif"
    before = _image(gif)
    out = tmp_path / "out.obj"
    err = _refused(["reconstruct", str(leaf), "-o", str(out), "--turntable", str(gif),
                    "--texture", str(gif), "--grid", "32"], capsys)  # fmt: skip
    assert f"{gif}: is also an input" in err
    assert gif.read_bytes() == before and not out.exists()


@pytest.mark.parametrize("role", ["leaf", "vein", "against"])
def test_a_level_of_detail_over_an_input_is_refused(tmp_path, capsys, role):
    demo = ls.demo("nested")
    named = tmp_path / "out_lod1.ply"  # where --lod 1 writes the second level of out.ply
    leaf = tmp_path / "leaf.csv"
    ls.save_leaf(demo, leaf)
    extra: list[str] = []
    if role == "leaf":
        ls.save_leaf(demo, named)
        leaf = named
    elif role == "vein":
        ls.save_leaf(ls.Leaf(boundary=demo.veins[0]), named)
        extra = ["--vein", str(named)]
    else:
        ls.save_leaf(ls.Leaf(boundary=demo.boundary), named)
        extra = ["--against", str(named)]
    before = named.read_bytes()
    out = tmp_path / "out.ply"
    err = _refused(["reconstruct", str(leaf), "-o", str(out), "--lod", "1", *extra, "--grid",
                    "32"], capsys)  # fmt: skip
    assert f"{named}: is also an input" in err
    assert named.read_bytes() == before and not out.exists()


def test_a_screenshot_over_the_file_opened_is_refused(tmp_path, capsys):
    photo = tmp_path / "photo.png"
    before = _image(photo)
    err = _refused(["gui", str(photo), "--screenshot", str(photo)], capsys)
    assert f"{photo}: is also an input" in err
    assert photo.read_bytes() == before


def _photo_project(tmp_path: Path) -> tuple[Path, Path, bytes]:
    """A project traced from photo.png beside it (its "photo" entry, as `leafstudio photo`
    writes it), and the photo's bytes."""
    import json

    photo = tmp_path / "photo.png"
    before = _image(photo)
    project = tmp_path / "leaf.leaf.json"
    ls.save_leaf(ls.demo("nested"), project)
    data = json.loads(project.read_text())
    data["photo"] = {"image": "photo.png", "pixel_from_world": [[10, 0, 8], [0, -10, 8]],
                     "upright": True}  # fmt: skip
    project.write_text(json.dumps(data))
    return project, photo, before


@pytest.mark.parametrize("flag", ["--figure", "--steps-figure"])
def test_an_output_over_the_photo_a_project_was_traced_from_is_refused(tmp_path, capsys, flag):
    """The photo a project names is its texture (--texture auto) and the app's backdrop: an
    input, which `reconstruct p.leaf.json -o x.glb --figure photo.png` replaced (exit 0)."""
    project, photo, before = _photo_project(tmp_path)
    out = tmp_path / "out.glb"
    err = _refused(["reconstruct", str(project), "-o", str(out), flag, str(photo), "--grid",
                    "32"], capsys)  # fmt: skip
    assert f"{photo}: is also an input" in err
    assert photo.read_bytes() == before and not out.exists()


def test_a_screenshot_over_the_photo_of_the_project_opened_is_refused(tmp_path, capsys):
    project, photo, before = _photo_project(tmp_path)
    err = _refused(["gui", str(project), "--screenshot", str(photo)], capsys)
    assert f"{photo}: is also an input" in err
    assert photo.read_bytes() == before
