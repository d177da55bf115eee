"""Leaves from the botanical vocabulary, and veins grown inside any outline.

- `Form` / `make_form`: a leaf from terms (shape, apex, base, margin, venation, relief, seed),
  following the forms' convention (docs/architecture.md): base at the origin, apex on +x at
  length 1.
- `grow_veins`: veins of a chosen kind inside any outline (space colonization, Runions et al. 2005).
- `terms`: every term with its definition in plain words.
"""

from leafstudio.forms.make import Form, make_form
from leafstudio.forms.terms import CATEGORIES, SHAPES, definition, format_terms
from leafstudio.forms.veins import VENATION_KINDS, grow_veins

__all__ = [
    "CATEGORIES",
    "SHAPES",
    "VENATION_KINDS",
    "Form",
    "definition",
    "format_terms",
    "grow_veins",
    "make_form",
]
