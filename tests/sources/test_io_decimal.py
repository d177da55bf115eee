"""Point lists as spreadsheets write them: every separator, with or without quotes around each
field, with a decimal point or a decimal comma, with or without a header, reads as the numbers it
holds, or is refused in one line where the numbers cannot be told apart; never misread."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import leafstudio as ls
from leafstudio.cli import main
from leafstudio.sources.scan import is_scan_file, read_scan

SEPARATORS = {"semicolon": ";", "semicolon-space": "; ", "tab": "\t", "space": " ", "comma": ","}
HEADERS = ("none", "names", "quoted names")
COMBINATIONS = list(itertools.product(SEPARATORS, ("bare", "quoted"), (".", ","), HEADERS, (2, 3)))


def _table(rows: np.ndarray, separator: str, quoted: bool, mark: str, header: str) -> str:
    """`rows` as a spreadsheet writes them: each number with 6 decimals (0 as `0`, a cell a
    spreadsheet holds as a whole number), `mark` for the decimal mark, each field in double
    quotes when `quoted`, and a header line of x, y, z."""

    def cell(text: str) -> str:
        return f'"{text}"' if quoted else text

    def number(value: float) -> str:
        return "0" if value == 0 else f"{value:.6f}".replace(".", mark)

    lines = [separator.join(cell(number(v)) for v in row) for row in rows]
    if header != "none":
        names = "xyz"[: rows.shape[1]]
        lines.insert(0, separator.join(f'"{n}"' if header == "quoted names" else n for n in names))
    return "\n".join(lines) + "\n"


def _outline(columns: int) -> np.ndarray:
    """A demo's outline as a spreadsheet's numbers: 6 decimals, its first point's y at 0."""
    points = np.round(ls.demo("parallel").boundary[::4, :columns], 6)
    points[0, 1] = 0.0
    return points


def _readable(separator: str, quoted: bool, mark: str) -> bool:
    """Whether such a file can be read: every combination but decimal commas between commas."""
    return not (SEPARATORS[separator] == "," and mark == ",")


@pytest.mark.parametrize("separator, quoting, mark, header, columns", COMBINATIONS)
def test_every_spreadsheets_point_list_reads_as_its_numbers_or_is_refused(
    tmp_path: Path, separator: str, quoting: str, mark: str, header: str, columns: int
):
    """A European spreadsheet stores numbers as text in double quotes with decimal commas
    (`"1,5";"0"`): such a file was refused ('not a number in '"1,5";"0"''), where `1,5;0` and
    `"1.5","0"` were read. Quoted decimal commas now read as the unquoted ones, and a
    comma-separated file of quoted decimal points is read as before."""
    quoted = quoting == "quoted"
    points = _outline(columns)
    path = tmp_path / "outline.csv"
    path.write_text(_table(points, SEPARATORS[separator], quoted, mark, header))
    expected = points if columns == 3 else np.column_stack([points, np.zeros(len(points))])
    if _readable(separator, quoted, mark):
        np.testing.assert_array_equal(ls.load_leaf(path).boundary, expected)
        if columns == 3:
            np.testing.assert_array_equal(read_scan(path), expected)
    elif quoted:  # `"1,5","0"`: a decimal comma, or a thousands separator? refused, never misread
        with pytest.raises(ls.LeafError, match=r"line \d+: .*quoted"):
            ls.load_leaf(path)


@pytest.mark.parametrize("separator", ["semicolon", "tab"])
def test_a_quoted_european_scan_is_told_from_a_leaf(tmp_path: Path, separator: str):
    """Six quoted columns with decimal commas are a scan with normals, four a labelled leaf."""
    points = np.round(np.random.default_rng(1).uniform(-1, 1, size=(80, 6)), 6)
    scan, leaf = tmp_path / "scan.csv", tmp_path / "leaf.csv"
    scan.write_text(_table(points, SEPARATORS[separator], True, ",", "none"))
    labelled = np.column_stack([points[:, :3], np.zeros(len(points))])
    leaf.write_text(_table(labelled, SEPARATORS[separator], True, ",", "none"))
    assert is_scan_file(str(scan)) and not is_scan_file(str(leaf))
    np.testing.assert_array_equal(read_scan(scan), points[:, :3])


def test_quoted_numbers_with_both_decimal_marks_are_refused_in_one_line(tmp_path: Path, capsys):
    path = tmp_path / "mixed.csv"
    path.write_text('"0";"0";"0"\n"1,5";"0";"0"\n"1.5";"1";"0"\n')
    code = main(["measure", str(path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert "line 3" in err[0] and "both decimal commas and points" in err[0]


def test_quoted_decimal_commas_between_commas_are_refused_in_one_line(tmp_path: Path, capsys):
    """`"1,5","0"`: a comma inside quotes, commas between them; a decimal comma, or the
    thousands separator of `"1,000","2"`, cannot be told: refused, naming the line."""
    path = tmp_path / "us.csv"
    path.write_text('# "2,5" in a comment\n"0","0","0"\n"1,5","0","0"\n"0","1","0"\n')
    code = main(["measure", str(path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert str(path) in err[0] and 'line 3: a quoted number with a comma ("1,5")' in err[0]
    first = tmp_path / "first.csv"  # on the first line it was skipped as a header
    first.write_text('"1,5","0","0"\n"0","1","0"\n"0","0","0"\n')
    with pytest.raises(ls.LeafError, match="line 1: a quoted number"):
        read_scan(first)


NUMBERS = st.floats(-1e4, 1e4, allow_nan=False).map(lambda v: round(v, 4))


@settings(
    max_examples=60, deadline=None, derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)  # fmt: skip
@given(
    rows=st.lists(st.tuples(NUMBERS, NUMBERS, NUMBERS), min_size=3, max_size=8),
    combination=st.sampled_from(COMBINATIONS),
)
def test_any_numbers_in_any_readable_spreadsheet_format_read_exactly(
    tmp_path: Path, rows: list[tuple[float, float, float]], combination: tuple
):
    separator, quoting, mark, header, _ = combination
    points = np.asarray(rows, dtype=float)
    path = tmp_path / "any.csv"
    path.write_text(_table(points, SEPARATORS[separator], quoting == "quoted", mark, header))
    if _readable(separator, quoting == "quoted", mark):
        np.testing.assert_allclose(_numbers(path), points, rtol=1e-12, atol=5e-7)


def _numbers(path: Path) -> np.ndarray:
    """The (n, 3) numbers a point list holds, as the leaf reader takes them."""
    from leafstudio.sources.files import read_point_table

    return read_point_table(path)
