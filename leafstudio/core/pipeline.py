"""The staged pipeline with a cache per stage, and its Result.

| stage    | depends on                          | output                                   |
|----------|-------------------------------------|------------------------------------------|
| frame    | the leaf, margin                    | PCA frame, 2D polygon, 2D veins, heights |
|          |                                     | above the base b(x) (base.py)            |
| implicit | frame, mpu_tolerance                | the MPU implicit g                       |
| grid     | frame, grid                         | the regular grid                         |
| guide    | implicit, grid                      | g and p(x) on the grid                   |
| gmm      | guide, k, samples, seed             | the EM mixture                           |
| surface  | gmm, taper, refine                  | amplitudes, z on the kept grid nodes     |
| mesh     | surface, mesher, radius_factor      | the triangle mesh in world coordinates   |

A stage reruns only when a value it depends on changed, so moving K reruns gmm, surface and mesh.
Each parameter's stage is declared with it (model.Params); the cache keys (STAGE_KEYS) follow from
those declarations and this table's stage inputs (STAGE_INPUTS; tests/test_params.py checks that
this table says the same).
"""

from __future__ import annotations

import threading
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np

from leafstudio.core import analysis, mesher
from leafstudio.core.autok import choose_mixture
from leafstudio.core.base import PLANAR, BaseSurface, fit_base
from leafstudio.core.curvature import surface_curvatures
from leafstudio.core.gmm import Mixture, fit_mixture, fit_signed_mixture, sample_guide
from leafstudio.core.grid import Grid, make_grid
from leafstudio.core.height import height_guide
from leafstudio.core.measure import curvature_summary, shape_measurements
from leafstudio.core.mpu import MPUImplicit, build_mpu
from leafstudio.core.plane import Frame, fit_frame
from leafstudio.core.prepare.outline import (
    contains,
    distinct_indices,
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
from leafstudio.core.surface import HeightSurface, fit_surface
from leafstudio.core.trianglemesh import TriangleMesh
from leafstudio.errors import LeafError
from leafstudio.model import K_AUTO, PARAMS, Leaf, Params, as_leaf, as_params

if TYPE_CHECKING:
    import pyvista as pv

STAGE_INPUTS: dict[str, tuple[str, ...]] = {  # the table's "depends on", less the parameters
    "frame": (),
    "implicit": ("frame",),
    "grid": ("frame",),
    "guide": ("implicit", "grid"),
    "gmm": ("guide",),
    "surface": ("gmm",),
    "mesh": ("surface",),
}
STAGES = tuple(STAGE_INPUTS)


def _stage_keys() -> dict[str, tuple[str, ...]]:
    """Each stage's cache key: the parameters declared for it (model.Params, `stage`) and those
    of every stage it reads, in field order."""
    keys: dict[str, set[str]] = {}
    for stage, inputs in STAGE_INPUTS.items():
        own = {name for name, p in PARAMS.items() if p.stage == stage}
        keys[stage] = own.union(*(keys[i] for i in inputs))
    return {stage: tuple(n for n in PARAMS if n in names) for stage, names in keys.items()}


STAGE_KEYS = _stage_keys()
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
    _steps: analysis.Steps | None = field(default=None, init=False, repr=False, compare=False)

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
        >>> result.height(xy).round(3).tolist()  # heights along the midrib, base to tip
        [0.016, 0.031, 0.036]
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
        """The paper's Table 1 distances and the mesh's facts (see analysis.table_metrics), the
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

    def _metric_steps(self) -> analysis.Steps[dict[str, Any]]:
        table = yield from analysis.table_steps(self.triangle_mesh, self.leaf)
        yield
        area = table["mesh"]["area"]
        shape = shape_measurements(self.triangle_mesh, self.frame, self.polygon, area)
        yield
        curvature = curvature_summary(self.triangle_mesh)
        return {**table, "leaf": {**shape, "k": self.chosen_k}, "curvature": curvature}


def _frame_stage(
    leaf: Leaf, margin: str = "auto", units: Units | None = None
) -> tuple[FrameStage, list[str]]:
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
        outside = ~contains(polygon, v_xy)
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
    stage = FrameStage(
        frame=frame,
        polygon=polygon,
        veins=veins,
        heights=heights,
        length=length,
        polygon_h=None if base is None else polygon_h,
        base=base,
    )
    return stage, notes


def _flat_mixture(center: np.ndarray) -> Mixture:
    """A mixture of amplitude zero: the surface of a leaf without relief."""
    return Mixture(
        weights=np.ones(1),
        means=center[None].copy(),
        covariances=np.eye(2)[None].copy(),
        amplitudes=np.zeros(1),
    )


class Pipeline:
    """The staged reconstruction of one leaf, caching each stage's last output.

    Examples
    --------
    >>> import leafstudio as ls
    >>> pipe = ls.Pipeline(ls.demo("nested"))
    >>> r1 = pipe.run(ls.Params(k=3, grid=64))
    >>> r2 = pipe.run(ls.Params(k=4, grid=64))
    >>> r2.ran
    ('gmm', 'surface', 'mesh')
    """

    def __init__(self, leaf: Leaf) -> None:
        self.leaf = leaf = as_leaf(leaf)  # a clear TypeError for anything else
        self.units = Units.of(leaf)  # the stages run on the leaf at unit size (units.py)
        self._unit_leaf = self.units.leaf(leaf)
        self._cache: dict[str, tuple[tuple[Any, ...], Any]] = {}
        self._layout: tuple[GuideStage, tuple[np.ndarray, ...]] | None = None
        self._drawn: tuple[GuideStage, tuple[int, int], np.ndarray] | None = None

    def _samples(self, guide: GuideStage, grid: Grid, params: Params) -> np.ndarray:
        """The EM samples drawn from the guide (gmm.sample_guide), kept while the guide stage's
        output, the sample count and the seed are the same: a new K refits the same samples."""
        key = (params.samples, params.seed)
        if self._drawn is None or self._drawn[0] is not guide or self._drawn[1] != key:
            inside = guide.inside
            drawn = sample_guide(
                grid.points[inside], guide.p[inside], params.samples, grid.spacing, params.seed
            )
            drawn.flags.writeable = False
            self._drawn = (guide, key, drawn)
        return self._drawn[2]

    def _grid_mesh(self, fs: FrameStage, grid: Grid, guide: GuideStage) -> tuple[np.ndarray, ...]:
        """The conforming mesh in the plane (mesher.conforming_grid_mesh), kept while the guide
        stage's output is the same: it depends on nothing later (K and the fit only lift it)."""
        if self._layout is None or self._layout[0] is not guide:
            layout = mesher.conforming_grid_mesh(fs.polygon, grid, guide.inside)
            for array in layout:  # shared by the runs that follow, and MPUImplicit.derivatives
                array.flags.writeable = False  # keeps its result for a read-only array
            self._layout = (guide, layout)
        return self._layout[1]

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
        params = as_params(params)  # Params, None or a dict; a clear error for anything else
        timings: dict[str, float] = {}
        ran: list[str] = []

        def stage(name: str, compute: Callable[[], Any]) -> Any:
            key = tuple(getattr(params, k) for k in STAGE_KEYS[name])
            cached = self._cache.get(name)
            if cached is not None and cached[0] == key:
                return cached[1]
            if should_stop is not None and should_stop():
                raise Cancelled
            if on_stage is not None:
                on_stage(name)
            start = time.perf_counter()
            value = compute()
            timings[name] = time.perf_counter() - start
            ran.append(name)
            self._cache[name] = (key, value)
            return value

        fs, notes = stage("frame", lambda: _frame_stage(self._unit_leaf, params.margin, self.units))
        tol = params.mpu_tolerance * fs.length
        implicit: MPUImplicit = stage(
            "implicit",
            lambda: build_mpu(
                fs.polygon, outward_normals(fs.polygon), tol, lambda q: contains(fs.polygon, q)
            ),
        )
        grid: Grid = stage("grid", lambda: make_grid(fs.polygon, params.grid))
        guide: GuideStage = stage("guide", lambda: _guide_stage(fs, implicit, grid))
        flat = not fs.veins or not np.any(np.abs(fs.vein_h) > 1e-9 * fs.length)
        nodes = grid.points[guide.inside]
        samples, mixture = stage(
            "gmm",
            lambda: _gmm_stage(
                fs, guide, grid, params, flat, lambda: self._samples(guide, grid, params)
            ),
        )
        surf: SurfaceStage = stage(
            "surface", lambda: _surface_stage(fs, implicit, guide, nodes, mixture, params)
        )
        mesh: TriangleMesh = stage(
            "mesh",
            lambda: _mesh_stage(
                fs, implicit, grid, guide, surf, params, lambda: self._grid_mesh(fs, grid, guide)
            ),
        )
        unit = Result(
            leaf=self._unit_leaf,
            params=params,
            frame=fs.frame,
            polygon=fs.polygon,
            grid=grid,
            g_grid=guide.g,
            p_grid=guide.p,
            inside=guide.inside,
            em_samples=samples,
            surface=surf.surface,
            surface_points=fs.frame.to_world(nodes, surf.z),
            triangle_mesh=mesh,
            length=fs.length,
            timings=timings,
            ran=tuple(ran),
            warnings=list(notes),
        )
        return _in_world(unit, self.leaf, self.units)


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


def _guide_stage(fs: FrameStage, implicit: MPUImplicit, grid: Grid) -> GuideStage:
    nodes = grid.points
    g = implicit.on_grid(grid)
    inside = g >= 0
    p = np.zeros(len(nodes))
    p[inside] = height_guide(
        nodes[inside], fs.polygon, fs.veins, fs.heights, step=GUIDE_STEP * grid.spacing
    )
    return GuideStage(g=g, p=p, inside=inside)


def _gmm_stage(
    fs: FrameStage,
    guide: GuideStage,
    grid: Grid,
    params: Params,
    flat: bool,
    draw: Callable[[], np.ndarray],
) -> tuple[np.ndarray, Mixture]:
    if flat:
        return np.zeros((0, 2)), _flat_mixture(fs.polygon.mean(axis=0))
    p_in = guide.p[guide.inside]
    support = int(np.count_nonzero(p_in))  # grid nodes the samples can come from
    if params.k != K_AUTO and params.k > support // MIN_NODES_PER_COMPONENT:
        raise LeafError(
            f"K = {params.k} is more than the data supports: the height guide covers only "
            f"{support} grid nodes (at least {MIN_NODES_PER_COMPONENT} per component needed); "
            f"lower K or raise the grid resolution"
        )
    samples = draw()
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


def _surface_stage(
    fs: FrameStage,
    implicit: MPUImplicit,
    guide: GuideStage,
    nodes: np.ndarray,
    mixture: Mixture,
    params: Params,
) -> SurfaceStage:
    g_in = guide.g[guide.inside]
    surface = fit_surface(
        mixture,
        implicit,
        nodes,
        g_in,
        guide.p[guide.inside],
        fs.vein_xy,
        fs.vein_h,
        params.taper,
        params.refine,
        params.seed,
        base=fs.base,
    )
    return SurfaceStage(surface=surface, z=surface(nodes, g_in))


def _mesh_stage(
    fs: FrameStage,
    implicit: MPUImplicit,
    grid: Grid,
    guide: GuideStage,
    surf: SurfaceStage,
    params: Params,
    grid_mesh: Callable[[], tuple[np.ndarray, ...]],
) -> TriangleMesh:
    nodes = grid.points[guide.inside]
    n_outline = len(fs.polygon)
    # the margin at the boundary points' own heights (0 in the plane for a planar one, eq. 3);
    # the kept grid nodes' heights are already known
    rim = np.zeros(n_outline) if fs.polygon_h is None else fs.polygon_h
    if params.mesher == "conforming":
        xy, triangles, kept = grid_mesh()
        implicit.derivatives_on_grid(xy, grid, kept)  # kept for the curvatures below
        added = xy[n_outline : len(xy) - int(np.count_nonzero(kept))]  # against slivers
        z = np.concatenate([rim, surf.surface(added), surf.z[kept[guide.inside]]])
        world = fs.frame.to_world(xy, z)
    else:
        xy = np.vstack([fs.polygon, nodes])
        z = np.concatenate([rim, surf.z])
        world = fs.frame.to_world(xy, z)
        grad = surf.surface.gradient(xy)
        normals = fs.frame.to_world(-grad, np.ones(len(xy))) - fs.frame.origin
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        triangles = mesher.ball_pivoting(world, normals, grid.spacing, params.radius_factor)
    on_margin = np.arange(len(xy)) < n_outline  # both meshers put the outline first
    return TriangleMesh(
        points=world,
        regular_faces=triangles,
        point_data={"height": z, **surface_curvatures(surf.surface, xy, on_margin)},
    )


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
