"""Pictures of the terms, and forms side by side: what a class compares.

- `term_picture(kind, term)`: the outline (and veins) that shows one term, with the part of the
  leaf's plane to look at (an apex: the leaf's tip; a base: its foot; a toothed or entire
  margin: one side's middle, from the midrib out, where the teeth stand a few pixels deep at the
  glossary's size; a sinuate or lobed one: the blade's whole middle; a shape or venation: the
  whole leaf). Made once per term from the forms themselves, then cached.
- `COMPARISONS`: forms a lesson sets side by side (ovate beside obovate, serrate beside
  dentate, ...), and `compared_terms(forms)`: each form's terms that differ from the others',
  with their definitions: what the class should look at.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

from leafstudio.errors import LeafError
from leafstudio.forms.make import Form
from leafstudio.forms.terms import (
    APEXES,
    BASES,
    MARGINS,
    SHAPES,
    VENATIONS,
    definition,
    term_key,
)

PICTURED: dict[str, tuple[str, ...]] = {  # the terms drawn, by kind
    "shape": tuple(SHAPES),
    "apex": tuple(APEXES),
    "base": tuple(BASES),
    "margin": tuple(MARGINS),
    "venation": tuple(VENATIONS),
}
WHOLE_MARGINS = ("sinuate", "lobed")  # a few waves or lobes: the blade's whole middle shown
COMPARED_KINDS = ("shape", "apex", "base", "margin", "venation")


@dataclass(frozen=True)
class TermPicture:
    """What to draw for one term.

    Attributes
    ----------
    outline : (n, 2) float array
        The blade's outline in the plane (forms' convention: base at 0, apex at x = 1).
    veins : tuple of (m, 2) float arrays
        The veins to draw over it (the midrib alone for apex, base and margin pictures).
    box : (4,) float array
        The part of the plane shown: x0, y0, x1, y1.
    """

    outline: np.ndarray
    veins: tuple[np.ndarray, ...]
    box: np.ndarray


def _form_for(kind: str, term: str) -> Form:
    """The form that shows `term` plainly: an elliptic leaf for an apex or a margin, an ovate
    one for a base or a venation (a base that defines its shape: that shape)."""
    if kind == "shape":
        return Form(term)
    if kind == "apex":
        return Form("elliptic", apex=term)
    if kind == "base":
        return (
            Form(term) if SHAPES.get(term) and SHAPES[term].fixed_base else Form("ovate", base=term)
        )
    if kind == "margin":
        return Form("elliptic", margin=term)
    if kind == "venation":
        return Form("ovate", venation=term)
    raise LeafError(f"no pictures of {kind!r} terms; choose from {', '.join(PICTURED)}")


@cache
def term_picture(kind: str, term: str) -> TermPicture:
    """The picture of one term (see the module's text); made once, then cached.

    Parameters
    ----------
    kind : {"shape", "apex", "base", "margin", "venation"}
    term : str
        One of `PICTURED[kind]`.

    Returns
    -------
    TermPicture

    Examples
    --------
    >>> from leafstudio.forms.glossary import term_picture
    >>> picture = term_picture("apex", "emarginate")
    >>> bool(picture.box[0] > 0.4)  # the leaf's tip, not the whole leaf
    True
    """
    if term not in PICTURED.get(kind, ()):
        definition(term, kind)  # the one message for an unknown term
        raise LeafError(f"no picture of the {kind} term {term!r}")
    form = _form_for(kind, term)
    if kind in ("shape", "venation"):
        leaf = form.leaf()
        outline = leaf.boundary[:, :2]
        veins = tuple(v[:, :2] for v in leaf.veins)
    else:  # the outline alone (no veins to grow): the midrib as a straight line
        outline = form.outline().xy
        veins = (np.array([[0.0, 0.0], [1.0, 0.0]]),)
    lo, hi = outline.min(axis=0), outline.max(axis=0)
    half = float(np.abs(outline[:, 1]).max())
    if kind == "apex":
        box = (0.55, -1.3 * half, 1.05, 1.3 * half)
    elif kind == "base":
        box = (lo[0] - 0.05, -1.3 * half, 0.45, 1.3 * half)
    elif kind == "margin" and term in WHOLE_MARGINS:
        box = (0.15, -1.1 * half, 0.85, 1.1 * half)
    elif kind == "margin":  # one side's middle, from the midrib out: teeth a few pixels deep
        box = (0.36, -0.02 * half, 0.64, 1.08 * half)
    else:
        box = (*lo, *hi)
    return TermPicture(outline, veins, np.asarray(box, dtype=float))


COMPARISONS: dict[str, tuple[Form, ...]] = {
    "ovate beside obovate": (Form("ovate"), Form("obovate")),
    "lanceolate beside oblanceolate": (Form("lanceolate"), Form("oblanceolate")),
    "serrate beside dentate": (
        Form("ovate", margin="serrate", teeth=24),
        Form("ovate", margin="dentate", teeth=24),
    ),
    "four margins": tuple(
        Form("ovate", margin=m) for m in ("entire", "serrate", "crenate", "lobed")
    ),
    "pinnate beside palmate": (Form("ovate"), Form("ovate", venation="palmate")),
    "four venations": tuple(Form("ovate", venation=v) for v in VENATIONS),
    "four bases": tuple(
        Form("ovate", base=b) for b in ("cuneate", "rounded", "truncate", "cordate")
    ),
}


def form_terms(form: Form) -> dict[str, str]:
    """A form's terms by kind (its shape's usual apex, base and venation when it names none)."""
    return {
        "shape": form.shape,
        "apex": form.apex_term,
        "base": form.base_term,
        "margin": form.margin,
        "venation": form.venation_term,
    }


def compared_terms(forms: tuple[Form, ...] | list[Form]) -> list[list[tuple[str, str, str]]]:
    """For each form, the terms in which the forms differ, as (kind, term, definition): what a
    class compares. Forms alike in every term get their shape.

    Examples
    --------
    >>> from leafstudio.forms.glossary import COMPARISONS, compared_terms
    >>> [[t[:2] for t in terms] for terms in compared_terms(COMPARISONS["serrate beside dentate"])]
    [[('margin', 'serrate')], [('margin', 'dentate')]]
    """
    if not 1 <= len(forms) <= 4:
        raise LeafError(f"compare one to four forms, not {len(forms)}")
    terms = [form_terms(f) for f in forms]
    kinds = [k for k in COMPARED_KINDS if len({t[k] for t in terms}) > 1] or ["shape"]
    if "shape" in kinds:  # a shape's usual apex and base are part of it: said when chosen
        chosen = {k for f in forms for k in ("apex", "base") if getattr(f, k) is not None}
        kinds = [k for k in kinds if k not in ("apex", "base") or k in chosen]
    return [[(k, t[k], definition(t[k], k)) for k in kinds] for t in terms]


def form_of_term(term: str) -> Form:
    """The form that shows `term` (see term_picture); a word of two kinds is read as the first
    in PICTURED's order ("cordate": the shape; "rounded": the apex).

    Examples
    --------
    >>> from leafstudio.forms.glossary import form_of_term
    >>> form_of_term("serrate").margin, form_of_term("obovate").shape
    ('serrate', 'obovate')
    """
    key = term_key(term)
    for kind, terms in PICTURED.items():
        if key in terms:
            return _form_for(kind, key)
    raise LeafError(f"unknown term {term!r}; `leafstudio form --list` lists every term")
