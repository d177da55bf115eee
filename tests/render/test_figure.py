"""Off-screen figures: iso and top views side by side, input points, a colour bar."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

import leafstudio as ls
from leafstudio.cli import main
from leafstudio.render.figure import WINDOW_SIZE, render_figure

VIRIDIS_TOP = np.array([253, 231, 37])  # the colour bar's and the midrib's yellow
VEIN_RED = np.array([214, 39, 40])


def _has_colour(pixels: np.ndarray, colour: np.ndarray, tolerance: int = 40) -> bool:
    return bool(np.any(np.abs(pixels[..., :3].astype(int) - colour).sum(axis=-1) < tolerance))


@pytest.fixture(scope="module")
def figure(tmp_path_factory):
    path = tmp_path_factory.mktemp("fig") / "nested.png"
    leaf_file = path.with_name("nested.leaf.json")
    ls.save_leaf(ls.demo("nested"), leaf_file)
    argv = ["reconstruct", str(leaf_file), "-o", str(path.with_suffix(".vtp"))]
    assert main([*argv, "--grid", "48", "--figure", str(path)]) == 0
    return np.asarray(Image.open(path))


def test_figure_is_two_views_with_points_and_colour_bar(figure):
    height, width = figure.shape[:2]
    assert (width, height) == WINDOW_SIZE
    left, right = figure[:, : width // 2], figure[:, width // 2 :]
    for half in (left, right):
        background = np.all(half[..., :3] > 245, axis=-1).mean()
        assert 0.2 < background < 0.97  # a leaf drawn in each view, on white
        assert _has_colour(half, VEIN_RED)  # the vein points over the surface
    assert _has_colour(right[int(0.75 * height) :], VIRIDIS_TOP)  # the colour bar, bottom right
    assert not np.array_equal(left, right)


def test_curvature_figure(tmp_path):
    result = ls.reconstruct(ls.demo("parallel"), ls.Params(k=2, grid=32))
    path = render_figure(result, tmp_path / "sub" / "curv.png", "mean_curvature", (800, 400))
    pixels = np.asarray(Image.open(path))
    assert pixels.shape[:2] == (400, 800)
    assert _has_colour(pixels, np.array([59, 76, 192]), 60)  # coolwarm's blue end


def test_render_rejects_unknown_arrays_and_types(tmp_path):
    result = ls.reconstruct(ls.demo("parallel"), ls.Params(k=2, grid=16))
    with pytest.raises(ls.LeafError, match="cannot colour by"):
        render_figure(result, tmp_path / "x.png", "slope")
    with pytest.raises(ls.LeafError, match=r"must be a \.png"):
        render_figure(result, tmp_path / "x.jpg")


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--figure", "out.jpg"], "out.jpg: a figure must be a .png file"),
        (["--figure", "f.png", "--colour-by", "slope"], "argument --colour-by: invalid choice"),
        (["--k", "twelve"], "K must be a whole number or 'auto'"),
    ],
)
def test_reconstruct_bad_figure_options_are_one_line(tmp_path, capsys, extra, message):
    ls.save_leaf(ls.demo("nested"), tmp_path / "n.leaf.json")
    argv = ["reconstruct", str(tmp_path / "n.leaf.json"), "-o", str(tmp_path / "n.ply")]
    assert main([*argv, *extra]) == 2
    err = capsys.readouterr().err
    assert message in err
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "n.ply").exists()  # checked before any work


def test_reconstruct_auto_k_reports_the_chosen_k(tmp_path, capsys):
    ls.save_leaf(ls.demo("nested"), tmp_path / "n.leaf.json")
    metrics = tmp_path / "m.json"
    argv = ["reconstruct", str(tmp_path / "n.leaf.json"), "-o", str(tmp_path / "n.vtp")]
    assert main([*argv, "--k", "auto", "--grid", "48", "--metrics", str(metrics)]) == 0
    data = json.loads(metrics.read_text())
    assert data["params"]["k"] == "auto"
    assert 1 <= data["k"] <= 12
    assert f"K = {data['k']} (chosen by BIC)" in capsys.readouterr().err


@pytest.mark.parametrize("shape", ["ovate", "obovate"])
def test_the_iso_view_and_the_turntable_start_from_the_base(shape):
    """The figure's iso view and the slides' mesh picture (the turntable's first frame) looked
    at an obovate leaf from its apex, an ovate one from its base: both took the plane's u,
    which runs to the outline's farther extreme. They now take the midrib's direction."""
    from leafstudio.render.figure import _cameras
    from leafstudio.render.slides import _iso_camera

    result = ls.reconstruct(ls.forms.make_form(shape), ls.Params(grid=48))
    midrib = result.leaf.veins[0]
    along = midrib[-1] - midrib[0]  # base to apex
    for eye, centre, _ in (_cameras(result)["iso"], _iso_camera(result)):
        assert np.dot(np.subtract(eye, centre), along) < 0  # on the base's side
