"""Base and apex of leaves from photos without a petiole: each gallery form drawn (tests/photos.py)
in several orientations, `leaf_from_photo` on it, and the found leaf compared with the known one
in the forms' convention (base at the origin, apex on +x, both at the same length). Prints JSON:
per form and angle the IoU in that frame (a wrong base turns the outline round, IoU ~0.6), the
IoU in the photo's pixels (segmentation alone) and the base's error as a share of the length.

    .venv/bin/python benchmarks/bench_photo_base.py [--angles 0 90 ...] [--forms cordate ...]
        [--variants N] [--plain] [--scans] [--petioles]

--variants N adds each form's seeds 1..N (other proportions); --plain draws the blades without
veins (then only the outline tells the base); --scans adds the real scans' renders, where the
base is known where the scan shows the petiole (left out of the render); --petioles adds 12
forms drawn with a petiole of 0.12 and 0.25 of the length at each angle (found? base? IoU?).

Angles: the form's base-to-apex direction in the photo, counter-clockwise from +x (0: base left,
90: base at the bottom, 180: base right, 270: base at the top).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np
import shapely

from leafstudio.sources.photo import leaf_from_photo
from tests.photos import leaf_frame_match

FORMS: dict[str, dict] = {  # name: make_form's arguments
    name: {"shape": name}
    for name in (
        "linear", "lanceolate", "oblanceolate", "elliptic", "oblong", "ovate", "obovate",
        "orbicular", "cordate", "reniform", "deltoid", "spatulate", "sagittate", "hastate",
    )
}  # fmt: skip
FORMS["ovate lobed"] = {"shape": "ovate", "margin": "lobed", "lobes": 5}
FORMS["cordate palmate lobed"] = {
    "shape": "cordate", "margin": "lobed", "lobes": 5, "venation": "palmate",
}  # fmt: skip
FORMS["orbicular palmate lobed"] = {
    "shape": "orbicular", "margin": "lobed", "lobes": 7, "venation": "palmate",
}  # fmt: skip
FORMS["obovate serrate"] = {"shape": "obovate", "margin": "serrate", "teeth": 30}
ANGLES = (0.0, 90.0, 180.0, 270.0, 35.0, -125.0)


def scan_rows() -> dict:
    """The real scans rendered from above (tests/photos.scan_photo): the pixel IoU and, where
    the scan shows its petiole (it is left out of the render), the found base's distance from
    where it met the blade, as a share of the found length."""
    from tests.photos import REALLEAVES, iou, scan_photo

    rows = {}
    for path in sorted(REALLEAVES.glob("*.txt")):
        image, known, base = scan_photo(path)
        found = leaf_from_photo(image, veins="none")
        at, apex = found.pixel_from_world @ [0, 0, 1], found.pixel_from_world @ [1, 0, 1]
        length = float(np.linalg.norm(apex - at))
        rows[path.name] = {
            "iou_pixels": round(iou(shapely.Polygon(found.outline_px).buffer(0), known), 4),
            "base_error": None
            if base is None
            else round(float(np.linalg.norm(at - base)) / length, 3),
            "base_cue": found.base_cue,
        }
    return rows


PETIOLE_SHAPES = (
    "linear", "lanceolate", "elliptic", "ovate", "obovate", "orbicular", "cordate", "reniform",
    "deltoid", "spatulate", "sagittate", "hastate",
)  # fmt: skip


def petiole_rows(angles: list[float]) -> dict:
    """Forms drawn with a petiole (0.12 and 0.25 of the length): whether it is found, the base's
    distance from the joint (share of the found length) and the pixel IoU; the cases where one
    of them misses (not found, base over 3%, IoU under 0.97) are listed."""
    from leafstudio.forms import make_form
    from tests.photos import form_photo, iou

    misses, count = [], 0
    for shape in PETIOLE_SHAPES:
        leaf = make_form(shape)
        for petiole in (0.12, 0.25):
            for angle in angles:
                image, known, base = form_photo(leaf.boundary, leaf.veins, angle, petiole=petiole)
                found = leaf_from_photo(image, veins="none")
                pixels_long = float(np.linalg.norm(found.pixel_from_world[:, 0]))
                error = float(np.linalg.norm(found.pixel_from_world @ [0, 0, 1] - base))
                overlap = iou(shapely.Polygon(found.outline_px).buffer(0), known)
                count += 1
                if not found.petiole or error > 0.03 * pixels_long or overlap < 0.97:
                    misses.append(
                        f"{shape} petiole {petiole} at {angle:g}: found {found.petiole}, base "
                        f"{error / pixels_long:.3f}, IoU {overlap:.3f}"
                    )
    return {"cases": count, "missed": len(misses), "misses": misses}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--angles", type=float, nargs="+", default=list(ANGLES))
    parser.add_argument("--forms", nargs="+", default=list(FORMS), choices=list(FORMS))
    parser.add_argument("--variants", type=int, default=0, help="also forms' seeds 1..N")
    parser.add_argument("--plain", action="store_true", help="draw the blades without veins")
    parser.add_argument("--scans", action="store_true", help="also the real scans' renders")
    parser.add_argument("--petioles", action="store_true", help="also forms with a petiole")
    args = parser.parse_args()
    rows, start, cpu = {}, time.perf_counter(), time.process_time()
    for name in args.forms:
        for variant in range(args.variants + 1):
            terms = dict(FORMS[name], seed=variant)
            rows[name if not variant else f"{name} seed {variant}"] = {
                f"{a:g}": leaf_frame_match(terms, a, draw_veins=not args.plain) for a in args.angles
            }
    cases = [r for per in rows.values() for r in per.values()]
    print(
        json.dumps(
            {
                "forms": rows,
                "scans": scan_rows() if args.scans else None,
                "petioles": petiole_rows(args.angles) if args.petioles else None,
                "cases": len(cases),
                "passed": sum(r["iou_leaf_frame"] >= 0.97 for r in cases),
                "base_within_2pct": sum(r["base_error"] < 0.02 for r in cases),
                "min_iou_leaf_frame": min(r["iou_leaf_frame"] for r in cases),
                "wall_s": round(time.perf_counter() - start, 1),
                "cpu_s": round(time.process_time() - cpu, 1),
                "load_average": [round(x, 2) for x in os.getloadavg()],
            },
            indent=1,
        )
    )


if __name__ == "__main__":
    main()
