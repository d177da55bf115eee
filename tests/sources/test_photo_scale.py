"""A photo's own scale (issue 23, item 6): a scan's recorded DPI makes the leaf its real size
when no length is given, and the command line says so."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from leafstudio.cli import main
from leafstudio.forms import make_form
from leafstudio.sources.files import load_leaf
from leafstudio.sources.photo import read_photo_leaf
from leafstudio.sources.photo_scale import photo_dpi
from tests.photos import form_photo

PIXELS_PER_UNIT = 360.0  # form_photo's: the form's length 1 is 360 pixels base to apex


@pytest.fixture(scope="module")
def image() -> np.ndarray:
    form = make_form("ovate")
    return form_photo(form.boundary, form.veins, angle=25.0)[0]


def test_a_scans_dpi_gives_the_leaf_its_real_length(image, tmp_path, capsys):
    path = tmp_path / "scan.png"
    Image.fromarray(image).save(path, dpi=(300, 300))
    assert photo_dpi(path) == 300
    found = read_photo_leaf(path)
    real = PIXELS_PER_UNIT * 25.4 / 300  # millimetres
    assert found.length == pytest.approx(real, rel=0.02)
    assert np.ptp(found.leaf.boundary[:, 0]) == pytest.approx(real, rel=0.03)
    assert found.scale == "the photo's 300 DPI"
    assert read_photo_leaf(path, length=2.0).length == 2.0  # a given length wins

    out = tmp_path / "leaf.csv"
    assert main(["photo", str(path), "-o", str(out)]) == 0
    assert "mm long (the photo's 300 DPI" in capsys.readouterr().err
    assert np.ptp(load_leaf(out).boundary[:, 0]) == pytest.approx(real, rel=0.03)


def test_exif_resolution_in_centimetres_is_read(image, tmp_path):
    exif = Image.Exif()
    exif[0x011A], exif[0x0128] = 100.0, 3  # 100 pixels a centimetre: 254 DPI
    path = tmp_path / "scan.png"
    Image.fromarray(image).save(path, exif=exif)
    assert photo_dpi(path) == pytest.approx(254.0)


def test_default_and_camera_resolutions_are_no_scale(image, tmp_path, capsys):
    plain = tmp_path / "plain.png"
    Image.fromarray(image).save(plain, dpi=(72, 72))  # an editor's default
    assert photo_dpi(plain) is None
    assert read_photo_leaf(plain).length == 1.0
    assert main(["photo", str(plain), "-o", str(tmp_path / "p.csv")]) == 0
    assert "the photo records no scale" in capsys.readouterr().err

    exif = Image.Exif()
    exif[0x011A], exif[0x0128] = 300.0, 2
    exif.get_ifd(0x8769)[0x920A] = 4.5  # a focal length: a camera's print resolution
    camera = tmp_path / "camera.jpg"
    Image.fromarray(image).save(camera, exif=exif, quality=95)
    assert photo_dpi(camera) is None
    assert photo_dpi(tmp_path / "missing.png") is None
