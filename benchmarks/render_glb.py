"""Render .glb files as an importer sees them (trimesh reads the file: mesh, UVs, base-colour
texture, filtered as engines filter it: bilinear with mipmaps), off screen with pyvista, side by
side into one PNG. `--zoom Z` looks Z times closer at the leaf's margin (its vertex highest in
y) instead of the whole leaf; `--background dark` draws on a dark grey (a pale fringe shows);
`--size N` is each view's width and height in pixels (small: the far mipmaps).

    .venv/bin/python benchmarks/render_glb.py OUT.png LEAF.glb [MORE.glb ...] [--zoom Z]
        [--background white|dark] [--size N]
"""

from __future__ import annotations

import numpy as np


def render(
    paths: list[str], out: str, size: int = 700, zoom: float = 1.0, background: str = "white"
) -> None:
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
        plotter.set_background("#303030" if background == "dark" else "white")
        image = getattr(mesh.visual.material, "baseColorTexture", None)
        if image is not None:
            poly.active_texture_coordinates = np.asarray(mesh.visual.uv, float)
            opaque = getattr(mesh.visual.material, "alphaMode", None) in (None, "OPAQUE")
            rgba = np.asarray(image.convert("RGB" if opaque else "RGBA"))[::-1].copy()  # rows up
            texture = pv.Texture(rgba)
            texture.interpolate, texture.mipmap = True, True
            plotter.add_mesh(poly, texture=texture, smooth_shading=True)
        else:
            plotter.add_mesh(poly, color=(0.3, 0.5, 0.2), smooth_shading=True)
        label = "white" if background == "dark" else "black"
        plotter.add_text(path.rsplit("/", 1)[-1], font_size=10, color=label)
        plotter.view_isometric()
        plotter.camera.zoom(1.3)
        if zoom != 1.0:
            edge = np.asarray(mesh.vertices)[np.argmax(np.asarray(mesh.vertices)[:, 1])]
            shift = edge - np.asarray(plotter.camera.focal_point)
            plotter.camera.focal_point = tuple(edge)
            plotter.camera.position = tuple(np.asarray(plotter.camera.position) + shift)
            plotter.camera.zoom(zoom)
    plotter.screenshot(out)
    plotter.close()


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out")
    parser.add_argument("paths", nargs="+")
    parser.add_argument("--zoom", type=float, default=1.0)
    parser.add_argument("--background", choices=("white", "dark"), default="white")
    parser.add_argument("--size", type=int, default=700)
    args = parser.parse_args()
    render(args.paths, args.out, args.size, args.zoom, args.background)
