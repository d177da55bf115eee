"""Automatic K: BIC on the EM samples picks the number of separate bumps, and on the paper's
leaves a K whose surface is no farther from the input than the paper's."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.mixture import GaussianMixture

import leafstudio as ls
from leafstudio.core.autok import bic, choose_mixture
from leafstudio.core.gmm import Mixture, fit_mixture, fit_signed_mixture, sample_guide
from leafstudio.sources.demos import PAPER_K

CENTRES = np.array([[0.5, 0.5], [1.5, 0.6], [2.5, 0.4]])


def _three_bumps(seed: int, signs=(1, 1, 1)) -> tuple[np.ndarray, np.ndarray]:
    """EM samples drawn from heights made of three well-separated Gaussian bumps, and whether
    each sample comes from a positive height."""
    xs, ys = np.meshgrid(np.linspace(0, 3, 121), np.linspace(0, 1, 41))
    nodes = np.column_stack([xs.ravel(), ys.ravel()])
    heights = sum(
        s * h * np.exp(-np.sum((nodes - c) ** 2, axis=1) / (2 * 0.12**2))
        for s, h, c in zip(signs, (1.0, 0.6, 0.8), CENTRES, strict=True)
    )
    samples = sample_guide(nodes, heights, 4000, 0.025, seed)
    nearest = np.argmin(np.sum((samples[:, None] - CENTRES[None]) ** 2, axis=2), axis=1)
    return samples, np.asarray(signs)[nearest] > 0


@pytest.mark.parametrize("seed", [0, 1])
def test_three_separate_bumps_give_three_components(seed):
    samples, _ = _three_bumps(seed)
    mixture, scores = choose_mixture(lambda k: fit_mixture(samples, k, seed), samples)
    assert len(mixture.weights) == 3
    assert set(scores) == set(range(1, 13))
    order = np.argsort(mixture.means[:, 0])
    assert np.allclose(mixture.means[order], CENTRES, atol=0.03)


def test_bumps_of_both_signs_count_together():
    samples, positive = _three_bumps(0, signs=(1, -1, 1))
    fit = lambda k: fit_signed_mixture(  # noqa: E731
        samples, positive, lambda part, k_part: fit_mixture(part, k_part, 0), k
    )
    mixture, scores = choose_mixture(fit, samples)
    assert len(mixture.weights) == 3
    assert max(scores) == 12
    assert mixture.weights.sum() == pytest.approx(1.0)


def test_bic_is_sklearns():
    samples, _ = _three_bumps(0)
    reference = GaussianMixture(2, covariance_type="full", random_state=0).fit(samples)
    mixture = Mixture(
        reference.weights_, reference.means_, reference.covariances_, reference.weights_
    )
    assert bic(mixture, samples) == pytest.approx(reference.bic(samples), rel=1e-9)


def test_few_samples_limit_the_ks_tried():
    samples = np.random.default_rng(0).normal(size=(20, 2))
    mixture, scores = choose_mixture(lambda k: fit_mixture(samples, k, 0), samples)
    assert max(scores) == 4  # fit_mixture needs 5 distinct samples per component
    assert len(mixture.weights) in scores


def test_too_few_samples_for_one_component_is_an_error():
    samples = np.zeros((50, 2))
    with pytest.raises(ls.LeafError, match="more than the data supports"):
        choose_mixture(lambda k: fit_mixture(samples, k, 0), samples)


@pytest.mark.parametrize("name", ["nested", "parallel"])
def test_auto_k_is_no_worse_than_the_papers_k(name):
    """The mixtures themselves: without the correction onto the veins (correct.py), which
    brings either onto them."""
    pipe = ls.Pipeline(ls.demo(name))
    paper = pipe.run(ls.Params(k=PAPER_K[name], through_veins=False))
    auto = pipe.run(ls.Params(k="auto", through_veins=False))
    assert auto.ran == ("gmm", "surface", "mesh")
    assert 1 <= auto.chosen_k <= 12
    assert paper.chosen_k == PAPER_K[name]
    assert auto.metrics["veins"]["mean"] <= paper.metrics["veins"]["mean"] * 1.001
    assert auto.metrics["veins"]["max"] <= paper.metrics["veins"]["max"] * 1.001
    assert auto.metrics["boundary"]["max"] <= paper.metrics["boundary"]["max"] + 1e-9


def test_auto_on_a_flat_leaf_is_one_flat_component():
    t = np.linspace(0, 2 * np.pi, 100, endpoint=False)
    leaf = ls.Leaf(boundary=np.column_stack([np.cos(t), 0.5 * np.sin(t), np.zeros_like(t)]))
    result = ls.Pipeline(leaf).run(ls.Params(k="auto", grid=32))
    assert result.chosen_k == 1
    assert np.allclose(result.mesh["height"], 0)


@pytest.mark.parametrize("bad", ["many", "Auto", 0, 13.0, True])
def test_params_reject_other_ks(bad):
    with pytest.raises(ls.LeafError, match="K must be"):
        ls.Params(k=bad)


def test_params_accept_auto_and_round_trip():
    params = ls.Params(k="auto")
    assert ls.Params.from_dict(params.to_dict()) == params


def test_auto_k_on_a_guide_between_the_grids_nodes_says_to_raise_the_grid():
    """Fuzzing finding (hunt26): a narrow blade at grid 16, whose veins fall between the grid's
    nodes, said "K = 1 is more than the data supports: ... raise the grid resolution" for K = 1
    but "the height guide is zero everywhere: nothing to fit" for K = auto, which no setting
    answers. K = auto now says to raise the grid, as K = 1 does, in its own words."""
    from leafstudio.forms import Form

    leaf = Form("orbicular", aspect=26.5, margin="serrulate").leaf()
    with pytest.raises(ls.LeafError, match=r"too few for even one component.*raise the grid"):
        ls.reconstruct(leaf, ls.Params(grid=16, k="auto"))
    assert ls.reconstruct(leaf, ls.Params(grid=24, k="auto")).chosen_k >= 1
