"""A leaf given in 3D with the bend that lays it flat (core/unfold.py), found once per curves.

Curves found to need no bend are remembered (UNBENT_KEPT of them, by their bytes): a file's leaf
is unfolded when opened (workflows.open_file) and again by its Pipeline, and a waved blade,
fitted and refused, took 0.5-1.4 s of CPU each time.
"""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict

import numpy as np

from leafstudio.core.unfold import fit_pose
from leafstudio.core.unfold_checks import bent
from leafstudio.model import Leaf

UNBENT_KEPT = 32  # curves remembered as needing no bend
_UNBENT: OrderedDict[bytes, None] = OrderedDict()
_UNBENT_LOCK = threading.Lock()  # pipelines run on worker threads too


def unfolded(leaf: Leaf) -> Leaf:
    """`leaf` with the bend `fit_pose` finds for it; the leaf itself when none is needed (and
    then remembered: the module docstring)."""
    if leaf.bend is not None:
        return leaf
    digest = hashlib.blake2b(digest_size=16)
    for curve in (leaf.boundary, *leaf.veins):
        digest.update(np.ascontiguousarray(curve, dtype=float).tobytes() + b"|")
    key = digest.digest()
    with _UNBENT_LOCK:
        if key in _UNBENT:
            return leaf
    bend = fit_pose(leaf)
    if bend is not None:
        return Leaf(leaf.boundary, leaf.veins, bend=bend)
    with _UNBENT_LOCK:
        _UNBENT[key] = None
        while len(_UNBENT) > UNBENT_KEPT:
            _UNBENT.popitem(last=False)
    return leaf


def unposed_hint(leaf: Leaf) -> str:
    """What to add to a refusal of `leaf` as `unfolded` left it: when its margin stands bent in
    3D (unfold_checks.bent, the test before a pose is fitted) and no bend lays it flat (none
    given, none fitted), that it may be a posed or scanned leaf written without its pose or
    sheet (a lanceolate form twisted 1, saved as .csv, was refused with "vein 1: 2 of 49 points
    lie outside the boundary" and no word of why); "" otherwise."""
    if leaf.bend is not None or not bent(np.asarray(leaf.boundary, dtype=float)):
        return ""
    return (
        "; the leaf is bent in 3D and no pose lays it flat: a posed or scanned leaf saved as a "
        "point list keeps neither its pose nor its sheet (its .leaf.json does)"
    )
