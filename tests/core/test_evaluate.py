"""evaluate.py: measurements against leaves with known answers; edge_counts, compiled (edges
bucketed by their lower vertex, core/edges.py), gives what one sorted key per edge gives: the
same edges in the same order, the same counts, on grid meshes, fans (a hub vertex with thousands
of edges), repeated and degenerate triangles, and no triangles; and each triangle's side its
edge."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import shapely
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial.transform import Rotation

import leafstudio as ls
from leafstudio.cli import main
from leafstudio.core.curvature import CURVATURE_ARRAYS
from leafstudio.core.edges import edge_table
from leafstudio.core.evaluate import (
    FIELDS,
    NO_MIXTURE,
    count_border_loops,
    edge_counts,
    format_table,
    leaf_measurements,
    margin_length,
)
from tests.leaves import ellipse as _ellipse

A, B = 1.0, 0.4  # the ellipse leaf's semi-axes


def _moved(points: np.ndarray) -> np.ndarray:
    rotation = Rotation.from_euler("xyz", [30, -20, 50], degrees=True)
    return rotation.apply(points) + np.array([5.0, -3.0, 2.0])


@pytest.fixture(scope="module")
def flat():
    """An ellipse leaf without veins, tilted and moved in space: flat, of known size."""
    with pytest.warns(UserWarning, match="flat"):
        return ls.reconstruct(ls.Leaf(boundary=_moved(_ellipse())), ls.Params(grid=48))


@pytest.fixture(scope="module")
def ridged():
    """The ellipse with a raised midrib."""
    x = np.linspace(-0.8, 0.8, 60)
    vein = np.column_stack([x, np.zeros_like(x), 0.1 * (1 - x**2)])
    leaf = ls.Leaf(boundary=_ellipse(), veins=[vein])
    return ls.reconstruct(leaf, ls.Params(k=2, grid=48))


def test_flat_ellipse_has_the_ellipse_sizes(flat):
    m = leaf_measurements(flat)
    polygon_area = shapely.Polygon(_ellipse()[:, :2]).area  # π a b up to the outline's sampling
    assert m["projected_area"] == pytest.approx(polygon_area, rel=1e-9)
    assert m["area"] == pytest.approx(polygon_area, rel=1e-9)
    assert m["area"] == pytest.approx(np.pi * A * B, rel=1e-3)
    ramanujan = np.pi * (3 * (A + B) - np.sqrt((3 * A + B) * (A + 3 * B)))
    assert m["perimeter"] == pytest.approx(ramanujan, rel=1e-3)
    assert m["length"] == pytest.approx(2 * A, rel=1e-6)
    assert m["width"] == pytest.approx(2 * B, rel=1e-3)
    assert m["aspect_ratio"] == pytest.approx(A / B, rel=1e-3)
    assert m["height"] == pytest.approx(0, abs=1e-12)
    # no mixture is fitted on a flat blade: its placeholder Gaussian's K of 1 read as a K
    assert flat.chosen_k == 1 and flat.fitted_k is None and m["k"] is None
    assert "K (Gaussians)" in (table := format_table(m)) and NO_MIXTURE in table


def test_flat_leaf_has_zero_curvature(flat):
    m = leaf_measurements(flat)
    for name in CURVATURE_ARRAYS:
        assert np.all(flat.mesh[name] == 0)
        assert m["curvature"][name] == {"min": 0.0, "max": 0.0, "mean": 0.0}


def test_ridged_leaf_area_is_the_integral_of_its_slope(ridged):
    m = leaf_measurements(ridged)
    assert m["projected_area"] == pytest.approx(np.pi * A * B, rel=2e-3)
    # ∫∫ √(1 + |∇z|²) over the leaf: the midpoint rule with the closed-form gradient
    h = 0.0025
    xs, ys = np.meshgrid(np.arange(-A, A, h) + h / 2, np.arange(-B, B, h) + h / 2)
    xy = np.column_stack([xs.ravel(), ys.ravel()])
    inside = (xy[:, 0] / A) ** 2 + (xy[:, 1] / B) ** 2 < 1
    slope = np.sum(ridged.surface.gradient(xy[inside]) ** 2, axis=1)
    integral = np.sqrt(1 + slope).sum() * h**2
    assert m["area"] > m["projected_area"] * 1.01
    assert m["area"] == pytest.approx(integral, rel=5e-3)
    assert m["height"] == pytest.approx(0.1, rel=0.1)
    assert m["veins"]["max"] < 0.01
    assert m["curvature"]["mean_curvature"]["min"] < 0  # the midrib is a ridge


def test_table_lists_every_measurement(ridged):
    table = format_table(leaf_measurements(ridged))
    for _, label in FIELDS:
        assert label in table
    assert "distance veins -> mesh" in table
    assert len(table.splitlines()) == len(FIELDS) + 1 + len(CURVATURE_ARRAYS) + 2


def test_cli_measure_prints_a_table_and_json(tmp_path, capsys):
    ls.save_leaf(ls.demo("parallel"), tmp_path / "p.leaf.json")
    argv = ["measure", str(tmp_path / "p.leaf.json"), "--k", "2", "--grid", "32"]
    assert main(argv) == 0
    table = capsys.readouterr().out
    assert "surface area (3D)" in table and "greatest width" in table
    assert main([*argv, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["k"] == 2
    assert data["length"] == pytest.approx(1.0, rel=2e-2)  # the demos are 1 long (main axis)
    assert data["area"] > data["projected_area"]


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["measure", "missing.csv"], "missing.csv: no such file"),
        (["measure", "LEAF", "--k", "0"], "K must be between 1 and"),
        (["measure", "LEAF", "--grid", "100000"], "grid must be between"),
        (["measure", "LEAF", "--k", "3.5"], "K must be a whole number or 'auto'"),
        (["measure", "LEAF", "--grid", "many"], "argument --grid: grid must be a whole number"),
        (["measure"], "the following arguments are required: input"),
    ],
)
def test_cli_measure_bad_input_is_one_line(tmp_path, capsys, argv, message):
    ls.save_leaf(ls.demo("nested"), tmp_path / "n.leaf.json")
    argv = [str(tmp_path / "n.leaf.json") if a == "LEAF" else a for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err
    assert len(err.strip().splitlines()) == 1


def test_result_metrics_carry_the_measurements(ridged):
    metrics = ridged.metrics
    assert set(metrics["leaf"]) == {key for key, _ in FIELDS} | {"k"}
    assert set(metrics["curvature"]) == set(CURVATURE_ARRAYS)
    assert metrics["leaf"]["k"] == ridged.chosen_k == 2
    json.dumps(metrics)  # plain numbers only: the CLI writes them with --metrics


# --- edge_counts ---------------------------------------------------------------------------------


def by_sorted_keys(triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The formulation edge_counts replaced: np.unique over one integer key per edge."""
    edges = np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1).astype(np.int64)
    base = int(edges.max(initial=0)) + 1
    keys, counts = np.unique(edges[:, 0] * base + edges[:, 1], return_counts=True)
    return np.column_stack([keys // base, keys % base]).reshape(-1, 2), counts


def grid_mesh(n: int) -> np.ndarray:
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1), indexing="ij")
    a = (i * n + j).ravel()
    return np.vstack(
        [np.column_stack([a, a + 1, a + n]), np.column_stack([a + 1, a + n + 1, a + n])]
    )


def fan(n: int) -> np.ndarray:
    return np.column_stack([np.zeros(n - 2, int), np.arange(1, n - 1), np.arange(2, n)])


rng = np.random.default_rng(7)
MESHES = {
    "grid": grid_mesh(40),
    "shuffled grid": rng.permutation(grid_mesh(30)),
    "fan": fan(640),  # a hub vertex: Shell's sort, not a quadratic one
    "reversed fan": fan(96)[::-1, ::-1],
    "random with repeats": rng.integers(0, 60, (500, 3)),
    "one triangle three times": np.array([[0, 1, 2], [2, 1, 0], [0, 1, 2]]),
    "none": np.empty((0, 3), np.int64),
}


@pytest.mark.parametrize("name", MESHES)
def test_edge_counts_match_the_sorted_keys(name):
    triangles = MESHES[name]
    edges, counts = edge_counts(triangles)
    want_edges, want_counts = by_sorted_keys(triangles)
    np.testing.assert_array_equal(edges, want_edges)
    np.testing.assert_array_equal(counts, want_counts)
    assert edges.dtype == np.int64 and edges.shape == (len(counts), 2)


@pytest.mark.parametrize("name", MESHES)
def test_each_side_of_a_triangle_names_the_edge_of_its_corners(name):
    """edges.edge_table's sides (what bent_mesh.sag_splits halves by): side k of triangle t is
    the edge between its corners k and k + 1, and the edges are edge_counts' own."""
    triangles = MESHES[name]
    edges, counts, sides = edge_table(triangles)
    assert np.array_equal(edges, edge_counts(triangles)[0])
    corners = np.stack([triangles, np.roll(triangles, -1, axis=1)], axis=-1).reshape(-1, 2)
    np.testing.assert_array_equal(edges[sides], np.sort(corners, axis=1))
    assert np.array_equal(np.bincount(sides, minlength=len(edges)), counts)


def test_a_grid_mesh_has_one_boundary_loop_from_given_counts():
    triangles = grid_mesh(12)
    counted = edge_counts(triangles)
    assert count_border_loops(triangles, counted) == count_border_loops(triangles) == 1


def test_the_margin_is_each_pieces_outer_loop_in_any_vertex_order():
    """margin_length: a 6 x 6 square with a 2 x 2 hole (24 round, 8 round the hole) and a
    2 x 2 square apart (8), their vertices shuffled: the outer loops' 32, the hole's not
    counted; the same mesh stood up in 3D (the length is the points', the pieces told apart
    on the flat ones)."""
    big, small = grid_mesh(7), grid_mesh(3) + 49
    corner = big.min(axis=1)  # each cell's two triangles share their lowest corner's index
    row, col = corner // 7, corner % 7
    big = big[~((row >= 2) & (row < 4) & (col >= 2) & (col < 4))]
    i, j = np.divmod(np.arange(49), 7)
    k, m = np.divmod(np.arange(9), 3)
    flat = np.vstack([np.column_stack([i, j]), np.column_stack([k + 10.0, m])]).astype(float)
    order = np.random.default_rng(3).permutation(len(flat))
    back = np.argsort(order)
    triangles, xy = back[np.vstack([big, small])], flat[order]
    points = np.column_stack([xy, np.zeros(len(xy))])
    assert margin_length(points, triangles, xy) == pytest.approx(32.0, rel=1e-12)
    stood = np.column_stack([xy[:, 0], np.zeros(len(xy)), xy[:, 1]])  # turned, lengths kept
    assert margin_length(stood, triangles, xy) == pytest.approx(32.0, rel=1e-12)
    assert margin_length(points, np.empty((0, 3), np.int64), xy) == 0.0


def test_a_blade_trimmed_by_its_bend_measures_its_trimmed_margin():
    """A scan's holes are cut out of the bent mesh (sheet_bend.Scaled.trim), which renumbers
    its vertices: the perimeter was the ring through the first len(polygon) of them, no longer
    the outline (sugar beet pot1_7: 215.2 mm, its one margin 195.6; here 2.958 for 2.098). A
    hole torn into the margin is part of it; one inside the blade is not."""
    from tests.core.test_outline_points import notched_blade

    leaf, blade = notched_blade()
    result = ls.reconstruct(leaf, ls.Params(k=2, grid=64))
    assert result.metrics["mesh"]["boundary_loops"] == 2  # the margin, notched, and the hole
    # rolled about the blade's length, which keeps lengths: the flat blade's (2.0979; 2.0938
    # since the sheet's cubes are cut in the points' own frame, plane.grid_frame: its unrolling
    # is isometric to 0.2%, the ring crossing the blade was 41% long)
    assert result.metrics["leaf"]["perimeter"] == pytest.approx(blade.exterior.length, rel=3e-3)


@pytest.mark.parametrize(("pose", "longer"), [({"fold": 60.0}, 0.060), ({"twist": 1.0}, 0.171)])
def test_a_posed_leafs_perimeter_is_its_bent_margins_length(pose, longer):
    """The perimeter of a posed leaf is its bent margin's 3D length, which the pose changes
    (README, Real size: the pose bends the blade about its relief; review appreview31, finding
    5), while its length and width are the flat blade's."""
    from leafstudio.forms import Form

    flat = ls.reconstruct(Form("ovate").leaf(), ls.Params(k=3, grid=48)).metrics["leaf"]
    leaf = Form("ovate", **pose).leaf()
    posed = ls.reconstruct(leaf, ls.Params(k=3, grid=48)).metrics["leaf"]
    margin = np.linalg.norm(leaf.boundary - np.roll(leaf.boundary, 1, axis=0), axis=1).sum()
    assert posed["perimeter"] == pytest.approx(margin, rel=1e-4)
    assert posed["perimeter"] / flat["perimeter"] - 1 == pytest.approx(longer, abs=2e-3)
    assert (posed["length"], posed["width"]) == pytest.approx((flat["length"], flat["width"]))


REAL = Path(__file__).resolve().parents[3] / "shared" / "realleaves"


@pytest.mark.skipif(not REAL.is_dir(), reason="needs ../shared/realleaves")
def test_a_scan_with_a_hole_torn_into_its_margin_measures_that_margin():
    """Sugar beet pot1_7: the perimeter is the length of its mesh's outer boundary loop (it was
    215.2 mm: a ring crossing the blade), not of a hole's. Its gap beside the curled-under tip
    was a tear into the margin (one loop, 195.6 mm); cut in the scan's own frame (plane.
    grid_frame) the strips of blade beyond it are kept and close it into a hole (loops of 170.3
    and 55.0 mm): either way the margin, and only it, is measured."""
    from leafstudio import workflows

    path = next(REAL.glob("sugarbeet_*_pot1_7.txt"))
    result = workflows.reconstruct(workflows.open_scan(path), ls.Params(grid=96)).result
    mesh = result.triangle_mesh
    edges, counts = edge_counts(np.asarray(mesh.regular_faces))
    border = edges[counts == 1]
    points = np.asarray(mesh.points)
    _, loop_of = connected_components(
        coo_matrix((np.ones(len(border)), (border[:, 0], border[:, 1])), (len(points),) * 2)
    )
    sides = np.linalg.norm(points[border[:, 0]] - points[border[:, 1]], axis=1)
    loops = np.bincount(loop_of[border[:, 0]], weights=sides)
    outer = loops.max()
    assert result.metrics["leaf"]["perimeter"] == pytest.approx(outer, rel=1e-9)
    assert 160 < outer < 200


@pytest.mark.parametrize(
    ("shape", "length", "width"),
    [("reniform", 1.0, 1 / 0.72), ("cordate", 1.0, 1 / 1.4), ("orbicular", 1.0, 1.0),
     ("ovate", 1.0, 1 / 1.6)],
)  # fmt: skip
def test_a_leaf_is_measured_base_to_apex_along_its_midrib_and_across_it(shape, length, width):
    """A reniform leaf is wider than long (its definition) and a cordate leaf's lobes reaching
    back past the base are not part of its length: the length runs along the midrib, from the
    base to the apex, as `--length` sets it (the boundary's main axis made a kidney's width its
    length, aspect 1.21 instead of 0.72). Forms are 1 long, base to apex."""
    from leafstudio.assets.placement import result_placement
    from leafstudio.forms import make_form

    for pose in ({}, {"fold": 50.0}, {"curl": 0.5}):  # a bent leaf: its flat blade's
        result = ls.reconstruct(make_form(shape, **pose), ls.Params(grid=48))
        measured = result.metrics["leaf"]
        assert measured["length"] == pytest.approx(length, rel=2e-3), pose
        assert measured["width"] == pytest.approx(width, rel=1e-2), pose
        assert measured["aspect_ratio"] == pytest.approx(length / width, rel=1e-2), pose
        assert result_placement(result).length == pytest.approx(measured["length"], rel=1e-9)


def test_a_midrib_given_shuffled_is_measured_as_in_order():
    """The pipeline takes a vein's points in any order (prepare/vein_order.py: a scanner's dense,
    unordered vein); the length's direction was the chord from the midrib's first given point to
    its last, two random points of a shuffled one: a soybean scan's leaf measured 53.3 for 65.5
    (and `--length` scaled it by that). The midrib is put in order first, as the stages do."""
    from leafstudio.assets.placement import result_placement
    from leafstudio.forms import make_form

    form = make_form("elliptic")
    x = np.linspace(0.03, 0.97, 60)
    bow = 0.06 * np.sin(np.pi * (x - 0.03) / 0.94)  # on the axis at both ends
    midrib = np.column_stack([x, bow, np.zeros_like(x)])
    rng = np.random.default_rng(3)
    for veins in ([midrib], [midrib[rng.permutation(len(x))]], [midrib[rng.permutation(len(x))]]):
        result = ls.reconstruct(ls.Leaf(form.boundary, veins), ls.Params(k=3, grid=32))
        measured = result.metrics["leaf"]
        assert measured["length"] == pytest.approx(1.0, rel=1e-3)
        assert measured["width"] == pytest.approx(0.5, rel=1e-3)
        assert result.blade_length == result_placement(result).length == measured["length"]


def test_the_view_frame_runs_along_the_midrib_base_to_apex():
    """An obovate leaf's plane has u toward its base (its outline's farther extreme); the frame
    it is shown on is turned half a turn, u from base to apex as the placement has it."""
    from leafstudio.assets.placement import result_placement
    from leafstudio.core.evaluate import view_frame

    result = ls.reconstruct(ls.forms.make_form("obovate"), ls.Params(grid=32))
    assert result.frame.u[0] < -0.99  # the plane's u: toward the base, -x
    frame = view_frame(result)
    np.testing.assert_allclose(frame.u, [1, 0, 0], atol=1e-9)  # base (origin) to apex (+x)
    assert frame.u @ result_placement(result).axes[0] > 0.99  # the exports' along
    np.testing.assert_allclose(frame.normal, result.frame.normal)


@pytest.mark.parametrize(
    ("shape", "venation"), [("ovate", "pinnate"), ("obovate", "arcuate"), ("cordate", "pinnate")]
)
def test_a_midrib_written_apex_first_is_taken_base_to_apex(shape, venation):
    """A midrib (vein 1) written from the apex to the base put the exported glTF's apex at the
    origin, and measured and showed the leaf from its apex. Side veins leave the midrib toward
    the apex: when they clearly lean toward its first point, its last is the base (said as a
    warning), and the length, the export's placement and the view are the base-first leaf's."""
    from leafstudio.assets.placement import result_placement
    from leafstudio.core.evaluate import view_frame
    from leafstudio.core.prepare.plausibility import leaf_warnings
    from leafstudio.forms import make_form

    leaf = make_form(shape, venation=venation)
    backward = ls.Leaf(leaf.boundary, [leaf.veins[0][::-1], *leaf.veins[1:]])
    assert not any("apex to the base" in w for w in leaf_warnings(leaf))
    assert any("vein 1, the midrib, seems written from the apex" in w
               for w in leaf_warnings(backward))  # fmt: skip
    params = ls.Params(k=3, grid=48)
    want, got = ls.reconstruct(leaf, params), ls.reconstruct(backward, params)
    a, b = result_placement(want), result_placement(got)
    np.testing.assert_allclose(b.base, a.base, atol=1e-9)  # the base at the glTF's origin
    np.testing.assert_allclose(b.axes, a.axes, atol=1e-9)  # the apex on +X
    assert got.blade_length == pytest.approx(want.blade_length, rel=1e-9)
    assert got.metrics["leaf"]["length"] == pytest.approx(1.0, rel=2e-3)
    np.testing.assert_allclose(view_frame(got).u, view_frame(want).u, atol=1e-9)


def test_parallel_veins_claim_no_end_of_the_midrib():
    """Veins beside the midrib (parallel venation) say nothing of its ends: a midrib written
    either way is taken as written, without a warning."""
    from leafstudio.core.prepare.plausibility import leaf_warnings
    from leafstudio.forms import make_form

    leaf = make_form("sagittate", venation="parallel")
    backward = ls.Leaf(leaf.boundary, [leaf.veins[0][::-1], *leaf.veins[1:]])
    assert not any("apex to the base" in w for w in leaf_warnings(leaf) + leaf_warnings(backward))


def test_the_apps_bending_frame_starts_at_the_base_of_a_midrib_written_apex_first():
    """The app bends a leaf about placed.blade_frame, whose origin was vein 1's first point: a
    midrib written apex first was folded and curled from its apex while the length, the export
    and the view took it base first; the frame is now the base-first leaf's."""
    from leafstudio.core.placed import blade_frame
    from leafstudio.forms import make_form

    leaf = make_form("ovate", venation="pinnate")
    backward = ls.Leaf(leaf.boundary, [leaf.veins[0][::-1], *leaf.veins[1:]])
    want, got = blade_frame(leaf), blade_frame(backward)
    np.testing.assert_allclose(got.origin, want.origin, atol=1e-9)
    np.testing.assert_allclose(got.u, want.u, atol=1e-9)


@pytest.mark.parametrize("mirror", [1.0, -1.0], ids=["base_left", "base_right"])
def test_a_dense_noisy_midribs_end_is_told_from_its_written_first_point(mirror):
    """A dense, noisy midrib (a scan's labelled points) is put in a canonical order along its
    axis before its side veins are read (vein_order), whose start is the base or the apex by the
    axis' sign alone: a midrib written base first was turned round (and said to be written apex
    first) when that order ran from the apex. Which end is its first is now the written one's."""
    from leafstudio.core.prepare.vein_order import midrib_turned
    from leafstudio.forms import make_form

    leaf = make_form("ovate", venation="pinnate")
    t = np.linspace(0, 1, 2000)
    m = leaf.veins[0]
    dense = np.column_stack([np.interp(t, np.linspace(0, 1, len(m)), m[:, i]) for i in range(3)])
    dense[:, 1] += np.random.default_rng(0).normal(0, 0.005, len(t))
    scale = np.array([mirror, 1.0, 1.0])
    side = [v * scale for v in leaf.veins[1:]]
    assert not midrib_turned([dense * scale, *side])
    assert midrib_turned([dense[::-1] * scale, *side])
