"""A fold about the blade's own midrib (bend.Pose with a relief, pose_relief.py): each half
turned about the hinge, the midrib's height, so a domed blade keeps its size.

In the coordinates (y, o) of a cross-section, y across the midrib and o = z − hinge, the fold
without a relief is y -> y c, o -> o + |y| s (c, s the fold's cosine and sine): the relief is
lifted straight up, and a dome falling from the midrib 14° was drawn in to 0.82 of its area
at 60°. Turned rigidly, (y, o) -> (y c − σ o s, |y| s + o c), σ = ±1 the half. Two things
keep that from working everywhere, and this fold is

    y -> y c − σ(y) w s o,    o -> |y| s + (1 − w + w c) o.

- w, the share of the relief's turn (`fold_share`): a point at an angle γ off the hinge,
  across from it, swings over the midrib's plane into the other half once γ and the fold pass
  a right angle (a dome folded down 75°, a wavy margin folded up, a rolled tube folded at all:
  132 of test_forms_posed's 168 poses flattened a point onto the wrong half). With
  w tan |fold| ≤ cot γ each half stays on its side; a blade folded without a roll turns
  rigidly (w = 1), a tube folded as without a relief (w = 0).
- σ(y), the half, goes from −1 to 1 across a band 2 BAND of the blade's length wide, smoothly
  (t (3 − t²) / 2, t = y / band): a point on the crease a little off the hinge (the surface
  passes within the vein tolerance of the midrib, not through it) was turned one way or the
  other, the two halves parted there, and a folded cordate blade's solid crossed itself.
  Across the band o stays what it was, so the crease is the fold's V, as sharp as before.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

BAND = 0.03  # of the blade's length: the crease's band where σ turns over
NEWTON_STEPS = 6  # Newton's steps of the band's inverse (ovate folded 60°, grid 128: all
# 1266 of its mesh's points in the band within ROOT_TOLERANCE after 4, 327 left after 3)
ROOT_TOLERANCE = 1e-13  # of the band: a Newton root farther off is bisected
BISECTIONS = 60  # steps of the band's inverse by bisection: the band halved 60 times


@dataclass(frozen=True)
class HingeFold:
    """The fold's numbers: its cosine and sine, the share w of the relief's turn, and the
    band's half-width, in the blade's units."""

    c: float
    s: float
    share: float
    band: float

    @property
    def lift(self) -> float:
        """1 − w + w c: the relief's own factor."""
        return 1 - self.share + self.share * self.c

    def sigma(self, y: np.ndarray) -> np.ndarray:
        """σ(y) (module docstring): `folded` needs no more of it."""
        t = np.clip(y / self.band, -1.0, 1.0)
        return np.where(np.abs(y) < self.band, 0.5 * t * (3 - t**2), np.where(y < 0, -1.0, 1.0))

    def side(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """σ(y), σ' and σ'' (module docstring)."""
        t = np.clip(y / self.band, -1.0, 1.0)
        inside = np.abs(y) < self.band
        sigma = self.sigma(y)
        slope = np.where(inside, 1.5 * (1 - t**2) / self.band, 0.0)
        bend = np.where(inside, -3 * t / self.band**2, 0.0)
        return sigma, slope, bend

    def folded(self, y: np.ndarray, off: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(y, o) folded (module docstring)."""
        sigma = self.sigma(y)
        return y * self.c - sigma * self.share * self.s * off, np.abs(y) * self.s + self.lift * off

    def unfolded(self, y: np.ndarray, off: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The inverse of `folded`. Past the band each half is linear; a point either half's
        fold reaches (inside the fold, where a relief falls from the hinge into it: a dome
        folded down) or neither does is taken on the side of the midrib's plane it lies, and
        one in the band is found by `_in_band` (y c − σ(y) w s o(y) rises across it while o is
        under band c / (1.5 w s): 1e-3 of the length on an ovate blade folded 75°, whose
        surface passes within 4e-4 of the midrib)."""
        c, s, w, e = self.c, self.s, self.share, self.lift
        det = c * e + w * s * s
        plus = (e * y + w * s * off) / det  # y, were it on the + half past the band
        minus = (e * y - w * s * off) / det
        on_plus, on_minus = plus >= self.band, minus <= -self.band
        across = np.where(on_plus == on_minus, y >= 0, on_plus)
        flat = np.where(across, plus, minus)
        crossing = ~on_plus & ~on_minus
        if crossing.any():
            flat[crossing] = self._in_band(y[crossing], off[crossing])
        return flat, (off - np.abs(flat) * s) / e

    def _in_band(self, y: np.ndarray, off: np.ndarray) -> np.ndarray:
        """y in the band whose fold is (y, off): Newton's steps on y' (y) = y from the middle of
        the band, kept in it, then bisection for any left more than ROOT_TOLERANCE off (60
        bisections for every point near the crease took 46% of a folded form's run, cProfile
        of ovate folded 60° at grid 128); 0 exactly for a point on the crease's plane (y' = 0
        is the crease's own, σ(0) = 0: an inexact root put a form's tip 1e-20 beside the
        crease, and cutting the mesh there left a face of no area)."""
        s, ws, e = self.s, self.share * self.s, self.lift
        guess = np.clip(y / self.c, -self.band, self.band)
        for _ in range(NEWTON_STEPS):
            sigma, slope, _ = self.side(guess)
            relief = (off - np.abs(guess) * s) / e
            miss = guess * self.c - sigma * ws * relief - y
            rate = self.c - slope * ws * relief + sigma * ws * np.sign(guess) * s / e
            guess = np.clip(guess - miss / np.where(rate > 0, rate, np.inf), -self.band, self.band)
        relief = (off - np.abs(guess) * s) / e
        left = np.abs(self.folded(guess, relief)[0] - y) > ROOT_TOLERANCE * self.band
        if left.any():
            guess[left] = self._bisected(y[left], off[left])
        return np.where(y == 0, 0.0, guess)

    def _bisected(self, y: np.ndarray, off: np.ndarray) -> np.ndarray:
        """`_in_band` by bisection on the band."""
        low, high = np.full(len(y), -self.band), np.full(len(y), self.band)
        for _ in range(BISECTIONS):
            middle = 0.5 * (low + high)
            relief = (off - np.abs(middle) * self.s) / self.lift
            above = self.folded(middle, relief)[0] > y
            high, low = np.where(above, middle, high), np.where(above, low, middle)
        return 0.5 * (low + high)


def fold_share(fold: float, room: float) -> float:
    """w, the share of the relief's turn a fold of `fold` degrees may take when a point of the
    blade stands `room` radians short of a right angle off the hinge (Relief.fold_room)."""
    if room <= 0:
        return 0.0
    return min(1.0, float(np.tan(room) / abs(np.tan(np.deg2rad(fold)))))
