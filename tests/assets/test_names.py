"""The names inside an exported file: the mesh and its material bear the file's name
(assets/export.object_name)."""

from __future__ import annotations

import leafstudio as ls
from leafstudio.assets import mesh_assets


def test_a_mesh_and_its_material_are_named_after_the_file(tmp_path):
    """Designers import several leaves side by side: each was named "leaf" inside its file
    (glTF's node, mesh and material, OBJ's object and material), so Blender listed leaf,
    leaf.001, ... for oak.glb and maple.glb. Each now bears its file's name."""
    from pygltflib import GLTF2

    nested = ls.reconstruct(ls.demo("nested"), ls.Params(k=3, grid=32))

    for stem in ("oak", "Field maple 3"):
        ls.save_mesh(nested, tmp_path / f"{stem}.leaf.glb")
        gltf = GLTF2.load(str(tmp_path / f"{stem}.leaf.glb"))
        name = stem.replace(" ", "_")
        assert [node.name for node in gltf.nodes if node.mesh is not None] == [name]
        assert [mesh.name for mesh in gltf.meshes] == [name]
        assert [material.name for material in gltf.materials] == [name]
    ls.save_mesh(nested, tmp_path / "oak.obj")
    lines = (tmp_path / "oak.obj").read_text().splitlines()
    assert "o oak" in lines and "usemtl oak" in lines
    assert "newmtl oak" in (tmp_path / "oak.mtl").read_text().splitlines()
    assert [a.name for a in mesh_assets(nested, texture="none")] == ["leaf"]  # no file: "leaf"
