"""Fidelity on the real leaf scans in ../shared/realleaves: extract boundary and veins from each
scan, reconstruct at grid 128, and measure the distance from the scan's blade points to the
surface and the coverage of the outline. Prints JSON: per scan and the mean over usable scans.

    .venv/bin/python benchmarks/bench_realleaves.py [--k K] [--grid N] [--mesher M] [SCAN ...]

Each scan is scaled to leaf length 1 (the blade's extent along its main axis), so the distances
are shares of the leaf length. "Usable" scans are those where extraction and reconstruction
succeed. Reference figures are printed beside ours: a flat plane through the boundary
(flat_plane_mean) and the base surface through the boundary's heights without the veins' relief
(base_only_mean).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import leafstudio as ls
from leafstudio.analysis.fidelity import coverage, scan_distances
from leafstudio.errors import LeafError
from leafstudio.sources.extract import extract_leaf
from leafstudio.sources.scan import read_scan

SCANS = Path(__file__).resolve().parents[2] / "shared" / "realleaves"


def _flat(result: ls.Result, points: np.ndarray) -> float:
    """Mean distance from the points to the boundary's PCA plane (the flat reference)."""
    return float(np.abs(result.frame.to_plane(points)[1]).mean())


def _base_only(result: ls.Result, points: np.ndarray) -> float:
    """Mean distance from the points to the base surface alone (no vein relief): what the GMM
    adds on top of the boundary's heights."""
    base = result.surface.base
    mesh = result.mesh.copy()
    xy, z = result.frame.to_plane(np.asarray(mesh.points))
    n = len(result.polygon)  # the outline keeps its own heights
    z[n:] = base(xy[n:]) if base is not None else 0.0
    mesh.points = result.frame.to_world(xy, z)
    return scan_distances(mesh, points, 1.0)["mean"]


def measure(path: Path, params: ls.Params) -> dict:
    """The figures for one scan."""
    raw = read_scan(path)
    start = time.perf_counter()
    ex = extract_leaf(raw)
    extract_s = time.perf_counter() - start
    scale = 1.0 / ex.length
    leaf = ls.Leaf(boundary=ex.leaf.boundary * scale, veins=[v * scale for v in ex.leaf.veins])
    blade = raw[ex.blade] * scale
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = ls.reconstruct(leaf, params)
    reconstruct_s = time.perf_counter() - start
    return {
        "scan": path.name,
        "points": len(raw),
        "blade_points": int(ex.blade.sum()),
        "petiole_points": int(ex.petiole.sum()),
        "veins": len(leaf.veins),
        "distance": scan_distances(result.mesh, blade, 1.0),
        "coverage": coverage(result.mesh, result.frame, result.polygon),
        "flat_plane_mean": _flat(result, blade),
        "base_only_mean": _base_only(result, blade),
        "seconds": {"extract": round(extract_s, 3), "reconstruct": round(reconstruct_s, 3)},
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scans", nargs="*", type=Path)
    parser.add_argument("--k", type=int, default=3)
    parser.add_argument("--grid", type=int, default=128)
    parser.add_argument("--mesher", default="conforming", choices=("conforming", "bpa"))
    args = parser.parse_args()
    params = ls.Params(k=args.k, grid=args.grid, mesher=args.mesher)
    paths = args.scans or sorted(SCANS.glob("*.txt"))
    rows, failed = [], {}
    for path in paths:
        try:
            rows.append(measure(path, params))
        except LeafError as exc:
            failed[path.name] = str(exc)
    keys = ("mean", "median", "p95", "max", "beyond_1pct", "beyond_2pct")
    summary = {
        "params": params.to_dict(),
        "usable": len(rows),
        "failed": failed,
        "mean": {k: float(np.mean([r["distance"][k] for r in rows])) for k in keys},
        "flat_plane_mean": float(np.mean([r["flat_plane_mean"] for r in rows])),
        "base_only_mean": float(np.mean([r["base_only_mean"] for r in rows])),
        "coverage_min": min(r["coverage"]["covered"] for r in rows),
        "outside_max": max(r["coverage"]["outside"] for r in rows),
        "pieces_max": max(r["coverage"]["pieces"] for r in rows),
    }
    json.dump({"scans": rows, "summary": summary}, sys.stdout, indent=1)
    print()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
