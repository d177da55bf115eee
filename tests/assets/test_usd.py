"""USD out (issue 23, item 3): .usda, .usdc and .usdz through usd-core, Y-up in metres, with
normals, UVs, the material and its textures, levels of detail as variants, passing usd-core's own
validators (the UsdValidation registry `usdchecker` runs, with the usdz packaging checks)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.assets import leaf_asset
from leafstudio.assets.placement import place, result_placement
from leafstudio.errors import LeafError

pxr = pytest.importorskip("pxr", reason="usd-core (the usd extra) is not installed")
from pxr import Usd, UsdGeom, UsdShade, UsdValidation  # noqa: E402

SUFFIXES = (".usda", ".usdc", ".usdz")


@pytest.fixture(scope="module")
def nested() -> ls.Result:
    return ls.reconstruct(ls.demo("nested"), ls.Params(grid=40))


def validation_errors(path: Path) -> list[str]:
    """Every validator usd-core registers, run on the stage, as `usdchecker` does."""
    validators = UsdValidation.ValidationRegistry().GetOrLoadAllValidators()
    errors = UsdValidation.ValidationContext(validators).Validate(Usd.Stage.Open(str(path)))
    return [f"{e.GetName()}: {e.GetMessage()}" for e in errors]


def mesh_of(stage: Usd.Stage) -> UsdGeom.Mesh:
    return UsdGeom.Mesh(stage.GetPrimAtPath("/Leaf/Leaf"))


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_usd_is_y_up_in_metres_with_normals_uvs_and_its_textures(nested, tmp_path, suffix):
    path = tmp_path / f"leaf{suffix}"
    ls.save_mesh(nested, path, length="8cm")
    assert validation_errors(path) == []
    stage = Usd.Stage.Open(str(path))
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y
    assert UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert stage.GetDefaultPrim().GetPath() == "/Leaf"
    mesh = mesh_of(stage)
    expected = place(leaf_asset(nested), result_placement(nested), 0.08, suffix)
    points = np.asarray(mesh.GetPointsAttr().Get())
    np.testing.assert_allclose(points, expected.points, atol=1e-7)
    assert np.ptp(points[:, 0]) == pytest.approx(0.08, rel=1e-6)  # base to apex, in metres
    np.testing.assert_allclose(np.asarray(mesh.GetNormalsAttr().Get()), expected.normals,
                               atol=1e-6)  # fmt: skip
    assert mesh.GetNormalsInterpolation() == UsdGeom.Tokens.vertex
    st = UsdGeom.PrimvarsAPI(mesh).GetPrimvar("st")
    np.testing.assert_allclose(np.asarray(st.Get()), expected.uv, atol=1e-6)
    indices = np.asarray(mesh.GetFaceVertexIndicesAttr().Get()).reshape(-1, 3)
    np.testing.assert_array_equal(indices, expected.faces)
    height = UsdGeom.PrimvarsAPI(mesh).GetPrimvar("height").Get()
    np.testing.assert_allclose(height, expected.point_data["height"], rtol=1e-5, atol=1e-9)
    material, _ = UsdShade.MaterialBindingAPI(mesh.GetPrim()).ComputeBoundMaterial()
    assert material.GetPath() == "/Leaf/Looks/Leaf"
    for shader in ("BaseColor", "Normal"):
        file = UsdShade.Shader(stage.GetPrimAtPath(f"/Leaf/Looks/Leaf/{shader}"))
        resolved = file.GetInput("file").Get().resolvedPath
        assert resolved, shader  # the texture is there (beside the file, or in the package)


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_a_usd_sheet_carries_its_translucency_and_a_solid_does_not(nested, tmp_path, suffix):
    """UsdPreviewSurface has no translucency input: the material's own inputs carry it, the
    share glTF's KHR_materials_diffuse_transmission writes, and the validators still pass."""
    from leafstudio.assets.material import DIFFUSE_TRANSMISSION

    for thickness, sheet in ((None, True), (0.01, False)):
        path = tmp_path / f"{'sheet' if sheet else 'solid'}{suffix}"
        ls.save_mesh(nested, path, thickness=thickness)
        assert validation_errors(path) == []
        stage = Usd.Stage.Open(str(path))
        material = UsdShade.Material(stage.GetPrimAtPath("/Leaf/Looks/Leaf"))
        share, thin = material.GetInput("diffuseTransmission"), material.GetInput("thinWalled")
        if sheet:
            assert share.Get() == pytest.approx(DIFFUSE_TRANSMISSION) and thin.Get() is True
        else:
            assert not share and not thin


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_usd_levels_of_detail_are_variants(nested, tmp_path, suffix):
    path = tmp_path / f"leaf{suffix}"
    ls.save_mesh(nested, path, lod=2, texture="none")
    assert validation_errors(path) == []
    stage = Usd.Stage.Open(str(path))
    variants = stage.GetDefaultPrim().GetVariantSets().GetVariantSet("LOD")
    assert variants.GetVariantNames() == ["LOD0", "LOD1", "LOD2"]
    assert variants.GetVariantSelection() == "LOD0"
    counts = []
    for name in variants.GetVariantNames():
        variants.SetVariantSelection(name)
        counts.append(len(mesh_of(stage).GetFaceVertexCountsAttr().Get()))
    assert counts[1] == pytest.approx(counts[0] / 2, rel=0.1)
    assert counts[2] == pytest.approx(counts[0] / 4, rel=0.1)


def test_a_solid_usd_is_closed_and_single_sided(nested, tmp_path):
    path = tmp_path / "solid.usdz"
    ls.save_mesh(nested, path, thickness=0.01 * nested.length)
    assert validation_errors(path) == []
    stage = Usd.Stage.Open(str(path))
    assert mesh_of(stage).GetDoubleSidedAttr().Get() is False


def test_without_usd_core_the_error_names_the_extra(nested, tmp_path, monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "pxr", None)  # import pxr raises ImportError
    with pytest.raises(LeafError, match=r"leafstudio\[usd\]"):
        ls.save_mesh(nested, tmp_path / "leaf.usda")
    assert not (tmp_path / "leaf.usda").exists()
