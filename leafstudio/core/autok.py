"""Automatic K: the number of Gaussians chosen by the Bayesian information criterion.

The paper fixes K by hand and names its choice as future work. EM fits a density to the points
drawn from the height guide, so the natural criterion is that density's BIC on those same points,

    BIC(K) = −2 Σ_j log Σ_k π_k N(s_j | μ_k, Σ_k) + (6K − 1) log n

(a 2D full-covariance component has 2 mean, 3 covariance and 1 weight parameter, less one for
Σ π_k = 1). The smallest BIC wins. It needs only EM fits, no surface fits, so it is cheap, and on
the paper's leaves it picks the paper's K for nested veins (3); for parallel veins it picks 5,
whose surface is closer to the veins than the paper's K = 2 (see tests/test_autok.py).
"""

from __future__ import annotations

import numpy as np

from leafstudio.core.gmm import Mixture, fit_mixture

K_AUTO_MAX = 12
PER_COMPONENT = 5  # fit_mixture's floor of distinct samples per component


def bic(mixture: Mixture, samples: np.ndarray) -> float:
    """BIC of a mixture's density on (n, 2) samples (lower is better)."""
    log_likelihood = np.log(np.maximum(mixture.density(samples), 1e-300)).sum()
    parameters = 6 * len(mixture.weights) - 1
    return float(-2 * log_likelihood + parameters * np.log(len(samples)))


def choose_mixture(
    samples: np.ndarray, seed: int, k_max: int = K_AUTO_MAX
) -> tuple[Mixture, dict[int, float]]:
    """EM fits for K = 1..k_max (fewer if the samples cannot support that many) and the one of
    smallest BIC.

    Parameters
    ----------
    samples : (n, 2) float array
        The points drawn from the height guide (gmm.sample_guide).
    seed : int
        EM's seed, as for a fixed K.
    k_max : int, default: 12

    Returns
    -------
    mixture : Mixture
        The fit with the smallest BIC; its K is len(mixture.weights).
    scores : dict
        K -> BIC for every K tried.
    """
    distinct = len(np.unique(np.round(samples, 9), axis=0))
    top = max(1, min(k_max, distinct // PER_COMPONENT))
    fits = {k: fit_mixture(samples, k, seed) for k in range(1, top + 1)}
    scores = {k: bic(mixture, samples) for k, mixture in fits.items()}
    best = min(scores, key=scores.__getitem__)
    return fits[best], scores
