"""`leafstudio compare`: our surface beside screened Poisson (distances, spill, time)."""

from __future__ import annotations

import argparse
import json

from leafstudio.cli.options import EXIT_OK, add_run_options, first_run_said, settings
from leafstudio.errors import LeafError


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The `compare` subcommand."""
    com = sub.add_parser(
        "compare", help="our surface beside screened Poisson: distances, spill, time"
    )
    add_run_options(com)
    com.add_argument("--json", action="store_true", help="print JSON instead of a table")


def run(args: argparse.Namespace) -> int:
    """Print the comparison, as a table or JSON."""
    from leafstudio.analysis.compare import compare, format_comparison  # heavy: not for --help
    from leafstudio.sources.files import load_leaf
    from leafstudio.workflows import check_finite

    leaf = load_leaf(args.input, veins=args.vein)
    params = settings(args)
    try:
        with first_run_said():
            report = compare(leaf, params)
    except LeafError as exc:
        raise LeafError(exc.problem, args.input) from None
    report.pop("meshes")
    check_finite(report, args.input)  # areas of a leaf past about 1e154 overflow: one line
    if args.json:
        print(json.dumps({"input": args.input, **report}, indent=2))
    else:
        print(format_comparison(report))
    return EXIT_OK
