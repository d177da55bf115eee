"""Step 1 (section 3.1) for a margin off its plane, the base surface b(x): a thin-plate spline
through the boundary's heights off its plane.

The paper puts the whole margin at height 0 in the boundary's PCA plane. Real margins are not
planar: leaves curl along their length, fold along the midrib and let their margins roll up or
down. We carry the margin's heights with a smooth base surface over the leaf region,

    b(x) = Σ_i w_i φ(|x − c_i|) + a_0 + a_1 x + a_2 y,     φ(r) = r² log r,

the thin-plate spline (the interpolant of least bending energy, the physics of a thin blade)
through the boundary points' signed heights, with a few centres c_i taken evenly along the
outline so that it stays cheap (`CENTRES`: as few as follow the heights between them; one small
dense solve, then O(n · centres) to evaluate).
The Gaussian mixture then models the veins' relief above or below b (see surface.py). For a planar
boundary there is no base (b ≡ 0 exactly) and the paper's method is unchanged.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg

CENTRES = (48, 192)  # the spline's centres along the outline, tried in turn (see fit_base)
CLOSE = 1e-4  # of the length: a spline this close (rms) to the outline's heights needs no more
# centres; nor one within twice the heights' own noise (more centres would follow the noise)
PLANAR = 1e-9  # boundary heights under this fraction of the leaf length count as planar
SMOOTHING = 1e-7  # ridge on the spline's kernel (in units of the leaf length), against noise


@dataclass(frozen=True)
class BaseSurface:
    """b(x) = Σ w_i φ(|x − c_i| / L) + a_0 + a_1 x̃ + a_2 ỹ, with x̃ = (x − origin) / L.

    Attributes
    ----------
    centres : (m, 2) float array
        Spline centres, in plane coordinates.
    weights : (m,) float array
        w_i.
    affine : (3,) float array
        a_0, a_1, a_2 (in the scaled coordinates).
    origin : (2,) float array
    scale : float
        L, the leaf length; the spline works in x̃ so that its system is well conditioned.
    """

    centres: np.ndarray
    weights: np.ndarray
    affine: np.ndarray
    origin: np.ndarray
    scale: float

    def __call__(self, xy: np.ndarray) -> np.ndarray:
        """(n,) b at (n, 2) plane points."""
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        local = (xy - self.origin) / self.scale
        kernel = _kernel(_squared_distances(local, (self.centres - self.origin) / self.scale))
        return kernel @ self.weights + self.affine[0] + local @ self.affine[1:]

    def derivatives(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """b (n,), ∇b (n, 2) and ∇²b (n, 2, 2) at (n, 2) plane points, in closed form.

        With d = x̃ − c̃ and r = |d|: ∇φ = (2 log r + 1) d and ∇²φ = (2 log r + 1) I + 2 d dᵀ / r²
        (taken as 0 at a centre, where φ is only C1); each derivative divides by L once more.
        Sums over the centres are written as matrix products, so nothing is (n, m, 2, 2).
        """
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        x = (xy - self.origin) / self.scale
        c = (self.centres - self.origin) / self.scale
        r2 = _squared_distances(x, c)
        away = r2 > 0
        log_r2 = np.log(np.where(away, r2, 1.0))
        value = _kernel(r2) @ self.weights + self.affine[0] + x @ self.affine[1:]
        slope = np.where(away, log_r2 + 1.0, 0.0) * self.weights  # (n, m): (2 log r + 1) w
        total = slope.sum(axis=1)
        grad = x * total[:, None] - slope @ c + self.affine[1:]
        q = np.where(away, 2.0 / np.where(away, r2, 1.0), 0.0) * self.weights  # 2 w / r²
        q_sum, q_c = q.sum(axis=1), q @ c
        hess = np.empty((len(x), 2, 2))
        for i in range(2):
            for j in range(i, 2):
                # Σ q (x_i − c_i)(x_j − c_j), expanded
                term = x[:, i] * x[:, j] * q_sum - x[:, i] * q_c[:, j] - x[:, j] * q_c[:, i]
                term += q @ (c[:, i] * c[:, j])
                hess[:, i, j] = hess[:, j, i] = term + (total if i == j else 0.0)
        return value, grad / self.scale, hess / self.scale**2


def _squared_distances(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n, m) squared distances between (n, 2) and (m, 2) points."""
    return np.maximum((a**2).sum(axis=1)[:, None] + (b**2).sum(axis=1)[None] - 2 * a @ b.T, 0.0)


def _kernel(r2: np.ndarray) -> np.ndarray:
    """φ(r) = r² log r = ½ r² log r², from squared distances (0 at r = 0)."""
    return 0.5 * r2 * np.log(np.where(r2 > 0, r2, 1.0))


def _even_along(polygon: np.ndarray, count: int) -> np.ndarray:
    """Indices of `count` polygon vertices spread evenly by arc length around the outline."""
    if len(polygon) <= count:
        return np.arange(len(polygon))
    steps = np.linalg.norm(np.diff(polygon, axis=0, append=polygon[:1]), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(steps)[:-1]])
    targets = np.linspace(0.0, arc[-1] + steps[-1], count, endpoint=False)
    return np.unique(np.clip(np.searchsorted(arc, targets), 0, len(polygon) - 1))


def fit_base(
    polygon: np.ndarray, heights: np.ndarray, length: float, *, noisy: bool = False
) -> BaseSurface | None:
    """The thin-plate spline through the outline's heights, or None if the outline is planar.

    The spline passes through a few outline points spread evenly along it, the fewest of
    `CENTRES` whose spline stays within CLOSE of the length (rms) of every outline point's
    height, or within twice the heights' noise. 48 missed a waved sagittate form's margin by
    1.4e-2 of its length between them (hastate 9.5e-3, deltoid 3.1e-3), and the form's veins,
    which ride on the same base, by as much; 192 by 1.3e-3 (2.5e-3, 4.2e-4). A noisy margin keeps
    48: more centres follow the noise (a noisy cloud's smoothed mean margin is `noisy`, its noise
    no longer in its second differences; with 192 centres the 99th-percentile margin dihedral
    of a noisy ovate at grid 256 rose from 0.7° to 2.5°).

    Parameters
    ----------
    polygon : (b, 2) float array
        The leaf outline in the plane, in order around it.
    heights : (b,) float array
        Signed heights of the outline's points off the plane.
    length : float
        The leaf length; sets the planarity threshold and the spline's scale.
    noisy : bool, default: False
        The heights are a noisy margin's (smoothed): the fewest centres only.

    Returns
    -------
    BaseSurface or None
        None when every |height| <= 1e-9 of the length (then b ≡ 0 and the paper's method holds).
    """
    if len(polygon) < 3 or np.max(np.abs(heights)) <= PLANAR * length:
        return None
    enough = max(CLOSE * length, 2 * _noise(heights))
    for count in CENTRES[:1] if noisy else CENTRES:
        base = _fit(polygon, heights, length, count)
        if np.sqrt(np.mean((base(polygon) - heights) ** 2)) <= enough:
            break
    return base


def _noise(heights: np.ndarray) -> float:
    """The heights' noise σ along the outline, from their fourth differences: σ √70 for white
    noise, next to nothing for a smooth margin (second differences took a waved spatulate
    form's waves, sampled 50 to a wave, for noise); the median keeps a corner's jump out."""
    fourth = np.diff(heights, 4)
    return float(np.median(np.abs(fourth))) / (0.6745 * np.sqrt(70)) if len(fourth) else 0.0


def _fit(polygon: np.ndarray, heights: np.ndarray, length: float, count: int) -> BaseSurface:
    """The spline through `count` of the outline's points, spread evenly along it."""
    pick = _even_along(polygon, count)
    origin = polygon.mean(axis=0)
    centres = (polygon[pick] - origin) / length
    m = len(centres)
    system = np.zeros((m + 3, m + 3))
    system[:m, :m] = _kernel(_squared_distances(centres, centres)) + SMOOTHING * np.eye(m)
    affine = np.column_stack([np.ones(m), centres])  # the columns 1, x, y
    system[:m, m:] = affine
    system[m:, :m] = affine.T
    rhs = np.concatenate([heights[pick], np.zeros(3)])
    with warnings.catch_warnings():  # symmetric indefinite: LDLᵀ, many times cheaper than
        # lstsq's SVD with 192 centres; lstsq when it is singular (centres on a line)
        warnings.simplefilter("error", scipy.linalg.LinAlgWarning)
        try:
            solution = scipy.linalg.solve(system, rhs, assume_a="sym", check_finite=False)
        except (np.linalg.LinAlgError, scipy.linalg.LinAlgWarning):
            solution = np.linalg.lstsq(system, rhs, rcond=None)[0]
    return BaseSurface(
        centres=polygon[pick].copy(),
        weights=solution[:m],
        affine=solution[m:],
        origin=origin,
        scale=float(length),
    )
