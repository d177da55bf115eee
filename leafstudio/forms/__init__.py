"""Leaves from the botanical vocabulary, and veins grown inside any outline.

- `Form` / `make_form`: a leaf from terms (shape, apex, base, margin, venation, relief, seed),
  following the forms' convention (docs/architecture.md): base at the origin, apex on +x at
  length 1.
- `grow_veins`: veins of a chosen kind inside any outline (space colonization, Runions et al. 2005).
- `terms`: every term with its definition in plain words.
"""

import lazy_loader

# imported on first use: the command line's parsers take the terms (forms.terms, plain data)
# without the outlines' splines and the veins' growth (scipy, shapely, the kernels)
__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "make": ["Form", "make_form"],
        "terms": ["CATEGORIES", "SHAPES", "VENATION_KINDS", "definition", "format_terms"],
        "veins": ["grow_veins"],
    },
)
