"""The order of a vein's points does not matter (issue 10, finding 6): dense veins given shuffled
give the surface of the same veins in order, and any two shuffles give the same mesh."""

from __future__ import annotations

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.core.prepare.vein_order import ORDERED_PATH, vein_order, vein_orders

PARAMS = ls.Params(k=3, grid=96)


def _dense_veins(total: int = 100_000) -> ls.Leaf:
    """The nested demo with its veins resampled to `total` points in all, in order."""
    leaf = ls.demo("nested")
    lengths = np.array([np.linalg.norm(np.diff(v, axis=0), axis=1).sum() for v in leaf.veins])
    veins = []
    for vein, share in zip(leaf.veins, lengths / lengths.sum(), strict=True):
        arc = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(vein, axis=0), axis=1))])
        at = np.linspace(0, arc[-1], int(total * share))
        veins.append(np.column_stack([np.interp(at, arc, vein[:, k]) for k in range(3)]))
    return ls.Leaf(boundary=leaf.boundary, veins=veins)


def _shuffled(leaf: ls.Leaf, seed: int) -> ls.Leaf:
    rng = np.random.default_rng(seed)
    return ls.Leaf(boundary=leaf.boundary, veins=[rng.permutation(v) for v in leaf.veins])


@pytest.fixture(scope="module")
def runs() -> dict[str, ls.Result]:
    leaf = _dense_veins()
    return {
        "ordered": ls.reconstruct(leaf, PARAMS),
        "shuffled": ls.reconstruct(_shuffled(leaf, 1), PARAMS),
        "again": ls.reconstruct(_shuffled(leaf, 2), PARAMS),
    }


def test_shuffled_dense_veins_fit_as_well_as_ordered_ones(runs):
    ordered, shuffled = runs["ordered"].metrics, runs["shuffled"].metrics
    assert shuffled["veins"]["mean"] <= 1.2 * ordered["veins"]["mean"] + 1e-5
    assert shuffled["leaf"]["height"] == pytest.approx(ordered["leaf"]["height"], rel=0.02)


def test_any_two_shuffles_give_the_same_mesh(runs):
    a, b = runs["shuffled"].triangle_mesh, runs["again"].triangle_mesh
    np.testing.assert_array_equal(a.regular_faces, b.regular_faces)
    np.testing.assert_allclose(a.points, b.points, rtol=0, atol=1e-12)


def test_an_ordered_vein_keeps_its_order_and_a_shuffled_one_runs_along_its_axis():
    t = np.linspace(0, 1, 50)
    arc = np.column_stack([np.cos(2.5 * t), np.sin(2.5 * t)])  # turns 143°: not along one axis
    np.testing.assert_array_equal(vein_order(arc), np.arange(50))
    line = np.column_stack([t, 0.1 * t**2])
    order = vein_order(np.random.default_rng(0).permutation(line))
    steps = np.diff(np.random.default_rng(0).permutation(line)[order][:, 0])
    assert np.all(steps > 0) or np.all(steps < 0)


def test_the_veins_orders_at_once_are_each_veins_own():
    """vein_orders (the frame stage's: the veins in order found in one compiled pass) gives
    vein_order of each vein: ordered, shuffled, short, random, and a zigzag whose path is
    ORDERED_PATH times its box's diagonal to the bit (ordered, by vein_order's own sum)."""
    rng = np.random.default_rng(3)
    t = np.linspace(0, 1, 40)
    arc = np.column_stack([np.cos(2.5 * t), np.sin(2.5 * t)])
    back_and_forth = np.array([[0.0, 0.0], [1.0, 0.0]] * 2 + [[0.0, 0.0]])  # path 4, box 1
    assert ORDERED_PATH == 4.0
    veins = [arc, rng.permutation(arc), arc[:2], arc[:3], back_and_forth]
    veins += [rng.normal(size=(n, 2)) for n in (5, 30, 300)]
    for got, vein in zip(vein_orders(veins), veins, strict=True):
        np.testing.assert_array_equal(got, vein_order(vein))
    assert vein_orders([]) == []
