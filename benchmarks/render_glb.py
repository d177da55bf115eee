"""Render .glb files as an importer sees them (trimesh reads the file: mesh, UVs, base-colour
texture), off screen with pyvista, side by side into one PNG.

    .venv/bin/python benchmarks/render_glb.py OUT.png LEAF.glb [MORE.glb ...]
"""

from __future__ import annotations

import sys

import numpy as np


def render(paths: list[str], out: str, size: int = 700) -> None:
    import pyvista as pv
    import trimesh

    width = size * len(paths)
    plotter = pv.Plotter(off_screen=True, shape=(1, len(paths)), window_size=(width, size))
    for i, path in enumerate(paths):
        scene = trimesh.load(path, process=False)
        mesh = next(iter(scene.geometry.values())) if isinstance(scene, trimesh.Scene) else scene
        faces = np.hstack([np.full((len(mesh.faces), 1), 3), mesh.faces]).ravel()
        poly = pv.PolyData(np.asarray(mesh.vertices), faces)
        poly.point_data["Normals"] = np.asarray(mesh.vertex_normals)
        plotter.subplot(0, i)
        plotter.set_background("white")
        image = getattr(mesh.visual.material, "baseColorTexture", None)
        if image is not None:
            poly.active_texture_coordinates = np.asarray(mesh.visual.uv, float)
            opaque = getattr(mesh.visual.material, "alphaMode", None) in (None, "OPAQUE")
            rgba = np.asarray(image.convert("RGB" if opaque else "RGBA"))[::-1].copy()  # rows up
            plotter.add_mesh(poly, texture=pv.Texture(rgba), smooth_shading=True)
        else:
            plotter.add_mesh(poly, color=(0.3, 0.5, 0.2), smooth_shading=True)
        plotter.add_text(path.rsplit("/", 1)[-1], font_size=10, color="black")
        plotter.view_isometric()
        plotter.camera.zoom(1.3)
    plotter.screenshot(out)
    plotter.close()


if __name__ == "__main__":
    render(sys.argv[2:], sys.argv[1])
