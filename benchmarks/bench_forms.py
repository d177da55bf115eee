"""Leaf forms: the time to make a form, to grow veins in a 200-point outline, to draw a thumbnail.

Run: `QT_QPA_PLATFORM=offscreen .venv/bin/python benchmarks/bench_forms.py`. Prints JSON: for each
measurement the median over repeats (milliseconds), and the slowest case. The issue's targets: a
form and a vein growth each under 50 ms, so the gallery feels instant. Timings are shared-host
figures: other work on the machine moves them.
"""

from __future__ import annotations

import json
import os
import statistics
import time

import numpy as np

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

REPEATS = 5
_APP = None


CPU: list[float] = []  # the process's CPU time of every measurement, beside its wall time


def _ms(call, repeats: int = REPEATS) -> float:
    """Median wall time of `call` in ms; its median CPU time goes to CPU (a loaded host stretches
    wall time, much less CPU time)."""
    times, cpu = [], []
    for _ in range(repeats):
        start, start_cpu = time.perf_counter(), time.process_time()
        call()
        times.append(1000 * (time.perf_counter() - start))
        cpu.append(1000 * (time.process_time() - start_cpu))
    CPU.append(statistics.median(cpu))
    return statistics.median(times)


def _cpu_median(count: int) -> float:
    """The median CPU time of the last `count` measurements."""
    return statistics.median(CPU[-count:])


def _resampled(xy: np.ndarray, count: int) -> np.ndarray:
    ring = np.vstack([xy, xy[:1]])
    s = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(ring, axis=0), axis=1))])
    t = np.linspace(0, s[-1], count, endpoint=False)
    return np.column_stack([np.interp(t, s, ring[:, 0]), np.interp(t, s, ring[:, 1])])


def main() -> dict:
    from PySide6.QtGui import QGuiApplication

    import leafstudio as ls
    from leafstudio.forms import SHAPES, VENATION_KINDS, Form, grow_veins

    global _APP
    _APP = QGuiApplication.instance() or QGuiApplication([])  # QPainter needs one; kept to exit
    from leafstudio.gui.qt.forms_dock import draw_leaf

    Form("ovate").leaf()  # imports and first calls out of the way
    forms = {name: _ms(lambda n=name: Form(n).leaf()) for name in SHAPES}
    forms_cpu = _cpu_median(len(forms))
    variants = {
        "ovate serrate 60 teeth": _ms(lambda: Form("ovate", margin="serrate", teeth=60).leaf()),
        "orbicular lobed 7 palmate": _ms(
            lambda: Form("orbicular", margin="lobed", lobes=7, venation="palmate").leaf()
        ),
        "lanceolate arcuate": _ms(lambda: Form("lanceolate", venation="arcuate").leaf()),
    }
    outlines = {
        "nested demo": _resampled(ls.demo("nested").boundary[:, :2], 200),
        "ovate form": _resampled(Form("ovate").outline().xy, 200),
    }
    veins = {
        f"{name}, {kind}": _ms(lambda o=outline, k=kind: grow_veins(o, k))
        for name, outline in outlines.items()
        for kind in VENATION_KINDS
    }
    veins_cpu = _cpu_median(len(veins))
    leaves = {name: Form(name).leaf() for name in SHAPES}
    draw = {name: _ms(lambda leaf=leaf: draw_leaf(leaf, 84)) for name, leaf in leaves.items()}
    report = {
        "units": f"milliseconds, median of {REPEATS} runs",
        "make_form": {
            "median_over_shapes": statistics.median(forms.values()),
            "median_over_shapes_cpu": forms_cpu,
            "slowest": max(forms.items(), key=lambda kv: kv[1]),
            "per_shape": forms,
            "variants": variants,
        },
        "grow_veins_200_points": {
            "median": statistics.median(veins.values()),
            "median_cpu": veins_cpu,
            "slowest": max(veins.items(), key=lambda kv: kv[1]),
            "cases": veins,
        },
        "thumbnail_84px": {
            "draw_median": statistics.median(draw.values()),
            "form_and_draw_median": statistics.median(forms.values())
            + statistics.median(draw.values()),
        },
        "targets": {"make_form": 50, "grow_veins_200_points": 50},
        "note": "shared host: other work on the machine moves these figures",
    }
    return report


if __name__ == "__main__":
    print(json.dumps(main(), indent=2), flush=True)
