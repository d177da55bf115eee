"""Worker processes started by spawn that do not import the parent's `__main__` (for the batch's
pool and its local Dask cluster)."""

from __future__ import annotations

import contextlib
import multiprocessing
import sys
import types
from collections.abc import Iterator
from typing import Any


class WorkerProcess(multiprocessing.context.SpawnProcess):
    """A spawned worker that does not import the parent's `__main__`: a plain script calling
    ls.batch or ls.reconstruct (no `if __name__ == "__main__":` guard) would otherwise run again
    in every worker, which then fails starting a pool of its own. The workers need nothing from
    `__main__`: their jobs and functions are leafstudio's."""

    @staticmethod
    def _Popen(process_obj: Any) -> Any:  # multiprocessing's name
        with main_hidden():  # only while the process is launched, in the thread that submits
            return multiprocessing.context.SpawnProcess._Popen(process_obj)


@contextlib.contextmanager
def main_hidden() -> Iterator[None]:
    """Processes spawned meanwhile do not import the parent's `__main__`: spawn's preparation
    data names the main module (its path or name) when it has one; an empty stand-in, as in an
    interactive session, names none. The batch's pool launches each worker so; a local Dask
    cluster's workers are launched while it starts (the caller waits for it meanwhile)."""
    main = sys.modules["__main__"]
    sys.modules["__main__"] = types.ModuleType("__main__")
    try:
        yield
    finally:
        sys.modules["__main__"] = main


class WorkerContext(multiprocessing.context.SpawnContext):
    """The spawn start method, with workers that do not import `__main__` (WorkerProcess)."""

    Process = WorkerProcess
