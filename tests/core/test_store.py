"""The one cache of stage outputs (store.StageStore, as stages.py uses it): a stage is
recomputed exactly when its inputs change, keyed by the leaf's fingerprint and the parameters it
reads."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.core import stages
from leafstudio.core.grid import make_grid
from leafstudio.core.pipeline import Pipeline
from leafstudio.core.stages import Stage, StageRun
from leafstudio.core.store import MISSING, StageStore
from leafstudio.core.trianglemesh import TriangleMesh

PARAMS = ls.Params(k=3, grid=48, samples=800)
EVERY_STAGE = (
    "frame", "implicit", "grid", "guide", "samples", "gmm", "bending", "surface", "layout", "mesh"
)  # fmt: skip


def test_a_new_k_reruns_the_mixture_and_after_and_reuses_the_implicit_and_guide_outputs():
    pipe = Pipeline(ls.demo("nested"))
    first = pipe.run(PARAMS)
    assert first.ran == EVERY_STAGE
    second = pipe.run(PARAMS.with_(k=4))
    assert second.ran == ("gmm", "surface", "mesh")
    assert second.unit.g_grid is first.unit.g_grid  # the guide's very output, not a copy
    assert second.unit.em_samples is first.unit.em_samples  # the samples stage's
    assert second.unit.surface.implicit is first.unit.surface.implicit
    assert not np.array_equal(second.triangle_mesh.points, first.triangle_mesh.points)


def test_a_new_seed_draws_new_samples_but_keeps_the_guide():
    pipe = Pipeline(ls.demo("nested"))
    pipe.run(PARAMS)
    assert pipe.run(PARAMS.with_(seed=7)).ran == ("samples", "gmm", "surface", "mesh")


def test_the_same_parameters_again_run_nothing_and_give_the_same_mesh():
    pipe = Pipeline(ls.demo("parallel"))
    first = pipe.run(PARAMS)
    again = pipe.run(PARAMS)
    assert again.ran == () and again.timings == {}
    assert again.unit.triangle_mesh is first.unit.triangle_mesh


def test_a_different_leaf_with_the_same_parameters_misses_a_shared_store():
    store = StageStore()
    Pipeline(ls.demo("nested"), store).run(PARAMS)
    assert Pipeline(ls.demo("parallel"), store).run(PARAMS).ran == EVERY_STAGE


def test_an_equal_leaf_hits_a_shared_store_and_a_store_keeps_several_leaves():
    store = StageStore(per_stage=2)
    nested, parallel = ls.demo("nested"), ls.demo("parallel")
    Pipeline(nested, store).run(PARAMS)
    Pipeline(parallel, store).run(PARAMS)
    copy = ls.Leaf(nested.boundary.copy(), [v.copy() for v in nested.veins])
    assert Pipeline(copy, store).run(PARAMS).ran == ()  # keyed by coordinates, not identity
    moved = ls.Leaf(nested.boundary + [0, 0, 1e-9], nested.veins)
    assert Pipeline(moved, store).run(PARAMS).ran == EVERY_STAGE


def test_a_cached_run_gives_what_a_fresh_pipeline_gives():
    pipe = Pipeline(ls.demo("nested"))
    pipe.run(PARAMS.with_(k=5, mesher="bpa"))
    cached = pipe.run(PARAMS)
    fresh = Pipeline(ls.demo("nested")).run(PARAMS)
    for name in ("points", "regular_faces"):
        np.testing.assert_array_equal(
            getattr(cached.triangle_mesh, name), getattr(fresh.triangle_mesh, name)
        )
    for name, values in fresh.triangle_mesh.point_data.items():
        np.testing.assert_array_equal(cached.triangle_mesh.point_data[name], values)


def test_the_store_keeps_per_stage_outputs_most_recent_first():
    store = StageStore(per_stage=2)
    for key in ("a", "b", "c"):
        store.put("gmm", (key,), key)
    assert store.get("gmm", ("a",)) is MISSING
    assert store.get("gmm", ("b",)) == "b"  # now the most recent: "c" goes next
    store.put("gmm", ("d",), "d")
    assert store.get("gmm", ("c",)) is MISSING
    assert store.stages() == ("gmm",)


def test_a_stage_that_reads_an_output_it_does_not_depend_on_is_refused(monkeypatch):
    def sneaky(run: StageRun):
        return run["mesh"]  # grid does not depend on the mesh: its key would not cover it

    monkeypatch.setitem(stages.STAGE_TABLE, "grid", Stage("grid", ("frame",), sneaky))
    with pytest.raises(KeyError, match="'grid' reads 'mesh'"):
        Pipeline(ls.demo("nested")).run(PARAMS)


def test_the_layout_keeps_the_implicits_derivatives_at_the_mesh_vertices():
    """They used to be kept on the MPUImplicit by array identity (a side cache); now they are
    the layout stage's output, read-only, and equal to a fresh evaluation."""
    pipe = Pipeline(ls.demo("nested"))
    result = pipe.run(PARAMS)
    implicit = result.unit.surface.implicit
    assert not hasattr(implicit, "_last")
    run = StageRun(pipe, PARAMS, None, None)
    layout = run["layout"]
    assert run.ran == []  # from the store
    for kept, fresh in zip(layout.implicit_at, implicit.derivatives(layout.xy), strict=True):
        assert not kept.flags.writeable
        np.testing.assert_allclose(kept, fresh, rtol=1e-12, atol=1e-12)


def test_a_runs_metrics_and_vtk_mesh_are_store_entries_under_the_meshs_key():
    """They were kept on each Result (a measuring generator under one global lock, a cached
    property): a rerun of the same leaf and parameters measured and built them again."""
    pipe = Pipeline(ls.demo("nested"))
    first = pipe.run(PARAMS)
    metrics, poly = first.metrics, first.mesh
    again = pipe.run(PARAMS)
    assert again.measured and again.metrics is metrics and again.mesh is poly
    assert {"metrics", "polydata"} <= set(pipe.store.stages())
    other = pipe.run(PARAMS.with_(k=4))  # another mesh: its own entries
    assert not other.measured and other.mesh is not poly
    assert first.metrics is metrics  # the first Result keeps its own once measured
    assert first.unit.measured and first.unit.metrics["mesh"]["area"] > 0  # shared with its unit


def test_a_result_copied_with_another_mesh_measures_that_mesh():
    result = Pipeline(ls.demo("nested")).run(PARAMS)
    area = result.metrics["mesh"]["area"]
    mesh = result.triangle_mesh
    doubled = TriangleMesh(2 * mesh.points, mesh.regular_faces, mesh.point_data)
    bigger = replace(result, triangle_mesh=doubled, unit=None, units=None)
    assert not bigger.measured  # replace carries no figures of the mesh it replaced
    assert bigger.metrics["mesh"]["area"] == pytest.approx(4 * area)
    assert bigger.mesh.n_points == len(doubled.points)
    np.testing.assert_array_equal(bigger.mesh.points, doubled.points)


def test_core_keeps_no_cache_beside_the_store():
    """One cache (issue 20): no cached_property, lru_cache or functools.cache left in core; the
    grid's nodes are made with the grid (the grid stage's output)."""
    core = Path(stages.__file__).parent
    found = [
        f"{path.relative_to(core)}: {marker}"
        for path in core.rglob("*.py")
        for marker in ("cached_property", "lru_cache", "functools.cache", "@cache\n")
        if marker in path.read_text(encoding="utf-8")
    ]
    assert found == []
    grid = make_grid(np.array([[0.0, 0.0], [1.0, 0.5]]), 16)
    gx, gy = np.meshgrid(
        grid.origin[0] + grid.spacing * np.arange(grid.shape[1]),
        grid.origin[1] + grid.spacing * np.arange(grid.shape[0]),
    )
    np.testing.assert_array_equal(grid.points, np.column_stack([gx.ravel(), gy.ravel()]))
    assert not grid.points.flags.writeable
