"""Leaf files in and out (.csv/.txt/.xyz, .ply with labels, .leaf.json) and mesh export.

Point lists: one point per line, `x y z [label]`, comma or whitespace separated, an optional header
line; label 0 is the boundary and 1..n are veins. A file without labels is a boundary; one of two
columns, `x y`, a flat one (z = 0: an outline traced in a spreadsheet or on a photo).
"""

from __future__ import annotations

import json
import math
import os
import re
from collections.abc import Sequence
from io import BytesIO
from pathlib import Path
from typing import Any

import numpy as np

from leafstudio._shared.inputs import (
    PHOTO_SUFFIXES,
    block_rows,
    check_file_kind,
    line_blocks,
    load_json,
    parse_number,
    ply_numbers,
    ply_xyz,
    read_numbers,
    read_ply,
)
from leafstudio._shared.safewrite import check_outputs, write_bytes
from leafstudio._shared.safewrite import staged as staged  # re-exported: outputs replaced together
from leafstudio.core.bend import Pose
from leafstudio.core.placed import PlacedPose
from leafstudio.core.pose_limits import check_pose
from leafstudio.core.sheet_bend import Scaled
from leafstudio.errors import LeafError, shorten
from leafstudio.model import Leaf, Params
from leafstudio.sources.bend_entry import FRAME_KEYS, project_bend

POINT_SUFFIXES = (".csv", ".txt", ".xyz")
LEAF_SUFFIXES = (*POINT_SUFFIXES, ".ply", ".leaf.json", ".json")
FORMAT_NAME, FORMAT_VERSION = "leafstudio", 3  # 2: fold and curl keep the size (bend_entry.py)
# 3: a scan's sheet keeps a smoothing per cell (core/sheet.refit); written only by projects that
# have one, so that an older LeafStudio says the file is newer rather than that its sheet does
# not read whole (version 2's single value still opens as it was)
PER_CELL_SMOOTHING = 3
MAX_LABEL = 100_000  # vein labels 1..MAX_LABEL


def _suffix(path: Path) -> str:
    name = path.name.lower()
    return ".leaf.json" if name.endswith(".leaf.json") else path.suffix.lower()


def read_point_table(path: Path, columns: Sequence[int] = (2, 3, 4)) -> np.ndarray:
    """Numbers from a point list, (n, c) with c one of `columns` (2: x y, returned with z = 0 as
    a third column); header and blank lines skipped. Read in blocks of lines (line_blocks: each
    reported as read), each by numpy's reader when it holds only numbers, else line by line,
    which names the first faulty line. A header naming x, y and z (and label) says which columns
    they are, in any order among others (an index); one naming x and y but no z, a flat list."""
    text = read_numbers(path)  # decimal commas (`1,5;2,25;0`) made points
    named = named_columns(text, columns)
    table = _PointTable(path, columns if named is None else (named[0],))
    for first, block in line_blocks(text):
        table.add(first, block)
    if not table.parts:
        raise LeafError("holds no points", str(path))
    rows = np.vstack(table.parts)
    if named is not None:  # a column of zeros (index -1) where the header names no z
        rows = np.column_stack([rows, np.zeros(len(rows))])
        return rows[:, named[1]]
    return np.column_stack([rows, np.zeros(len(rows))]) if rows.shape[1] == 2 else rows


NOT_HEIGHTS = {"", "id", "index", "idx", "n", "no", "num", "point", "pt", "label"}  # header names


def named_columns(text: str, columns: Sequence[int] = (3, 4)) -> tuple[int, list[int]] | None:
    r"""From a header line naming x and y, and z (any case, a unit after them: `x [mm]`): its
    width and the indices of x, y, z (-1 when it names no z and its other columns are an index
    or labels, NOT_HEIGHTS: the points are flat) and, when 4 is one of `columns`, label; None for
    no such header.

    Examples
    --------
    >>> named_columns(",x,y,z,label\n0,1.5,2,0,0\n")
    (5, [1, 2, 3, 4])
    >>> named_columns("id,x,y\n0,1.5,2\n")
    (3, [1, 2, -1])
    >>> named_columns("x,y,height\n1.5,2,0.1\n") is None  # read in order: x, y, z
    True
    >>> named_columns("1 2 3\n") is None
    True
    """
    lines = filter(None, (r.split("#")[0].rstrip().lstrip(" ") for r in text[:4096].splitlines()))
    fields, data = header_fields(next(lines, "")), header_fields(next(lines, ""))
    if len(data) != len(fields):
        return None  # the first row is not as wide as the header: its names are not the columns'
    names = [re.split(r"[\s(\[]", f.strip().strip("\"'").lower(), maxsplit=1)[0] for f in fields]
    if not {"x", "y"} <= set(names) or len(set(names)) < len(names) - names.count(""):
        return None
    if "z" not in names and not set(names) - {"x", "y"} <= NOT_HEIGHTS:
        return None  # `x,y,height`: its third column may be the heights, read in order as before
    wanted = ["x", "y", "z", *(["label"] if 4 in columns and "label" in names else [])]
    take = [names.index(name) if name in names else -1 for name in wanted]
    if take == list(range(len(take))) and len(names) == len(take):
        return None  # the columns in their usual order: read as before (`x y z` over labels too)
    if take[:2] == [0, 1] and len(names) == 2:
        return None  # `x,y`: a flat list, read as before
    return len(names), take


def header_fields(line: str) -> list[str]:
    """A line's fields by its own separator, empty ones kept (`x [mm],y [mm]`: 2)."""
    return line.split(next((s for s in ",;\t" if s in line), None))


class _PointTable:
    """The rows of a point list read so far (read_point_table), block by block."""

    def __init__(self, path: Path, columns: Sequence[int]) -> None:
        self.path, self.columns = path, tuple(columns)
        self.parts: list[np.ndarray] = []
        self.width: int | None = None  # the columns of the rows read so far
        self.header = False  # a header line was skipped (only one, before any row)
        self.names = 0  # ... and how many fields it has

    def add(self, first: int, block: str) -> None:
        """The rows of `block`, whose first line is line `first` of the file."""
        fast = self._fast(block)
        if fast is not None:
            self.parts.append(fast)
            self.width = fast.shape[1]
            return
        rows = [row for number, line in enumerate(block.splitlines(), start=first)
                if (row := self._row(number, line)) is not None]  # fmt: skip
        if rows:
            self.parts.append(np.asarray(rows, dtype=float))

    def _fast(self, block: str) -> np.ndarray | None:
        """The block by numpy's reader, when it holds nothing but numbers and separators (no
        header, comment or word: there numpy's reader and parse_number could differ) and its
        rows are finite and as wide as they must be; else None."""
        if not block.isascii() or _NOT_PLAIN.search(block):
            return None
        rows = block_rows(block)
        if rows is None or not np.all(np.isfinite(rows)):
            return None
        width = rows.shape[1]
        return rows if (self.width or width) == width and width in self.columns else None

    def _row(self, number: int, line: str) -> list[float] | None:
        """Line `number`'s numbers, None for a blank or header line; LeafError naming it if bad."""
        text = line.split("#", 1)[0].strip()
        if not text:
            return None
        path = str(self.path)
        fields = text.replace(",", " ").replace(";", " ").split()
        try:
            values = [parse_number(f) for f in fields]
        except ValueError:
            if self.width is None and not self.header:  # a header line
                self.header, self.names = True, len(header_fields(text))
                return None
            raise LeafError(f"line {number}: not a number in {shorten(text)!r}", path) from None
        if len(values) == 2 and self.names > 2 and self.width is None:  # `x,y,z` over `1,2`
            raise LeafError(
                f"line {number}: 2 columns where the header line names {self.names}", path
            )
        if self.width is not None and len(values) != self.width:
            raise LeafError(
                f"line {number}: {len(values)} columns where earlier lines have {self.width}", path
            )
        if len(values) not in self.columns:
            *most, last = [str(c) for c in self.columns]
            expected = f"{', '.join(most)} or {last}" if most else last
            names = "x y [z]" if 4 not in self.columns else "x y [z] [label]"
            names = names if 2 in self.columns else "x y z [label]"  # a header's width
            scan = "; a scan (x y z with normals or colours)? `leafstudio extract` takes a leaf's"
            raise LeafError(
                f"line {number}: expected {expected} columns ({names}), got {len(values)}"
                + (f"{scan} boundary and veins from it" if len(values) > 4 else ""),
                path,
            )
        if not all(math.isfinite(v) for v in values):
            raise LeafError(f"line {number}: NaN or infinite value", path)
        self.width = len(values)
        return values


_NOT_PLAIN = re.compile(r"[^0-9eE+\-.,;\s]")  # any other character: read line by line


def _split_labels(xyz: np.ndarray, labels: np.ndarray | None, source: str) -> Leaf:
    if labels is None:
        return _checked_leaf(xyz, [], source)
    if (
        not np.all(np.isfinite(labels))
        or not np.all(labels == np.round(labels))
        or labels.min() < 0
        or labels.max() > MAX_LABEL
    ):
        raise LeafError(
            f"labels must be whole numbers from 0 to {MAX_LABEL} (0 boundary, 1..n veins)", source
        )
    labels = labels.astype(int)
    veins = [xyz[labels == lab] for lab in np.unique(labels[labels > 0])]
    return _checked_leaf(xyz[labels == 0], veins, source)


def _checked_leaf(boundary: np.ndarray, veins: list[np.ndarray], source: str) -> Leaf:
    if len(boundary) < 3:
        raise LeafError(f"needs at least 3 boundary points (label 0), got {len(boundary)}", source)
    try:
        return Leaf(boundary=boundary, veins=veins)
    except LeafError as exc:
        raise LeafError(exc.problem, source) from None


def _read_ply(path: Path) -> Leaf:
    ply = read_ply(path)  # header checked against the file's size; one LeafError on failure
    xyz, names = ply_xyz(ply, path)
    if not np.all(np.isfinite(xyz)):
        raise LeafError("NaN or infinite coordinates", str(path))
    labels = ply_numbers(ply, "label", path) if "label" in names else None
    return _split_labels(xyz, labels, str(path))


def _read_project(path: Path) -> dict[str, Any]:
    data = load_json(path)  # size and nesting bounded (_shared/inputs.py)
    if not isinstance(data, dict) or data.get("format") != FORMAT_NAME:
        raise LeafError(f'not a LeafStudio project (no "format": "{FORMAT_NAME}")', str(path))
    version = data.get("version", FORMAT_VERSION)
    if isinstance(version, bool) or not isinstance(version, int) or version < 1:
        raise LeafError(
            f'"version" must be a whole number from 1, got {shorten(json.dumps(version))}',
            str(path),
        )
    if version > FORMAT_VERSION:
        raise LeafError(f"written by a newer LeafStudio (version {shorten(version)})", str(path))
    for key, kind, what in (
        ("boundary", list, "a list of [x, y, z] points"),
        ("veins", list, "a list of veins, each a list of [x, y, z] points"),
        ("params", dict, "an object of parameter names and values"),
        ("sketch", dict, "an object"),
    ):
        if data.get(key) is not None and not isinstance(data[key], kind):
            raise LeafError(
                f'"{key}" must be {what}, got {shorten(json.dumps(data[key]))}', str(path)
            )
    return data


def _project_points(values: list, what: str, source: str) -> np.ndarray:
    """An (n, 3) float array from a project's list of [x, y, z] points."""
    if any(not isinstance(p, list) or len(p) != 3 for p in values) or any(
        isinstance(c, bool) or not isinstance(c, (int, float)) for p in values for c in p
    ):
        raise LeafError(f"{what} must be a list of [x, y, z] points (numbers)", source)
    try:
        return np.asarray(values, dtype=float).reshape(-1, 3)
    except OverflowError:
        raise LeafError(f"{what} holds a number too large for a coordinate", source) from None


def load_project(path: str | os.PathLike) -> tuple[Leaf, Params | None, dict[str, Any]]:
    """A .leaf.json project: its leaf, its parameters (None if absent) and its sketch."""
    path = Path(path)
    data = _read_project(path)
    source = str(path)
    boundary = _project_points(data.get("boundary") or [], "boundary", source)
    veins_data = data.get("veins") or []
    if any(not isinstance(v, list) for v in veins_data) or any(
        v and not isinstance(v[0], list) for v in veins_data
    ):
        raise LeafError(
            '"veins" must be a list of veins, each a list of [x, y, z] points (one vein is '
            "[[[x, y, z], ...]])",
            source,
        )
    veins = [_project_points(v, f"vein {i + 1}", source) for i, v in enumerate(veins_data)]
    leaf = _checked_leaf(boundary, veins, source)
    if data.get("bend"):
        leaf = project_bend(data["bend"], source, leaf, data.get("version", FORMAT_VERSION))
    try:
        params = Params.from_dict(data["params"]) if data.get("params") else None
    except (TypeError, LeafError) as exc:
        raise LeafError(f"bad params: {exc}", source) from None
    return leaf, params, dict(data.get("sketch") or {})


def load_leaf(path: str | os.PathLike, veins: Sequence[str | os.PathLike] = ()) -> Leaf:
    """Read a leaf from a point list, a labelled PLY or a project; `veins` adds one vein per file.

    Parameters
    ----------
    path : str or path-like
        A point list (.csv, .txt, .xyz: rows `x y z [label]`, label 0 the boundary, 1..n vein
        n, comma or whitespace separated, an optional header line; without labels, a boundary;
        rows `x y` a flat boundary, z = 0),
        a PLY with an integer vertex property `label`, or a project (.leaf.json).
    veins : sequence of paths, default: ()
        Files of one vein each (a point list, `x y z` or `x y`, or a PLY, labels ignored), added
        after the file's own.

    Returns
    -------
    Leaf
        The (n, 3) boundary and one (m_i, 3) array per vein, as read (a project's parameters and
        sketch are left out: see `load_project`).

    Raises
    ------
    LeafError
        With the file's name and the problem, for anything unreadable or malformed.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> import leafstudio as ls
    >>> path = Path(tempfile.mkdtemp()) / "leaf.csv"
    >>> ls.save_leaf(ls.demo("parallel"), path)
    >>> leaf = ls.load_leaf(path)
    >>> leaf.boundary.shape, [v.shape for v in leaf.veins]
    ((238, 3), [(48, 3), (48, 3)])
    >>> ls.load_leaf(path.with_name("missing.csv"))
    Traceback (most recent call last):
    leafstudio.errors.LeafError: .../missing.csv: no such file
    """
    path = Path(path)
    if isinstance(veins, (str, os.PathLike)):
        veins = [veins]  # one vein file given alone, not a sequence of one-letter names
    check_file_kind(path)
    suffix = _suffix(path)
    if suffix in POINT_SUFFIXES:
        table = read_point_table(path)
        leaf = _split_labels(table[:, :3], table[:, 3] if table.shape[1] == 4 else None, str(path))
    elif suffix == ".ply":
        leaf = _read_ply(path)
    elif suffix in (".leaf.json", ".json"):
        leaf = load_project(path)[0]
    else:
        photo = (
            "; a photo? `leafstudio photo` finds the leaf in it" if suffix in PHOTO_SUFFIXES else ""
        )
        raise LeafError(
            f"unknown file type {suffix or '(none)'!r}; use one of {', '.join(LEAF_SUFFIXES)}"
            + photo,
            str(path),
        )
    extra = [_read_vein(Path(v)) for v in veins]
    return Leaf(boundary=leaf.boundary, veins=[*leaf.veins, *extra]) if extra else leaf


def _read_vein(path: Path) -> np.ndarray:
    if _suffix(path) == ".ply":
        return _read_ply(path).boundary
    return read_point_table(path, columns=(2, 3))


def check_leaf_output(output: str, inputs: Sequence[str | os.PathLike]) -> None:
    """Refuse, before any work, a leaf output of an unknown type, one that is also one of the
    `inputs`, or one that cannot be written (LeafError naming the output)."""
    if not output.lower().endswith(LEAF_SUFFIXES):
        raise LeafError(f"unknown leaf type; use one of {', '.join(LEAF_SUFFIXES)}", output)
    check_outputs(list(inputs), [output])


def project_dict(
    leaf: Leaf,
    params: Params | None = None,
    sketch: dict[str, Any] | None = None,
    photo: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """The .leaf.json content for a leaf; `photo` is the photo it came from (sources/leafphoto.py),
    kept only when given."""
    data = {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "boundary": leaf.boundary.tolist(),
        "veins": [v.tolist() for v in leaf.veins],
        "params": params.to_dict() if params else {},
        "sketch": sketch or {},
    }
    if photo is not None:
        data["photo"] = photo
    if isinstance(leaf.bend, Pose):  # a posed form: reconstructed flat, then bent (core/bend.py)
        data["bend"] = leaf.bend.entry()
    elif isinstance(leaf.bend, PlacedPose):  # a leaf bent in the app, about its midrib
        f, pose = leaf.bend.frame, leaf.bend.pose
        frame = dict(zip(FRAME_KEYS, (f.origin, f.u, f.v, f.normal), strict=True))
        data["bend"] = pose.entry()
        data["bend"]["frame"] = {k: [float(x) for x in a] for k, a in frame.items()}
    elif isinstance(leaf.bend, Scaled):  # a scan's blade, unrolled (core/sheet_bend.py)
        data["bend"] = leaf.bend.entry(np.vstack([leaf.boundary, leaf.vein_points]))
    if not isinstance(data.get("bend", {}).get("sheet", {}).get("smoothing", 0.0), list):
        data["version"] = PER_CELL_SMOOTHING - 1  # nothing in it a version 2 reader lacks
    return data


def bend_not_kept(leaf: Leaf, path: str | os.PathLike) -> str | None:
    """The one line saying that writing the bent `leaf` to `path` drops its bend, None when it
    does not (a flat leaf, a project). A point list or PLY holds the bent points only, not the
    pose or the scan's sheet that lays them flat: opened again, its curves are unfolded by a
    fitted pose (core/unfold.py), which a twisted form's may not be (a lanceolate form twisted
    1 was refused: "vein 1: 2 of 49 points lie outside the boundary")."""
    if leaf.bend is None or _suffix(Path(path)) in (".leaf.json", ".json"):
        return None
    if isinstance(leaf.bend, Pose | PlacedPose):
        lost = "its pose (fold, curl, roll, twist)"
    else:
        lost = "the blade's sheet they were found on (core/sheet.py)"
    return f"{path}: a point list keeps the bent points, not {lost}; a .leaf.json keeps it"


def save_leaf(
    leaf: Leaf,
    path: str | os.PathLike,
    params: Params | None = None,
    sketch: dict[str, Any] | None = None,
    photo: dict[str, Any] | None = None,
) -> None:
    """Write a leaf as .leaf.json (with params, sketch and the photo it came from), a labelled
    point list or PLY, atomically (a failed write leaves the old file as it was).

    Parameters
    ----------
    leaf : Leaf
        The (n, 3) boundary and the (m_i, 3) veins.
    path : str or path-like
        Its suffix chooses the format: .leaf.json/.json (a project), .csv/.txt/.xyz (rows
        `x y z label`, with a header), .ply (vertices with a `label` property).
    params : Params, optional
        Saved with a project (ignored by the other formats); `load_project` gives them back.
    sketch : dict, optional
        The app's sketch (control points), saved with a project.
    photo : dict, optional
        The photo the leaf came from, `{"image": PATH, "pixel_from_world": [[...], [...]]}`.

    Raises
    ------
    LeafError
        For an unknown suffix, a file that cannot be written, or a project whose pose is past
        what it keeps of the blade (core/pose_limits.py: its loader would refuse it).

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> import leafstudio as ls
    >>> path = Path(tempfile.mkdtemp()) / "nested.leaf.json"
    >>> ls.save_leaf(ls.demo("nested"), path, ls.Params(k=3))
    >>> from leafstudio.sources.files import load_project
    >>> leaf, params, sketch = load_project(path)
    >>> params.k, len(leaf.veins)
    (3, 7)
    """
    path = Path(path)
    suffix = _suffix(path)
    labels = np.concatenate(
        [np.zeros(len(leaf.boundary))] + [np.full(len(v), i + 1) for i, v in enumerate(leaf.veins)]
    ).astype(int)
    xyz = np.vstack([leaf.boundary, *leaf.veins])
    if suffix in (".leaf.json", ".json"):
        try:  # a project the loader would refuse (its pose past its limits) is not written
            check_pose(leaf.bend, leaf.boundary, list(leaf.veins))
        except LeafError as exc:
            raise LeafError(exc.problem, str(path)) from None
        write_bytes(path, json.dumps(project_dict(leaf, params, sketch, photo), indent=1))
    elif suffix in POINT_SUFFIXES:
        sep = "," if suffix == ".csv" else " "
        lines = [sep.join(["x", "y", "z", "label"])]
        lines += [
            sep.join([f"{x:.9g}", f"{y:.9g}", f"{z:.9g}", str(lab)])
            for (x, y, z), lab in zip(xyz, labels, strict=True)
        ]
        write_bytes(path, "\n".join(lines) + "\n")
    elif suffix == ".ply":
        from plyfile import PlyData, PlyElement

        data = np.empty(len(xyz), dtype=[("x", "f8"), ("y", "f8"), ("z", "f8"), ("label", "i4")])
        data["x"], data["y"], data["z"], data["label"] = xyz[:, 0], xyz[:, 1], xyz[:, 2], labels
        buffer = BytesIO()
        PlyData([PlyElement.describe(data, "vertex")], text=False).write(buffer)
        write_bytes(path, buffer.getvalue())
    else:
        kinds = ", ".join([".leaf.json", *POINT_SUFFIXES, ".ply"])
        raise LeafError(
            f"cannot write a leaf as {suffix or '(none)'!r}: its curves go to {kinds}"
            " (a mesh: `leafstudio reconstruct LEAF -o MESH`)",
            str(path),
        )
