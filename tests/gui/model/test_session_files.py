"""Issue 20, finding 3: the session, not the window, opens files (through workflows.open_file,
the command line's path), owns the side jobs (texture, Poisson, the scan's distances) and hears
how each job ended through its own handle. All without Qt: the jobs run at once."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from leafstudio.gui.model.jobs import Job, run_now
from leafstudio.gui.model.session import Session
from leafstudio.sources.demos import demo
from leafstudio.sources.files import save_leaf
from tests.gui.builders import Runner, six_column_scan, write_points

from .test_session import FAST


def opened_session() -> tuple[Session, Runner, dict[str, list]]:
    runner = Runner()
    session = Session(runner, FAST)
    got: dict[str, list] = {"opened": [], "failed": [], "opening": []}
    session.opened.connect(got["opened"].append)
    session.open_failed.connect(lambda what, message: got["failed"].append((what, message)))
    session.opening.connect(lambda path, what: got["opening"].append(what))
    return session, runner, got


def test_a_job_handle_says_how_its_job_ended_even_to_a_late_listener():
    done = run_now("x", lambda a, b: a + b, 2, 3)
    seen: list = []
    done.on_done(seen.append).on_failed(seen.append)
    assert done.finished and seen == [5]
    failed = run_now("x", lambda: 1 / 0)
    failed.on_done(seen.append).on_failed(lambda exc: seen.append(type(exc)))
    assert seen == [5, ZeroDivisionError]
    pending = Job(7)
    pending.on_done(seen.append)
    assert not pending.finished and seen == [5, ZeroDivisionError]
    pending.finish("late")
    assert seen[-1] == "late"


def test_the_session_opens_a_project_with_its_parameters(tmp_path):
    session, runner, got = opened_session()
    path = tmp_path / "p.leaf.json"
    save_leaf(demo("nested"), path, FAST.with_(k=4))
    job = session.open_path(str(path))
    assert job.finished and got["opened"] == [str(path)] and got["opening"] == ["file"]
    assert session.state.path == str(path) and session.params == FAST.with_(k=4)
    np.testing.assert_allclose(session.leaf.boundary, demo("nested").boundary)
    assert runner.requests[-1][1] == FAST.with_(k=4) and not session.is_modified()


def test_a_point_list_that_is_a_scan_opens_as_a_scan(tmp_path):
    session, runner, got = opened_session()
    path = write_points(tmp_path / "scan.txt", six_column_scan())
    session.open_path(path)
    assert got["opened"] == [path] and session.state.scan is not None
    assert [p.name for p in session.state.scan.pieces] == ["scan:blade", "scan:dropped"]
    runner.finish(session)
    fidelity = session.shown.fidelity  # the scan's distances, computed after the result
    assert fidelity is not None and fidelity[0] == session.shown_id
    assert fidelity[1][0][0].startswith("Scan → mesh distance")


@pytest.mark.parametrize(
    ("name", "rows", "words"),
    [
        (  # a figure eight: refused where the command line refuses it
            "eight.csv",
            np.column_stack(
                [
                    np.cos(np.linspace(0, 2 * np.pi, 80, endpoint=False)),
                    0.3 * np.sin(2 * np.linspace(0, 2 * np.pi, 80, endpoint=False)),
                    np.zeros(80),
                ]
            ),
            "crosses itself near",
        ),
        (
            "blob.xyz",
            np.random.default_rng(1).normal(size=(2000, 3)),
            "does not look like one leaf",
        ),
    ],
)
def test_a_file_the_command_line_refuses_is_refused_and_the_document_kept(
    tmp_path, name, rows, words
):
    session, _runner, got = opened_session()
    session.open_demo("nested")
    before = session.state
    path = write_points(tmp_path / name, rows)
    session.open_path(path)
    assert got["opened"] == [] and len(got["failed"]) == 1
    what, message = got["failed"][0]
    assert what == "file" and words in message and name in message and "\n" not in message
    assert session.state is before


def test_a_demo_or_a_new_sketch_supersedes_a_file_still_being_read(tmp_path):
    pending: list[Job] = []

    def later(kind, function, *args):  # a worker that has not answered yet
        pending.append(Job(len(pending) + 1))
        pending[-1].work = (function, args)
        return pending[-1]

    session = Session(Runner(), FAST, run=later)
    path = tmp_path / "p.leaf.json"
    save_leaf(demo("parallel"), path)
    job = session.open_path(str(path))
    session.open_demo("nested")
    function, args = job.work
    job.finish(function(*args))  # the file arrives after the demo was chosen
    assert session.state.title == "nested demo" and session.state.path is None


def test_the_texture_is_made_when_shown_and_a_bad_image_falls_back_to_the_generated_one(tmp_path):
    session, runner, _got = opened_session()
    shown, notes = [], []
    session.side.texture_shown.connect(lambda image, key: shown.append(key))
    session.noticed.connect(notes.append)
    session.open_demo("nested")
    runner.finish(session)
    assert shown == []  # the mesh does not show the texture: nothing made
    session.side.set_texture_shown(True)
    assert len(shown) == 1 and shown[0][0] == ("auto",)
    session.side.set_texture_shown(True)
    assert len(shown) == 1  # already on the mesh
    session.choose_texture(str(tmp_path / "missing.png"))
    assert session.texture() == "auto" and "Cannot show the texture" in notes[-1]
    assert len(shown) == 1 and session.side.texture_key == shown[0]


def test_the_same_leaf_opened_again_keeps_its_texture_and_another_leaf_drops_it():
    """The texture image depends only on what its key names (textures.texture_key): the same
    leaf opened again (a demo chosen twice, a file reopened) keeps the image on the mesh rather
    than making it again (about 0.3 s of CPU at a small grid); another leaf's image goes."""
    session, runner, _got = opened_session()
    shown: list = []
    session.side.texture_shown.connect(lambda image, key: shown.append(key))
    session.side.set_texture_shown(True)
    session.open_demo("nested")
    runner.finish(session)
    assert len(shown) == 1
    session.new_sketch()
    session.open_demo("nested")
    runner.finish(session)
    assert len(shown) == 1 and session.side.texture_key == shown[0]
    session.open_demo("parallel")
    runner.finish(session)
    assert len(shown) == 2 and shown[1] != shown[0] and session.side.texture_key == shown[1]


def test_an_image_made_for_a_texture_no_longer_wanted_never_replaces_the_one_wanted(tmp_path):
    """The leaf shows its generated texture; an image is picked, then the generated one again
    before the picked one is made: the picked image, when it comes, is not put on the mesh."""
    pending: list[Job] = []

    def later(kind, function, *args):  # texture jobs answer when the test says
        pending.append(Job(len(pending) + 1))
        pending[-1].work = (function, args)
        return pending[-1]

    runner = Runner()
    session = Session(runner, FAST, run=later)
    shown: list = []
    session.side.texture_shown.connect(lambda image, key: shown.append(key))
    session.side.set_texture_shown(True)
    session.open_demo("nested")
    runner.finish(session)
    function, args = pending[-1].work
    pending[-1].finish(function(*args))
    assert len(shown) == 1 and shown[0][0] == ("auto",)
    picked = tmp_path / "picked.png"
    Image.fromarray(np.full((8, 8, 3), 90, np.uint8)).save(picked)
    session.choose_texture(str(picked))
    picked_job = pending[-1]
    session.choose_texture("auto")  # the generated one again, before the picked one came
    function, args = picked_job.work
    picked_job.finish(function(*args))
    assert len(shown) == 1 and session.side.texture_key == shown[0]


def test_a_texture_made_once_is_not_made_again_for_the_same_leaf(monkeypatch):
    """The images last made are kept by their key (textures.texture_key), as the pipeline keeps
    its stages: going back to a leaf shown a moment ago (another demo and back, an undo, a new
    window on the same leaf) brings its texture without making it again (0.1-0.3 s of CPU each
    at 1024², the side lane's largest cost); a changed leaf still gets its own."""
    from leafstudio.gui.model import textures

    textures.forget_textures()
    made: list = []
    real = textures.base_color
    monkeypatch.setattr(textures, "base_color", lambda *a: made.append(1) or real(*a))
    images: list = []
    for _window in range(2):  # a second window (a new session) on the same leaves
        session, runner, _got = opened_session()
        session.side.texture_shown.connect(lambda image, key: images.append((key, image)))
        session.side.set_texture_shown(True)
        for name in ("nested", "parallel", "nested"):
            session.open_demo(name)
            runner.finish(session)
    assert len(made) == 2  # nested and parallel, once each
    assert len(images) == 6  # each window shows nested, parallel and nested again
    by_key: dict = {}
    for key, image in images:
        assert not image.flags.writeable  # shared: nobody may paint on it
        np.testing.assert_array_equal(by_key.setdefault(key, image), image)
    assert len(by_key) == 2


@pytest.mark.parametrize("scale", [1e300, 1e160])
def test_a_leaf_beyond_what_the_app_draws_and_measures_is_refused_in_one_line(tmp_path, scale):
    """The command line takes a leaf at 1e300 (reconstruct writes its mesh; measure refuses in
    one line), but the app's sketch, texture and camera failed on it with tracebacks in the
    log (issue 24 audit): the app refuses it when it opens, in one line, and keeps its leaf."""
    session, _runner, got = opened_session()
    session.open_demo("nested")
    before = session.state
    nested = demo("nested")
    path = tmp_path / "huge.csv"
    save_leaf(type(nested)(nested.boundary * scale, [v * scale for v in nested.veins]), path)
    session.open_path(str(path))
    assert got["opened"] == [] and len(got["failed"]) == 1
    what, message = got["failed"][0]
    assert what == "file" and "huge.csv" in message and "\n" not in message
    assert "leafstudio reconstruct" in message and "1e+150" in message
    assert session.state is before


def test_a_scan_whose_surface_crumples_is_warned_of_in_the_window():
    """As the command line and batch warn (analysis/fidelity.scan_warnings): soybean pot1_1's
    doubled cloud crumples its mesh (and folds it back a little), which its distances to the
    scan hide. The window's status line hears it as a side job's note, and the panel shows the
    shares."""
    from pathlib import Path

    from leafstudio.analysis.fidelity import CRUMPLED
    from leafstudio.model import Params

    scan = Path(__file__).resolve().parents[3].parent / "shared" / "realleaves"
    path = scan / "soybean_11_20190508T043118_pot1_1.txt"
    if not path.exists():
        pytest.skip("the shared scans are not beside us")
    runner = Runner()
    session = Session(runner, Params())
    notes: list[str] = []
    session.side.note.connect(notes.append)
    session.open_path(str(path))
    runner.finish(session)
    rows = dict(session.shown.fidelity[1][0][1])
    assert float(rows["Mesh area crumpled"].rstrip("%")) / 100 > CRUMPLED
    assert float(rows["Mesh edges folded back"].rstrip("%")) > 0
    assert any("crumples over" in note for note in notes)


def test_a_scans_first_sketch_edit_says_it_replaces_the_scans_outline_and_one_undo_restores_it():
    """Session 31, noticed: the first edit of a scan's derived sketch replaced the scan's outline
    and veins by the sketch's curves (soybean pot1_1 at grid 128: 3,000 outline points by a
    spline through 85, the area 1.4% less, the mesh moved up to 0.93 mm) without a word. The
    session says so once, with the edit's result, and as a note while the sketch draws the
    leaf; one Undo brings the scan's own leaf back, exactly."""
    from pathlib import Path

    from leafstudio.model import Params

    path = Path(__file__).resolve().parents[3].parent / "shared" / "realleaves"
    path = path / "soybean_11_20190508T043118_pot1_1.txt"
    if not path.exists():
        pytest.skip("the shared scans are not beside us")
    runner = Runner()
    session = Session(runner, Params(k=3, grid=64))
    told: list[str] = []
    session.outline_replaced.connect(told.append)
    session.open_path(str(path))
    runner.finish(session)
    opened, polygon = session.leaf, session.result.polygon.copy()
    boundary = opened.boundary.copy()
    assert session.state.scan is not None and session.outline_note == "" and not told
    sketch = session.editable_sketch()
    i = len(sketch.boundary) // 3
    moved = sketch.moved(-1, i, sketch.boundary[i] + 0.002 * (sketch.boundary[i] - [0, 0]))
    session.commit_sketch(moved, "Move point")
    assert len(told) == 1 and "replaced the scan's outline and veins" in told[0]
    assert f"({len(sketch.boundary)} outline points)" in told[0] and "Undo" in told[0]
    assert session.notes_of(session.last_id) == told
    assert "scan's outline and veins were replaced" in session.outline_note
    session.commit_sketch(moved.moved(-1, i, moved.boundary[i] * 1.001), "Move point")
    assert len(told) == 1  # said once: the leaf is the sketch's already
    session.undo()
    assert "replaced" in session.outline_note  # still drawn by the sketch
    session.undo()  # back to before the first edit: the scan's own leaf
    assert session.leaf is opened and np.array_equal(session.leaf.boundary, boundary)
    assert session.outline_note == ""
    runner.finish(session)
    np.testing.assert_array_equal(session.result.polygon, polygon)  # its 3,000-point outline
    assert len(polygon) > 10 * len(sketch.boundary)


def test_an_opened_leafs_first_sketch_edit_says_it_is_redrawn_by_the_sketch(tmp_path):
    """The same for a leaf read from a file (its derived sketch approximates it too)."""
    session, runner, _ = opened_session()
    session.open_demo("nested")
    runner.finish(session)
    told: list[str] = []
    session.outline_replaced.connect(told.append)
    sketch = session.editable_sketch()
    session.commit_sketch(sketch.moved(-1, 2, sketch.boundary[2] * 1.01), "Move point")
    assert len(told) == 1 and "the opened leaf's outline and veins" in told[0]


def test_a_project_whose_sketch_plane_is_degenerate_is_refused_in_one_line(tmp_path):
    """A project whose sketch's plane is all zeros opened, and its sketch made the leaf all at
    one point; the app says so in one line naming the file and keeps its leaf (review36)."""
    import json

    from tests.leaves import clicked_sketch

    session, _runner, got = opened_session()
    session.open_demo("nested")
    before = session.state
    sketch = clicked_sketch()
    path = tmp_path / "flat.leaf.json"
    save_leaf(sketch.to_leaf(), path, FAST, sketch.to_dict())
    data = json.loads(path.read_text())
    data["sketch"]["plane"] = {"origin": [0, 0, 0], "u": [0] * 3, "v": [0] * 3, "normal": [0] * 3}
    path.write_text(json.dumps(data))
    session.open_path(str(path))
    assert got["opened"] == [] and len(got["failed"]) == 1
    what, message = got["failed"][0]
    assert what == "file" and "flat.leaf.json" in message and "\n" not in message
    assert 'bad sketch ("plane"\'s u must be a unit vector' in message
    assert session.state is before
