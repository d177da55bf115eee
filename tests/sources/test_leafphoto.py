"""A photo-made leaf remembers its photo (issue 14): the project's "photo" entry, relative to the
project, read back by the app's session, which maps it as the leaf's texture; old projects load."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from leafstudio.assets.export import base_color, photo_transform
from leafstudio.errors import LeafError
from leafstudio.model import Leaf
from leafstudio.sources.files import load_project, save_leaf
from leafstudio.sources.leafphoto import LeafPhoto, PhotoTexture, from_entry, project_photo

MAP = np.array([[300.0, 10.0, 50.0], [-10.0, -300.0, 400.0]])


def _leaf() -> Leaf:
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    return Leaf(np.column_stack([0.5 + 0.5 * np.cos(t), 0.2 * np.sin(t), 0 * t]), [])


def _photo(path) -> None:
    from PIL import Image

    path.parent.mkdir(parents=True, exist_ok=True)
    Image.new("RGB", (64, 48), (40, 120, 30)).save(path)


def test_the_photo_is_kept_relative_to_the_project_and_found_again(tmp_path):
    image = tmp_path / "pictures" / "leaf.png"
    _photo(image)
    project = tmp_path / "work" / "leaf.leaf.json"
    project.parent.mkdir()
    photo = LeafPhoto(image.resolve(), MAP, petiole_cut=True)
    save_leaf(_leaf(), project, photo=photo.entry(project))
    entry = json.loads(project.read_text())["photo"]
    assert entry["image"] == "../pictures/leaf.png"  # relative: a moved folder keeps working
    assert entry["petiole_cut"] is True
    again = project_photo(project)
    assert again.image == image.resolve() and again.exists()
    np.testing.assert_array_equal(again.pixel_from_world, MAP)
    np.testing.assert_array_equal(photo_transform(project), MAP)  # reconstruct --texture PHOTO
    load_project(project)  # the leaf loads as before
    moved = tmp_path / "moved"
    shutil.copytree(tmp_path / "pictures", moved / "pictures")
    shutil.copytree(tmp_path / "work", moved / "work")
    assert project_photo(moved / "work" / "leaf.leaf.json").image == moved / "pictures/leaf.png"


def test_projects_without_a_photo_or_with_a_name_only_still_load(tmp_path):
    plain = tmp_path / "plain.leaf.json"
    save_leaf(_leaf(), plain)
    assert "photo" not in json.loads(plain.read_text())
    assert project_photo(plain) is None and project_photo(tmp_path / "leaf.csv") is None
    old = tmp_path / "old.leaf.json"  # as `leafstudio photo` wrote it before: the name only
    data = json.loads(plain.read_text())
    data["photo"] = {"image": "leaf.png", "pixel_from_world": MAP.tolist(), "petiole_cut": False}
    old.write_text(json.dumps(data))
    photo = project_photo(old)
    assert photo.image == (tmp_path / "leaf.png").resolve() and not photo.exists()


@pytest.mark.parametrize(
    "entry, problem",
    [
        ({"image": "a.png", "pixel_from_world": [[1, 2]]}, "2 rows of 3 numbers"),
        ({"image": "a.png", "pixel_from_world": [[1, 2, 3], [2, 4, 6]]}, "invertible"),
        ({"pixel_from_world": MAP.tolist()}, '"image" must name'),
        ("leaf.png", "2 rows of 3 numbers"),
    ],
)
def test_a_bad_photo_entry_is_one_clear_error(tmp_path, entry, problem):
    with pytest.raises(LeafError, match=problem):
        from_entry(entry, tmp_path / "p.leaf.json")


def test_the_photo_leaf_command_writes_the_relative_path(tmp_path):
    from PIL import Image

    from leafstudio.forms import make_form
    from leafstudio.sources.photo import leaf_from_photo, save_photo_leaf
    from tests.photos import form_photo

    form = make_form("ovate")
    image, _, _ = form_photo(form.boundary, form.veins, angle=20)
    photo = tmp_path / "in" / "leaf.png"
    photo.parent.mkdir()
    Image.fromarray(image).save(photo)
    found = leaf_from_photo(image, veins="none")
    out = tmp_path / "out" / "leaf.leaf.json"
    out.parent.mkdir()
    save_photo_leaf(found, photo, out)
    assert json.loads(out.read_text())["photo"]["image"] == "../in/leaf.png"
    texture = project_photo(out).texture()
    assert isinstance(texture, PhotoTexture) and texture.image == photo.resolve()
    np.testing.assert_allclose(texture.pixel_from_world, found.pixel_from_world)


def test_the_session_texture_is_the_photo_while_it_is_there(tmp_path):
    """Qt-free: the texture the app shows and exports (Session.texture), and the message when
    a project's photo is missing."""
    from leafstudio.gui.model.session import Session

    image = tmp_path / "leaf.png"
    _photo(image)
    photo = LeafPhoto(image.resolve(), MAP)
    session = Session()
    notes: list[str] = []
    session.noticed.connect(notes.append)
    session.open_document(_leaf(), None, "leaf.png", photo=photo)
    assert session.texture() == photo.texture() and not notes
    session.chosen_texture = "none"  # picked in the export dialog: shown and exported
    assert session.texture() == "none"
    session.open_document(_leaf(), None, "again", photo=photo)
    assert session.texture() == photo.texture()  # a new document forgets the pick
    image.unlink()
    session.open_document(_leaf(), None, "moved", photo=photo)
    assert session.texture() == "auto"  # the generated texture: the leaf is kept
    assert len(notes) == 1 and "missing" in notes[0] and str(image.resolve()) in notes[0]
    assert session.leaf is not None and session.state.photo is photo  # saved again as it was


def test_the_photo_texture_lands_the_photo_on_the_leaf(tmp_path):
    """base_color (what the app draws) of a photo texture: the photo's leaf colour inside the
    outline, alpha 0 outside."""
    import leafstudio as ls
    from leafstudio.forms import make_form
    from leafstudio.sources.photo import leaf_from_photo
    from tests.photos import form_photo

    form = make_form("elliptic")
    image, _, _ = form_photo(form.boundary, angle=-30, noise=0, blur=0)
    path = tmp_path / "leaf.png"
    from PIL import Image

    Image.fromarray(image).save(path)
    found = leaf_from_photo(image, veins="none")
    result = ls.reconstruct(found.leaf, ls.Params(k=1, grid=48, samples=800))
    texture = np.asarray(base_color(result, PhotoTexture(path, found.pixel_from_world)))
    inside = texture[..., 3] == 255
    assert inside.mean() > 0.2 and (texture[..., 3] == 0).mean() > 0.2
    assert np.all(np.abs(np.median(texture[inside][:, :3], axis=0) - (62, 118, 44)) <= 6)


def test_no_photo_background_inside_the_outline(tmp_path):
    """Where the smooth margin rounds a sinus of a serrate leaf, or the photo's edge is blurred,
    the texels inside the outline took the photo's background (a pale band 1-2 photo pixels
    deep, about a thousand texels here); they now take the nearest leaf colour."""
    import leafstudio as ls
    from leafstudio.forms import make_form
    from leafstudio.sources.photo import leaf_from_photo
    from tests.photos import BACKGROUND, form_photo

    form = make_form("ovate", margin="serrate", teeth=24)
    image, _, _ = form_photo(form.boundary, form.veins, angle=-40)
    found = leaf_from_photo(image, veins="none")
    result = ls.reconstruct(found.leaf, ls.Params(k=1, grid=64, samples=800))
    path = tmp_path / "leaf.png"
    from PIL import Image

    Image.fromarray(image).save(path)
    texture = np.asarray(base_color(result, PhotoTexture(path, found.pixel_from_world)))
    inside = texture[..., 3] == 255
    rgb = texture[..., :3].astype(float)
    to_background = np.linalg.norm(rgb - BACKGROUND, axis=2)
    to_leaf = np.linalg.norm(rgb - (62, 118, 44), axis=2)
    assert np.count_nonzero(inside & (to_background < to_leaf)) == 0
    outside = texture[..., 3] == 0  # outside too, edge padding (tests/test_texture_bleed.py)
    assert np.count_nonzero(outside & (to_background < to_leaf)) == 0
