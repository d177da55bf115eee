"""Veins from a photo are the veins it shows (issue 23, finding 6): traced, not invented."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from leafstudio.cli import main
from leafstudio.core.plane import fit_frame
from leafstudio.forms import make_form
from leafstudio.sources.photo import leaf_from_photo
from tests.leaves import extracted_scan
from tests.photos import REALLEAVES, form_photo, photo_pixels

SCANS = sorted(REALLEAVES.glob("*.txt"))


def _whole_length_gap(found, drawn_px: np.ndarray) -> float:
    """The farthest any point of either midrib, the traced one or the drawn one, lies from the
    other, over their whole lengths, in shares of the drawn one's base-to-tip length (in the
    photo's pixels): the traced midrib follows the drawn one all along, and stops where it
    stops (a drawn midrib that stops short of the outline is the one the photo shows)."""
    traced = found.leaf.veins[0][:, :2]
    traced_px = np.column_stack([traced, np.ones(len(traced))]) @ found.pixel_from_world.T
    length = float(np.linalg.norm(drawn_px[-1] - drawn_px[0]))
    lines = shapely.LineString(drawn_px), shapely.LineString(traced_px)
    farthest = [
        shapely.distance(
            other, shapely.points(shapely.get_coordinates(shapely.segmentize(line, 1.0)))
        ).max()
        for line, other in (lines, lines[::-1])
    ]
    return float(max(farthest)) / length


@pytest.mark.parametrize("shape", ["ovate", "cordate", "lanceolate", "obovate"])
@pytest.mark.parametrize("angle", [25.0, 100.0])
def test_a_forms_drawn_midrib_is_traced_within_2_percent(shape, angle):
    leaf = make_form(shape)
    image, _, _ = form_photo(leaf.boundary, leaf.veins, angle=angle)
    found = leaf_from_photo(image, length=1.0)
    assert found.veins_from == "photo"
    drawn_px = photo_pixels(leaf.boundary, angle)(leaf.veins[0])
    assert _whole_length_gap(found, drawn_px) <= 0.02
    assert len(found.leaf.veins) - 1 >= 0.6 * (len(leaf.veins) - 1)  # most secondaries seen


CANVAS = (820, 820)  # the 560-pixel leaf turned 30 degrees fits with a margin


@pytest.mark.parametrize("scan", SCANS, ids=lambda p: p.stem)
def test_a_real_leafs_outline_with_drawn_veins_gives_its_midrib(scan):
    """The traced midrib lies within 2% of the length of the drawn one over its whole length,
    both ways (_whole_length_gap)."""
    from leafstudio.core.bend import flat_leaf

    leaf = flat_leaf(extracted_scan(scan)[1].leaf)  # the blade as drawn: unrolled (core/sheet.py)
    frame = fit_frame(leaf.boundary, np.zeros((0, 3)))
    outline = frame.to_plane(leaf.boundary)[0]
    veins = [frame.to_plane(v)[0] for v in leaf.veins]
    ppu = 560.0 / float(np.ptp(outline, axis=0).max())
    image, _, _ = form_photo(outline, veins, angle=30.0, pixels_per_unit=ppu, size=CANVAS)
    found = leaf_from_photo(image, length=1.0)
    assert found.veins_from == "photo"
    drawn_px = photo_pixels(outline, 30.0, ppu, CANVAS)(veins[0])
    assert _whole_length_gap(found, drawn_px) <= 0.02


def test_a_photo_without_visible_veins_grows_them_and_says_so(tmp_path, capsys):
    leaf = make_form("ovate")
    image, _, _ = form_photo(leaf.boundary, [], angle=25.0)
    assert leaf_from_photo(image).veins_from == "grown"
    traced = leaf_from_photo(image, veins="trace")
    assert traced.veins_from == "none" and not traced.leaf.veins
    from PIL import Image

    path = tmp_path / "plain.png"
    Image.fromarray(image).save(path)
    assert main(["photo", str(path), "-o", str(tmp_path / "p.leaf.json")]) == 0
    assert "grown: the photo shows no midrib" in capsys.readouterr().err


def test_the_command_line_says_the_veins_were_traced(tmp_path, capsys):
    from PIL import Image

    leaf = make_form("ovate")
    image, _, _ = form_photo(leaf.boundary, leaf.veins, angle=25.0)
    path = tmp_path / "veined.png"
    Image.fromarray(image).save(path)
    assert main(["photo", str(path), "-o", str(tmp_path / "p.leaf.json")]) == 0
    assert "traced in the photo" in capsys.readouterr().err


def test_the_ridge_filter_is_scikit_images_sato_both_ways():
    """photo_veins reads light and dark ridges from one Hessian per width (half the filter's
    time): equal to the last bit to scikit-image's sato run twice, on a photo with veins."""
    from skimage.filters import sato

    from leafstudio.sources.photo_veins import _sato_light_and_dark

    leaf = make_form("ovate")
    image, _, _ = form_photo(leaf.boundary, leaf.veins, angle=25.0, size=(300, 240),
                             pixels_per_unit=150.0)  # fmt: skip
    grey = image.astype(float) @ np.array([0.299, 0.587, 0.114]) / 255
    widths = np.array([1.0, 2.0, 3.0]) * 1.3
    light, dark = _sato_light_and_dark(grey, widths)
    assert np.array_equal(light, sato(grey, sigmas=widths, black_ridges=False, mode="reflect"))
    assert np.array_equal(dark, sato(grey, sigmas=widths, black_ridges=True, mode="reflect"))
    assert light.max() > 0 and dark.max() > 0


@pytest.mark.parametrize("sigma", [0.8, 1.0, 1.3, 2.0, 3.0])
def test_the_hessian_is_scikit_images_to_the_last_bit(sigma):
    """photo_veins.hessian leaves out the Gaussian taps that are exactly 0 (scikit-image widens
    its kernels to 100 sigmas at sigma <= 1): the same Hessian, to the last bit, at widths on
    both sides of that switch."""
    from skimage.feature import hessian_matrix

    from leafstudio.sources.photo_veins import hessian

    leaf = make_form("ovate")
    image, _, _ = form_photo(leaf.boundary, leaf.veins, angle=25.0, size=(300, 240),
                             pixels_per_unit=150.0)  # fmt: skip
    grey = image.astype(float) @ np.array([0.299, 0.587, 0.114]) / 255
    want = hessian_matrix(grey, sigma, mode="reflect", use_gaussian_derivatives=True)
    got = hessian(grey, sigma)
    assert len(got) == 3
    for a, b in zip(got, want, strict=True):
        assert np.array_equal(a, b)


def test_the_hessians_eigenvalues_are_scikit_images_to_the_last_bit():
    from skimage.feature import hessian_matrix_eigvals

    from leafstudio.sources.photo_veins import eigenvalues, hessian

    leaf = make_form("cordate")
    image, _, _ = form_photo(leaf.boundary, leaf.veins, angle=25.0, size=(300, 240),
                             pixels_per_unit=150.0)  # fmt: skip
    grey = image.astype(float) @ np.array([0.299, 0.587, 0.114]) / 255
    elements = hessian(grey, 1.0)
    assert np.array_equal(eigenvalues(*elements), hessian_matrix_eigvals(elements))


def test_reading_a_photo_leaves_scikit_images_feature_module_unloaded():
    """skimage.feature imports scipy.stats: 0.6 s of CPU on the first photo a fresh process
    (the command line, a batch worker) reads; its two filters are written here instead."""
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    script = (
        "import sys\n"
        "from leafstudio.forms import make_form\n"
        "from leafstudio.sources.photo import leaf_from_photo\n"
        "from tests.photos import form_photo\n"
        "leaf = make_form('ovate')\n"
        "found = leaf_from_photo(form_photo(leaf.boundary, leaf.veins, angle=25.0)[0])\n"
        "assert found.veins_from == 'photo', found.veins_from\n"
        "print(sorted(m for m in ('skimage.feature', 'scipy.stats') if m in sys.modules))\n"
    )
    done = subprocess.run([sys.executable, "-c", script], cwd=root, capture_output=True,
                          text=True, timeout=300)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().splitlines()[-1] == "[]"
