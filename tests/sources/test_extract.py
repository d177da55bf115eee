"""From a scan to boundary and veins: reading scans, cleaning, dropping the petiole, the outline."""

from __future__ import annotations

import sys

import numpy as np
import pytest
import shapely

from leafstudio.cli import main
from leafstudio.errors import LeafError
from leafstudio.sources.extract import extract_leaf, lift
from leafstudio.sources.files import load_leaf
from leafstudio.sources.scan import read_scan, read_scan_returns
from tests.leaves import (
    assert_outline_is_the_blades,
    scan_blade_outline,
    scan_surface,
    synthetic_scan,
)


@pytest.fixture(scope="module")
def scan():
    parts = synthetic_scan()
    points = np.vstack([parts["blade"], parts["petiole"], parts["outliers"]])
    return parts, points, extract_leaf(points)


def test_the_outline_of_a_scan_with_outliers_and_a_petiole_is_the_blade(scan):
    parts, _, found = scan
    assert_outline_is_the_blades(found)
    n_blade, n_petiole = len(parts["blade"]), len(parts["petiole"])
    assert not found.blade[n_blade + n_petiole :].any()  # no outlier is kept
    far_petiole = parts["petiole"][:, 0] < -0.56
    assert not found.blade[n_blade : n_blade + n_petiole][far_petiole].any()
    assert found.blade[:n_blade].mean() > 0.99


def test_the_boundary_is_lifted_to_the_scans_heights_and_evenly_spaced(scan):
    _, _, found = scan
    b = found.leaf.boundary
    assert len(b) == 200
    assert np.abs(b[:, 2] - scan_surface(b[:, 0], b[:, 1])).max() < 4e-3
    steps = np.linalg.norm(np.diff(np.vstack([b, b[:1]])[:, :2], axis=0), axis=1)
    assert steps.max() < 1.3 * np.median(steps)


def test_the_midrib_runs_from_the_petiole_to_the_tip_on_the_surface(scan):
    _, _, found = scan
    midrib = found.leaf.veins[0]
    assert midrib[0, 0] < -0.45 and midrib[-1, 0] > 0.45
    assert np.abs(midrib[:, 1]).max() < 0.03
    assert np.abs(midrib[:, 2] - scan_surface(midrib[:, 0], midrib[:, 1])).max() < 2e-3
    assert len(found.leaf.veins) >= 5  # side veins too
    region = shapely.Polygon(found.leaf.boundary[:, :2])
    for vein in found.leaf.veins:
        assert shapely.contains_xy(region, vein[:, 0], vein[:, 1]).all()


def test_the_base_end_can_be_given():
    parts = synthetic_scan(seed=1)
    points = np.vstack([parts["blade"], parts["outliers"]])
    midrib = extract_leaf(points, base_end="+x").leaf.veins[0]
    assert midrib[0, 0] > 0.45 and midrib[-1, 0] < -0.45
    midrib = extract_leaf(points, base_end="auto").leaf.veins[0]  # no petiole: the wider end
    assert midrib[0, 0] < -0.45
    with pytest.raises(LeafError, match="base end"):
        extract_leaf(points, base_end="up")


def test_lift_fits_a_plane_through_the_neighbours():
    rng = np.random.default_rng(2)
    xy = rng.uniform(-1, 1, size=(500, 2))
    h = 0.3 * xy[:, 0] - 0.1 * xy[:, 1] + 2
    at = np.array([[1.05, 0.0], [0.0, 0.0]])  # one just outside the points
    assert np.allclose(lift(at, xy, h), 0.3 * at[:, 0] - 0.1 * at[:, 1] + 2, atol=1e-4)


def test_bad_scans_are_refused():
    with pytest.raises(LeafError, match="too few"):
        extract_leaf(np.random.default_rng(0).normal(size=(20, 3)))
    line = np.column_stack([np.linspace(0, 1, 200), np.zeros(200), np.zeros(200)])
    with pytest.raises(LeafError):
        extract_leaf(line)


def test_scans_are_read_with_extra_columns_and_headers(tmp_path):
    points = np.random.default_rng(3).normal(size=(60, 3))
    txt = tmp_path / "scan.txt"
    rows = [",".join(f"{v:.9g}" for v in (*p, 0.1, 0.2, 0.9, 1, 2, 3, 4)) for p in points]
    txt.write_text("x,y,z,nx,ny,nz,r,g,b,a\n" + "\n".join(rows) + "\n")
    assert np.allclose(read_scan(txt), points)
    from plyfile import PlyData, PlyElement

    data = np.empty(len(points), dtype=[("x", "f8"), ("y", "f8"), ("z", "f8"), ("red", "u1")])
    data["x"], data["y"], data["z"], data["red"] = *points.T, 7
    PlyData([PlyElement.describe(data, "vertex")]).write(str(tmp_path / "scan.ply"))
    assert np.allclose(read_scan(tmp_path / "scan.ply"), points)


def test_a_scan_with_nan_points_says_how_many_and_the_first(tmp_path):
    """qa37: a 2,266-point scan with one NaN point was refused as "NaN or infinite
    coordinates", naming neither how many nor which (a leaf file names its line): a
    researcher had to search the file for it."""
    points = np.random.default_rng(3).normal(size=(100, 3))
    points[[5, 40], 1] = np.nan, np.inf
    txt = tmp_path / "scan.txt"
    np.savetxt(txt, points, delimiter=",")
    with pytest.raises(LeafError, match=r"NaN or infinite coordinates at 2 of 100 points "
                       r"\(the first is point 6\)"):  # fmt: skip
        read_scan(txt)


def _with_missed_returns(points: np.ndarray, every: int = 25) -> np.ndarray:
    """`points` with a row of NaN before every `every`-th: an organised cloud's pixels without a
    return, as PCL and Open3D write them."""
    missed = np.full((len(points) // every, 3), np.nan)
    where = np.minimum(np.arange(len(missed)) * every + 3, len(points))
    return np.insert(points, where, missed, axis=0)


def test_a_scan_with_missed_returns_opens_without_them_and_says_so(tmp_path, scan):
    """qa37: a scan with one NaN point was refused whole ("NaN or infinite coordinates"); a
    scanner's organised cloud writes every pixel without a return so. Opened, the NaN rows are
    left out, the note says how many and the first, and the leaf is the one without them; too
    few finite points left are still refused."""
    from leafstudio.workflows import open_scan, reconstruct

    _, points, found = scan
    txt = tmp_path / "scan.xyz"
    np.savetxt(txt, _with_missed_returns(points))
    opened = open_scan(txt)
    assert opened.notes[0].startswith(f"left out {len(points) // 25} of its ")
    assert "the first is point 4)" in opened.notes[0]
    np.testing.assert_allclose(opened.leaf.boundary, found.leaf.boundary, atol=1e-9)
    assert opened.notes[0] in reconstruct(opened, {"grid": 48}).warnings
    few = tmp_path / "few.xyz"
    np.savetxt(few, _with_missed_returns(points[:40], every=2))
    with pytest.raises(LeafError, match=r"NaN or infinite coordinates are left out: 40 of 60 "):
        open_scan(few)


def _pcd(path, points: np.ndarray) -> None:
    header = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
    header += f"WIDTH {len(points)}\nHEIGHT 1\nPOINTS {len(points)}\nDATA ascii\n"
    path.write_text(header + "\n".join(" ".join(f"{v:.6f}" for v in p) for p in points))


@pytest.mark.open3d
def test_pcd_scans_are_read(tmp_path):
    points = np.random.default_rng(3).normal(size=(60, 3))
    _pcd(tmp_path / "scan.pcd", points)
    assert np.allclose(read_scan(tmp_path / "scan.pcd"), points, atol=1e-5)


def test_a_pcd_scan_without_open3d_says_which_extra_reads_it(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "open3d", None)  # import open3d fails, as when missing
    _pcd(tmp_path / "scan.pcd", np.random.default_rng(3).normal(size=(60, 3)))
    with pytest.raises(LeafError, match=r"reading \.pcd scans needs open3d.*leafstudio\[open3d\]"):
        read_scan(tmp_path / "scan.pcd")


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        ("empty.xyz", "", "holds no points"),
        ("few.csv", "1,2,3\n4,5,6\n", "too few points"),
        ("words.txt", "1 2 3\nfour five six\n", "not a number"),
        ("short.txt", "1 2\n", "needs x, y and z"),
        ("bad.ply", "not a ply", "not a readable PLY"),
        ("bad.pcd", "garbage", "not a readable PCD"),
        ("scan.obj", "v 1 2 3", "too few points"),
        ("scan.stl", "garbage", "not a readable mesh"),
        ("scan.dxf", "garbage", "unknown scan type"),
        ("nan.xyz", "\n".join(["nan 1 2"] * 60), "NaN"),
    ],
)
def test_a_bad_scan_is_one_line_and_exit_2(tmp_path, capsys, name, content, message):
    path = tmp_path / name
    path.write_text(content)
    assert main(["extract", str(path), "-o", str(tmp_path / "leaf.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err and name in err


def _scanners_mesh(path):
    """A Delaunay mesh of the synthetic scan's blade with a few large triangles along its
    middle, written to `path` (by its suffix); its points and faces."""
    import trimesh
    from scipy.spatial import Delaunay

    blade = synthetic_scan(seed=2)["blade"]
    coarse = blade[np.abs(blade[:, 1]) > 0.05]
    faces = Delaunay(coarse[:, :2]).simplices
    centres = coarse[faces].mean(axis=1)
    outline = shapely.Polygon(scan_blade_outline(np.linspace(0, 2 * np.pi, 400, endpoint=False)))
    faces = faces[shapely.contains_xy(outline.buffer(0.01), centres[:, 0], centres[:, 1])]
    trimesh.Trimesh(coarse, faces, process=False).export(path)
    return coarse, faces


@pytest.mark.parametrize("suffix", [".stl", ".obj", ".off"])
def test_a_scanners_mesh_is_read_as_points_spread_over_its_surface(tmp_path, suffix):
    """Scanners and photogrammetry write meshes, of triangles of uneven size: read as points
    spread evenly over the surface, as a scanner's cloud is. They were refused ("unknown scan
    type")."""
    coarse, faces = _scanners_mesh(tmp_path / f"scan{suffix}")
    points = read_scan(tmp_path / f"scan{suffix}")
    assert len(points) >= 20_000
    heights = scan_surface(points[:, 0], points[:, 1])
    assert np.abs(points[:, 2] - heights).max() < 0.01  # on the blade (its flat triangles)
    meshed = shapely.union_all(shapely.polygons(coarse[faces][:, :, :2]))  # the mesh's outline
    band = meshed.intersection(shapely.box(-1, -0.04, 1, 0.04)).area / meshed.area
    middle = np.abs(points[:, 1]) < 0.04  # the large triangles' middle as dense as the rest
    assert abs(middle.mean() - band) < 0.03


def test_a_scanners_mesh_is_extracted_as_its_blade(tmp_path):
    coarse, faces = _scanners_mesh(tmp_path / "scan.stl")
    meshed = shapely.union_all(shapely.polygons(coarse[faces][:, :, :2]))
    got = shapely.Polygon(extract_leaf(read_scan(tmp_path / "scan.stl")).leaf.boundary[:, :2])
    assert meshed.symmetric_difference(got).area < 0.04 * meshed.area
    assert shapely.hausdorff_distance(meshed.exterior, got.exterior) < 0.03
    assert main(["extract", str(tmp_path / "scan.stl"), "-o", str(tmp_path / "l.leaf.json")]) == 0
    assert len(load_leaf(tmp_path / "l.leaf.json").veins) >= 3


def test_extract_writes_a_leaf_that_reconstructs(tmp_path, capsys):
    parts = synthetic_scan(seed=4)
    scan_file = tmp_path / "scan.xyz"
    np.savetxt(scan_file, np.vstack([parts["blade"], parts["petiole"], parts["outliers"]]))
    out = tmp_path / "leaf.leaf.json"
    assert main(["extract", str(scan_file), "-o", str(out), "--points", "150"]) == 0
    leaf = load_leaf(out)
    assert len(leaf.boundary) == 150 and len(leaf.veins) >= 3
    said = capsys.readouterr()  # the closing line, on stderr as every command's (options.summary)
    assert said.out == "" and said.err.count("\n") == 1 and "wrote 150 boundary points" in said.err
    assert main(["extract", str(scan_file), "-o", str(out), "--points", "3"]) == 2
    assert main(["extract", str(tmp_path / "missing.ply"), "-o", str(out)]) == 2
    assert main(["extract", str(scan_file), "-o", str(tmp_path / "leaf.doc")]) == 2
    assert capsys.readouterr().err.count("\n") == 3  # one line an error


def test_the_outline_count_changes_only_the_outline(scan):
    """Review finding: --points set the spacing of the veins and of the region kept as blade, so
    a finer outline moved the blade/petiole split and the length, and cost quadratically in it
    (100,000 points ran past a minute). Now the blade, the petiole, the length and the veins'
    sampling are the same whatever the count."""
    _, points, coarse = scan  # the module's extraction: the default count, 200 outline points
    fine = extract_leaf(points, count=5000)
    assert len(coarse.leaf.boundary) == 200 and len(fine.leaf.boundary) == 5000
    np.testing.assert_array_equal(fine.blade, coarse.blade)
    np.testing.assert_array_equal(fine.petiole, coarse.petiole)
    assert fine.length == pytest.approx(coarse.length, rel=1e-12)
    # the veins end where the outline clips them: on the unrolled blade, a point either way
    assert len(fine.leaf.veins) == len(coarse.leaf.veins)
    for a, b in zip(fine.leaf.veins, coarse.leaf.veins, strict=True):
        assert abs(len(a) - len(b)) <= 1
    outline = shapely.Polygon(coarse.leaf.boundary[:, :2])
    assert shapely.Polygon(fine.leaf.boundary[:, :2]).area == pytest.approx(outline.area, rel=0.01)


def test_a_base_end_with_a_minus_sign_is_taken_as_written(tmp_path, capsys):
    """Review finding: `--base-end -x`, as --help writes it, was read as an option ("expected
    one argument"); only `--base-end=-x` worked."""
    parts = synthetic_scan(seed=1)
    scan = tmp_path / "scan.xyz"
    np.savetxt(scan, np.vstack([parts["blade"], parts["outliers"]]))
    out = tmp_path / "leaf.csv"
    code = main(["extract", str(scan), "-o", str(out), "--base-end", "-x"])
    assert code == 0, capsys.readouterr().err
    midrib = load_leaf(out).veins[0]
    assert midrib[0, 0] < -0.45 and midrib[-1, 0] > 0.45


def test_a_scan_that_repeats_its_points_is_extracted_as_the_same_scan_once(tmp_path, capsys):
    """Fuzzing finding (hunt26): a scan whose every point was written three times (two passes of
    a scanner merged, an export that repeats vertices) was refused as "not one leaf: 3190 large
    separate clusters of points (3, 3, 3, ...)" (the median distance to the nearest other point
    was 0, so no two repeats linked), and with --force no blade was found. Repeated points now
    count once: the same leaf as the scan written once."""
    parts = synthetic_scan(seed=2)
    points = np.vstack([parts["blade"], parts["petiole"], parts["outliers"]])
    once, thrice = tmp_path / "once.xyz", tmp_path / "thrice.xyz"
    np.savetxt(once, points)
    np.savetxt(thrice, np.repeat(points, 3, axis=0))
    for scan in (once, thrice):
        out = tmp_path / f"{scan.stem}.leaf.json"
        assert main(["extract", str(scan), "-o", str(out)]) == 0, capsys.readouterr().err
    a, b = load_leaf(tmp_path / "once.leaf.json"), load_leaf(tmp_path / "thrice.leaf.json")
    np.testing.assert_allclose(b.boundary, a.boundary, atol=1e-9)
    assert len(b.veins) == len(a.veins)


def test_one_stray_return_far_off_merges_no_points_of_the_leaf():
    """Review finding: repeats were points within 1e-9 of the scan's size, strays included, so
    one return a million lengths off made the leaf's own spacing "a repeat": the scan merged to
    2 points and was refused as too few even with force. Only exact repeats are dropped now."""
    from leafstudio.workflows import _scan_opened

    parts = synthetic_scan(seed=2)
    points = np.vstack([parts["blade"], parts["petiole"], parts["outliers"]])
    stray = points[:1] + [1e8 * float(np.ptp(points, axis=0).max()), 0.0, 0.0]
    opened = _scan_opened("stray.xyz", np.vstack([points, stray]), force=True)
    assert len(opened.scan) == len(points) + 1
    assert opened.extraction.blade.sum() >= 0.5 * len(parts["blade"])


def test_a_scan_of_one_point_repeated_says_so():
    """Review finding: a file of 60 lines of one point, its repeats dropped, was refused as
    "too few points for a leaf scan: 1", which reads as if the file held one line."""
    from leafstudio.workflows import _scan_opened

    with pytest.raises(LeafError, match="too few distinct points for a leaf scan: 1 of its 60"):
        _scan_opened("same.xyz", np.tile([[1.0, 2.0, 3.0]], (60, 1)))


@pytest.mark.parametrize("suffix", [".stl", ".obj"])
def test_a_mesh_with_nan_vertices_says_how_many_and_the_first(tmp_path, suffix):
    """Review of qa37: a point list's NaN points are named (how many, the first) or left out
    with a note, but a mesh's were refused as "NaN or infinite coordinates", naming neither.
    A mesh's triangles join its vertices, so one is still refused, saying where."""
    import trimesh

    coarse, faces = _scanners_mesh(tmp_path / "good.obj")
    coarse[[4, 30]] = np.nan
    trimesh.Trimesh(coarse, faces, process=False).export(tmp_path / f"scan{suffix}")
    for reader in (read_scan, read_scan_returns):
        with pytest.raises(LeafError, match=r"NaN or infinite coordinates at \d+ of \d+ vertices "
                           r"\(the first is vertex \d+\)"):  # fmt: skip
            reader(tmp_path / f"scan{suffix}")
