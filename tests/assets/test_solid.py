"""Solid leaves (--thickness): closed, consistently oriented with outward normals, volume = area ×
thickness within 2%, no self-intersection, also at thin tips and deep sinuses; every solid format
reads back watertight."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

import leafstudio as ls
from leafstudio.assets import leaf_asset
from leafstudio.assets.export import mesh_assets
from leafstudio.assets.solid import parse_thickness, thicken, thickness_in_mesh_units
from leafstudio.errors import LeafError
from leafstudio.forms import make_form
from tests.leaves import lobed, narrow
from tests.photos import error_lines

LEAVES = {
    "nested": lambda: ls.demo("nested"),  # a thin, pointed base (narrower than T there)
    "parallel": lambda: ls.demo("parallel"),
    "lobed": lambda: lobed()[0],  # deep sinuses
    "narrow": lambda: narrow()[0],  # grass-like, sharp tip
    "acuminate": lambda: make_form("elliptic", apex="acuminate"),  # a long thin tip
}


@pytest.fixture(scope="module", params=sorted(LEAVES))
def sheet(request):
    result = ls.reconstruct(LEAVES[request.param](), ls.Params(grid=48))
    return result, leaf_asset(result)


def self_intersecting(points: np.ndarray, faces: np.ndarray, per_cell: int = 400) -> bool:
    """open3d's test of every pair of faces that share no vertex, cell by cell: the faces are
    binned by their boxes into cells across the solid's two widest axes, a face in every cell its
    box meets, so two faces that cross share a point, and so a cell. The same pairs are found as
    by one call on the whole mesh, whose all-pairs loop cost 2 s at grid 128 (now about 0.1 s)."""
    o3d = pytest.importorskip("open3d")  # the other checks ran; this one needs it
    corners = points[faces]  # (m, 3, 3)
    low, high = corners.min(axis=1), corners.max(axis=1)
    axes = np.argsort(np.ptp(points, axis=0))[1:]  # the two widest
    n = max(1, int(np.sqrt(len(faces) / per_cell)))
    edges = [np.linspace(points[:, a].min(), points[:, a].max(), n + 1) for a in axes]
    for i in range(n):
        for j in range(n):
            meets = np.ones(len(faces), bool)
            for a, e, k in zip(axes, edges, (i, j), strict=True):
                meets &= (low[:, a] <= e[k + 1]) & (high[:, a] >= e[k])
            used, local = np.unique(faces[meets], return_inverse=True)  # shared vertices kept
            mesh = o3d.geometry.TriangleMesh(
                o3d.utility.Vector3dVector(points[used]),
                o3d.utility.Vector3iVector(local.reshape(-1, 3).astype(np.int32)),
            )
            if mesh.is_self_intersecting():
                return True
    return False


@pytest.mark.parametrize("pierced", [False, True])
def test_the_crossing_check_by_cells_finds_what_one_on_the_whole_mesh_finds(pierced):
    """A sound solid, and the same with one top vertex near the blade's middle pushed through
    the bottom sheet: the check by cells agrees with open3d's on the whole mesh. (The crossing
    case was a thickness at which the nested demo's sheets happened to cross at the margin, 0.3
    of its length, then 0.2; the surface moved and none crossed up to 0.8.)"""
    o3d = pytest.importorskip("open3d")
    result = ls.reconstruct(ls.demo("nested"), ls.Params(grid=40))
    solid = thicken(leaf_asset(result), 0.01 * result.length)
    points = np.array(solid.points)
    if pierced:
        n = len(points) // 2  # the top sheet's vertices, then the bottom's (solid.thicken)
        middle = points[:n].mean(axis=0)
        i = int(np.argmin(np.linalg.norm(points[:n] - middle, axis=1)))
        points[i] = points[n + i] - 2 * (points[i] - points[n + i])
    whole = o3d.geometry.TriangleMesh(
        o3d.utility.Vector3dVector(points), o3d.utility.Vector3iVector(solid.faces)
    )
    assert whole.is_self_intersecting() == pierced
    assert self_intersecting(points, solid.faces, per_cell=20) == pierced  # 12 x 12 cells


@pytest.mark.parametrize("fraction", [0.005, 0.02])
def test_solid_is_closed_oriented_and_of_the_right_volume(sheet, fraction):
    result, asset = sheet
    thickness = fraction * result.length
    solid = thicken(asset, thickness)
    mesh = trimesh.Trimesh(solid.points, solid.faces, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.is_volume
    area = trimesh.Trimesh(asset.points, asset.faces, process=False).area
    assert mesh.volume > 0  # outward normals
    assert mesh.volume == pytest.approx(area * thickness, rel=0.02)
    assert not self_intersecting(solid.points, solid.faces)
    # the top sheet's normals point out: away from the bottom sheet
    top = solid.points[: asset.n_points]
    bottom = solid.points[asset.n_points :]
    assert np.all(np.einsum("ij,ij->i", top - bottom, solid.normals[: asset.n_points]) >= 0)


@pytest.mark.parametrize("suffix", [".stl", ".obj", ".ply", ".glb", ".3mf"])
def test_every_solid_format_reads_back_watertight(tmp_path: Path, suffix: str):
    result = ls.reconstruct(ls.demo("nested"), ls.Params(grid=40))
    thickness = 0.01 * result.length
    path = tmp_path / f"leaf{suffix}"
    ls.save_mesh(result, path, thickness=thickness)
    loaded = trimesh.load(path, force="mesh")  # merges STL's corners
    if suffix == ".stl":
        loaded.merge_vertices()
    assert loaded.is_watertight and loaded.is_volume
    expected = thicken(leaf_asset(result), thickness)
    reference = trimesh.Trimesh(expected.points, expected.faces, process=False)
    assert loaded.volume == pytest.approx(reference.volume, rel=1e-4)


@pytest.mark.parametrize("thickness", [None, 1e-3])
def test_an_stl_whose_32_bit_floats_would_merge_its_points_is_refused(tmp_path, thickness):
    """A leaf of length 1 lying 1e5 from the origin: STL's 32-bit floats are 8e-3 apart there,
    so a solid of thickness 1e-3 of its length (in range) read back not closed, and even the
    bare sheet had 100 faces of no area (its area 9% off), both written with exit 0."""
    leaf = ls.demo("nested")
    far = ls.Leaf(leaf.boundary + 1e5, [v + 1e5 for v in leaf.veins])
    result = ls.reconstruct(far, ls.Params(grid=32))
    path = tmp_path / "far.stl"
    with pytest.raises(LeafError, match="32-bit"):
        ls.save_mesh(result, path, thickness=thickness)
    assert not path.exists()
    ls.save_mesh(result, tmp_path / "far.3mf", thickness=thickness)  # 3MF keeps their digits
    near = ls.reconstruct(leaf, ls.Params(grid=32))
    ls.save_mesh(near, tmp_path / "near.stl", thickness=thickness)  # at the origin: kept apart
    assert (tmp_path / "near.stl").stat().st_size > 0


def test_thickness_with_units_and_as_a_fraction():
    assert parse_thickness("0.01") == (0.01, None)
    assert parse_thickness("0.4mm") == (0.4, "mm")
    assert thickness_in_mesh_units("0.4mm", 80.0) == pytest.approx(0.4)
    assert thickness_in_mesh_units("0.04cm", 80.0) == pytest.approx(0.4)
    assert thickness_in_mesh_units("0.005", 80.0) == pytest.approx(0.4)
    for bad in ("", "-1", "0", "thick", "2", "0.4parsec"):
        with pytest.raises(LeafError):
            parse_thickness(bad)


def test_cli_thickness(tmp_path: Path, capsys):
    from leafstudio.cli import main

    leaf = tmp_path / "nested.leaf.json"
    ls.save_leaf(ls.demo("nested"), leaf)
    out = tmp_path / "leaf.3mf"
    assert main(["reconstruct", str(leaf), "-o", str(out), "--grid", "32", "--thickness",
                 "0.01"]) == 0  # fmt: skip
    assert trimesh.load(out, force="mesh").is_watertight
    code = main(["reconstruct", str(leaf), "-o", str(tmp_path / "x.stl"), "--thickness", "big"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "--thickness" in err and error_lines(err) == 1
    assert not (tmp_path / "x.stl").exists()


@pytest.mark.parametrize(
    ("name", "fraction"), [("narrow", 0.01), ("narrow", 0.02), ("nested", 0.05)]
)
def test_thick_solids_on_a_fine_mesh_keep_their_volume_and_do_not_cross(name, fraction):
    """A fine mesh sees the margin's steep, tightly bent band: the thickness is kept there and
    the sheets still do not cross (the grass-like blade is 0.06 wide: T = 0.02 is a third)."""
    result = ls.reconstruct(LEAVES[name](), ls.Params(grid=128))
    asset = leaf_asset(result)
    thickness = fraction * result.length
    solid = thicken(asset, thickness)
    mesh = trimesh.Trimesh(solid.points, solid.faces, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    area = trimesh.Trimesh(asset.points, asset.faces, process=False).area
    assert mesh.volume == pytest.approx(area * thickness, rel=0.02)
    assert not self_intersecting(solid.points, solid.faces)


def _gallery() -> dict[str, object]:
    """Every shape of the forms gallery with every margin, both demos, and blades folded
    steeply (their flanks near vertical: issue 23, finding 3; a cordate blade folded 75 degrees
    made 0.85 x area x T at grid 64)."""
    from itertools import product

    from leafstudio.forms import SHAPES
    from leafstudio.forms.make import Form
    from leafstudio.forms.terms import MARGINS

    cases: dict[str, object] = {
        f"{s}-{m}": (lambda s=s, m=m: make_form(s, margin=m)) for s, m in product(SHAPES, MARGINS)
    }
    for shape, fold in (("cordate", 60), ("sagittate", 60), ("cordate", 75), ("hastate", 75)):
        cases[f"{shape}-fold{fold}"] = lambda s=shape, f=fold: Form(s, fold=f).leaf()
    cases["cordate-fold75-grid64"] = cases["cordate-fold75"]  # where it was 0.85 x area x T
    cases["demo-nested"] = lambda: ls.demo("nested")
    cases["demo-parallel"] = lambda: ls.demo("parallel")
    return cases


GALLERY = _gallery()


@pytest.mark.parametrize("name", sorted(GALLERY))
def test_every_gallery_leaf_makes_a_sound_solid(name: str):
    """Consistent outward winding, positive volume within 2% of area x T, watertight, no
    self-intersection, for every shape and margin the app offers (trimesh and open3d)."""
    grid = 128 if name.endswith(("fold60", "fold75")) else 64  # the folds' flanks at the app's
    result = ls.reconstruct(GALLERY[name](), ls.Params(grid=grid))
    asset = leaf_asset(result)
    sheet = trimesh.Trimesh(asset.points, asset.faces, process=False)
    assert sheet.is_winding_consistent
    thickness = 0.01 * result.length
    solid = mesh_assets(result, texture="none", thickness=thickness)[0]  # a fold's: bent_offsets
    mesh = trimesh.Trimesh(solid.points, solid.faces, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent
    # > 0: outward; a steep fold's inner corner is mitred (solid._crease: T² over
    # 2 tan(opening / 2) of the crease's length, 3% of hastate folded 75°)
    kept = 0.04 if "fold" in name else 0.02
    assert mesh.volume == pytest.approx(sheet.area * thickness, rel=kept)
    assert not self_intersecting(solid.points, solid.faces)


def test_a_ball_pivoting_sheet_makes_a_closed_solid():
    """Ball pivoting's mesh has a pinched margin vertex (two fans of faces touching there): one
    vertex per fan, so every edge of the solid has two faces (was: not watertight)."""
    result = ls.reconstruct(make_form("cordate"), ls.Params(mesher="bpa"))
    asset = leaf_asset(result)
    thickness = 0.01 * result.length
    solid = thicken(asset, thickness)
    mesh = trimesh.Trimesh(solid.points, solid.faces, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent
    area = trimesh.Trimesh(asset.points, asset.faces, process=False).area
    assert mesh.volume == pytest.approx(area * thickness, rel=0.02)


def test_a_thickness_fraction_is_of_the_blade_length_the_metrics_give():
    """`--thickness 0.01` is a hundredth of the leaf length the metrics, `--length` and the scan
    distances use (the blade's, base to apex): a reniform blade, 1 long and 1.39 wide, had it of
    the outline's extent along its main axis (1.39), 1.39% of its length."""
    from leafstudio.assets.export import asset_options

    result = ls.reconstruct(make_form("reniform"), ls.Params(k=3, grid=32))
    length = result.metrics["leaf"]["length"]
    assert length == pytest.approx(1.0, rel=1e-3)
    options = asset_options("none", "0.01", 0, "leaf.csv", result)
    assert options["thickness"] == pytest.approx(0.01 * length, rel=1e-6)
    with_size = asset_options("none", "0.01", 0, "leaf.csv", result, "8cm")
    assert with_size["thickness"] == pytest.approx(0.01 * length, rel=1e-6)
