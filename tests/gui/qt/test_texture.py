"""Issue 14, the app side: the mesh shown with the texture it exports (Layers > "Show the texture"),
and a leaf opened from a photo keeps its photo as texture through save, reopen and export."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from PIL import Image
from PySide6.QtCore import Qt

from leafstudio.assets.asset import leaf_uvs
from leafstudio.gui.model.textures import TEXTURE, texture_key
from tests.gui.qt.conftest import WAIT_MS, exported, exports_done, wait_result


def _glb_texture(path) -> np.ndarray:
    import trimesh

    (mesh,) = trimesh.load(path, process=False).geometry.values()
    return np.asarray(mesh.visual.material.baseColorTexture)


def _show_texture(window, qtbot) -> np.ndarray:
    """Switch the mesh to the texture and wait until the leaf's image is on it (the Leaf look,
    the default, may have had it made already)."""
    window.coloring.setCurrentIndex(window.coloring.findData(TEXTURE))
    session = window.session
    qtbot.waitUntil(
        lambda: window.viewport.texture_key == texture_key(session.result, session.texture()),
        timeout=WAIT_MS,
    )
    return window.viewport.texture_actor_image()


def _mesh_uvs(window) -> np.ndarray:
    held = window.viewport.plotter.actors["mesh"].mapper.dataset
    return np.asarray(held.active_texture_coordinates)


def _render(window) -> np.ndarray:
    window.viewport.plotter.render()
    return window.viewport.plotter.screenshot(return_img=True)


def test_the_texture_colouring_shows_what_an_export_writes(window, qtbot, tmp_path, monkeypatch):
    from PySide6.QtWidgets import QFileDialog, QInputDialog

    image = _show_texture(window, qtbot)
    result = window.session.result
    assert image.shape == (1024, 1024, 4)
    glb = tmp_path / "leaf.glb"
    assert exported(qtbot, window.save_mesh(str(glb)))  # the leaf's texture: the generated one
    np.testing.assert_array_equal(image, _glb_texture(glb))  # pixel for pixel
    np.testing.assert_allclose(_mesh_uvs(window), leaf_uvs(result), atol=1e-6)
    assert window.viewport.plotter.actors["mesh"].mapper.scalar_visibility is False
    assert "height" not in window.viewport.plotter.scalar_bars  # an image, no colour scale

    # an image picked in the export dialog is what the view shows next: four quadrants land
    # where the UVs put them (top view: s, the leaf's length, to the right; t up)
    quads = np.zeros((64, 64, 3), np.uint8)
    quads[:32, :32], quads[:32, 32:] = (255, 0, 0), (0, 0, 255)  # top: t > 1/2
    quads[32:, :32], quads[32:, 32:] = (0, 255, 0), (255, 255, 0)
    picked = tmp_path / "quads.png"
    Image.fromarray(quads).save(picked)
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: (str(glb), ""))
    monkeypatch.setattr(QFileDialog, "getOpenFileName", lambda *a, **k: (str(picked), ""))
    monkeypatch.setattr(QInputDialog, "getItem", lambda *a, **k: (window.TEXTURE_CHOICES[2], True))
    monkeypatch.setattr(QInputDialog, "getText", lambda *a, **k: ("", True))  # its own units
    monkeypatch.setattr(QInputDialog, "getInt", lambda *a, **k: (0, True))  # no levels of detail
    with qtbot.waitSignal(window.texture_shown, timeout=WAIT_MS):
        window.export_mesh_dialog()
    exports_done(qtbot, window)
    np.testing.assert_array_equal(window.viewport.texture_actor_image(), _glb_texture(glb))
    window.viewport.camera("top")
    window.layer_list.item(1).setCheckState(Qt.CheckState.Unchecked)  # input points off
    shot = _render(window).astype(int)
    frame = result.frame
    centre = result.polygon.mean(axis=0)
    size = np.ptp(result.polygon, axis=0)
    for (du, dv), colour in {
        (-0.2, 0.12): (255, 0, 0),
        (0.2, 0.12): (0, 0, 255),
        (-0.2, -0.12): (0, 255, 0),
        (0.2, -0.12): (255, 255, 0),
    }.items():
        xy = centre + np.array([du * size[0], dv * size[1]])
        world = frame.to_world(xy[None], np.array([result.height(xy[None])[0]]))[0]
        column, row = _on_screen(window, world, shot.shape)
        patch = shot[row - 2 : row + 3, column - 2 : column + 3, :3].reshape(-1, 3).mean(axis=0)
        hue = np.asarray(colour) > 0
        assert np.all(patch[hue] > patch[~hue].max(initial=0) + 40), (colour, patch)

    # back to a colour scale: no image on the mesh
    window.coloring.setCurrentIndex(window.coloring.findData("height"))
    assert window.viewport.texture_actor_image() is None
    assert "height" in window.viewport.plotter.scalar_bars


def _on_screen(window, world: np.ndarray, shape) -> tuple[int, int]:
    """The screenshot pixel (column, row) of a world point."""
    x, y = window.viewport.display_points(np.asarray([world]))[0]
    width, height = window.viewport.plotter.render_window.GetSize()
    column = round(x * shape[1] / width)
    row = round(shape[0] - 1 - y * shape[0] / height)
    return column, row


@pytest.fixture(scope="module")
def oak_png(tmp_path_factory):
    """A photo of a generated ovate leaf with its veins, drawn once for the module."""
    from leafstudio.forms import make_form
    from tests.photos import form_photo

    form = make_form("ovate")
    image, _, _ = form_photo(form.boundary, form.veins, petiole=0.15, angle=30)
    path = tmp_path_factory.mktemp("oak") / "oak.png"
    Image.fromarray(image).save(path)
    return path


@pytest.fixture
def photo(tmp_path, oak_png):
    """That photo in this test's own folder (a test may move or spoil it)."""
    path = tmp_path / "photos" / "oak.png"
    path.parent.mkdir()
    shutil.copyfile(oak_png, path)
    return path


def _open(window, qtbot, path) -> None:
    assert window.open_path(str(path))
    qtbot.waitUntil(
        lambda: window.session.state.leaf is not None and window.session.state.path == str(path),
        timeout=WAIT_MS,
    )
    wait_result(qtbot, window, lambda outcome: outcome.result.leaf is window.session.state.leaf)


def test_a_photo_leaf_keeps_its_photo_through_save_reopen_and_export(
    window, qtbot, tmp_path, photo, monkeypatch
):
    from PySide6.QtWidgets import QInputDialog

    from leafstudio.assets.export import base_color

    _open(window, qtbot, photo)
    image = _show_texture(window, qtbot)
    expected = np.asarray(base_color(window.session.result, window.session.state.photo.texture()))
    np.testing.assert_array_equal(image, expected)
    inside = image[..., 3] == 255
    assert np.all(np.abs(np.median(image[inside][:, :3], axis=0) - (62, 118, 44)) <= 12)

    project = tmp_path / "projects" / "oak.leaf.json"
    project.parent.mkdir()
    assert window.save_to(str(project))
    leaf = window.session.state.leaf
    window.open_demo("nested")  # another leaf, then the project again
    wait_result(qtbot, window, lambda outcome: window.session.state.photo is None)
    with qtbot.waitSignal(window.texture_shown, timeout=WAIT_MS):
        _open(window, qtbot, project)
    assert window.session.state.photo.image == photo.resolve()
    np.testing.assert_allclose(window.session.state.leaf.boundary, leaf.boundary)
    np.testing.assert_array_equal(window.viewport.texture_actor_image(), expected)

    offered = {}

    def get_item(parent, title, label, items, current, editable):
        offered.update(items=items, current=current)
        return items[current], True  # the default: the photo

    monkeypatch.setattr(QInputDialog, "getItem", get_item)
    glb = tmp_path / "oak.glb"
    assert window._texture_choice(str(glb)) == "photo"
    assert offered["items"][offered["current"]] == window.PHOTO_CHOICE.format(name="oak.png")
    assert exported(qtbot, window.save_mesh(str(glb)))  # no choice given: the photo, as shown
    np.testing.assert_array_equal(_glb_texture(glb), expected)


def test_a_missing_photo_is_said_and_the_generated_texture_shown(window, qtbot, tmp_path, photo):
    from leafstudio.assets.export import base_color

    _open(window, qtbot, photo)
    project = tmp_path / "oak.leaf.json"
    assert window.save_to(str(project))
    leaf = window.session.state.leaf
    shutil.move(photo, tmp_path / "elsewhere.png")
    window.open_demo("nested")
    wait_result(qtbot, window, lambda outcome: window.session.state.photo is None)
    with qtbot.waitSignal(window.notice_shown, timeout=WAIT_MS) as notice:
        assert window.open_path(str(project))
    assert "missing" in notice.args[0] and "oak.png" in notice.args[0]
    assert "missing" in window.last_error_box.text()
    window.last_error_box.close()
    wait_result(qtbot, window, lambda outcome: outcome.result.leaf is window.session.state.leaf)
    np.testing.assert_allclose(
        window.session.state.leaf.boundary, leaf.boundary
    )  # the leaf is there
    image = _show_texture(window, qtbot)
    np.testing.assert_array_equal(image, np.asarray(base_color(window.session.result, "auto")))
    assert window.save_to(str(project))  # the photo's place is kept for when it comes back
    assert '"oak.png"' in project.read_text() or "photos/oak.png" in project.read_text()
    assert not window.save_mesh(str(tmp_path / "x.glb"), texture="photo")  # said, not written
    assert "missing" in window.last_error_box.text()
    window.last_error_box.close()


def test_an_unreadable_photo_is_said_and_the_generated_one_shown(window, qtbot, tmp_path, photo):
    from leafstudio.assets.export import base_color

    _open(window, qtbot, photo)
    _show_texture(window, qtbot)
    photo.write_bytes(b"not a picture any more")
    project = tmp_path / "oak.leaf.json"
    assert window.save_to(str(project))
    with qtbot.waitSignal(window.notice_shown, timeout=WAIT_MS) as notice:
        _open(window, qtbot, project)  # the texture job fails on the side lane
    assert "not a readable image" in notice.args[0] and "generated" in notice.args[0]
    window.last_error_box.close()
    # the photo's texture stays on screen until the generated one replaces it (the notice may
    # come first): wait for the generated one, not for any texture
    qtbot.waitUntil(
        lambda: (window.viewport.texture_key or (None,))[0] == ("auto",), timeout=WAIT_MS
    )
    generated = np.asarray(base_color(window.session.result, "auto"))
    np.testing.assert_array_equal(window.viewport.texture_actor_image(), generated)


def test_the_image_arrives_on_the_same_actor_and_keeps_the_view_aids(window, qtbot):
    """Until the image is made the mesh has the blade's colour; the image then goes onto the
    same actor, so the height exaggeration (explain.py's view aids) stays on it."""
    window.view_aids.exaggeration.setValue(3.0)
    window.coloring.setCurrentIndex(window.coloring.findData(TEXTURE))
    actor = window.viewport.plotter.actors["mesh"]
    assert actor.GetUserMatrix() is not None
    if window.viewport.texture_key is None:  # the blade's colour while the image is made
        assert window.viewport.texture_actor_image().shape[:2] == (1, 1)
    qtbot.waitUntil(lambda: window.viewport.texture_key is not None, timeout=WAIT_MS)
    assert window.viewport.plotter.actors["mesh"] is actor and actor.GetUserMatrix() is not None
    assert window.viewport.texture_actor_image().shape == (1024, 1024, 4)
