"""Step 4: a K-component Gaussian mixture fitted by EM to the height guide (eqs. 6-9).

The paper draws points with density following p(x) and fits π_k, μ_k, Σ_k by EM. A mixture is a
density that integrates to 1, not a height, so we scale it: z(x) = Σ_k a_k N(x | μ_k, Σ_k), with
the amplitudes a_k fitted to p by least squares (see surface.py). With a_k = A π_k this is the
paper's scaled GMM; letting each a_k free (and signed) follows veins of different heights, and
veins below the boundary's plane, that a single scale cannot.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from sklearn.mixture import GaussianMixture
from threadpoolctl import threadpool_limits

from leafstudio.errors import LeafError


@dataclass(frozen=True)
class Mixture:
    """K Gaussians in the plane with amplitudes.

    Attributes
    ----------
    weights : (K,) float array
        π_k from EM (eq. 9: non-negative, sum 1).
    means : (K, 2) float array
        μ_k (eq. 7).
    covariances : (K, 2, 2) float array
        Σ_k (eq. 7).
    amplitudes : (K,) float array
        a_k; z(x) = Σ a_k N(x | μ_k, Σ_k). Defaults to the weights.
    """

    weights: np.ndarray
    means: np.ndarray
    covariances: np.ndarray
    amplitudes: np.ndarray

    @property
    def precisions(self) -> np.ndarray:
        """(K, 2, 2) Σ_k⁻¹."""
        return np.linalg.inv(self.covariances)

    def components(self, xy: np.ndarray) -> np.ndarray:
        """(n, K) values of each Gaussian N(x | μ_k, Σ_k) (eq. 6), without weights."""
        xy = np.atleast_2d(xy)
        d = xy[:, None, :] - self.means[None]
        maha = np.einsum("nki,kij,nkj->nk", d, self.precisions, d)
        norm = 1.0 / (2 * np.pi * np.sqrt(np.linalg.det(self.covariances)))
        return norm[None] * np.exp(-0.5 * maha)

    def density(self, xy: np.ndarray) -> np.ndarray:
        """The GMM of eq. 8, Σ π_k N_k(x): a probability density."""
        return self.components(xy) @ self.weights

    def value(self, xy: np.ndarray) -> np.ndarray:
        """Σ a_k N_k(x) at (n, 2) points."""
        return self.components(xy) @ self.amplitudes

    def derivatives(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Value (n,), gradient (n, 2) and Hessian (n, 2, 2) of Σ a_k N_k(x), in closed form.

        ∇N = −N P d and ∇²N = N (P d dᵀ P − P), with d = x − μ and P = Σ⁻¹.
        """
        xy = np.atleast_2d(xy)
        comp = self.components(xy) * self.amplitudes[None]
        prec = self.precisions
        pd = np.einsum("kij,nkj->nki", prec, xy[:, None, :] - self.means[None])
        grad = -np.einsum("nk,nki->ni", comp, pd)
        outer = pd[..., :, None] * pd[..., None, :] - prec[None]
        hess = np.einsum("nk,nkij->nij", comp, outer)
        return comp.sum(axis=1), grad, hess


def sample_guide(
    xy: np.ndarray, p: np.ndarray, count: int, spacing: float, seed: int
) -> np.ndarray:
    """Draw `count` points with density proportional to |p| (the guide as an existence probability).

    Each draw picks a grid node with probability |p| / Σ|p| and jitters it uniformly within its
    cell, so the samples cover the plane rather than stacking on nodes.
    """
    rng = np.random.default_rng(seed)
    mass = np.abs(p)
    total = mass.sum()
    if total <= 0:
        raise LeafError("the height guide is zero everywhere: nothing to fit")
    picks = rng.choice(len(xy), size=count, p=mass / total)
    return xy[picks] + rng.uniform(-0.5, 0.5, size=(count, 2)) * spacing


def fit_mixture(samples: np.ndarray, k: int, seed: int) -> Mixture:
    """EM fit of a K-component full-covariance GMM (sklearn), one BLAS thread, fixed seed.

    scikit-learn's EM is erratic in time with several BLAS threads on small machines and steady
    with one, so it runs with one.
    """
    distinct = len(np.unique(np.round(samples, 9), axis=0))
    if k > distinct // 5:
        raise LeafError(
            f"K = {k} is more than the data supports: the guide has only {distinct} distinct "
            f"samples (need at least 5 per component); lower K or raise the grid resolution"
        )
    gmm = GaussianMixture(
        n_components=k, covariance_type="full", random_state=seed, reg_covar=1e-6, max_iter=200
    )
    with threadpool_limits(limits=1):
        gmm.fit(samples)
    return Mixture(
        weights=gmm.weights_.copy(),
        means=gmm.means_.copy(),
        covariances=gmm.covariances_.copy(),
        amplitudes=gmm.weights_.copy(),
    )


MIN_SIGN_SHARE = 0.05  # a sign of the guide with less of its mass than this gets no component


def split_components(positive_share: float, k: int) -> tuple[int, int]:
    """Components for the guide's positive and negative parts, in proportion to their mass.

    A part holding at least MIN_SIGN_SHARE of the mass gets at least one component when k >= 2.
    """
    if positive_share >= 1 - MIN_SIGN_SHARE:
        return k, 0
    if positive_share <= MIN_SIGN_SHARE:
        return 0, k
    if k == 1:
        return (1, 0) if positive_share >= 0.5 else (0, 1)
    k_pos = int(np.clip(round(k * positive_share), 1, k - 1))
    return k_pos, k - k_pos


def fit_signed_mixture(
    samples: np.ndarray,
    positive: np.ndarray,
    fit: Callable[[np.ndarray, int | None], Mixture],
    k: int | None,
) -> Mixture:
    """One mixture for a guide that may be positive in places and negative in others.

    A density cannot be negative, so the samples drawn from |p| where p > 0 and those where p < 0
    are fitted apart (`fit(part, k_part)`; k_part is None when `k` is None, for an automatic
    choice) and joined, each part's weights scaled by its share of the samples. The signed
    amplitudes fitted afterwards (surface.py) then raise one part and lower the other.
    """
    share = float(positive.mean())
    if k is None:
        counts = [None if share > MIN_SIGN_SHARE else 0, None if share < 1 - MIN_SIGN_SHARE else 0]
    else:
        counts = list(split_components(share, k))
    parts = [
        (fit(samples[mask], count), mask.mean())
        for mask, count in zip((positive, ~positive), counts, strict=True)
        if count != 0
    ]
    return Mixture(
        weights=np.concatenate([m.weights * frac for m, frac in parts]),
        means=np.concatenate([m.means for m, _ in parts]),
        covariances=np.concatenate([m.covariances for m, _ in parts]),
        amplitudes=np.concatenate([m.weights * frac for m, frac in parts]),
    )
