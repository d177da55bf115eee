"""What every textured format shares: the leaf material's constants, the texture's file name
beside a mesh, and images as PNG bytes (writers.py and usd.py both use them)."""

from __future__ import annotations

from io import BytesIO
from typing import Any

METALLIC, ROUGHNESS, ALPHA_CUTOFF = 0.0, 0.8, 0.5
# A sheet's translucency (light through a thin blade, against the sun), written in glTF twice:
# KHR_materials_transmission (ratified; the one Blender's importer reads, as the Principled
# BSDF's Transmission Weight; the validator checks it) and KHR_materials_diffuse_transmission
# (the leaf's own model, a Lambertian lobe through the blade, for renderers that know it; not
# yet ratified, neither Blender 4.5's nor 5.0's importer reads it). Where both are read, the
# first takes its share and the second the rest (the diffuse-transmission spec's mix). An OBJ's
# MTL carries the first as `Tf` (Blender's OBJ importer reads it as the Transmission Weight).
TRANSMISSION = 0.2  # the share of the diffuse lobe turned into rough transmission
DIFFUSE_TRANSMISSION = 0.4  # the share of the diffuse lobe transmitted, Lambertian
TRANSLUCENT_EXTENSIONS = ("KHR_materials_transmission", "KHR_materials_diffuse_transmission")
TEXTURE_SUFFIX = "_texture.png"  # a mesh's texture beside it: oak.obj -> oak_texture.png


def png_bytes(image: Any) -> bytes:
    """A PIL image as PNG file bytes."""
    buffer = BytesIO()
    image.save(buffer, format="PNG")
    return buffer.getvalue()
