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


def sketch_plane(sketch: dict[str, Any]) -> Frame | None:
    """The frame stored as a sketch's "plane" (its origin, u, v and normal, three numbers
    each), or None when it stored none.

    Raises
    ------
    ValueError
        If the plane lacks one of its vectors or one is not three numbers, saying so: numpy's
        and Python's own words ("bad sketch ('origin')", "bad sketch (string indices must be
        integers, not 'str')") named neither the plane nor what it wants (review36).
    """
    plane = sketch.get("plane") or {}
    if not plane:
        return None
    names = ("origin", "u", "v", "normal")
    try:
        return Frame(**{k: np.asarray(plane[k], dtype=float).reshape(3) for k in names})
    except (KeyError, TypeError, ValueError, IndexError):
        raise ValueError(
            f'"plane" must give origin, u, v and normal, three numbers each; got {plane!r:.60}'
        ) from None


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
