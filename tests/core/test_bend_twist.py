"""A twisted blade (issue 21, build item 1): each cross-section turned about the midrib by
twist · x radians, a helicoid, as a twisted grass blade; undone exactly, reconstructed on the
flat blade. The project and command-line checks of a pose term are written once here, for the
roll and the twist alike."""

from __future__ import annotations

import json

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.core.bend import Pose
from leafstudio.forms.make import Form
from tests.core.test_bend_roll import posed_form_on_its_surface

TWISTED = [
    ("lanceolate", {"aspect": 30, "twist": 1.0}),  # a grass blade turned half a turn
    ("ovate", {"twist": 0.5}),
    ("ovate", {"twist": -0.5, "fold": 45, "curl": 0.5, "roll": 0.3}),
]


@pytest.mark.parametrize(("shape", "terms"), TWISTED)
def test_a_twisted_forms_mesh_lies_on_its_twisted_surface(shape, terms):
    """The mesh is the flat blade's mesh twisted: within 2e-3 of the length of the form's own
    surface (mean and 95th percentile), the veins as close as a fold's, the boundary exact, no
    side-on warning."""
    pose, _ = posed_form_on_its_surface(shape, terms)
    assert pose.twist == pytest.approx(terms["twist"] * np.pi)


def test_a_twist_is_undone_exactly_and_keeps_the_midrib():
    pose = Pose(fold=30, curl=0.4, roll=9.0, twist=2.0)
    rng = np.random.default_rng(1)
    points = np.column_stack(
        [rng.uniform(0, 1, 50), rng.uniform(-0.3, 0.3, 50), rng.normal(0, 0.01, 50)]
    )
    np.testing.assert_allclose(pose.flatten(pose.apply(points)), points, atol=1e-12)
    # a cross-section at x turns by twist · x, its width kept; the midrib stays put
    v = np.linspace(-0.3, 0.3, 11)
    section = Pose(twist=2.0).apply(np.column_stack([np.full_like(v, 0.5), v, np.zeros_like(v)]))
    np.testing.assert_allclose(section[:, 2], v * np.sin(1.0), atol=1e-12)
    np.testing.assert_allclose(section[5], [0.5, 0, 0], atol=1e-12)


def test_no_twist_is_todays_pose_and_a_project_stores_the_twist_in_radians(tmp_path):
    assert Pose(40, 0.3).key() == np.array([40.0, 0.3]).tobytes()
    assert Pose(40, 0.3, twist=1.0).key() != Pose(40, 0.3, roll=1.0).key()
    plain, twisted0 = Form("ovate", fold=40).leaf(), Form("ovate", fold=40, twist=0.0).leaf()
    assert np.array_equal(plain.boundary, twisted0.boundary) and plain.bend == twisted0.bend
    leaf = Form("ovate", twist=0.5).leaf()
    path = tmp_path / "twisted.leaf.json"
    ls.save_leaf(leaf, path)
    assert json.loads(path.read_text())["bend"]["twist"] == pytest.approx(0.5 * np.pi)


@pytest.mark.parametrize("term", ["roll", "twist"])
def test_a_posed_project_opens_posed_and_a_bad_term_is_one_error(tmp_path, term):
    leaf = Form("ovate", **{term: 0.5}).leaf()
    path = tmp_path / f"{term}.leaf.json"
    ls.save_leaf(leaf, path)
    assert ls.load_leaf(path).bend == leaf.bend
    data = json.loads(path.read_text())
    data["bend"] = {term: "x"}
    path.write_text(json.dumps(data))
    with pytest.raises(ls.LeafError) as caught:
        ls.load_leaf(path)
    assert "\n" not in str(caught.value) and term in str(caught.value)


@pytest.mark.parametrize("flag", ["--roll", "--twist"])
def test_the_cli_writes_a_rolled_or_twisted_grass_blade(tmp_path, capsys, flag):
    from leafstudio.cli import main

    out = tmp_path / "x.glb"
    assert main(["form", "lanceolate", "--aspect", "30", flag, "1", "-o", str(out)]) == 0
    assert out.stat().st_size > 0
    assert "edge" not in capsys.readouterr().err


def test_the_cli_refuses_a_twist_past_its_range(tmp_path):
    from leafstudio.cli import main

    out = tmp_path / "x.glb"
    assert main(["form", "ovate", "--twist", "3", "-o", str(out)]) == 2
