"""Fidelity against a scan: distances from scan points to the surface, coverage of the outline."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import pyvista as pv

import leafstudio as ls
from leafstudio.analysis.fidelity import coverage, scan_distances
from leafstudio.cli import main
from leafstudio.core.plane import Frame
from tests.leaves import extracted_scan


def _plane() -> pv.PolyData:
    return pv.Plane(i_size=2, j_size=2, i_resolution=8, j_resolution=8).triangulate()


def test_distances_to_a_plane_are_the_heights():
    heights = np.array([0.0, 0.005, 0.015, 0.025, -0.03])
    points = np.column_stack([np.linspace(-0.5, 0.5, 5), np.zeros(5), heights])
    d = scan_distances(_plane(), points, 1.0)
    assert d["points"] == 5
    assert d["mean"] == pytest.approx(np.abs(heights).mean(), abs=1e-6)
    assert d["median"] == pytest.approx(0.015, abs=1e-6)
    assert d["max"] == pytest.approx(0.03, abs=1e-6)
    assert d["beyond_1pct"] == pytest.approx(3 / 5)
    assert d["beyond_2pct"] == pytest.approx(2 / 5)
    assert scan_distances(_plane(), points, 2.0)["beyond_1pct"] == pytest.approx(2 / 5)


def _curled_leaf() -> tuple[ls.Leaf, np.ndarray]:
    """A leaf on z = 0.4 x² + 0.5 y², and a dense scan of that surface over the leaf."""
    t = np.linspace(0, 2 * np.pi, 160, endpoint=False)
    xy = np.column_stack([0.5 * np.cos(t), 0.2 * np.sin(t)])
    surface = lambda p: 0.4 * p[:, 0] ** 2 + 0.5 * p[:, 1] ** 2  # noqa: E731
    mid = np.column_stack([np.linspace(-0.46, 0.46, 40), np.zeros(40)])
    rng = np.random.default_rng(0)
    inside = rng.uniform([-0.5, -0.2], [0.5, 0.2], size=(3000, 2))
    inside = inside[(inside[:, 0] / 0.5) ** 2 + (inside[:, 1] / 0.2) ** 2 < 0.95]
    lift = lambda p: np.column_stack([p, surface(p)])  # noqa: E731
    return ls.Leaf(boundary=lift(xy), veins=[lift(mid)]), lift(inside)


def test_a_curled_leaf_is_close_to_its_scan_and_covers_its_outline():
    leaf, scan = _curled_leaf()
    result = ls.reconstruct(leaf, ls.Params(k=3, grid=64))
    d = scan_distances(result.mesh, scan, result.length)
    assert d["mean"] < 3e-3 and d["beyond_2pct"] < 0.02
    flat = scan_distances(pv.PolyData(result.mesh.points * [1, 1, 0], result.mesh.faces), scan, 1)
    assert flat["mean"] > 5 * d["mean"]  # the planar paper surface would be far off
    cover = coverage(result.mesh, result.frame, result.polygon)
    assert cover["covered"] > 0.98 and cover["outside"] < 1e-6 and cover["pieces"] == 1


def test_coverage_sees_a_hole_and_a_spill():
    mesh = _plane()
    frame = Frame(origin=np.zeros(3), u=np.eye(3)[0], v=np.eye(3)[1], normal=np.eye(3)[2])
    square = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
    cover = coverage(mesh, frame, square)
    assert cover["covered"] == pytest.approx(1.0) and cover["outside"] == pytest.approx(3.0)
    half = mesh.clip(normal="x", origin=(0, 0, 0)).extract_surface(algorithm=None).triangulate()
    assert coverage(half, frame, square)["covered"] == pytest.approx(0.5, abs=1e-6)


def test_reconstruct_against_a_scan_reports_the_distances(tmp_path, capsys):
    leaf, scan = _curled_leaf()
    leaf_file, scan_file = tmp_path / "leaf.leaf.json", tmp_path / "scan.csv"
    ls.save_leaf(leaf, leaf_file)
    np.savetxt(scan_file, np.column_stack([scan, np.ones((len(scan), 3))]), delimiter=",")
    metrics = tmp_path / "m.json"
    args = ["reconstruct", str(leaf_file), "-o", str(tmp_path / "m.ply"), "--grid", "64"]
    assert main([*args, "--against", str(scan_file), "--metrics", str(metrics)]) == 0
    out = capsys.readouterr().out
    assert "mean" in out and "beyond 2%" in out
    fidelity = json.loads(metrics.read_text())["fidelity"]
    assert fidelity["all"]["points"] == len(scan)
    assert fidelity["all"]["mean"] < 3e-3
    real = tmp_path / "real.json"  # given a real length: the distances in mm, the shares kept
    assert (
        main([*args, "--against", str(scan_file), "--metrics", str(real), "--length", "5cm"]) == 0
    )
    in_mm = json.loads(real.read_text())["fidelity"]["all"]
    assert in_mm["length"] == pytest.approx(50, rel=1e-9)
    s = 50 / fidelity["all"]["length"]
    assert in_mm["mean"] == pytest.approx(fidelity["all"]["mean"] * s, rel=1e-9)
    assert in_mm["beyond_1pct"] == fidelity["all"]["beyond_1pct"]
    assert "(leaf length 50 mm)" in capsys.readouterr().out
    empty = tmp_path / "empty.xyz"
    empty.write_text("x y z\n")
    assert main([*args, "--against", str(empty)]) == 2
    err = capsys.readouterr().err.strip()
    assert "holds no points" in err and "\n" not in err


REAL = Path(__file__).resolve().parents[3] / "shared" / "realleaves"


@pytest.mark.skipif(not REAL.is_dir(), reason="the real leaf scans are not beside the repository")
def test_a_real_sugar_beet_leaf_from_its_scan_is_close_to_the_scan():
    raw, found = extracted_scan(REAL / "sugarbeet_f00012_20170829T010129_pot1_1.txt")
    scale = 1.0 / found.length
    leaf = ls.Leaf(
        boundary=found.leaf.boundary * scale, veins=[v * scale for v in found.leaf.veins]
    )
    result = ls.Pipeline(leaf).run(ls.Params(k=3, grid=128))
    assert result.surface.base is not None  # a real margin is far from planar
    d = scan_distances(result.mesh, raw[found.blade] * scale, 1.0)
    assert d["mean"] < 0.008 and d["beyond_2pct"] < 0.05
    cover = coverage(result.mesh, result.frame, result.polygon)
    assert cover["covered"] > 0.98 and cover["outside"] < 1e-6 and cover["pieces"] == 1
