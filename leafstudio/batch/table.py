"""The trait table: one row per input, appended and flushed as results arrive, rewritten sorted
by input at the end. Each table type (CSV, JSON lines, Parquet) is a small format class behind
one interface; `TraitTable` keeps the journal and never asks which format it has."""

from __future__ import annotations

import csv
import io
import json
import os
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

from leafstudio._shared.safewrite import replace_atomically, write_bytes
from leafstudio.batch.settings import FLOAT_COLUMNS, INT_COLUMNS, columns
from leafstudio.errors import LeafError, shorten


def _parse(name: str, text: str) -> Any:
    """A CSV cell back to its value ("" is None); LeafError for a number column that holds
    something else (a table edited by hand)."""
    if text == "":
        return None
    try:
        if name in INT_COLUMNS:
            return int(text)
        if name in FLOAT_COLUMNS:
            return float(text)
    except ValueError:
        raise _not_a_number(name, text) from None
    return text


def _not_a_number(name: str, value: Any) -> LeafError:
    """The error for a number column holding something else."""
    kind = "a whole number" if name in INT_COLUMNS else "a number"
    return LeafError(f"{name} is {shorten(str(value), 40)!r}, not {kind}")


def _checked(row: dict[str, Any]) -> dict[str, Any]:
    """A JSON row whose number columns hold numbers (or null); LeafError otherwise, as a CSV
    cell's (_parse): a row whose k was "three" was resumed as done and written back so."""
    for name, value in row.items():
        if value is None or (name not in INT_COLUMNS and name not in FLOAT_COLUMNS):
            continue
        whole = isinstance(value, int) and not isinstance(value, bool)
        if not (whole or (name in FLOAT_COLUMNS and isinstance(value, float))):
            raise _not_a_number(name, value)
    return row


def _cell(value: Any) -> str:
    """A CSV cell: floats exactly (repr), text on one line (a row is one line of the file)."""
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)
    return " ".join(str(value).splitlines())


def _complete(handle: Iterable[str]) -> Iterator[str]:
    """The lines that end in a newline (a row cut short by a kill does not)."""
    return (line for line in handle if line.endswith("\n"))


class _LineFormat:
    """A table written one row a line, to the table itself (it is its own journal)."""

    def __init__(self, columns: tuple[str, ...]) -> None:
        self.columns = columns

    def journal(self, path: Path) -> Path:
        """Where rows are appended as they arrive."""
        return path

    def header(self) -> str:
        """The text before the first row."""
        return ""

    def line(self, row: dict[str, Any]) -> str:
        """One row as one line of the journal."""
        raise NotImplementedError

    def key(self, line: str) -> str:
        """A journal line's input (ValueError, KeyError, ... for a line that is not a row)."""
        raise NotImplementedError

    def read(self, lines: Iterator[str]) -> Iterator[dict[str, Any]]:
        """The rows of the journal's complete lines."""
        raise NotImplementedError

    def is_table(self, path: Path) -> bool:
        """Whether the non-empty file at `path` is a table of this kind."""
        with open(path, encoding="utf-8", errors="replace") as handle:
            return self.is_first_line(handle.readline(4096).strip())

    def is_first_line(self, first: str) -> bool:
        """Whether a file's first line is that of a table of this kind."""
        raise NotImplementedError

    def rows(self, source: Path) -> Iterator[dict[str, Any]]:
        """The complete rows in `source` (a journal or a finished table)."""
        with open(source, encoding="utf-8", newline="") as handle:
            yield from self.read(_complete(handle))

    def finish(self, path: Path, journal: Path) -> None:
        """Rewrite the table sorted by input: the journal's own lines, not parsed (nor held)
        whole."""
        write_bytes(path, self.header() + "".join(self._sorted_lines(journal)))

    def _sorted_lines(self, journal: Path) -> list[str]:
        """The journal's complete row lines (one line a row: see _cell), sorted by input."""
        keyed = []
        with open(journal, encoding="utf-8", newline="") as handle:
            if self.header():
                next(handle, None)
            for line in _complete(handle):
                try:
                    keyed.append((self.key(line), line))
                except (ValueError, KeyError, IndexError, TypeError, StopIteration):
                    continue
        return [line for _, line in sorted(keyed)]


class CsvFormat(_LineFormat):
    """CSV: a header, then one line a row; floats exactly (repr)."""

    def header(self) -> str:
        return ",".join(self.columns) + "\n"

    def line(self, row: dict[str, Any]) -> str:
        buffer = io.StringIO()
        csv.writer(buffer, lineterminator="\n").writerow([_cell(row.get(c)) for c in self.columns])
        return buffer.getvalue()

    def key(self, line: str) -> str:
        return str(next(csv.reader([line]))[0])

    def read(self, lines: Iterator[str]) -> Iterator[dict[str, Any]]:
        reader = csv.reader(lines)
        header = next(reader, None)
        if header is None:
            return
        for cells in reader:
            if len(cells) == len(header):
                try:
                    yield {n: _parse(n, c) for n, c in zip(header, cells, strict=True)}
                except LeafError as exc:
                    raise LeafError(f"row {reader.line_num - 1}: {exc.problem}") from None

    def is_first_line(self, first: str) -> bool:
        return first.startswith("input,status,")


class JsonLinesFormat(_LineFormat):
    """JSON lines: one object a row."""

    def line(self, row: dict[str, Any]) -> str:
        return json.dumps({c: row.get(c) for c in self.columns}) + "\n"

    def key(self, line: str) -> str:
        return str(json.loads(line)["input"])

    def read(self, lines: Iterator[str]) -> Iterator[dict[str, Any]]:
        for number, line in enumerate(lines, 1):
            try:
                row = json.loads(line)
            except json.JSONDecodeError:
                continue
            if isinstance(row, dict):
                try:
                    yield _checked(row)
                except LeafError as exc:
                    raise LeafError(f"row {number}: {exc.problem}") from None

    def is_first_line(self, first: str) -> bool:
        try:
            row = json.loads(first)
        except json.JSONDecodeError:
            return False
        return isinstance(row, dict) and {"input", "status"} <= row.keys()


class ParquetFormat(JsonLinesFormat):
    """Parquet: rows journalled in a JSON lines file beside the table (`.NAME.rows.jsonl`), the
    table written from it at the end."""

    def __init__(self, columns: tuple[str, ...]) -> None:
        try:
            import pyarrow  # noqa: F401  (an optional extra: checked before any work)
        except ImportError:
            raise LeafError(
                "a .parquet table needs pyarrow (pip install pyarrow); or use .csv or .json"
            ) from None
        super().__init__(columns)

    def journal(self, path: Path) -> Path:
        return path.with_name(f".{path.name}.rows.jsonl")

    def is_table(self, path: Path) -> bool:
        import pyarrow.parquet as pq  # optional extra

        try:
            names = pq.read_schema(path).names
        except Exception:  # not a Parquet file at all
            return False
        return names[:2] == ["input", "status"]

    def rows(self, source: Path) -> Iterator[dict[str, Any]]:
        if source.suffix.lower() != ".parquet":  # the journal
            yield from super().rows(source)
            return
        import pyarrow.parquet as pq  # optional extra

        try:
            yield from pq.read_table(source).to_pylist()
        except Exception:  # a table we cannot read is not resumed from
            return

    def finish(self, path: Path, journal: Path) -> None:
        import pyarrow as pa  # optional extra
        import pyarrow.parquet as pq

        rows = sorted(self.rows(journal), key=lambda r: str(r.get("input")))
        types = {c: pa.float64() for c in FLOAT_COLUMNS} | {c: pa.int64() for c in INT_COLUMNS}
        fields = [(c, types.get(c, pa.string())) for c in self.columns]
        schema = pa.schema(fields, metadata={"pandas": _pandas_note(self.columns)})
        table = pa.Table.from_pylist(
            [{c: r.get(c) for c in self.columns} for r in rows], schema=schema
        )
        replace_atomically(path, lambda tmp: pq.write_table(table, tmp))
        journal.unlink(missing_ok=True)


def _pandas_note(columns: tuple[str, ...]) -> str:
    """The note pandas leaves in a Parquet file it writes (pa.Table.from_pandas), for the
    whole-number columns only: pd.read_parquet reads them as its nullable Int64, as they are
    written (int64 with nulls), where it took a column with a null (a flat blade's k, a failed
    row's) for float64: 3.0 and NaN. Arrow's other readers (polars, R) keep them whole as it is."""
    ints = [
        {
            "name": c,
            "field_name": c,
            "pandas_type": "int64",
            "numpy_type": "Int64",
            "metadata": None,
        }
        for c in columns
        if c in INT_COLUMNS
    ]
    return json.dumps({"index_columns": [], "column_indexes": [], "columns": ints})


FORMAT_CLASSES: dict[str, type[_LineFormat]] = {
    ".csv": CsvFormat,
    ".json": JsonLinesFormat,
    ".jsonl": JsonLinesFormat,
    ".parquet": ParquetFormat,
}
TABLE_SUFFIXES = tuple(FORMAT_CLASSES)


class TraitTable:
    """The trait table: rows appended and flushed as they arrive, sorted at `close`.

    CSV and JSON lines are appended to the table itself; a Parquet table is journalled in a JSON
    lines file beside it (`.NAME.rows.jsonl`) and written at `close`.
    """

    def __init__(self, path: str | os.PathLike, scans: bool) -> None:
        self.path = Path(path)
        suffix = self.path.suffix.lower()
        if suffix not in FORMAT_CLASSES:
            raise LeafError(
                f"unknown table type {suffix or '(none)'!r}; use .csv, .json or .parquet",
                str(self.path),
            )
        self.columns = columns(scans)
        try:
            self.format = FORMAT_CLASSES[suffix](self.columns)
        except LeafError as exc:
            raise LeafError(exc.problem, str(self.path)) from None
        self.journal = self.format.journal(self.path)
        self._handle: io.TextIOWrapper | None = None

    # reading -----------------------------------------------------------------------------
    def is_foreign(self) -> bool:
        """Whether the table's path holds a file that is not a trait table (a leaf, a user's
        CSV): writing the table would replace it."""
        if not self.path.exists():
            return False
        if not self.path.is_file():
            return True
        if self.path.stat().st_size == 0:
            return False
        return not self.format.is_table(self.path)

    def rows(self) -> Iterator[dict[str, Any]]:
        """The complete rows in the journal (a row cut short by a kill is left out); LeafError
        naming the table for a row whose number is not one."""
        source = self.journal if self.journal.exists() else self.path
        if not source.exists():
            return
        try:
            yield from self.format.rows(source)
        except LeafError as exc:  # a row edited by hand: said, not resumed over (nor dropped)
            raise LeafError(
                f"{exc.problem}; correct it, or run without --resume", str(source)
            ) from None

    # writing -----------------------------------------------------------------------------
    def start(self, keep: Iterable[dict[str, Any]] = ()) -> None:
        """Start the journal afresh with the rows in `keep` (rows resumed), then open it."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        text = self.format.header() + "".join(self.format.line(r) for r in keep)
        if text:
            write_bytes(self.journal, text)
        self._handle = open(self.journal, "a" if text else "w", encoding="utf-8", newline="")  # noqa: SIM115

    def add(self, row: dict[str, Any]) -> None:
        """Append one row and flush it to the disk."""
        assert self._handle is not None, "start() first"
        self._handle.write(self.format.line(row))
        self._handle.flush()
        os.fsync(self._handle.fileno())

    def close(self) -> None:
        """Rewrite the table sorted by input path (atomically); for Parquet, from the journal."""
        if self._handle is None:
            return
        self._handle.close()
        self._handle = None
        self.format.finish(self.path, self.journal)
