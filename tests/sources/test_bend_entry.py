"""Projects of format version 1 keep the blade that was drawn (sources/bend_entry.py): their
fold and curl were shears, z += |y| tan(fold) + curl · x², and today's keep the blade's size."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from leafstudio.core.bend import Pose
from leafstudio.core.placed import PlacedPose
from leafstudio.core.plane import Frame
from leafstudio.errors import LeafError
from leafstudio.forms import Form
from leafstudio.sources import files
from leafstudio.sources.files import load_project, save_leaf


def _sheared(points: np.ndarray, fold: float, curl: float) -> np.ndarray:
    """Flat blade points bent as version 1 bent them (no roll, no twist)."""
    bent = np.array(points, dtype=float)
    bent[:, 2] += np.abs(bent[:, 1]) * np.tan(np.radians(fold)) + curl * bent[:, 0] ** 2
    return bent


def _write_v1(path, boundary, veins, bend) -> None:
    data = {"format": "leafstudio", "version": 1, "boundary": boundary.tolist()}
    data |= {"veins": [v.tolist() for v in veins], "bend": bend}
    path.write_text(json.dumps(data))


def test_a_version_1_posed_project_opens_on_the_blade_it_was_drawn_on(tmp_path):
    flat = Form("ovate").leaf()
    path = tmp_path / "old.leaf.json"
    sheared = [_sheared(c, 60.0, 0.5) for c in (flat.boundary, *flat.veins)]
    _write_v1(path, sheared[0], sheared[1:], {"fold": 60.0, "curl": 0.5})
    leaf = load_project(path)[0]
    assert leaf.bend == Pose(60.0, 0.5)
    np.testing.assert_allclose(leaf.bend.flatten(leaf.boundary), flat.boundary, atol=1e-12)
    for vein, drawn in zip(leaf.veins, flat.veins, strict=True):
        np.testing.assert_allclose(leaf.bend.flatten(vein), drawn, atol=1e-12)
    # read as today's pose, the old curves would lay a blade twice as wide
    wide = Pose(60.0, 0.5).flatten(sheared[0])
    assert np.ptp(wide[:, 1]) > 1.9 * np.ptp(flat.boundary[:, 1])


def test_a_version_1_project_bent_in_the_app_opens_on_its_blade(tmp_path):
    flat = Form("elliptic").leaf()
    frame = Frame(
        origin=np.array([1.0, 2.0, 3.0]),
        u=np.array([0.0, 1.0, 0.0]),
        v=np.array([0.0, 0.0, 1.0]),
        normal=np.array([1.0, 0.0, 0.0]),
    )
    world = lambda blade: frame.to_world(blade[:, :2], blade[:, 2])  # noqa: E731
    curves = [world(_sheared(c, -40.0, 0.3)) for c in (flat.boundary, *flat.veins)]
    axes = {k: getattr(frame, k).tolist() for k in ("origin", "u", "v", "normal")}
    path = tmp_path / "old.leaf.json"
    _write_v1(path, curves[0], curves[1:], {"fold": -40.0, "curl": 0.3, "frame": axes})
    leaf = load_project(path)[0]
    assert isinstance(leaf.bend, PlacedPose)
    np.testing.assert_allclose(leaf.bend.flatten(leaf.boundary), world(flat.boundary), atol=1e-9)


@pytest.mark.parametrize("bend", [{"roll": 2.0}, {"fold": 0.0, "curl": 0.0, "twist": 1.0}])
def test_a_version_1_roll_or_twist_reads_as_it_was(tmp_path, bend):
    flat = Form("linear").leaf()
    pose = Pose(**bend)
    bent = [pose.apply(c) for c in (flat.boundary, *flat.veins)]
    path = tmp_path / "old.leaf.json"
    _write_v1(path, bent[0], bent[1:], bend)
    leaf = load_project(path)[0]
    np.testing.assert_array_equal(leaf.boundary, bent[0])


def test_a_posed_project_is_saved_as_version_2_and_reads_back(tmp_path):
    leaf = Form("ovate", fold=45.0, curl=0.4).leaf()
    path = tmp_path / "new.leaf.json"
    save_leaf(leaf, str(path))
    assert json.loads(path.read_text())["version"] == 2  # what a version 2 reader reads whole
    again = load_project(path)[0]
    np.testing.assert_allclose(again.boundary, leaf.boundary, atol=1e-12)
    assert again.bend == leaf.bend


def test_a_version_1_curl_past_half_a_turn_is_eased_and_said(tmp_path):
    """A shear raised an 80 mm leaf curled 0.05 per mm (z = 0.05 x²) whatever its length; on a
    circle that is 8 radians, which no flattening undoes (the project failed to open: "vein 4:
    3 of 15 points lie outside the boundary")."""
    flat = Form("elliptic").leaf()
    scaled = [c * 80 for c in (flat.boundary, *flat.veins)]
    path = tmp_path / "long.leaf.json"
    _write_v1(path, *(lambda c: (c[0], c[1:]))([_sheared(c, 0.0, 0.05) for c in scaled]),
              {"curl": 0.05})  # fmt: skip
    with pytest.warns(UserWarning, match="curl of 0.05 is read as"):
        leaf = load_project(path)[0]
    assert 0 < leaf.bend.curl < 0.05
    np.testing.assert_allclose(leaf.bend.flatten(leaf.boundary), scaled[0], atol=1e-9)


@pytest.mark.parametrize("sheet", ["bogus", "MARGIN", None, 1])
def test_a_reliefs_bad_sheet_is_named_not_the_whole_bend_form(sheet):
    """A fitted relief's "sheet" must be "margin" or "mean": the error says so, where it gave the
    whole "bend" form and about 2,800 characters of the value (review of session 29)."""
    import leafstudio as ls
    from leafstudio.core.unfold import fit_pose
    from leafstudio.errors import LeafError
    from leafstudio.sources.bend_entry import _bend

    posed = Form("ovate", fold=45.0).leaf()
    pose = fit_pose(ls.Leaf(posed.boundary, posed.veins)).pose
    relief = pose.relief.entry() | {"sheet": sheet}
    with pytest.raises(LeafError, match='"relief": a relief\'s "sheet" must be "margin" or "mean"'):
        _bend({"fold": pose.fold, "relief": relief}, "leaf.leaf.json", posed)


def _with_bend(tmp_path, bend: dict):
    """A form's project (ovate folded 30, as `form` writes it) with its "bend" replaced."""
    from leafstudio.sources.files import save_leaf

    path = tmp_path / "edited.leaf.json"
    save_leaf(Form("ovate", fold=30).leaf(), path)
    data = json.loads(path.read_text())
    data["bend"] = bend
    path.write_text(json.dumps(data))
    return path


@pytest.mark.parametrize(
    "bend, term",
    [
        ({"fold": 89}, '"fold" 89'),  # 0.83 of the blade's area
        ({"fold": -85}, '"fold" -85'),  # 1.10
        ({"roll": 1000}, '"roll" 1000'),  # 54 s, 5.9 GB, 2.35 M triangles
        ({"roll": 1e9}, '"roll" 1e+09'),  # the boundary 0.34 of the length off the mesh
        ({"curl": 5}, '"curl" 5'),  # wrapped past a full turn
        ({"curl": 50}, '"curl" 50'),
        ({"curl": -1e6}, '"curl" -1e+06'),
        ({"twist": 100}, '"twist" 100'),  # refused as "is this a scan?"
        ({"fold": 30, "roll": 1000}, '"roll" 1000'),
    ],
)
def test_a_bend_past_what_the_pose_honours_is_refused_by_name(tmp_path, bend, term):
    """appreview31 findings 6 and 9: a hand-edited (or another tool's) "bend" beyond what the
    pose keeps was taken without a word. It is refused in one line that names the term, its
    value and the range it may take on this blade, in the file's units."""
    from leafstudio.errors import LeafError

    with pytest.raises(LeafError) as raised:
        load_project(_with_bend(tmp_path, bend))
    message = str(raised.value)
    assert term in message and "\n" not in message
    assert " to " in message  # the range allowed


def test_the_cli_refuses_such_a_bend_in_one_line(tmp_path, capsys):
    from leafstudio.cli import main

    path = _with_bend(tmp_path, {"roll": 1000})
    assert main(["measure", str(path), "--grid", "32"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and '"roll" 1000' in err[0]


EXTREMES = [(75, 1, 1, 1), (-75, -1, -1, -1), (75, -1, 1, -1), (-75, 1, -1, 1)]


@pytest.mark.parametrize("shape", ["ovate", "reniform", "linear", "cordate"])
@pytest.mark.parametrize("terms", EXTREMES)
def test_a_form_posed_at_the_sliders_ends_reopens(tmp_path, shape, terms):
    """Whatever `form` and the Forms dock write reopens: every term at its slider's end."""
    from leafstudio.sources.files import save_leaf

    fold, curl, roll, twist = terms
    leaf = Form(shape, fold=fold, curl=curl, roll=roll, twist=twist).leaf()
    path = tmp_path / "posed.leaf.json"
    save_leaf(leaf, path)
    assert load_project(path)[0].bend == leaf.bend


@pytest.mark.parametrize("terms", EXTREMES)
def test_a_drawn_leaf_bent_at_the_sliders_ends_reopens(tmp_path, terms):
    """The Parameters panel's sliders at their ends (bend_sliders.RANGES, in their units: a roll
    of 1 closes the blade into a tube, a twist of 1 turns the apex half a turn), saved as the
    window saves, reopen with the same pose."""
    from leafstudio.gui.model.bending import blade_half_width
    from leafstudio.gui.model.session import Session
    from leafstudio.model import Params
    from leafstudio.sources.files import save_leaf
    from tests.gui.builders import Runner
    from tests.leaves import clicked_sketch

    runner = Runner()
    session = Session(runner, Params(k=3, grid=32))
    session.commit_sketch(clicked_sketch(), "Draw")
    fold, curl, roll, twist = terms
    half = blade_half_width(session.state.leaf, session.state.sketch.frame)
    session.set_bend(Pose(fold, curl, roll * np.pi / half, twist * np.pi), final=True)
    path = tmp_path / "drawn.leaf.json"
    save_leaf(session.state.leaf, path, session.state.params, session.state.sketch.to_dict())
    leaf = load_project(path)[0]
    assert isinstance(leaf.bend, PlacedPose) and leaf.bend.pose == session.state.leaf.bend.pose


def test_a_pose_saved_without_its_relief_at_the_sliders_ends_reopens(tmp_path):
    """A project saved before reliefs (its pose bends the sheet z = 0) at the sliders' ends."""
    from leafstudio.model import Leaf
    from leafstudio.sources.files import save_leaf

    blade = Form("ovate").blade()
    half = float(np.abs(blade.boundary[:, 1]).max())
    for fold, curl, roll, twist in EXTREMES:
        pose = Pose(fold, curl, roll * np.pi / half, twist * np.pi)
        leaf = Leaf(pose.apply(blade.boundary), [pose.apply(v) for v in blade.veins], bend=pose)
        path = tmp_path / "old.leaf.json"
        save_leaf(leaf, path)
        assert load_project(path)[0].bend == pose


def test_a_fit_the_app_saved_past_the_folds_limit_reopens(tmp_path):
    """A pose fitted to curves in 3D (core/unfold.py) was searched to 85° each way before the
    loader took folds to pose_limits.FOLD (80°): a project the app saved with such a fit (a leaf
    folded past 80° given as curves) was refused on opening. It reopens, its curves as saved;
    a form's pose at the same fold is still refused."""
    from dataclasses import replace

    from leafstudio.core.bend import flat_leaf
    from leafstudio.core.unfold import fit_pose
    from leafstudio.errors import LeafError
    from leafstudio.model import Leaf

    form = Form("ovate", fold=75.0).leaf()
    fit = fit_pose(Leaf(form.boundary, form.veins))
    assert fit is not None and fit.pose.relief.on_margin
    flat = flat_leaf(Leaf(form.boundary, form.veins, bend=fit))
    bend = PlacedPose(replace(fit.pose, fold=83.0), fit.frame)
    leaf = Leaf(bend.apply(flat.boundary), [bend.apply(v) for v in flat.veins], bend=bend)
    path = tmp_path / "fitted.leaf.json"
    save_leaf(leaf, path)
    opened = load_project(path)[0]
    assert opened.bend.pose.fold == 83.0
    assert np.allclose(opened.boundary, leaf.boundary)
    with pytest.raises(LeafError, match='"fold" 83'):
        load_project(_with_bend(tmp_path, {"fold": 83}))


@pytest.mark.parametrize(
    "form",
    [
        {"shape": "cordate", "wave": 0.2, "roll": 1.0},  # read 1.41 half turns, refused
        {"shape": "ovate", "wave": 0.2, "fold": 75.0, "curl": 1.0, "roll": 1.0, "twist": 1.0},
        {"shape": "hastate", "wave": 0.2, "fold": 75.0, "roll": 1.0},
        {"shape": "orbicular", "aspect": 30.0, "fold": -75.0, "roll": -1.0},  # 1.31
    ],
)
def test_a_wavy_or_narrow_form_rolled_at_the_sliders_end_reopens(tmp_path, form):
    """review31: the roll's measure of the margin's reach counted the blade's own heights (its
    wave, its relief), so `form cordate --wave 0.2 --roll 1` wrote a project it then refused
    ("rolls its margins ... through 1.41 half turns")."""
    from leafstudio.sources.files import save_leaf

    leaf = Form(**form).leaf()
    path = tmp_path / "rolled.leaf.json"
    save_leaf(leaf, path)
    assert load_project(path)[0].bend == leaf.bend


def test_a_strongly_curled_point_list_the_app_fitted_reopens(tmp_path):
    """Ovate curled 1.7 (as a form's relief bends it) given as curves: the unfold fits a curl
    turning the midrib 3.11 radians (its search is over the curled outline's short diagonal,
    pose_limits.CURL_SEARCH), the app saves it, and the loader refused it past MOST_TURN
    (review31). What the fit searched reopens; ten times that curl is still refused."""
    from dataclasses import replace

    from leafstudio.core.unfolded import unfolded
    from leafstudio.errors import LeafError
    from leafstudio.model import Leaf
    from leafstudio.sources.files import load_leaf

    form = Form("ovate")
    blade = form.blade()
    pose = Pose(curl=1.7, relief=form.with_(curl=1.0).leaf(blade).bend.relief)
    csv = tmp_path / "curled.csv"
    save_leaf(Leaf(pose.apply(blade.boundary), [pose.apply(v) for v in blade.veins]), csv)
    fitted = unfolded(load_leaf(csv))
    assert isinstance(fitted.bend, PlacedPose) and 2 * fitted.bend.pose.curl > 2.98
    path = tmp_path / "curled.leaf.json"
    save_leaf(fitted, path)
    assert load_project(path)[0].bend.pose.curl == fitted.bend.pose.curl
    bend = PlacedPose(replace(fitted.bend.pose, curl=10 * fitted.bend.pose.curl), fitted.bend.frame)
    with pytest.raises(LeafError, match='"curl"'):  # not written (core/pose_limits.check_pose)
        save_leaf(replace(fitted, bend=bend), path)
    data = json.loads(path.read_text())  # ... nor read, edited by hand
    data["bend"]["curl"] *= 10
    path.write_text(json.dumps(data))
    with pytest.raises(LeafError, match='"curl"'):
        load_project(path)


def test_a_scan_project_with_a_smoothing_per_cell_is_version_3_and_an_older_reader_says_so(
    tmp_path, monkeypatch
):
    """A scan's sheet keeps a smoothing per cell (core/sheet.refit): a version 2 reader took the
    list for a broken sheet ("its "sheet" does not read whole", review33); the project is
    version 3, and a version 2 reader says it was written by a newer LeafStudio. A scan project
    saved before (one smoothing) stays version 2, and both open."""
    from leafstudio.core.sheet import fit_sheet
    from leafstudio.core.sheet_bend import Scaled
    from leafstudio.model import Leaf

    rng = np.random.default_rng(0)
    uv = rng.uniform([-0.5, -0.2], [0.5, 0.2], (12000, 2))
    uv = uv[(uv[:, 0] / 0.5) ** 2 + (uv[:, 1] / 0.2) ** 2 < 1][:4000]
    blade = np.column_stack([uv, 0.1 * uv[:, 0] ** 2])
    sheet = fit_sheet(blade, np.array([0.0, 0.0, 1.0]), 1.0)
    assert np.ndim(sheet.smoothing) == 1
    t = np.linspace(0, 2 * np.pi, 60, endpoint=False)
    flat = np.column_stack([0.45 * np.cos(t), 0.18 * np.sin(t), 0 * t])
    midrib = np.column_stack([np.linspace(-0.4, 0.4, 12), np.zeros(12), np.zeros(12)])
    saved = {}
    for name, kept in (("new", sheet), ("old", replace(sheet, smoothing=2e-3))):
        bend = Scaled(kept, np.zeros(3), 1.0)
        leaf = Leaf(bend.apply(flat), [bend.apply(midrib)], bend=bend)
        path = tmp_path / f"{name}.leaf.json"
        save_leaf(leaf, str(path))
        saved[name] = path
        assert json.loads(path.read_text())["version"] == (3 if name == "new" else 2)
        again = load_project(path)[0]
        assert again.bend.key() == bend.key()
    monkeypatch.setattr(files, "FORMAT_VERSION", 2)  # an older LeafStudio
    with pytest.raises(LeafError, match=r"written by a newer LeafStudio \(version 3\)"):
        load_project(saved["new"])
    assert (
        load_project(saved["old"])[0].bend.key()
        == Scaled(replace(sheet, smoothing=2e-3), np.zeros(3), 1.0).key()
    )


@pytest.mark.parametrize(
    "term, value, said",
    [
        ("fold", True, "true"),  # was read as a fold of 1, refused as veins outside the boundary
        ("fold", "30", '"30"'),  # was read as 30
        ("curl", None, "null"),
        ("roll", [0.5], "[0.5]"),
        ("twist", False, "false"),
    ],
)
def test_a_bend_term_that_is_no_number_is_refused_by_name(tmp_path, capsys, term, value, said):
    """A hand-edited "bend": {"fold": true} was read as a fold of 1 (Python's float(True)) and
    then refused as veins outside the boundary; a string was read as its number, and null or a
    list gave the whole "bend" form. Each is refused in one line naming the term (CLI exit 2)."""
    from leafstudio.cli import main

    path = _with_bend(tmp_path, {"fold": 30.0, term: value})
    with pytest.raises(LeafError) as raised:
        load_project(path)
    message = str(raised.value)
    assert f'"bend": its "{term}" must be a number, got {said}' in message
    assert "\n" not in message and "boundary" not in message
    assert main(["measure", str(path), "--grid", "32"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f'"{term}"' in err[0]
