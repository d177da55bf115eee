"""The command line: `leafstudio [gui|reconstruct|measure|compare|demo|extract|batch|form|veins|
photo] ...`, one module per command (each with add_parser and run; options.py holds what several
share). This module holds the parser, the logging and the error handling (docs/architecture.md,
"Command line").

Every failure is one line on stderr naming the file and the problem, with exit code 2.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import traceback
import warnings
from collections.abc import Callable, Sequence

from leafstudio._shared.blas import one_blas_thread
from leafstudio._shared.safewrite import install_signal_cleanup
from leafstudio.cli import (
    batch,
    compare,
    demo,
    extract,
    form,
    gui,
    measure,
    photo,
    reconstruct,
    slides,
)
from leafstudio.cli.options import EXIT_BAD_INPUT, EXIT_INTERNAL, EXIT_OK, log
from leafstudio.errors import LeafError, error_line, shorten


class _Parser(argparse.ArgumentParser):
    """argparse that reports usage errors as one line with exit code 2; every parser (the main
    one and each command's) takes -v, -q and --debug."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        quiet = argparse.SUPPRESS  # unset unless given, so a command's parser keeps the main one's
        self.add_argument(
            "-v", "--verbose", action="count", default=quiet, help="say more (-v -v: debug)"
        )
        self.add_argument(
            "-q", "--quiet", action="count", default=quiet, help="say less (-q -q: errors only)"
        )
        self.add_argument(
            "--debug", action="store_true", default=quiet, help="show a traceback on a bug"
        )

    def error(self, message: str) -> None:  # type: ignore[override]
        raise LeafError(f"{message} (see {self.prog} --help)")  # "leafstudio form", "leafstudio"


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("leafstudio")
    except PackageNotFoundError:
        return "(not installed)"


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with its subcommands."""
    parser = _Parser(
        prog="leafstudio", description="Smooth 3D leaf surfaces from boundaries and veins."
    )
    parser.add_argument("--version", action="version", version=f"leafstudio {_version()}")
    sub = parser.add_subparsers(dest="command", parser_class=_Parser)
    for add in (
        gui.add_parser,
        reconstruct.add_parser,
        measure.add_parser,
        compare.add_parser,
        demo.add_parser,
        extract.add_parser,
        batch.add_parser,
        form.add_form_parser,
        form.add_veins_parser,
        photo.add_photo_parser,
        slides.add_parser,
    ):
        add(sub)
    return parser


COMMANDS: dict[str, Callable[[argparse.Namespace], int]] = {
    "gui": gui.run,
    "reconstruct": reconstruct.run,
    "demo": demo.run,
    "extract": extract.run,
    "measure": measure.run,
    "compare": compare.run,
    "batch": batch.run,
    "form": form.run_form,
    "veins": form.run_veins,
    "photo": photo.run_photo,
    "slides": slides.run,
}


class _Format(logging.Formatter):
    """`leafstudio: message`, with `warning: ` or `error: ` for those levels; one line each."""

    def format(self, record: logging.LogRecord) -> str:
        text = " ".join(record.getMessage().split("\n"))
        if record.levelno >= logging.ERROR:
            return f"leafstudio: error: {text}"
        if record.levelno >= logging.WARNING:
            return f"leafstudio: warning: {text}"
        return f"leafstudio: {text}"


def _configure_logging(verbose: int, quiet: int) -> None:
    """INFO by default; each -v one level more, each -q one less (to errors only)."""
    level = min(max(logging.INFO + 10 * (quiet - verbose), logging.DEBUG), logging.ERROR)
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(_Format())
    log.handlers[:] = [handler]
    log.setLevel(level)
    log.propagate = False


def _debugging(argv: Sequence[str]) -> bool:
    """--debug or -v -v anywhere on the line (checked before parsing, which may itself fail)."""
    verbose = sum(a.count("v") for a in argv if a.startswith("-v") and set(a[1:]) == {"v"})
    return "--debug" in argv or verbose + argv.count("--verbose") >= 2


def _pipe_closed() -> int:
    """The reader of our output went away (`| head`): end quietly, as Unix tools do."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass
    return EXIT_OK


DASHED_VALUES = {"--base-end": ("-x", "-y", "-z")}  # values argparse would take for options


def _join_dashed_values(argv: list[str]) -> list[str]:
    """`--base-end -z` as `--base-end=-z`: argparse reads a value that starts with a dash as the
    next option and reports a missing argument."""
    out: list[str] = []
    for word in argv:
        if out and word in DASHED_VALUES.get(out[-1], ()):
            out[-1] = f"{out[-1]}={word}"
        else:
            out.append(word)
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the `leafstudio` console script; returns the exit code.

    Exit 0: done. Exit 2: bad input or an output that cannot be written, one line on stderr and no
    output changed. Exit 1: a bug (one line; --debug shows the traceback for a report).
    """
    argv = _join_dashed_values(list(sys.argv[1:] if argv is None else argv))
    debug = _debugging(argv)
    _configure_logging(0, 0)
    try:
        args = build_parser().parse_args(argv)
        _configure_logging(getattr(args, "verbose", 0) or 0, getattr(args, "quiet", 0) or 0)
        if (args.command or "gui") != "gui":  # the app's event loop keeps SIGTERM's default
            install_signal_cleanup()
        with warnings.catch_warnings(), one_blas_thread():  # the app's lanes too (blas.py)
            warnings.simplefilter("ignore")  # library chatter; our own notes are printed
            code = COMMANDS[args.command or "gui"](args)
        sys.stdout.flush()
        return code
    except BrokenPipeError:
        return _pipe_closed()
    except (LeafError, MemoryError, OSError) as exc:
        log.error(error_line(exc))
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        return 130
    except Exception as exc:  # a bug: one line (a traceback with --debug), and a distinct code
        return _internal_error(exc, debug)


def _internal_error(exc: Exception, debug: bool) -> int:
    """Report a bug (not bad input) in one line, or with its traceback under --debug; the test
    suite replaces this to make any internal error a failing test (tests/conftest.py)."""
    if debug:
        traceback.print_exception(exc, file=sys.stderr)
    detail = shorten(f"{type(exc).__name__}: {exc}", 300)
    log.error(f"internal error: {detail} (run with --debug for the traceback, and report it)")
    return EXIT_INTERNAL
