"""The paper's steps as the pipeline's stages: one function per stage (`compute_<stage>`), each
reading the outputs of the stages it depends on from a StageRun (stages.py holds the table that
names them, in order), and the outputs they pass on (FrameStage, GuideStage, SurfaceStage, Layout).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from leafstudio.core import mesher
from leafstudio.core.autok import choose_mixture
from leafstudio.core.base import PLANAR, BaseSurface, fit_base
from leafstudio.core.bent_curvature import jet_of
from leafstudio.core.carried import normal_stretch
from leafstudio.core.correct import Pinning, onto_veins, pinning
from leafstudio.core.curvature import graph_curvatures
from leafstudio.core.gmm import Mixture, fit_mixture, fit_signed_mixture, sample_guide
from leafstudio.core.grid import Grid, make_grid
from leafstudio.core.height import height_guide
from leafstudio.core.mpu import MPUImplicit, build_mpu
from leafstudio.core.node_derivatives import node_derivatives
from leafstudio.core.plane import Frame, fit_frame
from leafstudio.core.prepare.outline import trace_outline
from leafstudio.core.prepare.plausibility import (
    BentRefusal,
    check_boundary,
    check_not_a_surface,
    keep_outer_loop,
    read_loop,
)
from leafstudio.core.prepare.polygon import (
    EdgeBands,
    contains,
    distinct_each,
    edge_bands,
    outward_normals,
    thin_outline,
    thin_veins,
)
from leafstudio.core.prepare.units import Units
from leafstudio.core.prepare.vein_order import vein_orders
from leafstudio.core.surface import HeightSurface, fit_surface, taper_of, taper_width
from leafstudio.core.trianglemesh import TriangleMesh
from leafstudio.errors import LeafError
from leafstudio.model import K_AUTO, Leaf

if TYPE_CHECKING:
    from leafstudio.core.stages import StageRun

MIN_NODES_PER_COMPONENT = 5
GUIDE_STEP = 0.5  # the guide's curves are thinned to this fraction of the grid step (height.py)
NO_VEINS_FLAT = "no veins given: the leaf is flat"
VEINS_IN_PLANE = "all veins lie in the boundary's plane: the leaf is flat"
# the same notes for a bent leaf (Leaf.bend), whose stages run on its flat blade: the bend gives
# it a shape the notes are not about (appreview31, finding 8: ovate-like blade folded 45 stood
# 0.14 of its length out of its plane, and was "flat")
BENT_NOTES = {
    NO_VEINS_FLAT: "no veins given: the blade has no relief of its own, only its bend",
    VEINS_IN_PLANE: "all veins lie in the blade's plane: the blade has no relief of its own, "
    "only its bend",
}
VEIN_OUTSIDE_TOLERANCE = 0.01  # vein points may stray this fraction of the leaf length outside


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
    """g and p on the grid; `inside` marks the nodes kept (g >= 0), at `nodes`."""

    g: np.ndarray
    p: np.ndarray
    inside: np.ndarray
    nodes: np.ndarray  # (n, 2) grid.points[inside], made once: the samples, the surface and
    # the result read them (numpy's boolean index of an (n, 2) array took
    # 0.084 ms at grid 128 (6,895 of 10,790 nodes), np.compress 0.010)
    g_in: np.ndarray  # (n,) g[inside] and p[inside], made once too: four stages read them five
    p_in: np.ndarray  # times (each boolean index took 0.05 ms at grid 128, np.compress 0.012)


@dataclass(frozen=True)
class SurfaceStage:
    """The fitted height surface and its values on the kept grid nodes."""

    surface: HeightSurface
    z: np.ndarray
    correction: np.ndarray | None = None  # c at the nodes inside the leaf (correct.onto_veins)


def frame_stage(leaf: Leaf, margin: str = "auto", units: Units | None = None) -> FrameStage:
    scale, offset = (units.scale, units.offset) if units is not None else (1.0, None)
    loop = read_loop(leaf.boundary)  # the boundary as one ordered loop, read once for both
    check_not_a_surface(leaf.boundary, loop)  # a whole scan given as the boundary: an error
    check_boundary(leaf.boundary, scale, offset, loop)  # a figure eight would lose a lobe
    boundary, notes = keep_outer_loop(leaf.boundary, loop)  # holes, loops: dropped, and said
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
    base = fit_base(polygon, polygon_h, length, noisy=outline.smoothed)
    if outline.smoothed and base is not None:  # a noisy margin: on the smooth base itself
        polygon_h = base(polygon)
    # the veins' order and repeats checked for all at once (vein_orders, distinct_each: this
    # function 2.1 -> 1.6 ms on a flat ovate at grid 128, best of 100); to_plane stays per vein
    # (numpy's product of a stack of veins rounded rows apart in 49 of 3000 random slices)
    projected = [frame.to_plane(vein) for vein in leaf.veins]
    orders = vein_orders([v_xy for v_xy, _ in projected])  # shuffled veins sorted (veins.py)
    projected = [(v_xy[o], v_h[o]) for (v_xy, v_h), o in zip(projected, orders, strict=True)]
    distinct = distinct_each([v_xy for v_xy, _ in projected], length)
    kept = thin_veins([v_xy[keep] for (v_xy, _), keep in zip(projected, distinct, strict=True)])
    keeps = [d[k] for d, k in zip(distinct, kept, strict=True)]  # dense veins: a few thousand
    # points in all (thin_veins)
    veins = [v_xy[keep] for (v_xy, _), keep in zip(projected, keeps, strict=True)]
    if veins:  # every vein's points tested at once (13 calls took 0.14 ms of a flat ovate's)
        outside = ~contains(polygon, np.vstack(veins), bands)
        if outside.any() and outline.smoothed:
            outside = _beyond_the_given(outside, xy, np.vstack(veins), polygon, notes)
        if outside.any():
            ends = np.cumsum([len(v_xy) for v_xy in veins])
            for i, (v_xy, end) in enumerate(zip(veins, ends, strict=True)):
                _inside_enough(i, v_xy, outside[end - len(v_xy) : end], polygon, length)
    heights = [
        v_h[keep] - (base(v_xy) if base is not None else 0.0)
        for (_, v_h), keep, v_xy in zip(projected, keeps, veins, strict=True)
    ]
    if base is not None:
        if not veins:
            notes.append("no veins given: the surface only follows the boundary's heights")
    elif not veins:
        notes.append(NO_VEINS_FLAT)
    elif all(np.allclose(h, 0, atol=1e-9 * length) for h in heights):
        notes.append(VEINS_IN_PLANE)
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


def _beyond_the_given(
    outside: np.ndarray,
    given: np.ndarray,
    points: np.ndarray,
    polygon: np.ndarray,
    notes: list[str],
) -> np.ndarray:
    """`outside` (the (n, 2) vein `points` beyond the outline `polygon`) without those inside the
    boundary as given, in its own order, when that order traces a simple polygon: there the
    outline, a noisy boundary's smoothed mean, was drawn inside the points, not the vein outside
    them (soybean pot1_1 resampled: its extracted midrib's end 1.5% of the length beyond the
    smoothed outline, and the scan was refused). Such points are said in a note."""
    import shapely  # the polygon tests of the pipeline's hot path are compiled (polygon.py)

    given_ring = shapely.Polygon(given)
    if not given_ring.is_valid:  # an unordered cloud, or a zig-zag through noise: no outline
        return outside
    within = outside & shapely.contains_xy(given_ring, points[:, 0], points[:, 1])
    if within.any():
        length = float(np.ptp(polygon[:, 0]))
        beyond = shapely.distance(shapely.LinearRing(polygon), shapely.points(points[within]))
        if beyond.max() > VEIN_OUTSIDE_TOLERANCE * length:  # nearer ones were kept unsaid before
            count = int(within.sum())
            notes.append(
                f"{count} vein point{'s lie' if count > 1 else ' lies'} up to "
                f"{beyond.max() / length:.1%} of the length beyond the margin as smoothed (a "
                "noisy boundary's mean line), though inside the boundary's points: the surface "
                "ends at that margin"
            )
    return outside & ~within


def _inside_enough(
    i: int, v_xy: np.ndarray, outside: np.ndarray, polygon: np.ndarray, length: float
) -> None:
    """Raise LeafError when vein i's (m, 2) points flagged `outside` the polygon stray more than
    VEIN_OUTSIDE_TOLERANCE of the length from it."""
    if not outside.any():
        return
    from shapely import LinearRing, distance, points

    # measured at a scale that keeps a far point's squared distance finite (a point at 1e200
    # was "up to inf% of the leaf length")
    scale = max(float(np.abs(v_xy[outside]).max()), float(np.abs(polygon).max()))
    gap = scale * distance(LinearRing(polygon / scale), points(v_xy[outside] / scale)).max()
    if gap > VEIN_OUTSIDE_TOLERANCE * length:
        share = gap / length
        far = f"{share:.1%} of the leaf length" if share < 1 else f"{share:.3g} leaf lengths"
        raise BentRefusal(
            f"vein {i + 1}: {outside.sum()} of {len(v_xy)} points lie outside the boundary "
            f"(up to {far})"
        )


def _flat_mixture(center: np.ndarray) -> Mixture:
    """A mixture of amplitude zero: the surface of a leaf without relief."""
    return Mixture(
        weights=np.ones(1),
        means=center[None].copy(),
        covariances=np.eye(2)[None].copy(),
        amplitudes=np.zeros(1),
    )


def _frozen(*arrays: np.ndarray) -> None:
    """Make stored arrays read-only: later runs share them."""
    for array in arrays:
        array.flags.writeable = False


def compute_frame(run: StageRun) -> FrameStage:
    pipe = run.pipeline
    return frame_stage(pipe.unit_leaf, run.params.margin, pipe.units)


def compute_implicit(run: StageRun) -> MPUImplicit:
    fs: FrameStage = run["frame"]
    tol = run.params.mpu_tolerance * fs.length
    normals = outward_normals(fs.polygon)
    return build_mpu(fs.polygon, normals, tol, lambda q: contains(fs.polygon, q, fs.bands))


def compute_grid(run: StageRun) -> Grid:
    return make_grid(run["frame"].polygon, run.params.grid)


def compute_guide(run: StageRun) -> GuideStage:
    fs: FrameStage = run["frame"]
    grid: Grid = run["grid"]
    g = run["implicit"].on_grid(grid)
    inside = g >= 0
    nodes = grid.points.compress(inside, axis=0)
    p = np.zeros(len(grid.points))
    p_in = height_guide(nodes, fs.polygon, fs.veins, fs.heights, step=GUIDE_STEP * grid.spacing)
    p[inside] = p_in
    return GuideStage(g=g, p=p, inside=inside, nodes=nodes, g_in=g.compress(inside), p_in=p_in)


def compute_samples(run: StageRun) -> np.ndarray:
    """The EM samples drawn from the guide (gmm.sample_guide): a new K refits the same ones."""
    guide: GuideStage = run["guide"]
    grid: Grid = run["grid"]
    drawn = sample_guide(guide.nodes, guide.p_in, run.params.samples, grid.spacing, run.params.seed)
    _frozen(drawn)
    return drawn


def compute_gmm(run: StageRun) -> tuple[np.ndarray, Mixture]:
    fs: FrameStage = run["frame"]
    guide: GuideStage = run["guide"]
    grid: Grid = run["grid"]
    params = run.params
    if fs.flat:
        return np.zeros((0, 2)), _flat_mixture(fs.polygon.mean(axis=0))
    p_in = guide.p_in
    support = int(np.count_nonzero(p_in))  # grid nodes the samples can come from
    # auto tries from 1: a guide between the grid's nodes said "zero everywhere: nothing to fit"
    least = 1 if params.k == K_AUTO else params.k
    if least > support // MIN_NODES_PER_COMPONENT:
        if params.k == K_AUTO:
            raise LeafError(
                f"the height guide covers only {support} grid nodes, too few for even one "
                f"component (at least {MIN_NODES_PER_COMPONENT} needed); raise the grid resolution"
            )
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


def compute_bending(run: StageRun) -> Pinning:
    """The vein correction's centres and the lattice it bends least on (correct.pinning): all
    that K does not change, so moving K reruns only the correction's solve."""
    fs: FrameStage = run["frame"]
    guide: GuideStage = run["guide"]
    g_in = guide.g_in
    delta = taper_width(run.params.taper, g_in)
    taper = taper_of(g_in, delta)
    implicit, grid = run["implicit"], run["grid"]
    return pinning(fs.veins, fs.heights, fs.length, implicit, delta, grid, guide.inside, taper)


def compute_surface(run: StageRun) -> SurfaceStage:
    fs: FrameStage = run["frame"]
    guide: GuideStage = run["guide"]
    nodes = guide.nodes
    g_in = guide.g_in
    through = run.params.through_veins and bool(fs.veins)  # onto every vein point (correct.py)
    # T at the nodes once a run: the bending stage's (the same δ: its tanh took 0.02-0.035 ms of
    # a flat ovate's at grid 128 each time), else here; and g at the veins, the bending stage's
    node_taper, vein_g = (
        (run["bending"].node_taper, run["bending"].vein_g) if through else (None, None)
    )
    if node_taper is None:
        node_taper = taper_of(g_in, taper_width(run.params.taper, g_in))
    surface, relief = fit_surface(  # relief: M at the nodes, once (the correction takes it)
        run["gmm"][1],
        run["implicit"],
        nodes,
        g_in,
        guide.p_in,
        fs.vein_xy,
        fs.vein_h,
        run.params.taper,
        run.params.refine,
        run.params.seed,
        base=fs.base,
        node_taper=node_taper,
        vein_g=vein_g,
    )
    correction = None
    if through:
        surface, correction = onto_veins(
            surface, fs.heights, fs.length, run["bending"], nodes, relief, _stretch(run, surface)
        )
        if correction is not None:
            relief = relief + correction
    return SurfaceStage(surface, surface(nodes, g_in, relief, node_taper), correction)


def _stretch(run: StageRun, surface: HeightSurface) -> list[np.ndarray] | None:
    """Per vein, how many times the leaf's bend lengthens a distance off `surface` at each
    point, at least 1 (carried.normal_stretch); None for a leaf without a bend."""
    bend = run.pipeline.leaf.bend
    fs: FrameStage = run["frame"]
    if bend is None or not fs.veins:
        return None
    frame, xy = fs.frame, fs.vein_xy
    z = surface(xy)
    slope = surface.gradient(xy)
    axes = np.array([frame.u, frame.v, frame.normal])
    unit = frame.origin + np.column_stack([xy, z]) @ axes
    tangents = np.zeros((len(xy), 3, 3))
    tangents[:, 0, 0] = tangents[:, 1, 1] = 1.0
    tangents[:, :2, 2] = slope
    normal = np.column_stack([-slope, np.ones(len(xy))])
    tangents[:, 2] = normal / np.linalg.norm(normal, axis=1)[:, None]
    world = run.pipeline.units.to_world(unit)
    stretch = np.maximum(normal_stretch(bend, world, tangents @ axes), 1.0)
    return np.split(stretch, np.cumsum([len(v) for v in fs.veins])[:-1])


class Layout(NamedTuple):
    """The conforming mesh in the plane and g's derivatives at its vertices: they depend on
    nothing after the guide (K and the fit only lift the mesh)."""

    xy: np.ndarray  # (v, 2) the outline, points added in the band, the kept grid nodes
    triangles: np.ndarray  # (t, 3)
    kept: np.ndarray  # (ny * nx,) bool: the grid nodes among the vertices
    implicit_at: tuple[np.ndarray, np.ndarray, np.ndarray]  # g, ∇g, ∇²g at xy


def compute_layout(run: StageRun) -> Layout:
    grid: Grid = run["grid"]
    xy, triangles, kept = mesher.conforming_grid_mesh(
        run["frame"].polygon, grid, run["guide"].inside
    )
    implicit_at = run["implicit"].derivatives_on_grid(xy, grid, kept)
    _frozen(xy, triangles, kept, *implicit_at)
    return Layout(xy, triangles, kept, implicit_at)


def _correction_at(
    surf: SurfaceStage,
    grid: Grid,
    inside: np.ndarray,
    xy: np.ndarray,
    kept: np.ndarray,
    margin: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """c, ∇c and ∇²c at the conforming mesh's vertices: by differences of c at its kept grid
    nodes (the last of them, core/node_derivatives.py: the closed form at every vertex took
    more than the rest of a run at grid 512), in closed form at the outline's and the band's
    points before them; None when the nodes' differences cannot be taken. The outline's, the
    first `margin` points, get ∇²c = 0: the taper's T = 0 there multiplies it
    (HeightSurface.derivatives), and c and ∇c alone cost less
    (VeinCorrection.value_and_gradient)."""
    correction = surf.surface.correction
    if correction is None or surf.correction is None:
        return None
    nodes = np.flatnonzero(kept)
    on_nodes = node_derivatives(correction.value, grid, inside, surf.correction, nodes)
    if on_nodes is None:
        return None
    value, grad = correction.value_and_gradient(xy[:margin])
    rim = value, grad, np.zeros((margin, 2, 2))
    band = correction.derivatives(xy[margin : len(xy) - len(nodes)])
    return tuple(np.concatenate(parts) for parts in zip(rim, band, on_nodes, strict=True))


def compute_mesh(run: StageRun) -> TriangleMesh:
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
        # usually none: not read (an empty read cost 0.05 ms of a flat ovate's run at grid 128)
        z_added = surf.surface(added) if len(added) else np.zeros(0)
        z = np.concatenate([rim, z_added, surf.z.compress(kept.compress(guide.inside))])
        world = fs.frame.to_world(xy, z)
    else:
        xy = np.vstack([fs.polygon, guide.nodes])
        z = np.concatenate([rim, surf.z])
        world = fs.frame.to_world(xy, z)
        grad = surf.surface.gradient(xy)
        normals = fs.frame.to_world(-grad, np.ones(len(xy))) - fs.frame.origin
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        triangles = mesher.ball_pivoting(world, normals, grid.spacing, params.radius_factor)
    on_margin = np.arange(len(xy)) < n_outline  # both meshers put the outline first
    correction_at = None
    if params.mesher == "conforming":
        correction_at = _correction_at(surf, grid, guide.inside, xy, kept, n_outline)
    _, grad, hess = surf.surface.derivatives(xy, on_margin, implicit_at, correction_at)
    return TriangleMesh(
        points=world,
        regular_faces=triangles,
        point_data={"height": z, **graph_curvatures(grad, hess)},
        jet=jet_of(grad, hess),
    )
