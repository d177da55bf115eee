"""CPU time of the two sources the suite and batch runs use most: `extract_leaf` on each shared
scan in ../shared/realleaves and `leaf_from_photo` on gallery forms drawn as photos
(tests/photos.form_photo), each the best of N runs of time.process_time (one thread: run it
with OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1, the script sets them when it starts Python).

    .venv/bin/python benchmarks/bench_sources.py [--repeats N] [--only scans|photos]
        [--dump OUT.npz] [--compare BEFORE.npz AFTER.npz] [--profile OUT.prof]

--dump writes every case's outputs (boundary, veins, masks, pixel map) to one .npz, and
--compare prints, per case, the largest difference between two dumps (0 when the outputs are
identical; a mask's flipped point counts 1), also as a share of the boundary's extent, and
exits 1 when a case's arrays differ in shape. --profile runs each case once, then once more
under cProfile (CPU time), and writes the stats. Prints JSON: seconds per case and totals.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import json
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np

SCANS = Path(__file__).resolve().parents[2] / "shared" / "realleaves"
# (shape, form terms, petiole, angle, veins): the tests' mix of petioles, angles and vein modes
PHOTOS = [
    ("ovate", {}, 0.25, 25.0, "none"),
    ("lanceolate", {}, 0.0, -60.0, "none"),
    ("elliptic", {"margin": "serrate", "teeth": 30}, 0.25, 100.0, "none"),
    ("obovate", {}, 0.0, 170.0, "none"),
    ("cordate", {}, 0.12, 60.0, "none"),
    ("elliptic", {"apex": "acuminate"}, 0.0, 45.0, "none"),
    ("ovate", {}, 0.0, 25.0, "auto"),
    ("cordate", {}, 0.0, 100.0, "auto"),
    ("lanceolate", {}, 0.0, 25.0, "trace"),
    ("obovate", {}, 0.0, 100.0, "auto"),
    ("orbicular", {"venation": "palmate"}, 0.0, 10.0, "auto"),
]


def _scan_cases() -> dict[str, Callable[[], dict[str, np.ndarray]]]:
    """name: a call extracting one shared scan, returning its outputs."""
    from leafstudio.sources.extract import extract_leaf
    from leafstudio.sources.scan import read_scan

    cases = {}
    for path in sorted(SCANS.glob("*.txt")):
        points = read_scan(path)

        def run(points=points) -> dict[str, np.ndarray]:
            found = extract_leaf(points)
            out = {"boundary": found.leaf.boundary, "blade": found.blade,
                   "petiole": found.petiole, "length": np.array(found.length)}  # fmt: skip
            out.update({f"vein{k}": v for k, v in enumerate(found.leaf.veins)})
            return out

        parts = path.stem.split("_")
        cases[f"scan:{parts[0]}_{parts[-2]}_{parts[-1]}"] = run
    return cases


def _photo_cases() -> dict[str, Callable[[], dict[str, np.ndarray]]]:
    """name: a call reading one drawn form's photo, returning its outputs."""
    from leafstudio.forms import make_form
    from leafstudio.sources.photo import leaf_from_photo
    from tests.photos import form_photo

    cases = {}
    for shape, terms, petiole, angle, veins in PHOTOS:
        leaf = make_form(shape, **terms)
        image = form_photo(leaf.boundary, leaf.veins, angle=angle, petiole=petiole)[0]

        def run(image=image, veins=veins) -> dict[str, np.ndarray]:
            found = leaf_from_photo(image, veins=veins)
            out = {"boundary": found.leaf.boundary, "pixel_from_world": found.pixel_from_world,
                   "blade": found.blade, "outline_px": found.outline_px}  # fmt: skip
            out.update({f"vein{k}": v for k, v in enumerate(found.leaf.veins)})
            return out

        name = f"photo:{shape}{'+' if terms else ''}:{angle:g}:p{petiole:g}:{veins}"
        cases[name] = run
    return cases


def compare(before: Path, after: Path) -> int:
    """Print each case's largest difference between two dumps; 1 when shapes or keys differ."""
    a, b = np.load(before), np.load(after)
    bad = 0
    cases = sorted({k.split("|")[0] for k in a.files} | {k.split("|")[0] for k in b.files})
    for case in cases:
        keys_a = {k for k in a.files if k.split("|")[0] == case}
        keys_b = {k for k in b.files if k.split("|")[0] == case}
        if keys_a != keys_b:
            print(f"{case}: outputs differ: {sorted(keys_a ^ keys_b)}")
            bad = 1
            continue
        worst, where = 0.0, ""
        size = float(np.ptp(a[f"{case}|boundary"], axis=0).max())
        for key in sorted(keys_a):
            x, y = a[key], b[key]
            if x.shape != y.shape:
                print(f"{case}: {key.split('|')[1]} shape {x.shape} -> {y.shape}")
                bad = 1
                continue
            diff = float(np.max(np.abs(x.astype(float) - y.astype(float)))) if x.size else 0.0
            if diff > worst:
                worst, where = diff, key.split("|")[1]
        print(f"{case}: max difference {worst:.3g}, {worst / size:.2g} of the leaf's size"
              + (f" ({where})" if where else ""))  # fmt: skip
    return bad


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--only", choices=("scans", "photos"))
    parser.add_argument("--match", default="", help="only cases whose name holds this")
    parser.add_argument("--dump", type=Path)
    parser.add_argument("--compare", type=Path, nargs=2)
    parser.add_argument("--profile", type=Path)
    args = parser.parse_args()
    if args.compare:
        return compare(*args.compare)
    warnings.simplefilter("ignore")
    cases = {}
    if args.only != "photos":
        cases.update(_scan_cases())
    if args.only != "scans":
        cases.update(_photo_cases())
    cases = {k: v for k, v in cases.items() if args.match in k}
    if args.profile:
        import cProfile

        profiler = cProfile.Profile(time.process_time)
        for run in cases.values():  # once first: imports and caches out of the profile
            run()
        for run in cases.values():
            profiler.runcall(run)
        profiler.dump_stats(args.profile)
        return 0
    seconds, dump = {}, {}
    for name, run in cases.items():
        best = np.inf
        for _ in range(args.repeats):
            start = time.process_time()
            out = run()
            best = min(best, time.process_time() - start)
        seconds[name] = round(best, 3)
        dump.update({f"{name}|{k}": np.asarray(v) for k, v in out.items()})
    totals = {
        "scans": round(sum(v for k, v in seconds.items() if k.startswith("scan:")), 3),
        "photos": round(sum(v for k, v in seconds.items() if k.startswith("photo:")), 3),
    }
    print(json.dumps({"cpu_seconds": seconds, "totals": totals}, indent=1))
    if args.dump:
        np.savez_compressed(args.dump, **dump)
    return 0


if __name__ == "__main__":
    sys.exit(main())
