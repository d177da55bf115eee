"""A posed form's bend is kept in its project (issue 21: `.leaf.json` lost it, so a folded form
written to a file and opened again was reconstructed side-on)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.core.bend import Pose
from leafstudio.forms import make_form


def test_a_folded_forms_project_reconstructs_as_the_form_does(tmp_path):
    leaf = make_form("ovate", fold=60, curl=0.3)
    path = tmp_path / "folded.leaf.json"
    ls.save_leaf(leaf, path)
    bend = json.loads(path.read_text())["bend"]
    assert (bend["fold"], bend["curl"]) == (60.0, 0.3)
    loaded = ls.load_leaf(path)
    assert loaded.bend == Pose(60.0, 0.3)
    assert loaded.bend.key() == leaf.bend.key()  # its relief too (core/pose_relief.py)
    params = ls.Params(k=3, grid=64)
    direct, reopened = ls.reconstruct(leaf, params), ls.reconstruct(loaded, params)
    np.testing.assert_allclose(reopened.triangle_mesh.points, direct.triangle_mesh.points)


def test_a_flat_leafs_project_has_no_bend(tmp_path):
    path = tmp_path / "flat.leaf.json"
    ls.save_leaf(ls.demo("nested"), path)
    assert "bend" not in json.loads(path.read_text())
    assert ls.load_leaf(path).bend is None


@pytest.mark.parametrize("bend", [{"fold": 95}, {"fold": "x"}, [60], {"wobble": 1}, {"twist": "x"}])
def test_a_bad_bend_is_one_leaf_error(tmp_path, bend):
    path = tmp_path / "bad.leaf.json"
    ls.save_leaf(ls.demo("nested"), path)
    data = json.loads(path.read_text())
    data["bend"] = bend
    path.write_text(json.dumps(data))
    with pytest.raises(ls.LeafError, match="bend"):
        ls.load_leaf(path)
