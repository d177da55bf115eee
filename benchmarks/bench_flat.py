"""A flat leaf's reconstruction time at grid 128, against a reference checkout (issue 21: "flat
leaves no slower than today", today being the code before it, 45d60f1).

    .venv/bin/python benchmarks/bench_flat.py [--reference DIR ...] [--rounds 5] [--runs 20]
                                              [--shapes ovate,oblanceolate,cordate,...]

Each round times this checkout, then each reference (a worktree of another commit, run with its own
code by PYTHONPATH; --reference may be given more than once), each in a fresh interpreter:
`ls.reconstruct` of the same flat gallery leaves (made here, by this checkout's forms, and passed
to all as points, so all reconstruct the same input: the forms' vein heights changed since issue
21), K 3, grid 128, the default Params (through the veins, where the checkout has it). Each process
warms up once per shape, then runs `--runs` times; the tables give the minimum and the median wall
time over all rounds, in milliseconds, and the same of CPU time (the process's: the pipeline runs
on one thread, so on a quiet host the two agree, and on a loaded one CPU time strays less), and
this checkout's over the first reference's. They alternate round by round: a shared host's load
falls on all alike. Without --reference, this checkout alone.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SHAPES = ("ovate", "oblanceolate", "cordate", "elliptic", "hastate", "linear")

# runs in the checkout's own interpreter (its code by PYTHONPATH): prints {shape: [(wall, CPU)]}
TIMED = """
import json, sys, time, warnings
import numpy as np
import leafstudio as ls
warnings.simplefilter("ignore")
saved, runs = np.load(sys.argv[1]), int(sys.argv[2])
times = {}
for shape in sys.argv[3].split(","):
    count = int(saved[shape + ":veins"])
    leaf = ls.Leaf(saved[shape + ":boundary"], [saved[f"{shape}:{i}"] for i in range(count)])
    ls.reconstruct(leaf, ls.Params(k=3, grid=128))
    times[shape] = []
    for _ in range(runs):
        wall, cpu = time.perf_counter(), time.process_time()
        ls.reconstruct(leaf, ls.Params(k=3, grid=128))
        times[shape].append((time.perf_counter() - wall, time.process_time() - cpu))
print(json.dumps(times))
"""


def save_leaves(shapes: list[str], path: Path) -> None:
    """This checkout's flat gallery leaves as points, for every checkout to read."""
    from leafstudio.forms.make import Form

    arrays: dict[str, np.ndarray] = {}
    for shape in shapes:
        leaf = Form(shape).leaf()
        arrays[shape + ":boundary"] = np.asarray(leaf.boundary)
        arrays[shape + ":veins"] = np.array(len(leaf.veins))
        for i, vein in enumerate(leaf.veins):
            arrays[f"{shape}:{i}"] = np.asarray(vein)
    np.savez(path, **arrays)


def timed(
    checkout: Path, leaves: Path, runs: int, shapes: list[str]
) -> dict[str, list[list[float]]]:
    """Wall and CPU seconds of each shape's reconstruct, in a fresh interpreter running
    `checkout`."""
    python = checkout / ".venv" / "bin" / "python"
    env = dict(os.environ, PYTHONPATH=str(checkout), PYTHONDONTWRITEBYTECODE="1")
    out = subprocess.run(
        [str(python if python.exists() else sys.executable), "-c", TIMED, str(leaves),
         str(runs), ",".join(shapes)],
        cwd=checkout, env=env, capture_output=True, text=True, check=True,
    )  # fmt: skip
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--reference", type=Path, action="append", default=[], help="another checkout"
    )
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--runs", type=int, default=20, help="timed runs per round and shape")
    parser.add_argument("--shapes", default=",".join(SHAPES))
    args = parser.parse_args()
    shapes = args.shapes.split(",")
    checkouts = {"this": ROOT} | {str(path): path for path in args.reference}
    times: dict[str, dict[str, list[list[float]]]] = {n: {s: [] for s in shapes} for n in checkouts}
    with tempfile.TemporaryDirectory() as tmp:
        leaves = Path(tmp) / "leaves.npz"
        save_leaves(shapes, leaves)
        for _ in range(args.rounds):
            for name, checkout in checkouts.items():
                for shape, seconds in timed(checkout, leaves, args.runs, shapes).items():
                    times[name][shape] += seconds
    for column, clock in enumerate(("wall", "CPU")):  # CPU: less of a loaded host's noise
        print(f"\n## flat leaves, K 3, grid 128: {clock} ms, min / median of "
              f"{args.rounds} x {args.runs}")  # fmt: skip
        ratio = " | this over the first reference (min / median) |" if args.reference else " |"
        print("| shape | " + " | ".join(checkouts) + ratio)
        print("|---|" + "---|" * (len(checkouts) + bool(args.reference)))
        for shape in shapes:
            cells = [[run[column] for run in times[name][shape]] for name in checkouts]
            row = [f"{1e3 * min(t):.1f} / {1e3 * float(np.median(t)):.1f}" for t in cells]
            if args.reference:
                this, ref = cells[:2]
                row.append(f"{min(this) / min(ref):.2f} / {np.median(this) / np.median(ref):.2f}")
            print(f"| {shape} | " + " | ".join(row) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
