"""What several commands share: the reconstruction parameters as flags, the leaf input, the
Params they give, and one pipeline run with its notes logged."""

from __future__ import annotations

import argparse
import contextlib
import logging
import sys
from collections.abc import Iterator
from typing import TYPE_CHECKING

from leafstudio._shared.kernelcache import NOTICE, kernels_cached, mark_cached
from leafstudio.errors import LeafError, shorten
from leafstudio.model import PARAMS, Params
from leafstudio.paramspec import Choice, Switch, read_whole

if TYPE_CHECKING:
    from leafstudio.paramspec import Param

EXIT_OK, EXIT_INTERNAL, EXIT_BAD_INPUT = 0, 1, 2
log = logging.getLogger("leafstudio")


def summary(line: str) -> None:
    """A command's closing line (what it wrote) on stderr, unless -q: said at the logger's INFO
    level as reconstruct's notes are, and on their stream; stdout holds only what a command is
    asked to print (measure's and compare's tables, reconstruct --against's distances). Before,
    extract's and slides' were on stdout and form's, veins', photo's and batch's on stderr
    (assets33), and `form -q` and `extract -q` printed theirs all the same (appreview31)."""
    if log.isEnabledFor(logging.INFO):
        print(line, file=sys.stderr)


def whole(text: str, low: int, high: int) -> int:
    """A whole number in [low, high] from the command line (paramspec.read_whole)."""
    value = read_whole(text)
    if value is None:
        raise argparse.ArgumentTypeError(f"must be a whole number, got {shorten(text)!r}")
    if not low <= value <= high:
        raise argparse.ArgumentTypeError(f"must be between {low} and {high}, got {shorten(text)}")
    return value


def _param_value(param: Param):
    """The argparse `type` of a parameter's flag: its text read and checked as Params does."""

    def value(text: str) -> object:
        try:
            return param.parse(text)
        except LeafError as exc:
            raise argparse.ArgumentTypeError(exc.problem) from None

    return value


def add_param_flags(parser: argparse.ArgumentParser) -> None:
    """A flag for each reconstruction parameter, as Params declares it (model.PARAMS): unset
    (None) unless given, so that a project's saved value stands."""
    group = parser.add_argument_group("reconstruction parameters")
    for name, param in PARAMS.items():
        options = {"dest": name, "default": None, "help": param.help_text().replace("%", "%%")}
        if isinstance(param, Switch):
            group.add_argument(param.flag, action=argparse.BooleanOptionalAction, **options)
        elif isinstance(param, Choice):
            group.add_argument(param.flag, choices=param.choices, **options)
        else:
            group.add_argument(
                param.flag, type=_param_value(param), metavar=param.metavar, **options
            )


def add_run_options(parser: argparse.ArgumentParser) -> None:
    """The leaf input and reconstruction settings shared by reconstruct, measure and compare."""
    parser.add_argument("input", help="leaf file: .csv, .txt, .xyz, .ply or .leaf.json")
    add_param_flags(parser)
    parser.add_argument(
        "--vein", action="append", default=[], metavar="FILE", help="a vein file (repeatable)"
    )


def params_for(args: argparse.Namespace, base: object | None):
    """`base` (Params, else the defaults) with the parameter flags given (add_param_flags)."""
    params = base if isinstance(base, Params) else Params()
    changes = {name: getattr(args, name) for name in PARAMS}
    return params.with_(**{k: v for k, v in changes.items() if v is not None})


def settings(args: argparse.Namespace):
    """Params from the command line, over a project's saved ones."""
    from leafstudio.sources.files import load_project  # heavy (bends: scipy): not for --help

    saved = load_project(args.input)[1] if args.input.lower().endswith(".json") else None
    try:  # each flag is checked as it is read (_param_value): a bad one is the command line's
        return params_for(args, saved)
    except LeafError as exc:
        raise LeafError(exc.problem, args.input) from None


def run_pipeline(args: argparse.Namespace, leaf: object):
    """The Params (see settings) and the pipeline's Result; the run's notes are printed as
    warnings, and the chosen K when K is auto."""
    from leafstudio.core.pipeline import Pipeline  # heavy (numba, scipy): not for --help
    from leafstudio.core.prepare.plausibility import leaf_warnings

    params = settings(args)
    try:  # the frame stage refuses a crossing boundary and keeps the largest of several loops
        with first_run_said():
            result = Pipeline(leaf).run(params)
    except LeafError as exc:
        raise LeafError(exc.problem, args.input) from None
    args.warnings = [*leaf_warnings(leaf), *result.warnings]  # for --metrics
    for note in args.warnings:
        log.warning(f"{args.input}: {note}")
    if params.k == "auto":  # a flat blade's K of 1 is a placeholder, chosen by nothing
        flat = result.fits_no_mixture
        said = "unused (the blade is flat)" if flat else f"{result.chosen_k} (chosen by BIC)"
        log.info(f"{args.input}: K = {said}")
    return params, result


@contextlib.contextmanager
def first_run_said() -> Iterator[None]:
    """Around a command's reconstruction (any: `form -o x.glb` and `compare` too): the compiling
    line first when this run compiles the kernels, and the cache marked compiled once it ran."""
    compiling_notice()
    yield
    mark_cached()


def compiling_notice() -> None:
    """Say so when this run compiles the numerical kernels (the first run; README, "How good
    and how fast"): the line the app's status shows then too."""
    if not kernels_cached():
        log.info(NOTICE)
