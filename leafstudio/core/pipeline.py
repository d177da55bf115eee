"""Steps 1-5 in order (section 3): the staged pipeline with one cache of stage outputs (StageStore),
and its Result.

| stage    | depends on                             | output                                   |
|----------|----------------------------------------|------------------------------------------|
| frame    | the leaf, margin                       | PCA frame, 2D polygon, 2D veins, heights |
|          |                                        | above the base b(x) (base.py)            |
| implicit | frame, mpu_tolerance                   | the MPU implicit g                       |
| grid     | frame, grid                            | the regular grid                         |
| guide    | implicit, grid                         | g and p(x) on the grid                   |
| samples  | guide, samples, seed                   | the EM samples drawn from p (lazy)       |
| gmm      | samples, k                             | the EM mixture                           |
| surface  | gmm, taper, refine, through_veins      | amplitudes, z on the kept grid nodes     |
| layout   | guide                                  | the conforming mesh in the plane and g's |
|          |                                        | derivatives at its vertices (lazy)       |
| mesh     | surface, layout, mesher, radius_factor | the triangle mesh in world coordinates   |

A stage reruns only when a value it depends on changed, so moving K reruns gmm, surface and mesh
(the samples and the layout are kept). Each parameter's stage is declared with it (model.Params);
the cache keys (STAGE_KEYS) follow from those declarations and this table's stage inputs
(STAGE_TABLE; tests/test_params.py checks that this table says the same). A lazy stage runs
only when a later stage asks for it. Every output goes through one StageStore, keyed by the
leaf's fingerprint and the stage's parameters; numba's on-disk cache of compiled kernels
(_shared/kernelcache.py) is a compile cache, not a store of results.
"""

from __future__ import annotations

import threading
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from leafstudio.core import evaluate, mesher
from leafstudio.core.autok import choose_mixture
from leafstudio.core.base import PLANAR, BaseSurface, fit_base
from leafstudio.core.bend import bent_result, flat_leaf
from leafstudio.core.correct import onto_veins
from leafstudio.core.curvature import graph_curvatures
from leafstudio.core.evaluate import curvature_summary, shape_measurements
from leafstudio.core.gmm import Mixture, fit_mixture, fit_signed_mixture, sample_guide
from leafstudio.core.grid import Grid, make_grid
from leafstudio.core.height import height_guide
from leafstudio.core.mpu import MPUImplicit, build_mpu
from leafstudio.core.plane import Frame, fit_frame
from leafstudio.core.prepare.outline import (
    EdgeBands,
    contains,
    distinct_indices,
    edge_bands,
    outward_normals,
    thin_outline,
    thin_veins,
    trace_outline,
)
from leafstudio.core.prepare.plausibility import (
    check_boundary,
    check_not_a_surface,
    keep_outer_loop,
)
from leafstudio.core.prepare.units import ScaledSurface, Units
from leafstudio.core.prepare.vein_order import vein_order
from leafstudio.core.store import MISSING, StageStore, leaf_key
from leafstudio.core.surface import HeightSurface, fit_surface
from leafstudio.core.trianglemesh import TriangleMesh
from leafstudio.errors import LeafError
from leafstudio.model import K_AUTO, PARAMS, Leaf, Params, as_leaf, as_params

if TYPE_CHECKING:
    import pyvista as pv

MIN_NODES_PER_COMPONENT = 5
GUIDE_STEP = 0.5  # the guide's curves are thinned to this fraction of the grid step (height.py)
VEIN_OUTSIDE_TOLERANCE = 0.01  # vein points may stray this fraction of the leaf length outside


class Cancelled(Exception):
    """Raised inside `Pipeline.run` (or `Result.measure`) when its `should_stop` callback says
    so."""


_MEASURING = threading.Lock()  # held while a Result takes one step of its measuring


@dataclass(frozen=True)
class FrameStage:
    """Step 1 output: the plane frame and everything projected onto it."""

    frame: Frame
    polygon: np.ndarray  # (b, 2) counter-clockwise leaf outline
    veins: list[np.ndarray]  # (m_i, 2) per vein
    heights: list[np.ndarray]  # (m_i,) signed heights per vein above the base, h_v − b(v')
    length: float  # leaf length along its main axis
    polygon_h: np.ndarray | None = None  # (b,) the outline points' own heights; None: planar
    base: BaseSurface | None = None  # b(x) through the outline's heights; None: b ≡ 0
    bands: EdgeBands | None = None  # the polygon's edge_bands, for contains
    notes: tuple[str, ...] = ()  # what the run should warn of (dropped loops, a flat leaf)

    @property
    def flat(self) -> bool:
        """No vein rises off the base: the surface is the base (or the plane) itself."""
        return not self.veins or not np.any(np.abs(self.vein_h) > 1e-9 * self.length)

    @property
    def vein_xy(self) -> np.ndarray:
        return np.vstack(self.veins) if self.veins else np.zeros((0, 2))

    @property
    def vein_h(self) -> np.ndarray:
        return np.concatenate(self.heights) if self.heights else np.zeros(0)


@dataclass(frozen=True)
class GuideStage:
    """g and p on the grid; `inside` marks the nodes kept (g >= 0)."""

    g: np.ndarray
    p: np.ndarray
    inside: np.ndarray


@dataclass(frozen=True)
class SurfaceStage:
    """The fitted height surface and its values on the kept grid nodes."""

    surface: HeightSurface
    z: np.ndarray


@dataclass
class Result:
    """Everything one run produced; the mesh is in the input's (world) coordinates.

    Attributes
    ----------
    leaf, params : Leaf, Params
        What was reconstructed, and how.
    frame : Frame
        The boundary's PCA plane: `frame.to_plane` maps (n, 3) world points to (n, 2) plane
        points and heights, `frame.to_world` back.
    triangle_mesh : TriangleMesh
        The mesh as arrays: (n, 3) `points`, (m, 3) `regular_faces`, and (n,) point arrays
        height, mean_curvature, gaussian_curvature, k1, k2.
    mesh : pyvista.PolyData
        The same mesh for VTK, made on first use.
    metrics : dict
        Table-1 distances ("boundary", "veins"), mesh facts ("mesh"), sizes ("leaf"), curvature
        ranges ("curvature"); measured on first use.
    chosen_k : int
        The K the surface uses (the BIC's choice when params.k is "auto").
    warnings : list of str
        What the run noticed (a leaf without veins is flat, ...).
    ran, timings : tuple of str, dict of str to float
        The stages this run computed (the others came from the cache), and their seconds.

    Examples
    --------
    >>> import leafstudio as ls
    >>> result = ls.reconstruct(ls.demo("nested"), ls.Params(k=3, grid=32))
    >>> result.triangle_mesh.points.shape, result.chosen_k
    ((372, 3), 3)
    >>> result.metrics["mesh"]["components"], round(result.metrics["leaf"]["length"], 6)
    (1, 1.0)
    """

    leaf: Leaf
    params: Params
    frame: Frame
    polygon: np.ndarray
    grid: Grid
    g_grid: np.ndarray  # (ny * nx,) g at every grid node
    p_grid: np.ndarray  # (ny * nx,) the probability map, 0 outside
    inside: np.ndarray  # (ny * nx,) bool, g >= 0
    em_samples: np.ndarray  # (s, 2) points drawn from p for EM
    surface: HeightSurface
    surface_points: np.ndarray  # (n, 3) the GMM samples: kept grid nodes lifted, world coords
    triangle_mesh: TriangleMesh  # the mesh's arrays: points, triangles, height and curvatures
    length: float
    timings: dict[str, float] = field(default_factory=dict)
    ran: tuple[str, ...] = ()
    warnings: list[str] = field(default_factory=list)
    unit: Result | None = None  # the same run at unit size (units.py); None: this is it
    units: Units | None = None  # how `unit` maps to this one
    # the metrics once measured, and the measuring steps under way (see measure)
    _metrics: dict[str, Any] | None = field(default=None, init=False, repr=False, compare=False)
    _steps: evaluate.Steps | None = field(default=None, init=False, repr=False, compare=False)

    def height(self, xy: np.ndarray) -> np.ndarray:
        """z of the surface at (n, 2) plane points (differentiable; see surface.py).

        Parameters
        ----------
        xy : (n, 2) or (2,) float array
            Points in the plane frame's coordinates (`frame.to_plane` of world points).

        Returns
        -------
        (n,) float array
            The surface's height above the plane there, z(x) = b(x) + tanh(g/δ) Σ a_k N_k(x).

        Examples
        --------
        >>> import leafstudio as ls
        >>> result = ls.reconstruct(ls.demo("nested"), ls.Params(k=3, grid=32))
        >>> midrib = np.array([[0.3, 0.0, 0.0], [0.5, 0.0, 0.0], [0.7, 0.0, 0.0]])
        >>> xy, _ = result.frame.to_plane(midrib)
        >>> result.height(xy).round(2).tolist()  # heights along the midrib, base to tip
        [0.02, 0.03, 0.04]
        """
        return self.surface(np.atleast_2d(np.asarray(xy, dtype=float)))

    @property
    def chosen_k(self) -> int:
        """The K the surface uses: params.k, or the one chosen when params.k is "auto"."""
        return len(self.surface.mixture.weights)

    @cached_property
    def mesh(self) -> pv.PolyData:
        """The mesh as a pyvista.PolyData with its point arrays, built on first use: a run itself
        never creates a VTK object (the app draws from `triangle_mesh` on its main thread)."""
        return self.triangle_mesh.to_pyvista()

    @property
    def metrics(self) -> dict[str, Any]:
        """The paper's Table 1 distances and the mesh's facts (see evaluate.table_metrics), the
        leaf's measurements with the K used ("leaf") and its curvature ranges ("curvature"; see
        measure.py). Measured at unit size and mapped back (units.py): they do not depend on
        the input's units or its distance from the origin. Computed once (see measure)."""
        return self.measure()

    @property
    def measured(self) -> bool:
        """True once `metrics` are computed."""
        return self._metrics is not None

    def measure(self, should_stop: Callable[[], bool] | None = None) -> dict[str, Any]:
        """`metrics`, computed in steps (distances, mesh facts, shape, curvature, in pieces):
        when `should_stop()` is true after a step, Cancelled is raised, and the next call goes
        on from there (the app stops measuring a shown result when a newer request waits; the
        steps done are kept)."""
        if self._metrics is None:
            if self.unit is not None and self.units is not None:
                self._metrics = self.units.metrics(self.unit.measure(should_stop))
            else:
                self._metrics = self._measure_in_steps(should_stop)
        return self._metrics

    def _measure_in_steps(self, should_stop: Callable[[], bool] | None) -> dict[str, Any]:
        while True:
            with _MEASURING:  # one thread at a time runs the steps (a generator is not shared)
                if self._metrics is not None:  # another thread finished them meanwhile
                    return self._metrics
                if self._steps is None:
                    self._steps = self._metric_steps()
                try:
                    next(self._steps)
                except StopIteration as stop:
                    self._metrics, self._steps = stop.value, None
                    return self._metrics
                except BaseException:
                    self._steps = None  # a failed step: the next call starts again
                    raise
            if should_stop is not None and should_stop():
                raise Cancelled

    def _metric_steps(self) -> evaluate.Steps[dict[str, Any]]:
        table = yield from evaluate.table_steps(self.triangle_mesh, self.leaf)
        yield
        area = table["mesh"]["area"]
        shape = shape_measurements(self.triangle_mesh, self.frame, self.polygon, area)
        yield
        curvature = curvature_summary(self.triangle_mesh)
        return {**table, "leaf": {**shape, "k": self.chosen_k}, "curvature": curvature}


def _frame_stage(leaf: Leaf, margin: str = "auto", units: Units | None = None) -> FrameStage:
    scale, offset = (units.scale, units.offset) if units is not None else (1.0, None)
    check_not_a_surface(leaf.boundary)  # a whole scan given as the boundary: an error
    check_boundary(leaf.boundary, scale, offset)  # a figure eight would lose a lobe: an error
    boundary, notes = keep_outer_loop(leaf.boundary)  # holes, separate loops: dropped, and said
    if notes:
        leaf = Leaf(boundary, leaf.veins)
    frame = fit_frame(leaf.boundary, leaf.vein_points)
    xy, boundary_h = frame.to_plane(leaf.boundary)
    outline = trace_outline(xy, boundary_h, margin)  # input points, or a noisy cloud's mean
    kept_vertices = thin_outline(outline.polygon)  # a few thousand vertices at most
    polygon = outline.polygon[kept_vertices]
    bands = edge_bands(polygon)
    length = float(np.ptp(polygon[:, 0]))
    if np.max(np.abs(boundary_h)) <= PLANAR * length:  # planar: no base
        polygon_h = np.zeros(len(polygon))
    else:
        polygon_h = outline.heights[kept_vertices]
    base = fit_base(polygon, polygon_h, length)
    if outline.smoothed and base is not None:  # a noisy margin: on the smooth base itself
        polygon_h = base(polygon)
    veins, heights = [], []
    projected = [frame.to_plane(vein) for vein in leaf.veins]
    orders = [vein_order(v_xy) for v_xy, _ in projected]  # shuffled veins sorted (veins.py)
    projected = [(v_xy[o], v_h[o]) for (v_xy, v_h), o in zip(projected, orders, strict=True)]
    distinct = [distinct_indices(v_xy, length) for v_xy, _ in projected]
    kept = thin_veins([v_xy[keep] for (v_xy, _), keep in zip(projected, distinct, strict=True)])
    for i, (v_xy, v_h) in enumerate(projected):
        keep = distinct[i][kept[i]]  # dense veins: a few thousand points in all (thin_veins)
        v_xy = v_xy[keep]
        outside = ~contains(polygon, v_xy, bands)
        if outside.any():
            from shapely import LinearRing, distance, points

            gap = distance(LinearRing(polygon), points(v_xy[outside])).max()
            if gap > VEIN_OUTSIDE_TOLERANCE * length:
                raise LeafError(
                    f"vein {i + 1}: {outside.sum()} of {len(v_xy)} points lie outside the "
                    f"boundary (up to {gap / length:.1%} of the leaf length)"
                )
        veins.append(v_xy)
        heights.append(v_h[keep] - (base(v_xy) if base is not None else 0.0))
    if base is not None:
        if not veins:
            notes.append("no veins given: the surface only follows the boundary's heights")
    elif not veins:
        notes.append("no veins given: the leaf is flat")
    elif all(np.allclose(h, 0, atol=1e-9 * length) for h in heights):
        notes.append("all veins lie in the boundary's plane: the leaf is flat")
    return FrameStage(
        frame=frame,
        polygon=polygon,
        veins=veins,
        heights=heights,
        length=length,
        polygon_h=None if base is None else polygon_h,
        base=base,
        bands=bands,
        notes=tuple(notes),
    )


def _flat_mixture(center: np.ndarray) -> Mixture:
    """A mixture of amplitude zero: the surface of a leaf without relief."""
    return Mixture(
        weights=np.ones(1),
        means=center[None].copy(),
        covariances=np.eye(2)[None].copy(),
        amplitudes=np.zeros(1),
    )


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
        store = self.pipeline.store
        key = (self.pipeline.leaf_key, *(getattr(self.params, k) for k in STAGE_KEYS[name]))
        value = store.get(name, key)
        if value is MISSING:
            value = self._compute(name)
            store.put(name, key, value)
        self.outputs[name] = value
        return value

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
        self.leaf = leaf = as_leaf(leaf)  # a clear TypeError for anything else
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
            Called with a stage's name just before it runs.
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
        for stage in STAGES:
            if not STAGE_TABLE[stage].lazy:
                run[stage]
        fs: FrameStage = run["frame"]
        grid: Grid = run["grid"]
        guide: GuideStage = run["guide"]
        samples, _ = run["gmm"]
        surf: SurfaceStage = run["surface"]
        nodes = grid.points[guide.inside]
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
            surface=surf.surface,
            surface_points=fs.frame.to_world(nodes, surf.z),
            triangle_mesh=run["mesh"],
            length=fs.length,
            timings=run.timings,
            ran=tuple(run.ran),
            warnings=list(fs.notes),
        )
        return bent_result(_in_world(unit, self.flat, self.units), self.leaf, self.units)


def _in_world(unit: Result, leaf: Leaf, units: Units) -> Result:
    """The unit-size run `unit` in the input's coordinates (units.py)."""
    s = units.scale
    return Result(
        leaf=leaf,
        params=unit.params,
        frame=units.frame(unit.frame),
        polygon=s * unit.polygon,
        grid=units.grid(unit.grid),
        g_grid=s * unit.g_grid,
        p_grid=s * unit.p_grid,
        inside=unit.inside,
        em_samples=s * unit.em_samples,
        surface=ScaledSurface(unit.surface, s),  # type: ignore[arg-type]
        surface_points=units.to_world(unit.surface_points),
        triangle_mesh=units.mesh(unit.triangle_mesh),
        length=s * unit.length,
        timings=unit.timings,
        ran=unit.ran,
        warnings=unit.warnings,
        unit=unit,
        units=units,
    )


def _frozen(*arrays: np.ndarray) -> None:
    """Make stored arrays read-only: later runs share them."""
    for array in arrays:
        array.flags.writeable = False


def _frame(run: StageRun) -> FrameStage:
    pipe = run.pipeline
    return _frame_stage(pipe.unit_leaf, run.params.margin, pipe.units)


def _implicit(run: StageRun) -> MPUImplicit:
    fs: FrameStage = run["frame"]
    tol = run.params.mpu_tolerance * fs.length
    normals = outward_normals(fs.polygon)
    return build_mpu(fs.polygon, normals, tol, lambda q: contains(fs.polygon, q, fs.bands))


def _grid(run: StageRun) -> Grid:
    return make_grid(run["frame"].polygon, run.params.grid)


def _guide(run: StageRun) -> GuideStage:
    fs: FrameStage = run["frame"]
    grid: Grid = run["grid"]
    nodes = grid.points
    g = run["implicit"].on_grid(grid)
    inside = g >= 0
    p = np.zeros(len(nodes))
    p[inside] = height_guide(
        nodes[inside], fs.polygon, fs.veins, fs.heights, step=GUIDE_STEP * grid.spacing
    )
    return GuideStage(g=g, p=p, inside=inside)


def _samples(run: StageRun) -> np.ndarray:
    """The EM samples drawn from the guide (gmm.sample_guide): a new K refits the same ones."""
    guide: GuideStage = run["guide"]
    grid: Grid = run["grid"]
    inside = guide.inside
    drawn = sample_guide(
        grid.points[inside], guide.p[inside], run.params.samples, grid.spacing, run.params.seed
    )
    _frozen(drawn)
    return drawn


def _gmm(run: StageRun) -> tuple[np.ndarray, Mixture]:
    fs: FrameStage = run["frame"]
    guide: GuideStage = run["guide"]
    grid: Grid = run["grid"]
    params = run.params
    if fs.flat:
        return np.zeros((0, 2)), _flat_mixture(fs.polygon.mean(axis=0))
    p_in = guide.p[guide.inside]
    support = int(np.count_nonzero(p_in))  # grid nodes the samples can come from
    if params.k != K_AUTO and params.k > support // MIN_NODES_PER_COMPONENT:
        raise LeafError(
            f"K = {params.k} is more than the data supports: the height guide covers only "
            f"{support} grid nodes (at least {MIN_NODES_PER_COMPONENT} per component needed); "
            f"lower K or raise the grid resolution"
        )
    samples = run["samples"]
    # the sign of p at each sample's node: veins above and below the plane are fitted apart
    cell = np.rint((samples - grid.origin) / grid.spacing).astype(int)
    ny, nx = grid.shape
    cell = np.clip(cell, 0, [nx - 1, ny - 1])
    positive = guide.p[cell[:, 1] * nx + cell[:, 0]] >= 0

    def fit(k: int) -> Mixture:
        return fit_signed_mixture(
            samples, positive, lambda part, k_part: fit_mixture(part, k_part, params.seed), k
        )

    # auto: K from 1 to 12 (both signs together) by the BIC of the joined fit (autok.py)
    mixture = choose_mixture(fit, samples)[0] if params.k == K_AUTO else fit(params.k)
    return samples, mixture


def _surface(run: StageRun) -> SurfaceStage:
    fs: FrameStage = run["frame"]
    guide: GuideStage = run["guide"]
    nodes = run["grid"].points[guide.inside]
    g_in = guide.g[guide.inside]
    surface = fit_surface(
        run["gmm"][1],
        run["implicit"],
        nodes,
        g_in,
        guide.p[guide.inside],
        fs.vein_xy,
        fs.vein_h,
        run.params.taper,
        run.params.refine,
        run.params.seed,
        base=fs.base,
    )
    if run.params.through_veins:  # onto every vein point (correct.py)
        surface = onto_veins(surface, fs.veins, fs.heights, fs.length)
    return SurfaceStage(surface=surface, z=surface(nodes, g_in))


class Layout(NamedTuple):
    """The conforming mesh in the plane and g's derivatives at its vertices: they depend on
    nothing after the guide (K and the fit only lift the mesh)."""

    xy: np.ndarray  # (v, 2) the outline, points added in the band, the kept grid nodes
    triangles: np.ndarray  # (t, 3)
    kept: np.ndarray  # (ny * nx,) bool: the grid nodes among the vertices
    implicit_at: tuple[np.ndarray, np.ndarray, np.ndarray]  # g, ∇g, ∇²g at xy


def _layout(run: StageRun) -> Layout:
    grid: Grid = run["grid"]
    xy, triangles, kept = mesher.conforming_grid_mesh(
        run["frame"].polygon, grid, run["guide"].inside
    )
    implicit_at = run["implicit"].derivatives_on_grid(xy, grid, kept)
    _frozen(xy, triangles, kept, *implicit_at)
    return Layout(xy, triangles, kept, implicit_at)


def _mesh(run: StageRun) -> TriangleMesh:
    fs: FrameStage = run["frame"]
    grid: Grid = run["grid"]
    guide: GuideStage = run["guide"]
    surf: SurfaceStage = run["surface"]
    params = run.params
    n_outline = len(fs.polygon)
    # the margin at the boundary points' own heights (0 in the plane for a planar one, eq. 3);
    # the kept grid nodes' heights are already known
    rim = np.zeros(n_outline) if fs.polygon_h is None else fs.polygon_h
    implicit_at = None
    if params.mesher == "conforming":
        layout: Layout = run["layout"]
        xy, triangles, kept, implicit_at = layout
        added = xy[n_outline : len(xy) - int(np.count_nonzero(kept))]  # against slivers
        z = np.concatenate([rim, surf.surface(added), surf.z[kept[guide.inside]]])
        world = fs.frame.to_world(xy, z)
    else:
        xy = np.vstack([fs.polygon, grid.points[guide.inside]])
        z = np.concatenate([rim, surf.z])
        world = fs.frame.to_world(xy, z)
        grad = surf.surface.gradient(xy)
        normals = fs.frame.to_world(-grad, np.ones(len(xy))) - fs.frame.origin
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        triangles = mesher.ball_pivoting(world, normals, grid.spacing, params.radius_factor)
    on_margin = np.arange(len(xy)) < n_outline  # both meshers put the outline first
    _, grad, hess = surf.surface.derivatives(xy, on_margin, implicit_at)
    return TriangleMesh(
        points=world,
        regular_faces=triangles,
        point_data={"height": z, **graph_curvatures(grad, hess)},
    )


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
        Stage("frame", (), _frame),
        Stage("implicit", ("frame",), _implicit),
        Stage("grid", ("frame",), _grid),
        Stage("guide", ("implicit", "grid"), _guide),
        Stage("samples", ("guide",), _samples, lazy=True),
        Stage("gmm", ("samples",), _gmm),
        Stage("surface", ("gmm",), _surface),
        Stage("layout", ("guide",), _layout, lazy=True),
        Stage("mesh", ("surface", "layout"), _mesh),
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
