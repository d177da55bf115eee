"""The margin of extract's outlines on the real scans: how far the boundary points lie from the
mesh, the margin's creases and the blade's distance to the mesh, with the margin chosen by the
measured noise (auto) and with the points kept exactly (exact).

    .venv/bin/python benchmarks/bench_extract_margin.py [--grid 128]

Prints one JSON line per scan and margin; figures are shares of the leaf length and degrees.
"""

from __future__ import annotations

import argparse
import json
import warnings
from pathlib import Path

import leafstudio as ls
from leafstudio.analysis.fidelity import scan_distances
from leafstudio.core.evaluate import margin_creases
from leafstudio.sources.extract import extract_leaf
from leafstudio.sources.scan import read_scan

REALLEAVES = Path(__file__).resolve().parents[2] / "shared" / "realleaves"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grid", type=int, default=128)
    grid = parser.parse_args().grid
    warnings.simplefilter("ignore")
    for path in sorted(REALLEAVES.glob("*.txt")):
        scan = read_scan(path)
        found = extract_leaf(scan)
        for margin in ("auto", "exact"):
            result = ls.reconstruct(found.leaf, ls.Params(grid=grid, margin=margin))
            mesh, length = result.triangle_mesh, result.length
            boundary = scan_distances(mesh, found.leaf.boundary, length)
            blade = scan_distances(mesh, scan[found.blade], length)
            creases = margin_creases(result)
            row = {
                "scan": path.name,
                "margin": margin,
                "boundary_mean": boundary["mean"] / length,
                "boundary_max": boundary["max"] / length,
                "crease_margin_p99": creases["margin_p99"],
                "crease_interior_p99": creases["interior_p99"],
                "blade_mean": blade["mean"] / length,
            }
            rounded = {k: round(v, 5) if isinstance(v, float) else v for k, v in row.items()}
            print(json.dumps(rounded))


if __name__ == "__main__":
    main()
