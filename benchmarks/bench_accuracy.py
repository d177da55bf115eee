"""The core issue's accuracy figures: Table-1 distances, mesh facts and coverage on the demos (both
meshers, the paper's K, grid 128) and on the harder test leaves, as JSON.

    .venv/bin/python benchmarks/bench_accuracy.py [--grid N]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # for tests.leaves

import leafstudio as ls
from leafstudio.sources.demos import PAPER_K
from tests import leaves

PAPER_TABLE1 = {
    "nested": {"boundary_mean": 4.25e-3, "boundary_max": 8.77e-3, "vein_mean": 9.77e-3},
    "parallel": {"boundary_mean": 17.37e-3, "boundary_max": 31.98e-3, "vein_mean": 11.41e-3},
}


def table1_figures(metrics: dict) -> dict:
    """The issue's figures from Result.metrics: Table-1 distances and mesh facts, flat."""
    return {
        "boundary_mean": metrics["boundary"]["mean"],
        "boundary_max": metrics["boundary"]["max"],
        "vein_mean": metrics["veins"]["mean"],
        "vein_max": metrics["veins"]["max"],
        "components": metrics["mesh"]["components"],
        "boundary_loops": metrics["mesh"]["boundary_loops"],
        "non_manifold_edges": metrics["mesh"]["non_manifold_edges"],
    }


def _figures(result: ls.Result, region, rot=None, shift=None) -> dict:
    covered, spilled = leaves.coverage(result, region, rot, shift)
    return {
        **table1_figures(result.metrics),
        "covered": covered,
        "spilled": spilled,
        "seconds": sum(result.timings.values()),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--grid", type=int, default=128)
    grid = parser.parse_args().grid
    out: dict[str, dict] = {}
    for name in ("nested", "parallel"):
        params = ls.Params(k=PAPER_K[name], grid=grid)
        region = leaves.halfwidth_region(name)
        for mesher in ("conforming", "bpa"):
            result = ls.Pipeline(ls.demo(name)).run(params.with_(mesher=mesher))
            out[f"{name}/{mesher}"] = {**_figures(result, region), "paper": PAPER_TABLE1[name]}
        leaf, rot, shift = leaves.moved(ls.demo(name))
        out[f"{name}/moved"] = _figures(ls.Pipeline(leaf).run(params), region, rot, shift)
        out[f"{name}/noisy"] = _figures(ls.Pipeline(leaves.noisy(name)).run(params), region)
    leaf, region = leaves.lobed()
    out["lobed/k6"] = _figures(ls.Pipeline(leaf).run(ls.Params(k=6, grid=grid)), region)
    leaf, region = leaves.narrow()
    out["narrow/k3"] = _figures(ls.Pipeline(leaf).run(ls.Params(k=3, grid=grid)), region)
    stamp = time.strftime("%Y-%m-%d %H:%M")
    print(json.dumps({"grid": grid, "time": stamp, "cases": out}, indent=1))


if __name__ == "__main__":
    main()
