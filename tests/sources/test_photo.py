"""Leaves from photos: the outline matches the known one (IoU >= 0.97) on generated forms and on
real scans rendered from above; the petiole is cut; bad photos get one clear message; the photo
maps back onto the mesh through the UVs."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import shapely
from PIL import Image

import leafstudio as ls
from leafstudio.forms import make_form
from leafstudio.sources.photo import leaf_from_photo
from tests.photos import REALLEAVES, error_lines, exif_turned, form_photo, iou, scan_photo

FORMS = [
    ("ovate", {}, 0.25, 25.0),
    ("lanceolate", {}, 0.0, -60.0),
    ("elliptic", {"margin": "serrate", "teeth": 30}, 0.25, 100.0),
    ("ovate", {"margin": "lobed", "lobes": 5}, 0.25, 0.0),
    ("obovate", {}, 0.2, 170.0),
    ("elliptic", {"apex": "acuminate"}, 0.25, -20.0),
    ("elliptic", {"apex": "acuminate"}, 0.0, 45.0),  # a long thin tip is not a petiole
    ("cordate", {}, 0.12, 60.0),  # a short petiole in the sinus
    ("linear", {}, 0.12, -30.0),  # a petiole nearly as wide as the blade
]


@pytest.mark.parametrize(("shape", "terms", "petiole", "angle"), FORMS)
def test_outline_of_a_generated_form_matches(shape, terms, petiole, angle):
    leaf = make_form(shape, **terms)
    image, known, base = form_photo(leaf.boundary, leaf.veins, angle=angle, petiole=petiole)
    found = leaf_from_photo(image, veins="none")
    assert iou(shapely.Polygon(found.outline_px), known) >= 0.97
    assert found.petiole == (petiole > 0)
    if petiole:  # the petiole marks the base: where the stalk met the blade
        assert np.linalg.norm(found.pixel_from_world @ [0, 0, 1] - base) < 12


@pytest.mark.parametrize(
    "name",
    [
        "soybean_11_20190508T043118_pot1_1.txt",
        "soybean_11_20190508T043118_pot1_36.txt",
        "sugarbeet_f00012_20170829T010129_pot1_1.txt",
        "sugarbeet_f00012_20170904T115033_pot1_7.txt",
    ],
)
def test_outline_of_a_rendered_real_scan_matches(name):
    path = REALLEAVES / name
    if not path.exists():
        pytest.skip(f"{path} is missing")
    image, known, _ = scan_photo(path)
    found = leaf_from_photo(image, veins="none")
    assert iou(shapely.Polygon(found.outline_px), known) >= 0.97


def test_leaf_follows_the_forms_convention_and_maps_back_to_the_photo():
    leaf = make_form("ovate")
    image, _, _ = form_photo(leaf.boundary, angle=-35, petiole=0.2)
    found = leaf_from_photo(image, length=4.0)
    boundary = found.leaf.boundary
    assert np.allclose(boundary[:, 2], 0)
    apex = boundary[np.argmax(np.linalg.norm(boundary[:, :2], axis=1))]
    np.testing.assert_allclose(apex[:2], [4.0, 0.0], atol=1e-9)  # base at 0, apex on +x
    assert np.min(np.linalg.norm(boundary[:, :2], axis=1)) < 1e-9  # the base is on the outline
    ones = np.column_stack([boundary[:, :2], np.ones(len(boundary))])
    np.testing.assert_allclose(ones @ found.pixel_from_world.T, found.outline_px, atol=1e-9)
    assert len(found.leaf.veins) >= 3  # grown: a midrib and secondaries
    assert (
        shapely.Polygon(boundary[:, :2])
        .buffer(1e-6)
        .contains(shapely.MultiPoint(np.vstack(found.leaf.veins)[:, :2]))
    )


def test_a_photos_exif_orientation_is_applied_where_it_is_read(tmp_path: Path):
    """A phone's portrait photo stores its pixels sideways and says so in EXIF: it was read
    sideways (the app's dialog showed it on its side, `--base-end left` named the wrong end). It
    is now turned upright where every photo is read (_shared/inputs.read_image): the same leaf,
    pixel map and texture as from the upright photo."""
    from leafstudio._shared.inputs import read_image
    from leafstudio.sources.photo import read_photo_leaf

    form = make_form("obovate")
    upright = form_photo(form.boundary, form.veins, angle=0, size=(760, 500))[0]
    straight = tmp_path / "upright.png"
    Image.fromarray(upright).save(straight)
    turned = exif_turned(upright, tmp_path / "portrait.png")
    np.testing.assert_array_equal(read_image(turned), upright)
    a = read_photo_leaf(straight, base_end="left", veins="none")
    b = read_photo_leaf(turned, base_end="left", veins="none")
    np.testing.assert_allclose(b.leaf.boundary, a.leaf.boundary, atol=1e-9)
    np.testing.assert_allclose(b.pixel_from_world, a.pixel_from_world, atol=1e-9)


def _two_leaves() -> np.ndarray:
    leaf = make_form("elliptic")
    a = form_photo(leaf.boundary, size=(900, 500), pixels_per_unit=300, angle=0)[0]
    image = a.copy()
    image[:, 450:] = a[:, 225:675][:, :450]  # the same leaf again, beside it
    image[:, :450] = a[:, 225:675][:, :450]
    return image


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: np.full((300, 400, 3), 200, np.uint8), "no leaf found"),
        (_two_leaves, "several leaves"),
        (
            lambda: form_photo(make_form("ovate").boundary, pixels_per_unit=900)[0],
            "cut by the image border",
        ),
    ],
    ids=["blank", "two leaves", "cut off"],
)
def test_bad_photos_get_one_clear_message(tmp_path: Path, capsys, make, message):
    from leafstudio.cli import main

    path = tmp_path / "photo.png"
    Image.fromarray(make()).save(path)
    code = main(["photo", str(path), "-o", str(tmp_path / "leaf.leaf.json")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and message in err and error_lines(err) == 1, err
    assert not (tmp_path / "leaf.leaf.json").exists()


def test_unreadable_image_is_one_line_exit_2(tmp_path: Path, capsys):
    from leafstudio.cli import main

    path = tmp_path / "photo.jpg"
    path.write_bytes(b"\x00not a jpeg")
    assert main(["photo", str(path), "-o", str(tmp_path / "leaf.leaf.json")]) == 2
    err = capsys.readouterr().err.strip()
    assert "not a readable image" in err and error_lines(err) == 1


def test_photo_texture_lands_on_the_mesh_margin_within_2_pixels(tmp_path: Path):
    """photo -> leaf -> reconstruct --texture photo: the leaf's edge in the photo (segmented as
    `leafstudio photo` does), the texture's cut-out (its alpha) and the mesh's margin coincide
    within 2 photo pixels, and the texture's pixels are the photo's where the UVs put them (its
    drawn veins on the photo's veins). The photo's edge is found in the photo, not in the
    texture's colours: outside the outline the texture has the leaf's colour (edge padding)."""
    from scipy.ndimage import distance_transform_edt, map_coordinates
    from scipy.spatial import cKDTree
    from skimage.measure import find_contours

    from leafstudio.assets.placement import result_placement
    from leafstudio.assets.solid import boundary_edges
    from leafstudio.cli import main
    from leafstudio.sources.photo import foreground
    from tests.assets.test_assets import assert_valid_gltf, scene_mesh

    leaf = make_form("ovate", margin="serrate", teeth=24)
    # no petiole: a cut petiole leaves the photo's edge on purpose (tested above)
    image, _, _ = form_photo(leaf.boundary, leaf.veins, angle=-40)
    photo = tmp_path / "photo.png"
    Image.fromarray(image).save(photo)
    project = tmp_path / "leaf.leaf.json"
    assert main(["photo", str(photo), "-o", str(project), "--length", "3"]) == 0
    glb = tmp_path / "leaf.glb"
    assert main(["reconstruct", str(project), "-o", str(glb), "--grid", "48", "--texture",
                 str(photo)]) == 0  # fmt: skip
    assert_valid_gltf(glb)
    mesh = scene_mesh(glb)
    texture = np.asarray(mesh.visual.material.baseColorTexture.convert("RGBA"))
    pixels = texture.shape[0]
    pixel_from_world = ls.assets.photo_transform(project)
    uv = np.asarray(mesh.visual.uv) * [1, -1] + [0, 1]  # glTF's v runs down: (column, row) / px
    # the glTF is Y-up with the base at the origin (assets/placement.py): back to the leaf's own
    placement = result_placement(ls.reconstruct(ls.load_leaf(project), ls.Params(grid=48)))
    turn, offset = placement.transform(None, ".glb")
    world = (np.asarray(mesh.vertices) - offset) @ turn
    photo_px = world[:, :2] @ pixel_from_world[:, :2].T + pixel_from_world[:, 2]
    # the margin: the mesh's boundary vertices; the distance to the nearest of them bounds the
    # distance to the margin from above
    rim = np.unique(boundary_edges(np.asarray(mesh.faces)))
    # texture pixels per photo pixel: the UVs' scale over the photo's, along the leaf
    far = np.argmax(np.linalg.norm(uv[rim] - uv[rim[0]], axis=1))
    along_uv = np.linalg.norm(uv[rim][far] - uv[rim[0]])
    texture_per_photo = pixels * along_uv / np.linalg.norm(photo_px[rim][far] - photo_px[rim[0]])

    def assert_within_2(edge: np.ndarray, margin: np.ndarray, per_photo_px: float) -> None:
        """Every edge point near the margin and every margin point near the edge."""
        assert np.max(cKDTree(margin).query(edge)[0]) / per_photo_px <= 2.0
        assert np.max(cKDTree(edge).query(margin)[0]) / per_photo_px <= 2.0

    # the photo's leaf edge and the margin mapped into the photo (pixel centres at k + 0.5)
    edge = max(find_contours(foreground(image).astype(float), 0.5), key=len)[:, ::-1] + 0.5
    assert_within_2(edge, photo_px[rim], 1.0)
    # the texture's cut-out (what an engine draws with alphaMode MASK) and the margin's UVs
    cut = max(find_contours(texture[..., 3].astype(float), 127.5), key=len)[:, ::-1] + 0.5
    assert_within_2(cut, uv[rim] * pixels, texture_per_photo)

    # the texture is the photo where the UVs put it: vertices on a vein in the texture are on (or
    # within 2 photo pixels of) a vein in the photo, and most vertices on the photo's veins are
    # on the texture's
    def on_vein(rgb: np.ndarray) -> np.ndarray:
        rgb = rgb.astype(float)
        return np.linalg.norm(rgb - (120, 160, 80), axis=-1) < np.linalg.norm(
            rgb - (62, 118, 44), axis=-1
        )

    inner = np.setdiff1d(np.arange(len(uv)), rim)
    texel = np.clip((uv[inner] * pixels).astype(int), 0, pixels - 1)
    in_texture = on_vein(texture[texel[:, 1], texel[:, 0], :3])
    veins = on_vein(image)
    to_vein = distance_transform_edt(~veins)
    where = [photo_px[inner, 1] - 0.5, photo_px[inner, 0] - 0.5]
    assert in_texture.sum() >= 20
    assert np.max(map_coordinates(to_vein, where, order=1)[in_texture]) <= 2.0
    in_photo = map_coordinates(veins.astype(float), where, order=1) > 0.5
    assert np.mean(in_texture[in_photo]) > 0.8


def test_a_malformed_photo_entry_is_one_line_exit_2(tmp_path: Path, capsys):
    import json

    from leafstudio.cli import main

    project = tmp_path / "leaf.leaf.json"
    ls.save_leaf(ls.demo("nested"), project)
    data = json.loads(project.read_text())
    data["photo"] = {"pixel_from_world": [[1, 2], [3]]}
    project.write_text(json.dumps(data))
    image = tmp_path / "photo.png"
    Image.new("RGB", (40, 40)).save(image)
    out = tmp_path / "leaf.glb"
    assert main(["reconstruct", str(project), "-o", str(out), "--grid", "32", "--texture",
                 str(image)]) == 2  # fmt: skip
    err = capsys.readouterr().err
    assert 'bad "photo" entry' in err and error_lines(err) == 1


def test_an_obj_export_never_writes_over_the_photo_it_came_from(tmp_path: Path):
    """The README's steps: `photo oak.png -o oak.leaf.json`, then `reconstruct oak.leaf.json -o
    oak.obj`. The OBJ's texture used to be oak.png, written over the user's photo; the next step,
    `--texture oak.png`, then mapped that generated texture instead of the photo."""
    from leafstudio.cli import main

    leaf = make_form("ovate")
    image, _, _ = form_photo(leaf.boundary, leaf.veins)
    photo = tmp_path / "oak.png"
    Image.fromarray(image).save(photo)
    before = photo.read_bytes()
    project = tmp_path / "oak.leaf.json"
    assert main(["photo", str(photo), "-o", str(project)]) == 0
    assert main(["reconstruct", str(project), "-o", str(tmp_path / "oak.obj"), "--grid", "32"]) == 0
    assert photo.read_bytes() == before
    assert (tmp_path / "oak_texture.png").is_file()
    assert "map_Kd oak_texture.png" in (tmp_path / "oak.mtl").read_text()


def test_the_leafs_holes_are_filled_as_in_the_whole_photo():
    """_leaf_component fills the leaf's holes on its box with a ring of background (a sixth of
    the whole photo's time): an enclosed hole is filled, a bay open to the background is not,
    exactly as binary_fill_holes on the whole photo, also with the box at the photo's edge."""
    from scipy.ndimage import binary_fill_holes

    from leafstudio.sources.photo import _leaf_component

    rows, cols = np.mgrid[:120, :160]
    disc = (rows - 60) ** 2 + (cols - 70) ** 2 < 45**2
    hole = (rows - 60) ** 2 + (cols - 90) ** 2 < 8**2  # enclosed, near the box's right side
    bay = (np.abs(rows - 60) < 4) & (cols < 50)  # open to the left, into the background
    mask = disc & ~hole & ~bay
    leaf = _leaf_component(mask)
    assert np.array_equal(leaf, binary_fill_holes(mask))
    assert leaf[60, 90] and not leaf[60, 40]
    at_edge = mask[:, 25:]  # the disc one pixel from the photo's left edge: its ring there
    assert at_edge[:, 1].any() and not at_edge[:, 0].any()  # is the photo's edge
    assert np.array_equal(_leaf_component(at_edge), binary_fill_holes(at_edge))


@pytest.mark.parametrize("orientation", range(2, 9))
def test_a_project_saved_before_photos_were_turned_upright_keeps_its_texture(
    tmp_path: Path, orientation: int
):
    """A project saved from a phone's photo before read_image applied the EXIF orientation
    kept a pixel map into the photo's stored (sideways) pixels; read upright, its texture took
    other pixels (a leaf's texture from the photo's background). Its map is now turned with the
    photo, so each leaf point finds the pixel it found before; a project saved now says its map
    is upright and is read as it is."""
    from leafstudio._shared.inputs import read_image
    from leafstudio.sources.leafphoto import project_photo

    stored = np.random.default_rng(orientation).integers(0, 255, (7, 5, 3), dtype=np.uint8)
    exif = Image.Exif()
    exif[0x0112] = orientation
    photo = tmp_path / "phone.jpg"
    Image.fromarray(stored).save(photo, format="PNG", exif=exif)
    upright = read_image(photo)
    old = np.array([[2.0, 0.5, 0.25], [-0.5, 3.0, 0.75]])  # world (x, y, 1) -> stored pixels
    rows, columns = np.mgrid[0:7, 0:5]
    centres = np.column_stack([columns.ravel() + 0.5, rows.ravel() + 0.5])
    world = np.linalg.solve(old[:, :2], (centres - old[:, 2]).T).T
    leaf = make_form("ovate")
    ls.save_leaf(leaf, tmp_path / "old.leaf.json")
    data = json.loads((tmp_path / "old.leaf.json").read_text())
    data["photo"] = {"image": photo.name, "pixel_from_world": old.tolist()}
    (tmp_path / "old.leaf.json").write_text(json.dumps(data))
    found = project_photo(tmp_path / "old.leaf.json")
    assert found is not None
    now = np.floor(world @ found.pixel_from_world[:, :2].T + found.pixel_from_world[:, 2])
    now = now.astype(int)
    np.testing.assert_array_equal(
        upright[now[:, 1], now[:, 0]], stored[rows.ravel(), columns.ravel()]
    )
    saved = found.entry(tmp_path / "new.leaf.json")
    data["photo"] = saved
    (tmp_path / "new.leaf.json").write_text(json.dumps(data))
    again = project_photo(tmp_path / "new.leaf.json")
    assert again is not None
    np.testing.assert_allclose(again.pixel_from_world, found.pixel_from_world)
