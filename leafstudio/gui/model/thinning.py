"""Fewer points of a big input where the app only shows or approximates it (numpy only).

The views draw at most DISPLAY_POINTS of a point layer: software OpenGL (Mesa llvmpipe) spends
main-thread time on every point of every render, about 2 µs each here (a 2M-point scan took
7-10 s a render, and as long again at each layer toggle or camera move). A loaded leaf's derived
sketch keeps a thinned relief and follows a thinned outline (sketch_model.Sketch.from_result),
which its editor queries on the main thread at every edit. Every computation (the pipeline, the
scan's distances, exports) takes the input whole.
"""

from __future__ import annotations

import numpy as np

DISPLAY_POINTS = 25_000  # a point layer draws at most this many points
INPUT_POINTS = 5000  # the input's boundary and veins together: a dotted outline needs fewer


def thinned(points: np.ndarray, budget: int = DISPLAY_POINTS, ordered: bool = False) -> np.ndarray:
    """At most `budget` of the (n, d) points, for what only shows or approximates them.

    Along a curve (`ordered`) they are spread evenly by index; from a cloud a fixed random subset
    is taken (a scan's rows often come in scan lines, which a stride would band), in the file's
    order.
    """
    n = len(points)
    if n <= budget:
        return points
    if ordered:
        return points[np.unique(np.linspace(0, n - 1, budget).round().astype(np.int64))]
    keep = np.random.default_rng(0).choice(n, size=budget, replace=False)
    return points[np.sort(keep)]
