"""Import a LeafStudio .glb (or .gltf, .obj, .usda, .usdc, .usdz) into Blender (the `bpy`
package) and print what arrived, as JSON: the meshes shown (and those hidden: a glTF's coarser
levels of detail), UV layers, the material and its image texture, the vertex count beside the
file's (glTF), the extent of the meshes shown in metres along Blender's x, y, z (z up): a leaf
lying flat has its relief as the z extent and its apex at its length along x, and its vertex
nearest the origin (the base is there).

The issue's client is Blender 4.5 LTS (bpy 4.5 is built for Python 3.11); bpy pins numpy < 2, so
it lives in a venv of its own, not the project's:
    python3.11 -m venv /tmp/bpy45 && /tmp/bpy45/bin/pip install "bpy==4.5.*"
    .venv/bin/leafstudio reconstruct leaf.leaf.json -o leaf.glb
    /tmp/bpy45/bin/python benchmarks/check_blender.py leaf.glb [--render PNG]

--length L (metres, the length the leaf was exported at) adds the issue's checks (`checks`).
--render also renders the imported scene with Cycles on the CPU (a sun, a camera above);
--engine eevee renders with Eevee instead, --backlit puts the sun behind the leaf (translucency).
For each material the report names the Principled BSDF inputs fed by an image (Base Color, Alpha,
Normal) and its Transmission Weight (glTF's KHR_materials_transmission), and a .glb's
extensions_used: Blender 4.5's importer reads KHR_materials_transmission, not
KHR_materials_diffuse_transmission, and USD's diffuseTransmission input not at all.
"""

from __future__ import annotations

import json
import struct
import sys


def glb_json(path: str) -> dict:
    """The GLB's JSON chunk."""
    with open(path, "rb") as handle:
        data = handle.read()
    length = struct.unpack_from("<I", data, 12)[0]
    return json.loads(data[20 : 20 + length])


def file_vertex_count(gltf: dict) -> int:
    """POSITION accessors' counts summed over the file's meshes."""
    return sum(
        gltf["accessors"][p["attributes"]["POSITION"]]["count"]
        for mesh in gltf["meshes"]
        for p in mesh["primitives"]
    )


def main(path: str) -> dict:
    import bpy
    from mathutils import Vector

    bpy.ops.wm.read_factory_settings(use_empty=True)
    suffix = path.lower().rsplit(".", 1)[-1]
    if suffix in ("glb", "gltf"):
        bpy.ops.import_scene.gltf(filepath=path)
    elif suffix == "obj":
        bpy.ops.wm.obj_import(filepath=path)
    else:
        bpy.ops.wm.usd_import(filepath=path)
    bpy.context.view_layer.update()
    meshes = shown_meshes()
    hidden = [o.name for o in bpy.context.scene.objects if o.type == "MESH" and o not in meshes]
    report = {"blender": bpy.app.version_string, "file": path, "meshes": len(meshes),
              "hidden_meshes": hidden}  # fmt: skip
    if suffix == "glb":  # the importer reads only the extensions it knows (Blender 4.5 and 5.0:
        # not KHR_materials_diffuse_transmission; the Transmission Weight is the other one's)
        gltf = glb_json(path)
        report["file_vertices"] = file_vertex_count(gltf)
        report["extensions_used"] = gltf.get("extensionsUsed", [])
    corners = [o.matrix_world @ Vector(c) for o in meshes for c in o.bound_box]
    report["extent_xyz"] = [
        round(max(c[i] for c in corners) - min(c[i] for c in corners), 6) for i in range(3)
    ]
    report["min_xyz"] = [round(min(c[i] for c in corners), 6) for i in range(3)]
    points = [o.matrix_world @ v.co for o in meshes for v in o.data.vertices]
    # the leaf's base is at the origin: its nearest vertex there (0 up to the mesh's spacing)
    report["nearest_vertex_to_origin"] = round(min(p.length for p in points), 6)
    report["objects"] = []
    for obj in meshes:
        mesh = obj.data
        materials = []
        for material in mesh.materials:
            images = [
                node.image.name
                for node in (material.node_tree.nodes if material.use_nodes else [])
                if node.type == "TEX_IMAGE" and node.image is not None
            ]
            sizes = [list(bpy.data.images[name].size) for name in images]
            materials.append(
                {"name": material.name, "image_textures": images, "image_sizes": sizes,
                 "backface_culling": material.use_backface_culling, **principled(material)}
            )  # fmt: skip
        report["objects"].append(
            {
                "name": obj.name,
                "vertices": len(mesh.vertices),
                "polygons": len(mesh.polygons),
                "uv_layers": [layer.name for layer in mesh.uv_layers],
                "materials": materials,
                "attributes": sorted(a.name for a in mesh.attributes if a.name.startswith("_")),
            }
        )
    return report


def shown_meshes() -> list:
    """The scene's mesh objects the view layer shows: not those in a collection it excludes
    (the glTF importer's "Orphan Nodes": a glTF's coarser levels of detail, outside its scene)."""
    import bpy

    return [o for o in bpy.context.scene.objects if o.type == "MESH" and o.visible_get()]


def principled(material) -> dict:
    """What the material's Principled BSDF has: the inputs a texture feeds (through any nodes:
    Base Color, Alpha, Normal) and its Transmission Weight (the glTF importer's reading of
    KHR_materials_transmission), or {} without one."""
    nodes = material.node_tree.nodes if material.use_nodes else []
    bsdf = next((n for n in nodes if n.type == "BSDF_PRINCIPLED"), None)
    if bsdf is None:
        return {}

    def from_image(socket) -> bool:
        links = list(socket.links)
        while links:
            node = links.pop().from_node
            if node.type == "TEX_IMAGE":
                return True
            links += [link for s in node.inputs for link in s.links]
        return False

    fed = [s.name for s in bsdf.inputs if s.is_linked and from_image(s)]
    weight = bsdf.inputs["Transmission Weight"]
    return {"textured_inputs": fed, "transmission_weight": round(weight.default_value, 4),
            "transmission_textured": weight.is_linked}  # fmt: skip


def checks(report: dict, length: float, suffix: str = "glb") -> dict:
    """The issue's client checks on a report of a `suffix` file, for a leaf exported at `length`
    metres: its vertex nearest the origin within 1% of the length (the base), its vertical extent
    under its width (lying flat, the relief up), its farthest point along x (the apex) at the length
    within 1% (a flat leaf's; a curled one's is nearer; a cordate leaf's lobes reach behind its
    base, past the origin), its materials' Base Color and Normal fed by images (an
    OBJ's Base Color only: its MTL names no normal map, assets/writers.py says why) and
    translucent (a Transmission Weight; USD has none), and one leaf shown (levels of detail
    beside it hidden)."""
    x, y, z = report["extent_xyz"]
    materials = [m for o in report["objects"] for m in o["materials"]]
    images = {"Base Color"} if suffix == "obj" else {"Base Color", "Normal"}
    return {
        "base_at_origin": report["nearest_vertex_to_origin"] <= 0.01 * length,
        "lies_flat": z < y,
        "apex_at_length": abs(report["min_xyz"][0] + x - length) <= 0.01 * length,
        "textured": all(images <= set(m.get("textured_inputs", [])) for m in materials),
        "translucent": all(m.get("transmission_weight", 0) > 0 for m in materials),
        "one_leaf_shown": report["meshes"] == 1,
    }


def render(
    out: str, pixels: int = 640, samples: int = 24, engine: str = "CYCLES", backlit: bool = False
) -> None:
    """Render the imported leaf from above and aside to `out` (Cycles on the CPU, or Eevee);
    `backlit` puts the sun behind the leaf, facing the camera (the translucency shows)."""
    import bpy
    from mathutils import Vector

    scene = bpy.context.scene
    meshes = shown_meshes()
    corners = [o.matrix_world @ Vector(c) for o in meshes for c in o.bound_box]
    lo = Vector([min(c[i] for c in corners) for i in range(3)])
    hi = Vector([max(c[i] for c in corners) for i in range(3)])
    centre, size = (lo + hi) / 2, max(hi - lo)
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    camera.location = centre + Vector((0.6, -0.9, 1.1)) * size
    camera.rotation_euler = (centre - camera.location).to_track_quat("-Z", "Y").to_euler()
    # Blender's default clip (0.1 to 100 m) cut the near half off a 6 cm leaf seen from 9 cm
    camera.data.clip_start, camera.data.clip_end = 0.01 * size, 100 * size
    scene.camera = camera
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", type="SUN"))
    sun.data.energy = 4.0
    sun.rotation_euler = (0.5, 0.3, 0.8)
    if backlit:  # the light from under the blade, toward the camera above it, exposed for the
        # glow (at 4 the light through the blade overexposes and AgX bleaches it)
        sun.rotation_euler = (camera.location - centre).to_track_quat("Z", "Y").to_euler()
        sun.rotation_euler.x += 3.1416
        sun.data.energy = 2.0
    scene.collection.objects.link(sun)
    world = bpy.data.worlds.new("world")
    world.color = (0.15, 0.15, 0.15) if backlit else (0.8, 0.8, 0.8)
    scene.world = world
    engines = scene.render.bl_rna.properties["engine"].enum_items.keys()
    if engine == "BLENDER_EEVEE" and engine not in engines:  # Blender 4.2 to 4.5's name
        engine = "BLENDER_EEVEE_NEXT"
    scene.render.engine = engine
    if engine == "CYCLES":
        scene.cycles.device = "CPU"
        scene.cycles.samples = samples
    else:
        scene.eevee.taa_render_samples = samples
    scene.render.resolution_x = scene.render.resolution_y = pixels
    scene.render.filepath = out
    bpy.ops.render.render(write_still=True)


def quietly(path: str, out: str | None = None, **how) -> dict:
    """main(path) (and render to `out`, `how` as render takes it) with Blender's own log lines
    sent to stderr (stdout is the JSON alone)."""
    import os

    sys.stdout.flush()
    saved = os.dup(1)
    os.dup2(2, 1)
    try:
        report = main(path)
        if out:
            render(out, **how)
        return report
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)


if __name__ == "__main__":
    args = sys.argv
    target = args[args.index("--render") + 1] if "--render" in args else None
    engine = args[args.index("--engine") + 1].upper() if "--engine" in args else "CYCLES"
    how = {"engine": "BLENDER_EEVEE" if engine == "EEVEE" else engine,
           "backlit": "--backlit" in args}  # fmt: skip
    report = quietly(args[1], target, **how)
    if "--length" in args:  # metres, as the leaf was exported (--length 0.08)
        suffix = args[1].lower().rsplit(".", 1)[-1]
        report["checks"] = checks(report, float(args[args.index("--length") + 1]), suffix)
    print(json.dumps(report, indent=1))
