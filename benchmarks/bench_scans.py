"""Scans at scan scale (issue 10): `extract` on 1e5- and 1e6-point scans, and scan-to-mesh
distances for 20,000 points against a grid-512 mesh, ours beside open3d's raycasting.

Prints one JSON document:

- ``extract``: per size, a fresh interpreter reads a synthetic scan (the blade of the test's
  egg-shaped leaf on a curved surface, a petiole and outliers, written as .xyz) and extracts its
  leaf: seconds to read, seconds to extract, and peak RSS above the interpreter once leafstudio
  is imported (targets: 1e6 points under 5 s and 2 GB);
- ``scan_distances``: the largest real scan in ../shared/realleaves, reconstructed at grid 512,
  and 20,000 points drawn from it (jittered by 0.1% of its length): our median time, open3d's
  RaycastingScene (build and query) when it is installed, and the longest pause of a thread
  that ticks every millisecond while ours runs on another (the app's main thread beside its
  worker; target: under 16 ms), beside its longest pause while the other thread only sleeps
  (on a loaded host, the scheduler's share of it).

The machine is shared and its load varies: compare figures taken minutes apart with care.

Usage: ``.venv/bin/python benchmarks/bench_scans.py [--sizes 100000 1000000] [--repeats 5]``
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import warnings
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the synthetic scan of the tests

from bench_realleaves import SCANS  # noqa: E402

import leafstudio as ls  # noqa: E402
from leafstudio.core.distance import mesh_distances  # noqa: E402
from leafstudio.sources.extract import extract_leaf  # noqa: E402
from leafstudio.sources.scan import read_scan  # noqa: E402
from tests.sources.test_extract_scale import _big_scan  # noqa: E402

SIZES = (100_000, 1_000_000)
SCAN_POINTS = 20_000
REAL = SCANS / "soybean_11_20190508T043118_pot1_36.txt"  # the largest
TARGETS = {"extract_1e6_s": 5.0, "extract_1e6_mb": 2048.0, "main_thread_pause_ms": 16.0}

EXTRACT = """
import json, sys, time
def high_water_kb():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1])
import leafstudio
from leafstudio.sources.extract import extract_leaf
from leafstudio.sources.scan import read_scan
extract_leaf(read_scan(sys.argv[2]))  # compiled kernels loaded, as in a long-running app
imported = high_water_kb()
start = time.perf_counter()
points = read_scan(sys.argv[1])
read = time.perf_counter()
found = extract_leaf(points)
done = time.perf_counter()
print(json.dumps({"points": len(points), "read_s": round(read - start, 3),
                  "extract_s": round(done - read, 3), "total_s": round(done - start, 3),
                  "above_import_mb": round((high_water_kb() - imported) / 1024, 1),
                  "length": round(found.length, 4)}))
"""


def extract_figures(sizes: tuple[int, ...]) -> dict[str, Any]:
    """read + extract time and peak memory per scan size, each in a fresh interpreter."""
    out: dict[str, Any] = {}
    with tempfile.TemporaryDirectory() as folder:
        small = Path(folder) / "small.xyz"
        np.savetxt(small, _big_scan(2000)[0], fmt="%.6f")
        for size in sizes:
            path = Path(folder) / f"scan_{size}.xyz"
            np.savetxt(path, _big_scan(size)[0], fmt="%.6f")
            run = subprocess.run(
                [sys.executable, "-c", EXTRACT, str(path), str(small)],
                capture_output=True, text=True, check=True, timeout=1200,
            )  # fmt: skip
            out[f"{size:.0e}".replace("+0", "")] = json.loads(run.stdout.strip().splitlines()[-1])
    return out


def _longest_pause(work) -> tuple[float, float]:
    """`work()` on a thread while this one ticks every millisecond: (work's seconds, the longest
    gap between ticks in ms)."""
    gaps: list[float] = []
    done = threading.Event()
    took: list[float] = []

    def run() -> None:
        start = time.perf_counter()
        work()
        took.append(time.perf_counter() - start)
        done.set()

    thread = threading.Thread(target=run)
    last = time.perf_counter()
    thread.start()
    while not done.is_set():
        time.sleep(0.001)
        now = time.perf_counter()
        gaps.append(now - last)
        last = now
    thread.join()
    return took[0], 1e3 * max(gaps, default=0.0)


def distance_figures(repeats: int) -> dict[str, Any]:
    """Ours and open3d's distances from 20,000 scan points to a grid-512 mesh."""
    raw = read_scan(REAL)
    found = extract_leaf(raw)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mesh = ls.reconstruct(found.leaf, ls.Params(k=3, grid=512)).triangle_mesh
    rng = np.random.default_rng(0)
    jitter = rng.normal(0, 1e-3 * found.length, (SCAN_POINTS, 3))
    points = raw[rng.integers(0, len(raw), SCAN_POINTS)] + jitter
    vertices, triangles = mesh.points, mesh.regular_faces
    ours = mesh_distances(vertices, triangles, points)  # compiled kernels loaded
    runs = [_longest_pause(lambda: mesh_distances(vertices, triangles, points)) for _ in
            range(repeats)]  # fmt: skip
    out: dict[str, Any] = {
        "scan": REAL.name,
        "points": SCAN_POINTS,
        "mesh_triangles": len(triangles),
        "ours_ms": round(1e3 * statistics.median(t for t, _ in runs), 1),
        "ours_min_ms": round(1e3 * min(t for t, _ in runs), 1),
        "main_thread_longest_pause_ms": round(max(p for _, p in runs), 1),
    }
    # the same ticking beside a thread that only sleeps as long: the host's own jitter
    idle = [_longest_pause(partial(time.sleep, t))[1] for t, _ in runs]
    out["baseline_longest_pause_ms"] = round(max(idle), 1)
    try:
        import open3d as o3d
    except ImportError:
        out["open3d"] = "not installed"
        return out

    def raycast() -> np.ndarray:
        scene = o3d.t.geometry.RaycastingScene()
        scene.add_triangles(
            o3d.core.Tensor(vertices.astype(np.float32)),
            o3d.core.Tensor(triangles.astype(np.uint32)),
        )
        return scene.compute_distance(o3d.core.Tensor(points.astype(np.float32))).numpy()

    theirs = raycast()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        raycast()
        times.append(time.perf_counter() - start)
    out["open3d_ms"] = round(1e3 * statistics.median(times), 1)
    out["open3d_min_ms"] = round(1e3 * min(times), 1)
    out["open3d_over_ours"] = round(statistics.median(times) / statistics.median(
        t for t, _ in runs), 2)  # fmt: skip
    out["largest_difference_to_open3d"] = float(np.abs(theirs - ours).max())  # its float32
    return out


def scan_figures(repeats: int = 5, sizes: tuple[int, ...] = SIZES) -> dict[str, Any]:
    """Both parts, with the targets checked."""
    figures: dict[str, Any] = {
        "extract": extract_figures(sizes),
        "scan_distances": distance_figures(repeats),
    }
    big = figures["extract"].get("1e6")
    checks: dict[str, Any] = {}
    if big is not None:
        checks["extract_1e6_s"] = {"value": big["total_s"], "limit": TARGETS["extract_1e6_s"]}
        checks["extract_1e6_mb"] = {
            "value": big["above_import_mb"],
            "limit": TARGETS["extract_1e6_mb"],
        }
    pause = figures["scan_distances"]["main_thread_longest_pause_ms"]
    checks["main_thread_pause_ms"] = {"value": pause, "limit": TARGETS["main_thread_pause_ms"]}
    ratio = figures["scan_distances"].get("open3d_over_ours")
    if ratio is not None:
        checks["open3d_over_ours"] = {"value": ratio, "limit": 1.0, "ok": ratio >= 1.0}
    for check in checks.values():
        check.setdefault("ok", check["value"] <= check["limit"])
    figures["targets"] = checks
    return figures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="*", default=list(SIZES))
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    print(json.dumps(scan_figures(args.repeats, tuple(args.sizes)), indent=1))


if __name__ == "__main__":
    main()
