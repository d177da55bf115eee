"""How near a form's own surface the method can come, and what holds it back (issue 21: the
mesh within 2e-3 of the length of a form's own surface, 95th percentile).

    .venv/bin/python benchmarks/bench_own_bound.py [--shapes reniform deltoid ...] [--k 3 6 10]

For every shape (flat, grid 128) and K: the 95th-percentile distance from our mesh to the
form's own surface (bench_bent.own_relief, a share of the length), with the paper's height
guide p(x) (core/height.py: linear between the margin and a vein, dipping between veins) and
with the form's own surface given as the guide instead (an oracle: `core.steps.height_guide`
replaced for the run). With the oracle the guide is exact, so what is left is the Gaussian
mixture's own reach at that K; what the oracle takes off is the guide's share.
"""

from __future__ import annotations

import argparse
from unittest import mock

import numpy as np
from bench_bent import off_own, own_relief  # the script's own folder is on the path

import leafstudio as ls
import leafstudio.core.steps as steps
from leafstudio.core.prepare.units import Units
from leafstudio.forms.make import Form
from leafstudio.forms.terms import SHAPES


def _p95(form: Form, k: int, oracle: bool) -> float:
    """The 95th-percentile distance to the form's own surface at K = `k`, grid 128."""
    leaf, own = form.leaf(), own_relief(form)
    params = ls.Params(k=k, grid=128)
    if not oracle:
        return float(np.percentile(off_own(ls.reconstruct(leaf, params), None, own), 95))
    units = Units.of(leaf)
    frame = ls.reconstruct(leaf, params).frame  # the run's plane, in the world
    origin = units.to_unit(frame.origin)
    up = np.sign(frame.normal[2])  # the plane's heights are along its normal

    def exact(nodes: np.ndarray, *_args, **_kwargs) -> np.ndarray:
        world = units.to_world(origin + nodes[:, :1] * frame.u + nodes[:, 1:2] * frame.v)
        return up * own(world[:, :2]) / units.scale

    with mock.patch.object(steps, "height_guide", exact):
        result = ls.reconstruct(leaf, params)
    return float(np.percentile(off_own(result, None, own), 95))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shapes", nargs="*", default=list(SHAPES))
    parser.add_argument("--k", nargs="*", type=int, default=[3, 6, 10])
    args = parser.parse_args()
    print("## own surface, 95th percentile (flat forms, grid 128; target 2e-3)")
    print("| shape | " + " | ".join(f"K {k}: paper guide / exact guide" for k in args.k) + " |")
    print("|---|" + "---|" * len(args.k))
    for shape in args.shapes:
        form = Form(shape)
        cells = [f"{_p95(form, k, False):.1e} / {_p95(form, k, True):.1e}" for k in args.k]
        print(f"| {shape} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
