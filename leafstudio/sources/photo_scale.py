"""A photo's own scale: how long one of its pixels is, when the file says (issue 23, item 6).

A flatbed scan records its resolution: PNG's pHYs chunk, JPEG's JFIF density, TIFF's and EXIF's
XResolution with ResolutionUnit (inch or centimetre). Pillow reads the first three into
`info["dpi"]`; EXIF is read from `getexif()` for the formats that keep it elsewhere. Not every
resolution is a scale: 72 and 96 DPI are what editors and screens write by default, and a
camera's EXIF carries a print resolution (Nikon 300, Canon 180) that says nothing of the leaf's
size; so those are not taken (`photo_dpi` returns None), and a photo without a scale keeps the
leaf's length 1 unless one is given (`--length`, or the ruler in the app's Open photo dialog).
"""

from __future__ import annotations

from pathlib import Path

MM_PER_INCH = 25.4
SCREEN_DEFAULTS = (72.0, 96.0)  # DPI written by default, not measured
CAMERA_TAGS = (0x829A, 0x829D, 0x920A)  # EXIF ExposureTime, FNumber, FocalLength
EXIF_IFD = 0x8769
X_RESOLUTION, RESOLUTION_UNIT = 0x011A, 0x0128
UNIT_INCHES = {2: 1.0, 3: 2.54}  # ResolutionUnit: inches, centimetres (to DPI)


def photo_dpi(path: str | Path) -> float | None:
    """The resolution an image file records, in dots per inch, or None when it records none
    that is a scale (see the module docstring). Never raises for a file Pillow cannot read:
    that is read_image's to say."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as image:
            exif = image.getexif()
            dpi = image.info.get("dpi")
    except (UnidentifiedImageError, OSError, ValueError, SyntaxError):
        return None
    camera = any(tag in exif.get_ifd(EXIF_IFD) for tag in CAMERA_TAGS)
    value = _first(dpi)
    if value is None and exif.get(X_RESOLUTION) is not None:
        unit = exif.get(RESOLUTION_UNIT, 2)
        if unit in UNIT_INCHES:
            value = _first(exif[X_RESOLUTION]) * UNIT_INCHES[unit]
    if value is None or camera:
        return None
    value = round(value, 1)  # PNG keeps whole pixels per metre: 72 DPI reads 72.009
    return None if value in SCREEN_DEFAULTS or value <= 0 else value


def _first(value: object) -> float | None:
    """A resolution's horizontal value as a float (Pillow gives tuples or rationals)."""
    if value is None:
        return None
    if isinstance(value, tuple):
        value = value[0]
    try:
        number = float(value)  # an IFDRational converts
    except (TypeError, ValueError, ZeroDivisionError):
        return None
    return number if number == number and number > 0 else None


def dpi_pixel_size(path: str | Path) -> tuple[float, float] | None:
    """(millimetres per pixel, DPI) from the file's resolution, or None (photo_dpi)."""
    dpi = photo_dpi(path)
    return None if dpi is None else (MM_PER_INCH / dpi, dpi)
