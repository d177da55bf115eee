"""One input's job, in a worker process: read, (extract,) reconstruct, measure, write its mesh,
and return its table row; a bad input becomes a failed row, never an exception."""

from __future__ import annotations

import signal
import time
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from leafstudio import workflows
from leafstudio.assets.export import save_mesh
from leafstudio.assets.placement import result_placement, size_note
from leafstudio.batch.plan import Job, file_hash
from leafstudio.batch.settings import CURVATURE_COLUMNS, SHAPE_COLUMNS, TRAIT_POWERS, columns
from leafstudio.errors import LeafError, error_line
from leafstudio.sources.files import load_leaf

_PINNED = False


def pin_threads() -> None:
    """One BLAS thread and one numba thread for the rest of this process (a batch worker: the
    workers run side by side); done once per process."""
    global _PINNED
    if _PINNED:
        return
    import numba
    from threadpoolctl import threadpool_limits

    numba.set_num_threads(1)  # for any parallel kernel (leafstudio's are serial today)
    threadpool_limits(1)  # after numba: its OpenMP layer too
    _PINNED = True


@contextmanager
def _one_thread() -> Iterator[None]:
    """One BLAS and one numba thread while a job runs in a process that is not a pinned worker
    (a Dask worker, or a caller's own process), given back after: a job run in the caller's
    process must not change its threads (a later fit there would differ in its last digits)."""
    if _PINNED:
        yield
        return
    import numba
    from threadpoolctl import threadpool_limits

    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        with threadpool_limits(1):
            yield
    finally:
        numba.set_num_threads(threads)


def worker_start() -> None:
    """Pool initializer: pin threads, then import the pipeline once per worker. Ctrl-C reaches
    the whole process group: the parent stops the batch (and lets running jobs finish)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    pin_threads()
    import leafstudio.core.pipeline  # noqa: F401


def _number(x: Any) -> float | None:
    return None if x is None else float(x)


def _traits(result: Any) -> dict[str, Any]:
    """The shape and curvature columns of a Result, in the leaf's own units: its metrics, as
    `measure` prints them (measured at unit size: a leaf at 1e-90 measured in its own units had
    facet areas that underflowed to 0, "Weights sum to zero"). LeafError past about 1e150."""
    metrics = result.metrics
    shape, curvature = metrics["leaf"], metrics["curvature"]
    row = {name: _number(shape[name]) for name in SHAPE_COLUMNS}
    for name in CURVATURE_COLUMNS:
        array, stat = name.rsplit("_", 1)
        row[name] = _number(curvature[array][stat]) if array in curvature else None
    return row


def _scaled(row: dict[str, Any], scale: float) -> dict[str, Any]:
    """The row's lengths, areas and curvatures in other units, `scale` of them a leaf unit
    (millimetres, when --length gives the real length)."""
    return {
        k: None if v is None else v * scale ** TRAIT_POWERS[k]
        for k, v in row.items()
        if k in TRAIT_POWERS
    }


def _reconstruct(job: Job) -> dict[str, Any]:
    """Read, (extract,) reconstruct, measure and write one input; raises on bad input. It opens,
    fails and warns as `leafstudio extract` (for a scan) then `reconstruct` would: both go
    through workflows."""
    settings = job.settings
    try:
        if settings.scans:
            opened = workflows.open_scan(job.path, force=settings.force)
        else:
            opened = workflows.Opened(job.path, "leaf", load_leaf(job.path))
        done = workflows.reconstruct(opened, settings.params)
        result = done.result
        row: dict[str, Any] = {"k": result.fitted_k, "grid": settings.params.grid}
        row.update(_traits(result))  # LeafError: a leaf at 1e160 is too large to measure
    except LeafError as exc:
        raise LeafError(exc.problem, job.input) from None
    notes = list(done.warnings)
    if done.scan_fit is not None:
        found = done.scan_fit
        row.update(
            scan_points=found["points"],
            scan_mean=_number(found.get("mean")),  # in the scan's (the leaf's) units
            scan_p95=_number(found.get("p95")),
            scan_beyond_1pct=_number(found.get("beyond_1pct")),
            scan_beyond_2pct=_number(found.get("beyond_2pct")),
            scan_folded=_number(found.get("folded")),  # the mesh's edges folded back
            scan_crumpled=_number(found.get("crumpled")),  # its area bent to a radius < L/100
        )
    length, placement = settings.length, result_placement(result)
    if length is not None:
        row.update(_scaled(row, placement.scale(length, ".ply")))  # Z-up formats: mm a unit
    workflows.check_finite(row, job.input)
    if job.mesh:
        # the bare mesh: normals, UVs and the point arrays, without the texture image and the
        # closed-form normals a Result gets (a second per leaf; `reconstruct` writes those)
        mesh = Path(job.out_dir) / job.mesh
        save_mesh(result.triangle_mesh, mesh, length=length, placement=placement)
        row["mesh"] = job.mesh
        row["mesh_sha256"] = file_hash(Path(job.out_dir) / job.mesh)  # --resume checks it
        if length is None and (note := size_note(placement.length, mesh.suffix)):
            notes.append(note)  # a millimetre leaf that glTF or USD reads as metres
    row["warnings"] = "; ".join(notes) or None
    return row


def _as_listed(exc: Exception, job: Job) -> Exception:
    """The error naming the input as the user listed it (the worker reads its absolute path)."""
    if isinstance(exc, LeafError) and exc.source == job.path:
        return LeafError(exc.problem, job.input)
    if isinstance(exc, FileNotFoundError):
        return LeafError("no such file", job.input)
    if isinstance(exc, IsADirectoryError):
        return LeafError("is a folder, not a file", job.input)
    if isinstance(exc, OSError) and exc.filename == job.path:
        return LeafError(f"cannot be read ({exc.strerror or exc})", job.input)
    return exc


def run_job(job: Job) -> dict[str, Any]:
    """One input's table row: `ok` with its traits, or `failed` with the one-line message that
    `leafstudio reconstruct` would print. Never raises for a bad input (the batch goes on)."""
    with _one_thread():
        return _run(job)


def _run(job: Job) -> dict[str, Any]:
    """run_job's work, with the threads already set."""
    start = time.perf_counter()
    row: dict[str, Any] = dict.fromkeys(columns(job.settings.scans))
    row.update(input=job.input, settings=job.settings.key())
    try:
        row["sha256"] = file_hash(job.path)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # library chatter; the run's notes are in the row
            row.update(_reconstruct(job), status="ok")
    except Exception as exc:
        row.update({c: None for c in row if c not in ("input", "settings", "sha256")})
        row.update(status="failed", error=error_line(_as_listed(exc, job)))
    row["seconds"] = round(time.perf_counter() - start, 4)
    return row


def run_failed(job: Job, exc: BaseException) -> dict[str, Any]:
    """A failed row for a job that could not be run at all."""
    row: dict[str, Any] = dict.fromkeys(columns(job.settings.scans))
    row.update(input=job.input, settings=job.settings.key(), status="failed", error=error_line(exc))
    return row
