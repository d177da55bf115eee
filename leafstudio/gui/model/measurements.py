"""The rows of the measurements panel, from a Result's metrics (no Qt here).

Shows whatever `Result.metrics` holds (the leaf's measurements, the paper's Table-1 distances, the
mesh's facts, curvature ranges, and anything added later), flattened into labelled rows.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from leafstudio.core.pipeline import Result

SECTION_NAMES = {
    "leaf": "Leaf",
    "boundary": "Boundary points → mesh distance (Table 1)",
    "veins": "Vein points → mesh distance (Table 1)",
    "mesh": "Mesh",
    "curvature": "Curvature",
}


def _label(key: str) -> str:
    return key.replace("_", " ").capitalize()


def _value(value: Any) -> str:
    if value is None:
        return "–"
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
            rows.append((_label(key), _value(value)))
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
