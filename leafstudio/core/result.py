"""The output of a run (Leaf + Params -> Result, section 4): the mesh, the surface, what the
stages made on the way, and the Table-1 metrics measured on first use (evaluate.py). A run works
at unit size (prepare/units.py); `in_world` maps its Result to the input's coordinates.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from typing import TYPE_CHECKING, Any

import numpy as np

from leafstudio.core import evaluate
from leafstudio.core.evaluate import blade_midrib, curvature_summary, shape_measurements
from leafstudio.core.gmm import Mixture
from leafstudio.core.grid import Grid
from leafstudio.core.plane import Frame
from leafstudio.core.prepare.units import ScaledSurface, Units
from leafstudio.core.surface import HeightSurface
from leafstudio.core.trianglemesh import TriangleMesh
from leafstudio.model import Leaf, Params

if TYPE_CHECKING:
    import pyvista as pv


class Cancelled(Exception):
    """Raised inside `Pipeline.run` (or `Result.measure`) when its `should_stop` callback says
    so."""


class Measuring:
    """One run's metrics, measured in steps on first use and then kept: the pipeline's "metrics"
    entry in its one cache (store.py, keyed as the mesh stage is), shared by the run's Result,
    its unit-size Result and a later run of the same leaf and parameters.

    `steps` measures at unit size; `units` maps the figures to the input's units (units.py).
    """

    def __init__(
        self, steps: Callable[[], evaluate.Steps[dict[str, Any]]], units: Units | None
    ) -> None:
        self._make, self._units = steps, units
        self._steps: evaluate.Steps[dict[str, Any]] | None = None  # the steps under way
        self._unit: dict[str, Any] | None = None
        self._world: dict[str, Any] | None = None
        self._lock = threading.Lock()  # one thread at a time steps (a generator is not shared)

    @property
    def done(self) -> bool:
        """True once the metrics are measured."""
        return self._unit is not None

    def metrics(self, should_stop: Callable[[], bool] | None, in_world: bool) -> dict[str, Any]:
        """The metrics at unit size, or with `in_world` in the input's units (see Result.measure
        for `should_stop`)."""
        unit = self._unit if self._unit is not None else self._measure(should_stop)
        if not in_world or self._units is None:
            return unit
        with self._lock:
            if self._world is None:
                world = self._units.metrics(unit)
                evaluate.check_finite(world)  # past about 1e154 an area is inf: LeafError
                self._world = world
            return self._world

    def _measure(self, should_stop: Callable[[], bool] | None) -> dict[str, Any]:
        while True:
            with self._lock:
                if self._unit is not None:  # another thread finished them meanwhile
                    return self._unit
                if self._steps is None:
                    self._steps = self._make()
                try:
                    next(self._steps)
                except StopIteration as stop:
                    self._unit, self._steps = stop.value, None
                    return self._unit
                except BaseException:
                    self._steps = None  # a failed step: the next call starts again
                    raise
            if should_stop is not None and should_stop():
                raise Cancelled


class Later:
    """A value made on first use and then kept: the pipeline's "polydata" entry (the VTK mesh,
    made on the main thread when asked for, never by a run), keyed as the mesh stage is."""

    def __init__(self, make: Callable[[], Any]) -> None:
        self._make: Callable[[], Any] | None = make
        self._value: Any = None

    def get(self) -> Any:
        """The value, made now if this is the first call."""
        if self._make is not None:
            self._value, self._make = self._make(), None
        return self._value


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
        The K the surface uses (the BIC's choice when params.k is "auto"); 1 for a blade that
        fits no mixture (`fits_no_mixture`), whose Gaussian is a placeholder.
    fitted_k : int or None
        `chosen_k`, or None when the blade fits no mixture: what the metrics' "k" says.
    em_samples, em_mixture : (s, 2) float array, gmm.Mixture
        The EM samples drawn from the height guide p(x), in the plane, and the mixture EM
        fitted to them (the gmm stage's output); `surface.mixture` is refined from it (its
        Gaussians can move far from the samples they came from: the lesson colours the samples
        by EM's own).
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
    em_mixture: Mixture  # the mixture EM fitted to them (the surface's is refined from it)
    surface: HeightSurface
    surface_points: np.ndarray  # (n, 3) the GMM samples: kept grid nodes lifted, world coords
    triangle_mesh: TriangleMesh  # the mesh's arrays: points, triangles, height and curvatures
    length: float
    timings: dict[str, float] = field(default_factory=dict)
    ran: tuple[str, ...] = ()
    warnings: list[str] = field(default_factory=list)
    unit: Result | None = None  # the same run at unit size (units.py); None: this is it
    units: Units | None = None  # how `unit` maps to this one
    # a bent leaf's mesh points on its flat blade, in `frame`'s plane (core/bent_result.bent_result:
    # laid flat again, a twisted tube's points by its seam fell on the other margin)
    blade_xy: np.ndarray | None = field(default=None, repr=False, compare=False)
    # a bent leaf's mesh points on its outline (bent_mesh.bent_mesh: its trim drops some, its
    # cuts add some); None: the first len(polygon), as the meshers put them (see on_outline)
    outline_points: np.ndarray | None = field(default=None, repr=False, compare=False)
    # a bent leaf's flat blade (bent_result.bent_result), whose midrib the metrics measure along:
    # not flattened again (0.45 ms of a four-term pose's run); None: `leaf` is flat
    blade: Leaf | None = field(default=None, repr=False, compare=False)
    # the metrics and the VTK mesh, entries of the pipeline's cache (Pipeline.run sets them);
    # not init fields, so a Result copied with other arrays (dataclasses.replace) measures its own
    measuring: Measuring | None = field(default=None, init=False, repr=False, compare=False)
    polydata: Later | None = field(default=None, init=False, repr=False, compare=False)

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

    def mesh_on_blade(self) -> tuple[np.ndarray, np.ndarray]:
        """`on_blade` of this result's mesh points: (n, 2) plane coordinates and (n,) heights,
        a bent leaf's kept from before it was bent."""
        mesh = self.triangle_mesh
        kept = self.blade_xy is not None and len(self.blade_xy) == len(mesh.points)
        if kept and "height" in mesh.point_data:
            return self.blade_xy, np.asarray(mesh.point_data["height"], dtype=float)
        return self.on_blade(mesh.points)

    def on_outline(self) -> np.ndarray:
        """(n,) bool: which of the mesh's points lie on the leaf's outline, the margin where the
        surface takes its limits from inside (surface.HeightSurface.derivatives): the first
        len(polygon), as both meshers put them, or a bent leaf's carried through its cuts and
        trim (bent_mesh.bent_mesh; the exports and the view's lighter mesh read it)."""
        n = len(self.triangle_mesh.points)
        if self.outline_points is not None and len(self.outline_points) == n:
            return self.outline_points
        return np.arange(n) < len(self.polygon)

    def on_blade(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(n, 2) plane coordinates and (n,) heights, in `frame`, of (n, 3) points of this
        result's mesh on the flat blade: a bent leaf's (`leaf.bend`) are laid flat first, as its
        surface, grid and outline are the flat blade's (its mesh seen in `frame` as it is bent
        put a fold's UVs, normals and texture across a blade half as wide)."""
        points = np.asarray(points, dtype=float)
        if self.leaf.bend is not None:
            points = self.leaf.bend.flatten(points)
        return self.frame.to_plane(points)

    @property
    def blade_length(self) -> float:
        """The blade's length, base to apex along its midrib (evaluate.blade_axis): the metrics'
        "length", what `--length` sets, and what the scan distances' shares are of. (`length`,
        the outline's extent along u, is the stages' own scale.)"""
        base, direction = evaluate.leaf_axis(self.leaf, self.frame, self.polygon)  # its bend's
        return evaluate.blade_length_width(self.polygon, base, direction)[0]

    @property
    def chosen_k(self) -> int:
        """The K the surface uses: params.k, or the one chosen when params.k is "auto"."""
        return len(self.surface.mixture.weights)

    @property
    def fits_no_mixture(self) -> bool:
        """Whether the blade had no relief of its own to fit (no veins, or all in its plane):
        its gmm stage is then one Gaussian of amplitude 0 (steps.compute_gmm), and `chosen_k`'s 1
        is that placeholder's, whatever K was asked (appreview31, finding 8)."""
        return not np.any(self.em_mixture.amplitudes)

    @property
    def fitted_k(self) -> int | None:
        """The K of the mixture the surface fits, None when it fits none (`fits_no_mixture`):
        what the metrics, `measure`, `reconstruct --metrics`, `compare` and a batch's trait
        table say. A flat blade's placeholder Gaussian read "k": 1 there, and in the app's
        Measurements panel, for a blade where K does nothing (the view's corner said "K
        unused (flat blade)" beside it: review of session 31)."""
        return None if self.fits_no_mixture else self.chosen_k

    @property
    def mesh(self) -> pv.PolyData:
        """The mesh as a pyvista.PolyData with its point arrays, built on first use: a run itself
        never creates a VTK object (the app draws from `triangle_mesh` on its main thread)."""
        if self.polydata is None:  # a Result no Pipeline made
            self.polydata = Later(self.triangle_mesh.to_pyvista)
        return self.polydata.get()

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
        return self.measuring is not None and self.measuring.done

    def measure(self, should_stop: Callable[[], bool] | None = None) -> dict[str, Any]:
        """`metrics`, computed in steps (distances, mesh facts, shape, curvature, in pieces):
        when `should_stop()` is true after a step, Cancelled is raised, and the next call goes
        on from there (the app stops measuring a shown result when a newer request waits; the
        steps done are kept)."""
        if self.measuring is None:  # a Result no Pipeline made
            self.measuring = self.new_measuring()
            if self.unit is not None:
                self.unit.measuring = self.measuring
        return self.measuring.metrics(should_stop, in_world=self.unit is not None)

    def new_measuring(self) -> Measuring:
        """The measuring of this Result's metrics (at unit size, on its unit-size Result)."""
        unit = self if self.unit is None else self.unit
        # seen face-on when its flat blade does not lie on the leaf's own plane (a scan's sheet:
        # sheet_bend.Scaled.own_plane); asked here: the unit-size run's leaf has no bend
        face_on = getattr(self.leaf.bend, "own_plane", True) is False
        # the flat blade's midrib, which the length runs along: found on this Result's leaf, which
        # has its bend (the unit-size run's leaf is the bent leaf without it, bent_result.
        # bent_result), when the metrics are first measured rather than when the run ends (0.2
        # ms of a flat ovate's run at grid 128, which only the metrics read)
        blade = self.leaf if self.blade is None else self.blade
        to_unit = self.units if self.unit is not None else None
        midrib = partial(_unit_midrib, blade, to_unit)
        return Measuring(partial(unit._metric_steps, midrib, face_on), self.units)

    def _metric_steps(
        self, midrib: Callable[[], np.ndarray | None], face_on: bool = False
    ) -> evaluate.Steps[dict[str, Any]]:
        """The metrics in resumable steps; `midrib` finds the flat blade's midrib at unit size."""
        table = yield from evaluate.table_steps(self.triangle_mesh, self.leaf)
        yield
        area = table["mesh"]["area"]
        shape = shape_measurements(
            self.triangle_mesh, self.frame, self.polygon, area, midrib(), face_on, self.blade_xy
        )
        yield
        curvature = curvature_summary(self.triangle_mesh)
        return {**table, "leaf": {**shape, "k": self.fitted_k}, "curvature": curvature}


def _unit_midrib(blade: Leaf, units: Units | None) -> np.ndarray | None:
    """The flat `blade`'s midrib (evaluate.blade_midrib), at unit size by `units` if given."""
    midrib = blade_midrib(blade)
    return midrib if midrib is None or units is None else units.to_unit(midrib)


def in_world(unit: Result, leaf: Leaf, units: Units) -> Result:
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
        em_mixture=unit.em_mixture.scaled(s),
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
