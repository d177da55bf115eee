"""Step 4 (section 3.4), K chosen automatically: the number of Gaussians chosen by the Bayesian
information criterion.

The paper fixes K by hand and names its choice as future work. EM fits a density to the points
drawn from the height guide, so the natural criterion is that density's BIC on those same points,

    BIC(K) = −2 Σ_j log Σ_k π_k N(s_j | μ_k, Σ_k) + (6K − 1) log n

(a 2D full-covariance component has 2 mean, 3 covariance and 1 weight parameter, less one for
Σ π_k = 1). The smallest BIC wins. A guide with both signs (veins above and below the margin) is
fitted per sign and joined (gmm.fit_signed_mixture); K then counts the components of both, and the
BIC is the joined density's. It needs only EM fits, no surface fits, so it is cheap, and on
the paper's leaves it picks the paper's K for nested veins (3); for parallel veins it picks 5,
whose surface is closer to the veins than the paper's K = 2 (see tests/test_autok.py).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from leafstudio.core.gmm import Mixture
from leafstudio.errors import LeafError
from leafstudio.model import K_AUTO_MAX  # declared beside Params.k, whose help names it


def bic(mixture: Mixture, samples: np.ndarray) -> float:
    """BIC of a mixture's density on (n, 2) samples (lower is better)."""
    log_likelihood = np.log(np.maximum(mixture.density(samples), 1e-300)).sum()
    parameters = 6 * len(mixture.weights) - 1
    return float(-2 * log_likelihood + parameters * np.log(len(samples)))


def choose_mixture(
    fit: Callable[[int], Mixture], samples: np.ndarray, k_max: int = K_AUTO_MAX
) -> tuple[Mixture, dict[int, float]]:
    """Fits for K = 1..k_max and the one of smallest BIC on the samples.

    Parameters
    ----------
    fit : callable
        K -> the Mixture EM fits with K components (for a signed guide, the joined fit of both
        signs, gmm.fit_signed_mixture: its weights still sum to 1, so it is a density).
        Raising LeafError for a K the samples cannot support ends the search there.
    samples : (n, 2) float array
        The points drawn from the height guide (gmm.sample_guide) that `fit` fits.
    k_max : int, default: 12

    Returns
    -------
    mixture : Mixture
        The fit with the smallest BIC; its K is len(mixture.weights).
    scores : dict
        K -> BIC for every K tried.
    """
    fits: dict[int, Mixture] = {}
    for k in range(1, k_max + 1):
        try:
            fits[k] = fit(k)
        except LeafError:
            if k == 1:
                raise
            break  # more components than the samples support: so are all larger K
    scores = {k: bic(mixture, samples) for k, mixture in fits.items()}
    best = min(scores, key=scores.__getitem__)
    return fits[best], scores
