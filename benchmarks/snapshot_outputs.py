"""Snapshot every command's outputs, to show that a change of layout changed no result.

Runs the command line (its contract does not change when the code moves) on the built-in demos,
a set of gallery forms and the real scans in ``../shared/realleaves``, and writes one JSON: for
each output file its SHA-256 (meshes, leaves) or its numbers (metrics, measurements, traits; times
left out). Run it before and after a change and compare the two files::

    python benchmarks/snapshot_outputs.py before.json            # on the old checkout
    python benchmarks/snapshot_outputs.py after.json
    python benchmarks/snapshot_outputs.py --compare before.json after.json

``--compare`` prints each differing entry and exits 1 if any differ. LEAFSTUDIO_SCANS names
another folder of scans.
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
SCANS = Path(os.environ.get("LEAFSTUDIO_SCANS", ROOT.parent / "shared" / "realleaves"))
FORMS = [
    ["ovate"],
    ["cordate", "--margin", "serrate", "--teeth", "24"],
    ["lanceolate", "--venation", "parallel"],
    ["orbicular", "--venation", "palmate"],
    ["elliptic", "--fold", "40"],
    ["linear", "--curl", "0.4"],
    ["obovate", "--margin", "lobed", "--lobes", "5"],
]
TIMING_KEYS = ("seconds", "time", "elapsed", "duration")


def _cli(*args: str) -> subprocess.CompletedProcess:
    """Run `python -m leafstudio ARGS`, failing loudly if the command fails."""
    done = subprocess.run(
        [sys.executable, "-m", "leafstudio", "-q", *args], capture_output=True, text=True
    )
    if done.returncode != 0:
        raise SystemExit(f"leafstudio {' '.join(args)} failed: {done.stderr.strip()}")
    return done


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _numbers(value: Any) -> Any:
    """The JSON value with timings dropped, floats rounded to 9 significant digits and the
    run's temporary folder named OUT."""
    if isinstance(value, dict):
        return {k: _numbers(v) for k, v in value.items() if not any(t in k for t in TIMING_KEYS)}
    if isinstance(value, list):
        return [_numbers(v) for v in value]
    if isinstance(value, float):
        return float(f"{value:.9g}")
    if isinstance(value, str):
        return re.sub(r"/\S*?/tmp\w+/", "OUT/", value.replace(str(SCANS), "SCANS"))
    return value


def _reconstruct(leaf: Path, out: Path, name: str, snap: dict, *extra: str) -> None:
    mesh, metrics = out / f"{name}.ply", out / f"{name}.metrics.json"
    _cli("reconstruct", str(leaf), "-o", str(mesh), "--metrics", str(metrics), *extra)
    snap[f"{name}.ply"] = _sha(mesh)
    snap[f"{name}.metrics"] = _numbers(json.loads(metrics.read_text()))


def snapshot(out: Path) -> dict[str, Any]:
    """Run every command once on the fixed inputs; return what they wrote."""
    snap: dict[str, Any] = {}
    for demo in ("nested", "parallel"):
        leaf = out / f"{demo}.leaf.json"
        _cli("demo", demo, "-o", str(leaf))
        snap[f"demo {demo}"] = _sha(leaf)
        _reconstruct(leaf, out, demo, snap)
        _reconstruct(leaf, out, f"{demo}-k-auto", snap, "--k", "auto", "--grid", "96")
        glb = out / f"{demo}.glb"
        _cli("reconstruct", str(leaf), "-o", str(glb), "--grid", "64")
        snap[f"{demo}.glb"] = _sha(glb)
        measured = _cli("measure", str(leaf), "--json").stdout
        snap[f"measure {demo}"] = _numbers(json.loads(measured))
    for i, terms in enumerate(FORMS):
        leaf = out / f"form{i}.leaf.json"
        _cli("form", *terms, "-o", str(leaf))
        snap[f"form {' '.join(terms)}"] = _sha(leaf)
        _reconstruct(leaf, out, f"form{i}", snap, "--grid", "96")
    scans = sorted(SCANS.glob("*.txt"))
    if not scans:
        raise SystemExit(f"no scans in {SCANS}")
    for scan in scans:
        leaf = out / f"{scan.stem}.leaf.json"
        _cli("extract", str(scan), "-o", str(leaf))
        snap[f"extract {scan.stem}"] = _sha(leaf)
        _reconstruct(leaf, out, scan.stem, snap, "--grid", "96", "--against", str(scan))
    batch_dir = out / "batch"
    _cli(
        "batch",
        str(out / "nested.leaf.json"),
        str(out / "parallel.leaf.json"),
        "-o",
        str(batch_dir),
        "--grid",
        "64",
    )
    with open(batch_dir / "traits.csv", newline="") as table:
        rows = [
            {k: v for k, v in row.items() if k not in ("seconds", "mesh", "input")}
            for row in csv.DictReader(table)
        ]
    snap["batch traits"] = rows
    return snap


def compare(before: dict[str, Any], after: dict[str, Any]) -> list[str]:
    """The keys whose values differ (or are missing on one side)."""
    return [key for key in sorted(set(before) | set(after)) if before.get(key) != after.get(key)]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("output", nargs="?", help="the snapshot JSON to write")
    parser.add_argument("--compare", nargs=2, metavar=("BEFORE", "AFTER"))
    args = parser.parse_args()
    if args.compare:
        before, after = (json.loads(Path(p).read_text()) for p in args.compare)
        differing = compare(before, after)
        for key in differing:
            print(f"differs: {key}")
        print(f"{len(before)} entries before, {len(after)} after, {len(differing)} differ")
        return 1 if differing else 0
    if not args.output:
        parser.error("give the snapshot file to write, or --compare BEFORE AFTER")
    with tempfile.TemporaryDirectory() as tmp:
        snap = snapshot(Path(tmp))
    Path(args.output).write_text(json.dumps(snap, indent=1, sort_keys=True))
    print(f"{len(snap)} outputs written to {args.output}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    raise SystemExit(main())
