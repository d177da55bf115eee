"""Assets for 3D tools: meshes with normals, UVs and textures (glTF, OBJ, PLY, ...), solid leaves
for printing, levels of detail, and leaves from photos (DESIGN.md: assets)."""

from leafstudio.assets.asset import MeshAsset, UVMap, leaf_asset, mesh_asset
from leafstudio.assets.export import PhotoTexture, export_mesh, mesh_assets, photo_transform
from leafstudio.assets.writers import ASSET_SUFFIXES

__all__ = [
    "ASSET_SUFFIXES",
    "MeshAsset",
    "PhotoTexture",
    "UVMap",
    "export_mesh",
    "leaf_asset",
    "mesh_asset",
    "mesh_assets",
    "photo_transform",
]
