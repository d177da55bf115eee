"""A leaf from botanical terms: the outline (outline.py), grown veins (veins.py) and relief.

The convention (docs/architecture.md): the blade's base, where the midrib meets it, is at the
origin; the apex lies on +x and the outline's farthest point along +x is at x = 1; the blade lies
in z = 0 apart from its relief. Relief is heights on the boundary and the veins, so it goes through
the pipeline like any leaf's: the fold and the wave on the boundary become the base surface b(x),
the veins' heights above it (a smooth dome, forms/relief.py) the Gaussian mixture.
"""

from __future__ import annotations

import warnings
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np
import shapely

from leafstudio.core.base import fit_base
from leafstudio.core.bend import Pose
from leafstudio.core.pose_limits import eased_roll, seam_note
from leafstudio.core.pose_relief import relief_of
from leafstudio.core.prepare.vein_order import veins_inside_outline
from leafstudio.errors import LeafError
from leafstudio.forms.outline import FormOutline, form_outline
from leafstudio.forms.terms import (
    APEXES,
    DEFAULT_LOBES,
    DEFAULT_TEETH,
    MARGINS,
    SHAPES,
    TOOTHED,
    USER_BASES,
    check_term,
)
from leafstudio.forms.veins import VENATION_KINDS, grow_veins
from leafstudio.model import Leaf

WAVES_PER_SIDE = 3
WAVE_WIDTH_SHARE = 0.5  # the margin's wave at most this share of the blade's half-width
VEIN_SLACK = 0.004  # vein points may lie this far (of the length) outside the outline as the
# pipeline sees it (it allows 0.01): the midrib's ends on the base and apex are kept
LIMITS = {  # name: (lowest, highest)
    "teeth": (2, 300),
    "lobes": (2, 15),
    "secondaries": (0, 40),
    "aspect": (0.5, 30.0),
    "fold": (-75.0, 75.0),
    "curl": (-1.0, 1.0),
    "roll": (-1.0, 1.0),
    "twist": (-1.0, 1.0),
    "wave": (0.0, 0.2),
}


class _Still:
    """Stands in for a random generator when seed is 0: every draw is its range's middle, so the
    canonical form is the one the definitions describe."""

    def uniform(self, low: float = 0.0, high: float = 1.0, size: Any = None) -> Any:
        mid = 0.5 * (low + high)
        return mid if size is None else np.full(size, mid)


@dataclass(frozen=True)
class Form:
    """A leaf form by its terms (terms.py lists and defines them); None means the shape's usual.

    The leaf follows the forms' convention: base at the origin, apex on +x at length 1, the
    blade in z = 0 apart from its relief.

    Parameters
    ----------
    shape : str, default: "elliptic"
        One of `SHAPES` (linear, lanceolate, ..., ovate, cordate, ...); every term in any case,
        spaces around it ignored ("Ovate").
    apex, base : str, optional
        Apex and base terms (acute, obtuse, rounded, ...; cuneate, rounded, truncate, ...);
        default the shape's usual. Shapes defined by their base (cordate, reniform, sagittate,
        hastate) refuse another base.
    margin : str, default: "entire"
        entire, serrate, serrulate, dentate, crenate, sinuate or lobed.
    teeth, lobes : int, optional
        Teeth along a toothed margin, lobes of a lobed one; default the margin's usual.
    venation : {"pinnate", "palmate", "parallel", "arcuate"}, optional
        Default the shape's usual: palmate for reniform, else pinnate.
    secondaries : int, optional
        Secondary veins on each side (see `grow_veins`); default the shape's usual (10 for
        deltoid, 8 for spatulate, else the venation's: 6 pinnate).
    aspect : float, optional
        Length over width; default the shape's usual.
    fold, curl, roll, wave, twist : float, default: 0.0
        Relief: the fold along the midrib (degrees), the curl along the length, the roll
        across it (the share of a half turn the widest margins roll through: 1 closes the
        blade into a tube; negative rolls them down), the margin's wave amplitude, the twist
        about the midrib (half turns of the apex against the base).
    seed : int, default: 0
        0 gives the form exactly; other seeds vary it a little, the same seed the same leaf.

    Raises
    ------
    LeafError
        For an unknown term or a value out of its range, in the words of `leafstudio form`.

    Examples
    --------
    >>> from leafstudio.forms import Form
    >>> leaf = Form("ovate", margin="serrate", teeth=30).leaf()
    >>> float(leaf.boundary[:, 0].max())
    1.0
    >>> Form("roundish")
    Traceback (most recent call last):
    leafstudio.errors.LeafError: unknown shape 'roundish'; choose from linear, ...
    """

    shape: str = "elliptic"
    apex: str | None = None
    base: str | None = None
    margin: str = "entire"
    teeth: int | None = None
    lobes: int | None = None
    venation: str | None = None
    secondaries: int | None = None
    aspect: float | None = None
    fold: float = 0.0
    curl: float = 0.0
    wave: float = 0.0
    seed: int = 0
    roll: float = 0.0
    twist: float = 0.0

    def __post_init__(self) -> None:
        for name, allowed in (("shape", SHAPES), ("apex", APEXES), ("base", USER_BASES),
                              ("margin", MARGINS), ("venation", VENATION_KINDS)):  # fmt: skip
            if getattr(self, name) is not None:  # kept as the tables spell it ("Ovate": ovate)
                object.__setattr__(self, name, check_term(name, getattr(self, name), allowed))
        spec = SHAPES[self.shape]
        if self.base is not None and spec.fixed_base and self.base != spec.base:
            raise LeafError(
                f"a {self.shape} leaf has a {spec.base} base by definition; leave out --base"
            )
        if self.teeth is not None and self.margin not in TOOTHED:
            raise LeafError(f"--teeth needs a toothed margin ({', '.join(TOOTHED)})")
        if self.lobes is not None and self.margin != "lobed":
            raise LeafError("--lobes needs --margin lobed")
        for name, (low, high) in LIMITS.items():
            value = getattr(self, name)
            if value is not None and not low <= value <= high:
                raise LeafError(f"--{name} must be between {low:g} and {high:g}, got {value:g}")
        if self.seed < 0:
            raise LeafError(f"--seed must be zero or positive, got {self.seed}")

    # the terms in effect
    @property
    def apex_term(self) -> str:
        return self.apex or SHAPES[self.shape].apex

    @property
    def base_term(self) -> str:
        return self.base or SHAPES[self.shape].base

    @property
    def venation_term(self) -> str:
        return self.venation or SHAPES[self.shape].venation

    @property
    def secondaries_count(self) -> int | None:
        """Secondaries on each side: the given count, else the shape's usual with its usual
        venation (ShapeSpec.secondaries), else None (the venation's default)."""
        if self.secondaries is not None:
            return self.secondaries
        spec = SHAPES[self.shape]
        return spec.secondaries if self.venation_term == spec.venation else None

    @property
    def teeth_count(self) -> int:
        return self.teeth or DEFAULT_TEETH.get(self.margin, 0)

    @property
    def lobe_count(self) -> int:
        return self.lobes or (DEFAULT_LOBES if self.margin == "lobed" else 1)

    def with_(self, **changes: Any) -> Form:
        """A copy with some terms changed (checked again)."""
        return replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    def outline(self) -> FormOutline:
        """The blade's outline in the plane (see outline.py)."""
        rng = np.random.default_rng(self.seed) if self.seed else _Still()
        spec = SHAPES[self.shape]
        aspect = (self.aspect or spec.aspect) * (1 + rng.uniform(-0.05, 0.05))
        return form_outline(
            self.shape,
            self.apex_term,
            self.base_term,
            self.margin,
            self.teeth_count,
            self.lobe_count,
            aspect,
            self.venation_term == "palmate",
            rng,  # type: ignore[arg-type]
        )

    def leaf(self, blade: Leaf | None = None) -> Leaf:
        """The leaf: boundary and grown veins, with heights for the fold, curl and wave.

        Parameters
        ----------
        blade : Leaf, optional
            This form's flat blade (`blade()`), when the caller kept it: a change of pose alone
            then grows no veins again (the Forms dock's pose sliders).

        Returns
        -------
        Leaf
            The (n, 3) outline and the veins (midrib first), in the forms' convention.
        """
        if blade is not None and not isinstance(blade, Leaf):
            raise LeafError(f"blade must be a Leaf (Form.blade()), not {type(blade).__name__}")
        if blade is None:
            blade, note = self.blade_and_note()
            if note:
                warnings.warn(note, stacklevel=2)
        if self.fold == 0 and self.curl == 0 and self.roll == 0 and self.twist == 0:
            return blade
        # the leaf knows its pose: reconstruction runs on the flat blade and bends the mesh
        # (core/bend.py), so no fold or curl stands it on edge; the veins are kept on the blade
        half_width = float(np.abs(blade.boundary[:, 1]).max())  # the roll's share of a turn
        # bent about its own relief: a fold turns each half about the midrib as it stands, a
        # roll keeps each section's length and a curl the midrib's (core/pose_relief.py)
        relief = relief_of(blade.boundary, blade.veins)
        pose = Pose(
            self.fold, self.curl, self.roll * np.pi / half_width, self.twist * np.pi, relief
        )
        pose = eased_roll(pose, half_width)  # a folded or twisted tube kept off its seam
        return Leaf(pose.apply(blade.boundary), [pose.apply(v) for v in blade.veins], bend=pose)

    def seam_note(self) -> str:
        """What `leaf` says of its roll when it eased it (pose_limits.seam_note); "" when the
        roll is as asked."""
        return seam_note(self.roll, self.fold, self.twist)

    def unposed(self) -> Form:
        """This form without its fold, curl, roll and twist: the terms its blade depends on."""
        return replace(self, fold=0.0, curl=0.0, roll=0.0, twist=0.0)

    def blade(self) -> Leaf:
        """The flat blade: the outline with its wave, and the veins grown in it (about 60 ms, the
        growth most of it); `leaf()` poses it. Warns (SIDE_ON) as `blade_and_note` notes."""
        blade, note = self.blade_and_note()
        if note:
            warnings.warn(note, stacklevel=2)
        return blade

    def blade_and_note(self) -> tuple[Leaf, str]:
        """The flat blade (`blade`), and the side-on note when its veins had to be clipped to
        the outline in the blade's own plane ("" if none): said, not warned, for a caller off
        the main thread (warnings.catch_warnings is not thread-safe)."""
        outline = self.outline()
        xy = outline.xy
        veins = grow_veins(
            xy,
            self.venation_term,
            self.secondaries_count,
            base=np.zeros(2),
            seed=self.seed,
            apex=xy[outline.apex_index],
            relief="dome",
            round_base=self.base_term == "rounded",
        )
        wave = self._wave(outline)
        base = fit_base(xy, wave, 1.0)  # the wave's surface (the pipeline's b): veins ride on it
        if base is not None:
            veins = [np.column_stack([v[:, :2], v[:, 2] + base(v[:, :2])]) for v in veins]
        boundary = np.column_stack([xy, wave])
        veins, side_on = _veins_on_blade(boundary, veins)
        return Leaf(boundary, veins), f"{SIDE_ON}; lower the fold or curl" if side_on else ""

    def _wave(self, outline: FormOutline) -> np.ndarray:
        """The margin's waves: WAVES_PER_SIDE along each half, fading to none at the base and
        apex (the envelope sin(π s/S) flattens them there too: a full-slope wave met its mirror
        at the base in a V that no smooth base b(x) follows, and the pipeline's b, through other
        outline points than the form's, missed the midrib's end by 2.7% of the length)."""
        z = np.zeros(len(outline.xy))
        if self.wave == 0:
            return z
        # no higher than half the blade's half-width: a wave taller than a narrow blade is wide
        # tilts the boundary's plane on its side, and the outline then crosses itself there
        amplitude = min(self.wave, WAVE_WIDTH_SHARE * float(np.abs(outline.xy[:, 1]).max()))
        for half in (outline.lower, outline.upper):
            pts = outline.xy[half]
            s = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
            t = s / s[-1]
            z[half] = amplitude * np.sin(2 * np.pi * WAVES_PER_SIDE * t) * np.sin(np.pi * t)
        return z


SIDE_ON = (
    "this fold or curl stands the leaf on edge to the plane reconstruction fits to its "
    "boundary, so a mesh of it would be a side view"
)


def seen_on_edge(leaf: Leaf) -> bool:
    """Whether the pipeline would see this posed form on edge: a whole vein lies outside the
    outline on the boundary's PCA plane, which it takes for the leaf's, so that plane is not the
    blade's and a reconstruction would be a side view of the blade (see _veins_on_blade)."""
    if leaf.bend is not None:  # reconstructed on its flat blade (core/bend.py)
        return False
    return len(veins_inside_outline(leaf.boundary, leaf.veins, -VEIN_SLACK)) < len(leaf.veins)


def _veins_on_blade(boundary: np.ndarray, veins: list[np.ndarray]) -> tuple[list[np.ndarray], bool]:
    """The posed veins' points inside the posed outline as the pipeline sees it, on the
    boundary's PCA plane, when that outline holds every vein; else inside the outline before
    posing (the blade's own plane, z = 0, where the pose only added heights), and True: the
    plane stands on edge to the blade (SIDE_ON)."""
    seen = veins_inside_outline(boundary, veins, -VEIN_SLACK)
    if len(seen) == len(veins):
        # a fold, curl or wave tilts the boundary's plane: a vein end near the margin can fall
        # outside the outline there, and the pipeline refuses such a vein
        return seen, False
    # a fold or curl that raises the margin higher than the blade is wide stands that plane on
    # edge to the blade: the outline there is the blade's side view (a fold's halves fall on
    # each other), and whole veins, often all, the midrib too, fell outside it
    region = shapely.Polygon(boundary[:, :2]).buffer(VEIN_SLACK)
    kept = [v[shapely.contains_xy(region, v[:, 0], v[:, 1])] for v in veins]
    return [v for v in kept if len(v) >= 2], True


def make_form(shape: str = "elliptic", **terms: Any) -> Leaf:
    """The leaf of a form: `make_form("ovate", margin="serrate", teeth=30)`.

    Parameters
    ----------
    shape : str, default: "elliptic"
        One of `SHAPES`, in any case ("Ovate").
    **terms
        The other terms of `Form` (apex, base, margin, teeth, lobes, venation, secondaries,
        aspect, fold, curl, roll, wave, twist, seed).

    Returns
    -------
    Leaf
        The (n, 3) outline and the (m_i, 3) veins, midrib first: base at the origin, apex on +x
        at length 1, z = 0 apart from the relief.

    Raises
    ------
    LeafError
        For an unknown term or a value out of its range.

    Examples
    --------
    >>> from leafstudio.forms import make_form
    >>> leaf = make_form("ovate", margin="serrate", teeth=30)
    >>> leaf.boundary.shape, len(leaf.veins)
    ((704, 3), 13)
    >>> leaf.veins[0][0, :2].round(3).tolist()  # the midrib starts at the base
    [0.01, 0.0]
    """
    return Form(shape, **terms).leaf()
