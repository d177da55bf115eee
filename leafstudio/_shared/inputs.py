"""Reading input files defensively: every bad file is one LeafError naming it, never a hang, a
huge allocation or a library's traceback.

- Only regular files are opened (a FIFO would block for ever, /dev/zero never ends).
- Sizes are bounded: text files by MAX_TEXT_BYTES, JSON by MAX_JSON_BYTES and MAX_JSON_DEPTH.
- A PLY header's element counts are checked against the file's size before plyfile allocates.
- Numbers are read strictly: Python's float() also takes "1_0" (as 10), which no scanner writes.
- A long text is parsed in blocks of lines (`line_blocks`), each reported as read
  (_shared/progress.py): the app's busy bar shows how far a big file has come.
"""

from __future__ import annotations

import codecs
import contextlib
import json
import os
import re
import stat
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from leafstudio._shared import progress
from leafstudio.errors import LeafError, shorten

MAX_TEXT_BYTES = 1 << 30  # a point list or scan of more than 1 GiB is refused
MAX_JSON_BYTES = 256 << 20
MAX_JSON_DEPTH = 32  # a project nests 4 deep (veins -> vein -> point -> number)
MAX_HEADER = 64 << 10  # a PLY or PCD header ends within this many bytes
BLOCK_CHARS = 1 << 20  # a long text is parsed, and its progress reported, in blocks this long
PLY_SIZES = {
    "char": 1, "int8": 1, "uchar": 1, "uint8": 1, "short": 2, "int16": 2, "ushort": 2,
    "uint16": 2, "int": 4, "int32": 4, "uint": 4, "uint32": 4, "float": 4, "float32": 4,
    "double": 8, "float64": 8,
}  # fmt: skip
_NUMBER = re.compile(
    r"[+-]?(?:\d+\.?\d*(?:[eE][+-]?\d+)?|\.\d+(?:[eE][+-]?\d+)?|nan|inf)", re.I | re.ASCII
)


FOLDER = "is a folder, not a file (`leafstudio batch` takes folders)"
# what a path is, when it is not a regular file: (stat's test, the one line that says so)
SPECIAL_FILES = (
    (stat.S_ISFIFO, "is a named pipe, not a file"),
    (stat.S_ISCHR, "is a device, not a file"),
    (stat.S_ISBLK, "is a device, not a file"),
    (stat.S_ISSOCK, "is a socket, not a file"),
)


def special_file(mode: int) -> str | None:
    """What a path of stat mode `mode` is when it is neither a regular file nor a folder ("is a
    named pipe, not a file"); None for those two. Such a file is never opened: a named pipe
    blocks until something writes to it, /dev/zero never ends."""
    if stat.S_ISREG(mode) or stat.S_ISDIR(mode):
        return None
    return next((said for test, said in SPECIAL_FILES if test(mode)), "is not a regular file")


def check_file_kind(path: str | os.PathLike) -> None:
    """Refuse a folder, a named pipe, a device or a socket given where an input file belongs,
    saying which, before its name's suffix is judged or anything opens it ("unknown file type
    '(none)'" did not say what was wrong; a pipe named .csv hung the app). A path that does not
    exist passes: its reader says so."""
    try:
        mode = Path(path).stat().st_mode
    except OSError:
        return
    _refuse_kind(mode, path)


def _refuse_kind(mode: int, path: str | os.PathLike) -> None:
    """LeafError when stat mode `mode` is not a regular file's (check_file_kind's test, for a
    caller that has stat'ed `path` already)."""
    if stat.S_ISDIR(mode):
        raise LeafError(FOLDER, str(path))
    if (said := special_file(mode)) is not None:
        raise LeafError(said, str(path))


def check_input_file(path: str | os.PathLike, limit: int | None = MAX_TEXT_BYTES) -> int:
    """The size of `path`, a regular file that exists; refused (LeafError) if it is missing, a
    folder, a named pipe, a device or a socket, or larger than `limit` bytes."""
    path = Path(path)
    try:
        info = path.stat()
    except FileNotFoundError:
        raise LeafError("no such file", str(path)) from None
    except OSError as exc:
        raise LeafError(f"cannot be read ({exc.strerror or exc})", str(path)) from None
    _refuse_kind(info.st_mode, path)  # the stat above: not a second one
    if limit is not None and info.st_size > limit:
        raise LeafError(
            f"is too large ({info.st_size / 2**20:.0f} MiB; at most {limit / 2**20:.0f} MiB)",
            str(path),
        )
    return info.st_size


def read_text(path: str | os.PathLike, limit: int = MAX_TEXT_BYTES) -> str:
    """A text file's contents (UTF-8, or UTF-16 after its byte-order mark: Excel's "Unicode
    Text"), after `check_input_file`."""
    path = Path(path)
    check_input_file(path, limit)
    try:
        with open(path, "rb") as handle:
            data = handle.read(limit + 1)
    except OSError as exc:
        raise LeafError(f"cannot be read ({exc.strerror or exc})", str(path)) from None
    if len(data) > limit:
        raise LeafError(f"is too large (more than {limit / 2**20:.0f} MiB)", str(path))
    if is_utf16(data):  # a spreadsheet's "Unicode text"
        return _utf16_numbers(data, str(path))
    if b"\0" in data:
        raise LeafError("is not a text file (it holds binary data)", str(path))
    try:
        return data.decode("utf-8-sig")  # Excel's "CSV UTF-8" starts with a byte-order mark
    except UnicodeDecodeError:
        raise LeafError("is not a text file (not UTF-8)", str(path)) from None


UTF16_MARKS = (codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)


def is_utf16(head: bytes) -> bool:
    """Whether a file's first bytes are UTF-16's byte-order mark (Excel's "Unicode Text")."""
    return head[:2] in UTF16_MARKS


def _utf16_numbers(data: bytes, source: str) -> str:
    """UTF-16 `data` after its byte-order mark, decoded when it is mostly ASCII, as a point list
    is (nine tenths of its characters' high bytes zero); else not a text file."""
    body = data[2:]
    high = body[1::2] if data[:2] == codecs.BOM_UTF16_LE else body[0::2]
    if len(body) % 2 or high.count(0) < 0.9 * len(high):
        raise LeafError("is not a text file (it holds binary data)", source)
    try:
        return data.decode("utf-16")
    except UnicodeDecodeError:
        raise LeafError("is not a text file (not UTF-16, as its first bytes say)", source) from None


def read_numbers(path: str | os.PathLike, limit: int = MAX_TEXT_BYTES) -> str:
    """A point list's text (read_text), its decimal commas made points (decimal_commas)."""
    return decimal_commas(read_text(path, limit), str(path))


_COMMENT = re.compile(r"#[^\n]*")
# a number, `;`, the next on its line; each may be in double quotes (`"1,5";"0"`: a spreadsheet's
# cells stored as text)
_SEMICOLON_FIELDS = re.compile(r'\d"?[ \t]*;[ \t]*"?[-+.\d]')
_DECIMAL_COMMA = re.compile(r"\d,\d")
_DECIMAL_POINT = re.compile(r"\d\.|\.\d")
DECIMAL_HEAD = 1 << 16  # characters from a file's start that tell tab- or space-separated
_SPACED_FIELDS = re.compile(r'\d"?[ \t]+"?[-+.\d]')  # a number, spaces or tabs, the next
# `1, 2`, `1,2,3`, `"1.5","0"`: commas between fields (one beside a quote ends or starts a field)
_SEPARATING_COMMA = re.compile(r',[ \t]|[ \t],|,,|\d,\d+,|,$|",|,"', re.MULTILINE)
# a line of numbers and separators only: a title's or a header's words ('exported 2024 05 01')
# say nothing of how the numbers are separated
_NUMBERS_LINE = re.compile(r'^[-+.,;\deE \t\r"]+$', re.MULTILINE)


def decimal_commas(text: str, source: str) -> str:
    r"""`text` with its decimal commas made points when its numbers are separated by `;`, or by
    tabs or spaces with no comma between them, and written with a comma for the decimal mark
    (`1,5;2,25;0`, a European spreadsheet's CSV; `1,5<tab>2,25<tab>0`, its tab-separated text);
    else `text` as it is. A LeafError naming the first line with a decimal point when the file
    holds those too (`1.000,5`: a thousands separator, or two conventions mixed): which is meant
    cannot be told.

    Examples
    --------
    >>> decimal_commas("x;y;z\n1,5;-2,25;0\n", "leaf.csv")
    'x;y;z\n1.5;-2.25;0\n'
    >>> decimal_commas("1,5\t-2,25\t0\n", "leaf.txt")
    '1.5\t-2.25\t0\n'
    >>> decimal_commas("1,5,0\n", "leaf.csv")
    '1,5,0\n'
    """
    if "," not in text:
        return text  # the usual files: a scan of the text in C
    if ";" in text and _SEMICOLON_FIELDS.search(body := _COMMENT.sub("", text)):
        separated = "';'"
    else:  # told from the file's start: a regex over a whole 1e6-line CSV took 0.8 s
        head = "\n".join(_NUMBERS_LINE.findall(_COMMENT.sub("", text[:DECIMAL_HEAD])))
        if not _SPACED_FIELDS.search(head) or _SEPARATING_COMMA.search(head):
            return _no_quoted_commas(text, source)  # commas separate the fields
        separated, body = "tabs or spaces", _COMMENT.sub("", text) if "#" in text else text
    if not _DECIMAL_COMMA.search(body):
        return text
    if "." in body and _DECIMAL_POINT.search(body):  # `in` first: the regex took 0.7 s a 1e6 lines
        number, line = next(
            (n, t) for n, t in enumerate(body.splitlines(), start=1) if _DECIMAL_POINT.search(t)
        )
        raise LeafError(
            f"line {number}: numbers separated by {separated} with both decimal commas and points "
            f"({shorten(line.strip())!r}); write every number with one decimal mark",
            source,
        )
    return text.replace(",", ".")


_QUOTED_COMMA = re.compile(r'"[-+]?\d*,\d+(?:[eE][-+]?\d+)?"')  # `"1,5"`: a quoted comma


def _no_quoted_commas(text: str, source: str) -> str:
    """`text`, whose fields commas separate, unless a number in double quotes holds a comma:
    `"1,5","0"` may be 1.5 or, from a spreadsheet with a thousands separator (`"1,000"`), 1000.
    A LeafError naming its line (it was refused as 'not a number', or skipped as a header when
    on the first line)."""
    if '"' not in text:
        return text
    body = _COMMENT.sub("", text) if "#" in text else text  # its lines kept: comments cut
    found = _QUOTED_COMMA.search(body)
    if found is None:
        return text
    line = body.count("\n", 0, found.start()) + 1
    raise LeafError(
        f"line {line}: a quoted number with a comma "
        f"({found.group()}) in fields separated by commas: a decimal comma or a thousands "
        "separator? Save it with ';' between the fields, or with decimal points",
        source,
    )


def line_blocks(text: str, size: int | None = None) -> Iterator[tuple[int, str]]:
    r"""Blocks of whole lines of `text` (each about `size` characters, BLOCK_CHARS by default, cut
    after a newline), with the number of each block's first line (from 1, as `str.splitlines`
    counts them); how much of the text was handed out is reported (progress.report) after each
    block is parsed.

    Examples
    --------
    >>> list(line_blocks("1 2 3\n4 5 6\n7 8 9\n", size=8))
    [(1, '1 2 3\n4 5 6\n'), (3, '7 8 9\n')]
    """
    size = size or BLOCK_CHARS
    start, line = 0, 1
    while start < len(text):
        cut = text.find("\n", start + size - 1)
        end = len(text) if cut < 0 else cut + 1
        block = text[start:end]
        yield line, block
        line += len(block.splitlines())
        start = end
        progress.report(start / len(text))


def block_rows(block: str, usecols: tuple[int, ...] | None = None) -> np.ndarray | None:
    """The (n, c) numbers of a block of lines by numpy's compiled reader (comma, semicolon or
    whitespace separated; `#` comments and blank lines skipped; `usecols` the columns taken),
    about 3 times faster than a loop over the lines; None when numpy refuses the block (ragged
    or short lines, a word) or it holds no row: the caller's loop over its lines says why."""
    import io
    import warnings

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "input contained no data"
            rows = np.loadtxt(
                io.StringIO(block.replace(",", " ").replace(";", " ")),
                usecols=usecols, comments="#", ndmin=2, dtype=float,
            )  # fmt: skip
    except (ValueError, IndexError):
        return None
    return rows if len(rows) else None


def parse_number(field: str) -> float:
    """A float from a plain decimal field ("1.5", "-2e3", "nan"), or one in double quotes (as
    Python's csv.QUOTE_ALL and a spreadsheet's cells stored as text write them); ValueError
    otherwise (Python's float() also reads "1_0" as 10 and "١" as 1)."""
    if len(field) > 2 and field[0] == field[-1] == '"':
        field = field[1:-1]
    if not _NUMBER.fullmatch(field):
        raise ValueError(field)
    return float(field)


def load_json(path: str | os.PathLike) -> Any:
    """Parsed JSON, with its size and nesting bounded and each failure one LeafError."""
    text = read_text(path, MAX_JSON_BYTES)
    depth = json_depth(text)
    if depth > MAX_JSON_DEPTH:
        raise LeafError(f"nested {depth} levels deep (at most {MAX_JSON_DEPTH})", str(path))
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise LeafError(f"not valid JSON (line {exc.lineno}: {exc.msg})", str(path)) from None
    except (ValueError, RecursionError) as exc:  # e.g. an integer of more than 4300 digits
        raise LeafError(f"not valid JSON ({shorten(exc, 80)})", str(path)) from None


def json_depth(text: str) -> int:
    """The deepest nesting of [ and { in JSON text, strings aside (no recursion: 1e6 levels are
    counted as quickly as 1)."""
    bare = re.sub(r'"(?:[^"\\]|\\.)*"', '""', text)
    codes = np.frombuffer(bare.encode("utf-8", "replace"), dtype=np.uint8)
    step = np.zeros(len(codes), dtype=np.int64)
    step[(codes == ord("[")) | (codes == ord("{"))] = 1
    step[(codes == ord("]")) | (codes == ord("}"))] = -1
    return int(np.cumsum(step).max(initial=0))


def _head(path: Path) -> tuple[int, bytes]:
    """A regular file's size and its first MAX_HEADER bytes (where a header must end)."""
    size = check_input_file(path, limit=None)
    try:
        with open(path, "rb") as handle:
            return size, handle.read(MAX_HEADER)
    except OSError as exc:
        raise LeafError(f"cannot be read ({exc.strerror or exc})", str(path)) from None


def check_ply_header(path: str | os.PathLike) -> None:
    """Refuse a PLY file whose header declares more data than the file holds (a header can claim
    2e9 vertices in a 200-byte file; plyfile would allocate them first)."""
    path = Path(path)
    size, head = _head(path)
    end = head.find(b"end_header")
    if not head.startswith(b"ply") or end < 0:
        raise LeafError("not a readable PLY file (no 'ply' ... 'end_header' header)", str(path))
    body = size - (end + len(b"end_header") + 1)
    lines = head[:end].decode("ascii", "replace").splitlines()
    ascii_format = any(line.split()[:2] == ["format", "ascii"] for line in lines if line.split())
    elements: list[list[int]] = []  # [count, bytes per element at least]
    for line in lines:
        words = line.split()
        if not words:
            continue
        if words[0] == "element":
            if len(words) != 3 or not words[2].isdigit():
                raise LeafError(f"not a readable PLY file (bad line {shorten(line)!r})", str(path))
            elements.append([int(words[2]), 0])
        elif words[0] == "property" and elements:
            if ascii_format:
                elements[-1][1] += 2  # a digit and a separator at least
            elif words[1:2] == ["list"] and len(words) >= 3:
                elements[-1][1] += PLY_SIZES.get(words[2], 1)  # the list's length, at least
            elif len(words) >= 2:
                elements[-1][1] += PLY_SIZES.get(words[1], 1)
    needed = sum(count * max(width, 1) for count, width in elements)
    if needed > body:
        counts = ", ".join(f"{count}" for count, _ in elements)
        raise LeafError(
            f"not a readable PLY file: its header declares {counts} elements, which need at least "
            f"{needed} bytes, but the file holds {max(body, 0)}",
            str(path),
        )


def check_pcd_header(path: str | os.PathLike) -> None:
    """Refuse a PCD file whose header declares more points than the file holds (open3d would
    allocate them first), or that has no PCD header at all."""
    path = Path(path)
    size, head = _head(path)
    fields: dict[str, list[str]] = {}
    body = None
    offset = 0
    for raw in head.split(b"\n"):
        offset += len(raw) + 1
        words = raw.decode("ascii", "replace").split()
        if not words or words[0].startswith("#"):
            continue
        fields[words[0].upper()] = words[1:]
        if words[0].upper() == "DATA":
            body = size - offset
            break
    points = fields.get("POINTS", [""])[0]
    if body is None or not points.isdigit():
        raise LeafError("not a readable PCD file (no POINTS ... DATA header)", str(path))
    mode = (fields.get("DATA") or ["ascii"])[0].lower()
    if mode == "binary_compressed":
        return  # its size says nothing about the point count; open3d checks it
    sizes = [int(v) for v in fields.get("SIZE", []) if v.isdigit()]
    counts = [int(v) for v in fields.get("COUNT", []) if v.isdigit()] or [1] * len(sizes)
    width = sum(a * b for a, b in zip(sizes, counts, strict=False)) if mode == "binary" else 2
    needed = int(points) * max(width, 1)
    if needed > body:
        raise LeafError(
            f"not a readable PCD file: its header declares {points} points, which need at least "
            f"{needed} bytes, but the file holds {max(body, 0)}",
            str(path),
        )


def read_ply(path: str | os.PathLike) -> Any:
    """A PlyData, header checked first; any failure of the parser is one LeafError."""
    from plyfile import PlyData

    path = Path(path)
    check_ply_header(path)
    try:
        return PlyData.read(str(path))
    except MemoryError:
        raise LeafError("not a readable PLY file (too large to read)", str(path)) from None
    except Exception as exc:  # plyfile raises many types on a damaged file; all mean the same
        raise LeafError(f"not a readable PLY file ({shorten(exc, 80)})", str(path)) from None


def ply_xyz(ply: Any, path: str | os.PathLike) -> tuple[np.ndarray, tuple[str, ...]]:
    """The (n, 3) vertex coordinates of a PlyData and its vertex property names."""
    if "vertex" not in ply:
        raise LeafError("PLY file has no vertex element", str(path))
    vertex = ply["vertex"]
    names = vertex.data.dtype.names or ()
    if not {"x", "y", "z"} <= set(names):
        raise LeafError("PLY vertices need x, y and z properties", str(path))
    xyz = np.column_stack([ply_numbers(ply, c, path) for c in "xyz"])
    if len(vertex.data) == 0:
        raise LeafError("holds no points", str(path))
    return xyz, names


def ply_numbers(ply: Any, name: str, path: str | os.PathLike) -> np.ndarray:
    """The vertex property `name` of a PlyData, as floats; refused if it is a list (one per
    vertex: x y z, a leaf's labels)."""
    vertex = ply["vertex"]
    kind = vertex.data.dtype[name]
    if kind.kind not in "biuf" or kind.shape:
        raise LeafError(f"PLY vertex property {name} must be a number, not a list", str(path))
    return np.asarray(vertex[name], dtype=float)


PHOTO_SUFFIXES = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".webp")  # read_image's


def read_image(path: str | Path) -> np.ndarray:
    """An image file as an (h, w, 3 or 4) uint8 array, upright as a viewer shows it (its EXIF
    orientation applied: a phone stores a portrait photo's pixels sideways and says so); the
    one reader of photos and textures, so the leaf found, its pixel map, the texture and the
    app's photo dialog see the same pixels. LeafError if it cannot be read (a FIFO, which
    Pillow would wait on for ever, is refused unopened: issue 24, finding 17)."""
    from PIL import Image, ImageOps, UnidentifiedImageError
    from PIL.Image import DecompressionBombError

    check_input_file(path, None)  # Pillow's pixel limit bounds the size
    try:
        with Image.open(path) as image:
            with contextlib.suppress(Exception):  # a damaged EXIF block: the pixels as stored
                image = ImageOps.exif_transpose(image)
            image = image.convert("RGBA" if "A" in image.getbands() else "RGB")
            return np.asarray(image)
    except DecompressionBombError:
        raise LeafError("not a readable image (too many pixels)", str(path)) from None
    except (UnidentifiedImageError, OSError, ValueError) as exc:
        raise LeafError(f"not a readable image ({type(exc).__name__})", str(path)) from None
