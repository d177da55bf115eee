"""`leafstudio measure`: reconstruct a leaf and print its measurements."""

from __future__ import annotations

import argparse
import json

from leafstudio.cli.options import EXIT_OK, add_run_options, run_pipeline
from leafstudio.errors import LeafError


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The `measure` subcommand."""
    mea = sub.add_parser("measure", help="reconstruct a leaf and print its measurements")
    add_run_options(mea)
    mea.add_argument("--json", action="store_true", help="print JSON instead of a table")


def run(args: argparse.Namespace) -> int:
    """Print the reconstructed leaf's measurements, as a table or JSON."""
    from leafstudio.core.evaluate import format_table, leaf_measurements  # heavy: not for --help
    from leafstudio.sources.files import load_leaf
    from leafstudio.workflows import check_finite

    _, result = run_pipeline(args, load_leaf(args.input, veins=args.vein))
    try:
        values = leaf_measurements(result)  # LeafError: a leaf too large to measure
    except LeafError as exc:
        raise LeafError(exc.problem, args.input) from None
    check_finite(values, args.input)
    if args.json:
        print(json.dumps({"input": args.input, **values}, indent=2))
    else:
        print(format_table(values))
    return EXIT_OK
