"""USD out: .usda (text), .usdc (crate), .usdz (a package with its textures), through usd-core.

One stage, Y-up (placement.py places the leaf), metersPerUnit 1, default prim /Leaf (an Xform of
kind component) holding the mesh /Leaf/Leaf and its material /Leaf/Looks/Leaf. The mesh has
vertex normals, UVs as primvars:st, the scalars as float primvars (height, curvatures), and the
material is a UsdPreviewSurface: base colour (and, from the texture's alpha, the cut-out outline
of a sheet) and a normal map from the textures, otherwise the blade's colour. A sheet is
double-sided, and its material carries its translucency as its own inputs (diffuseTransmission,
thinWalled; _translucency says why not as a shader). Levels of detail are the variant set "LOD"
on /Leaf, variants LOD0, LOD1, ... (LOD0 selected), each holding its own /Leaf/Leaf.

.usda and .usdc write their textures beside them (`<stem>_texture.png`, `<stem>_normal.png`);
.usdz packs them in.
"""

from __future__ import annotations

import re
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from leafstudio._shared.extras import require
from leafstudio._shared.safewrite import write_bytes
from leafstudio.assets.asset import MeshAsset
from leafstudio.assets.material import (
    ALPHA_CUTOFF,
    DIFFUSE_TRANSMISSION,
    METALLIC,
    ROUGHNESS,
    TEXTURE_SUFFIX,
    png_bytes,
)
from leafstudio.assets.texture import BLADE
from leafstudio.errors import LeafError

USD_SUFFIXES = (".usda", ".usdc", ".usdz")
ROOT, MESH, LOOKS = "/Leaf", "/Leaf/Leaf", "/Leaf/Looks"
NORMAL_SUFFIX = "_normal.png"
TRANSLUCENCY_INPUTS = {  # name: (Sdf value type, value, documentation)
    "diffuseTransmission": (
        "Float",
        DIFFUSE_TRANSMISSION,
        "Share of the diffuse light a sheet transmits through the blade, Lambertian and coloured "
        "by the base colour (glTF's KHR_materials_diffuse_transmission); UsdPreviewSurface has "
        "no input for it",
    ),
    "thinWalled": ("Bool", True, "The blade is a sheet with no inside (MDL's thin_walled)"),
}


def usd_companions(path: Path) -> tuple[Path, Path]:
    """The base-colour and normal-map images a .usda or .usdc at `path` refers to."""
    return path.with_name(f"{path.stem}{TEXTURE_SUFFIX}"), path.with_name(
        f"{path.stem}{NORMAL_SUFFIX}"
    )


def _pxr():
    require("pxr", "USD export (.usda, .usdc, .usdz)")
    from pxr import Gf, Kind, Sdf, Usd, UsdGeom, UsdShade, Vt

    return Gf, Kind, Sdf, Usd, UsdGeom, UsdShade, Vt


def _mesh(stage, asset: MeshAsset) -> None:
    """The asset as the UsdGeom.Mesh at MESH (in the current edit target)."""
    Gf, _, Sdf, _, UsdGeom, _, Vt = _pxr()
    mesh = UsdGeom.Mesh.Define(stage, MESH)
    points = np.asarray(asset.points, np.float32)
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(points))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(asset.faces), 3, np.int32)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(asset.faces.astype(np.int32).ravel()))
    mesh.CreateNormalsAttr(Vt.Vec3fArray.FromNumpy(np.asarray(asset.normals, np.float32)))
    mesh.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    mesh.CreateDoubleSidedAttr(not asset.solid)
    low, high = points.min(axis=0), points.max(axis=0)
    mesh.CreateExtentAttr(Vt.Vec3fArray([Gf.Vec3f(*map(float, low)), Gf.Vec3f(*map(float, high))]))
    primvars = UsdGeom.PrimvarsAPI(mesh)
    st = primvars.CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.vertex)
    st.Set(Vt.Vec2fArray.FromNumpy(np.asarray(asset.uv, np.float32)))
    for name, values in asset.point_data.items():
        scalar = primvars.CreatePrimvar(name, Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.vertex)
        scalar.Set(Vt.FloatArray.FromNumpy(np.asarray(values, np.float32)))


def _material(stage, asset: MeshAsset, colour: str | None, normal: str | None):
    """The UsdPreviewSurface material, its textures at the relative asset paths given."""
    Gf, _, Sdf, _, UsdGeom, UsdShade, _ = _pxr()
    UsdGeom.Scope.Define(stage, LOOKS)
    material = UsdShade.Material.Define(stage, f"{LOOKS}/Leaf")
    surface = UsdShade.Shader.Define(stage, f"{LOOKS}/Leaf/Surface")
    surface.CreateIdAttr("UsdPreviewSurface")
    surface.CreateInput("metallic", Sdf.ValueTypeNames.Float).Set(METALLIC)
    surface.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(ROUGHNESS)
    material.CreateSurfaceOutput().ConnectToSource(surface.ConnectableAPI(), "surface")
    if not asset.solid:
        _translucency(material)
    diffuse = surface.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f)
    if colour is None:
        diffuse.Set(Gf.Vec3f(*(c / 255 for c in BLADE)))
        return material
    reader = UsdShade.Shader.Define(stage, f"{LOOKS}/Leaf/ST")
    reader.CreateIdAttr("UsdPrimvarReader_float2")
    reader.CreateInput("varname", Sdf.ValueTypeNames.String).Set("st")
    st = reader.CreateOutput("result", Sdf.ValueTypeNames.Float2)

    def texture(name: str, file: str, raw: bool):
        shader = UsdShade.Shader.Define(stage, f"{LOOKS}/Leaf/{name}")
        shader.CreateIdAttr("UsdUVTexture")
        shader.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(file)
        shader.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(st)
        shader.CreateInput("sourceColorSpace", Sdf.ValueTypeNames.Token).Set(
            "raw" if raw else "sRGB"
        )
        for wrap in ("wrapS", "wrapT"):
            shader.CreateInput(wrap, Sdf.ValueTypeNames.Token).Set("clamp")
        return shader

    base = texture("BaseColor", colour, raw=False)
    diffuse.ConnectToSource(base.CreateOutput("rgb", Sdf.ValueTypeNames.Float3))
    if not asset.solid:  # a sheet's texture cuts the outline out (glTF: alphaMode MASK)
        opacity = surface.CreateInput("opacity", Sdf.ValueTypeNames.Float)
        opacity.ConnectToSource(base.CreateOutput("a", Sdf.ValueTypeNames.Float))
        surface.CreateInput("opacityThreshold", Sdf.ValueTypeNames.Float).Set(ALPHA_CUTOFF)
    if normal is not None:
        bump = texture("Normal", normal, raw=True)
        bump.CreateInput("scale", Sdf.ValueTypeNames.Float4).Set(Gf.Vec4f(2, 2, 2, 1))
        bump.CreateInput("bias", Sdf.ValueTypeNames.Float4).Set(Gf.Vec4f(-1, -1, -1, 0))
        surface.CreateInput("normal", Sdf.ValueTypeNames.Normal3f).ConnectToSource(
            bump.CreateOutput("rgb", Sdf.ValueTypeNames.Float3)
        )
    return material


def _translucency(material) -> None:
    """A sheet's translucency as the material's own inputs (TRANSLUCENCY_INPUTS), for pipelines
    that map them onto their renderer's translucent material: UsdPreviewSurface has no input
    for it, and an MDL shader (Omniverse's OmniSurface, thin-walled with diffuse transmission)
    fails usd-core's validators (no 'mdl' in its shader registry, OmniSurface.mdl unresolvable
    outside Omniverse), even in a variant not selected."""
    _, _, Sdf, _, _, _, _ = _pxr()
    for name, (kind, value, doc) in TRANSLUCENCY_INPUTS.items():
        put = material.CreateInput(name, getattr(Sdf.ValueTypeNames, kind))
        put.Set(value)
        put.GetAttr().SetDocumentation(doc)


def usd_stage(assets: Sequence[MeshAsset], colour: str | None, normal: str | None):
    """An in-memory stage of the assets (the first the full mesh, then its levels of detail)."""
    _, Kind, _, Usd, UsdGeom, UsdShade, _ = _pxr()
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    root = UsdGeom.Xform.Define(stage, ROOT).GetPrim()
    stage.SetDefaultPrim(root)
    Usd.ModelAPI(root).SetKind(Kind.Tokens.component)
    if len(assets) == 1:
        _mesh(stage, assets[0])
    else:
        variants = root.GetVariantSets().AddVariantSet("LOD")
        for level, asset in enumerate(assets):
            variants.AddVariant(f"LOD{level}")
            variants.SetVariantSelection(f"LOD{level}")
            with variants.GetVariantEditContext():
                _mesh(stage, asset)
        variants.SetVariantSelection("LOD0")
    material = _material(stage, assets[0], colour, normal)
    binding = UsdShade.MaterialBindingAPI.Apply(root)
    binding.Bind(material)
    return stage


def _crate_bytes(stage, images: dict[str, bytes] | None, path: Path) -> bytes:
    """The stage as .usdc bytes, or (with `images`) as a .usdz package of it and the images;
    made in a temporary folder (usd-core writes files), a failure there a LeafError naming
    `path`."""
    from pxr import Sdf, Tf

    try:
        with tempfile.TemporaryDirectory() as folder:
            crate = Path(folder) / "leaf.usdc"
            stage.GetRootLayer().Export(str(crate))
            if images is None:
                return crate.read_bytes()
            package = Path(folder) / "leaf.usdz"  # the layer first, then its textures
            writer = Sdf.ZipFileWriter.CreateNew(str(package))
            writer.AddFile(str(crate), "leaf.usdc")
            for name, blob in images.items():
                (Path(folder) / name).write_bytes(blob)
                writer.AddFile(str(Path(folder) / name), name)
            writer.Save()
            return package.read_bytes()
    except (OSError, Tf.ErrorException) as exc:
        found = re.search(r"writing file: ([^'\n]+)", str(exc))
        reason = getattr(exc, "strerror", None) or (found.group(1).strip() if found else "")
        raise LeafError(
            f"cannot be written (usd-core: {reason or 'the file could not be made'}); any old "
            "file is unchanged",
            str(path),
        ) from None


def write_usd(assets: Sequence[MeshAsset], path: Path) -> None:
    """.usda, .usdc or .usdz of the assets (module docstring); every file written atomically."""
    first = assets[0]
    suffix = path.suffix.lower()
    images = {}  # relative name -> PNG bytes
    if suffix == ".usdz":
        names = ("texture.png", "normal.png")
    else:
        names = tuple(p.name for p in usd_companions(path))
    if first.texture is not None:
        images[names[0]] = png_bytes(first.texture)
    if first.texture is not None and first.normal_map is not None:
        images[names[1]] = png_bytes(first.normal_map)
    colour = names[0] if names[0] in images else None
    normal = names[1] if names[1] in images else None
    stage = usd_stage(assets, colour, normal)
    if suffix == ".usda":
        data = stage.GetRootLayer().ExportToString().encode()
    else:
        data = _crate_bytes(stage, images if suffix == ".usdz" else None, path)
    if suffix != ".usdz":  # the textures first: a file on disk never names a missing one
        for name, blob in images.items():
            write_bytes(path.with_name(name), blob)
    write_bytes(path, data)
