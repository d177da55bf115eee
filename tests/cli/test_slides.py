"""`leafstudio slides` on a saved drawn project: the lesson's pictures on the frame its sketch was
drawn on, as the app's lesson and its File > Export slides draw them (review35)."""

from __future__ import annotations

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.cli import main
from leafstudio.errors import LeafError
from leafstudio.render import step_slides
from leafstudio.render.step_slides import plan_frame
from leafstudio.sources.files import save_leaf
from leafstudio.sources.sketch_entry import drawn_frame
from tests.leaves import clicked_sketch

PLANE = {"origin": [0, 0, 0], "u": [1, 0, 0], "v": [0, 1, 0], "normal": [0, 0, 1]}


def _slides_frame(argv: list[str], monkeypatch) -> tuple[object, object]:
    """The result and the frame `leafstudio slides` draws the lesson's slides on (nothing
    written): the one it gives lesson_slides, plan_frame's default when it gives none."""
    drawn = []
    monkeypatch.setattr(step_slides, "lesson_slides", lambda *a: drawn.append(a) or [])
    monkeypatch.setattr(step_slides, "write_slides", lambda *a: [])
    assert main(argv) == 0
    ((result, *given),) = drawn
    frame = given[1] if len(given) > 1 and given[1] is not None else plan_frame(result)
    return result, frame


def test_slides_draw_a_saved_drawn_leaf_at_the_angle_it_was_drawn(tmp_path, monkeypatch):
    """A leaf sketched at 40° and saved as a project: the app's lesson and File > Export slides
    show it at 40° (its sketch's frame), but `leafstudio slides` drew it level (the result's
    view frame: 0° from it). The command reads the sketch's plane from the project."""
    sketch = clicked_sketch(turn=40.0)
    project = tmp_path / "drawn.leaf.json"
    save_leaf(sketch.to_leaf(), project, ls.Params(k=3, grid=32), sketch.to_dict())
    result, frame = _slides_frame(["slides", str(project), "-o", str(tmp_path / "l.pdf")],
                                  monkeypatch)  # fmt: skip
    np.testing.assert_allclose(frame.u, plan_frame(result, sketch.frame).u, atol=1e-12)
    assert abs(frame.u @ plan_frame(result).u - np.cos(np.radians(40.0))) < 0.05  # not level


def test_slides_draw_a_leaf_file_on_its_results_view_frame(tmp_path, monkeypatch):
    """A leaf without a sketch (a point list, a project saved without one) keeps the result's
    view frame, as the app shows it."""
    path = tmp_path / "leaf.csv"
    ls.save_leaf(ls.demo("nested"), path)
    argv = ["slides", str(path), "-o", str(tmp_path / "l.pdf"), "--grid", "32", "--k", "3"]
    result, frame = _slides_frame(argv, monkeypatch)
    np.testing.assert_allclose(frame.u, plan_frame(result).u, atol=1e-12)
    assert drawn_frame({"boundary": [], "plane": {}}, "p.leaf.json") is None


def test_slides_draw_a_project_saved_without_a_sketch_on_its_results_view_frame(
    tmp_path, monkeypatch
):
    """A leaf drawn at 40° but saved as a project without its sketch (as `leafstudio form` or
    the API writes one): no plane to keep, so the slides show the result's view frame, not the
    world's axes a sketch without a plane reads as (review36: only point lists were run)."""
    sketch = clicked_sketch(turn=40.0)
    project = tmp_path / "plain.leaf.json"
    save_leaf(sketch.to_leaf(), project, ls.Params(k=3, grid=32))
    result, frame = _slides_frame(["slides", str(project), "-o", str(tmp_path / "l.pdf")],
                                  monkeypatch)  # fmt: skip
    np.testing.assert_allclose(frame.u, plan_frame(result).u, atol=1e-12)
    assert abs(frame.u @ plan_frame(result, sketch.frame).u - np.cos(np.radians(40.0))) < 0.05


def test_a_sketchs_unreadable_plane_is_named():
    with pytest.raises(LeafError, match="bad sketch"):
        drawn_frame({"boundary": [[0, 0], [1, 0], [0, 1]], "plane": {"u": [1, 0]}}, "p.leaf.json")


def _project_with_plane(tmp_path, plane: object) -> str:
    """The clicked leaf saved as a project, its sketch's "plane" then replaced by `plane`."""
    import json

    sketch = clicked_sketch()
    project = tmp_path / "drawn.leaf.json"
    save_leaf(sketch.to_leaf(), project, ls.Params(k=3, grid=32), sketch.to_dict())
    data = json.loads(project.read_text())
    data["sketch"]["plane"] = plane
    project.write_text(json.dumps(data))
    return str(project)


@pytest.mark.parametrize("plane", [{"u": [1, 0, 0]}, "tilted", {**PLANE, "origin": [0, 0]}])
def test_a_projects_unreadable_plane_is_one_line_naming_the_plane(tmp_path, capsys, plane):
    """A project whose sketch's plane lacks a vector, is a string or has a vector of two numbers:
    `leafstudio slides` (and the app, which reads it alike) said "bad sketch ('origin')", "bad
    sketch (string indices must be integers, not 'str')", "... (cannot reshape array of size 2
    into shape (3,))", not which entry nor what it wants (review36)."""
    project = _project_with_plane(tmp_path, plane)
    assert main(["slides", project, "-o", str(tmp_path / "l.pdf")]) == 2
    said = capsys.readouterr().err.strip()
    assert "\n" not in said and "bad sketch" in said
    assert '"plane" must give origin, u, v and normal, three numbers each' in said


@pytest.mark.parametrize(
    ("axes", "words"),
    [
        (
            {"u": [0, 0, 0], "v": [0, 0, 0], "normal": [0, 0, 0]},
            "u must be a unit vector, got one 0",
        ),
        ({"v": [1, 0, 0]}, "u and v must be perpendicular, got them 0 degrees apart"),
        ({"u": [2, 0, 0]}, "u must be a unit vector, got one 2 long"),
        ({"normal": [0, 0.6, 0.8]}, "v and normal must be perpendicular, got them 53.1 degrees"),
    ],
)
def test_a_projects_degenerate_plane_is_one_line_naming_the_axis(tmp_path, capsys, axes, words):
    """A sketch's plane of zeros, with u along v, u twice as long or the normal tilted off the
    plane: `leafstudio slides` took each (a plane of zeros drew the result's own frame, which
    turned_like falls back to) and so did the app (a plane of zeros made its sketch's leaf all
    at one point): a one-line refusal naming the axis, exit 2 (review36)."""
    project = _project_with_plane(tmp_path, {**PLANE, **axes})
    assert main(["slides", project, "-o", str(tmp_path / "l.pdf")]) == 2
    said = capsys.readouterr().err.strip()
    assert (
        "\n" not in said and "drawn.leaf.json" in said and f'bad sketch ("plane"\'s {words}' in said
    )
