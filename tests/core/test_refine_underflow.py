"""The refinement after EM (core/surface._refine) keeps EM's mixture when its result cannot be
made into covariances: a precision factor's diagonal exp(t) that underflowed to 0 made a
singular matrix, and np.linalg.inv raised out of reconstruct as a traceback (a helper's noisy
synthetic scan, session 25)."""

from __future__ import annotations

import numpy as np

from leafstudio.core import surface
from leafstudio.core.gmm import Mixture


def test_a_refinement_whose_precision_underflows_keeps_ems_mixture(monkeypatch):
    mixture = Mixture(
        weights=np.array([0.5, 0.5]),
        means=np.array([[0.0, 0.0], [0.3, 0.1]]),
        covariances=np.array([np.eye(2) * 0.01, np.eye(2) * 0.02]),
        amplitudes=np.array([0.05, 0.03]),
    )
    theta = surface._pack(mixture).copy()
    theta.reshape(-1, 6)[1, 3] = -800.0  # exp(-800) is 0: the second factor is singular

    monkeypatch.setattr(surface, "_levenberg_marquardt", lambda *args: theta)
    xy = np.random.default_rng(0).uniform(-0.5, 0.5, (50, 2))
    kept = surface._refine(mixture, xy, np.ones(50), np.zeros(50))
    assert kept is mixture
