"""Pictures for slides: a turntable (GIF) and the pipeline's steps side by side (PNG)."""

from __future__ import annotations

import imageio.v3 as iio
import pytest

import leafstudio as ls
from leafstudio.cli import main
from leafstudio.render.slides import TURNTABLE_FRAMES


@pytest.fixture(scope="module")
def leaf_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("slides") / "nested.leaf.json"
    ls.save_leaf(ls.demo("nested"), path)
    return path


def test_reconstruct_writes_a_turntable_and_a_steps_figure(leaf_file, tmp_path):
    gif, png = tmp_path / "turn.gif", tmp_path / "steps.png"
    argv = [str(leaf_file), "-o", str(tmp_path / "m.ply"), "--grid", "64"]
    assert main(["reconstruct", *argv, "--turntable", str(gif), "--steps-figure", str(png)]) == 0
    frames = iio.imread(gif, index=None)
    assert frames.shape[0] == TURNTABLE_FRAMES
    assert frames[0].std() > 1 and not (frames[0] == frames[TURNTABLE_FRAMES // 4]).all()  # turns
    steps = iio.imread(png)
    assert steps.shape[0] >= 800 and steps.shape[1] >= 1600
    thirds = [
        steps[: steps.shape[0] // 2, i * steps.shape[1] // 3 : (i + 1) * steps.shape[1] // 3]
        for i in range(3)
    ]
    assert all(part.std() > 5 for part in thirds)  # every panel has something drawn


@pytest.mark.parametrize("name,message", [("t.avi", "a turntable is a .gif or .mp4")])
def test_a_bad_turntable_name_is_one_line_and_writes_nothing(
    leaf_file, tmp_path, capsys, name, message
):
    mesh = tmp_path / "m.ply"
    assert (
        main(["reconstruct", str(leaf_file), "-o", str(mesh), "--turntable", str(tmp_path / name)])
        == 2
    )
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert not mesh.exists()


def test_the_steps_figures_plane_panels_show_an_obovate_leaf_base_left(tmp_path):
    """The steps figure's plane panels drew an obovate leaf apex left (the plane's u runs to
    its base) beside its mesh seen from the base: g(x), deepest where the blade is widest, near
    the apex, was in the panel's left half. They are now turned as the mesh's view."""
    import numpy as np

    from leafstudio.render.slides import render_steps

    result = ls.reconstruct(ls.forms.make_form("obovate"), ls.Params(grid=48))
    path = render_steps(result, tmp_path / "steps.png", size=(900, 500))
    pixels = iio.imread(path)[:, :, :3].astype(int)
    panel = pixels[40:250, 300:600]  # g(x): deep blue inside, red outside
    blue = panel[:, :, 2] - panel[:, :, 0]
    deepest = np.unravel_index(np.argmax(blue), blue.shape)[1]
    assert deepest > 0.5 * panel.shape[1]  # the wide end, the apex, on the right
