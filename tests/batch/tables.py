"""What the batch tests share besides their inputs (conftest.py): where the real scans are, the
grid they run at, and how a trait table and a failing command are read."""

from __future__ import annotations

import csv
from pathlib import Path

from leafstudio.cli import main

REAL = Path(__file__).resolve().parents[3] / "shared" / "realleaves"
GRID = "32"
SCANS = 4  # real scans in a batch: two workers get two each, and a kill after two rows leaves two


def read_rows(table: Path) -> list[dict[str, str]]:
    with open(table, newline="", encoding="utf-8") as handle:
        return list(csv.DictReader(handle))


def failed_line(argv: list[str], capsys) -> str:
    """The one line `leafstudio` prints for a failing command."""
    capsys.readouterr()
    assert main(argv) == 2
    return capsys.readouterr().err.strip()
