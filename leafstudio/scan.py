"""Reading leaf scans: point clouds of a leaf's whole surface (.ply, .pcd, .xyz, .csv, .txt).

Only x, y, z are read; extra columns or properties (normals, colours, intensities) are ignored.
Leaf files with labelled boundary and veins are io.py's business; this reads raw scans.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from leafstudio.errors import LeafError, shorten
from leafstudio.extras import require
from leafstudio.inputs import (
    check_input_file,
    check_not_a_folder,
    check_pcd_header,
    parse_number,
    ply_xyz,
    read_ply,
    read_text,
)

SCAN_SUFFIXES = (".ply", ".pcd", ".xyz", ".csv", ".txt")
MIN_SCAN_POINTS = 50


def _fast_rows(text: str) -> np.ndarray | None:
    """x, y, z of a well-formed point list by numpy's compiled reader (about 3 times faster than
    the line loop at 1e6 lines); None when it is not well formed (a header after data, short or
    ragged lines...), for _text_rows to read it and name the faulty line."""
    import io

    skip = 0
    for line in io.StringIO(text):  # a header: leading lines whose first field is not a number
        fields = line.split("#", 1)[0].replace(",", " ").replace(";", " ").split()
        if fields:
            try:
                float(fields[0])
                break
            except ValueError:
                pass
        skip += 1
    else:
        return None
    try:
        rows = np.loadtxt(
            io.StringIO(text.replace(",", " ").replace(";", " ")),
            usecols=(0, 1, 2), skiprows=skip, comments="#", ndmin=2, dtype=float,
        )  # fmt: skip
    except (ValueError, IndexError):
        return None
    return rows


def _text_rows(path: Path, text: str) -> np.ndarray:
    """x, y, z of each numeric line of a point list (comma, semicolon or whitespace separated)."""
    fast = _fast_rows(text)
    if fast is not None:
        return fast
    rows: list[list[float]] = []
    for number, line in enumerate(text.splitlines(), start=1):
        fields = line.split("#", 1)[0].replace(",", " ").replace(";", " ").split()
        if not fields:
            continue
        try:
            values = [parse_number(f) for f in fields[:3]]
        except ValueError:
            if not rows:  # a header line
                continue
            raise LeafError(
                f"line {number}: not a number in {shorten(line.strip())!r}", str(path)
            ) from None
        if len(values) < 3:
            raise LeafError(f"line {number}: needs x, y and z, got {len(values)} values", str(path))
        rows.append(values)
    return np.asarray(rows, dtype=float).reshape(-1, 3)


def _pcd_rows(path: Path) -> np.ndarray:
    """x, y, z of a PCD file (ASCII or binary) through open3d, which reports nothing on failure."""
    check_pcd_header(path)  # point counts against the file's size, before open3d allocates
    try:
        o3d = require("open3d", "reading .pcd scans")
    except LeafError as exc:
        raise LeafError(exc.problem, str(path)) from None

    with o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error):
        cloud = o3d.io.read_point_cloud(str(path), format="pcd")
    points = np.asarray(cloud.points, dtype=float)
    if len(points) == 0:
        raise LeafError("not a readable PCD file, or it holds no points", str(path))
    return points


def _ply_rows(path: Path) -> np.ndarray:
    return ply_xyz(read_ply(path), path)[0]  # header checked against the file's size first


def read_scan(path: str | os.PathLike) -> np.ndarray:
    """The (n, 3) points of a leaf scan.

    Raises
    ------
    LeafError
        With the file's name, if it is missing, unreadable, of an unknown type, holds NaN or
        infinite coordinates, or has fewer than MIN_SCAN_POINTS points.
    """
    path = Path(path)
    check_not_a_folder(path)
    suffix = path.suffix.lower()
    if suffix not in SCAN_SUFFIXES:
        raise LeafError(
            f"unknown scan type {suffix or '(none)'!r}; use one of {', '.join(SCAN_SUFFIXES)}",
            str(path),
        )
    check_input_file(path)  # a regular file (not a FIFO or a device) of a bounded size
    if suffix == ".ply":
        points = _ply_rows(path)
    elif suffix == ".pcd":
        points = _pcd_rows(path)
    else:
        points = _text_rows(path, read_text(path))
    if len(points) == 0:
        raise LeafError("holds no points", str(path))
    if not np.all(np.isfinite(points)):
        raise LeafError("NaN or infinite coordinates", str(path))
    if len(points) < MIN_SCAN_POINTS:
        raise LeafError(
            f"too few points for a leaf scan: {len(points)} (need {MIN_SCAN_POINTS})", str(path)
        )
    return points
