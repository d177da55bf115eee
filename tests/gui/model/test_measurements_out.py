"""The measurements out of the app, without Qt: the whole table as text, CSV and JSON."""

from __future__ import annotations

import csv
import json

import pytest

from leafstudio.errors import LeafError
from leafstudio.gui.model.measurements import (
    measurement_rows,
    save_sections,
    sections_csv,
    sections_json,
    sections_text,
)

SECTIONS = [
    ("Scan → mesh distance (blade points)", [("Points", "3268"), ("Mean", "0.0012")]),
    ("Leaf", [("Area", "0.1727"), ("Closed", "yes"), ("Beyond 1% of length", "2.5%")]),
]


def test_text_holds_every_section_and_row_not_just_one_cell():
    text = sections_text(SECTIONS)
    lines = text.splitlines()
    assert lines[0] == "Scan → mesh distance (blade points)"  # the title whole
    assert "Points\t3268" in lines and "Area\t0.1727" in lines and "Leaf" in lines
    assert len(lines) == 2 + 5


def test_csv_has_one_row_per_measurement_with_its_section():
    rows = list(csv.reader(sections_csv(SECTIONS).splitlines()))
    assert rows[0] == ["section", "measure", "value"]
    assert ["Leaf", "Area", "0.1727"] in rows and len(rows) == 1 + 5


def test_json_keeps_sections_and_makes_numbers_numbers():
    table = json.loads(sections_json(SECTIONS))
    assert table["Leaf"] == {"Area": 0.1727, "Closed": "yes", "Beyond 1% of length": "2.5%"}
    assert table["Scan → mesh distance (blade points)"]["Points"] == 3268


def test_save_writes_by_suffix_and_refuses_others(tmp_path, demo_result):
    sections = measurement_rows(demo_result("nested"))
    save_sections(str(tmp_path / "m.csv"), sections)
    save_sections(str(tmp_path / "m.json"), sections)
    assert (tmp_path / "m.csv").read_text(encoding="utf-8").startswith("section,measure,value")
    assert set(json.loads((tmp_path / "m.json").read_text(encoding="utf-8"))) == {
        title for title, _ in sections
    }
    with pytest.raises(LeafError, match=r"m\.txt"):
        save_sections(str(tmp_path / "m.txt"), sections)
    assert not (tmp_path / "m.txt").exists()
