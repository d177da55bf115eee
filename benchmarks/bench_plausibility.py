"""Whole scans given as a boundary (cover.surface_spread, refused over COVER_SPREAD): the
spread and verdict of each class of cloud, and the CPU cost of one call on a 10,000-point outline
and a 220,000-point cloud. Prints JSON.

    .venv/bin/python benchmarks/bench_plausibility.py [--before REV ...] [--repeats N]
        [--cases] [--table]

--before REV (repeatable) measures surface_spread as it was at git revision REV beside today's
(18be64f: before the two-strand and narrow-band looks; 760e578: two strands only). Each class
says what it should be ("surface": refused, "boundary": accepted; "boundary (most)": outlines
drawn past the range asked for, aspect up to 35 and noise up to 0.5%, where the two margins'
noise can merge into one filled band) and how many of its clouds get the other verdict
(`wrong`). --cases lists every cloud; --table prints a Markdown table instead
of JSON. The cost is the median of N calls' process (CPU) time, and wall time, in ms; the host's
load average is printed beside it, as the machine may be shared.
"""

from __future__ import annotations

import argparse
import importlib.util
import itertools
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from leafstudio.core.prepare import cover  # noqa: E402
from leafstudio.forms import make_form  # noqa: E402
from leafstudio.sources.scan import read_scan  # noqa: E402
from tests.core.prepare.test_scan_as_boundary import (  # noqa: E402
    SCANS,
    _dense_noisy,
    _strap,
    bent_filled_strip,
    bent_strap,
    narrow_striped_scan,
    random_narrow_outline,
    striped_scan,
)
from tests.leaves import true_boundaries  # noqa: E402


def _turn(seed: int) -> np.ndarray:
    return np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))[0]


def classes():
    """(class, what it should be, {case: cloud}) for each class of cloud."""
    scans = {path.stem[-22:]: read_scan(path) for path in SCANS}
    rng = np.random.default_rng(0)
    yield "real scans", "surface", scans
    yield (
        "real scans, half",
        "surface",
        {k: s[rng.choice(len(s), len(s) // 2, replace=False)] for k, s in scans.items()},
    )
    yield (
        "real scans, quarter",
        "surface",
        {k: s[rng.choice(len(s), len(s) // 4, replace=False)] for k, s in scans.items()},
    )
    yield (
        "real scans, turned",
        "surface",
        {
            f"{k} turn {seed}": s @ _turn(seed).T * 3 + 7
            for k, s in scans.items()
            for seed in (1, 2)
        },
    )
    yield (
        "striped scan",
        "surface",
        {f"spacing {s}": striped_scan(s) for s in (0.003, 0.005, 0.01, 0.02, 0.03)},
    )
    yield (
        "narrow striped scan",
        "surface",
        {
            f"spacing {s} {'along' if a else 'across'}": narrow_striped_scan(s, a)
            for s in (0.003, 0.005)
            for a in (True, False)
        },
    )
    yield (
        "straight filled strip",
        "surface",
        {f"aspect {a}": bent_filled_strip(20000, a, 0.0) for a in (25, 30)},
    )
    yield (
        "bent filled strip",
        "surface",
        {
            f"aspect {a} bend {b} n {n}": bent_filled_strip(n, a, b)
            for a in (25, 30)
            for b in (1.0, 2.0, 3.0)
            for n in (5000, 20000)
        },
    )
    yield (
        "bent narrow striped scan",
        "surface",
        {
            f"spacing {s} {'along' if a else 'across'} bend 2": narrow_striped_scan(s, a, 2.0)
            for s in (0.003, 0.005)
            for a in (True, False)
        },
    )
    yield "true boundaries", "boundary", dict(true_boundaries())
    yield (
        "narrow forms",
        "boundary",
        {
            f"{shape} aspect {a}": make_form(shape, aspect=a).boundary
            for shape in ("linear", "lanceolate")
            for a in (20, 25, 30)
        },
    )
    posed = itertools.product(
        ("linear", "lanceolate"),
        (20, 25, 30),
        (0.0, 0.5, 1.0, -1.0),
        (0.0, 30.0, 60.0),
        (0.0, 0.1),
        ("entire", "serrate"),
    )
    yield (
        "narrow forms, curl/fold/wave",
        "boundary",
        {
            f"{s} aspect {a} curl {c} fold {f} wave {w} {m}": make_form(
                s, aspect=a, curl=c, fold=f, wave=w, margin=m
            ).boundary
            for s, a, c, f, w, m in posed
        },
    )
    yield (
        "narrow straight outline",
        "boundary",
        {f"n {n} noise {s}": _strap(n, s) for n, s in [(2000, 0), (10000, 0.001), (20000, 0.004)]},
    )
    yield (
        "noisy toothed outline",
        "boundary",
        {
            f"{shape} {margin} noise {noise}": _dense_noisy(
                make_form(shape, margin=margin).boundary, 5000, noise
            )
            for shape in ("elliptic", "ovate")
            for margin in ("dentate", "serrate", "crenate", "lobed")
            for noise in (0.001, 0.003, 0.005)
        },
    )
    rng = np.random.default_rng(7)  # as the test draws them
    yield (
        "random narrow outline",
        "boundary",
        {f"seed 7 #{i}": random_narrow_outline(rng) for i in range(30)},
    )
    rng = np.random.default_rng(1)
    yield (
        "random narrow outline, wider range",
        "boundary (most)",
        {f"seed 1 #{i}": random_narrow_outline(rng, (20, 35), (0, 3.5), 0.005) for i in range(150)},
    )
    yield (
        "bent narrow outline",
        "boundary",
        {
            f"aspect {a} bend {b} n {n} noise {s}": bent_strap(n, a, b, s)
            for a in (25, 30)
            for b in (1.0, 2.0, 3.0)
            for n in (2000, 5000, 10000)
            for s in (0.0, 0.002, 0.004)
        },
    )


def _module_at(rev: str):
    """surface_spread's module as it was at git revision `rev` (core/prepare/cover.py, or
    before that
    core/prepare/plausibility.py), imported from a copy."""
    for name in ("cover", "plausibility"):
        shown = subprocess.run(
            ["git", "show", f"{rev}:leafstudio/core/{name}.py"],
            cwd=ROOT,
            capture_output=True,
            text=True,
        )
        if shown.returncode == 0:
            break
    else:
        raise SystemExit(f"no core/prepare/cover.py or core/prepare/plausibility.py at {rev}")
    path = Path(tempfile.mkdtemp()) / f"{name}_{rev}.py"
    path.write_text(shown.stdout)
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _cost(spread, cloud: np.ndarray, repeats: int) -> dict:
    cpu, wall = [], []
    for _ in range(repeats):
        start, start_cpu = time.perf_counter(), time.process_time()
        spread(cloud)
        cpu.append(1000 * (time.process_time() - start_cpu))
        wall.append(1000 * (time.perf_counter() - start))
    return {"cpu_ms": round(float(np.median(cpu)), 1), "wall_ms": round(float(np.median(wall)), 1)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--before", metavar="REV", action="append", default=[], help="also measure it at REV"
    )
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--cases", action="store_true", help="list every cloud's spread")
    parser.add_argument("--table", action="store_true", help="a Markdown table, not JSON")
    args = parser.parse_args()
    versions = {f"at {rev}": _module_at(rev) for rev in args.before} | {"now": cover}
    threshold = cover.COVER_SPREAD
    report: dict = {
        "command": " ".join([".venv/bin/python benchmarks/bench_plausibility.py", *sys.argv[1:]]),
        "threshold": threshold,
        "load_average_before": [round(x, 2) for x in os.getloadavg()],
        "classes": {},
    }
    for name, should, clouds in classes():
        entry: dict = {"should_be": should, "clouds": len(clouds)}
        for label, module in versions.items():
            spreads = {case: module.surface_spread(cloud) for case, cloud in clouds.items()}
            values = np.array(list(spreads.values()))
            refused = int(np.sum(values > threshold))
            entry[label] = {
                "spread_min": round(float(values.min()), 3),
                "spread_max": round(float(values.max()), 3),
                "refused": refused,
                "wrong": len(values) - refused if should == "surface" else refused,
            }
            if args.cases:
                entry[label]["cases"] = {k: round(v, 3) for k, v in spreads.items()}
        report["classes"][name] = entry
    scan = read_scan(SCANS[-2]) if SCANS else striped_scan(0.01)
    rng = np.random.default_rng(0)
    clouds = {
        "outline 10,000 points (bent, aspect 30, noise 0.4%)": bent_strap(10000, 30, 1.0, 0.004),
        "scan 220,000 points (a real scan, 30 jittered copies)": np.vstack(
            [scan + rng.normal(0, 1e-3 * np.ptp(scan), scan.shape) for _ in range(30)]
        ),
    }
    report["cost_per_call"] = {
        name: {label: _cost(m.surface_spread, cloud, args.repeats) for label, m in versions.items()}
        for name, cloud in clouds.items()
    }
    report["load_average_after"] = [round(x, 2) for x in os.getloadavg()]
    print(_table(report, list(versions)) if args.table else json.dumps(report, indent=1))


def _table(report: dict, labels: list[str]) -> str:
    """The report as Markdown: spread range and wrong verdicts per class, then the cost."""
    lines = [
        f"`{report['command']}` (refused over {report['threshold']}; load average "
        f"{report['load_average_before']} -> {report['load_average_after']})",
        "",
        "| class | should be | clouds | " + " | ".join(labels) + " |",
        "|---|---|---|" + "---|" * len(labels),
    ]
    for name, entry in report["classes"].items():
        cells = [
            f"{v['spread_min']:.2f}-{v['spread_max']:.2f}, wrong {v['wrong']}"
            for v in (entry[label] for label in labels)
        ]
        lines.append(f"| {name} | {entry['should_be']} | {entry['clouds']} | {' | '.join(cells)} |")
    lines += ["", "| CPU (wall) ms per call | " + " | ".join(labels) + " |"]
    lines.append("|---|" + "---|" * len(labels))
    for name, cost in report["cost_per_call"].items():
        cells = [f"{cost[label]['cpu_ms']} ({cost[label]['wall_ms']})" for label in labels]
        lines.append(f"| {name} | {' | '.join(cells)} |")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
