"""Exports written off the main thread, with their progress in the status bar (issue 23,
finding 4: File > Export froze the window for 2.2 s).

A mixin of FileCommands (file_commands.py). `run_export` starts a writer from the worker's
"export" lane (worker.py) in a process of its own (gui/model/exports.py: a thread would still
hold the window up through Python's lock): the mesh, its levels of detail, textures and USD are
made and written there (assets/ holds no Qt or VTK), reporting progress(fraction, what) through
the window's `export_progress` signal, which Qt queues to the main thread. Turntables and the
steps figure too: their off-screen renders run on the export process's own main thread.
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
    """Exports in the background, for MainWindow (which has `session`, `status_text`,
    `statusBar`, `show_error` and the `export_progress` signal)."""

    _export_bar: QProgressBar | None = None
    _export_process: ExportProcess | None = None

    def close_exports(self) -> None:
        """End the export process (the window closes)."""
        if self._export_process is not None:
            self._export_process.close()

    def run_export(self, name: str, write: Callable[..., Any], *args: Any, **kwargs: Any) -> Job:
        """Start `write(*args, progress=..., **kwargs)` on the export lane; the status bar shows
        its progress, the status line says when `name` is written, an error box why not."""
        bar = self._progress_bar()
        bar.setValue(0)
        bar.setFormat(f"{name}: %p%")
        bar.show()
        self.status_text.setStyleSheet("")
        self.status_text.setText(f"Exporting {name}…")
        if self._export_process is None:
            self._export_process = ExportProcess()
        run = self._export_process.run  # in a process of its own (gui/model/exports.py)
        job = self.session.run(EXPORT, partial(run, write, *args, progress=self._report, **kwargs))
        job.on_done(lambda _value: self._exported(name))
        job.on_failed(lambda exc: self._export_failed(name, exc))
        return job

    def _report(self, fraction: float, what: str) -> None:
        """progress(fraction, what) for a writer: from any thread (a queued signal)."""
        self.export_progress.emit(float(fraction), str(what))

    def _on_export_progress(self, fraction: float, what: str) -> None:
        bar = self._progress_bar()
        bar.setValue(round(100 * min(max(fraction, 0.0), 1.0)))
        bar.setToolTip(what)

    def _exported(self, name: str) -> None:
        self._progress_bar().hide()
        self.status_text.setText(f"Exported {name}")

    def _export_failed(self, name: str, exc: BaseException) -> None:
        self._progress_bar().hide()
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
