"""A curl's first guess for a pose fitted to curves in 3D (core/unfold.py), read off the midrib.

A curl lays the midrib on a circle and keeps its length (bend.Pose): a midrib turning 2t from
base to apex has a chord sin(t) / t of its length, leaning t off the midrib's way at its base,
toward the side it bows from. unfold.py starts each frame with the chord as the blade's x and no
curl, and a curl's fit from there must turn the frame as far as the curl leans the chord: where
the midrib turns two radians it found another basin. Reniform curled 1, written as a CSV, was
fitted a curl alone of -0.95 in a frame turned 1.5 radians off the midrib, 0.024 of the length
off flat (a curl of 1.23 about the margin's plane lays it within 1e-10), and a roll across the
midrib, which lays a curled margin as flat, was taken instead (1.126 times its length); curled
-1, nothing that lay it flat enough was found (0.733 times its length). `bowed_starts` gives a
curl alone, from each frame, a start with the midrib's own turn besides: the frame turned to
the midrib's way at its base, and the curl of that circle. Only a curl alone: the fits with a
fold or a roll start from several of theirs, and given this one too, obovate folded -75 (its
domed midrib reading a turn as a curl's) went to fold -52.9 and roll 0.55, 3.05 times its width.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

LEAST_TURN = 0.2  # radians a midrib turns, base to apex, for a start of its own: a form's
# midrib reads 0.04-0.14 when straight and flat (linear, lanceolate), 0.23-0.81 when its relief
# rises and falls along it (domed, folded, rolled or twisted blades; waved elliptic 1.35) and
# 0.61-2.71 curled (csv_traits.py's 28 posed forms, /work/notes/curl35/turns.py): its turn does
# not tell a curl from a dome, so every midrib past a straight one's gets the start


def bowed(midrib: np.ndarray, axes: np.ndarray) -> tuple[np.ndarray, float] | None:
    """The (3,) rotation vector that turns the (3, 3) `axes` (rows: u along the (m, 3)
    `midrib`'s chord, v, the normal) to the midrib's way at its base (about v), and the curl
    that lays a midrib of its length and chord on a circle from there (per unit of the
    midrib's coordinates, positive toward the normal); None for a midrib turning less than
    LEAST_TURN."""
    offsets = midrib - midrib[0]
    along = float(np.linalg.norm(np.diff(midrib, axis=0), axis=1).sum())
    chord = float(np.linalg.norm(offsets[-1]))
    if not (along > 0 and chord > 0) or chord / along >= np.sinc(LEAST_TURN / 2 / np.pi):
        return None  # np.sinc(t / pi) is sin(t) / t
    half = brentq(lambda t: np.sinc(t / np.pi) - chord / along, 1e-9, np.pi * (1 - 1e-9))
    way = offsets[-1] / chord
    bow = float(np.mean((offsets - np.outer(offsets @ way, way)) @ axes[2]))
    sign = -1.0 if bow > 0 else 1.0  # curled toward the normal, the midrib bows under its chord
    return sign * half * axes[1], sign * half / along


def bowed_starts(
    midrib: np.ndarray, frames: list[np.ndarray], terms: tuple[int, ...], length: float, most: float
) -> list[tuple[np.ndarray, np.ndarray]]:
    """unfold.py's starts ((3, 3) axes, (4 + k,) y: the rotation, the base's height and the
    `terms`' guesses, fold, curl, roll, twist as 0, 1, 2, 3) with the (m, 3) `midrib`'s own turn
    (`bowed`) in each of the `frames`: its curl in the fit's units (over the outline's diagonal
    `length`), at most `most` each way, the other terms 0."""
    starts = []
    for axes in frames:
        bow = bowed(midrib, axes)
        if bow is not None:
            curl = float(np.clip(bow[1] * length, -most, most))
            starts.append(
                (axes, np.array([*bow[0], 0.0, *(curl if t == 1 else 0.0 for t in terms)]))
            )
    return starts
