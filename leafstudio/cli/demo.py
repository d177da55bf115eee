"""`leafstudio demo`: write a built-in leaf."""

from __future__ import annotations

import argparse

from leafstudio.cli.options import EXIT_OK


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The `demo` subcommand."""
    dem = sub.add_parser("demo", help="write a built-in leaf")
    dem.add_argument("name", help="nested or parallel")
    dem.add_argument(
        "-o", "--output", required=True, metavar="FILE", help=".leaf.json, .csv, .txt, .xyz or .ply"
    )


def run(args: argparse.Namespace) -> int:
    """Write the named demo leaf."""
    from leafstudio.sources.demos import demo
    from leafstudio.sources.files import save_leaf  # heavy (bends: scipy): not for --help

    save_leaf(demo(args.name), args.output)
    return EXIT_OK
