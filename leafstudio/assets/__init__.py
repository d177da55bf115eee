"""Assets for 3D tools: meshes with normals, UVs and textures (glTF, OBJ, PLY, ...), solid leaves
for printing, levels of detail, and leaves from photos (docs/architecture.md, "Where to add")."""

import lazy_loader

# light (numpy and the image reader): imported now
from leafstudio.sources.leafphoto import PhotoTexture as PhotoTexture

# imported on first use: `from leafstudio.assets.units import ...` (the command line's help)
# then does not load the writers, the textures and the photo and form code behind them
__getattr__, _lazy_dir, _lazy_all = lazy_loader.attach(
    __name__,
    submod_attrs={
        "asset": ["MeshAsset", "UVMap", "leaf_asset", "mesh_asset"],
        "export": ["mesh_assets", "photo_transform", "save_mesh"],
        "writers": ["MESH_SUFFIXES"],
    },
)
__all__ = sorted([*_lazy_all, "PhotoTexture"])


def __dir__() -> list[str]:
    """The public names, the ones not imported yet included."""
    return list(__all__)
