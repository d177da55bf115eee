"""What the viewport draws, built without Qt: one piece per vein, names unique, data in place."""

from __future__ import annotations

import sys
import threading

import numpy as np
import pytest

from leafstudio.core.pipeline import Pipeline
from leafstudio.gui.model.layers import LAYERS, SIDE_LAYERS, build_layers
from leafstudio.gui.model.measurements import measurement_rows
from leafstudio.sources.demos import demo
from tests.gui.builders import FAST


@pytest.fixture
def result(demo_result):
    return demo_result("nested")


def test_every_layer_is_built_with_unique_names(result):
    layers = build_layers(result)
    assert set(layers) == {key for key, _, _ in LAYERS} - SIDE_LAYERS
    names = [piece.name for pieces in layers.values() for piece in pieces]
    assert len(names) == len(set(names))
    assert len(layers["points"]) == 1 + len(result.leaf.veins)  # boundary + each vein


def test_layers_built_off_the_main_thread_hold_no_vtk_object_until_drawn():
    result = Pipeline(demo("nested")).run(FAST)
    built = {}
    thread = threading.Thread(target=lambda: built.update(build_layers(result)))
    thread.start()
    thread.join()
    pieces = [piece for layer in built.values() for piece in layer]
    assert not any("data" in piece.__dict__ for piece in pieces)
    assert "mesh" not in result.__dict__  # nor the result's PolyData
    mesh = built["mesh"][0].data  # made here, on the main thread
    assert mesh.n_points == result.triangle_mesh.n_points
    normals = np.asarray(mesh.point_data["Normals"])
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0)
    assert (normals @ result.frame.normal > 0.5).all()  # a leaf's shading side faces up


def test_the_zero_contour_lies_on_the_plane_along_the_outline(result):
    contour = build_layers(result)["contour"][0].data
    xy, height = result.frame.to_plane(np.asarray(contour.points))
    np.testing.assert_allclose(height, 0.0, atol=1e-9)
    spacing = result.grid.spacing
    gap = np.min(np.linalg.norm(xy[:, None] - result.polygon[None], axis=2), axis=1)
    assert gap.max() < 2 * spacing


def test_the_probability_map_is_blank_outside_the_leaf(result):
    surface = build_layers(result)["probability"][0].data
    p = surface.point_data["p(x)"]
    assert np.isnan(p[~result.inside]).all() and np.isfinite(p[result.inside]).all()
    assert surface.n_cells == (result.grid.shape[0] - 1) * (result.grid.shape[1] - 1)


def test_the_mesh_has_colour_ranges_and_curvature_is_centred(result):
    mesh = build_layers(result)["mesh"][0]
    assert "Normals" in mesh.data.point_data
    low, high = mesh.ranges["height"]
    assert low <= 0 < high
    for name, (low, high) in mesh.ranges.items():
        if name != "height":
            assert low == -high


def test_measurements_show_the_table_1_distances(result):
    sections = dict(measurement_rows(result))
    table = next(rows for title, rows in sections.items() if title.startswith("Vein points"))
    assert [label for label, _ in table] == ["Min", "Max", "Mean"]
    assert all(value != "–" for _, value in table)


def test_a_layer_whose_extra_is_missing_says_which_to_install(monkeypatch):
    from leafstudio.gui.model.layers import unavailable

    assert unavailable("mesh") == ""
    monkeypatch.setitem(sys.modules, "open3d", None)  # as if the extra were not installed
    assert unavailable("poisson").endswith("pip install 'leafstudio[open3d]'")
