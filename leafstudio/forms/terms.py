"""The botanical vocabulary a form is made from, each term with a plain one-line definition.

Terms follow Ellis et al., *Manual of Leaf Architecture* (2009), and the usual textbook glossary.
A shape brings its own usual apex, base, proportions (L/W, length over the greatest width) and the
body of its outline: the half-width along the midrib as a smooth curve through a few values
(`ShapeSpec.body`), which the apex and base terms then finish at each end (outline.py).
"""

from __future__ import annotations

from dataclasses import dataclass

from leafstudio.errors import LeafError


@dataclass(frozen=True)
class ShapeSpec:
    """One shape term.

    Attributes
    ----------
    body : tuple of (t, value)
        Relative half-width at fractions t of the length from base (0) to apex (1); a monotone
        cubic (PCHIP) runs through them.
    aspect : float
        Length over the greatest width.
    apex, base : str
        The usual apex and base terms of the shape.
    apex_zone, base_zone : float
        The share of the length each end term shapes (Ellis: the distal and proximal quarter).
    fixed_base : bool
        The base is part of the shape's definition (basal lobes); --base cannot change it.
    venation : str
        The usual venation of leaves of the shape: palmate for a reniform one (Asarum, Caltha,
        Pelargonium: the main veins spread from the stalk into both lobes), pinnate for the
        rest.
    secondaries : int or None
        The usual secondary veins on each side with the usual venation; None: the venation's
        default (veins.DEFAULT_SECONDARIES, 6 pinnate). Shapes widest at one end carry more,
        so a secondary reaches the wide end's corners: deltoid birches have 6 to 12 pairs
        (Betula nigra and B. papyrifera 6-8, B. ermanii 10-12), and a spoon-shaped blade's
        broad apex takes as many.
    """

    definition: str
    body: tuple[tuple[float, float], ...]
    aspect: float
    apex: str
    base: str
    apex_zone: float = 0.25
    base_zone: float = 0.25
    fixed_base: bool = False
    venation: str = "pinnate"
    secondaries: int | None = None


SHAPES: dict[str, ShapeSpec] = {
    "linear": ShapeSpec(
        "long and narrow, the sides nearly parallel (12 or more times longer than wide)",
        ((0, 1), (0.5, 1), (1, 1)),
        14.0,
        "acute",
        "cuneate",
        0.12,
        0.1,
    ),
    "lanceolate": ShapeSpec(
        "lance-shaped: widest in the lower part, several times longer than wide",
        ((0, 1), (0.3, 1), (1, 0.75)),
        4.5,
        "acute",
        "cuneate",
        0.7,
        0.3,
    ),
    "oblanceolate": ShapeSpec(
        "the reverse of lanceolate: widest in the upper part, tapering to the base",
        ((0, 0.75), (0.7, 1), (1, 1)),
        4.5,
        "acute",
        "cuneate",
        0.3,
        0.7,
    ),
    "elliptic": ShapeSpec(
        "widest in the middle fifth, the two ends alike",
        ((0, 1), (1, 1)),
        2.0,
        "acute",
        "cuneate",
        0.5,
        0.5,
    ),
    "oblong": ShapeSpec(
        "the sides nearly parallel over the middle third, ends rounded",
        ((0, 0.9), (0.3, 1), (0.7, 1), (1, 0.9)),
        2.4,
        "obtuse",
        "rounded",
        0.2,
        0.2,
    ),
    "ovate": ShapeSpec(
        "egg-shaped: widest in the lower two fifths, rounded below, narrower above",
        ((0, 1), (0.35, 1), (1, 0.8)),
        1.6,
        "acute",
        "rounded",
        0.6,
        0.35,
    ),
    "obovate": ShapeSpec(
        "egg-shaped upside down: widest in the upper two fifths, narrowing to the base",
        ((0, 0.8), (0.65, 1), (1, 1)),
        1.6,
        "rounded",
        "cuneate",
        0.35,
        0.6,
    ),
    "orbicular": ShapeSpec(
        "round: about as wide as long",
        ((0, 1), (1, 1)),
        1.0,
        "rounded",
        "rounded",
        0.5,
        0.5,
    ),
    "cordate": ShapeSpec(
        "heart-shaped: ovate, with two rounded lobes reaching back past the base",
        ((0, 1), (0.35, 1), (1, 0.8)),
        1.4,
        "acute",
        "cordate",
        0.6,
        0.35,
        True,
    ),
    "reniform": ShapeSpec(
        "kidney-shaped: wider than long, with a notch where the stalk meets the blade",
        ((0, 1), (1, 1)),
        0.72,
        "rounded",
        "reniform",
        0.5,
        0.5,
        True,
        venation="palmate",
    ),
    "deltoid": ShapeSpec(
        "triangular: widest near the base, straight sides running to the apex",
        ((0, 1), (1, 0.12)),
        1.15,
        "acute",
        "truncate",
        0.12,
        0.1,
        secondaries=10,
    ),
    "spatulate": ShapeSpec(
        "spoon-shaped: widest near the apex, tapering to a long narrow base",
        ((0, 0.18), (0.45, 0.3), (0.82, 1), (1, 0.9)),
        2.8,
        "rounded",
        "cuneate",
        0.2,
        0.15,
        secondaries=8,
    ),
    "sagittate": ShapeSpec(
        "arrow-shaped: two pointed basal lobes pointing back, past the base",
        ((0, 1), (1, 0.15)),
        2.0,
        "acute",
        "sagittate",
        0.15,
        0.35,
        True,
    ),
    "hastate": ShapeSpec(
        "halberd-shaped: two pointed basal lobes flaring outward, sideways",
        ((0, 0.7), (1, 0.2)),
        1.5,
        "acute",
        "hastate",
        0.2,
        0.12,
        True,
    ),
}

APEXES: dict[str, str] = {
    "acute": "the tip comes to a point narrower than a right angle, the sides straight or bulging",
    "acuminate": "drawn out into a long narrow tip, the sides curving inward before it",
    "obtuse": "the tip comes to a blunt point, wider than a right angle",
    "rounded": "the tip is a smooth arc, without a point",
    "retuse": "rounded, with a shallow notch at the very tip",
    "emarginate": "rounded, with a distinct notch at the tip",
}

BASES: dict[str, str] = {
    "cuneate": "wedge-shaped: straight sides meeting at a narrow angle",
    "rounded": "the base is a smooth arc",
    "truncate": "cut almost straight across",
    "cordate": "two rounded lobes on either side of a notch, reaching back past the base",
    "reniform": "broad rounded lobes either side of a wide notch, like a kidney",
    "sagittate": "two pointed lobes pointing back (the base of an arrow)",
    "hastate": "two pointed lobes flaring outward (the base of a halberd)",
}
VENATION_KINDS = ("pinnate", "palmate", "parallel", "arcuate")  # the veins forms/veins.py grows
USER_BASES = ("cuneate", "rounded", "truncate", "cordate")  # what --base may choose

MARGINS: dict[str, str] = {
    "entire": "a smooth edge without teeth",
    "serrate": "saw-toothed: sharp teeth pointing toward the apex",
    "serrulate": "finely serrate: many small teeth pointing toward the apex",
    "dentate": "teeth pointing straight outward",
    "crenate": "rounded teeth, with sharp notches between them",
    "sinuate": "a few shallow waves in and out, in the blade's plane",
    "lobed": "cut into lobes by sinuses reaching at least a quarter of the way to the midvein",
}
TOOTHED = ("serrate", "serrulate", "dentate", "crenate", "sinuate")
DEFAULT_TEETH = {"serrate": 36, "serrulate": 80, "dentate": 24, "crenate": 24, "sinuate": 8}
DEFAULT_LOBES = 5

VENATIONS: dict[str, str] = {
    "pinnate": "one midrib from base to apex, secondary veins leaving it and running to the margin",
    "palmate": "three or more main veins spreading from the base, like fingers of a hand "
    "(actinodromous)",
    "parallel": "five or more veins running side by side from base to apex, never crossing",
    "arcuate": "secondary veins bowing up toward the apex inside the margin, fading without "
    "joining the next, as in dogwood (eucamptodromous)",
}

RELIEF: dict[str, str] = {  # plain words (the app shows them); FLAGS adds the CLI's syntax
    "fold": "the two halves rise from the midrib by this angle, like a half-open book (the "
    "crease runs straight from base to apex; they fall, if negative)",
    "curl": "the midrib arcs up along its length, the apex rising about this many leaf lengths "
    "(0.5: 0.46; 1: the tip turned 115°; droops, if negative)",
    "roll": "the margins roll up across the midrib, as a grass blade rolls: 1 closes the blade "
    "into a tube at its widest, 0.5 makes a half-pipe (rolls down, if negative)",
    "twist": "the blade turns about its midrib, as a twisted grass blade: the apex this many half "
    "turns against the base (the other way, if negative)",
    "wave": "the margin rises and falls in waves of this height (in leaf lengths; at most half "
    "the blade's half-width)",
    "seed": "a variant of the form: tooth spacing, lobe depth, vein angles and width vary "
    "slightly; the same seed gives the same leaf",
    "aspect": "the length over the greatest width (each shape has its own usual value)",
    "teeth": "how many teeth (or waves) in all, on both sides",
    "lobes": "how many lobes in all, with a lobed margin",
    "secondaries": "how many secondary veins on each side of the midrib",
}
FLAGS: dict[str, str] = {  # each RELIEF term's command-line option, for `form --list`
    "fold": "--fold DEG",
    "curl": "--curl C",
    "roll": "--roll R",
    "twist": "--twist T",
    "wave": "--wave A",
    "seed": "--seed S",
    "aspect": "--aspect L/W",
    "teeth": "--teeth N",
    "lobes": "--lobes N",
    "secondaries": "--secondaries N",
}

CATEGORIES: dict[str, dict[str, str]] = {
    "shape": {name: spec.definition for name, spec in SHAPES.items()},
    "apex": APEXES,
    "base": {name: BASES[name] for name in USER_BASES},
    "margin": MARGINS,
    "venation": VENATIONS,
    "relief and variants": RELIEF,
}


def definition(term: str, kind: str | None = None) -> str:
    """The plain-words definition of a term; `kind` ("shape", "apex", "base", "margin",
    "venation") picks the group when a word is in two (a rounded apex, a rounded base)."""
    groups = {
        "shape": CATEGORIES["shape"],
        "apex": APEXES,
        "base": BASES,
        "margin": MARGINS,
        "venation": VENATIONS,
        "relief": RELIEF,
    }
    for name, group in groups.items():
        if (kind is None or kind == name) and term in group:
            return group[term]
    raise LeafError(f"unknown {kind or 'term'} {term!r}")


def term_key(value: str) -> str:
    """A term as the tables spell it: any case, spaces around it dropped ("Ovate " -> "ovate");
    the command line's type for a term's option. Anything but a string is left as it is."""
    return value.strip().lower() if isinstance(value, str) else value


def check_term(kind: str, value: str, allowed: dict[str, str] | tuple[str, ...]) -> str:
    """`value` as the tables spell it (term_key) if it is one of `allowed`, else a LeafError
    listing the choices.

    Examples
    --------
    >>> check_term("shape", " Ovate", SHAPES)
    'ovate'
    """
    key = term_key(value)
    if key not in allowed:
        raise LeafError(f"unknown {kind} {value!r}; choose from {', '.join(allowed)}")
    return key


def format_terms() -> str:
    """Every term with its definition, grouped, for `leafstudio form --list` (the relief
    terms with their command-line option, e.g. "--teeth N: how many teeth ...")."""
    lines = []
    for group, terms in CATEGORIES.items():
        lines.append(f"{group}:")
        width = max(len(t) for t in terms)
        flagged = {t: f"{FLAGS[t]}: {text}" if t in FLAGS else text for t, text in terms.items()}
        lines += [f"  {term:<{width}}  {text}" for term, text in flagged.items()]
    return "\n".join(lines)
