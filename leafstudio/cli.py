"""The command line: `leafstudio [gui|reconstruct|measure|compare|demo|extract] ...` (DESIGN.md).

Every failure is one line on stderr naming the file and the problem, with exit code 2.
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path

from leafstudio.errors import LeafError

EXIT_OK, EXIT_INTERNAL, EXIT_BAD_INPUT = 0, 1, 2


class _Parser(argparse.ArgumentParser):
    """argparse that reports usage errors as one line with exit code 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise LeafError(f"{message} (see leafstudio {self.prog.split()[-1]} --help)")


def _k_value(text: str) -> int | str:
    if text == "auto":
        return text
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"K must be a whole number or 'auto', got {text!r}"
        ) from None


def _add_run_options(parser: argparse.ArgumentParser) -> None:
    """The leaf input and reconstruction settings shared by reconstruct, measure and compare."""
    parser.add_argument("input", help="leaf file: .csv, .txt, .xyz, .ply or .leaf.json")
    parser.add_argument(
        "--k", type=_k_value, default=None, help="number of Gaussians, or auto (default 3)"
    )
    parser.add_argument(
        "--grid", type=int, default=None, help="grid nodes along the leaf (default 128)"
    )
    parser.add_argument("--mesher", choices=("conforming", "bpa"), default=None)
    parser.add_argument("--seed", type=int, default=None, help="random seed (default 0)")
    parser.add_argument(
        "--vein", action="append", default=[], metavar="FILE", help="a vein file (repeatable)"
    )


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with its subcommands."""
    from leafstudio.figure import FIGURE_SCALARS

    parser = _Parser(
        prog="leafstudio", description="Smooth 3D leaf surfaces from boundaries and veins."
    )
    sub = parser.add_subparsers(dest="command", parser_class=_Parser)

    gui = sub.add_parser("gui", help="open the app (on FILE, or on the nested demo)")
    gui.add_argument("file", nargs="?", help="a leaf file, project or leaf scan to open")
    gui.add_argument(
        "--screenshot", metavar="PNG", help="save the window once reconstructed, then exit"
    )

    rec = sub.add_parser("reconstruct", help="reconstruct a leaf and write its mesh")
    _add_run_options(rec)
    rec.add_argument(
        "-o", "--output", required=True, metavar="MESH", help=".ply, .obj, .stl, .vtp or .vtk"
    )
    rec.add_argument(
        "--figure", metavar="PNG", help="also render iso and top views with the input points"
    )
    rec.add_argument(
        "--colour-by",
        choices=FIGURE_SCALARS,
        default="height",
        help="what the figure's colours show (default height)",
    )
    rec.add_argument(
        "--metrics", metavar="JSON", help="write Table-1 distances and mesh facts here"
    )
    rec.add_argument(
        "--against",
        metavar="SCAN",
        help="a scan of the real leaf: report the distances from its points to the surface",
    )

    mea = sub.add_parser("measure", help="reconstruct a leaf and print its measurements")
    _add_run_options(mea)
    mea.add_argument("--json", action="store_true", help="print JSON instead of a table")

    com = sub.add_parser(
        "compare", help="our surface beside screened Poisson: distances, spill, time"
    )
    _add_run_options(com)
    com.add_argument("--json", action="store_true", help="print JSON instead of a table")

    dem = sub.add_parser("demo", help="write a built-in leaf")
    dem.add_argument("name", help="nested or parallel")
    dem.add_argument(
        "-o", "--output", required=True, metavar="FILE", help=".leaf.json, .csv, .txt, .xyz or .ply"
    )
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
        "--points", type=int, default=200, metavar="N", help="boundary points (default 200)"
    )
    return parser


def _params_for(args: argparse.Namespace, base: object | None):
    from leafstudio.model import Params

    params = base if isinstance(base, Params) else Params()
    changes = {name: getattr(args, name) for name in ("k", "grid", "mesher", "seed")}
    return params.with_(**{k: v for k, v in changes.items() if v is not None})


def _settings(args: argparse.Namespace):
    """Params from the command line, over a project's saved ones."""
    from leafstudio.io import load_project

    saved = load_project(args.input)[1] if args.input.lower().endswith(".json") else None
    try:
        return _params_for(args, saved)
    except LeafError as exc:
        raise LeafError(exc.problem, args.input) from None


def _run(args: argparse.Namespace, leaf: object):
    """The Params (see _settings) and the pipeline's Result; the run's notes are printed as
    warnings, and the chosen K when K is auto."""
    from leafstudio.core.pipeline import Pipeline

    params = _settings(args)
    try:
        result = Pipeline(leaf).run(params)
    except LeafError as exc:
        raise LeafError(exc.problem, args.input) from None
    for note in result.warnings:
        print(f"leafstudio: warning: {args.input}: {note}", file=sys.stderr)
    if params.k == "auto":
        print(f"{args.input}: K = {result.chosen_k} (chosen by BIC)", file=sys.stderr)
    return params, result


def _reconstruct(args: argparse.Namespace) -> int:
    from leafstudio.figure import check_figure_path
    from leafstudio.io import MESH_SUFFIXES, load_leaf, save_mesh

    out = Path(args.output)
    if not out.name.lower().endswith(MESH_SUFFIXES):
        raise LeafError(f"unknown mesh type; use one of {', '.join(MESH_SUFFIXES)}", str(out))
    figure = check_figure_path(args.figure) if args.figure else None
    leaf = load_leaf(args.input, veins=args.vein)
    scan = None
    if args.against:
        from leafstudio.scan import read_scan

        scan = read_scan(args.against)
    params, result = _run(args, leaf)
    save_mesh(result, out)
    if figure is not None:
        from leafstudio.figure import render_figure

        render_figure(result, figure, args.colour_by)
    fidelity = None
    if scan is not None:
        from leafstudio.core.extract import split_scan
        from leafstudio.core.fidelity import scan_distances

        blade = split_scan(scan)[0]
        fidelity = {
            "all": scan_distances(result.triangle_mesh, scan, result.length),
            "blade": scan_distances(result.triangle_mesh, scan[blade], result.length),
        }
        for part, what in (("all", "all"), ("blade", "blade (no outliers, no petiole)")):
            f = fidelity[part]
            print(
                f"{args.against}: {what}: {f['points']} points to the surface: mean "
                f"{f['mean']:.4g}, median {f['median']:.4g}, 95% {f['p95']:.4g}, max "
                f"{f['max']:.4g}; beyond 1% of the leaf length {f['beyond_1pct']:.1%}, beyond 2% "
                f"{f['beyond_2pct']:.1%} (leaf length {result.length:.4g})"
            )
    if args.metrics:
        metrics = {
            "input": args.input,
            "params": params.to_dict(),
            "k": result.chosen_k,
            **result.metrics,
        }
        if fidelity is not None:
            metrics["fidelity"] = {"scan": args.against, **fidelity}
        Path(args.metrics).write_text(json.dumps(metrics, indent=2) + "\n", encoding="utf-8")
    return EXIT_OK


def _measure(args: argparse.Namespace) -> int:
    from leafstudio.core.measure import format_table, leaf_measurements
    from leafstudio.io import load_leaf

    _, result = _run(args, load_leaf(args.input, veins=args.vein))
    values = leaf_measurements(result)
    if args.json:
        print(json.dumps({"input": args.input, **values}, indent=2))
    else:
        print(format_table(values))
    return EXIT_OK


def _compare(args: argparse.Namespace) -> int:
    from leafstudio.core.compare import compare, format_comparison
    from leafstudio.io import load_leaf

    leaf = load_leaf(args.input, veins=args.vein)
    params = _settings(args)
    try:
        report = compare(leaf, params)
    except LeafError as exc:
        raise LeafError(exc.problem, args.input) from None
    report.pop("meshes")
    if args.json:
        print(json.dumps({"input": args.input, **report}, indent=2))
    else:
        print(format_comparison(report))
    return EXIT_OK


def _demo(args: argparse.Namespace) -> int:
    from leafstudio.demos import demo
    from leafstudio.io import save_leaf

    save_leaf(demo(args.name), args.output)
    return EXIT_OK


def _gui(args: argparse.Namespace) -> int:
    from leafstudio.gui.app import run_app

    return run_app(getattr(args, "file", None), getattr(args, "screenshot", None))


def _extract(args: argparse.Namespace) -> int:
    from leafstudio.core.extract import extract_leaf
    from leafstudio.io import LEAF_SUFFIXES, save_leaf
    from leafstudio.scan import read_scan

    if not args.output.lower().endswith(LEAF_SUFFIXES):
        raise LeafError(f"unknown leaf type; use one of {', '.join(LEAF_SUFFIXES)}", args.output)
    if not 8 <= args.points <= 100_000:
        raise LeafError(f"--points must be between 8 and 100000, got {args.points}")
    scan = read_scan(args.scan)
    try:
        found = extract_leaf(scan, args.base_end, args.points)
    except LeafError as exc:
        raise LeafError(exc.problem, args.scan) from None
    save_leaf(found.leaf, args.output)
    other = len(scan) - found.blade.sum() - found.petiole.sum()
    print(
        f"{args.scan}: blade of {found.blade.sum()} of {len(scan)} points (dropped: petiole "
        f"{found.petiole.sum()}, outliers and clutter {other}), length {found.length:.4g}; wrote "
        f"{len(found.leaf.boundary)} boundary points and {len(found.leaf.veins)} veins to "
        f"{args.output}"
    )
    return EXIT_OK


COMMANDS = {
    "gui": _gui,
    "reconstruct": _reconstruct,
    "demo": _demo,
    "extract": _extract,
    "measure": _measure,
    "compare": _compare,
}


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the `leafstudio` console script; returns the exit code."""
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        args = build_parser().parse_args(argv)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # library chatter; our own notes are printed
            return COMMANDS[args.command or "gui"](args)
    except LeafError as exc:
        print(f"leafstudio: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as exc:
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"leafstudio: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        return 130
    except Exception as exc:  # never a traceback: one line, and a distinct code
        print(f"leafstudio: internal error: {type(exc).__name__}: {exc}", file=sys.stderr)
        return EXIT_INTERNAL


if __name__ == "__main__":
    raise SystemExit(main())
