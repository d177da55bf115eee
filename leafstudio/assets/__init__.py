"""Assets for 3D tools: meshes with normals, UVs and textures (glTF, OBJ, PLY, ...), solid leaves
for printing, levels of detail, and leaves from photos (docs/architecture.md, "Where to add")."""

from leafstudio.assets.asset import MeshAsset, UVMap, leaf_asset, mesh_asset
from leafstudio.assets.export import mesh_assets, photo_transform, save_mesh
from leafstudio.assets.writers import MESH_SUFFIXES
from leafstudio.sources.leafphoto import PhotoTexture

__all__ = [
    "MESH_SUFFIXES",
    "MeshAsset",
    "PhotoTexture",
    "UVMap",
    "leaf_asset",
    "mesh_asset",
    "mesh_assets",
    "photo_transform",
    "save_mesh",
]
