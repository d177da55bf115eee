"""`leafstudio batch`: the command-line side of leafstudio.batch (a progress bar, each failure's
line, one summary line, the exit code)."""

from __future__ import annotations

import argparse
import logging
import sys
import time
from typing import TYPE_CHECKING

from leafstudio.assets.units import UNITS_SAID
from leafstudio.batch.settings import FORMATS
from leafstudio.cli.options import add_param_flags, compiling_notice, log, params_for
from leafstudio.cli.options import summary as closing

if TYPE_CHECKING:
    from leafstudio.batch.run import Batch


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The `batch` subcommand: many inputs, a worker pool or a Dask cluster (leafstudio/batch)."""
    bat = sub.add_parser("batch", help="reconstruct many leaves or scans: meshes and a trait table")
    bat.add_argument("inputs", nargs="+", metavar="INPUT", help="files, folders or glob patterns")
    bat.add_argument("-o", "--output", required=True, metavar="OUTDIR", help="folder for meshes")
    bat.add_argument("--scans", action="store_true", help="inputs are 3D scans: extract first")
    bat.add_argument(
        "--traits", metavar="FILE", help=".csv, .json or .parquet (default OUTDIR/traits.csv)"
    )
    bat.add_argument("--format", choices=FORMATS, default="ply")
    bat.add_argument(
        "--length",
        metavar="L",
        help=f"each leaf's real length, base to apex ({UNITS_SAID}): "
        "the meshes at real size and the traits in millimetres",
    )
    add_param_flags(bat)
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


SCAN_HINT = "`leafstudio extract"  # in the refusal of a scan given as a leaf file


def summary(run: Batch, seconds: float, warned: int = 0) -> str:
    """The one line printed at the end of a batch; `warned`: the rows run that carry warnings
    (a scan's poor fit, a vein off the plane), each said in a line of its own as it finished."""
    ok = run.ok + run.resumed
    ran = run.ok + run.failed
    noted = f" ({warned} with warnings: the table's warnings column)" if warned else ""
    inputs = "input" if run.total == 1 else "inputs"
    parts = [f"{run.total} {inputs}: {ok} ok{noted}, {run.failed} failed"]
    if run.resumed:
        parts.append(f"{run.resumed} already done")
    if ok + run.failed < run.total:
        parts.append(f"{run.total - ok - run.failed} not run")
    if run.stopped:
        parts.append("stopped at the first failure")
    rate = ran / seconds if seconds > 0 else 0.0
    return (
        f"leafstudio: batch: {', '.join(parts)}; {seconds:.1f} s ({rate:.2f} per second); "
        f"table {run.table.path}"
    )


def run(args: argparse.Namespace) -> int:
    """`leafstudio batch`: run the batch with a progress bar on stderr (when it is a terminal),
    each failure's line and each warned row's warnings (one line, as the table has them) as it
    happens and one summary line. Exit 0, or 1 if any input failed."""
    from tqdm import tqdm

    from leafstudio.batch.run import batch  # heavy (the workers' pipeline): not for --help

    running = batch(
        args.inputs,
        params_for(args, None),
        args.output,
        scans=args.scans,
        traits=args.traits,
        format=args.format,
        jobs=args.jobs,
        scheduler=args.scheduler,
        resume=args.resume,
        fail_fast=args.fail_fast,
        force=args.force,
        length=args.length,
    )
    if args.scheduler is None and running.total:
        compiling_notice()  # the local pool compiles the kernels before its first row
    start = time.perf_counter()
    bar = tqdm(
        total=running.total,
        file=sys.stderr,
        disable=not sys.stderr.isatty(),
        unit="leaf",
        dynamic_ncols=True,
        desc="leafstudio batch",
    )
    scans = 0  # rows refused as scans of whole leaves, whose hint is `leafstudio extract`
    warned = 0  # ok rows with warnings: said as reconstruct says them (qa37: the table only)
    try:
        with bar:
            for row in running.run():
                if row["status"] != "ok":
                    scans += SCAN_HINT in str(row["error"]) and not args.scans
                    internal = str(row["error"]).startswith("internal error:")
                    bar.write(
                        f"leafstudio: {'' if internal else 'error: '}{row['error']}", sys.stderr
                    )
                elif row.get("warnings"):
                    warned += 1
                    if log.isEnabledFor(logging.WARNING):  # -q -q hides them
                        line = f"leafstudio: warning: {row['input']}: {row['warnings']}"
                        bar.write(line, sys.stderr)
                bar.set_postfix(failed=running.failed, refresh=False)
                bar.update(1)
    except KeyboardInterrupt:
        print(f"{summary(running, time.perf_counter() - start, warned)}; interrupted (--resume "
              "goes on)",
              file=sys.stderr)  # fmt: skip
        raise
    # silenced by -q, as form's, extract's and slides' closing lines are (options.summary): it
    # printed all the same (review32b); a failed row's error is said above, the exit code is 1
    closing(summary(running, time.perf_counter() - start, warned))
    if scans:
        print(f"leafstudio: batch: {scans} of the inputs look like scans of whole leaves: --scans "
              "extracts and reconstructs them", file=sys.stderr)  # fmt: skip
    return 1 if running.failed else 0
