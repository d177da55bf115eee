"""Boundary clouds as scanners give them (issue 10, part A): how fast, how much memory, how smooth.

Prints one JSON document (bench_pipeline.py adds it under "clouds"):

- ``boundaries``: whole cold runs at grid 128 of an ovate leaf (a midrib of 40 points) whose
  boundary has 10^4, 5·10^4, 10^5 and 10^6 points along it at random spacing, in order and
  shuffled: median and minimum milliseconds, the frame stage's, and the outline's alone
  (outline.trace_outline, within the frame stage);
- ``linear``: the time per point at 10^6 over that at 10^4, from the minimum times (at most 1 is
  linear or better);
- ``memory_1e6``: peak RSS of a shuffled 10^6-point run in a fresh interpreter, above a bare one;
- ``noisy_margin``: for boundary noise of 0.2%, 0.5% and 1% of the length (x, y and z, 4,000
  shuffled points) at grids 128 and 256, the 99th-percentile dihedral angle within 3 grid steps
  of the margin and farther in (analysis.margin_creases), the boundary points' mean distance to
  the mesh over σ, and the projected area's error;
- ``targets``: the issue's.

Usage: ``.venv/bin/python benchmarks/bench_clouds.py [--repeats 5] [--quick]`` (--quick: up to
10^5 points, no memory run). Times depend on the host's load: quote them with it.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
import warnings
from typing import Any

import numpy as np
import shapely

import leafstudio as ls
from leafstudio.core.evaluate import margin_creases
from leafstudio.core.prepare.outline import trace_outline

SIZES = (10_000, 50_000, 100_000, 1_000_000)
NOISES = (0.002, 0.005, 0.01)
TARGET_50K_SHUFFLED_MS = 150.0
TARGET_1E6_MS = 3000.0
TARGET_1E6_MB = 1024.0


def ovate_leaf(n: int, shuffled: bool, sigma: float = 0.0, seed: int = 0) -> ls.Leaf:
    """An ovate leaf of length 1: `n` boundary points at random places along it, noise σ in x,
    y and z, in order or shuffled; a midrib of 40 points rising to 0.04."""
    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(0, 2 * np.pi, n))
    x = 0.5 - 0.5 * np.cos(t)
    boundary = np.column_stack([x, 0.3 * np.sin(t) * (1 - 0.4 * x), np.zeros(n)])
    boundary += rng.normal(0, sigma, boundary.shape) if sigma > 0 else 0.0
    if shuffled:
        boundary = rng.permutation(boundary)
    s = np.linspace(0.05, 0.95, 40)
    return ls.Leaf(boundary, [np.column_stack([s, 0 * s, 0.04 * np.sin(np.pi * s)])])


def ovate_area() -> float:
    t = np.linspace(0, 2 * np.pi, 20_000)
    x = 0.5 - 0.5 * np.cos(t)
    return float(shapely.Polygon(np.column_stack([x, 0.3 * np.sin(t) * (1 - 0.4 * x)])).area)


def _ms(samples: list[float]) -> dict[str, float]:
    return {
        "median": round(1e3 * statistics.median(samples), 1),
        "min": round(1e3 * min(samples), 1),
    }


def boundaries(sizes: tuple[int, ...], repeats: int) -> dict[str, Any]:
    """Cold grid-128 runs, ordered and shuffled."""
    params = ls.Params(k=2, grid=128)
    ls.Pipeline(ovate_leaf(2000, True)).run(params)  # compiled kernels loaded
    out: dict[str, Any] = {}
    for n in sizes:
        for shuffled in (False, True):
            leaf = ovate_leaf(n, shuffled)
            totals, frames = [], []
            for _ in range(repeats if n <= 100_000 else max(1, repeats // 3)):
                start = time.perf_counter()
                result = ls.Pipeline(leaf).run(params)
                totals.append(time.perf_counter() - start)
                frames.append(result.timings["frame"])
            xy, z = result.frame.to_plane(leaf.boundary)
            traces = []
            for _ in range(max(1, repeats // 3)):
                start = time.perf_counter()
                trace_outline(xy, z)
                traces.append(time.perf_counter() - start)
            out[f"{'shuffled' if shuffled else 'ordered'}_{n}"] = {
                "total_ms": _ms(totals),
                "frame_ms": _ms(frames)["median"],
                "outline_ms": _ms(traces)["median"],  # trace_outline alone, in the frame stage
            }
    return out


PEAK_RSS = """
import json, sys
sys.path.insert(0, {path!r})
from bench_clouds import ovate_leaf
import leafstudio as ls
def high_water_kb():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1])
leaf = ovate_leaf(1_000_000, True)
ls.Pipeline(leaf).run(ls.Params(k=2, grid=128))
print(json.dumps(high_water_kb()))
"""

BARE = """
for line in open("/proc/self/status"):
    if line.startswith("VmHWM:"):
        print(int(line.split()[1]))
"""


def memory_1e6() -> dict[str, float]:
    """Peak RSS (MB) of a shuffled 10^6-point run in a fresh interpreter, above a bare one."""

    def run(code: str) -> int:
        out = subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=600
        )
        return int(out.stdout.strip().splitlines()[-1])

    bare = run(BARE)
    peak = run(PEAK_RSS.format(path=str(__import__("pathlib").Path(__file__).parent)))
    return {"peak_mb": round(peak / 1024, 1), "above_bare_mb": round((peak - bare) / 1024, 1)}


def noisy_margin(grids: tuple[int, ...] = (128, 256)) -> dict[str, Any]:
    """Creases, distances and area of noisy margins (4,000 shuffled points)."""
    area = ovate_area()
    out: dict[str, Any] = {}
    for sigma in NOISES:
        leaf = ovate_leaf(4000, True, sigma=sigma, seed=3)
        for grid in grids:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                result = ls.reconstruct(leaf, ls.Params(k=2, grid=grid))
            creases = margin_creases(result)
            m = result.metrics
            out[f"noise_{sigma}_grid_{grid}"] = {
                **{k: round(v, 2) for k, v in creases.items()},
                "boundary_mean_over_sigma": round(m["boundary"]["mean"] / sigma, 3),
                "area_error": round(m["leaf"]["projected_area"] / area - 1, 5),
            }
    return out


def targets(report: dict[str, Any]) -> dict[str, Any]:
    checks: dict[str, Any] = {}
    b = report["boundaries"]
    if "shuffled_50000" in b:
        value = b["shuffled_50000"]["total_ms"]["median"]
        checks["shuffled_50k_ms"] = {
            "value": value, "limit": TARGET_50K_SHUFFLED_MS, "ok": value < TARGET_50K_SHUFFLED_MS
        }  # fmt: skip
    for order in ("ordered", "shuffled"):
        if f"{order}_1000000" in b:
            value = b[f"{order}_1000000"]["total_ms"]["median"]
            checks[f"{order}_1e6_ms"] = {"value": value, "limit": TARGET_1E6_MS,
                                         "ok": value < TARGET_1E6_MS}  # fmt: skip
    for order, ratio in report.get("linear", {}).items():
        checks[f"linear_{order}"] = {"value": ratio, "limit": 1.0, "ok": ratio <= 1.0}
    if "memory_1e6" in report:
        value = report["memory_1e6"]["above_bare_mb"]
        checks["memory_1e6_mb"] = {"value": value, "limit": TARGET_1E6_MB,
                                   "ok": value < TARGET_1E6_MB}  # fmt: skip
    for key, entry in report["noisy_margin"].items():
        ok = entry["margin_p99"] <= 2 * entry["interior_p99"] and entry["margin_p99"] < 10
        checks[f"creases_{key}"] = {"margin": entry["margin_p99"], "ok": ok}
        checks[f"on_data_{key}"] = {"value": entry["boundary_mean_over_sigma"], "limit": 1.5,
                                    "ok": entry["boundary_mean_over_sigma"] <= 1.5}  # fmt: skip
        if key.startswith(("noise_0.002", "noise_0.005")):
            checks[f"area_{key}"] = {"value": entry["area_error"], "limit": 0.01,
                                     "ok": abs(entry["area_error"]) <= 0.01}  # fmt: skip
    return checks


def clouds(repeats: int = 5, quick: bool = False) -> dict[str, Any]:
    """Every figure above, as one dict."""
    sizes = tuple(n for n in SIZES if not quick or n <= 100_000)
    report: dict[str, Any] = {"boundaries": boundaries(sizes, repeats)}
    b = report["boundaries"]
    if f"ordered_{sizes[-1]}" in b and sizes[-1] > sizes[0]:
        report["linear"] = {
            order: round(
                b[f"{order}_{sizes[-1]}"]["total_ms"]["min"]  # the minimum: a load spike on
                / b[f"{order}_{sizes[0]}"]["total_ms"]["min"]  # one small run skews a median
                / (sizes[-1] / sizes[0]),
                3,
            )
            for order in ("ordered", "shuffled")
        }
    if not quick:
        report["memory_1e6"] = memory_1e6()
    report["noisy_margin"] = noisy_margin()
    report["targets"] = targets(report)
    return report


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="runs per figure (median)")
    parser.add_argument("--quick", action="store_true", help="up to 1e5 points, no memory run")
    args = parser.parse_args()
    print(json.dumps(clouds(args.repeats, args.quick), indent=1))


if __name__ == "__main__":
    main()
