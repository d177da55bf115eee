"""Leaf analysis on the paper's two leaves: our surface beside screened Poisson (Fig. 10), the
automatic K against the paper's K, and the cost of curvature and measurements. Prints JSON.

    .venv/bin/python benchmarks/bench_analysis.py [--grid N]

Times are wall seconds on this machine after a warm-up run (the first run of a process includes
imports and compilation); compare's are of one run, curvature's and measure's the best of
--repeat.
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from functools import partial

import leafstudio as ls
from leafstudio.analysis.compare import compare
from leafstudio.core.curvature import surface_curvatures
from leafstudio.core.evaluate import leaf_measurements
from leafstudio.sources.demos import PAPER_K


def _best_time(function, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        function()
        best = min(best, time.perf_counter() - start)
    return best


def _distances(result) -> dict[str, float]:
    m = result.metrics
    return {"veins_mean": m["veins"]["mean"], "veins_max": m["veins"]["max"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--grid", type=int, default=128)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    out = {"grid": args.grid}
    for name, paper_k in PAPER_K.items():
        leaf = ls.demo(name)
        params = ls.Params(k=paper_k, grid=args.grid)
        ls.Pipeline(leaf).run(params)  # warm up: imports and compiled kernels
        report = compare(leaf, params)
        meshes = report.pop("meshes")
        pipe = ls.Pipeline(leaf)
        paper = pipe.run(params)
        auto = pipe.run(params.with_(k="auto"))
        xy, _ = paper.frame.to_plane(paper.mesh.points)
        out[name] = {
            "compare": {
                side: {
                    "boundary_max": r["boundary"]["max"],
                    "veins_mean": r["veins"]["mean"],
                    "veins_max": r["veins"]["max"],
                    "area": r["mesh"]["area"],
                    "spill": r["spill"],
                    "seconds": r["seconds"],
                }
                for side, r in report.items()
            },
            "auto_k": {
                "chosen": auto.chosen_k,
                "paper_k": paper_k,
                "auto": _distances(auto),
                "paper": _distances(paper),
                "seconds_auto": _best_time(
                    partial(ls.Pipeline(leaf).run, params.with_(k="auto")), 1
                ),
            },
            "curvature": {
                "vertices": int(paper.mesh.n_points),
                "seconds": _best_time(partial(surface_curvatures, paper.surface, xy), args.repeat),
            },
            "measure_seconds": _best_time(partial(leaf_measurements, paper), args.repeat),
            "poisson_triangles": len(meshes["poisson"].regular_faces),
        }
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
