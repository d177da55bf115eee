"""Mesh assets out, by format: each writer takes MeshAssets (asset.py) and a path.

- ``.ply``: binary, vertices x y z nx ny nz s t and the scalars (height, curvatures).
- ``.obj``: v, vt, vn and faces f a/a/a, with `<stem>.mtl` and the texture
  `<stem>_texture.png` beside it (not `<stem>.png`: often the photo the leaf came from); a
  sheet's MTL has `Tf`, its translucency.
- ``.glb``, ``.gltf``: glTF 2.0 through trimesh (one file; .gltf with its buffers embedded):
  NORMAL, TEXCOORD_0, a double-sided PBR material with the base colour (and normal) texture, and
  the scalars as custom attributes _HEIGHT, _MEAN_CURVATURE, _GAUSSIAN_CURVATURE, _K1, _K2;
  with a normal map, TANGENT too (the s axis in each tangent plane: no tangents left to guess).
  A sheet's material is translucent: KHR_materials_transmission and
  KHR_materials_diffuse_transmission (material.py says why both).
  Levels of detail are meshes leaf_LOD0, leaf_LOD1, ..., as MSFT_lod has them: the scene
  shows leaf_LOD0 (a reader without MSFT_lod, such as Blender 4.5, gets one leaf), whose
  MSFT_lod extension lists the coarser nodes, outside the scene.
- ``.stl``, ``.3mf``: through trimesh (geometry only; 3MF in millimetres, its unit by spec; an
  STL whose 32-bit floats would merge points of the mesh is refused, check_32_bit).
- ``.vtp``, ``.vtk``: through pyvista, with Normals, the texture coordinates and the scalars.
- ``.usda``, ``.usdc``, ``.usdz``: through usd-core (usd.py): normals, UVs, the scalars as
  primvars, a UsdPreviewSurface material with the textures; levels of detail as variants.

Every file is written atomically (safewrite.write_bytes); the OBJ's texture and material go
first, so an .obj on disk never names a file that is not there.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from leafstudio._shared.safewrite import write_bytes
from leafstudio.assets.asset import MeshAsset
from leafstudio.assets.material import (
    ALPHA_CUTOFF,
    DIFFUSE_TRANSMISSION,
    METALLIC,
    ROUGHNESS,
    TEXTURE_SUFFIX,
    TRANSLUCENT_EXTENSIONS,
    TRANSMISSION,
    png_bytes,
)
from leafstudio.assets.texture import BLADE
from leafstudio.assets.usd import USD_SUFFIXES, usd_companions, write_usd
from leafstudio.core.trianglemesh import polydata
from leafstudio.errors import LeafError

GLTF_SUFFIXES = (".glb", ".gltf")
LEVELS_IN_ONE = (*GLTF_SUFFIXES, *USD_SUFFIXES)  # formats that hold every level of detail
SHORT = ("nx", "ny", "nz", "s", "t")  # PLY properties kept as float32


def write_ply(asset: MeshAsset, path: Path) -> None:
    """Binary PLY: x y z nx ny nz s t and every scalar as a vertex property, faces as lists."""
    from plyfile import PlyData, PlyElement

    names = ["x", "y", "z", "nx", "ny", "nz", "s", "t", *asset.point_data]
    vertex = np.empty(asset.n_points, dtype=[(c, "f4" if c in SHORT else "f8") for c in names])
    columns = [*asset.points.T, *asset.normals.T, *asset.uv.T, *asset.point_data.values()]
    for name, column in zip(names, columns, strict=True):
        vertex[name] = column
    face = np.empty(len(asset.faces), dtype=[("vertex_indices", "i4", (3,))])
    face["vertex_indices"] = asset.faces
    elements = [PlyElement.describe(vertex, "vertex"), PlyElement.describe(face, "face")]
    header = PlyData(elements, text=False, byte_order="<").header
    # the bytes plyfile would write, with the faces as one block (it writes list rows one by
    # one: a tenth of a second per leaf, a third of a batch's time per scan)
    rows = np.empty(len(asset.faces), dtype=[("n", "u1"), ("v", "<i4", (3,))])
    rows["n"], rows["v"] = 3, asset.faces
    little = vertex.astype(vertex.dtype.newbyteorder("<"))
    write_bytes(path, header.encode("ascii") + b"\n" + little.tobytes() + rows.tobytes())


def obj_companions(path: Path) -> tuple[Path, Path]:
    """The material file and texture an .obj at `path` refers to, named after it with `_` for
    each space: OBJ separates file names by spaces (`mtllib` takes several), so strict readers
    split `mtllib my leaf.mtl` into two files and find neither."""
    stem = re.sub(r"\s", "_", path.stem)
    return path.with_name(f"{stem}.mtl"), path.with_name(f"{stem}{TEXTURE_SUFFIX}")


def write_obj(asset: MeshAsset, path: Path) -> None:
    """OBJ with vt and vn (one index for all three: no seams), its .mtl and, if the asset has a
    texture, the PNG beside it; a sheet's MTL has glTF's transmission as `Tf` (material.py).

    No normal map: Blender 4.5's importer reads `map_Bump` as one but loads the image as sRGB,
    which tilts every normal (the veins' relief was lost and the blade shaded darker)."""
    mtl, png = obj_companions(path)
    kd = " ".join(f"{c / 255:.4f}" for c in BLADE)
    lines = [f"newmtl {asset.material_name}", "Ka 0 0 0", "Ks 0 0 0", "illum 1"]
    if asset.texture is not None:
        write_bytes(png, png_bytes(asset.texture))
        lines += ["Kd 1 1 1", f"map_Kd {png.name}", f"map_d {png.name}"]
    else:
        lines.append(f"Kd {kd}")
    if not asset.solid:
        lines.append(f"Tf {TRANSMISSION} {TRANSMISSION} {TRANSMISSION}")
    write_bytes(mtl, ("\n".join(lines) + "\n").encode())
    rows = [f"# LeafStudio leaf: {asset.n_points} vertices, {len(asset.faces)} triangles",
            f"mtllib {mtl.name}", f"o {asset.name}"]  # fmt: skip
    corners = np.repeat(asset.faces + 1, 3, axis=1)  # a/a/a
    blocks = [
        "\n".join(rows),
        _rows("v {:.9g} {:.9g} {:.9g}", asset.points),
        _rows("vt {:.7g} {:.7g}", asset.uv),
        _rows("vn {:.6g} {:.6g} {:.6g}", asset.normals),
        f"usemtl {asset.material_name}",
        _rows("f {}/{}/{} {}/{}/{} {}/{}/{}", corners),
    ]
    write_bytes(path, ("\n".join(b for b in blocks if b) + "\n").encode())


def _rows(line: str, values: np.ndarray) -> str:
    """One formatted line per row, in one str.format call (np.savetxt formats row by row)."""
    if len(values) == 0:
        return ""
    return "\n".join([line] * len(values)).format(*values.ravel().tolist())


def material_of(asset: MeshAsset, textured: bool = True):
    """The asset's double-sided (a sheet) PBR material, with its textures."""
    from trimesh.visual.material import PBRMaterial

    texture = asset.texture if textured else None
    return PBRMaterial(
        name=asset.material_name,  # one material for every level of detail
        baseColorFactor=[255, 255, 255, 255] if texture is not None else [*BLADE, 255],
        baseColorTexture=texture,
        normalTexture=asset.normal_map if textured else None,
        metallicFactor=METALLIC,
        roughnessFactor=ROUGHNESS,
        doubleSided=not asset.solid,
        # a sheet's texture cuts the outline out; a solid is opaque (its walls sample the edge)
        alphaMode="MASK" if texture is not None and not asset.solid else "OPAQUE",
        alphaCutoff=ALPHA_CUTOFF if texture is not None and not asset.solid else None,
    )


def to_trimesh(asset: MeshAsset, textured: bool = True, material=None):
    """A trimesh.Trimesh of the asset: its normals, UVs, PBR material and scalars."""
    import trimesh
    from trimesh.visual import TextureVisuals

    material = material if material is not None else material_of(asset, textured)
    mesh = trimesh.Trimesh(
        vertices=asset.points,
        faces=asset.faces,
        vertex_normals=asset.normals,
        visual=TextureVisuals(uv=asset.uv, material=material),
        process=False,
        validate=False,
    )
    for name, values in asset.point_data.items():
        mesh.vertex_attributes[f"_{name.upper()}"] = np.asarray(values, np.float32)
    tangents = asset.tangents() if textured and asset.normal_map is not None else None
    if tangents is not None:  # renamed TANGENT in the written file (_standard_names)
        mesh.vertex_attributes[_TANGENT] = tangents.astype(np.float32)
    return mesh


_TANGENT = "_TANGENT"  # trimesh writes custom attributes only, with a leading underscore


def _standard_names(tree: dict) -> None:
    """glTF tree post-processor: the tangents written as a custom attribute become TANGENT, and
    a sheet's material (double-sided) is translucent (`translucent`)."""
    for mesh in tree.get("meshes", []):
        for primitive in mesh.get("primitives", []):
            attributes = primitive.get("attributes", {})
            if _TANGENT in attributes:
                attributes["TANGENT"] = attributes.pop(_TANGENT)
    sheets = [m for m in tree.get("materials", []) if m.get("doubleSided")]
    for material in sheets:
        translucent(material)
    if sheets:
        used = tree.setdefault("extensionsUsed", [])
        used += [name for name in TRANSLUCENT_EXTENSIONS if name not in used]


def translucent(material: dict) -> None:
    """A glTF material (a JSON dict) given the leaf's translucency (material.py): the
    transmission factor, and the diffuse transmission coloured by the base colour texture (the
    light through a blade takes its colour; without a texture, the base colour factor's)."""
    pbr = material.get("pbrMetallicRoughness", {})
    diffuse: dict = {"diffuseTransmissionFactor": DIFFUSE_TRANSMISSION}
    if "baseColorTexture" in pbr:
        diffuse["diffuseTransmissionColorTexture"] = dict(pbr["baseColorTexture"])
    else:
        diffuse["diffuseTransmissionColorFactor"] = pbr.get("baseColorFactor", [1, 1, 1, 1])[:3]
    extensions = material.setdefault("extensions", {})
    extensions[TRANSLUCENT_EXTENSIONS[0]] = {"transmissionFactor": TRANSMISSION}
    extensions[TRANSLUCENT_EXTENSIONS[1]] = diffuse


MSFT_LOD = "MSFT_lod"


def levels_of_detail(tree: dict, names: Sequence[str]) -> None:
    """glTF tree post-processor: the nodes `names` (finest first) become levels of detail as
    the MSFT_lod spec has them: the scene shows the first; the others leave the scene, listed
    by its `MSFT_lod` ids, with `MSFT_screencoverage` in its extras.

    A reader without MSFT_lod (Blender 4.5) gets one leaf, not every level on top of each
    other. Each level has half the triangles of the one before, so it takes over at half the
    screen coverage (triangles as big on screen): 1/2, 1/4, ...; the last is drawn down to 0."""
    index = {node.get("name"): k for k, node in enumerate(tree["nodes"])}
    top, *coarser = (index[name] for name in names)
    for holder in [*tree.get("scenes", []), *tree["nodes"]]:
        for key in ("nodes", "children"):
            if key in holder:
                holder[key] = [k for k in holder[key] if k not in coarser]
    node = tree["nodes"][top]
    node.setdefault("extensions", {})[MSFT_LOD] = {"ids": coarser}
    coverage = [0.5 ** (level + 1) for level in range(len(coarser))]
    node.setdefault("extras", {})["MSFT_screencoverage"] = [*coverage, 0.0]
    used = tree.setdefault("extensionsUsed", [])
    if MSFT_LOD not in used:
        used.append(MSFT_LOD)


def write_gltf(assets: Sequence[MeshAsset], path: Path) -> None:
    """glTF 2.0 (.glb binary, or .gltf with embedded buffers): one mesh per asset; more than
    one are levels of detail (`levels_of_detail`), the scene showing the first."""
    import trimesh
    from trimesh.exchange.gltf import export_glb, export_gltf

    scene = trimesh.Scene()
    materials: dict[tuple[int, int, bool], object] = {}  # levels share one material and image
    for asset in assets:
        key = (id(asset.texture), id(asset.normal_map), asset.solid)
        material = materials.setdefault(key, material_of(asset))
        mesh = to_trimesh(asset, material=material)
        scene.add_geometry(mesh, geom_name=asset.name, node_name=asset.name)

    def postprocess(tree: dict) -> None:
        _standard_names(tree)
        if len(assets) > 1:
            levels_of_detail(tree, [asset.name for asset in assets])

    if path.suffix.lower() == ".glb":
        data = export_glb(scene, include_normals=True, tree_postprocessor=postprocess)
    else:
        files = export_gltf(
            scene, include_normals=True, embed_buffers=True, tree_postprocessor=postprocess
        )
        data = files["model.gltf"]
    write_bytes(path, data)


def write_trimesh_format(asset: MeshAsset, path: Path) -> None:
    """STL or 3MF through trimesh (geometry only)."""
    if path.suffix.lower() == ".stl":
        check_32_bit(asset.points, asset.faces, path)
    mesh = to_trimesh(asset, textured=False)
    kind = path.suffix.lower().lstrip(".")
    write_bytes(path, mesh.export(file_type=kind))


def check_32_bit(points: np.ndarray, faces: np.ndarray, path: Path) -> None:
    """Refuse a mesh that a format of 32-bit coordinates (STL) cannot hold: one whose distinct
    (n, 3) `points` its rounding merges at a corner of a face. A leaf of length 1 lying 1e5 from
    the origin (the floats 8e-3 apart there) had 96 faces so merged, its area 9% off, and a
    solid 1e-3 thick read back not closed. (Slivers whose corners stay apart are kept.)"""
    wide = np.asarray(points, dtype=float)
    narrow = wide.astype(np.float32)
    corners = np.asarray(faces)[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    merged = (narrow[corners[:, 0]] == narrow[corners[:, 1]]).all(axis=1)
    merged &= (wide[corners[:, 0]] != wide[corners[:, 1]]).any(axis=1)  # apart before
    if merged.any():
        lost = int(merged.reshape(-1, 3).any(axis=1).sum())
        far = float(np.abs(wide).max())
        size = float(np.ptp(wide, axis=0).max())
        raise LeafError(
            f"{path.suffix.lower()} keeps 32-bit coordinates, which would merge corners of "
            f"{lost} faces of this mesh (size {size:.3g}, {far:.3g} from the origin); move the "
            "leaf nearer the origin, or write .ply or .3mf",
            str(path),
        )


def write_vtk(asset: MeshAsset, path: Path) -> None:
    """.vtp or .vtk through pyvista, with Normals, texture coordinates and the scalars."""
    mesh = polydata(asset.points, asset.faces, asset.point_data, normals=asset.normals)
    mesh.active_texture_coordinates = asset.uv.copy()
    write_bytes(path, vtk_bytes(mesh, path.suffix.lower()))


def write_assets(assets: Sequence[MeshAsset], path: Path) -> None:
    """Write the assets (the mesh, then its coarser levels) by the path's suffix: glTF and USD
    hold them all; other formats write level k > 0 beside it as `<stem>_lod<k><suffix>`."""
    suffix = path.suffix.lower()
    if suffix in LEVELS_IN_ONE:
        WRITERS[suffix](assets, path)
        return
    writer = WRITERS[suffix]
    for level, asset in enumerate(assets):
        writer(asset, path if level == 0 else lod_path(path, level))


def written_paths(path: Path, levels: int, textured: bool) -> list[Path]:
    """Every file `write_assets` writes for `levels` levels at `path`."""
    suffix = path.suffix.lower()
    if suffix in GLTF_SUFFIXES or suffix == ".usdz":
        return [path]
    if suffix in USD_SUFFIXES:  # the textures beside it
        return [path, *usd_companions(path)] if textured else [path]
    out = []
    for level in range(levels):
        target = path if level == 0 else lod_path(path, level)
        out.append(target)
        if suffix == ".obj":
            mtl, png = obj_companions(target)
            out += [mtl, png] if textured else [mtl]
    return out


def lod_path(path: Path, level: int) -> Path:
    """Where a format without levels of detail gets level `level`."""
    return path.with_name(f"{path.stem}_lod{level}{path.suffix}")


def vtk_bytes(mesh: Any, suffix: str) -> bytes:
    """A mesh as .vtp (XML, zlib-compressed base64) or legacy binary .vtk, made in memory: VTK's
    file writers report a failed write only through their observers (and an XML writer aborts
    the process when a disk fills), so the bytes are written by Python, which raises."""
    from vtkmodules.vtkIOLegacy import vtkPolyDataWriter
    from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

    if suffix == ".vtp":
        writer = vtkXMLPolyDataWriter()
        writer.SetDataModeToBinary()  # base64 inline: the output string is plain ASCII
        writer.SetCompressorTypeToZLib()
    else:
        writer = vtkPolyDataWriter()
        writer.SetFileTypeToBinary()
    writer.SetInputData(mesh)
    writer.SetWriteToOutputString(True)
    if writer.Write() != 1:
        raise LeafError(f"VTK could not encode the mesh as {suffix}")
    if suffix == ".vtp":
        return writer.GetOutputString().encode("ascii")
    return bytes(writer.GetOutputStdString())


# The one table of mesh types: every suffix a mesh can be written as, and its writer (glTF's
# and USD writers take every level of detail at once; `write_assets` calls them apart).
WRITERS = {
    ".ply": write_ply,
    ".obj": write_obj,
    ".stl": write_trimesh_format,
    ".vtp": write_vtk,
    ".vtk": write_vtk,
    ".glb": write_gltf,
    ".gltf": write_gltf,
    ".3mf": write_trimesh_format,
    ".usda": write_usd,
    ".usdc": write_usd,
    ".usdz": write_usd,
}
MESH_SUFFIXES = tuple(WRITERS)
