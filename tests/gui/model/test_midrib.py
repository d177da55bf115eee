"""Mirror editing follows a curved midrib (issue 12): reflection across the midrib's curve, in
the sketch model (no Qt)."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import shapely

from leafstudio.core.prepare.polygon import ring_crossings
from leafstudio.gui.model.midrib import Midrib
from leafstudio.gui.model.sketch_model import Sketch


def arc_midrib(points: int = 5) -> np.ndarray:
    """Control points (x, y, height) on a quarter circle of radius 1 about (0.5, -0.8)."""
    angle = np.linspace(0.75 * np.pi, 0.25 * np.pi, points)
    return np.column_stack([0.5 + np.cos(angle), -0.8 + np.sin(angle), np.full(points, 0.05)])


def band_points(sketch: Sketch, count: int = 60, seed: int = 0) -> np.ndarray:
    """Plane points near the midrib's curve, on both sides and past its ends."""
    rng = np.random.default_rng(seed)
    angle = rng.uniform(0.2 * np.pi, 0.8 * np.pi, count)
    radius = rng.uniform(0.75, 1.25, count)
    return np.column_stack([0.5 + radius * np.cos(angle), -0.8 + radius * np.sin(angle)])


def distance_to(curve: np.ndarray, points: np.ndarray) -> np.ndarray:
    return shapely.distance(shapely.points(points), shapely.LineString(curve[:, :2]))


def test_a_point_mirrored_across_a_curved_midrib_is_as_far_on_the_other_side():
    sketch = Sketch(veins=(arc_midrib(),))
    midrib = sketch.midrib()
    points = band_points(sketch)
    mirrored = midrib.reflect(points)
    curve = sketch.vein_curve(0)
    inside = (points[:, 0] > curve[0, 0]) & (points[:, 0] < curve[-1, 0])  # beside the curve
    np.testing.assert_allclose(
        distance_to(curve, mirrored[inside]), distance_to(curve, points[inside]), atol=1e-4
    )
    np.testing.assert_allclose(midrib.offset(mirrored), -midrib.offset(points), atol=1e-12)
    assert np.all(np.sign(midrib.offset(mirrored)) == -np.sign(midrib.offset(points)))
    # outside the circle maps inside it: the reflection follows the bend, not a straight line
    from_centre = lambda p: np.hypot(p[:, 0] - 0.5, p[:, 1] + 0.8)  # noqa: E731
    outer = from_centre(points) > 1.05
    assert np.all(from_centre(mirrored[outer]) < 0.97)


def test_mirroring_twice_gives_the_point_back():
    sketch = Sketch(veins=(arc_midrib(),))
    points = band_points(sketch, seed=1)
    heights = np.column_stack([points, np.linspace(0, 0.1, len(points))])
    twice = sketch.midrib().reflect(sketch.midrib().reflect(heights))
    np.testing.assert_allclose(twice, heights, atol=1e-12)


def test_a_straight_midrib_reflects_as_the_line_through_its_ends_did():
    """The old rule (reflection about the line through the midrib's first and last points)
    is what a straight midrib gives, also past its ends and with points between them."""
    ends = np.array([[0.1, 0.05], [0.9, 0.35]])
    between = ends[0] + np.outer([0.0, 0.3, 0.55, 1.0], ends[1] - ends[0])
    midrib = Midrib(Sketch(veins=(np.column_stack([between, np.zeros(4)]),)).vein_curve(0))
    points = np.random.default_rng(2).uniform(-1.0, 2.0, (80, 2))
    near_ends = np.vstack([ends + s * (ends[1] - ends[0]) for s in (-1e-8, 1e-8)])
    points = np.vstack([points, near_ends + [[0.0, 1e-4]]])  # a hair past a joint
    axis = (ends[1] - ends[0]) / np.linalg.norm(ends[1] - ends[0])
    normal = np.array([-axis[1], axis[0]])
    offset = (points - ends[0]) @ normal
    np.testing.assert_allclose(midrib.offset(points), offset, atol=1e-12)
    np.testing.assert_allclose(
        midrib.reflect(points), points - 2 * offset[:, None] * normal, atol=1e-12
    )


def lopsided_leaf(bend: float) -> Sketch:
    """A leaf along a midrib bent by `bend` (0: straight), wider on its left, with one left
    side vein; its boundary follows the midrib's bend."""
    t = np.linspace(0, 2 * np.pi, 14, endpoint=False)
    x = 0.5 + 0.5 * np.cos(t)
    width = 0.2 * np.sin(t) * (1 + 0.5 * np.sin(t))
    sag = bend * (x - 0.5) ** 2
    boundary = np.column_stack([x, width + sag])
    mx = np.linspace(0.0, 1.0, 5)
    midrib = np.column_stack([mx, bend * (mx - 0.5) ** 2, np.full(5, 0.04)])
    sx = np.array([0.4, 0.5, 0.6])
    side = np.column_stack([sx, bend * (sx - 0.5) ** 2 + [0.0, 0.08, 0.14], [0.04, 0.03, 0.02]])
    return Sketch(boundary=boundary, veins=(midrib, side))


def test_a_bent_leaf_is_mirrored_across_its_midrib_curve():
    sketch = lopsided_leaf(bend=1.2)
    mirrored = sketch.mirrored(+1.0)  # the left (wider) half is kept
    midrib = mirrored.midrib()
    offsets = midrib.offset(mirrored.boundary)
    left, right = offsets[offsets > 1e-9], offsets[offsets < -1e-9]
    np.testing.assert_allclose(np.sort(left), np.sort(-right), atol=1e-12)
    assert len(ring_crossings(mirrored.boundary_curve())) == 0
    assert len(mirrored.veins) == 3  # the side vein gained its mirror image
    np.testing.assert_allclose(
        midrib.offset(mirrored.veins[2]), -midrib.offset(sketch.veins[1]), atol=1e-12
    )
    np.testing.assert_allclose(mirrored.veins[2][:, 2], sketch.veins[1][:, 2])
    # the old straight-line rule would have put the mirror vein below the chord y = 0.3 * 1.2
    # ... instead it hugs the bent midrib: as far from its curve as the original is
    curve = sketch.vein_curve(0)
    np.testing.assert_allclose(
        distance_to(curve, mirrored.veins[2]), distance_to(curve, sketch.veins[1]), atol=2e-3
    )
    assert mirrored.mirrored(+1.0).veins[2].shape == mirrored.veins[2].shape  # replaced, not added


def test_a_straight_leaf_is_mirrored_as_before():
    sketch = lopsided_leaf(bend=0.0)
    mirrored = sketch.mirrored(+1.0)
    upper = mirrored.boundary[mirrored.boundary[:, 1] > 1e-9]
    lower = mirrored.boundary[mirrored.boundary[:, 1] < -1e-9]
    np.testing.assert_allclose(upper[::-1] * [1, -1], lower, atol=1e-12)
    np.testing.assert_allclose(
        mirrored.veins[2][:, :2], sketch.veins[1][:, :2] * [1, -1], atol=1e-12
    )


def test_the_midrib_and_profile_models_import_no_qt():
    code = (
        "import sys, leafstudio.gui.model.midrib, leafstudio.gui.model.vein_profile, "
        "leafstudio.gui.model.sketch_model; "
        "print(any(m.startswith(('PySide6', 'PyQt', 'vtk')) for m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
