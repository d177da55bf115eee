"""Worker processes started by spawn that do not import the parent's `__main__` (for the batch's
pool)."""

from __future__ import annotations

import multiprocessing
import sys
import types
from typing import Any


class WorkerProcess(multiprocessing.context.SpawnProcess):
    """A spawned worker that does not import the parent's `__main__`: a plain script calling
    ls.batch or ls.reconstruct (no `if __name__ == "__main__":` guard) would otherwise run again
    in every worker, which then fails starting a pool of its own. The workers need nothing from
    `__main__`: their jobs and functions are leafstudio's."""

    @staticmethod
    def _Popen(process_obj: Any) -> Any:  # multiprocessing's name
        # spawn's preparation data names the main module (its path or name) when it has one;
        # an empty stand-in, as in an interactive session, names none. Swapped only while the
        # process is launched, in the thread that submits.
        main = sys.modules["__main__"]
        sys.modules["__main__"] = types.ModuleType("__main__")
        try:
            return multiprocessing.context.SpawnProcess._Popen(process_obj)
        finally:
            sys.modules["__main__"] = main


class WorkerContext(multiprocessing.context.SpawnContext):
    """The spawn start method, with workers that do not import `__main__` (WorkerProcess)."""

    Process = WorkerProcess
