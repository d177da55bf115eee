"""Where a batch's jobs run: a pool of local worker processes, or a Dask distributed cluster.
Both offer submit(job), wait(pending), outcome(future, job) (the row, or None when a local worker
died with the job in flight) and close()."""

from __future__ import annotations

import signal
import threading
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from leafstudio._shared.spawn import WorkerContext, main_hidden
from leafstudio.batch.plan import Job
from leafstudio.batch.worker import run_failed, run_job, worker_start
from leafstudio.core.kernels import TABLES, compile_kernels
from leafstudio.errors import LeafError, shorten

# Dask settings for `--scheduler local` (measured: a batch of scans ran 1.5-2x faster): no
# statistical profiler sampling the task's stack every 10 ms, and no malloc trimming past 64 kB
# (numpy's arrays are freed to the system and faulted in again on every allocation)
LOCAL_CLUSTER_CONFIG = {
    "distributed.worker.profile.enabled": False,
    "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
}
CONNECT_S = 8  # seconds a scheduler has to answer
INSTALL_CLUSTER = "pip install 'leafstudio[cluster]' (or: pip install distributed)"


def check_scheduler(address: str) -> None:
    """Refuse, before any work, a scheduler that no run could use (LeafError): Dask distributed
    not installed, or an address that is neither `local` nor HOST:PORT of a scheme distributed
    knows (inproc:// names a scheduler inside one process, never this batch's)."""
    try:
        import distributed.comm.addressing as addressing  # an optional extra
    except ImportError:
        raise LeafError(f"--scheduler needs Dask distributed: {INSTALL_CLUSTER}") from None
    if address == "local":
        return
    try:
        scheme, _ = addressing.parse_address(address)
        if scheme == "inproc":
            raise ValueError("an inproc:// scheduler lives inside one process")
        addressing.get_address_host_port(address)
    except (ValueError, TypeError) as exc:
        raise LeafError(
            f"not a Dask scheduler address ({shorten(str(exc), 160)}); use tcp://HOST:PORT, or "
            "local for a cluster on this machine",
            address,
        ) from None


class LocalPool:
    """A pool of worker processes on this machine (spawned: each imports once; see
    _shared/spawn.py)."""

    def __init__(self, jobs: int) -> None:
        # a cold cache: compiled once, in parallel, not by every worker (a row is measured too)
        compile_kernels(tables=TABLES)
        self.workers = jobs
        self._context = WorkerContext()
        self._pool = self._new_pool()

    def _new_pool(self) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(self.workers, self._context, initializer=worker_start)

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


def _connect(address: str) -> Any:
    """A Client of the Dask scheduler at `address`; LeafError when none answers within
    CONNECT_S. distributed's own timeout covers connecting, not the handshake: a port that
    speaks HTTP kept it waiting for ever (issue 24, finding 17). The Client is made in a daemon
    thread, left behind if it never returns."""
    from distributed import Client  # an optional extra

    made: dict[str, Any] = {}

    def connect() -> None:
        try:
            made["client"] = Client(address, timeout=f"{CONNECT_S}s")
        except BaseException as exc:  # raised again in the caller's thread
            made["error"] = exc

    thread = threading.Thread(target=connect, name="leafstudio-dask-connect", daemon=True)
    thread.start()
    thread.join(CONNECT_S + 1)
    if "error" in made:
        raise made["error"]
    if "client" not in made:
        raise LeafError(
            f"no Dask scheduler answered within {CONNECT_S} s (is this a Dask scheduler's "
            "address?)",
            address,
        )
    return made["client"]


class DaskCluster:
    """A Dask distributed cluster: an existing one by address, or a LocalCluster for the run."""

    def __init__(self, address: str, jobs: int) -> None:
        check_scheduler(address)
        import logging

        from distributed import Client, LocalCluster  # an optional extra

        self._cluster = None
        try:
            if address == "local":
                import dask

                # its workers are spawned: without main_hidden a plain script (no __main__
                # guard) ran again in each, and started a cluster of its own ("Nanny failed")
                with dask.config.set(LOCAL_CLUSTER_CONFIG), main_hidden():
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
                self._client = _connect(address)
        except LeafError:
            raise
        except (OSError, ValueError, TypeError) as exc:  # refused, timed out, or not a scheduler
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
