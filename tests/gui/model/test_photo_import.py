"""File > Open photo's ruler and the photo's DPI, through the dialog's model (issue 23, item 6:
"the photo's own scale when it has one (DPI, or a ruler the user clicks)")."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from leafstudio.errors import LeafError
from leafstudio.forms import make_form
from leafstudio.gui.model.opening import read_document
from leafstudio.gui.model.photo_import import PhotoImport, real_length_text
from tests.photos import form_photo

PIXELS_PER_UNIT = 360.0  # form_photo's: base to apex is 360 pixels


@pytest.fixture(scope="module")
def photo(tmp_path_factory) -> str:
    form = make_form("ovate")
    image = form_photo(form.boundary, form.veins, angle=25.0)[0]
    path = tmp_path_factory.mktemp("photo") / "leaf.png"
    Image.fromarray(image).save(path)
    return str(path)


def _length(document) -> float:
    return float(np.max(document.leaf.boundary[:, 0]))


def test_a_ruler_clicked_on_the_photo_gives_the_leaf_its_real_size(photo):
    model = PhotoImport.of(photo)
    assert model.dpi is None and "records no scale" in model.summary()
    model.click((100.0, 40.0))
    assert "second end" in model.summary()
    model.click((100.0, 40.0 + 180.0))  # 180 pixels: half the leaf's length
    model.distance = "10 mm"
    assert model.options() == {"pixel_size": pytest.approx(10 / 180)}
    assert model.real_size() and "180 pixels are 10 mm" in model.summary()
    document = read_document(photo, **model.options())
    assert _length(document) == pytest.approx(20.0, rel=0.02)  # millimetres
    assert real_length_text(document.leaf.boundary).endswith("mm")

    model.length = "5cm"  # a typed length wins over the ruler
    assert model.options() == {"length": 50.0} and model.from_what() == "length"
    model.click((0.0, 0.0))  # a third click starts a new ruler
    assert len(model.ruler) == 1


def test_a_half_ruler_or_a_bad_distance_is_refused_in_words(photo):
    model = PhotoImport.of(photo)
    model.distance = "10 mm"
    with pytest.raises(LeafError, match="click the ruler's two ends"):
        model.options()
    model.click((10.0, 10.0))
    model.click((50.0, 10.0))
    model.distance = "ten"
    with pytest.raises(LeafError, match="ruler's distance"):
        model.options()
    assert "ruler's distance" in model.summary()


def test_the_photos_dpi_is_its_scale_when_nothing_else_is_given(photo, tmp_path):
    scan = tmp_path / "scan.png"
    Image.open(photo).save(scan, dpi=(600, 600))
    model = PhotoImport.of(str(scan))
    assert model.dpi == 600 and model.real_size() and model.options() == {}
    assert "600 DPI" in model.summary()
    document = read_document(str(scan), **model.options())
    assert _length(document) == pytest.approx(PIXELS_PER_UNIT * 25.4 / 600, rel=0.02)


def test_the_dialog_names_the_base_end_as_photo_base_end_does(tmp_path):
    """`leafstudio photo --base-end left` had no counterpart in File > Open photo: an obovate
    leaf whose veins do not show came out base at its wider end, its apex, with no way to say
    otherwise. The dialog's model takes the end as the command does."""
    form = make_form("obovate")
    path = tmp_path / "obovate.png"
    Image.fromarray(form_photo(form.boundary, angle=0.0)[0]).save(path)  # base left, no veins
    model = PhotoImport.of(str(path))
    assert model.base_end == "auto" and model.options() == {}

    def widest(document) -> float:  # where along base to apex the blade is widest, 0 to 1
        boundary = document.leaf.boundary
        return boundary[np.argmax(np.abs(boundary[:, 1])), 0] / np.max(boundary[:, 0])

    assert widest(read_document(str(path), **model.options())) < 0.5  # the wider end taken
    model.base_end = "left"
    assert model.options() == {"base_end": "left"}
    assert "base at the left end" in model.summary()
    assert widest(read_document(str(path), **model.options())) > 0.5  # obovate, as drawn
