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


def test_a_sketchs_unreadable_plane_is_named():
    with pytest.raises(LeafError, match="bad sketch"):
        drawn_frame({"boundary": [[0, 0], [1, 0], [0, 1]], "plane": {"u": [1, 0]}}, "p.leaf.json")


@pytest.mark.parametrize("plane", [{"u": [1, 0, 0]}, "tilted", {**PLANE, "origin": [0, 0]}])
def test_a_projects_unreadable_plane_is_one_line_naming_the_plane(tmp_path, capsys, plane):
    """A project whose sketch's plane lacks a vector, is a string or has a vector of two numbers:
    `leafstudio slides` (and the app, which reads it alike) said "bad sketch ('origin')", "bad
    sketch (string indices must be integers, not 'str')", "... (cannot reshape array of size 2
    into shape (3,))", not which entry nor what it wants (review36)."""
    import json

    sketch = clicked_sketch()
    project = tmp_path / "drawn.leaf.json"
    save_leaf(sketch.to_leaf(), project, ls.Params(k=3, grid=32), sketch.to_dict())
    data = json.loads(project.read_text())
    data["sketch"]["plane"] = plane
    project.write_text(json.dumps(data))
    assert main(["slides", str(project), "-o", str(tmp_path / "l.pdf")]) == 2
    said = capsys.readouterr().err.strip()
    assert "\n" not in said and "bad sketch" in said
    assert '"plane" must give origin, u, v and normal, three numbers each' in said
