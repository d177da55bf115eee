"""The rows of the measurements panel, from a Result's metrics (no Qt here).

Shows whatever `Result.metrics` holds (the analysis module may add more), flattened into labelled
rows, plus the outline's length, width and perimeter when the metrics do not already give them.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from leafstudio.core.pipeline import Result

SECTION_NAMES = {
    "boundary": "Boundary points → mesh distance",
    "veins": "Vein points → mesh distance",
    "mesh": "Mesh",
}


def _label(key: str) -> str:
    return key.replace("_", " ").capitalize()


def _value(value: Any) -> str:
    if value is None:
        return "–"
    if isinstance(value, bool):
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


def outline_size(result: Result) -> dict[str, float]:
    """Length (along the leaf's main axis), greatest width and perimeter of the leaf outline."""
    polygon = result.polygon
    closed = np.vstack([polygon, polygon[:1]])
    return {
        "length": float(result.length),
        "width": float(np.ptp(polygon[:, 1])),
        "perimeter": float(np.linalg.norm(np.diff(closed, axis=0), axis=1).sum()),
    }


def measurement_rows(result: Result) -> list[tuple[str, list[tuple[str, str]]]]:
    """(section title, [(label, value text), ...]) for every section of the panel."""
    metrics = result.metrics
    known = {label.split()[-1].lower() for _, rows in _sections(metrics) for label, _ in rows}
    leaf = [(_label(k), _value(v)) for k, v in outline_size(result).items() if k not in known]
    return [("Leaf", leaf), *_sections(metrics)] if leaf else _sections(metrics)


def _sections(metrics: dict[str, Any]) -> list[tuple[str, list[tuple[str, str]]]]:
    sections, loose = [], {}
    for key, value in metrics.items():
        if isinstance(value, dict):
            sections.append((SECTION_NAMES.get(key, _label(key)), _flatten(value)))
        else:
            loose[key] = value
    if loose:
        sections.insert(0, ("Measurements", _flatten(loose)))
    return sections
