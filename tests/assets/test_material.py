"""Issue 23 follow-up: backlit Blender renders of the leaf material looked pale. Blender tints
transmitted light by the square root of the base colour, so the base colour's blue must be low
for the light through the blade to stay a leaf's yellow-green (a real leaf transmits about 5%
of blue, 15-20% of green)."""

from __future__ import annotations

import numpy as np

from leafstudio.assets.texture import BLADE, VEIN


def _linear(srgb: tuple[int, int, int]) -> np.ndarray:
    c = np.asarray(srgb, float) / 255
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _srgb(linear: np.ndarray) -> np.ndarray:
    c = np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * linear ** (1 / 2.4) - 0.055)
    return 255 * c


def test_the_light_through_the_blade_stays_green_in_blender():
    transmitted = _srgb(np.sqrt(_linear(BLADE)))  # Blender's tint through one sheet
    red, green, blue = transmitted
    assert blue < 0.5 * green  # the old (78, 128, 50) gave 118 of 181: a grey-mint
    assert red < 0.8 * green


def test_veins_are_paler_than_the_blade_and_as_warm():
    assert all(v > b for v, b in zip(VEIN, BLADE, strict=True))
    assert VEIN[2] < 0.5 * VEIN[1]
