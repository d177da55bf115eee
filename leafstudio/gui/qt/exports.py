"""Exports written off the main thread, with their progress in the status bar (issue 23,
finding 4: File > Export froze the window for 2.2 s).

A mixin of FileCommands (file_commands.py). `run_export` starts a writer from the worker's
"export" lane (worker.py) in a process of its own (gui/model/exports.py: a thread would still
hold the window up through Python's lock): the mesh, its levels of detail, textures and USD are
made and written there (assets/ holds no Qt or VTK), reporting progress(fraction, what) through
the window's `export_progress` signal, which Qt queues to the main thread. Turntables and the
steps figure too: their off-screen renders run on the export process's own main thread.

Exports run one after another, in the order asked: each has a kind of its own on the export lane
(the worker replaces a waiting job of the same kind, which would drop a second export queued
behind a running one without a word), and the status line names the one running and how many
wait.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import Any

from PySide6.QtWidgets import QProgressBar

from leafstudio.gui.model.exports import ExportProcess
from leafstudio.gui.model.jobs import Job, describe

EXPORT = "export"  # the worker's kind (and lane) for exports


class BackgroundExports:
    """Exports in the background, for MainWindow (which has `session`, `worker`,
    `status_text`, `statusBar`, `show_error` and the `export_progress` signal)."""

    _export_bar: QProgressBar | None = None
    _export_process: ExportProcess | None = None
    _export_count = 0  # exports asked for so far: each one's own kind
    _export_queue: list[str] | None = None  # the names of the exports not yet written, in order

    def close_exports(self) -> None:
        """End the export process (the window closes)."""
        if self._export_process is not None:
            self._export_process.close()

    def run_export(self, name: str, write: Callable[..., Any], *args: Any, **kwargs: Any) -> Job:
        """Start `write(*args, progress=..., **kwargs)` on the export lane, after the exports
        already asked for; the status bar shows its progress, the status line says when `name`
        is written, an error box why not."""
        if self._export_queue is None:
            self._export_queue = []
        self._export_queue.append(name)
        if len(self._export_queue) == 1:
            self._show_running()
        else:
            self._say_queued()
        if self._export_process is None:
            self._export_process = ExportProcess()
        run = self._export_process.run  # in a process of its own (gui/model/exports.py)
        BackgroundExports._export_count += 1
        kind = f"{EXPORT} {BackgroundExports._export_count}"  # never replaces a waiting one
        self.worker.lanes[kind] = self.worker.lanes[EXPORT]
        job = self.session.run(kind, partial(run, write, *args, progress=self._report, **kwargs))
        job.on_done(lambda _value: self._exported(name))
        job.on_failed(lambda exc: self._export_failed(name, exc))
        return job

    def _show_running(self) -> None:
        """The bar and the status line for the export at the head of the queue."""
        assert self._export_queue
        bar = self._progress_bar()
        bar.setValue(0)
        bar.setFormat(f"{self._export_queue[0]}: %p%")
        bar.show()
        self._say_queued()

    def _say_queued(self) -> None:
        queue = self._export_queue or []
        waiting = f" ({len(queue) - 1} more queued)" if len(queue) > 1 else ""
        self.status_text.setStyleSheet("")
        self.status_text.setText(f"Exporting {queue[0]}…{waiting}")

    def _export_ended(self, name: str) -> bool:
        """Take `name` off the queue; start showing the next one. Whether one is next."""
        queue = self._export_queue or []
        if name in queue:
            queue.remove(name)
        if queue:
            self._show_running()
            return True
        self._progress_bar().hide()
        return False

    def _report(self, fraction: float, what: str) -> None:
        """progress(fraction, what) for a writer: from any thread (a queued signal)."""
        self.export_progress.emit(float(fraction), str(what))

    def _on_export_progress(self, fraction: float, what: str) -> None:
        bar = self._progress_bar()
        bar.setValue(round(100 * min(max(fraction, 0.0), 1.0)))
        bar.setToolTip(what)

    def _exported(self, name: str) -> None:
        if not self._export_ended(name):
            self.status_text.setText(f"Exported {name}")

    def _export_failed(self, name: str, exc: BaseException) -> None:
        self._export_ended(name)
        self.status_text.setStyleSheet("color: #b00020")
        self.status_text.setText(f"Not exported: {name}")
        self.show_error(f"Cannot export {name}", describe(exc))

    def _progress_bar(self) -> QProgressBar:
        if self._export_bar is None:
            self._export_bar = QProgressBar()
            self._export_bar.setRange(0, 100)
            self._export_bar.setMaximumWidth(220)
            policy = self._export_bar.sizePolicy()  # shown and hidden without a new layout
            policy.setRetainSizeWhenHidden(True)
            self._export_bar.setSizePolicy(policy)
            self._export_bar.hide()
            self.statusBar().addPermanentWidget(self._export_bar)
        return self._export_bar
