"""A form's veins stand on a smooth dome (forms/relief.py; issue 21)."""

from __future__ import annotations

import numpy as np
import pytest
from shapely.geometry import Polygon

import leafstudio.forms.veins as veins_module
from leafstudio.errors import LeafError
from leafstudio.forms import grow_veins
from leafstudio.forms.blade import Blade
from leafstudio.forms.make import Form
from leafstudio.forms.relief import SINUS, base_angle, dome, notches


def _ellipse(a: float = 0.5, b: float = 0.2) -> Blade:
    t = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    return Blade(Polygon(np.column_stack([0.5 + a * np.cos(t), b * np.sin(t)])))


def test_the_dome_on_an_ellipse_is_the_paraboloid_met_at_the_roofs_slope():
    """The membrane −Δψ = 1, ψ = 0 on an ellipse's margin is s = 1 − x²/a² − y²/b² scaled, and
    the dome is s (1 + s) / 2 as high as the roof's top (0.25 b), flattened only around the
    base (here the left end, far from the points checked); across the middle it meets the
    margin at the roof's slope."""
    a, b = 0.5, 0.2
    heights = dome(_ellipse(a, b), 0.25, np.array([0.0, 0.0]))
    rng = np.random.default_rng(1)
    xy = rng.uniform([0.4, -b], [1.0, b], (3000, 2))
    s = 1 - ((xy[:, 0] - 0.5) / a) ** 2 - (xy[:, 1] / b) ** 2
    xy, s = xy[s > 0.0], s[s > 0.0]
    exact = 0.25 * b * s * (1 + s) / 2
    assert np.abs(heights(xy) - exact).max() <= 5e-4  # of a top 0.05 high
    edge = np.array([[0.5, b - 1e-3], [0.5, b - 2e-3]])
    slope = np.diff(heights(edge))[0] / 1e-3
    assert slope == pytest.approx(0.25, rel=0.05)


def test_the_dome_has_no_crease_along_the_midrib():
    """The roof's slope jumps by half across the midrib (0.25 up, 0.25 down); the dome's is
    continuous there."""
    heights = dome(_ellipse(), 0.25, np.array([0.0, 0.0]))
    step = 0.01
    at = np.array([[0.6, -step], [0.6, 0.0], [0.6, step]])
    z = heights(at)
    jump = ((z[2] - z[1]) - (z[1] - z[0])) / step
    assert abs(jump) < 0.05


def test_grown_veins_keep_the_roof_unless_asked():
    """Veins grown in a drawn or loaded outline keep today's heights; an unknown relief is a
    one-line error."""
    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    outline = np.column_stack([0.5 + 0.5 * np.cos(t), 0.25 * np.sin(t)])
    roof = grow_veins(outline, "pinnate", secondaries=4)
    again = grow_veins(outline, "pinnate", secondaries=4, relief="roof")
    domed = grow_veins(outline, "pinnate", secondaries=4, relief="dome")
    assert all(np.array_equal(r, s) for r, s in zip(roof, again, strict=True))
    assert all(np.array_equal(r[:, :2], d[:, :2]) for r, d in zip(roof, domed, strict=True))
    assert not np.allclose(roof[0][:, 2], domed[0][:, 2])
    with pytest.raises(LeafError, match="unknown relief"):
        grow_veins(outline, relief="tent")


@pytest.mark.parametrize(
    ("shape", "sinus"),
    [
        ("orbicular", False),
        ("oblong", False),
        ("hastate", False),
        ("cordate", True),
        ("reniform", True),
        ("sagittate", True),
    ],
)
def test_a_base_is_a_sinus_where_the_outline_turns_inward(shape, sinus, monkeypatch):
    """base_angle: a round or truncate base fills about half a small circle around it, a
    sinus's notch (the lobes reach back past the base) more than SINUS degrees of it."""
    seen = []

    def spy(blade, ratio, base, round_base=False):
        seen.append(base_angle(blade, base))
        return dome(blade, ratio, base, round_base)

    monkeypatch.setattr(veins_module, "dome", spy)
    Form(shape).leaf()
    assert (seen[0] > SINUS) == sinus
    if not sinus:
        assert seen[0] == pytest.approx(180, abs=15)


@pytest.mark.parametrize("margin", ["entire", "serrate", "dentate", "crenate", "sinuate"])
def test_hastate_lobes_notches_are_found_under_any_margin(margin, monkeypatch):
    """notches: hastate's two notches between the blade and its lobes, whatever the margin's
    teeth; an ovate form with teeth has none."""
    seen = []

    def spy(blade, ratio, base, round_base=False):
        seen.append(notches(blade))
        return dome(blade, ratio, base, round_base)

    monkeypatch.setattr(veins_module, "dome", spy)
    Form("hastate", margin=margin).leaf()
    Form("ovate", margin=margin).leaf()
    lobes, ovate = seen
    assert len(lobes) == 2 and len(ovate) == 0
    assert np.allclose(np.sort(lobes[:, 1]), [-0.3, 0.3], atol=0.03)
    assert np.allclose(lobes[:, 0], 0.15, atol=0.04)


def test_the_dome_is_flat_at_a_lobes_notch(monkeypatch):
    """ψ rises beside hastate's notches between the blade and its lobes as steeply as at a
    sinus's notch (the vein correction then creased the veinless lobe): the dome is flattened
    there too. A lobed margin's notches, near the axis, are left (flattened, the midrib's dome
    went with them)."""
    domes = []

    def spy(blade, ratio, base, round_base=False):
        domes.append((blade, dome(blade, ratio, base, round_base)))
        return domes[-1][1]

    monkeypatch.setattr(veins_module, "dome", spy)
    Form("hastate").leaf()
    Form("ovate", margin="lobed", lobes=5).leaf()
    (blade, heights), (lobed, lobed_heights) = domes
    for notch in notches(blade):
        way = np.array([0.3, 0.0]) - notch
        inward = notch + 0.02 * way / np.linalg.norm(way)
        assert blade.inside(inward[None])[0]
        assert heights(inward[None])[0] < 1e-4  # 0.0033 before: 0.02 in from the margin
    assert len(notches(lobed)) == 4
    assert lobed_heights(np.array([[0.5, 0.0]]))[0] > 0.03  # 0.042; 0.009 flattened


@pytest.mark.parametrize(
    ("base", "flat"), [("rounded", False), ("truncate", True), ("cuneate", True)]
)
def test_the_dome_is_flattened_at_a_truncate_or_cuneate_base_only(base, flat):
    """A rounded base is a smooth arc: the dome rises from it as from any margin, and flattened
    there the midrib was flat for 0.04 of the length and then turned up, a bend a surface
    through it had to follow (orbicular). A truncate or a cuneate base, whose corners crease
    without it, is flattened within BASE_CALM."""
    midrib = Form("ovate", base=base).leaf().veins[0]
    near = np.asarray(midrib)[:, 0] < 0.06  # the base at x = 0, the length 1
    rise = np.asarray(midrib)[near, 2] / np.maximum(np.asarray(midrib)[near, 0], 1e-9)
    assert (rise[1:].min() < 0.05) == flat  # the slope from the base: ~0 flattened, ~0.2 not
