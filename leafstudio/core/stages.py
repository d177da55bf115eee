"""The pipeline's stages in order (section 3), what each depends on, and one run through them
(StageRun), each output from the one cache (store.StageStore) or computed (steps.py).

| stage    | depends on                             | output                                   |
|----------|----------------------------------------|------------------------------------------|
| frame    | the leaf, margin                       | PCA frame, 2D polygon, 2D veins, heights |
|          |                                        | above the base b(x) (base.py)            |
| implicit | frame, mpu_tolerance                   | the MPU implicit g                       |
| grid     | frame, grid                            | the regular grid                         |
| guide    | implicit, grid                         | g and p(x) on the grid                   |
| samples  | guide, samples, seed                   | the EM samples drawn from p (lazy)       |
| gmm      | samples, k                             | the EM mixture                           |
| bending  | guide, taper                           | the vein correction's centres, lattice   |
|          |                                        | and bending gram (lazy)                  |
| surface  | gmm, bending, refine, through_veins    | amplitudes, z on the kept grid nodes     |
| layout   | guide                                  | the conforming mesh in the plane and g's |
|          |                                        | derivatives at its vertices (lazy)       |
| mesh     | surface, layout, mesher, radius_factor | the triangle mesh in world coordinates   |


A stage reruns only when a value it depends on changed, so moving K reruns gmm, surface and mesh
(the samples and the layout are kept). Each parameter's stage is declared with it (model.Params);
the cache keys (STAGE_KEYS) follow from those declarations and this table's stage inputs
(STAGE_TABLE; tests/test_params.py checks that this table says the same). A lazy stage runs
only when a later stage asks for it. Every output goes through one StageStore, keyed by the
leaf's fingerprint and the stage's parameters, and so do what is made from a run's mesh after
the run, on first use: its metrics ("metrics", a result.Measuring) and its VTK mesh ("polydata",
a result.Later), kept under the mesh stage's key (Pipeline.run). numba's on-disk cache of
compiled kernels (_shared/kernelcache.py) is a compile cache, not a store of results.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, NamedTuple

from leafstudio.core import steps
from leafstudio.core.result import Cancelled
from leafstudio.model import PARAMS, Params

if TYPE_CHECKING:
    from leafstudio.core.pipeline import Pipeline


class Stage(NamedTuple):
    """One row of the stage table: its name, the stages whose outputs it reads, and how it is
    computed from them (``compute(run)``; parameters from ``run.params``). A lazy stage runs
    only when a later one asks for it (the layout: for the conforming mesher only)."""

    name: str
    inputs: tuple[str, ...]
    compute: Callable[[StageRun], Any]
    lazy: bool = False


#: The stages in order (the module docstring's table). A new step is a row here, a function
#: of a StageRun, and its parameters declared with stage=its name (model.Params).
STAGE_TABLE: dict[str, Stage] = {
    s.name: s
    for s in (
        Stage("frame", (), steps.compute_frame),
        Stage("implicit", ("frame",), steps.compute_implicit),
        Stage("grid", ("frame",), steps.compute_grid),
        Stage("guide", ("implicit", "grid"), steps.compute_guide),
        Stage("samples", ("guide",), steps.compute_samples, lazy=True),
        Stage("gmm", ("samples",), steps.compute_gmm),
        Stage("bending", ("guide",), steps.compute_bending, lazy=True),
        Stage("surface", ("gmm", "bending"), steps.compute_surface),
        Stage("layout", ("guide",), steps.compute_layout, lazy=True),
        Stage("mesh", ("surface", "layout"), steps.compute_mesh),
    )
}


STAGE_INPUTS: dict[str, tuple[str, ...]] = {s.name: s.inputs for s in STAGE_TABLE.values()}
STAGES = tuple(STAGE_TABLE)


def _upstream() -> dict[str, frozenset[str]]:
    """Each stage's inputs, their inputs and so on: what its function may read."""
    found: dict[str, frozenset[str]] = {}
    for stage, inputs in STAGE_INPUTS.items():
        found[stage] = frozenset(inputs).union(*(found[i] for i in inputs))
    return found


def _stage_keys() -> dict[str, tuple[str, ...]]:
    """Each stage's cache key: the parameters declared for it (model.Params, `stage`) and those
    of every stage it reads, in field order."""
    keys: dict[str, set[str]] = {}
    for stage, inputs in STAGE_INPUTS.items():
        own = {name for name, p in PARAMS.items() if p.stage == stage}
        keys[stage] = own.union(*(keys[i] for i in inputs))
    return {stage: tuple(n for n in PARAMS if n in names) for stage, names in keys.items()}


UPSTREAM = _upstream()
STAGE_KEYS = _stage_keys()


class StageRun:
    """One Pipeline.run: the stage outputs asked for so far, each from the store or computed.

    A stage's function reads the outputs of the stages it depends on as ``run["name"]`` and the
    parameters as ``run.params``; reading a stage that is not upstream of it is an error (its
    output could be stale: the cache key would not cover it).
    """

    def __init__(
        self,
        pipeline: Pipeline,
        params: Params,
        on_stage: Callable[[str], None] | None,
        should_stop: Callable[[], bool] | None,
    ) -> None:
        self.pipeline, self.params = pipeline, params
        self.on_stage, self.should_stop = on_stage, should_stop
        self.outputs: dict[str, Any] = {}
        self.timings: dict[str, float] = {}
        self.ran: list[str] = []
        self._running: list[str] = []  # the stages being computed, innermost last

    def __getitem__(self, name: str) -> Any:
        if self._running and name not in UPSTREAM[self._running[-1]]:
            raise KeyError(f"stage {self._running[-1]!r} reads {name!r}, not among its inputs")
        if name in self.outputs:
            return self.outputs[name]
        value = self.pipeline.store.setdefault(name, self.key(name), lambda: self._compute(name))
        self.outputs[name] = value
        return value

    def key(self, stage: str) -> tuple[Any, ...]:
        """`stage`'s key in the store: the leaf's digest and the parameters it reads."""
        return (self.pipeline.leaf_key, *(getattr(self.params, k) for k in STAGE_KEYS[stage]))

    def _compute(self, name: str) -> Any:
        if self.should_stop is not None and self.should_stop():
            raise Cancelled
        if self.on_stage is not None:
            self.on_stage(name)
        start = time.perf_counter()
        inner = sum(self.timings.values())
        self._running.append(name)
        try:
            value = STAGE_TABLE[name].compute(self)
        finally:
            self._running.pop()
        # a stage's own time: less that of the (lazy) stages it asked for meanwhile
        self.timings[name] = time.perf_counter() - start - (sum(self.timings.values()) - inner)
        self.ran.append(name)
        return value
