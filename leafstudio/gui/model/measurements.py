"""The rows of the measurements panel, from a Result's metrics, and the table out of the app as
text (Copy), CSV or JSON (Save) (no Qt here).

Shows whatever `Result.metrics` holds (the leaf's measurements, the paper's Table-1 distances, the
mesh's facts, curvature ranges, and anything added later), flattened into labelled rows.
"""

from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from leafstudio._shared.safewrite import write_bytes
from leafstudio.core.evaluate import NO_MIXTURE
from leafstudio.core.pipeline import Result
from leafstudio.errors import LeafError

SECTION_NAMES = {
    "leaf": "Leaf",
    "boundary": "Boundary points → mesh distance (Table 1)",
    "veins": "Vein points → mesh distance (Table 1)",
    "mesh": "Mesh",
    "curvature": "Curvature",
}


def _label(key: str) -> str:
    return key.replace("_", " ").capitalize()


# what a figure of None says, by its key (else "–"): a flat blade's K is not one (fitted_k)
NONE_TEXTS = {"k": NO_MIXTURE}


def _value(value: Any, key: str = "") -> str:
    if value is None:
        return NONE_TEXTS.get(key, "–")
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        return f"{float(value):.4g}"
    return str(value)


def _flatten(values: dict[str, Any]) -> list[tuple[str, str]]:
    rows = []
    for key, value in values.items():
        if isinstance(value, dict):
            rows.extend((f"{_label(key)} {label.lower()}", text) for label, text in _flatten(value))
        elif not isinstance(value, (list, tuple, np.ndarray)):
            rows.append((_label(key), _value(value, key)))
    return rows


def measurement_rows(result: Result) -> list[tuple[str, list[tuple[str, str]]]]:
    """(section title, [(label, value text), ...]) per section, the known sections first."""
    metrics = result.metrics
    order = [k for k in SECTION_NAMES if k in metrics] + [
        k for k in metrics if k not in SECTION_NAMES
    ]
    sections, loose = [], {}
    for key in order:
        value = metrics[key]
        if isinstance(value, dict):
            sections.append((SECTION_NAMES.get(key, _label(key)), _flatten(value)))
        else:
            loose[key] = value
    if loose:
        sections.append(("Other", _flatten(loose)))
    return sections


# --- out of the app: copy and save ----------------------------------------------------------
Sections = list[tuple[str, list[tuple[str, str]]]]
SAVE_SUFFIXES = (".csv", ".json")


def sections_text(sections: Sections) -> str:
    """The whole table as plain text, as Copy puts it on the clipboard: each section's title on
    a line of its own, then its rows as "label<TAB>value" (two columns in a spreadsheet)."""
    lines = []
    for title, rows in sections:
        lines.append(title)
        lines.extend(f"{label}\t{value}" for label, value in rows)
    return "\n".join(lines) + "\n"


def sections_csv(sections: Sections) -> str:
    """The table as CSV, one row per measurement: section, measure, value (as shown)."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["section", "measure", "value"])
    writer.writerows([title, label, value] for title, rows in sections for label, value in rows)
    return out.getvalue()


def _number(text: str) -> float | int | str:
    """A value shown as text, as a JSON number when it is one ("0.1727", "3"), else the text."""
    for kind in (int, float):
        try:
            number = kind(text)
        except ValueError:
            continue
        return number if math.isfinite(number) else text
    return text


def sections_json(sections: Sections) -> str:
    """The table as JSON: {section: {measure: value}}, numbers as numbers."""
    table = {title: {label: _number(value) for label, value in rows} for title, rows in sections}
    return json.dumps(table, indent=2, ensure_ascii=False) + "\n"


def save_sections(path: str, sections: Sections) -> None:
    """Write the table to `path` as CSV or JSON, by its suffix (atomically: safewrite).

    Raises
    ------
    LeafError
        Another suffix, or the file cannot be written.
    """
    suffix = Path(path).suffix.lower()
    if suffix not in SAVE_SUFFIXES:
        raise LeafError(f"measurements save as {' or '.join(SAVE_SUFFIXES)}", path)
    text = sections_csv(sections) if suffix == ".csv" else sections_json(sections)
    write_bytes(path, text)
