"""Step 4: the Gaussian mixture (eqs. 6-9), its EM fit and its closed-form derivatives."""

import numpy as np
import pytest

from leafstudio.core.gmm import Mixture, fit_mixture, fit_signed_mixture, split_components
from leafstudio.errors import LeafError

KNOWN = Mixture(
    weights=np.array([0.5, 0.3, 0.2]),
    means=np.array([[0.0, 0.0], [3.0, 0.5], [1.0, 3.0]]),
    covariances=np.array(
        [[[0.30, 0.10], [0.10, 0.20]], [[0.20, -0.05], [-0.05, 0.40]], [[0.15, 0.0], [0.0, 0.15]]]
    ),
    amplitudes=np.array([0.5, 0.3, 0.2]),
)


def _draw(mixture: Mixture, n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    comp = rng.choice(len(mixture.weights), size=n, p=mixture.weights)
    chol = np.linalg.cholesky(mixture.covariances)
    return mixture.means[comp] + np.einsum("nij,nj->ni", chol[comp], rng.normal(size=(n, 2)))


def test_eq6_gaussian_by_hand():
    """At its mean a 2D Gaussian is 1 / (2π |Σ|^½); one standard deviation away, times e^-½."""
    m = Mixture(np.ones(1), np.zeros((1, 2)), np.diag([4.0, 1.0])[None], np.ones(1))
    assert m.value(np.array([[0.0, 0.0]]))[0] == pytest.approx(1 / (2 * np.pi * 2))
    assert m.value(np.array([[2.0, 0.0]]))[0] == pytest.approx(np.exp(-0.5) / (4 * np.pi))


def test_eq8_density_integrates_to_one():
    xs = np.linspace(-4, 7, 551)
    grid = np.column_stack([a.ravel() for a in np.meshgrid(xs, xs)])
    cell = (xs[1] - xs[0]) ** 2
    assert KNOWN.density(grid).sum() * cell == pytest.approx(1.0, abs=1e-3)


def test_em_recovers_a_known_mixture():
    fitted = fit_mixture(_draw(KNOWN, 20000), 3, seed=0)
    order = [int(np.argmin(np.linalg.norm(fitted.means - mu, axis=1))) for mu in KNOWN.means]
    assert sorted(order) == [0, 1, 2]
    np.testing.assert_allclose(fitted.means[order], KNOWN.means, atol=0.03)
    np.testing.assert_allclose(fitted.weights[order], KNOWN.weights, atol=0.02)
    np.testing.assert_allclose(fitted.covariances[order], KNOWN.covariances, atol=0.03)
    assert fitted.weights.sum() == pytest.approx(1.0)  # eq. 9


def test_em_repeats_for_a_seed():
    samples = _draw(KNOWN, 3000)
    a, b = fit_mixture(samples, 3, seed=7), fit_mixture(samples, 3, seed=7)
    np.testing.assert_array_equal(a.means, b.means)


def test_closed_form_gradient_and_hessian_match_finite_differences():
    pts = np.random.default_rng(1).uniform(-1, 4, size=(50, 2))
    _, grad, hess = KNOWN.derivatives(pts)
    eps = 1e-5
    steps = (np.array([eps, 0.0]), np.array([0.0, eps]))
    fd_grad = np.column_stack(
        [(KNOWN.value(pts + d) - KNOWN.value(pts - d)) / (2 * eps) for d in steps]
    )
    np.testing.assert_allclose(grad, fd_grad, atol=1e-7)
    fd_hess = np.stack(
        [
            (KNOWN.derivatives(pts + d)[1] - KNOWN.derivatives(pts - d)[1]) / (2 * eps)
            for d in steps
        ],
        axis=1,
    )
    np.testing.assert_allclose(hess, fd_hess, atol=1e-6)


def test_more_components_than_the_data_supports_is_an_error():
    with pytest.raises(LeafError, match="more than the data supports"):
        fit_mixture(np.random.default_rng(0).normal(size=(20, 2)), 5, seed=0)


@pytest.mark.parametrize(
    "share, k, expected",
    [(1.0, 3, (3, 0)), (0.0, 2, (0, 2)), (0.5, 2, (1, 1)), (0.7, 4, (3, 1)), (0.02, 3, (0, 3)),
     (0.3, 1, (0, 1))],
)  # fmt: skip
def test_components_split_between_raised_and_lowered_parts(share, k, expected):
    assert split_components(share, k) == expected


def test_signed_mixture_fits_each_sign_apart():
    up = _draw(Mixture(np.ones(1), np.array([[0.0, 2.0]]), np.eye(2)[None] * 0.1, np.ones(1)), 600)
    down = _draw(
        Mixture(np.ones(1), np.array([[0.0, -2.0]]), np.eye(2)[None] * 0.1, np.ones(1)), 400
    )
    samples = np.vstack([up, down])
    positive = np.arange(1000) < 600
    joined = fit_signed_mixture(samples, positive, lambda s, k: fit_mixture(s, k, 0), 2)
    np.testing.assert_allclose(joined.means[:, 1], [2.0, -2.0], atol=0.05)
    np.testing.assert_allclose(joined.weights, [0.6, 0.4])


def test_a_fit_seeds_k_means_as_a_new_random_state_would():
    """fit_mixture's reused generator (gmm._seeded) draws what np.random.RandomState(seed) draws,
    whatever it drew before (its normal's cache too)."""
    from leafstudio.core.gmm import _seeded

    for seed in (0, 7, 2**31):
        _seeded(3).standard_normal(3)  # used, and a normal left cached
        fresh, reused = np.random.RandomState(seed), _seeded(seed)
        assert fresh.random_sample() == reused.random_sample()
        np.testing.assert_array_equal(fresh.uniform(size=4), reused.uniform(size=4))
        assert fresh.standard_normal() == reused.standard_normal()


def test_k_means_tolerance_reads_numpys_own_variance():
    """gmm._column_variances (k-means' tolerance) is np.var(axis=0) to the bit."""
    from leafstudio.core.gmm import _column_variances

    rng = np.random.default_rng(4)
    for trial in range(300):
        n = int(rng.integers(1, 5000 if trial % 2 else 30))
        x = rng.standard_normal((n, 2)) * rng.choice([1e-5, 1.0, 1e8]) + rng.choice([0.0, 1e3])
        assert _column_variances(x).tobytes() == np.var(x, axis=0).tobytes()
