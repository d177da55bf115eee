"""Property tests of the public API (issue 24, What to build 5): whatever a script hands
`ls.Leaf`, `ls.Params`, the image reader or `ls.reconstruct`, it gets a value or one LeafError
on one line, never another exception (`ls.Leaf([[0.0], []])` raised numpy's ValueError)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import leafstudio as ls
from leafstudio._shared.inputs import read_image

FUZZ = settings(
    max_examples=120,
    deadline=10_000,  # ms per example: a hang shows as a failure
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
    derandomize=True,  # the same examples on every run: a failure repeats
)
NUMBERS = st.floats() | st.integers(-(10**30), 10**30) | st.sampled_from([1e308, -1e308, 5e-324])
# ragged lists, strings, None and booleans as well as numbers, nested up to three deep
VALUES = st.recursive(
    NUMBERS | st.none() | st.booleans() | st.text(max_size=4),
    lambda inner: st.lists(inner, max_size=6),
    max_leaves=40,
)


def _one_line(error: ls.LeafError) -> None:
    assert "\n" not in str(error) and 0 < len(str(error)) < 500, str(error)


@FUZZ
@given(boundary=VALUES, veins=st.none() | VALUES)
def test_a_leaf_from_anything_is_a_leaf_or_one_leaf_error(boundary, veins):
    try:
        leaf = ls.Leaf(boundary) if veins is None else ls.Leaf(boundary, veins)
    except ls.LeafError as exc:
        _one_line(exc)
        return
    assert leaf.boundary.ndim == 2 and leaf.boundary.shape[1] == 3
    assert np.isfinite(leaf.boundary).all()


PARAM_VALUES = (
    NUMBERS | st.none() | st.booleans() | st.text(max_size=8) | st.lists(NUMBERS, max_size=2)
)


@FUZZ
@given(
    values=st.dictionaries(
        st.sampled_from(
            ["k", "grid", "mpu_tolerance", "samples", "seed", "mesher", "radius_factor", "taper",
             "refine", "margin", "through_veins"]
        ),
        PARAM_VALUES,
        max_size=4,
    )
)  # fmt: skip
def test_params_from_anything_are_params_or_one_leaf_error(values):
    try:
        ls.Params(**values)
    except ls.LeafError as exc:
        _one_line(exc)


@FUZZ
@given(data=st.binary(max_size=3000), suffix=st.sampled_from([".png", ".jpg", ".gif", ".tif"]))
def test_an_image_from_any_bytes_is_pixels_or_one_leaf_error(tmp_path, data, suffix):
    path = tmp_path / f"photo{suffix}"
    path.write_bytes(data)
    try:
        pixels = read_image(path)
    except ls.LeafError as exc:
        _one_line(exc)
        assert str(exc).startswith(str(path))
        return
    assert pixels.dtype == np.uint8 and pixels.ndim == 3 and pixels.shape[2] in (3, 4)


@settings(FUZZ, max_examples=25)
@given(
    radii=st.lists(st.floats(0.05, 1.0), min_size=3, max_size=40),
    heights=st.lists(st.floats(-0.2, 0.2), min_size=3, max_size=40),
    scale=st.sampled_from([1e-6, 1e-3, 1.0, 1e3, 1e6]),
    offset=st.floats(-1e3, 1e3),
    vein=st.booleans(),
    k=st.integers(1, 4),
)
def test_reconstruct_on_a_small_random_leaf_is_a_result_or_one_leaf_error(
    radii, heights, scale, offset, vein, k
):
    angles = np.linspace(0, 2 * np.pi, len(radii), endpoint=False)
    z = np.resize(np.asarray(heights), len(radii))
    boundary = np.column_stack([np.cos(angles) * radii, np.sin(angles) * radii, z])
    veins = [np.array([[0.0, 0.0, 0.1], [0.02, 0.01, 0.12]])] if vein else []
    try:
        leaf = ls.Leaf(
            boundary * scale + offset * scale, [v * scale + offset * scale for v in veins]
        )
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = ls.reconstruct(leaf, ls.Params(k=k, grid=24, samples=400))
    except ls.LeafError as exc:
        _one_line(exc)
        return
    points = result.triangle_mesh.points
    assert len(points) and np.isfinite(points).all()


FINDING_18_LEAF = [
    [5e-324, 0.5, 0.5], [1, 1e300, 0], [-1, 0.5, 1e-300], [0, 5e-324, 0], [1e-300, 1e-300, 1e300]
]  # fmt: skip


def test_finding_18s_leaf_after_another_run_is_a_result_whose_metrics_are_one_leaf_error():
    """Issue 24, finding 18: after a run of the nested demo in the same process this leaf
    crashed the process (SIGSEGV in the mesher); then it gave a Result whose metrics held an
    infinite area (its extent is 1e300: its area overflows float64)."""
    ls.reconstruct(ls.demo("nested"), ls.Params(grid=32))
    params = ls.Params(k=3, grid=68, mpu_tolerance=0.02542281920342735, samples=776,
                       seed=1680591309, margin="exact")  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # no veins: flat
        result = ls.reconstruct(ls.Leaf(FINDING_18_LEAF), params)
    assert np.isfinite(result.triangle_mesh.points).all()
    with pytest.raises(ls.LeafError, match="too large") as exc:
        result.metrics  # noqa: B018
    _one_line(exc.value)
