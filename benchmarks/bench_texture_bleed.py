"""What edge padding (texture.bleed: alpha-0 texels take the nearest leaf texel's colour) costs:
CPU and wall time of `bleed` on the 1024^2 generated and photo textures, and their PNG sizes
without and with it. Prints JSON.

    .venv/bin/python benchmarks/bench_texture_bleed.py
"""

from __future__ import annotations

import io
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def _png_bytes(image) -> int:
    buffer = io.BytesIO()
    image.save(buffer, format="PNG")  # as writers._png saves it
    return len(buffer.getvalue())


def main(repeats: int = 5) -> dict:
    from unittest import mock

    from PIL import Image

    import leafstudio as ls
    from leafstudio.assets import texture
    from leafstudio.assets.export import base_color
    from leafstudio.forms import make_form
    from leafstudio.sources.leafphoto import PhotoTexture
    from leafstudio.sources.photo import leaf_from_photo
    from tests.photos import form_photo

    form = make_form("ovate", margin="serrate", teeth=24)
    image, _, _ = form_photo(form.boundary, form.veins, angle=-40)
    found = leaf_from_photo(image, veins="none")
    photo_leaf = ls.reconstruct(found.leaf, ls.Params(k=1, grid=48, samples=800))
    generated_leaf = ls.reconstruct(form, ls.Params(k=1, grid=48, samples=800))
    out = {"pixels": texture.TEXTURE_PIXELS, "repeats": repeats, "load": os.getloadavg()[0]}
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "photo.png"
        Image.fromarray(image).save(path)
        cases = {
            "generated": (generated_leaf, "auto"),
            "photo": (photo_leaf, PhotoTexture(path, found.pixel_from_world)),
        }
        for name, (result, option) in cases.items():
            with mock.patch.object(texture, "bleed", lambda image: image):
                plain = base_color(result, option)
            padded = base_color(result, option)
            cpu, wall = [], []
            for _ in range(repeats):
                c, w = time.process_time(), time.perf_counter()
                texture.bleed(plain)
                cpu.append(time.process_time() - c)
                wall.append(time.perf_counter() - w)
            out[name] = {
                "bleed_cpu_ms": round(1000 * statistics.median(cpu), 1),
                "bleed_wall_ms": round(1000 * statistics.median(wall), 1),
                "png_bytes_without": _png_bytes(plain),
                "png_bytes_with": _png_bytes(padded),
            }
    return out


if __name__ == "__main__":
    print(json.dumps(main(), indent=1))
