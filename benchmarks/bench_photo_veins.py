"""The photo reader's ridge filter (issue 23, item 6): its cost on a 1200-pixel photo and how
many times one photo runs it.

A form (ovate, cordate) with its veins drawn, photographed 1200 pixels wide with the leaf about
1000 pixels long (tests/photos.form_photo), is read with `leaf_from_photo`. Printed, as JSON:
the CPU time of one ridge filter (photo_veins.find_ridges: Sato on the blade's box, best of
three), how many times reading the photo ran it, and the whole read's CPU time (best of three).
CPU time, not wall time: the host is shared.
Run: `.venv/bin/python benchmarks/bench_photo_veins.py`.
"""

from __future__ import annotations

import json
import time

import numpy as np

from leafstudio.forms import make_form
from leafstudio.sources import photo_veins
from leafstudio.sources.photo import leaf_from_photo
from tests.photos import form_photo

SIZE = (1200, 980)
PIXELS_PER_UNIT = 1000.0
RUNS = 3


def _best_cpu(run) -> float:
    """The least CPU time of RUNS calls, in seconds."""
    best = np.inf
    for _ in range(RUNS):
        start = time.process_time()
        run()
        best = min(best, time.process_time() - start)
    return round(float(best), 3)


def _row(shape: str) -> dict:
    """One shape's photo: the ridge filter's cost, its runs per read, the whole read's cost."""
    leaf = make_form(shape)
    image, _, _ = form_photo(
        leaf.boundary, leaf.veins, angle=25.0, pixels_per_unit=PIXELS_PER_UNIT, size=SIZE
    )
    calls = []
    original = photo_veins.ridge_strength

    def counted(*args, **kwargs):
        calls.append(1)
        return original(*args, **kwargs)

    photo_veins.ridge_strength = counted
    try:
        found = leaf_from_photo(image, length=1.0)
    finally:
        photo_veins.ridge_strength = original
    box = photo_veins.find_ridges(image, found.blade).blade
    return {
        "photo": f"{SIZE[0]}x{SIZE[1]}",
        "blade box": f"{box.shape[1]}x{box.shape[0]}",
        "ridge filter cpu s": _best_cpu(lambda: photo_veins.find_ridges(image, found.blade)),
        "ridge filter runs per photo": len(calls),
        "read cpu s": _best_cpu(lambda: leaf_from_photo(image, length=1.0)),
        "veins from": found.veins_from,
    }


def main() -> dict:
    """One row per shape (ovate, cordate)."""
    return {shape: _row(shape) for shape in ("ovate", "cordate")}


if __name__ == "__main__":
    print(json.dumps(main(), indent=1))
