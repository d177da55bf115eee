"""What every textured format shares: the leaf material's constants, the texture's file name
beside a mesh, and images as PNG bytes (writers.py and usd.py both use them)."""

from __future__ import annotations

from io import BytesIO
from typing import Any

METALLIC, ROUGHNESS, ALPHA_CUTOFF = 0.0, 0.8, 0.5
TEXTURE_SUFFIX = "_texture.png"  # a mesh's texture beside it: oak.obj -> oak_texture.png


def png_bytes(image: Any) -> bytes:
    """A PIL image as PNG file bytes."""
    buffer = BytesIO()
    image.save(buffer, format="PNG")
    return buffer.getvalue()
