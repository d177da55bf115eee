"""A batch's plan: the input files named by files, folders and patterns, one job for each (where
its mesh goes), and which rows of an earlier run a resumed run keeps."""

from __future__ import annotations

import glob
import hashlib
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from leafstudio._shared.inputs import check_input_file
from leafstudio.batch.settings import Settings, columns
from leafstudio.errors import LeafError
from leafstudio.sources.files import LEAF_SUFFIXES
from leafstudio.sources.scan import SCAN_SUFFIXES


@dataclass(frozen=True)
class Job:
    """One input: where to read it, where its mesh goes, and how to run it."""

    input: str  # the path as listed (the table's key)
    path: str  # absolute path the worker reads
    mesh: str  # mesh path relative to the output folder ("" for format none)
    out_dir: str  # absolute output folder
    settings: Settings


def _input_suffixes(scans: bool) -> tuple[str, ...]:
    if scans:
        return SCAN_SUFFIXES
    return LEAF_SUFFIXES


def _inside(path: Path, folder: Path) -> bool:
    return path == folder or folder in path.parents


def find_inputs(
    inputs: Sequence[str | os.PathLike], scans: bool = False, exclude: Sequence[Path] = ()
) -> list[tuple[str, Path]]:
    """The input files named by files, folders (recursive) and glob patterns, sorted by path.

    Folders contribute their non-hidden files with a leaf (or, for scans, a scan) suffix; a file
    named outright is taken whatever its suffix (so a bad one becomes a failed row), as is every
    file a pattern matches. Files under `exclude` (the output folder) are left out.

    Returns
    -------
    list of (str, Path)
        The path as the user would write it (the table's key), and its root: the folder its
        structure is kept relative to (the folder given, a pattern's fixed part, a file's folder).
    """
    suffixes = _input_suffixes(scans)
    excluded = [Path(e).resolve() for e in exclude]
    found: dict[str, Path] = {}
    for item in inputs:
        text = os.fspath(item)
        if glob.has_magic(text):
            fixed = Path(text.split("*")[0].split("?")[0].split("[")[0])
            root = fixed if text.endswith(os.sep) or fixed.is_dir() else fixed.parent
            matches = [Path(m) for m in glob.iglob(text, recursive=True)]
            candidates = [(m, root) for m in matches if m.is_file()]
        elif Path(text).is_dir():
            root = Path(text)
            candidates = []
            for folder, dirs, names in os.walk(text):
                # hidden folders and the output folder are not searched
                dirs[:] = sorted(
                    d for d in dirs
                    if not d.startswith(".")
                    and not any(_inside(Path(folder, d).resolve(), e) for e in excluded)
                )  # fmt: skip
                candidates += [
                    (Path(folder) / name, root)
                    for name in names
                    if name.lower().endswith(suffixes) and not name.startswith(".")
                ]
        else:
            candidates = [(Path(text), Path(text).parent)]
        for path, root in candidates:
            if any(_inside(path.resolve(), e) for e in excluded):
                continue
            found.setdefault(os.path.normpath(path), root)
    return sorted(found.items())


def _mesh_name(relative: Path, fmt: str) -> str:
    name = relative.name
    stem = name[: -len(".leaf.json")] if name.lower().endswith(".leaf.json") else relative.stem
    return (relative.parent / f"{stem}.{fmt}").as_posix()


def plan(
    inputs: Sequence[str | os.PathLike],
    out_dir: str | os.PathLike,
    settings: Settings,
    exclude: Sequence[Path] = (),
) -> list[Job]:
    """The jobs of a batch, sorted by input path.

    Meshes keep the inputs' folder structure below the common folder of their roots.

    Raises
    ------
    LeafError
        If no input is found, two inputs would write the same mesh, or an input's name holds a
        line break.
    """
    out = Path(out_dir).resolve()
    found = find_inputs(inputs, settings.scans, [out, *exclude])
    if not found:
        for item in inputs:  # a file named outright in the output folder (its own meshes?)
            if Path(item).is_file() and _inside(Path(item).resolve(), out):
                raise LeafError(f"lies in the output folder {os.fspath(out_dir)}, whose files "
                                "batch leaves out; choose another -o", os.fspath(item))  # fmt: skip
        raise LeafError(f"no input files found in {' '.join(map(os.fspath, inputs))}")
    roots = {os.path.abspath(root) for _, root in found}  # links are not followed: a linked
    common = Path(os.path.commonpath(sorted(roots)))  # file stays where it was listed
    jobs, owners = [], {}
    for shown, _ in found:
        if len(str(shown).splitlines()) > 1:  # the table's cells are one line: it would name
            raise LeafError(  # a file that does not exist (issue 24, finding 15)
                "a file name with a line break cannot be a row of the trait table; rename it",
                repr(os.fspath(shown)),
            )
        absolute = Path(os.path.abspath(shown))
        mesh = ""
        if settings.format != "none":
            mesh = _mesh_name(absolute.relative_to(common), settings.format)
            if mesh in owners:
                raise LeafError(f"{owners[mesh]} and {shown} would both write {mesh}; rename one")
            owners[mesh] = shown
        jobs.append(Job(shown, str(absolute), mesh, str(out), settings))
    return jobs


def file_hash(path: str | os.PathLike) -> str:
    """sha256 of a file's content (hex); LeafError for anything but a regular file (a pipe
    would block for ever, /dev/zero never end), checked before it is opened."""
    check_input_file(path, limit=None)
    with open(path, "rb") as handle:
        return hashlib.file_digest(handle, "sha256").hexdigest()


def resumable(
    jobs: Sequence[Job], rows: Iterable[dict[str, Any]], settings: Settings, out_dir: Path
) -> dict[str, dict[str, Any]]:
    """The rows of an earlier run that stand, by input: ok, made with the same settings from the
    same content, and their mesh as written (not lost, cut short or edited), in a table with
    every column this one has (one written before scan_crumpled was kept that column blank)."""
    key, needed = settings.key(), set(columns(settings.scans))
    wanted = {job.input: job for job in jobs}
    kept: dict[str, dict[str, Any]] = {}
    for row in rows:
        job = wanted.get(str(row.get("input")))
        if job is None or row.get("status") != "ok" or row.get("settings") != key:
            continue
        if not needed <= row.keys():  # an older table's: run again, as a clean run would
            continue
        try:  # the input unchanged, and its mesh as written (not lost, cut short or edited)
            same = row.get("sha256") == file_hash(job.path) and (
                not job.mesh or row.get("mesh_sha256") == file_hash(out_dir / job.mesh)
            )
        except (OSError, LeafError):  # gone, unreadable, or no longer a regular file
            same = False
        if same:
            kept[job.input] = row
    return kept
