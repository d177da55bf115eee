"""Doctests: the Examples sections of leafstudio's docstrings run with the tests (`./dev test`;
pyproject.toml turns on --doctest-modules over `leafstudio`).

Only the package's modules that hold an example (a `>>>` line) are collected: importing every
module for doctests, the app's Qt views included, would cost time and test nothing.
"""

from __future__ import annotations

from pathlib import Path

PACKAGE = Path(__file__).parent / "leafstudio"


def pytest_ignore_collect(collection_path: Path) -> bool | None:
    if collection_path.suffix != ".py" or PACKAGE not in collection_path.parents:
        return None
    return True if ">>>" not in collection_path.read_text(encoding="utf-8") else None
