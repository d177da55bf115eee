"""Sparse clouds given as a boundary (cover.filled_share, refused over FILL_SHARE): the share of
surrounded points of each class of outline and of area-filling cloud, too sparse for
surface_spread, and the margin between the worst outline and the least area. Prints JSON.

    .venv/bin/python benchmarks/bench_fill.py [--cases]

Outlines: the scan test's true boundaries, every gallery form (shape x margin), each subsampled to
100-300 points (in order, shuffled, with noise of 0.25%, 0.5% and 1% of its length), and the real
scans' extracted boundaries (when ../shared/realleaves is there). Areas: discs, hemispheres, caps,
flattened blobs and points inside forms' outlines, 100-700 points, and real scans thinned to
100-400 points. A cloud dense enough for surface_spread scores 0 and is left out.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from leafstudio.core.prepare.cover import FILL_FROM, FILL_SHARE, filled_share  # noqa: E402
from leafstudio.forms import SHAPES, make_form  # noqa: E402
from leafstudio.forms.terms import MARGINS  # noqa: E402
from leafstudio.sources.scan import read_scan  # noqa: E402
from tests import leaves  # noqa: E402  (the tests' builders: outlines and areas)

REAL = ROOT.parent / "shared" / "realleaves"
SCANS = sorted(REAL.glob("*.txt")) if REAL.is_dir() else []

NOISES = (0.0025, 0.005, 0.01)


def outlines():
    """(class, case, points) of outlines that must pass."""
    for name, points in leaves.true_boundaries():
        yield "true boundaries", name, points
    rng = np.random.default_rng(5)
    for shape in SHAPES:
        for margin in MARGINS:
            outline = make_form(shape, margin=margin).boundary
            yield "forms", f"{shape} {margin}", outline
            length = np.ptp(outline[:, 0])
            for n in (100, 120, 150, 200, 300):
                kept = outline[np.sort(rng.choice(len(outline), n, replace=False))]
                yield "forms subsampled", f"{shape} {margin} {n}", kept
                yield "forms subsampled", f"{shape} {margin} {n} shuffled", rng.permutation(kept)
                for noise in NOISES:
                    jitter = rng.normal(size=(n, 3)) * [noise * length, noise * length, 0]
                    yield (
                        f"forms subsampled, noise {noise:.2%}",
                        f"{shape} {margin} {n}",
                        rng.permutation(kept) + jitter,
                    )
    for path in SCANS:
        boundary = leaves.extracted_scan(path)[1].leaf.boundary
        yield "real scans' extracted boundaries", path.stem, boundary


def areas():
    """(class, case, points) of clouds that fill an area."""
    for n in (100, 120, 150, 200, 300, 400, 700):
        yield "discs", f"{n}", leaves.disc(n, n)
        for height in (1.0, 0.5, 0.3):
            yield "hemispheres and caps", f"height {height} {n}", leaves.cap(n, height, n)
        for flat in (0.05, 0.2, 0.3, 0.5):
            yield "flattened blobs", f"flat {flat} {n}", leaves.blob(n, flat, n)
        for shape in ("elliptic", "linear", "cordate", "lanceolate"):
            yield "points inside a form", f"{shape} {n}", leaves.filled_form(shape, n, n)
    rng = np.random.default_rng(11)
    for path in SCANS:
        scan = read_scan(path)
        for n in (100, 120, 150, 200, 400):
            yield "real scans thinned", f"{path.stem} {n}", scan[rng.choice(len(scan), n, False)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", action="store_true", help="list every cloud's share")
    args = parser.parse_args()
    report: dict = {"threshold": FILL_SHARE, "from_points": FILL_FROM, "classes": {}}
    worst: dict = {}
    for should, clouds in (("outline", outlines()), ("area", areas())):
        for name, case, points in clouds:
            share = filled_share(points)
            if share == 0.0 and should == "area":
                continue  # dense enough for surface_spread (or too few points)
            entry = report["classes"].setdefault(name, {"should_be": should, "cases": {}})
            entry["cases"][case] = round(share, 3)
            key = (should, name.endswith("noise 1.00%"))
            better = max if should == "outline" else min
            if key not in worst or better(share, worst[key][0]) == share:
                worst[key] = (share, f"{name}: {case}")
    for entry in report["classes"].values():
        values = list(entry["cases"].values())
        entry |= {"clouds": len(values), "min": min(values), "max": max(values)}
        wrong = [v > FILL_SHARE if entry["should_be"] == "outline" else v <= FILL_SHARE
                 for v in values]  # fmt: skip
        entry["wrong"] = int(sum(wrong))
        if not args.cases:
            del entry["cases"]
    report["worst outline (noise up to 0.5%)"] = worst[("outline", False)]
    report["worst outline (noise 1%)"] = worst.get(("outline", True))
    report["least area"] = worst[("area", False)]
    print(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
