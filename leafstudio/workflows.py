"""The one path from a file to a leaf, and from a leaf to a checked result.

The command line (`reconstruct`, `extract`), `batch` and the app all open files here, so they
accept and refuse the same files with the same messages (docs/architecture.md, "Data flow"):

- `open_file`: whatever a user may open (a photo, a project, a point list, a scan), decided in
  one order: photo by suffix, project by suffix, then a point list, read as a scan when only a
  scan reader takes it or when its points cover a surface instead of tracing an outline.
- `open_scan`: a scan read, checked (`check_scan`: the same refusal everywhere) and extracted.
- `reconstruct`: the pipeline run on an opened leaf, with every warning the input and the
  result give, and the distances from a scan's blade to the surface.

Examples
--------
>>> from leafstudio import workflows
>>> from leafstudio.sources.demos import demo
>>> done = workflows.reconstruct(workflows.Opened("nested", "leaf", demo("nested")),
...                              Params(k=3, grid=48))
>>> done.result.chosen_k
3
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Literal

import numpy as np

from leafstudio._shared import progress
from leafstudio._shared.blas import one_blas_thread
from leafstudio._shared.inputs import check_file_kind
from leafstudio.analysis.fidelity import scan_distances, scan_warnings, with_folds
from leafstudio.core import evaluate
from leafstudio.core.bend import flat_leaf
from leafstudio.core.pipeline import Pipeline, Result
from leafstudio.core.plane import fit_frame
from leafstudio.core.prepare.outline import ordered_crossing
from leafstudio.core.prepare.plausibility import leaf_warnings
from leafstudio.core.prepare.units import Units
from leafstudio.core.unfolded import unfolded, unposed_hint
from leafstudio.errors import LeafError
from leafstudio.model import Leaf, Params
from leafstudio.sources import extract
from leafstudio.sources.extract import (
    FINDING,
    OUTLINE_POINTS,
    Extraction,
    check_scan,
    extract_leaf,
    unit_scan,
)
from leafstudio.sources.files import load_leaf, load_project
from leafstudio.sources.photo import PhotoLeaf, is_photo, read_photo_leaf
from leafstudio.sources.scan import is_scan_file, looks_like_scan, read_scan_returns

Kind = Literal["leaf", "project", "scan", "photo"]


@dataclass(frozen=True)
class Opened:
    """A file read and checked: its leaf, and what else the file held.

    Attributes
    ----------
    path : str
        The file as the user named it (errors name it so).
    kind : {"leaf", "project", "scan", "photo"}
        What the file turned out to be.
    leaf : Leaf
        Boundary and veins: read, extracted from the scan, or found in the photo.
    params : Params or None
        A project's saved parameters.
    sketch : dict or None
        A project's saved sketch (the app's control points), as stored.
    scan : (n, 3) float array or None
        A scan's points.
    extraction : Extraction or None
        What `extract_leaf` found in the scan (blade, petiole, length).
    photo : PhotoLeaf or None
        What was found in a photo (its outline's map to the photo's pixels).
    notes : tuple of str
        Warnings about the input (`check_scan` with `force`).

    Examples
    --------
    >>> from leafstudio.workflows import Opened
    >>> from leafstudio.sources.demos import demo
    >>> Opened("nested", "leaf", demo("nested")).kind
    'leaf'
    """

    path: str
    kind: Kind
    leaf: Leaf
    params: Params | None = None
    sketch: dict[str, Any] | None = None
    scan: np.ndarray | None = None
    extraction: Extraction | None = None
    photo: PhotoLeaf | None = None
    notes: tuple[str, ...] = ()


def open_scan(
    path: str, *, base_end: str = "auto", points: int = OUTLINE_POINTS, force: bool = False
) -> Opened:
    """Read a scan, check that it is plausibly one leaf, and extract its boundary and veins.

    Parameters
    ----------
    path : str
        A scan file (.ply, .pcd, .xyz, .csv, .txt; x, y, z read).
    base_end : str, default: "auto"
        Which end of the scan is the leaf's base (`extract --base-end`).
    points : int, default: 200
        Boundary points to take.
    force : bool, default: False
        Turn the plausibility refusals into warnings (`Opened.notes`).

    Returns
    -------
    Opened
        kind "scan": the extracted leaf (`points` boundary points, the veins lifted onto the
        scan), the scan's (n, 3) points and the extraction (which points are the blade).

    Raises
    ------
    LeafError
        Naming `path`: unreadable, not leaf-like, or no blade found.

    Examples
    --------
    A scan of an elliptic blade with a raised midrib, as a scanner's points:

    >>> import tempfile
    >>> from pathlib import Path
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> xy = rng.uniform(-1, 1, (6000, 2)) * [1, 0.4]
    >>> xy = xy[xy[:, 0] ** 2 + (xy[:, 1] / 0.4) ** 2 < 1]
    >>> scan = np.column_stack([xy, 0.05 * np.exp(-((xy[:, 1] / 0.05) ** 2))])
    >>> path = Path(tempfile.mkdtemp()) / "scan.xyz"
    >>> np.savetxt(path, scan)
    >>> opened = open_scan(path)
    >>> opened.kind, opened.leaf.boundary.shape, opened.scan.shape
    ('scan', (200, 3), (4710, 3))
    """
    scan, returns = read_scan_returns(path)
    return _scan_opened(str(path), scan, base_end, points, force, returns)


def _scan_with_missed_returns(path: str, force: bool) -> Opened | None:
    """A point list or PLY that load_leaf refused, opened as a scan when it holds NaN or
    infinite points and its finite ones look like a scan (open_scan's note says how many were
    left out); None otherwise, for the leaf file's own refusal (review37: File > Open refused
    an x y z scan with one missed return by its line, the scan reader never asked)."""
    try:
        scan, returns = read_scan_returns(path)
    except LeafError:
        return None
    if not returns or not looks_like_scan(Leaf(boundary=scan, veins=[])):
        return None
    return _scan_opened(path, scan, force=force, read=returns)


def _scan_opened(
    path: str, scan: np.ndarray, base_end: str = "auto", points: int = OUTLINE_POINTS,
    force: bool = False, read: tuple[str, ...] = (),
) -> Opened:  # fmt: skip
    """A scan's points read from `path`, checked and extracted (open_scan); `read`: the notes of
    reading it (read_scan_returns), said before the check's."""
    progress.report(0.0, FINDING)
    try:
        with one_blas_thread():  # small solves: a second thread only waits (_shared/blas.py)
            once = _once(scan)
            if len(once) < extract.MIN_POINTS <= len(scan):  # said as what the file holds
                raise LeafError(
                    f"too few distinct points for a leaf scan: {len(once)} of its {len(scan)} "
                    f"are different (need {extract.MIN_POINTS})"
                )
            scan = once
            at_unit = unit_scan(scan)  # thinned once, for the check and the extraction
            notes = check_scan(scan, force=force, at_unit=at_unit)
            with progress.share(0.1, 1.0):  # check_scan: a tenth of a big scan's time
                found = extract_leaf(scan, base_end, points, at_unit=at_unit)
    except LeafError as exc:
        raise LeafError(exc.problem, path) from None
    notes = (*read, *notes)
    return Opened(path, "scan", found.leaf, scan=scan, extraction=found, notes=notes)


def _once(scan: np.ndarray) -> np.ndarray:
    """The (n, 3) scan with its exact repeats dropped (the first of each kept, in order), when
    it is used whole: a scan of up to extract.BUDGET points is checked and extracted point by
    point, and a point written three times (two scanner passes merged) linked with nothing in the
    check's clusters (the median gap to the nearest other point was 0) nor in the blade's. Exact
    repeats only: points merged within a share of the scan's size merged a whole leaf into two
    points when one stray return lay 1e6 of its lengths off. A larger scan is thinned to its
    cubes' centroids (scan_thinning.voxel_thinning), where repeats merge."""
    scan = np.asarray(scan, dtype=float)
    if len(scan) > extract.BUDGET or not np.isfinite(scan).all():  # unit_scan names a NaN
        return scan
    first = np.unique(scan, axis=0, return_index=True)[1]
    return scan if len(first) == len(scan) else scan[np.sort(first)]


def open_file(
    path: str,
    *,
    force: bool = False,
    length: float | None = None,
    pixel_size: float | None = None,
    base_end: str = "auto",
) -> Opened:
    """Open any file a user may give: a photo, a project, a point list or PLY leaf, or a scan.

    A point list that only a scan reader takes (more columns than x, y, z and a label, or a
    .pcd), or whose points cover a surface instead of tracing an outline, opens as a scan.

    Parameters
    ----------
    path : str or path-like
        A photo (.png, .jpg, ...), a project (.leaf.json), a leaf file (.csv, .txt, .xyz,
        .ply) or a scan (.ply, .pcd, .xyz, .csv, .txt).
    force : bool, default: False
        For a scan: turn the plausibility refusals into warnings (see `open_scan`).
    length : float, optional
        For a photo: the leaf's length base to apex, in the units the leaf gets (default 1;
        `leafstudio photo --length`).
    pixel_size : float, optional
        For a photo without `length`: one pixel's length in the leaf's units (a ruler's);
        without either, the photo's own DPI when it records one (sources/photo_scale.py).
    base_end : {"auto", "left", "right", "top", "bottom"}, default: "auto"
        For a photo: the end of the leaf that is its base, as the photo shows it (`leafstudio
        photo --base-end`); "auto" finds it (petiole, notch, veins, else the wider end).

    Returns
    -------
    Opened
        The leaf, what the file turned out to be (`kind`) and what else it held.

    Raises
    ------
    LeafError
        Naming `path`: unreadable, malformed, a boundary that crosses itself, a scan that is not
        plausibly one leaf.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> from leafstudio.sources.demos import demo
    >>> from leafstudio.sources.files import save_leaf
    >>> folder = Path(tempfile.mkdtemp())
    >>> save_leaf(demo("nested"), folder / "leaf.csv")
    >>> opened = open_file(folder / "leaf.csv")
    >>> opened.kind, len(opened.leaf.veins)
    ('leaf', 7)
    >>> save_leaf(demo("nested"), folder / "leaf.leaf.json", Params(k=4))
    >>> open_file(folder / "leaf.leaf.json").params.k
    4
    """
    path = str(path)
    check_file_kind(path)  # a pipe named leaf.csv is not opened (its sniffing would block)
    if is_photo(path):
        found = read_photo_leaf(path, length=length, pixel_size=pixel_size, base_end=base_end)
        grown = found.veins_from == "grown"
        notes = ("the photo shows no midrib: its veins were grown",) if grown else ()
        return Opened(path, "photo", found.leaf, photo=found, notes=notes)
    if path.lower().endswith(".json"):
        leaf, params, sketch = load_project(path)
        opened = Opened(path, "project", leaf, params=params, sketch=sketch or None)
    else:
        try:
            leaf = load_leaf(path)
        except LeafError:
            if is_scan_file(path):
                return open_scan(path, force=force)
            if (scan := _scan_with_missed_returns(path, force)) is not None:
                return scan
            raise
        if looks_like_scan(leaf):  # its points as read (unlabelled): not read a second time
            return _scan_opened(path, leaf.boundary, force=force)
        opened = Opened(path, "leaf", leaf)
    if opened.sketch is None:  # a drawn project's leaf is its sketch's, as drawn
        # curves in 3D without a bend are unfolded here, once, so that the leaf the app and the
        # commands hold is the one reconstructed (core/unfold.py; the pipeline's own call then
        # finds the bend given)
        leaf = unfolded(leaf)
        opened = replace(opened, leaf=leaf)
        crossing = boundary_crossing(flat_leaf(leaf))
        if crossing is not None:
            x, y, z = crossing
            raise LeafError(
                f"the boundary crosses itself near ({x:.4g}, {y:.4g}, {z:.4g}); its points must "
                f"go once around the leaf{unposed_hint(leaf)}",
                path,
            )
    return opened


def boundary_crossing(leaf: Leaf) -> np.ndarray | None:
    """Where a leaf's boundary crosses itself, as a (3,) world point, when its points trace the
    outline in order (an unordered cloud is ordered by the pipeline, not read as given).

    Parameters
    ----------
    leaf : Leaf
        Its (n, 3) boundary is read in the given order.

    Returns
    -------
    (3,) float array or None
        A crossing point, or None when the boundary does not cross itself or is not ordered.

    Examples
    --------
    >>> from leafstudio.model import Leaf
    >>> bow_tie = Leaf([[0, 0, 0], [1, 1, 0], [1, 0, 0], [0, 1, 0], [0.5, -0.2, 0]])
    >>> boundary_crossing(bow_tie).tolist()
    [0.5, 0.5, 0.0]
    """
    if len(leaf.boundary) < 4:
        return None
    # at unit size, as the pipeline runs: in the world's units a leaf 1e9 away was found to
    # cross itself, and one at 1e300 overflowed ("data must be finite")
    units = Units.of(leaf)
    unit = units.leaf(leaf)
    points = unit.boundary
    try:
        frame = fit_frame(points, unit.vein_points)
    except LeafError:
        return None
    found = ordered_crossing(frame.to_plane(points)[0])
    if found is None:
        return None
    return units.to_world(frame.to_world(found[None], np.zeros(1)))[0]


@dataclass(frozen=True)
class Reconstruction:
    """A result with every warning its input and its run gave, and its fit to a scan.

    Attributes
    ----------
    result : Result
        The pipeline's result.
    warnings : list of str
        The input's notes, the leaf's plausibility warnings, the run's own, in that order.
    scan_fit : dict or None
        For a scan, the distances from its blade points to the surface: points, mean, median,
        p95, max and the shares beyond 1% and 2% of the leaf length (`length`), and the share
        of the mesh's edges folded back ("folded": analysis.fidelity.folded_share); a mean
        beyond FAR_FROM_SCAN of the length, or folds at more than FOLDED of the edges, add a
        warning (fidelity.scan_warnings).
    """

    result: Result
    warnings: list[str] = field(default_factory=list)
    scan_fit: dict[str, Any] | None = None


def reconstruct(opened: Opened, params: Params, pipeline: Pipeline | None = None) -> Reconstruction:
    """Run the pipeline on an opened leaf (through `pipeline`, to reuse its stage cache).

    Parameters
    ----------
    opened : Opened
        From `open_file` or `open_scan` (or built from a Leaf).
    params : Params
        The reconstruction's settings.
    pipeline : Pipeline, optional
        A pipeline of `opened.leaf` whose cached stages to reuse; default a fresh one.

    Returns
    -------
    Reconstruction
        The result; the input's notes, the leaf's plausibility warnings and the result's own
        warnings, in that order; for a scan, the distances from its blade points to the surface
        (`analysis.fidelity.scan_distances`).

    Raises
    ------
    LeafError
        Naming the opened file.

    Examples
    --------
    >>> from leafstudio.sources.demos import demo
    >>> done = reconstruct(Opened("nested", "leaf", demo("nested")), Params(k=3, grid=48))
    >>> done.result.chosen_k, done.warnings, done.scan_fit
    (3, [], None)
    """
    try:
        result = (pipeline or Pipeline(opened.leaf)).run(params)
    except LeafError as exc:
        raise LeafError(exc.problem, opened.path) from None
    warnings = [*opened.notes, *leaf_warnings(opened.leaf), *result.warnings]
    fit = None
    if opened.scan is not None and opened.extraction is not None:
        blade = opened.scan[opened.extraction.blade]
        length = result.blade_length
        fit = with_folds(scan_distances(result.triangle_mesh, blade, length), result.triangle_mesh)
        warnings += scan_warnings(fit)
    return Reconstruction(result, warnings, fit)


def check_finite(figures: dict, source: str) -> None:
    """evaluate.check_finite, its LeafError naming `source`."""
    try:
        evaluate.check_finite(figures)
    except LeafError as exc:
        raise LeafError(exc.problem, source) from None
