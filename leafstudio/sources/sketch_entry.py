"""A project's "sketch" entry (stored by sources/files.py as the app gives it) read for the plane
it was drawn on: the app's main view shows a drawn leaf on that plane (gui/model/session's
`view_frame`), and so do its lesson and File > Export slides (render/step_slides.plan_frame);
`leafstudio slides` on a saved project does too. gui/model/sketch_model.Sketch reads the rest.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from leafstudio.core.plane import Frame
from leafstudio.errors import LeafError


def world_frame() -> Frame:
    """The world's axes as a frame: a new sketch's plane, and a stored sketch's without one."""
    return Frame(origin=np.zeros(3), u=np.eye(3)[0], v=np.eye(3)[1], normal=np.eye(3)[2])


# how far from unit length, and from perpendicular (the cosine between two axes), a stored
# plane's axes may be and still read as the frame meant, made exact: the app writes its frames
# as Python floats, read back to 4.4e-16 (Sketch.from_result on three turned demos, through
# JSON), but a frame typed or written to two decimals is up to 0.0136 off (three: 0.0014; the
# worst of 20,000 random rotations rounded). Past it an axis is not a rounded unit one: 5% long
# or short, or two axes 87 degrees apart, is a mistake the user is told of (review36).
PLANE_TOLERANCE = 0.05


def sketch_plane(sketch: dict[str, Any]) -> Frame | None:
    """The frame stored as a sketch's "plane" (its origin, u, v and normal, three numbers
    each), or None when it stored none. Axes within PLANE_TOLERANCE of unit and perpendicular
    are made exactly so (orthonormal_frame).

    Raises
    ------
    ValueError
        If the plane lacks one of its vectors or one is not three numbers, saying so: numpy's
        and Python's own words ("bad sketch ('origin')", "bad sketch (string indices must be
        integers, not 'str')") named neither the plane nor what it wants (review36). If its
        axes are not a frame (orthonormal_frame).
    """
    plane = sketch.get("plane") or {}
    if not plane:
        return None
    names = ("origin", "u", "v", "normal")
    try:
        vectors = [np.asarray(plane[k], dtype=float).reshape(3) for k in names]
    except (KeyError, TypeError, ValueError, IndexError):
        raise ValueError(
            f'"plane" must give origin, u, v and normal, three numbers each; got {plane!r:.60}'
        ) from None
    return orthonormal_frame(*vectors)


def orthonormal_frame(
    origin: np.ndarray, u: np.ndarray, v: np.ndarray, normal: np.ndarray
) -> Frame:
    """The frame of (3,) `origin` and axes `u`, `v` and `normal` made exactly orthonormal (u
    kept in direction, v squared to it, the normal u x v on the side the given one points);
    axes orthonormal to 1e-12, as the app writes them, kept bit for bit.

    Raises
    ------
    ValueError
        If a number is NaN or infinite, an axis is not within PLANE_TOLERANCE of unit length or
        two are not within it of perpendicular, naming the axis: the app and `leafstudio
        slides` took a plane of zeros, or u along v, and showed the leaf on another frame
        (turned_like's fallback: the result's own), and a zero plane's sketch made its leaf all
        at one point (review36).
    """
    if not all(np.isfinite(a).all() for a in (origin, u, v, normal)):
        raise ValueError('"plane" holds a NaN or infinite number')
    axes = {"u": u, "v": v, "normal": normal}
    lengths = {name: float(np.linalg.norm(axis)) for name, axis in axes.items()}
    for name, length in lengths.items():
        if abs(length - 1.0) > PLANE_TOLERANCE:
            raise ValueError(f'"plane"\'s {name} must be a unit vector, got one {length:.3g} long')
    worst = max(abs(length - 1.0) for length in lengths.values())
    for a, b in (("u", "v"), ("u", "normal"), ("v", "normal")):
        cosine = float(axes[a] @ axes[b]) / lengths[a] / lengths[b]
        worst = max(worst, abs(cosine))
        if abs(cosine) > PLANE_TOLERANCE:
            angle = np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))
            raise ValueError(
                f'"plane"\'s {a} and {b} must be perpendicular, got them {angle:.3g} degrees apart'
            )
    if worst <= 1e-12:
        return Frame(origin=origin, u=u, v=v, normal=normal)
    u = u / np.linalg.norm(u)
    v = v - (v @ u) * u
    v = v / np.linalg.norm(v)
    across = np.cross(u, v)
    return Frame(origin=origin, u=u, v=v, normal=across if across @ normal > 0 else -across)


def drawn_frame(sketch: dict[str, Any], source: str) -> Frame | None:
    """The frame the app shows a saved project's leaf on: its sketch's plane (the world's axes
    when it stored none) when the sketch has an outline, so a leaf drawn at an angle keeps it;
    None without one (a project saved with no sketch: the result's own frame is shown).
    LeafError naming `source` for a sketch whose plane cannot be read, as the app's."""
    try:
        if not len(sketch.get("boundary") or []):
            return None
        return sketch_plane(sketch) or world_frame()
    except (TypeError, ValueError, KeyError) as exc:
        raise LeafError(f"bad sketch ({exc})", source) from None
