"""`leafstudio extract`: take a leaf's boundary and veins from a 3D scan."""

from __future__ import annotations

import argparse

from leafstudio.cli.options import EXIT_OK, log, summary, whole
from leafstudio.sources.scan import OUTLINE_POINTS


def _points_value(text: str) -> int:
    return whole(text, 8, 100_000)


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The `extract` subcommand."""
    ext = sub.add_parser("extract", help="take a leaf's boundary and veins from a 3D scan")
    ext.add_argument("scan", help="scan: .ply, .pcd, .xyz, .csv or .txt (x y z first)")
    ext.add_argument(
        "-o", "--output", required=True, metavar="LEAF", help=".leaf.json, .csv, .txt, .xyz or .ply"
    )
    ext.add_argument(
        "--base-end",
        default="auto",
        metavar="END",
        help="where the leaf's base is: auto (the petiole's end, else the wider end) or the "
        "world direction it lies in: +x, -x, +y, -y, +z, -z",
    )
    ext.add_argument(
        "--points",
        type=_points_value,
        default=OUTLINE_POINTS,
        metavar="N",
        help=f"boundary points (default {OUTLINE_POINTS})",
    )
    ext.add_argument(
        "--force",
        action="store_true",
        help="go on with a cloud that does not look like one leaf (its problems become warnings)",
    )


def run(args: argparse.Namespace) -> int:
    """Extract the scan's leaf, write it and say what was kept."""
    from leafstudio.core.evaluate import leaf_blade_length  # heavy (numba): not for --help
    from leafstudio.sources.files import bend_not_kept, check_leaf_output, save_leaf
    from leafstudio.workflows import open_scan

    check_leaf_output(args.output, [args.scan])
    opened = open_scan(args.scan, base_end=args.base_end, points=args.points, force=args.force)
    for note in opened.notes:
        log.warning(f"{args.scan}: {note}")
    found, scan = opened.extraction, opened.scan
    save_leaf(found.leaf, args.output)
    if (lost := bend_not_kept(found.leaf, args.output)) is not None:
        log.warning(lost)
    other = len(scan) - found.blade.sum() - found.petiole.sum()
    length = leaf_blade_length(found.leaf)  # base to apex; a reconstruction's outline is smoother
    summary(
        f"{args.scan}: blade of {found.blade.sum()} of {len(scan)} points (dropped: petiole "
        f"{found.petiole.sum()}, outliers and clutter {other}), length about {length:.3g} (base "
        f"to apex); wrote "
        f"{len(found.leaf.boundary)} boundary points and {len(found.leaf.veins)} veins to "
        f"{args.output}"
    )
    return EXIT_OK
