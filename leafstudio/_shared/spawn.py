"""Worker processes that do not import the parent's `__main__`, started from a fork server that
has imported leafstudio once (for the batch's pool, the app's export process and its readers of
big files).

A spawned worker imports numpy, scipy, numba and leafstudio afresh: 1.5-2 s of CPU before its
first job, paid by every pool, every export process and every big file read. On Linux the
workers are forked from one server process (multiprocessing's forkserver), started with the
first worker, which has imported leafstudio already (a worker is then ready in milliseconds).
The server is a fresh single-threaded process, so this is as safe as spawn from a process with
threads (the app's). A worker whose parent's environment, working folder or import path has
changed since the server started (a test's or a script's NUMBA_CACHE_DIR, say) is spawned
instead, so that every worker sees what a spawned one would. Elsewhere, spawn.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import multiprocessing.forkserver
import os
import sys
import threading
import types
from collections.abc import Iterator
from typing import Any

PRELOAD = ["leafstudio"]  # what the fork server imports once for every worker
# set anew for each test by pytest, read by nothing a worker runs
UNREAD = frozenset({"PYTEST_CURRENT_TEST"})

_LOCK = threading.Lock()
_server: dict[str, Any] = {}  # the fork server's pid and what it started with (_fits)


def _state() -> tuple[dict[str, str], str, list[str]]:
    """What a child inherits from its parent besides its job: environment, folder, path."""
    environ = {key: value for key, value in os.environ.items() if key not in UNREAD}
    return environ, os.getcwd(), list(sys.path)


def _forkserver_fits() -> bool:
    """Start the fork server if it is not running (PRELOAD imported there); True when it was
    started by this module with this process's present environment, folder and import path."""
    if not sys.platform.startswith("linux"):
        return False
    server = multiprocessing.forkserver._forkserver
    with _LOCK:
        pid = getattr(server, "_forkserver_pid", None)
        if pid is not None and pid != _server.get("pid"):
            return False  # another's server, started with what we cannot know
        if pid is None:
            multiprocessing.forkserver.set_forkserver_preload(PRELOAD)
        state = _state()
        server.ensure_running()  # (re)started if it is not running, with `state`
        if server._forkserver_pid != _server.get("pid"):
            _server.update(pid=server._forkserver_pid, state=state)
        return _server["state"] == state


@contextlib.contextmanager
def _no_main() -> Iterator[None]:
    """No `__main__` named to the child while it is launched: a plain script calling ls.batch
    or ls.reconstruct (no `if __name__ == "__main__":` guard) would otherwise run again in every
    worker, which then fails starting a pool of its own. The workers need nothing from
    `__main__`: their jobs and functions are leafstudio's. An empty stand-in, as in an
    interactive session, names none; swapped only while the process is launched."""
    main = sys.modules["__main__"]
    sys.modules["__main__"] = types.ModuleType("__main__")
    try:
        yield
    finally:
        sys.modules["__main__"] = main


class WorkerProcess(multiprocessing.context.SpawnProcess):
    """A worker forked from the fork server when it fits (_forkserver_fits), else spawned;
    neither imports the parent's `__main__`."""

    @staticmethod
    def _Popen(process_obj: Any) -> Any:  # multiprocessing's name
        with _no_main():
            if _forkserver_fits():
                from multiprocessing.popen_forkserver import Popen

                return Popen(process_obj)
            return multiprocessing.context.SpawnProcess._Popen(process_obj)


class WorkerContext(multiprocessing.context.SpawnContext):
    """Workers that start quickly and do not import `__main__` (WorkerProcess)."""

    Process = WorkerProcess
