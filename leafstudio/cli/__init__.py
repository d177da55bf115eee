"""The command line: `leafstudio [gui|reconstruct|measure|compare|demo|extract] ...` (DESIGN.md).

Every failure is one line on stderr naming the file and the problem, with exit code 2.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import sys
import traceback
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from leafstudio.errors import LeafError, error_line, shorten
from leafstudio.sources.extract import OUTLINE_POINTS

if TYPE_CHECKING:
    from leafstudio.paramspec import Param

EXIT_OK, EXIT_INTERNAL, EXIT_BAD_INPUT = 0, 1, 2
log = logging.getLogger("leafstudio")


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


def _whole(text: str, low: int, high: int) -> int:
    """A whole number in [low, high] from the command line (paramspec.read_whole)."""
    from leafstudio.paramspec import read_whole

    value = read_whole(text)
    if value is None:
        raise argparse.ArgumentTypeError(f"must be a whole number, got {shorten(text)!r}")
    if not low <= value <= high:
        raise argparse.ArgumentTypeError(f"must be between {low} and {high}, got {shorten(text)}")
    return value


def _points_value(text: str) -> int:
    return _whole(text, 8, 100_000)


def _param_value(param: Param):
    """The argparse `type` of a parameter's flag: its text read and checked as Params does."""

    def value(text: str) -> object:
        try:
            return param.parse(text)
        except LeafError as exc:
            raise argparse.ArgumentTypeError(exc.problem) from None

    return value


def _add_param_flags(parser: argparse.ArgumentParser) -> None:
    """A flag for each reconstruction parameter, as Params declares it (model.PARAMS): unset
    (None) unless given, so that a project's saved value stands."""
    from leafstudio.model import PARAMS
    from leafstudio.paramspec import Choice, Switch

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


def _add_run_options(parser: argparse.ArgumentParser) -> None:
    """The leaf input and reconstruction settings shared by reconstruct, measure and compare."""
    parser.add_argument("input", help="leaf file: .csv, .txt, .xyz, .ply or .leaf.json")
    _add_param_flags(parser)
    parser.add_argument(
        "--vein", action="append", default=[], metavar="FILE", help="a vein file (repeatable)"
    )


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("leafstudio")
    except PackageNotFoundError:
        return "(not installed)"


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with its subcommands."""
    from leafstudio.render.figure import FIGURE_SCALARS

    parser = _Parser(
        prog="leafstudio", description="Smooth 3D leaf surfaces from boundaries and veins."
    )
    parser.add_argument("--version", action="version", version=f"leafstudio {_version()}")
    sub = parser.add_subparsers(dest="command", parser_class=_Parser)

    gui = sub.add_parser("gui", help="open the app (on FILE, or on the nested demo)")
    gui.add_argument("file", nargs="?", help="a leaf file, project or leaf scan to open")
    gui.add_argument(
        "--screenshot", metavar="PNG", help="save the window once reconstructed, then exit"
    )

    rec = sub.add_parser("reconstruct", help="reconstruct a leaf and write its mesh")
    _add_run_options(rec)
    rec.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="MESH",
        help=".ply, .obj (+ .mtl, _texture.png), .glb, .gltf, .stl, .3mf, .vtp or .vtk",
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

    rec.add_argument(
        "--texture",
        default="auto",
        metavar="auto|none|IMAGE",
        help="the mesh's texture: auto (generated: blade and veins), none, or an image (a photo "
        "the leaf came from by `leafstudio photo` maps back onto itself; default auto)",
    )
    rec.add_argument(
        "--thickness",
        metavar="T",
        help="write a closed solid T thick: a fraction of the leaf length (0.01) or a length "
        "with its unit for a leaf in millimetres (0.4mm)",
    )
    rec.add_argument(
        "--lod",
        type=int,
        default=0,
        metavar="N",
        help="also write N coarser levels of detail, each with half the triangles",
    )
    rec.add_argument(
        "--turntable", metavar="GIF|MP4", help="also render the leaf turning once (for slides)"
    )
    rec.add_argument(
        "--steps-figure", metavar="PNG", help="also render the pipeline's steps side by side"
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
    _add_batch_parser(sub)
    from leafstudio.cli.form import add_form_parser, add_veins_parser

    add_form_parser(sub)
    add_veins_parser(sub)
    from leafstudio.cli.photo import add_photo_parser

    add_photo_parser(sub)
    return parser


def _add_batch_parser(sub: argparse._SubParsersAction) -> None:
    """`leafstudio batch`: many inputs, a worker pool or a Dask cluster (leafstudio/batch.py)."""
    from leafstudio.batch import FORMATS

    bat = sub.add_parser(
        "batch", help="reconstruct many leaves or scans: meshes and a trait table"
    )
    bat.add_argument("inputs", nargs="+", metavar="INPUT", help="files, folders or glob patterns")
    bat.add_argument("-o", "--output", required=True, metavar="OUTDIR", help="folder for meshes")
    bat.add_argument("--scans", action="store_true", help="inputs are 3D scans: extract first")
    bat.add_argument(
        "--traits", metavar="FILE", help=".csv, .json or .parquet (default OUTDIR/traits.csv)"
    )
    bat.add_argument("--format", choices=FORMATS, default="ply")
    _add_param_flags(bat)
    bat.add_argument("--jobs", type=int, default=None, help="worker processes (default: cores)")
    bat.add_argument(
        "--scheduler", metavar="ADDRESS", help="a Dask scheduler (tcp://HOST:PORT), or local"
    )
    bat.add_argument("--resume", action="store_true", help="skip inputs already done")
    bat.add_argument("--fail-fast", action="store_true", help="stop at the first failure")
    bat.add_argument(
        "--force",
        action="store_true",
        help="with --scans: go on with a cloud that does not look like one leaf (as extract "
        "--force: its problems become the row's warnings)",
    )


def _params_for(args: argparse.Namespace, base: object | None):
    """`base` (Params, else the defaults) with the parameter flags given (_add_param_flags)."""
    from leafstudio.model import PARAMS, Params

    params = base if isinstance(base, Params) else Params()
    changes = {name: getattr(args, name) for name in PARAMS}
    return params.with_(**{k: v for k, v in changes.items() if v is not None})


def _settings(args: argparse.Namespace):
    """Params from the command line, over a project's saved ones."""
    from leafstudio.sources.files import load_project

    saved = load_project(args.input)[1] if args.input.lower().endswith(".json") else None
    try:  # each flag is checked as it is read (_param_value): a bad one is the command line's
        return _params_for(args, saved)
    except LeafError as exc:
        raise LeafError(exc.problem, args.input) from None


def _run(args: argparse.Namespace, leaf: object):
    """The Params (see _settings) and the pipeline's Result; the run's notes are printed as
    warnings, and the chosen K when K is auto."""
    from leafstudio._shared.kernelcache import mark_cached
    from leafstudio.core.pipeline import Pipeline
    from leafstudio.core.prepare.plausibility import leaf_warnings

    params = _settings(args)
    _compiling_notice()
    try:  # the frame stage refuses a crossing boundary and keeps the largest of several loops
        result = Pipeline(leaf).run(params)
    except LeafError as exc:
        raise LeafError(exc.problem, args.input) from None
    mark_cached()
    args.warnings = [*leaf_warnings(leaf), *result.warnings]  # for --metrics
    for note in args.warnings:
        log.warning(f"{args.input}: {note}")
    if params.k == "auto":
        log.info(f"{args.input}: K = {result.chosen_k} (chosen by BIC)")
    return params, result


def _compiling_notice() -> None:
    """Say so when this run compiles the numerical kernels (the first run, about 20 s)."""
    from leafstudio._shared.kernelcache import kernels_cached

    if not kernels_cached():
        log.info("compiling the numerical kernels (the first run only; about 20 s)")


def _reconstruct(args: argparse.Namespace) -> int:
    """Read, check, compute everything, then write every output together (safewrite.staged):
    a run that fails anywhere leaves all old outputs as they were."""
    from leafstudio._shared.safewrite import check_outputs, staged, write_bytes
    from leafstudio.assets.export import save_mesh
    from leafstudio.assets.writers import MESH_SUFFIXES
    from leafstudio.render.figure import check_figure_path
    from leafstudio.sources.files import load_leaf

    out = Path(args.output)
    if not out.name.lower().endswith(MESH_SUFFIXES):
        raise LeafError(f"unknown mesh type; use one of {', '.join(MESH_SUFFIXES)}", str(out))
    figure = check_figure_path(args.figure) if args.figure else None
    from leafstudio.assets.export import asset_options, check_asset_options

    check_asset_options(args.texture, args.thickness, args.lod)
    from leafstudio.render.slides import check_turntable_path

    turntable = check_turntable_path(args.turntable) if args.turntable else None
    steps = check_figure_path(args.steps_figure) if args.steps_figure else None
    outputs = [out, args.metrics, figure, turntable, steps]  # every file this command writes
    check_outputs([args.input, *args.vein, args.against], outputs)
    leaf = load_leaf(args.input, veins=args.vein)
    scan = None
    if args.against:
        from leafstudio.sources.scan import read_scan

        scan = read_scan(args.against)
    params, result = _run(args, leaf)
    fidelity = None
    if scan is not None:
        from leafstudio.analysis.fidelity import scan_distances
        from leafstudio.sources.extract import split_scan

        blade = split_scan(scan)[0]
        fidelity = {
            "all": scan_distances(result.triangle_mesh, scan, result.length),
            "blade": scan_distances(result.triangle_mesh, scan[blade], result.length),
        }
    metrics = None
    if args.metrics:
        metrics = {
            "input": args.input,
            "params": params.to_dict(),
            "k": result.chosen_k,
            **result.metrics,
            "warnings": args.warnings,
        }
        if fidelity is not None:
            metrics["fidelity"] = {"scan": args.against, **fidelity}
    with staged():  # every output is written in this block; renamed over the old ones at its end
        options = asset_options(args.texture, args.thickness, args.lod, args.input, result.length)
        save_mesh(result, out, **options)
        if figure is not None:
            from leafstudio._shared.safewrite import replace_atomically
            from leafstudio.render.figure import render_figure

            replace_atomically(figure, lambda tmp: render_figure(result, tmp, args.colour_by))
        if metrics is not None:
            write_bytes(args.metrics, json.dumps(metrics, indent=2) + "\n")
        if turntable is not None or steps is not None:
            from leafstudio._shared.safewrite import replace_atomically
            from leafstudio.render.slides import render_steps, render_turntable

            if turntable is not None:
                replace_atomically(turntable, lambda tmp: render_turntable(result, tmp))
            if steps is not None:
                replace_atomically(steps, lambda tmp: render_steps(result, tmp))
    if fidelity is not None:
        for part, what in (("all", "all"), ("blade", "blade (no outliers, no petiole)")):
            f = fidelity[part]
            print(
                f"{args.against}: {what}: {f['points']} points to the surface: mean "
                f"{f['mean']:.4g}, median {f['median']:.4g}, 95% {f['p95']:.4g}, max "
                f"{f['max']:.4g}; beyond 1% of the leaf length {f['beyond_1pct']:.1%}, beyond 2% "
                f"{f['beyond_2pct']:.1%} (leaf length {result.length:.4g})"
            )
    return EXIT_OK


def _measure(args: argparse.Namespace) -> int:
    from leafstudio.core.measure import format_table, leaf_measurements
    from leafstudio.sources.files import load_leaf

    _, result = _run(args, load_leaf(args.input, veins=args.vein))
    values = leaf_measurements(result)
    if args.json:
        print(json.dumps({"input": args.input, **values}, indent=2))
    else:
        print(format_table(values))
    return EXIT_OK


def _compare(args: argparse.Namespace) -> int:
    from leafstudio.analysis.compare import compare, format_comparison
    from leafstudio.sources.files import load_leaf

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
    from leafstudio.sources.demos import demo
    from leafstudio.sources.files import save_leaf

    save_leaf(demo(args.name), args.output)
    return EXIT_OK


def _gui(args: argparse.Namespace) -> int:
    from leafstudio.gui.qt.app import run_app

    return run_app(getattr(args, "file", None), getattr(args, "screenshot", None))


def _extract(args: argparse.Namespace) -> int:
    from leafstudio.sources.files import check_leaf_output, save_leaf
    from leafstudio.workflows import open_scan

    check_leaf_output(args.output, [args.scan])
    opened = open_scan(args.scan, base_end=args.base_end, points=args.points, force=args.force)
    for note in opened.notes:
        log.warning(f"{args.scan}: {note}")
    found, scan = opened.extraction, opened.scan
    save_leaf(found.leaf, args.output)
    other = len(scan) - found.blade.sum() - found.petiole.sum()
    print(
        f"{args.scan}: blade of {found.blade.sum()} of {len(scan)} points (dropped: petiole "
        f"{found.petiole.sum()}, outliers and clutter {other}), length {found.length:.4g}; wrote "
        f"{len(found.leaf.boundary)} boundary points and {len(found.leaf.veins)} veins to "
        f"{args.output}"
    )
    return EXIT_OK


def _batch(args: argparse.Namespace) -> int:
    from leafstudio.batch import command

    args.params = _params_for(args, None)
    return command(args)


COMMANDS = {
    "gui": _gui,
    "reconstruct": _reconstruct,
    "demo": _demo,
    "extract": _extract,
    "measure": _measure,
    "compare": _compare,
    "batch": _batch,
    "form": lambda args: _forms_cli().run_form(args),
    "veins": lambda args: _forms_cli().run_veins(args),
    "photo": lambda args: _photo(args),
}


def _photo(args: argparse.Namespace) -> int:
    from leafstudio.cli.photo import run_photo

    return run_photo(args)


def _forms_cli():
    import leafstudio.cli.form as forms_cli

    return forms_cli


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
    from leafstudio._shared.safewrite import install_signal_cleanup

    argv = _join_dashed_values(list(sys.argv[1:] if argv is None else argv))
    debug = _debugging(argv)
    _configure_logging(0, 0)
    try:
        args = build_parser().parse_args(argv)
        _configure_logging(getattr(args, "verbose", 0) or 0, getattr(args, "quiet", 0) or 0)
        if (args.command or "gui") != "gui":  # the app's event loop keeps SIGTERM's default
            install_signal_cleanup()
        with warnings.catch_warnings():
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


if __name__ == "__main__":
    raise SystemExit(main())
