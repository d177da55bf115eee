"""The blade's frames for core/unfold.py's fits: the first guesses of its frame off the curves,
and a fitted bend read the way up the flat blade takes."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from leafstudio.core.bend import flat_leaf
from leafstudio.core.placed import PlacedPose
from leafstudio.core.plane import Frame, fit_frame
from leafstudio.model import Leaf


def first_frames(boundary: np.ndarray, midrib: np.ndarray) -> list[np.ndarray]:
    """(3, 3) first frames (rows u, v, normal): u along the midrib's chord; the normal the
    boundary's PCA normal, or the way the margin stands from the midrib (a fold's side)."""
    u = midrib[-1] - midrib[0]
    u = u / np.linalg.norm(u)
    centred = boundary - boundary.mean(axis=0)
    normals = [np.linalg.eigh(centred.T @ centred)[1][:, 0], boundary.mean(0) - midrib.mean(0)]
    frames = []
    for n in normals:
        n = n - (n @ u) * u
        if np.linalg.norm(n) < 1e-9:
            continue
        n = n / np.linalg.norm(n)
        frames.append(np.array([u, np.cross(n, u), n]))
    return frames


def upright(bend: PlacedPose, leaf: Leaf) -> PlacedPose:
    """`bend`, the same bend of `leaf`, in the frame whose normal is the one the flat blade's
    own plane takes (plane.fit_frame: toward its veins), as the app finds it again (a sketch's
    frame, placed.blade_frame): turned half about the midrib when the fit's normal, whichever
    way its start pointed, is the other (fold, curl, roll and relief negated; the twist, a turn
    about the midrib as that half turn is, kept; the same points to the last bit). An ovate
    folded 45 and curled 0.5 was fitted fold -45 and curl -0.5 about a normal down, and its
    sketch's first edit flipped the leaf over (0.82 of its length)."""
    flat = flat_leaf(Leaf(leaf.boundary, leaf.veins, bend=bend))
    if fit_frame(flat.boundary, flat.vein_points).normal @ bend.frame.normal >= 0:
        return bend
    pose, frame = bend.pose, bend.frame
    relief = None if pose.relief is None else pose.relief.mirrored()
    turned = replace(  # 0.0 - t: no -0.0 for a term the fit left out
        pose, fold=0.0 - pose.fold, curl=0.0 - pose.curl, roll=0.0 - pose.roll, relief=relief
    )
    return PlacedPose(turned, Frame(frame.origin, frame.u, -frame.v, -frame.normal))
