"""No cracks or slivers at a basal sinus (issue 21, finding 4 and What to build 5).

A heart-shaped blade whose veins all start at the notch on the boundary: a basal vein raised
beside the sinus's margin made the guide p rise faster than the taper lets z rise there, and
following it took a relief many times the veins' own across the lobe. Seen from above the lobes'
walls stood near vertical: triangles 10-29 grid cells long in 3D, though none was longer than
two cells in the plane. Now the fit asks no more of the mixture than 3 times the veins' relief
inside the taper (surface.RELIEF_CAP), and a vein correction that overshoots is refitted without
the margin band's points or dropped (correct.OVERSHOOT): a vein raised beside the margin stays
below its height there rather than lifting the whole lobe.
"""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

import leafstudio as ls
from leafstudio.core.evaluate import triangles_of

GRID = 128
LONGEST = 4  # grid cells: no triangle edge longer (finding 4 counted these in 3D)
STEEP = 5  # ... in 3D over random sinuses, where a bowed vein may run beside a lobe's margin
LIFT = 2.5  # ... nor a relief more than this many times the veins' own over random sinuses: the
# lifts this test was written for stood 2.8 times (0.139 under veins 0.05 high) and, before
# surface.RELIEF_CAP, 8 times; the mixture itself, at K 6 on three basal veins into the lobes and
# none along the blade, stands 1.9 times (the paper's surface) and 1.96 (ours), and on a single
# vein 0.0018 high, 1.93 times (Hypothesis 6.170.27's examples)


def heart(depth: float, half: float, n: int = 350, lobes: float = 0.0) -> tuple[np.ndarray, int]:
    """A clean (n, 2) counter-clockwise heart outline of length 1 (base at x = 0, apex at 1): an
    ovate blade less a V sinus whose notch is a boundary point at (depth, 0), its sides `half`
    degrees off the midrib's backward direction; `lobes` rounds the lobes out sideways.

    Returns the outline and the notch's index."""
    t = np.linspace(0, 2 * np.pi, 2000, endpoint=False)
    x = 0.5 - 0.5 * np.cos(t)
    y = 0.45 * np.sin(t) * (1 - 0.3 * x) * (0.6 + 0.4 * np.sqrt(np.abs(np.sin(t))))
    y *= 1 + lobes * np.exp(-(((x - 0.15) / 0.15) ** 2))
    back, side = 2 * np.cos(np.radians(half)), 2 * np.sin(np.radians(half))
    wedge = shapely.Polygon([(depth, 0), (depth - back, side), (depth - back, -side)])
    shape = shapely.Polygon(np.column_stack([x, y])).difference(wedge)
    if shape.geom_type != "Polygon":
        shape = max(shape.geoms, key=lambda part: part.area)
    ring = shapely.geometry.polygon.orient(shape, 1.0).exterior
    ring = np.array(ring.coords)[:-1]
    ring = np.roll(ring, -np.argmin(np.linalg.norm(ring - [depth, 0], axis=1)), axis=0)
    closed = np.vstack([ring, ring[:1]])
    along = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(closed, axis=0), axis=1))])
    s = np.linspace(0, along[-1], n, endpoint=False)  # s[0] = 0: the notch is point 0
    outline = np.column_stack([np.interp(s, along, closed[:, i]) for i in (0, 1)])
    low, length = outline[:, 0].min(), np.ptp(outline[:, 0])
    return (outline - [low, 0]) / length, 0


def vein_from(
    outline: np.ndarray, start: int, angle: float, bow: float, height: float, rise: float = 0.0
) -> np.ndarray:
    """(40, 3): a vein from boundary point `start` at `angle` degrees to 92% of the way to the
    margin, bowed sideways by `bow` of its length (halved until it stays inside the blade: a vein
    outside it is the input's error, not this test's subject), rising to `height` plus `rise`
    times its length in its middle (0 at the notch)."""
    origin = outline[start]
    direction = np.array([np.cos(np.radians(angle)), np.sin(np.radians(angle))])
    blade = shapely.Polygon(outline)
    reach = np.linspace(1e-4, 2, 20_000)
    inside = shapely.contains_xy(blade, *(origin + reach[:, None] * direction).T)
    first = int(np.argmax(inside))
    end = origin + 0.92 * reach[first + int(np.argmax(~inside[first:])) - 1] * direction
    t = np.linspace(0, 1, 40)[:, None]
    chord = end - origin
    across = np.array([-chord[1], chord[0]])
    for _ in range(12):
        xy = origin + t * chord + bow * np.sin(np.pi * t) * across
        if shapely.contains_xy(blade, *xy[1:].T).all():
            break
        bow /= 2
    top = height + rise * float(np.linalg.norm(chord))
    return np.column_stack([xy, top * np.sin(np.pi * t[:, 0])])


def longest_edges(result: ls.Result) -> tuple[float, float]:
    """The mesh's longest triangle edge in 3D and in the plane, in grid cells."""
    mesh = result.triangle_mesh
    corners = mesh.points[triangles_of(mesh)]
    sides = corners - np.roll(corners, 1, axis=1)
    cell = result.length / result.params.grid
    return (
        float(np.linalg.norm(sides, axis=2).max() / cell),
        float(np.linalg.norm(sides[..., :2], axis=2).max() / cell),
    )


@pytest.mark.parametrize("k", [3, 7])
def test_finding4_a_heart_with_veins_from_its_notch_has_no_cracks(k):
    """Finding 4 as described: a sinus a tenth of the length deep, a clean 350-point boundary,
    the midrib and basal veins at ±60° and ±125° all from the notch point, grid 128. Before: 33
    (K = 3) and 109 (K = 7) triangles had an edge over 4 grid cells, the longest 10.1 and 12.1
    cells, and the blade stood 0.086 and 0.139 high under veins 0.05 high."""
    outline, notch = heart(depth=0.1, half=50)
    veins = [vein_from(outline, notch, a, 0.0, 0.05) for a in (0, 60, -60, 125, -125)]
    boundary = np.column_stack([outline, np.zeros(len(outline))])
    result = ls.reconstruct(ls.Leaf(boundary, veins), ls.Params(grid=GRID, k=k))
    assert longest_edges(result)[0] <= LONGEST
    assert np.abs(result.triangle_mesh.points[:, 2]).max() <= 1.5 * 0.05
    # the basal veins at ±125° rise along the sinus's margin beside the midrib's start, where
    # T < 0.03 and the surface follows neither: not "veins 1 and 4 meet 2.3% ... apart"
    assert not result.warnings


@settings(
    max_examples=25,
    deadline=None,
    derandomize=True,  # the same examples in every run (at one Hypothesis version:
    # constraints-dev.txt names it); widen max_examples locally to search
    phases=[Phase.explicit, Phase.generate],  # no shrinking: each example is a grid-128 run
    suppress_health_check=[HealthCheck.too_slow],
)
@given(
    depth=st.floats(0.03, 0.2),
    half=st.floats(20, 55),
    lobes=st.floats(0.0, 0.4),
    fan=st.lists(st.floats(-1, 1), min_size=1, max_size=6, unique=True),
    bow=st.floats(-0.2, 0.2),
    rise=st.floats(0.02, 0.25),
    k=st.integers(2, 7),
)
def test_no_cracks_or_slivers_at_any_sinus(depth, half, lobes, fan, bow, rise, k):
    """Random sinus depths and openings, lobes and fans of veins from the notch on the boundary
    (each within the blade's opening there, bowed alike, rising by `rise` of its length): no
    triangle edge longer than 4 grid cells in 3D or in the plane, and no relief above LIFT times
    the veins' own."""
    outline, notch = heart(depth, half, lobes=lobes)
    opening = 180 - half - 8  # the veins keep 8° off the sinus's sides
    veins = [vein_from(outline, notch, f * opening, bow * np.sign(f), 0.0, rise) for f in fan]
    boundary = np.column_stack([outline, np.zeros(len(outline))])
    result = ls.reconstruct(ls.Leaf(boundary, veins), ls.Params(grid=GRID, k=k))
    in_3d, in_plane = longest_edges(result)
    assert in_plane <= LONGEST and in_3d <= STEEP
    relief = max(float(np.abs(v[:, 2]).max()) for v in veins)
    assert np.abs(result.triangle_mesh.points[:, 2]).max() <= LIFT * relief


def test_veins_crossing_at_different_heights_make_no_wall_and_are_named():
    """A midrib bowed across a basal vein from the same notch, 0.052 of the length apart in
    height where they cross (the property test's example at Hypothesis 6.170): the correction
    met both and stood a wall between them, a triangle edge 5.1 grid cells long in 3D. The later
    vein's points steeper than vein_centers.STEEPEST from the earlier's are left to it, and the
    result says so."""
    outline, notch = heart(depth=0.1687, half=31.44, lobes=0.0861)
    opening = 180 - 31.44 - 8
    fan = [(0.0, 0.2), (0.1813 * opening, -0.2), (0.8265 * opening, -0.2)]
    veins = [vein_from(outline, notch, angle, bow, 0.0, 0.1452) for angle, bow in fan]
    crossing = shapely.LineString(veins[0][:, :2]).intersection(
        shapely.LineString(veins[1][5:, :2])
    )
    assert crossing.geom_type == "Point"  # they cross away from the notch
    boundary = np.column_stack([outline, np.zeros(len(outline))])
    named = "veins 1 and 2 meet .* apart in height: the surface follows the earlier vein"
    with pytest.warns(UserWarning, match=named):
        result = ls.reconstruct(ls.Leaf(boundary, veins), ls.Params(grid=GRID, k=2))
    assert longest_edges(result)[0] <= STEEP - 2
    assert len(result.warnings) == 1
