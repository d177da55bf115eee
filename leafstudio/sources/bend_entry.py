"""A project's "bend" entry read (sources/files.py), and projects of format version 1 read as
they were meant.

Version 1 saved a posed leaf's boundary and veins bent by a fold and a curl that were shears
of the blade (z += |y| tan(fold), z += curl · x²: a fold of 60° doubled the blade's width in 3D).
Version 2's are turns that keep the blade's size (core/bend.py). A version 1 project's curves
are laid flat by the shear they were bent with and bent again by the same fold and curl, so
the blade the user drew is the one they get back.
"""

from __future__ import annotations

import contextlib
import json
import math
import warnings
from dataclasses import replace
from typing import Any

import numpy as np

from leafstudio.core.bend import Pose, sheared_flatten
from leafstudio.core.placed import PlacedPose
from leafstudio.core.plane import Frame
from leafstudio.core.pose_limits import FOLD, MOST_TURN, pose_trouble
from leafstudio.core.pose_relief import Relief
from leafstudio.core.sheet_bend import Scaled
from leafstudio.errors import LeafError, shorten
from leafstudio.model import Leaf


def project_bend(value: Any, source: str, leaf: Leaf, version: int) -> Leaf:
    """`leaf` with the bend of a project's "bend" entry `value` (a format `version` 1 project's
    curves bent again: `rebent`). A pose past what it keeps of the blade is refused, in one line
    naming the term, its value and its range on this blade (core/pose_limits.py)."""
    leaf = replace(leaf, bend=_bend(value, source, leaf))
    leaf = rebent(leaf) if version == 1 else leaf
    trouble = pose_trouble(leaf.bend, leaf.boundary, list(leaf.veins))
    if trouble is not None:
        raise LeafError(f'"bend": {trouble}', source)
    return leaf


FRAME_KEYS = ("origin", "u", "v", "normal")  # a bend's frame in a project (core/placed.py)


def _bend(value: Any, source: str, leaf: Leaf) -> Pose | PlacedPose | Scaled:
    """A project's "bend": {"fold": degrees, "curl": c, "roll": curvature, "twist": radians per
    length}, the pose a form was made in, with the "frame" {"origin", "u", "v", "normal"} of a
    leaf bent in the app (core/placed.py), or {"sheet": ...}, a scan's bend (core/sheet_bend.py)."""
    if isinstance(value, dict) and "sheet" in value:
        try:
            return Scaled.from_entry(value, np.vstack([leaf.boundary, leaf.vein_points]))
        except (TypeError, ValueError, KeyError, np.linalg.LinAlgError):
            raise LeafError('"bend": its "sheet" does not read whole', source) from None
    if isinstance(value, dict):
        _check_terms(value, source)
    fold = curl = roll = twist = math.nan  # stays nan, and is refused below, unless it reads whole
    frame = relief = None
    keys = {"fold", "curl", "roll", "twist", "frame", "relief"}
    named = ""  # what a relief says is wrong with it (a "sheet" neither "margin" nor "mean")
    if isinstance(value, dict) and not set(value) - keys:
        with contextlib.suppress(TypeError, ValueError, KeyError, AttributeError, OverflowError):
            if "frame" in value:  # read first: a bad frame leaves the fold nan
                axes = [np.asarray(value["frame"][k], float) for k in FRAME_KEYS]
                good = all(a.shape == (3,) and np.isfinite(a).all() for a in axes)
                if not (good and np.allclose(np.array(axes[1:]) @ np.array(axes[1:]).T, np.eye(3))):
                    raise ValueError
                frame = Frame(*axes)
            if "relief" in value:  # read first as well: a bad relief leaves the fold nan
                try:
                    relief = Relief.from_entry(value["relief"])
                except ValueError as error:
                    named = str(error)
                    raise
            fold, curl = float(value.get("fold", 0.0)), float(value.get("curl", 0.0))
            roll, twist = float(value.get("roll", 0.0)), float(value.get("twist", 0.0))
    if named:
        raise LeafError(f'"bend": its "relief": {named}', source)
    if not (abs(fold) < 90 and all(math.isfinite(t) for t in (curl, roll, twist))):
        raise LeafError(
            f'"bend" must be {{"fold": degrees from -{FOLD:g} to {FOLD:g}, "curl", "roll", '
            f'"twist": numbers}} (a "frame": {{"origin", "u", "v", "normal"}}, orthonormal '
            f'axes; a "relief": '
            f'{{"along", "midrib", "knots", "mean": lists, "half_width", "rise", "fall": '
            f'numbers, "sheet": "margin" or "mean"}}), got {shorten(value)}',
            source,
        )
    pose = Pose(fold, curl, roll, twist, relief)
    return pose if frame is None else PlacedPose(pose, frame)


def _check_terms(value: dict, source: str) -> None:
    """Refuse a "fold", "curl", "roll" or "twist" that is no JSON number, in one line naming it:
    float() read true as a fold of 1 (the project then refused as veins outside its boundary)
    and "30" as 30, and null or a list gave the whole "bend" form."""
    for term in ("fold", "curl", "roll", "twist"):
        if term in value and (
            isinstance(value[term], bool) or not isinstance(value[term], int | float)
        ):
            said = shorten(json.dumps(value[term], default=str))
            raise LeafError(f'"bend": its "{term}" must be a number, got {said}', source)


def rebent(leaf: Leaf) -> Leaf:
    """`leaf`, read from a version 1 project, with its curves bent by today's pose. A curl its
    blade cannot take (today's wraps the midrib on a circle, undone up to half a turn; a shear's
    raised it whatever its length) is eased to the most it can, and a warning says so."""
    bend = leaf.bend
    pose = bend.pose if isinstance(bend, PlacedPose) else bend
    if not isinstance(pose, Pose) or (pose.fold == 0 and pose.curl == 0):
        return leaf  # a roll and a twist are as they were; a sheet is no pose

    def blade(points: np.ndarray) -> np.ndarray:  # the flat blade's points, in its coordinates
        if isinstance(bend, PlacedPose):
            points = np.column_stack(bend.frame.to_plane(points))
        return sheared_flatten(pose, points)

    flat = [blade(c) for c in (leaf.boundary, *leaf.veins)]
    reach = max(float(np.abs(c[:, 0]).max()) for c in flat if len(c))
    most = MOST_TURN / (2 * reach) if reach > 0 else math.inf
    turned = pose
    if abs(pose.curl) > most:
        turned = replace(pose, curl=math.copysign(most, pose.curl))
        warnings.warn(
            f"the project's curl of {pose.curl:g} is read as {turned.curl:.3g}: a curl now bends "
            "the midrib on a circle, and this blade would wrap past half a turn",
            stacklevel=2,
        )

    def again(points: np.ndarray) -> np.ndarray:
        bent = turned.apply(points)
        if isinstance(bend, PlacedPose):
            return bend.frame.to_world(bent[:, :2], bent[:, 2])
        return bent

    new = turned if not isinstance(bend, PlacedPose) else PlacedPose(turned, bend.frame)
    return Leaf(again(flat[0]), [again(v) for v in flat[1:]], bend=new)
