"""From a Result (or any triangle mesh) to the files 3D tools read: texture, solid and levels of
detail chosen here, the bytes written by writers.py.

`texture`:
- "auto": the generated leaf texture (blade and veins, texture.py) and, in glTF, a normal map;
- "none": no image (the material has the blade's colour; UVs are still written);
- an image path: mapped through the UVs. If the leaf came from that photo (`leafstudio photo`
  stores the map from the leaf's coordinates to the photo's pixels in the project), each pixel
  lands where it was in the photo, and glTF and USD get the normal map of its veins (traced in
  the photo, so they lie on the photo's); otherwise the image covers the UV square as it is.
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from leafstudio._shared import safewrite
from leafstudio._shared.inputs import load_json, read_image
from leafstudio._shared.safewrite import refuse_overlap
from leafstudio.assets import texture as tex
from leafstudio.assets.asset import MeshAsset, leaf_asset, leaf_plane, mesh_asset
from leafstudio.assets.lod import coarser_levels
from leafstudio.assets.placement import mesh_placement, parse_length, place, result_placement
from leafstudio.assets.solid import bent_offsets, parse_thickness, thicken, thickness_in_mesh_units
from leafstudio.assets.writers import MESH_SUFFIXES, write_assets, written_paths
from leafstudio.errors import LeafError
from leafstudio.sources.leafphoto import PhotoTexture, pixel_map, project_photo

TEXTURES = ("auto", "none")
MAX_LOD = 8
TEXTURED_SUFFIXES = (".obj", ".glb", ".gltf", ".usda", ".usdc", ".usdz")  # carry a texture image
NORMAL_MAP_SUFFIXES = (".glb", ".gltf", ".usda", ".usdc", ".usdz")  # and a normal map


def photo_transform(leaf_path: str | os.PathLike) -> np.ndarray | None:
    """The (2, 3) world-to-pixel map a `leafstudio photo` project stores, or None (not a project,
    or a project without a photo); LeafError for a malformed entry.

    Parameters
    ----------
    leaf_path : str or path-like
        The leaf file a mesh is made from.

    Returns
    -------
    (2, 3) float array or None
        Maps a leaf point's (x, y, 1) to the photo's (column, row).

    Raises
    ------
    LeafError
        For a project whose "photo" entry is malformed.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> import leafstudio as ls
    >>> path = Path(tempfile.mkdtemp()) / "leaf.leaf.json"
    >>> photo = {"image": "leaf.png", "pixel_from_world": [[100, 0, 10], [0, -100, 50]]}
    >>> ls.save_leaf(ls.demo("nested"), path, photo=photo)
    >>> photo_transform(path).tolist()
    [[100.0, 0.0, 10.0], [0.0, -100.0, 50.0]]
    >>> photo_transform(path.with_name("leaf.csv")) is None
    True
    """
    if not str(leaf_path).lower().endswith(".json"):
        return None
    data = load_json(leaf_path)
    photo = data.get("photo") if isinstance(data, dict) else None
    if photo is None:
        return None
    return pixel_map(photo, str(leaf_path))


def _images(result: Any, texture: Any, gltf: bool) -> dict[str, Any]:
    """The texture (and, for glTF, normal map) images the option asks for, made once for all the
    levels of detail (they share the UV map)."""
    if isinstance(texture, str) and texture in TEXTURES:
        if texture == "none" or result is None:  # a bare mesh: no outline or veins to draw
            return {}
        plane = leaf_plane(result)
        strokes = tex.vein_strokes(plane, tex.TEXTURE_PIXELS)
        maps = tex.normal_map(plane, strokes=strokes) if gltf else None
        return {"texture": tex.leaf_texture(plane, strokes=strokes), "normal_map": maps}
    photo = texture if isinstance(texture, PhotoTexture) else PhotoTexture(texture)
    image = read_image(photo.image)
    if photo.pixel_from_world is not None and result is not None:  # the veins lie on the photo's
        plane = leaf_plane(result)
        maps = tex.normal_map(plane) if gltf else None
        return {"texture": tex.photo_texture(plane, image, photo.pixel_from_world),
                "normal_map": maps}  # fmt: skip
    return {"texture": tex.stretched_texture(image)}


def base_color(result: Any, texture: Any = "auto") -> Any:
    """The base-colour texture an export with this `texture` option writes for `result` (an
    RGBA or RGB PIL image, row 0 at t = 1), or None for "none"; the app draws it on the mesh."""
    return _images(result, texture, gltf=False).get("texture")


Progress = Callable[[float, str], object]  # (fraction done, what is being done)


def _silent(_fraction: float, _what: str) -> None:
    """The progress report of an export nobody watches."""


def mesh_assets(
    result_or_mesh: Any,
    texture: Any = "auto",
    thickness: float | None = None,
    lod: int = 0,
    gltf: bool = False,
    progress: Progress = _silent,
    name: str = "leaf",
) -> list[MeshAsset]:
    """The asset (and `lod` coarser ones) of a Result or a bare mesh.

    Parameters
    ----------
    result_or_mesh : Result, TriangleMesh or pyvista.PolyData
        A Result gets the surface's closed-form normals and its generated texture; a bare
        mesh area-weighted normals and no image ("auto" then means none).
    texture : "auto", "none", an image path or a PhotoTexture, default: "auto"
    thickness : float, optional
        Turn the sheet into a closed solid this thick (in the mesh's units; solid.py).
    lod : int, default: 0
        Coarser levels of detail to add, each with half the triangles of the one before (lod.py).
    gltf : bool, default: False
        Whether the target holds a normal map (glTF and USD do; the other formats do not).
    progress : callable, optional
        Called as progress(fraction, what) before each step (the mesh, each level of detail,
        the textures, each solid), fraction in [0, 0.8] (save_mesh reports the rest).
    name : str, default: "leaf"
        The mesh's name inside its file (save_mesh gives the file's: object_name).

    Returns
    -------
    list of MeshAsset
        `lod` + 1 assets, finest first, named `name` (or `name`_LOD0, `name`_LOD1, ...).

    Raises
    ------
    LeafError
        For an image that cannot be read, or a thickness the mesh cannot take.

    Examples
    --------
    >>> import leafstudio as ls
    >>> result = ls.reconstruct(ls.demo("nested"), ls.Params(k=3, grid=32))
    >>> [(a.name, len(a.faces)) for a in mesh_assets(result, texture="none")]
    [('leaf', 504)]
    >>> solid = mesh_assets(result, texture="none", thickness=0.01)[0]
    >>> solid.solid, len(solid.faces) > 2 * 504  # both sides and the rim
    (True, True)

    With open3d installed (the `open3d` extra), `lod=1` adds a level with half the triangles:
    `[('leaf_LOD0', 504), ('leaf_LOD1', 252)]`.
    """
    result = result_or_mesh if hasattr(result_or_mesh, "surface") else None
    progress(0.0, "the mesh")
    if result is not None:
        base = leaf_asset(result)
    else:
        base = mesh_asset(getattr(result_or_mesh, "triangle_mesh", result_or_mesh))
    levels = [base]
    if lod:
        progress(0.1, f"{lod} levels of detail")
        levels += coarser_levels(base, result, lod)
    progress(0.4, "the textures")
    images = _images(result, texture, gltf)
    out = []
    for level, asset in enumerate(levels):
        if thickness is not None:
            progress(0.6 + 0.2 * level / len(levels), f"the solid ({level + 1}/{len(levels)})")
            bent = result is not None and result.leaf.bend is not None
            asset = thicken(
                asset,
                thickness,
                partial(bent_offsets, result, thickness=thickness) if bent else None,
            )
        out.append(asset.with_(name=f"{name}_LOD{level}" if lod else name, **images))
    return out


def object_name(path: str | os.PathLike) -> str:
    """The name a mesh gets inside its file: the file's, without its suffixes, so that leaves
    imported side by side (Blender, an engine) are told apart; letters, digits, '-' and '_'
    only (an OBJ name ends at a space); "leaf" when none is left.

    >>> object_name("out/Oak leaf 2.glb"), object_name("oak.leaf.obj"), object_name(".glb")
    ('Oak_leaf_2', 'oak', 'leaf')
    """
    stem = Path(path).name.split(".")[0]
    return re.sub(r"[^\w-]+", "_", stem).strip("_") or "leaf"


def save_mesh(
    result_or_mesh: Any,
    path: str | os.PathLike,
    texture: Any = "auto",
    thickness: float | None = None,
    lod: int = 0,
    length: str | float | None = None,
    placement: Any = None,
    progress: Progress = _silent,
) -> None:
    """Write the mesh by the path's suffix (MESH_SUFFIXES) with normals, UVs, scalars, texture,
    placed for the format (placement.py: glTF, OBJ and USD Y-up with the base at the origin).

    Every file is replaced atomically, and together with its companions (an OBJ's .mtl and
    texture, the levels of detail): a failed write leaves the old files as they were.

    Parameters
    ----------
    result_or_mesh : Result, TriangleMesh or pyvista.PolyData
        What to write (see `mesh_assets`).
    path : str or path-like
        .ply, .obj (with .mtl and _texture.png beside it), .stl, .vtp, .vtk, .glb, .gltf,
        .3mf, .usda, .usdc, .usdz (`assets/writers.WRITERS`).
    texture : "auto", "none", an image path or a PhotoTexture, default: "auto"
        The image of formats that carry one (OBJ, glTF, USD); "auto" generates the leaf's.
    thickness : float, optional
        Write a closed solid this thick (in the mesh's units).
    lod : int, default: 0
        Coarser levels of detail to add (0 to 8): glTF and USD keep them in the file, the other
        formats write NAME_lod1.EXT, ...
    length : str or float, optional
        The leaf's real length, base to apex: '8cm', '0.08m', '80mm', '3in' (units mm, cm, m,
        in, ft), or metres. The leaf is scaled to it and written in metres (glTF, OBJ, USD) or
        millimetres (PLY, STL, 3MF, VTK).
        Default: the coordinates keep their scale.
    placement : Placement, optional
        Where the leaf's base and axes are (placement.py); default: a Result's own (its midrib
        and outline), a bare mesh's from its margin's plane.
    progress : callable, optional
        Called as progress(fraction, what) before each step, and progress(1, "done") at the
        end (the app's progress bar; from the thread that writes).

    Raises
    ------
    LeafError
        For an unknown suffix, a bad option, an image that would be overwritten, or a file
        that cannot be written.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> import leafstudio as ls
    >>> result = ls.reconstruct(ls.demo("nested"), ls.Params(k=3, grid=32))
    >>> folder = Path(tempfile.mkdtemp())
    >>> ls.save_mesh(result, folder / "leaf.obj")
    >>> sorted(p.name for p in folder.iterdir())
    ['leaf.mtl', 'leaf.obj', 'leaf_texture.png']
    >>> ls.save_mesh(result, folder / "leaf.xyz")
    Traceback (most recent call last):
    leafstudio.errors.LeafError: .../leaf.xyz: unknown mesh type '.xyz'; use one of .ply, ...
    """
    metres = None if length is None else parse_length(length)
    path = check_mesh_path(path)
    suffix = path.suffix.lower()
    if not isinstance(lod, int) or not 0 <= lod <= MAX_LOD:
        raise LeafError(f"lod must be a whole number from 0 to {MAX_LOD}, got {lod}")
    if not (isinstance(texture, str) and texture in TEXTURES):  # never write over the image
        image = texture.image if isinstance(texture, PhotoTexture) else texture
        refuse_overlap([image], written_paths(path, lod + 1, textured=True))
    if suffix not in TEXTURED_SUFFIXES:  # the format holds UVs but no image: make none
        texture = "none"
    gltf = suffix in NORMAL_MAP_SUFFIXES
    assets = mesh_assets(result_or_mesh, texture, thickness, lod, gltf, progress, object_name(path))
    progress(0.8, "placing")
    assets = placed(result_or_mesh, assets, metres, suffix, placement)
    progress(0.85, f"writing {path.name}")
    if safewrite._staging.get() is not None:  # the caller replaces its outputs together
        write_assets(assets, path)
    else:
        with safewrite.staged():  # an .obj, its .mtl and .png (and the levels) together
            write_assets(assets, path)
    progress(1.0, "done")


def check_mesh_path(path: str | os.PathLike) -> Path:
    """The path, if its suffix is a mesh type (MESH_SUFFIXES); LeafError naming it if not."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES:
        raise LeafError(
            f"unknown mesh type {suffix or '(none)'!r}; use one of {', '.join(MESH_SUFFIXES)}",
            str(path),
        )
    return path


def placed(
    result_or_mesh: Any,
    assets: list[MeshAsset],
    metres: float | None,
    suffix: str,
    placement: Any = None,
) -> list[MeshAsset]:
    """The assets placed for the format `suffix` and scaled to `metres` (placement.py)."""
    placement = placement if placement is not None else leaf_placement_of(result_or_mesh)
    return [place(asset, placement, metres, suffix) for asset in assets]


def leaf_placement_of(result_or_mesh: Any):
    """The Placement of a Result (its midrib and outline), or of a bare mesh (its margin's PCA
    plane)."""
    if hasattr(result_or_mesh, "surface"):
        return result_placement(result_or_mesh)
    asset = mesh_asset(getattr(result_or_mesh, "triangle_mesh", result_or_mesh))
    return mesh_placement(asset.points, asset.faces, asset.plane_normal)


def check_asset_options(
    texture: str, thickness: str | None, lod: int, length: str | None = None
) -> None:
    """Refuse bad --texture, --thickness, --lod and --length values before any work
    (LeafError)."""
    if texture not in TEXTURES:
        read_image(texture)
    if thickness is not None:
        parse_thickness(thickness)
    if not 0 <= lod <= MAX_LOD:
        raise LeafError(f"--lod must be a whole number from 0 to {MAX_LOD}, got {lod}")
    if length is not None:
        parse_length(length)


def asset_options(
    texture: str,
    thickness: str | None,
    lod: int,
    leaf_path: str | os.PathLike,
    result: Any,
    length: str | None = None,
    placement: Any = None,
) -> dict[str, Any]:
    """save_mesh's keyword arguments from the command line's: an image texture is a photo the
    leaf came from when the leaf's project says so; the thickness in the mesh's units (a length
    with its unit is real size when --length gives the leaf's); the result's placement, found
    once (`placement`, when the caller has it already)."""
    if texture not in TEXTURES:  # the project's own photo goes back where it was; another
        own = project_photo(leaf_path)  # image covers the texture as it is (issue 24, #15)
        same = own is not None and Path(texture).resolve() == own.image
        texture = PhotoTexture(texture, own.pixel_from_world if same else None)
    metres = None if length is None else parse_length(length)
    placement = placement if placement is not None else leaf_placement_of(result)
    per_unit = None if metres is None else metres / placement.length
    solid = None
    if thickness is not None:
        solid = thickness_in_mesh_units(thickness, placement.length, per_unit)  # the blade's
    return {
        "texture": texture,
        "thickness": solid,
        "lod": lod,
        "length": metres,
        "placement": placement,
    }
