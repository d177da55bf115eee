"""Projects of format version 1 keep the blade that was drawn (sources/bend_entry.py): their
fold and curl were shears, z += |y| tan(fold) + curl · x², and today's keep the blade's size."""

from __future__ import annotations

import json

import numpy as np
import pytest

from leafstudio.core.bend import Pose
from leafstudio.core.placed import PlacedPose
from leafstudio.core.plane import Frame
from leafstudio.forms import Form
from leafstudio.sources.files import FORMAT_VERSION, load_project, save_leaf


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
    assert json.loads(path.read_text())["version"] == FORMAT_VERSION == 2
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
