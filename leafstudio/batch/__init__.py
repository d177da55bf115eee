"""Many leaves at once: one mesh per input and a trait table, on a pool of local worker processes
or on a Dask distributed cluster (`leafstudio batch`, `ls.batch`).

- Inputs are files, folders (searched recursively) or glob patterns. Only their paths are listed
  up front; the workers read the files, and at most a few jobs per worker are in flight, so memory
  stays bounded whatever the number of inputs.
- Each input's mesh is written by the worker, atomically (io.save_mesh), at the input's path
  relative to the inputs' common folder, under the output folder.
- The trait table gets one row per input as results arrive, flushed at once; at the end it is
  rewritten sorted by input path (atomically). A row records the input's content hash and a key of
  the settings, so `resume` keeps exactly the rows (and meshes) that a new run would make again.
- A failing input becomes a `failed` row with the one-line message `leafstudio reconstruct`
  would print; the others go on.
- Every job runs in a worker process with BLAS (and numba) threads pinned to 1, so 1 or n
  workers, and the order results arrive in, give the same meshes and traits.
"""

from __future__ import annotations

import csv
import glob
import hashlib
import io
import json
import os
import signal
import threading
import time
import warnings
from collections.abc import Iterable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from leafstudio._shared.safewrite import stale_part
from leafstudio.errors import LeafError, error_line
from leafstudio.model import Params
from leafstudio.sources.extract import OUTLINE_POINTS

FORMATS = ("ply", "glb", "obj", "vtp", "none")  # mesh types save_mesh writes, or none
TABLE_SUFFIXES = (".csv", ".json", ".jsonl", ".parquet")
DEFAULT_TABLE = "traits.csv"
IN_FLIGHT_PER_WORKER = 2  # jobs queued per worker: keeps workers busy, memory bounded
# Dask settings for `--scheduler local` (measured: a batch of scans ran 1.5-2x faster): no
# statistical profiler sampling the task's stack every 10 ms, and no malloc trimming past 64 kB
# (numpy's arrays are freed to the system and faulted in again on every allocation)
LOCAL_CLUSTER_CONFIG = {
    "distributed.worker.profile.enabled": False,
    "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
}
INSTALL_CLUSTER = "pip install 'leafstudio[cluster]' (or: pip install distributed)"

SHAPE_COLUMNS = (
    "area",
    "projected_area",
    "perimeter",
    "length",
    "width",
    "aspect_ratio",
    "height",
)
CURVATURE_COLUMNS = tuple(
    f"{name}_{stat}"
    for name in ("mean_curvature", "gaussian_curvature")
    for stat in ("mean", "min", "max")
)
SCAN_COLUMNS = ("scan_points", "scan_mean", "scan_p95", "scan_beyond_1pct", "scan_beyond_2pct")
INT_COLUMNS = frozenset({"k", "grid", "scan_points"})
FLOAT_COLUMNS = frozenset(
    {*SHAPE_COLUMNS, *CURVATURE_COLUMNS, *SCAN_COLUMNS, "seconds"} - INT_COLUMNS
)


def columns(scans: bool) -> tuple[str, ...]:
    """The trait table's columns, in order (the scan distances only for scans)."""
    return (
        "input",
        "status",
        "error",
        "mesh",
        "k",
        "grid",
        *SHAPE_COLUMNS,
        *CURVATURE_COLUMNS,
        *(SCAN_COLUMNS if scans else ()),
        "warnings",
        "seconds",
        "sha256",
        "mesh_sha256",
        "settings",
    )


@dataclass(frozen=True)
class Settings:
    """What every input of a batch is run with.

    Parameters
    ----------
    params : Params
        The reconstruction settings (the same for every input, so traits compare; a project's
        saved parameters are not applied).
    scans : bool, default: False
        Inputs are 3D scans: extract boundary and veins, then reconstruct, then measure the
        distances from the scan's blade points to the surface.
    format : str, default: "ply"
        Mesh format (one of FORMATS; "none" writes no meshes).
    force : bool, default: False
        With scans: a scan that does not look like one leaf (extract's plausibility check) is
        reconstructed anyway, its problems the row's warnings, as `extract --force`; without it
        the row fails with extract's line.
    """

    params: Params = field(default_factory=Params)
    scans: bool = False
    format: str = "ply"
    force: bool = False

    def key(self) -> str:
        """A short hash of the settings: rows made with other settings are not resumed."""
        text = json.dumps(
            {
                "params": self.params.to_dict(),
                "scans": self.scans,
                "format": self.format,
                "points": OUTLINE_POINTS,
                "force": self.force,
            },
            sort_keys=True,
        )
        return hashlib.sha256(text.encode()).hexdigest()[:16]


@dataclass(frozen=True)
class Job:
    """One input: where to read it, where its mesh goes, and how to run it."""

    input: str  # the path as listed (the table's key)
    path: str  # absolute path the worker reads
    mesh: str  # mesh path relative to the output folder ("" for format none)
    out_dir: str  # absolute output folder
    settings: Settings


# ----------------------------------------------------------------------------- inputs


def _input_suffixes(scans: bool) -> tuple[str, ...]:
    if scans:
        from leafstudio.sources.scan import SCAN_SUFFIXES

        return SCAN_SUFFIXES
    from leafstudio.sources.files import LEAF_SUFFIXES

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
        If no input is found, or two inputs would write the same mesh.
    """
    out = Path(out_dir).resolve()
    found = find_inputs(inputs, settings.scans, [out, *exclude])
    if not found:
        raise LeafError(f"no input files found in {' '.join(map(os.fspath, inputs))}")
    roots = {os.path.abspath(root) for _, root in found}  # links are not followed: a linked
    common = Path(os.path.commonpath(sorted(roots)))  # file stays where it was listed
    jobs, owners = [], {}
    for shown, _ in found:
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
    """sha256 of a file's content (hex)."""
    with open(path, "rb") as handle:
        return hashlib.file_digest(handle, "sha256").hexdigest()


# ----------------------------------------------------------------------------- the worker

_PINNED = False


def pin_threads() -> None:
    """One BLAS thread and one numba thread in this process (the workers run side by side);
    done once per process."""
    global _PINNED
    if _PINNED:
        return
    import numba
    from threadpoolctl import threadpool_limits

    numba.set_num_threads(1)  # for any parallel kernel (leafstudio's are serial today)
    threadpool_limits(1)  # after numba: its OpenMP layer too
    _PINNED = True


def _worker_start() -> None:
    """Pool initializer: pin threads, then import the pipeline once per worker. Ctrl-C reaches
    the whole process group: the parent stops the batch (and lets running jobs finish)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    pin_threads()
    import leafstudio.core.pipeline  # noqa: F401


def _number(x: Any) -> float | None:
    return None if x is None else float(x)


def _traits(result: Any) -> dict[str, Any]:
    """The shape and curvature columns of a Result (core/measure.py)."""
    from leafstudio.core.measure import curvature_summary, shape_measurements

    mesh = result.triangle_mesh
    shape = shape_measurements(mesh, result.frame, result.polygon)
    curvature = curvature_summary(mesh)
    row = {name: _number(shape[name]) for name in SHAPE_COLUMNS}
    for name in CURVATURE_COLUMNS:
        array, stat = name.rsplit("_", 1)
        row[name] = _number(curvature[array][stat]) if array in curvature else None
    return row


def _reconstruct(job: Job) -> dict[str, Any]:
    """Read, (extract,) reconstruct, measure and write one input; raises on bad input. It opens,
    fails and warns as `leafstudio extract` (for a scan) then `reconstruct` would: both go
    through workflows."""
    from leafstudio import workflows
    from leafstudio.sources.files import load_leaf

    settings = job.settings
    try:
        if settings.scans:
            opened = workflows.open_scan(job.path, force=settings.force)
        else:
            opened = workflows.Opened(job.path, "leaf", load_leaf(job.path))
        done = workflows.reconstruct(opened, settings.params)
    except LeafError as exc:
        raise LeafError(exc.problem, job.input) from None
    result = done.result
    row: dict[str, Any] = {"k": result.chosen_k, "grid": settings.params.grid, **_traits(result)}
    if done.scan_fit is not None:
        found = done.scan_fit
        row.update(
            scan_points=found["points"],
            scan_mean=_number(found.get("mean")),
            scan_p95=_number(found.get("p95")),
            scan_beyond_1pct=_number(found.get("beyond_1pct")),
            scan_beyond_2pct=_number(found.get("beyond_2pct")),
        )
    if job.mesh:
        from leafstudio.assets.export import save_mesh

        # the bare mesh: normals, UVs and the point arrays, without the texture image and the
        # closed-form normals a Result gets (a second per leaf; `reconstruct` writes those)
        save_mesh(result.triangle_mesh, Path(job.out_dir) / job.mesh)
        row["mesh"] = job.mesh
        row["mesh_sha256"] = file_hash(Path(job.out_dir) / job.mesh)  # --resume checks it
    row["warnings"] = "; ".join(done.warnings) or None
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
    pin_threads()
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


# ----------------------------------------------------------------------------- the table


def _parse(name: str, text: str) -> Any:
    """A CSV cell back to its value ("" is None)."""
    if text == "":
        return None
    if name in INT_COLUMNS:
        return int(text)
    if name in FLOAT_COLUMNS:
        return float(text)
    return text


def _cell(value: Any) -> str:
    """A CSV cell: floats exactly (repr), text on one line (a row is one line of the file)."""
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)
    return " ".join(str(value).splitlines())


class TraitTable:
    """The trait table: rows appended and flushed as they arrive, sorted at `close`.

    CSV and JSON lines are appended to the table itself; a Parquet table is journalled in a JSON
    lines file beside it (`.NAME.rows.jsonl`) and written at `close`.
    """

    def __init__(self, path: str | os.PathLike, scans: bool) -> None:
        self.path = Path(path)
        suffix = self.path.suffix.lower()
        if suffix not in TABLE_SUFFIXES:
            raise LeafError(
                f"unknown table type {suffix or '(none)'!r}; use .csv, .json or .parquet",
                str(self.path),
            )
        self.kind = {".jsonl": ".json"}.get(suffix, suffix)
        if self.kind == ".parquet":
            try:
                import pyarrow  # noqa: F401
            except ImportError:
                raise LeafError(
                    "a .parquet table needs pyarrow (pip install pyarrow); or use .csv or .json",
                    str(self.path),
                ) from None
        self.columns = columns(scans)
        self.journal = (
            self.path.with_name(f".{self.path.name}.rows.jsonl")
            if self.kind == ".parquet"
            else self.path
        )
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
        if self.kind == ".parquet":
            import pyarrow.parquet as pq

            try:
                names = pq.read_schema(self.path).names
            except Exception:  # not a Parquet file at all
                return True
            return names[:2] != ["input", "status"]
        with open(self.path, encoding="utf-8", errors="replace") as handle:
            first = handle.readline(4096).strip()
        if self.kind == ".csv":
            return not first.startswith("input,status,")
        try:
            row = json.loads(first)
        except json.JSONDecodeError:
            return True
        return not (isinstance(row, dict) and {"input", "status"} <= row.keys())

    def rows(self) -> Iterator[dict[str, Any]]:
        """The complete rows in the journal (a row cut short by a kill is left out)."""
        source = self.journal if self.journal.exists() else self.path
        if not source.exists():
            return
        if source.suffix.lower() == ".parquet":
            import pyarrow.parquet as pq

            try:
                yield from pq.read_table(source).to_pylist()
            except Exception:  # a table we cannot read is not resumed from
                return
            return
        with open(source, encoding="utf-8", newline="") as handle:
            lines = (line for line in handle if line.endswith("\n"))
            if self.kind == ".csv":
                reader = csv.reader(lines)
                header = next(reader, None)
                if header is None:
                    return
                for cells in reader:
                    if len(cells) == len(header):
                        yield {n: _parse(n, c) for n, c in zip(header, cells, strict=True)}
            else:
                for line in lines:
                    try:
                        row = json.loads(line)
                    except json.JSONDecodeError:
                        continue
                    if isinstance(row, dict):
                        yield row

    # writing -----------------------------------------------------------------------------
    def _line(self, row: dict[str, Any]) -> str:
        if self.journal.suffix.lower() == ".csv":
            buffer = io.StringIO()
            csv.writer(buffer, lineterminator="\n").writerow(
                [_cell(row.get(c)) for c in self.columns]
            )
            return buffer.getvalue()
        return json.dumps({c: row.get(c) for c in self.columns}) + "\n"

    def _header(self) -> str:
        return ",".join(self.columns) + "\n" if self.journal.suffix.lower() == ".csv" else ""

    def start(self, keep: Iterable[dict[str, Any]] = ()) -> None:
        """Start the journal afresh with the rows in `keep` (rows resumed), then open it."""
        from leafstudio._shared.safewrite import write_bytes

        self.path.parent.mkdir(parents=True, exist_ok=True)
        text = self._header() + "".join(self._line(r) for r in keep)
        if text:
            write_bytes(self.journal, text)
        self._handle = open(self.journal, "a" if text else "w", encoding="utf-8", newline="")  # noqa: SIM115

    def add(self, row: dict[str, Any]) -> None:
        """Append one row and flush it to the disk."""
        assert self._handle is not None, "start() first"
        self._handle.write(self._line(row))
        self._handle.flush()
        os.fsync(self._handle.fileno())

    def close(self) -> None:
        """Rewrite the table sorted by input path (atomically); for Parquet, from the journal."""
        if self._handle is None:
            return
        self._handle.close()
        self._handle = None
        from leafstudio._shared.safewrite import replace_atomically, write_bytes

        if self.kind == ".parquet":
            import pyarrow as pa
            import pyarrow.parquet as pq

            rows = sorted(self.rows(), key=lambda r: str(r.get("input")))
            types = {c: pa.float64() for c in FLOAT_COLUMNS} | {c: pa.int64() for c in INT_COLUMNS}
            schema = pa.schema([(c, types.get(c, pa.string())) for c in self.columns])
            table = pa.Table.from_pylist(
                [{c: r.get(c) for c in self.columns} for r in rows], schema=schema
            )
            replace_atomically(self.path, lambda tmp: pq.write_table(table, tmp))
            self.journal.unlink(missing_ok=True)
        else:  # the journal's own lines, sorted: rows are not parsed (nor held) whole
            write_bytes(self.path, self._header() + "".join(self._sorted_lines()))

    def _sorted_lines(self) -> list[str]:
        """The journal's complete row lines (one line a row: see _cell), sorted by input."""
        keyed = []
        with open(self.journal, encoding="utf-8", newline="") as handle:
            if self.kind == ".csv":
                next(handle, None)  # the header
            for line in handle:
                if not line.endswith("\n"):
                    continue
                try:
                    key = next(csv.reader([line])) if self.kind == ".csv" else json.loads(line)
                    keyed.append((str(key[0] if self.kind == ".csv" else key["input"]), line))
                except (ValueError, KeyError, IndexError, TypeError, StopIteration):
                    continue
        return [line for _, line in sorted(keyed)]


# ----------------------------------------------------------------------------- executors


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


class _Local:
    """A pool of worker processes on this machine (spawned: each imports once)."""

    def __init__(self, jobs: int) -> None:
        import multiprocessing

        self.workers = jobs
        self._context = multiprocessing.get_context("spawn")
        self._pool = self._new_pool()

    def _new_pool(self) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(self.workers, self._context, initializer=_worker_start)

    def submit(self, job: Job) -> Future:
        # workers start on a submit; started with SIGINT ignored, they keep ignoring it (even
        # while importing), so Ctrl-C stops the batch in this process alone
        main = threading.current_thread() is threading.main_thread()
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN) if main else None
        try:
            future = self._pool.submit(run_job, job)
        finally:
            if main:
                signal.signal(signal.SIGINT, previous)
        future.pool = self._pool  # type: ignore[attr-defined]
        return future

    def wait(self, pending: set) -> tuple[set, set]:
        done, rest = wait(pending, return_when=FIRST_COMPLETED)
        return done, rest

    def outcome(self, future: Future, job: Job) -> dict[str, Any] | None:
        """The row, or None when a worker process died (a crash, or killed) with the job in
        flight: the pool is replaced, and the job may run again."""
        try:
            return future.result()
        except BrokenProcessPool:
            if future.pool is self._pool:  # type: ignore[attr-defined]
                self._pool.shutdown(wait=False, cancel_futures=True)
                self._pool = self._new_pool()
            return None

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)


class _Dask:
    """A Dask distributed cluster: an existing one by address, or a LocalCluster for the run."""

    def __init__(self, address: str, jobs: int) -> None:
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise LeafError(f"--scheduler needs Dask distributed: {INSTALL_CLUSTER}") from None
        import logging

        self._cluster = None
        try:
            if address == "local":
                import dask

                with dask.config.set(LOCAL_CLUSTER_CONFIG):
                    self._cluster = LocalCluster(
                        n_workers=jobs,
                        threads_per_worker=1,
                        processes=True,
                        dashboard_address=None,
                        # a worker's heartbeat racing the scheduler's shutdown logs a
                        # traceback at ERROR (seen once in 8 runs of bench_batch); a job's
                        # own failure reaches its row through its future, not the log
                        silence_logs=logging.CRITICAL,
                    )
                self._client = Client(self._cluster)
            else:
                self._client = Client(address, timeout="10s")
        except OSError as exc:
            if self._cluster is not None:
                self._cluster.close()
            raise LeafError(f"cannot reach the Dask scheduler ({exc})", address) from None
        threads = sum(self._client.nthreads().values())
        self.workers = max(1, threads)
        self._count = 0

    def submit(self, job: Job) -> Any:
        self._count += 1
        return self._client.submit(run_job, job, pure=False, key=f"leafstudio-batch-{self._count}")

    def wait(self, pending: set) -> tuple[set, set]:
        from distributed import wait as dask_wait

        done, rest = dask_wait(list(pending), return_when="FIRST_COMPLETED")
        return set(done), set(rest)

    def outcome(self, future: Any, job: Job) -> dict[str, Any] | None:
        try:
            return future.result()
        except Exception as exc:  # the worker died (KilledWorker) or could not run it
            row = run_failed(job, exc)
            return row
        finally:
            future.release()

    def close(self) -> None:
        self._client.close()
        if self._cluster is not None:
            self._cluster.close()


def run_failed(job: Job, exc: BaseException) -> dict[str, Any]:
    """A failed row for a job that could not be run at all."""
    row: dict[str, Any] = dict.fromkeys(columns(job.settings.scans))
    row.update(input=job.input, settings=job.settings.key(), status="failed", error=error_line(exc))
    return row


# ----------------------------------------------------------------------------- the batch


class Batch:
    """A batch run: planned when made (bad arguments raise LeafError at once), run by iterating,
    which yields one row (a dict of the table's columns) per input as it completes; rows resumed
    from an earlier run come first.

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
    ) -> None:
        if format not in FORMATS:
            raise LeafError(f"unknown mesh format {format!r}; use one of {', '.join(FORMATS)}")
        if jobs is not None and jobs < 1:
            raise LeafError(f"--jobs must be 1 or more, got {jobs}")
        self.out_dir = Path(out_dir)
        if self.out_dir.exists() and not self.out_dir.is_dir():
            raise LeafError("is a file, not a folder", str(self.out_dir))
        self.settings = Settings(params or Params(), scans, format, force)
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
        """Rows of an earlier run that stand: ok, same settings and content, the mesh as written."""
        if not self.resume:
            return {}
        key = self.settings.key()
        wanted = {job.input: job for job in self.jobs}
        kept: dict[str, dict[str, Any]] = {}
        for row in self.table.rows():
            job = wanted.get(str(row.get("input")))
            if (
                job is None
                or row.get("status") != "ok"
                or row.get("settings") != key
            ):
                continue
            try:  # the input unchanged, and its mesh as written (not lost, cut short or edited)
                same = row.get("sha256") == file_hash(job.path) and (
                    not job.mesh or row.get("mesh_sha256") == file_hash(self.out_dir / job.mesh)
                )
            except OSError:
                same = False
            if same:
                kept[job.input] = row
        return kept

    def __iter__(self) -> Iterator[dict[str, Any]]:
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
            self.table.start(kept[j.input] for j in self.jobs if j.input in kept)
            for job in self.jobs:
                if job.input in kept:
                    yield kept[job.input]
            todo = (job for job in self.jobs if job.input not in kept)
            if self.resumed < self.total:
                executor = (
                    _Dask(self.scheduler, self.workers) if self.scheduler else _Local(self.workers)
                )
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
        (scans that do not look like one leaf are reconstructed anyway, with warnings).

    Returns
    -------
    Batch
        Iterate over it to run the batch: one row (dict) per input as it completes.

    Examples
    --------
    >>> import leafstudio as ls
    >>> for row in ls.batch(["scans/"], ls.Params(grid=64), "out", scans=True):  # doctest: +SKIP
    ...     print(row["input"], row["status"], row["area"])
    """
    if isinstance(inputs, str | os.PathLike):
        inputs = [inputs]
    return Batch(list(inputs), params, out_dir, **options)


def summary(run: Batch, seconds: float) -> str:
    """The one line printed at the end of a batch."""
    ok = run.ok + run.resumed
    ran = run.ok + run.failed
    parts = [f"{run.total} inputs: {ok} ok, {run.failed} failed"]
    if run.resumed:
        parts.append(f"{run.resumed} already done")
    if ok + run.failed < run.total:
        parts.append(f"{run.total - ok - run.failed} not run")
    if run.stopped:
        parts.append("stopped at the first failure")
    rate = ran / seconds if seconds > 0 else 0.0
    return (
        f"leafstudio: batch: {', '.join(parts)}; {seconds:.1f} s ({rate:.2f} per second); "
        f"table {run.table.path}"
    )


def command(args: Any) -> int:
    """`leafstudio batch`: run the batch with a progress bar on stderr (when it is a terminal),
    each failure's line as it happens and one summary line. Exit 0, or 1 if any input failed."""
    import sys

    from tqdm import tqdm

    params = args.params  # from the parameter flags (cli._add_param_flags)
    run = batch(
        args.inputs,
        params,
        args.output,
        scans=args.scans,
        traits=args.traits,
        format=args.format,
        jobs=args.jobs,
        scheduler=args.scheduler,
        resume=args.resume,
        fail_fast=args.fail_fast,
        force=args.force,
    )
    start = time.perf_counter()
    bar = tqdm(
        total=run.total,
        file=sys.stderr,
        disable=not sys.stderr.isatty(),
        unit="leaf",
        dynamic_ncols=True,
        desc="leafstudio batch",
    )
    try:
        with bar:
            for row in run:
                if row["status"] != "ok":
                    internal = str(row["error"]).startswith("internal error:")
                    bar.write(
                        f"leafstudio: {'' if internal else 'error: '}{row['error']}", sys.stderr
                    )
                bar.set_postfix(failed=run.failed, refresh=False)
                bar.update(1)
    except KeyboardInterrupt:
        print(f"{summary(run, time.perf_counter() - start)}; interrupted (--resume goes on)",
              file=sys.stderr)  # fmt: skip
        raise
    print(summary(run, time.perf_counter() - start), file=sys.stderr)
    return 1 if run.failed else 0
