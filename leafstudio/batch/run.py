"""A batch run: `Batch` plans when made and runs when iterated, on one of the executors, writing
the trait table as rows arrive; `batch()` is its public entry point (`ls.batch`)."""

from __future__ import annotations

import os
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from leafstudio._shared.safewrite import stale_part
from leafstudio.assets.placement import parse_length
from leafstudio.batch.executors import DaskCluster, LocalPool, check_scheduler
from leafstudio.batch.plan import Job, plan, resumable
from leafstudio.batch.settings import DEFAULT_TABLE, FORMATS, Settings
from leafstudio.batch.table import TraitTable
from leafstudio.batch.worker import run_failed
from leafstudio.errors import LeafError
from leafstudio.model import Params

IN_FLIGHT_PER_WORKER = 2  # jobs queued per worker: keeps workers busy, memory bounded


def remove_temporaries(
    folder: Path, suffixes: Sequence[str], recursive: bool = True, stem: str = ""
) -> int:
    """Delete the temporary files that atomic writes killed midway left in `folder` (and below,
    if `recursive`): those of no live process, for targets ending with one of `suffixes` (and
    named `stem`..., if given). Returns how many. (safewrite.remove_stale does this for one
    target; a batch sweeps its whole output folder once.)"""
    removed = 0
    if not folder.is_dir():
        return 0
    walk = os.walk(folder) if recursive else [(str(folder), [], os.listdir(folder))]
    for where, _, names in walk:
        for name in names:
            if not name.startswith(f".{stem}") or not name.lower().endswith(tuple(suffixes)):
                continue
            if stale_part(name) is not None:
                Path(where, name).unlink(missing_ok=True)
                removed += 1
    return removed


class Batch:
    """A batch run: planned when made (bad arguments raise LeafError at once), run by iterating,
    which yields one row (a dict of the table's columns) per input as it completes; rows resumed
    from an earlier run come first. When every input failed, iterating ends in a LeafError once
    every row is yielded and written (a script's loop over the rows then exits non-zero).

    Attributes
    ----------
    jobs : list of Job
        Every input, sorted.
    total, resumed, failed : int
        Inputs, rows kept from an earlier run, failed rows so far.
    table : TraitTable
    """

    def __init__(
        self,
        inputs: Sequence[str | os.PathLike],
        params: Params | None = None,
        out_dir: str | os.PathLike = "leafstudio-batch",
        *,
        scans: bool = False,
        traits: str | os.PathLike | None = None,
        format: str = "ply",
        jobs: int | None = None,
        scheduler: str | None = None,
        resume: bool = False,
        fail_fast: bool = False,
        force: bool = False,
        length: str | float | None = None,
    ) -> None:
        if format not in FORMATS:
            raise LeafError(f"unknown mesh format {format!r}; use one of {', '.join(FORMATS)}")
        if jobs is not None and jobs < 1:
            raise LeafError(f"--jobs must be 1 or more, got {jobs}")
        if scheduler is not None:
            check_scheduler(scheduler)
        self.out_dir = Path(out_dir)
        if self.out_dir.exists() and not self.out_dir.is_dir():
            raise LeafError("is a file, not a folder", str(self.out_dir))
        metres = None if length is None else parse_length(length)
        self.settings = Settings(params or Params(), scans, format, force, metres)
        self.table = TraitTable(traits if traits else self.out_dir / DEFAULT_TABLE, scans)
        if self.table.is_foreign():  # never write the table over an input or a user's file
            raise LeafError(
                "exists and is not a trait table, so it would be replaced; choose another "
                "--traits path",
                str(self.table.path),
            )
        self.jobs = plan(inputs, self.out_dir, self.settings, exclude=[self.table.path])
        self.total = len(self.jobs)
        self.workers = jobs or os.cpu_count() or 1
        self.scheduler = scheduler
        self.resume = resume
        self.fail_fast = fail_fast
        self.resumed = 0
        self.ok = 0
        self.failed = 0
        self.stopped = False  # by fail_fast

    def _kept(self) -> dict[str, dict[str, Any]]:
        """Rows of an earlier run that stand (plan.resumable); none unless resuming."""
        if not self.resume:
            return {}
        return resumable(self.jobs, self.table.rows(), self.settings, self.out_dir)

    def __iter__(self) -> Iterator[dict[str, Any]]:
        yield from self.run()
        if self.failed and self.failed == self.total:
            raise LeafError(
                f"every input failed ({self.total}); the table's error column says why",
                str(self.table.path),
            )

    def run(self) -> Iterator[dict[str, Any]]:
        """The rows, as iterating yields them, without the error when every input failed (the
        command line says so in its summary and exit code)."""
        # what a killed run's atomic writes left: meshes under out_dir, the table beside it
        if self.settings.format != "none":
            companions = (".mtl", ".png") if self.settings.format == "obj" else ()
            remove_temporaries(self.out_dir, (f".{self.settings.format}", *companions))
        for path in {self.table.path, self.table.journal}:
            remove_temporaries(path.parent, (path.suffix.lower(),), False, path.stem)
        kept = self._kept()
        self.resumed = len(kept)
        executor = None
        try:
            if self.resumed < self.total:  # first: a scheduler out of reach leaves no table
                executor = (
                    DaskCluster(self.scheduler, self.workers)
                    if self.scheduler
                    else LocalPool(self.workers)
                )
            self.table.start(kept[j.input] for j in self.jobs if j.input in kept)
            for job in self.jobs:
                if job.input in kept:
                    yield kept[job.input]
            if executor is not None:
                todo = (job for job in self.jobs if job.input not in kept)
                yield from self._stream(executor, todo)
        finally:
            if executor is not None:
                executor.close()
            self.table.close()

    def _stream(self, executor: Any, todo: Iterator[Job]) -> Iterator[dict[str, Any]]:
        """Keep a few jobs per worker in flight; write and yield each row as it arrives."""
        limit = IN_FLIGHT_PER_WORKER * executor.workers
        pending: dict[Any, Job] = {}
        retried: set[str] = set()

        def refill() -> None:
            while len(pending) < limit and not self.stopped:
                job = next(todo, None)
                if job is None:
                    return
                pending[executor.submit(job)] = job

        refill()
        while pending:
            done, _ = executor.wait(set(pending))
            for future in sorted(done, key=lambda f: pending[f].input):
                job = pending.pop(future)
                row = executor.outcome(future, job)
                if row is None:  # its worker died: run it once more, then a failed row
                    if job.input not in retried:
                        retried.add(job.input)
                        pending[executor.submit(job)] = job
                        continue
                    row = run_failed(job, RuntimeError("the worker process died"))
                self.table.add(row)
                if row["status"] == "ok":
                    self.ok += 1
                else:
                    self.failed += 1
                    if self.fail_fast:
                        self.stopped = True
                yield row
            refill()


def batch(
    inputs: Sequence[str | os.PathLike] | str | os.PathLike,
    params: Params | None = None,
    out_dir: str | os.PathLike = "leafstudio-batch",
    **options: Any,
) -> Batch:
    """Reconstruct many leaves (or scans) and write their meshes and a trait table.

    Parameters
    ----------
    inputs : path, pattern, or sequence of them
        Leaf files (or scans, with scans=True), folders searched recursively, glob patterns.
    params : Params, optional
        The same reconstruction settings for every input (default Params()).
    out_dir : path, default: "leafstudio-batch"
        Where the meshes go, keeping the inputs' folder structure.
    **options
        scans (bool), traits (table path: .csv, .json, .parquet; default OUT_DIR/traits.csv),
        format ("ply", "glb", "obj", "vtp", "none"), jobs (worker processes, default the
        cores), scheduler (a Dask scheduler address, or "local"), resume, fail_fast, force
        (scans that do not look like one leaf are reconstructed anyway, with warnings), length
        (each leaf's real length, '8cm': meshes at real size, see save_mesh, and the traits
        in millimetres: mm, mm², 1/mm, 1/mm²).

    Returns
    -------
    Batch
        Iterate over it to run the batch: one row (dict) per input as it completes, with the
        trait table's columns (input, status, error, mesh, k, grid, area, ...).

    Raises
    ------
    LeafError
        For a bad option (an unknown format or table type, a table that would overwrite an
        input, a --scheduler that cannot be used); a bad input is a "failed" row instead, and
        the others go on. Iterating raises it at the end, once every row is written, when every
        input failed.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> import leafstudio as ls
    >>> folder = Path(tempfile.mkdtemp())
    >>> for name in ("nested", "parallel"):
    ...     ls.save_leaf(ls.demo(name), folder / "leaves" / f"{name}.csv")
    >>> rows = ls.batch([folder / "leaves"], ls.Params(k=2, grid=32), folder / "out", jobs=1)
    >>> sorted((row["mesh"], row["status"]) for row in rows)
    [('nested.ply', 'ok'), ('parallel.ply', 'ok')]
    >>> sorted(p.name for p in (folder / "out").iterdir())
    ['nested.ply', 'parallel.ply', 'traits.csv']
    """
    if isinstance(inputs, str | os.PathLike):
        inputs = [inputs]
    return Batch(list(inputs), params, out_dir, **options)
