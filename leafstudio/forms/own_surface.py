"""A form's own surface: the heights its veins were lifted to, everywhere on its flat blade.

A form knows its surface exactly (issue 21: the mesh is measured against it, bench_bent.py):
its dome (relief.py) made in the blade's own frame, base at the origin and apex at (1, 0),
scaled back by the base-to-apex distance (veins.grow_veins lifts the veins so), on its wave's
base (make.Form.leaf: the margin's wave under it).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
from shapely.geometry import Polygon

from leafstudio.core.base import fit_base
from leafstudio.forms.blade import Blade
from leafstudio.forms.relief import dome
from leafstudio.forms.veins import HEIGHT_RATIO

if TYPE_CHECKING:
    from leafstudio.forms.make import Form


def own_heights(form: Form) -> Callable[[np.ndarray], np.ndarray]:
    """The form's own surface over its flat blade (unposed): (n, 2) or (n, 3) points in the
    blade's plane -> (n,) heights."""
    outline = form.outline()
    xy = outline.xy
    apex = xy[outline.apex_index]  # the base is at the origin
    length = float(np.linalg.norm(apex))
    along = apex / length
    across = np.array([-along[1], along[0]])

    def local(at: np.ndarray) -> np.ndarray:
        return np.column_stack([at @ along, at @ across]) / length

    rise = dome(Blade(Polygon(local(xy))), HEIGHT_RATIO, np.zeros(2), form.base_term == "rounded")
    base = fit_base(xy, form._wave(outline), 1.0)

    def heights(at: np.ndarray) -> np.ndarray:
        at = np.asarray(at, dtype=float)[:, :2]
        return length * rise(local(at)) + (0.0 if base is None else base(at))

    return heights
