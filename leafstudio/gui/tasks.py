"""Side jobs off the main thread: reading a scan, its distances to a mesh, the Poisson surface.

One background thread, beside the pipeline's, so that these never hold up a reconstruction. Jobs
have a kind; a new job replaces a waiting one of its kind (only the newest scan, the newest
mesh's distances matter). Each job carries a token the window uses to drop stale answers.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from PySide6.QtCore import QObject, Signal

from leafstudio.errors import LeafError


class TaskWorker(QObject):
    """Runs submitted callables one at a time and reports by queued signal.

    Signals
    -------
    done(str, object, object)
        Kind, token and the callable's return value.
    failed(str, object, str)
        Kind, token and the user-facing message.
    """

    done = Signal(str, object, object)
    failed = Signal(str, object, str)

    def __init__(self, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._wake = threading.Condition()
        self._pending: dict[str, tuple[object, Callable[..., Any], tuple]] = {}
        self._busy = False
        self._quit = False
        self._thread = threading.Thread(target=self._loop, name="leafstudio-tasks", daemon=True)
        self._thread.start()

    def submit(self, kind: str, token: object, job: Callable[..., Any], *args: Any) -> None:
        """Queue `job(*args)`, replacing any waiting job of the same kind."""
        with self._wake:
            self._pending.pop(kind, None)
            self._pending[kind] = (token, job, args)
            self._wake.notify()

    def is_idle(self) -> bool:
        """True when nothing is running or waiting."""
        with self._wake:
            return not self._pending and not self._busy

    def shutdown(self, wait_ms: int = 10_000) -> None:
        """Drop waiting jobs and stop the thread after the running one."""
        with self._wake:
            self._quit = True
            self._pending.clear()
            self._wake.notify()
        self._thread.join(wait_ms / 1000)

    def _next(self) -> tuple[str, object, Callable[..., Any], tuple] | None:
        with self._wake:
            self._busy = False
            while not self._pending and not self._quit:
                self._wake.wait()
            if self._quit:
                return None
            kind = next(iter(self._pending))
            token, job, args = self._pending.pop(kind)
            self._busy = True
            return kind, token, job, args

    def _loop(self) -> None:
        while (task := self._next()) is not None:
            kind, token, job, args = task
            try:
                value = job(*args)
            except LeafError as exc:
                self.failed.emit(kind, token, str(exc))
                continue
            except Exception as exc:  # shown in the window; the app keeps running
                self.failed.emit(kind, token, f"internal error: {type(exc).__name__}: {exc}")
                continue
            self.done.emit(kind, token, value)
