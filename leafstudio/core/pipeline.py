"""Steps 1-5 in order (section 3): `Pipeline` runs the stages (stages.py: the table, what each
depends on; steps.py: what each computes) through one cache of stage outputs (store.StageStore),
and `reconstruct` is the one call. A run works on the leaf at unit size (prepare/units.py) and its
Result (result.py) is mapped back to the input's coordinates; a bent leaf's flat blade is
reconstructed and the Result bent again (bend.py).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable

from leafstudio._shared.blas import one_blas_thread
from leafstudio.core.bend import flat_leaf
from leafstudio.core.bent_result import bent_result
from leafstudio.core.grid import Grid
from leafstudio.core.kernels import BENT, STAGE, compile_kernels
from leafstudio.core.pose_limits import check_pose
from leafstudio.core.prepare.plausibility import BentRefusal
from leafstudio.core.prepare.units import Units
from leafstudio.core.result import Cancelled, Later, Result, in_world
from leafstudio.core.stages import STAGE_TABLE, STAGES, StageRun
from leafstudio.core.steps import BENT_NOTES, FrameStage, GuideStage, SurfaceStage
from leafstudio.core.store import StageStore, leaf_key
from leafstudio.core.unfolded import pose_note, unfolded, unposed_hint
from leafstudio.errors import LeafError
from leafstudio.model import Leaf, Params, as_leaf, as_params

__all__ = ["Cancelled", "Pipeline", "Result", "reconstruct"]


class Pipeline:
    """The staged reconstruction of one leaf, keeping each stage's last output (StageStore).

    Examples
    --------
    >>> import leafstudio as ls
    >>> pipe = ls.Pipeline(ls.demo("nested"))
    >>> r1 = pipe.run(ls.Params(k=3, grid=64))
    >>> r2 = pipe.run(ls.Params(k=4, grid=64))
    >>> r2.ran
    ('gmm', 'surface', 'mesh')
    """

    def __init__(self, leaf: Leaf, store: StageStore | None = None) -> None:
        # a clear TypeError for anything else; curves bent in 3D without a bend get the one
        # that lays them flat (unfold.py)
        self.leaf = leaf = unfolded(as_leaf(leaf))
        # a pose past what it keeps of the blade (a Leaf built with Pose(fold=89)) is refused
        # as the loader refuses it, before a bad mesh is made of it (pose_limits.py)
        check_pose(leaf.bend, leaf.boundary, list(leaf.veins))
        self.pose_note = pose_note(leaf)  # once a leaf, not at every run (_frame_notes)
        self.flat = flat_leaf(leaf)  # a bent leaf's flat blade (bend.py); else the leaf itself
        self.units = Units.of(self.flat)  # the stages run on the leaf at unit size (units.py)
        self.unit_leaf = self.units.leaf(self.flat)
        self.leaf_key = leaf_key(leaf)
        self.store = StageStore() if store is None else store

    def run(
        self,
        params: Params,
        on_stage: Callable[[str], None] | None = None,
        should_stop: Callable[[], bool] | None = None,
    ) -> Result:
        """Run the stages whose inputs changed since the last run and return the Result.

        Parameters
        ----------
        params : Params
        on_stage : callable, optional
            Called with a stage's name just before it runs; on a cold kernel cache first with
            "kernels", then "kernels 1/28", ... as they are compiled (core/kernels.py).
        should_stop : callable, optional
            Polled between stages; when it returns True the run raises Cancelled.

        Returns
        -------
        Result
            `Result.ran` names the stages this run computed.

        Raises
        ------
        LeafError
            For input the reconstruction cannot take (too few boundary points, a boundary that
            crosses itself, veins far outside it, ...), or params that are not valid Params.
        Cancelled
            When `should_stop` said so.
        """
        run = StageRun(self, as_params(params), on_stage, should_stop)
        # the first run only: in parallel, ahead of the stages (stopped, the first stage raises);
        # a bent leaf's own kernels with them, a flat leaf's run not waiting for those
        tables = (STAGE,) if self.leaf.bend is None else (STAGE, BENT)
        compile_kernels(on_stage, should_stop=should_stop, tables=tables)
        with one_blas_thread():  # its solves are small: a second thread only waits (blas.py)
            return self._result(run)

    def _frame_notes(self, fs: FrameStage) -> list[str]:
        """The frame stage's notes on the flat blade; a bent leaf's say that its blade, not the
        leaf, is flat (steps.BENT_NOTES): the stage is the same for every bend of a blade."""
        if self.leaf.bend is None:
            return list(fs.notes)
        said = self.pose_note  # a pose fitted wrong to 3D curves (unfolded.OFF_FLAT)
        return [BENT_NOTES.get(note, note) for note in fs.notes] + ([said] if said else [])

    @staticmethod
    def _vein_notes(run: StageRun, fs: FrameStage) -> list[str]:
        """What the vein correction says of veins that disagree where they meet (correct.py);
        nothing for the paper's surface, which asks no vein to be met."""
        if not (run.params.through_veins and fs.veins):
            return []
        return run["bending"].notes(fs.length)

    def _result(self, run: StageRun) -> Result:
        """Run the stages `run` needs and make its Result (run)."""
        # one after another: the bending and layout stages in a second thread beside samples
        # and gmm took a flat ovate's run at grid 128 from 28-30 to 34-39 ms of wall time on this
        # 2-core machine (gmm 3 -> 7.5 ms, bending 5.3 -> 9: the kernels release the GIL, yet the
        # two threads slowed each other down more than they overlapped)
        try:
            for stage in STAGES:
                if not STAGE_TABLE[stage].lazy:
                    run[stage]
        except BentRefusal as exc:  # said why, when the leaf is bent and nothing lays it flat
            if not (hint := unposed_hint(self.leaf)):
                raise
            raise LeafError(exc.problem + hint, exc.source) from exc
        fs: FrameStage = run["frame"]
        grid: Grid = run["grid"]
        guide: GuideStage = run["guide"]
        samples, em_mixture = run["gmm"]
        surf: SurfaceStage = run["surface"]
        nodes = guide.nodes
        unit = Result(
            leaf=self.unit_leaf,
            params=run.params,
            frame=fs.frame,
            polygon=fs.polygon,
            grid=grid,
            g_grid=guide.g,
            p_grid=guide.p,
            inside=guide.inside,
            em_samples=samples,
            em_mixture=em_mixture,
            surface=surf.surface,
            surface_points=fs.frame.to_world(nodes, surf.z),
            triangle_mesh=run["mesh"],
            length=fs.length,
            timings=run.timings,
            ran=tuple(run.ran),
            warnings=self._frame_notes(fs) + self._vein_notes(run, fs),
        )
        result = bent_result(in_world(unit, self.flat, self.units), self.leaf, self.units)
        # what is made from the mesh on first use: entries of the store under the mesh's key
        key = run.key("mesh")
        result.measuring = self.store.setdefault("metrics", key, result.new_measuring)
        result.polydata = self.store.setdefault(
            "polydata", key, lambda: Later(result.triangle_mesh.to_pyvista)
        )
        if result.unit is not None:
            result.unit.measuring = result.measuring
        return result


def reconstruct(leaf: Leaf, params: Params | None = None) -> Result:
    """Reconstruct a leaf's surface in one call (a fresh Pipeline).

    Warnings (such as a leaf without veins being flat) are issued with `warnings.warn` and kept in
    `Result.warnings`.

    Parameters
    ----------
    leaf : Leaf
        The (n, 3) boundary and (m_i, 3) veins, in any units and position.
    params : Params, optional
        The settings; default Params() (K 3, grid 128).

    Returns
    -------
    Result
        The surface, its mesh in the leaf's coordinates, and the measurements.

    Raises
    ------
    LeafError
        For input the reconstruction cannot take, saying why.

    Examples
    --------
    >>> import leafstudio as ls
    >>> result = ls.reconstruct(ls.demo("parallel"), ls.Params(k=2, grid=32))
    >>> result.chosen_k, result.triangle_mesh.points.shape[1]
    (2, 3)
    >>> ls.reconstruct(ls.Leaf([[0, 0, 0], [1, 0, 0]]))
    Traceback (most recent call last):
    leafstudio.errors.LeafError: the boundary needs at least 3 distinct points, got 2
    """
    result = Pipeline(leaf).run(as_params(params))
    for note in result.warnings:
        warnings.warn(note, stacklevel=2)
    return result
