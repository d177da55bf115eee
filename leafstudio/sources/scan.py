"""Reading leaf scans: point clouds of a leaf's whole surface (.ply, .pcd, .xyz, .csv, .txt), or
the meshes scanners and photogrammetry write (.obj, .stl, .off), read as points on their surface.

Only x, y, z are read; extra columns or properties (normals, colours, intensities) are ignored.
Leaf files with labelled boundary and veins are sources/files.py's business; this reads raw scans.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from leafstudio._shared.extras import require
from leafstudio._shared.inputs import (
    block_rows,
    check_file_kind,
    check_input_file,
    check_pcd_header,
    decimal_commas,
    is_utf16,
    line_blocks,
    parse_number,
    ply_xyz,
    read_numbers,
    read_ply,
)
from leafstudio.errors import LeafError, shorten
from leafstudio.model import Leaf

MESH_SCAN_SUFFIXES = (".obj", ".stl", ".off")  # read through trimesh (_mesh_points)
SCAN_SUFFIXES = (".ply", ".pcd", ".xyz", ".csv", ".txt", *MESH_SCAN_SUFFIXES)
MESH_SCAN_POINTS = 20_000  # at least this many points on a mesh's surface (_mesh_points)
MIN_SCAN_POINTS = 50
LEAF_COLUMNS = 4  # x y z [label]: a point list with more columns is a scan
OUTLINE_POINTS = 200  # an extracted outline's default count (sources/extract.py: its spacing
# sets the veins' and the rim's); here, with no scipy, for `extract --points` and batch's key


def _fast_rows(text: str) -> np.ndarray | None:
    """x, y, z of a well-formed point list by numpy's compiled reader (about 3 times faster than
    the line loop at 1e6 lines), in blocks of lines (line_blocks: each reported as read); None
    when it is not well formed (a header after data, short or ragged lines...), for _text_rows to
    read it and name the faulty line."""
    start = 0
    for line in text.splitlines(keepends=True):  # a header: leading lines whose first field is
        fields = line.split("#", 1)[0].replace(",", " ").replace(";", " ").split()  # not a number
        if fields:
            try:
                float(fields[0])
                break
            except ValueError:
                pass
        start += len(line)
    else:
        return None
    parts = []
    for _first, block in line_blocks(text[start:]):
        rows = block_rows(block, usecols=(0, 1, 2))
        if rows is None and any(line.split("#", 1)[0].strip() for line in block.splitlines()):
            return None  # a block of comments or blank lines alone holds no rows: no fault
        if rows is not None:
            parts.append(rows)
    return np.vstack(parts) if parts else None


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


def _mesh_points(path: Path) -> np.ndarray:
    """Points spread evenly over a scanned mesh's surface, as a scanner's cloud is: area-weighted
    samples (as many as its vertices, at least MESH_SCAN_POINTS; seeded, so a file always gives
    the same points), since a mesh's vertices crowd where its triangles are small and a CAD-like
    STL has a few large ones. A mesh without faces (an OBJ of vertices only) gives its vertices."""
    import trimesh  # heavy: only a mesh scan needs it

    try:
        loaded = trimesh.load(str(path), process=False)
        parts = loaded.dump() if isinstance(loaded, trimesh.Scene) else [loaded]
    except Exception as exc:  # trimesh's loaders raise many kinds for a damaged file
        raise LeafError(f"not a readable mesh ({shorten(str(exc))})", str(path)) from None
    points, meshes = [], []
    for part in parts:
        faces = np.asarray(getattr(part, "faces", np.empty((0, 3))))
        (meshes if len(faces) else points).append(part)
    if meshes:
        mesh = trimesh.util.concatenate(meshes) if len(meshes) > 1 else meshes[0]
        bad = np.flatnonzero(~np.isfinite(mesh.vertices).all(axis=1))
        if len(bad):  # refused still: its triangles join them (a cloud's are left out)
            where = _where(bad, len(mesh.vertices), "vertex", "vertices")
            raise LeafError(f"NaN or infinite coordinates {where}", str(path))
        if mesh.area > 0:
            count = max(len(np.unique(mesh.vertices, axis=0)), MESH_SCAN_POINTS)
            sampled, _faces = trimesh.sample.sample_surface(mesh, count, seed=0)
            points.append(sampled)
        else:
            points.append(mesh.vertices)
    rows = [np.asarray(getattr(p, "vertices", p), dtype=float).reshape(-1, 3) for p in points]
    if not rows or not sum(map(len, rows)):
        raise LeafError("not a readable mesh, or it holds no points", str(path))
    return np.vstack(rows)


def _ply_rows(path: Path) -> np.ndarray:
    return ply_xyz(read_ply(path), path)[0]  # header checked against the file's size first


def read_scan(path: str | os.PathLike) -> np.ndarray:
    """The (n, 3) points of a leaf scan, every one of them finite.

    Raises
    ------
    LeafError
        With the file's name, if it is missing, unreadable, of an unknown type, holds NaN or
        infinite coordinates, or has fewer than MIN_SCAN_POINTS points.
    """
    points = _scan_rows(Path(path))
    bad = np.flatnonzero(~np.isfinite(points).all(axis=1))
    if len(bad):  # how many and the first, in the file's order (a leaf file names its line)
        raise LeafError(f"NaN or infinite coordinates {_where(bad, len(points))}", str(path))
    return _enough(points, path)


def read_scan_returns(path: str | os.PathLike) -> tuple[np.ndarray, tuple[str, ...]]:
    """The (n, 3) finite points of a leaf scan, less those a scanner wrote as NaN or infinite
    (an organised cloud's missed returns: PCL and Open3D write a pixel without a return as NaN,
    and a Kinect-style PCD of a leaf holds thousands), and a note of how many were left out.
    open_scan reads a scan so: such a file was refused whole over one NaN point (qa37).

    Raises
    ------
    LeafError
        As read_scan, but for NaN or infinite points: when fewer than MIN_SCAN_POINTS are left.
    """
    points = _scan_rows(Path(path))
    bad = np.flatnonzero(~np.isfinite(points).all(axis=1))
    if not len(bad):
        return _enough(points, path), ()
    kept = np.delete(points, bad, axis=0)
    if len(kept) < MIN_SCAN_POINTS:
        raise LeafError(
            "too few points for a leaf scan once those with NaN or infinite coordinates are left "
            f"out: {len(kept)} of {len(points)} (need {MIN_SCAN_POINTS})",
            str(path),
        )
    note = (
        f"left out {len(bad)} of its {len(points)} points, whose coordinates are NaN or infinite "
        f"(a scanner's missed returns; the first is point {bad[0] + 1})"
    )
    return kept, (note,)


def _where(bad: np.ndarray, total: int, one: str = "point", many: str = "points") -> str:
    """Where a scan's non-finite points are: how many, and the first in the file's order."""
    return f"at {len(bad)} of {total} {many} (the first is {one} {bad[0] + 1})"


def _scan_rows(path: Path) -> np.ndarray:
    """The (n >= 1, 3) rows of a scan file, as read (NaN rows kept): read_scan's file checks."""
    check_file_kind(path)
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
    elif suffix in MESH_SCAN_SUFFIXES:
        points = _mesh_points(path)
    else:
        points = _text_rows(path, read_numbers(path))  # decimal commas made points
    if len(points) == 0:
        raise LeafError("holds no points", str(path))
    return points


def _enough(points: np.ndarray, path: str | os.PathLike) -> np.ndarray:
    """`points`, refused when fewer than MIN_SCAN_POINTS."""
    if len(points) < MIN_SCAN_POINTS:
        raise LeafError(
            f"too few points for a leaf scan: {len(points)} (need {MIN_SCAN_POINTS})", str(path)
        )
    return points


def is_scan_file(path: str) -> bool:
    """True for a file only a scan reader takes: a .pcd, a mesh (.obj, .stl, .off), or a point
    list whose first row of numbers has more than x, y, z and a label (normals, colours)."""
    path_ = Path(path)
    suffix = path_.suffix.lower()
    if suffix == ".pcd" or suffix in MESH_SCAN_SUFFIXES:
        return True
    if suffix not in SCAN_SUFFIXES or suffix == ".ply":
        return False
    try:
        with path_.open("rb") as raw:  # a spreadsheet's "Unicode Text" (inputs.read_text)
            utf16 = is_utf16(raw.read(2))
        with path_.open(encoding="utf-16" if utf16 else "utf-8") as handle:
            for line in handle:  # a European row's decimal commas are not separators
                row = decimal_commas(line.split("#", 1)[0], path)
                fields = row.replace(",", " ").replace(";", " ").split()
                if fields:
                    try:
                        return len([parse_number(f) for f in fields]) > LEAF_COLUMNS
                    except ValueError:
                        continue  # a header
    except (OSError, UnicodeDecodeError, LeafError):  # LeafError: both decimal marks in a row
        return False
    return False


SCAN_SHARE = 0.33  # looks_like_scan: a point list this much surrounded is a sparse scan (the
# eight shared scans cut to 150 or 300 points: 0.35-0.51), not a sparse noisy outline (shuffled,
# noise 1% of the length: up to 0.31, cover.FILL_SHARE's note), which the pipeline refuses


def looks_like_scan(leaf: Leaf) -> bool:
    """True when an unlabelled point list covers a surface (a scan) rather than tracing an
    outline, by the tests the pipeline refuses a scan as a boundary by
    (plausibility.boundary_cover): the surface's spread, or, where too sparse for it (a scan of
    300 points), the share of points surrounded (the app opened those as a boundary, and showed
    the pipeline's refusal). Its 12 nearest neighbours spread in two directions within a dense
    noisy outline's band too: the app opened such a boundary (24,000 points, noise 0.1% of the
    length) as a scan and extracted a leaf from it. The share asked is SCAN_SHARE, above a
    sparse noisy outline's: such a file stays a boundary, which the pipeline refuses by name."""
    # heavy (scipy's k-d tree): not for the command line's parser, which reads OUTLINE_POINTS
    from leafstudio.core.prepare.cover import COVER_SPREAD
    from leafstudio.core.prepare.plausibility import boundary_cover

    if leaf.veins or len(leaf.boundary) < MIN_SCAN_POINTS:
        return False
    spread, share = boundary_cover(leaf.boundary)
    return spread > COVER_SPREAD or share > SCAN_SHARE
