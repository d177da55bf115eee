"""Assets for 3D tools: normals, UVs, textures and glTF that validates, read back by the readers
people use (trimesh, open3d, meshio)."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
import trimesh

import leafstudio as ls
from leafstudio.assets import MeshAsset, UVMap, leaf_asset, mesh_assets
from leafstudio.assets.placement import place, result_placement
from leafstudio.assets.texture import BLADE, VEIN, outline_mask
from tests.leaves import moved
from tests.photos import error_lines

ROOT = Path(__file__).resolve().parents[2]
VALIDATOR = ROOT / "tests" / "tools" / "validate_gltf.cjs"
NODE_MODULES = ROOT / ".venv" / "node" / "node_modules"


@pytest.fixture(scope="module")
def nested() -> ls.Result:
    return ls.reconstruct(ls.demo("nested"), ls.Params(grid=48))


def gltf_reports(*paths: Path) -> dict:
    """The Khronos validator's report per file (skips when node or the validator is missing)."""
    node = shutil.which("node")
    if node is None or not (NODE_MODULES / "gltf-validator").is_dir():
        pytest.skip("node or the npm package gltf-validator is missing (./dev setup installs it)")
    env = {**os.environ, "NODE_PATH": str(NODE_MODULES)}
    out = subprocess.run(
        [node, str(VALIDATOR), *map(str, paths)], capture_output=True, text=True, env=env,
        check=True, timeout=120,
    )  # fmt: skip
    return json.loads(out.stdout)


def assert_valid_gltf(*paths: Path) -> None:
    """Zero errors, and zero warnings too (the normal map comes with its tangents)."""
    for path, report in gltf_reports(*paths).items():
        assert report["numErrors"] == 0, (path, report["messages"])
        assert report["numWarnings"] == 0, (path, report["messages"])


def gltf_attribute(path: Path, name: str, mesh: int = 0) -> np.ndarray:
    """A float vertex attribute of a glTF file's mesh, read with pygltflib (trimesh skips some)."""
    import base64

    from pygltflib import GLTF2

    gltf = GLTF2.load(str(path))
    accessor = gltf.accessors[getattr(gltf.meshes[mesh].primitives[0].attributes, name)]
    view = gltf.bufferViews[accessor.bufferView]
    if path.suffix == ".glb":
        blob = gltf.binary_blob()
    else:
        blob = base64.b64decode(gltf.buffers[view.buffer].uri.split(",", 1)[1])
    width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[accessor.type]
    start = view.byteOffset + (accessor.byteOffset or 0)
    data = np.frombuffer(blob, np.float32, accessor.count * width, start)
    return data.reshape(accessor.count, width)


def as_written(result: ls.Result, suffix: str) -> MeshAsset:
    """The leaf's asset placed as the format `suffix` has it (Y-up for glTF and OBJ)."""
    return place(leaf_asset(result), result_placement(result), None, suffix)


def scene_mesh(path: Path) -> trimesh.Trimesh:
    loaded = trimesh.load(path, process=False)
    if isinstance(loaded, trimesh.Scene):
        (loaded,) = loaded.geometry.values()
    return loaded


def test_normals_are_the_surfaces_own_in_closed_form(nested: ls.Result):
    asset = leaf_asset(nested)
    assert np.allclose(np.linalg.norm(asset.normals, axis=1), 1)
    # the graph's upward normal: (-z_x, -z_y, 1) in the plane frame, turned to the world
    xy = nested.frame.to_plane(asset.points)[0]
    grad = nested.surface.gradient(xy[len(nested.polygon) :])  # inside points: no margin limit
    up = np.column_stack([-grad, np.ones(len(grad))])
    up /= np.linalg.norm(up, axis=1, keepdims=True)
    frame = nested.frame
    world = up @ np.vstack([frame.u, frame.v, frame.normal])
    np.testing.assert_allclose(asset.normals[len(nested.polygon) :], world, atol=1e-9)
    # not the faces' average: that differs, most at the margin
    from leafstudio.core.trianglemesh import vertex_normals

    averaged = vertex_normals(asset.points, asset.faces)
    assert np.max(np.linalg.norm(averaged - asset.normals, axis=1)) > 1e-3
    # each triangle winds counter-clockwise seen from its normals' side
    a, b, c = (asset.points[asset.faces[:, i]] for i in range(3))
    facing = np.einsum("ij,ij->i", np.cross(b - a, c - a), asset.normals[asset.faces].sum(1))
    assert np.all(facing > 0)


def test_normals_are_in_world_coordinates_for_a_moved_leaf():
    from leafstudio.core.trianglemesh import vertex_normals

    leaf, rot, _ = moved(ls.demo("nested"))
    result = ls.reconstruct(leaf, ls.Params(grid=48))
    asset = leaf_asset(result)
    inner = np.arange(asset.n_points) >= len(result.polygon)
    averaged = vertex_normals(asset.points, asset.faces)[inner]
    angle = np.degrees(np.arccos(np.clip(np.sum(averaged * asset.normals[inner], 1), -1, 1)))
    assert np.median(angle) < 2 and np.percentile(angle, 95) < 6
    assert np.all(asset.normals @ rot.apply([0.0, 0.0, 1.0]) > 0.5)  # the leaf's upper side


def test_uvs_are_plane_coordinates_scaled_by_one_factor(nested: ls.Result):
    asset = leaf_asset(nested)
    uv = asset.uv
    assert uv.min() > 0 and uv.max() < 1
    xy = nested.frame.to_plane(asset.points)[0]
    uvmap = UVMap.around(nested.polygon)
    # no stretch: plane distances are UV distances times one factor, along both axes
    pairs = np.random.default_rng(0).integers(0, len(uv), (500, 2))
    ratio = np.linalg.norm(xy[pairs[:, 0]] - xy[pairs[:, 1]], axis=1) / np.linalg.norm(
        uv[pairs[:, 0]] - uv[pairs[:, 1]], axis=1
    )
    np.testing.assert_allclose(ratio[np.isfinite(ratio)], uvmap.size, rtol=1e-9)
    np.testing.assert_allclose(uvmap.to_plane(uv), xy, atol=1e-12)
    # centred, the longer side spanning all but the pad
    lo, hi = uv.min(axis=0), uv.max(axis=0)
    np.testing.assert_allclose((lo + hi) / 2, 0.5, atol=1e-9)
    assert max(hi - lo) == pytest.approx(1 / (1 + 2 * 1 / 64), rel=1e-6)


def test_generated_texture_has_blade_veins_and_alpha_outside(nested: ls.Result):
    (asset,) = mesh_assets(nested, "auto")
    image = np.asarray(asset.texture)
    assert image.shape == (1024, 1024, 4)
    alpha = image[..., 3]
    assert alpha[0, 0] == 0 and alpha[512, 0] == 0  # outside the leaf
    inside = alpha == 255
    colours = image[inside][:, :3].astype(int)
    blade = np.all(np.abs(colours - BLADE) <= 2, axis=1).mean()
    vein = np.all(np.abs(colours - VEIN) <= 2, axis=1).mean()
    assert blade > 0.8 and 0.005 < vein < 0.2
    # the texture's leaf is where the UVs put the mesh: its vertices land on opaque texels
    col = np.clip((asset.uv[:, 0] * 1024).astype(int), 0, 1023)
    row = np.clip(((1 - asset.uv[:, 1]) * 1024).astype(int), 0, 1023)
    inner = np.arange(asset.n_points) >= len(nested.polygon)
    assert np.mean(alpha[row[inner], col[inner]] == 255) > 0.99


def test_midrib_is_drawn_wider_than_the_secondaries(nested: ls.Result):
    from leafstudio.assets.asset import leaf_plane
    from leafstudio.assets.texture import vein_strokes

    plane = leaf_plane(nested)
    strokes = vein_strokes(plane, 1024) > 127

    def width_at(line: np.ndarray) -> float:  # stroke pixels across the vein at its middle
        mid = line[len(line) // 2]
        direction = line[min(len(line) // 2 + 1, len(line) - 1)] - line[len(line) // 2 - 1]
        across = np.array([-direction[1], direction[0]]) / np.linalg.norm(direction)
        steps = np.linspace(-0.05, 0.05, 2001) * nested.length
        samples = mid + steps[:, None] * across
        uv = plane.uvmap(samples)
        col, row = (uv[:, 0] * 1024).astype(int), ((1 - uv[:, 1]) * 1024).astype(int)
        return strokes[row, col].sum() * (steps[1] - steps[0])

    lengths = [np.linalg.norm(np.diff(v, axis=0), axis=1).sum() for v in plane.veins]
    midrib = plane.veins[int(np.argmax(lengths))]
    secondary = plane.veins[int(np.argmin(lengths))]
    assert width_at(midrib) > 1.3 * width_at(secondary)


@pytest.mark.parametrize("suffix", [".glb", ".gltf", ".obj", ".ply"])
def test_trimesh_reads_normals_uvs_and_texture_back(nested: ls.Result, tmp_path: Path, suffix):
    path = tmp_path / f"leaf{suffix}"
    ls.save_mesh(nested, path)
    asset = as_written(nested, suffix)
    back = scene_mesh(path)
    np.testing.assert_allclose(back.vertices, asset.points, atol=1e-6)
    np.testing.assert_array_equal(back.faces, asset.faces)
    np.testing.assert_allclose(back.vertex_normals, asset.normals, atol=1e-5)  # not recomputed
    np.testing.assert_allclose(back.visual.uv, asset.uv, atol=1e-6)
    if suffix in (".glb", ".gltf"):
        material = back.visual.material
        assert material.doubleSided is True
        assert material.baseColorTexture.size == (1024, 1024)
        assert material.normalTexture is not None
        tangents = gltf_attribute(path, "TANGENT")  # unit, in the tangent plane, w = +1 on top
        np.testing.assert_allclose(np.linalg.norm(tangents[:, :3], axis=1), 1, atol=1e-5)
        assert np.abs(np.sum(tangents[:, :3] * asset.normals, axis=1)).max() < 1e-5
        assert np.all(tangents[:, 3] == 1)
        np.testing.assert_allclose(
            back.vertex_attributes["_HEIGHT"].ravel(), asset.point_data["height"], atol=1e-6
        )
        assert {"_MEAN_CURVATURE", "_GAUSSIAN_CURVATURE", "_K1", "_K2"} <= set(
            back.vertex_attributes
        )
    if suffix == ".obj":
        assert (tmp_path / "leaf.mtl").is_file() and (tmp_path / "leaf_texture.png").is_file()
        assert back.visual.material.image.size == (1024, 1024)


@pytest.mark.open3d
@pytest.mark.parametrize("suffix", [".glb", ".gltf", ".obj", ".ply"])
def test_open3d_reads_normals_and_uvs_back(nested: ls.Result, tmp_path: Path, suffix: str):
    import open3d as o3d

    path = tmp_path / f"leaf{suffix}"
    ls.save_mesh(nested, path)
    mesh = o3d.io.read_triangle_mesh(str(path))
    asset = as_written(nested, suffix)
    assert len(mesh.vertices) == asset.n_points and mesh.has_vertex_normals()
    # open3d may renumber the vertices: match them by position
    from scipy.spatial import cKDTree

    distance, ours = cKDTree(asset.points).query(np.asarray(mesh.vertices))
    assert distance.max() < 1e-6
    np.testing.assert_allclose(np.asarray(mesh.vertex_normals), asset.normals[ours], atol=1e-5)
    if suffix != ".ply":  # open3d's PLY reader does not read per-vertex s, t
        assert mesh.has_triangle_uvs()
        uvs = np.asarray(mesh.triangle_uvs).reshape(-1, 3, 2)
        expected = asset.uv[ours[np.asarray(mesh.triangles)]]
        flipped = expected * [1, -1] + [0, 1]  # glTF's v runs down the image
        assert np.allclose(uvs, expected, atol=1e-5) or np.allclose(uvs, flipped, atol=1e-5)


@pytest.mark.parametrize("suffix", [".obj", ".ply", ".stl"])
def test_meshio_reads_normals_and_uvs_back(nested: ls.Result, tmp_path: Path, suffix: str):
    import meshio

    path = tmp_path / f"leaf{suffix}"
    ls.save_mesh(nested, path)
    mesh = meshio.read(path)
    asset = as_written(nested, suffix)
    assert len(mesh.cells_dict["triangle"]) == len(asset.faces)
    if suffix == ".obj":
        np.testing.assert_allclose(mesh.point_data["obj:vn"], asset.normals, atol=1e-5)
        np.testing.assert_allclose(mesh.point_data["obj:vt"][:, :2], asset.uv, atol=1e-6)
    if suffix == ".ply":
        normals = np.column_stack([mesh.point_data[c] for c in ("nx", "ny", "nz")])
        np.testing.assert_allclose(normals, asset.normals, atol=1e-6)
        uv = np.column_stack([mesh.point_data["s"], mesh.point_data["t"]])
        np.testing.assert_allclose(uv, asset.uv, atol=1e-6)
        np.testing.assert_allclose(mesh.point_data["height"], asset.point_data["height"])


def test_vtk_formats_carry_normals_and_texture_coordinates(nested: ls.Result, tmp_path: Path):
    import pyvista as pv

    asset = leaf_asset(nested)
    for suffix in (".vtp", ".vtk"):
        ls.save_mesh(nested, tmp_path / f"leaf{suffix}")
        back = pv.read(tmp_path / f"leaf{suffix}")
        np.testing.assert_allclose(back.point_data["Normals"], asset.normals, atol=1e-9)
        np.testing.assert_allclose(back.active_texture_coordinates, asset.uv, atol=1e-9)


def test_every_gltf_written_passes_the_khronos_validator(nested: ls.Result, tmp_path: Path):
    paths = []
    for texture in ("auto", "none"):
        for suffix in (".glb", ".gltf"):
            path = tmp_path / f"leaf-{texture}{suffix}"
            ls.save_mesh(nested, path, texture=texture)
            paths.append(path)
    paths.append(tmp_path / "solid.glb")
    ls.save_mesh(nested, paths[-1], thickness=0.01 * nested.length)
    paths.append(tmp_path / "bare.glb")
    ls.save_mesh(nested.triangle_mesh, paths[-1])
    assert_valid_gltf(*paths)


def test_texture_none_still_writes_uvs_and_a_coloured_material(nested: ls.Result, tmp_path):
    ls.save_mesh(nested, tmp_path / "leaf.glb", texture="none")
    back = scene_mesh(tmp_path / "leaf.glb")
    assert back.visual.material.baseColorTexture is None
    assert back.visual.uv.shape == (len(back.vertices), 2)
    ls.save_mesh(nested, tmp_path / "leaf.obj", texture="none")
    assert not (tmp_path / "leaf_texture.png").exists()
    assert f"Kd {BLADE[0] / 255:.4f}" in (tmp_path / "leaf.mtl").read_text()  # the blade green


def test_cli_texture_option(tmp_path: Path):
    from leafstudio.cli import main

    leaf = tmp_path / "nested.leaf.json"
    ls.save_leaf(ls.demo("nested"), leaf)
    out = tmp_path / "leaf.obj"
    run = ["reconstruct", str(leaf), "--grid", "32", "-o"]
    assert main([*run, str(out), "--texture", "none"]) == 0
    assert not (tmp_path / "leaf_texture.png").exists() and (tmp_path / "leaf.mtl").exists()
    assert main([*run, str(out)]) == 0
    assert (tmp_path / "leaf_texture.png").exists()
    image = tmp_path / "any.png"
    from PIL import Image

    Image.new("RGB", (64, 32), (200, 10, 10)).save(image)
    glb = tmp_path / "leaf.glb"
    assert main([*run, str(glb), "--texture", str(image)]) == 0
    texture = np.asarray(scene_mesh(glb).visual.material.baseColorTexture)
    assert tuple(texture[0, 0, :3]) == (200, 10, 10)


def test_cli_texture_that_is_not_an_image_is_one_line_exit_2(tmp_path: Path, capsys):
    from leafstudio.cli import main

    leaf = tmp_path / "nested.leaf.json"
    ls.save_leaf(ls.demo("nested"), leaf)
    bad = tmp_path / "notes.png"
    bad.write_text("not an image")
    code = main(["reconstruct", str(leaf), "-o", str(tmp_path / "x.glb"), "--texture", str(bad)])
    err = capsys.readouterr().err
    assert code == 2 and "not a readable image" in err and error_lines(err) == 1
    assert not (tmp_path / "x.glb").exists()


def test_outline_mask_matches_the_mesh_margin(nested: ls.Result):
    from leafstudio.assets.asset import leaf_plane

    plane = leaf_plane(nested)
    mask = outline_mask(plane, 512) > 127
    uv = UVMap.around(nested.polygon)(nested.polygon)
    col, row = (uv[:, 0] * 512).astype(int), ((1 - uv[:, 1]) * 512).astype(int)
    # every margin vertex is within a pixel of the mask's edge
    from scipy.ndimage import binary_dilation, binary_erosion

    edge = binary_dilation(mask, iterations=1) & ~binary_erosion(mask, iterations=1)
    assert np.mean(binary_dilation(edge, iterations=1)[row.clip(0, 511), col.clip(0, 511)]) > 0.99


@pytest.mark.open3d
def test_levels_of_detail_halve_the_triangles_and_keep_the_margin(nested: ls.Result, tmp_path):
    import shapely

    from leafstudio.assets.solid import boundary_edges

    path = tmp_path / "leaf.glb"
    ls.save_mesh(nested, path, lod=3)
    assert_valid_gltf(path)
    scene = trimesh.load(path, process=False)
    names = [f"leaf_LOD{k}" for k in range(4)]
    assert sorted(scene.geometry) == names
    counts = [len(scene.geometry[name].faces) for name in names]
    for coarse, fine in zip(counts[1:], counts[:-1], strict=True):
        assert coarse == pytest.approx(fine / 2, rel=0.1)
    ring = shapely.LinearRing(nested.polygon)
    full = shapely.Polygon(nested.polygon).area
    turn, offset = result_placement(nested).transform(None, ".glb")  # a rotation: Y-up
    for name in names[1:]:
        mesh = scene.geometry[name]
        xy = nested.frame.to_plane((np.asarray(mesh.vertices) - offset) @ turn)[0]
        rim = np.unique(boundary_edges(np.asarray(mesh.faces)))
        assert shapely.distance(ring, shapely.points(xy[rim])).max() < 5e-4 * nested.length
        area = shapely.union_all(shapely.polygons(xy[np.asarray(mesh.faces)])).area
        assert area == pytest.approx(full, rel=0.01)  # the outline keeps its shape
        assert mesh.visual.uv.shape == (len(mesh.vertices), 2)
        normals = np.asarray(mesh.vertex_normals)
        assert np.all(normals @ turn @ nested.frame.normal > 0)  # closed-form, the upper side
    ls.save_mesh(nested, tmp_path / "leaf.obj", lod=1)
    assert (tmp_path / "leaf_lod1.obj").is_file() and (tmp_path / "leaf_lod1.mtl").is_file()


def scene_nodes(gltf) -> list[int]:
    """The nodes a glTF's default scene shows: its root nodes and their descendants."""
    out, todo = [], list(gltf.scenes[gltf.scene or 0].nodes)
    while todo:
        out.append(todo.pop(0))
        todo += gltf.nodes[out[-1]].children or []
    return out


@pytest.mark.open3d
def test_a_gltf_shows_one_leaf_and_lists_its_coarser_levels_in_msft_lod(nested, tmp_path):
    """Issue 23: every level was a node of the scene, so Blender 4.5 (which reads no MSFT_lod)
    showed three overlapping leaves. The scene holds LOD0; the coarser nodes are outside it,
    named by LOD0's MSFT_lod, with MSFT_screencoverage in its extras (the MSFT_lod spec)."""
    from pygltflib import GLTF2

    paths = [tmp_path / "leaf.glb", tmp_path / "leaf.gltf"]
    for path in paths:
        ls.save_mesh(nested, path, lod=2)
        gltf = GLTF2.load(str(path))
        shown = [n for n in scene_nodes(gltf) if gltf.nodes[n].mesh is not None]
        assert [gltf.nodes[n].name for n in shown] == ["leaf_LOD0"]
        top = gltf.nodes[shown[0]]
        ids = top.extensions["MSFT_lod"]["ids"]
        assert [gltf.nodes[n].name for n in ids] == ["leaf_LOD1", "leaf_LOD2"]
        meshes = [top.mesh, *(gltf.nodes[n].mesh for n in ids)]
        counts = [gltf.accessors[gltf.meshes[m].primitives[0].indices].count for m in meshes]
        assert counts[0] > counts[1] > counts[2]  # finest first
        coverage = top.extras["MSFT_screencoverage"]
        assert len(coverage) == 3 and 1 >= coverage[0] > coverage[1] > coverage[2] >= 0
        assert "MSFT_lod" in gltf.extensionsUsed and "MSFT_lod" not in gltf.extensionsRequired
    assert_valid_gltf(*paths)
    ls.save_mesh(nested, paths[0])  # one level: no MSFT_lod
    assert "MSFT_lod" not in (GLTF2.load(str(paths[0])).extensionsUsed or [])


def test_an_obj_never_writes_its_texture_over_the_image_it_maps(nested: ls.Result, tmp_path):
    from PIL import Image

    photo = tmp_path / "leaf_texture.png"
    Image.new("RGB", (32, 32), (1, 2, 3)).save(photo)
    before = photo.read_bytes()
    with pytest.raises(ls.LeafError, match="is also an input"):
        ls.save_mesh(nested, tmp_path / "leaf.obj", texture=str(photo))
    assert photo.read_bytes() == before and not (tmp_path / "leaf.obj").exists()


def test_a_failed_obj_export_leaves_the_old_files_as_they_were(nested: ls.Result, tmp_path):
    from unittest import mock

    ls.save_mesh(nested, tmp_path / "leaf.obj")
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    full = mock.patch("leafstudio.assets.writers._rows", side_effect=OSError(28, "No space"))
    with full, pytest.raises((OSError, ls.LeafError)):
        ls.save_mesh(nested, tmp_path / "leaf.obj", texture="none")
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before  # no .png lost


def gltf_json(path: Path) -> dict:
    """The JSON chunk of a .glb."""
    data = path.read_bytes()
    length = int.from_bytes(data[12:16], "little")
    return json.loads(data[20 : 20 + length])


def test_a_sheets_material_is_translucent_and_validates(nested: ls.Result, tmp_path: Path):
    """Issue 23, item 2: light through the blade. KHR_materials_transmission (ratified, what
    Blender's importer reads) and KHR_materials_diffuse_transmission (the leaf's own model),
    coloured by the base colour texture; a solid for printing stays opaque."""
    from leafstudio.assets.material import DIFFUSE_TRANSMISSION, TRANSMISSION

    ls.save_mesh(nested, tmp_path / "leaf.glb")
    ls.save_mesh(nested, tmp_path / "plain.glb", texture="none")
    ls.save_mesh(nested, tmp_path / "solid.glb", thickness=0.01 * nested.length)
    tree = gltf_json(tmp_path / "leaf.glb")
    (material,) = tree["materials"]
    extensions = material["extensions"]
    assert extensions["KHR_materials_transmission"] == {"transmissionFactor": TRANSMISSION}
    diffuse = extensions["KHR_materials_diffuse_transmission"]
    assert diffuse["diffuseTransmissionFactor"] == DIFFUSE_TRANSMISSION
    base = material["pbrMetallicRoughness"]["baseColorTexture"]
    assert diffuse["diffuseTransmissionColorTexture"] == base
    assert set(tree["extensionsUsed"]) >= set(extensions)
    assert "extensionsRequired" not in tree  # a viewer without them still shows the leaf
    (plain,) = gltf_json(tmp_path / "plain.glb")["materials"]
    colour = plain["extensions"]["KHR_materials_diffuse_transmission"]
    assert colour["diffuseTransmissionColorFactor"] == pytest.approx([c / 255 for c in BLADE])
    assert "extensions" not in gltf_json(tmp_path / "solid.glb")["materials"][0]
    assert_valid_gltf(tmp_path / "leaf.glb", tmp_path / "plain.glb")


def test_an_obj_carries_its_translucency_to_blender(nested: ls.Result, tmp_path):
    """Blender 4.5's OBJ importer made a glTF's translucent leaf opaque: the MTL named only the
    base colour. It reads `Tf` as the Principled BSDF's Transmission Weight (bpy 4.5.15,
    benchmarks/check_blender.py), so a sheet's MTL has the glTF's share of transmission; a solid
    stays opaque. (No normal map: that importer loads a `map_Bump` image as sRGB, writers.py.)"""
    from leafstudio.assets.material import TRANSMISSION

    ls.save_mesh(nested, tmp_path / "leaf.obj")
    ls.save_mesh(nested, tmp_path / "plain.obj", texture="none")
    for name in ("leaf.mtl", "plain.mtl"):
        lines = (tmp_path / name).read_text().splitlines()
        assert f"Tf {TRANSMISSION} {TRANSMISSION} {TRANSMISSION}" in lines
    ls.save_mesh(nested, tmp_path / "solid.obj", thickness=0.01 * nested.length)
    assert "Tf" not in (tmp_path / "solid.mtl").read_text()


def test_an_obj_named_with_spaces_refers_to_companions_without_them(nested, tmp_path: Path):
    """`my leaf.obj` wrote `mtllib my leaf.mtl` and `map_Kd my leaf_texture.png`: the OBJ
    format separates file names by spaces (mtllib takes several), so strict readers
    (tinyobjloader, MeshLab, DirectXMesh) looked for `my` and `leaf.mtl` and drew the leaf
    untextured. The companions' names now have underscores for the spaces."""
    import trimesh

    path = tmp_path / "my leaf (1).obj"
    ls.save_mesh(nested, path)
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "my leaf (1).obj",
        "my_leaf_(1).mtl",
        "my_leaf_(1)_texture.png",
    ]
    assert "mtllib my_leaf_(1).mtl" in path.read_text().splitlines()
    assert "map_Kd my_leaf_(1)_texture.png" in (tmp_path / "my_leaf_(1).mtl").read_text()
    assert trimesh.load(path, force="mesh").visual.material.image.size == (1024, 1024)
