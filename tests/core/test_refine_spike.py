"""The refinement after EM keeps its mixture only if no grid node ends much farther off than
the linear fit left it (surface.REFINE_WORST): a K typed past the slider's 12 (the panel takes
up to 64) refined a component narrow onto a node or two, a spike several times the leaf's
relief that the summed cost did not see (bug hunt, session 27)."""

from __future__ import annotations

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.forms.make import Form


@pytest.mark.parametrize(("shape", "k", "seed"), [("ovate", 48, 2), ("reniform", 40, 0)])
def test_a_high_k_makes_no_spike_far_above_the_leaf(shape, k, seed):
    """ovate K 48 rose to 4.2 times its veins' highest point, reniform K 40 to 3.5 times; the
    linear fit alone, kept now, to 1.5 and 1.3 times."""
    leaf = Form(shape).leaf()
    relief = max(float(np.abs(v[:, 2]).max()) for v in leaf.veins)
    result = ls.reconstruct(leaf, ls.Params(k=k, grid=128, seed=seed))
    assert np.asarray(result.triangle_mesh.points)[:, 2].max() < 2.0 * relief
