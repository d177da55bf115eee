"""Lengths with their unit, as the commands and the app's fields take them: '8cm', '3 in', '0.4mm'.

One table of units for every such length (`--length`, `--thickness`, the photo's length and
its ruler), so that a unit one of them takes the others take too.
"""

from __future__ import annotations

import re

from leafstudio.errors import LeafError

METRES = {"um": 1e-6, "mm": 1e-3, "cm": 1e-2, "m": 1.0, "in": 0.0254, "ft": 0.3048}  # per unit
UNITS_SAID = f"8cm, 80mm, 3in; units {', '.join(METRES)}"  # in every length's help and prompt
_LENGTH = re.compile(r"\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*([a-zA-Z]*)\s*")


def split_length(text: str) -> tuple[float, str] | None:
    """A length's number and its unit in lower case ('' for none); None when `text` is not a
    number followed by letters.

    Examples
    --------
    >>> split_length(" 3 IN"), split_length("0.5"), split_length("8 cm 2")
    ((3.0, 'in'), (0.5, ''), None)
    """
    match = _LENGTH.fullmatch(text)
    return None if match is None else (float(match.group(1)), match.group(2).lower())


def unit_metres(unit: str, option: str) -> float:
    """Metres per `unit`; a LeafError naming the `option` and listing the units if unknown."""
    if unit not in METRES:
        raise LeafError(f"{option}: unknown unit {unit!r}; use one of {', '.join(METRES)}")
    return METRES[unit]
