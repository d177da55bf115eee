"""Veins grown inside any outline: primaries laid first, secondaries by space colonization.

Method (Runions, Fuhrer, Lane, Federl, Rolland-Lagan and Prusinkiewicz, "Modeling and
visualization of leaf venation patterns", SIGGRAPH 2005, open venation):
1. The primaries are laid first: the midrib from the base to the apex along the outline's longest
   axis (through the middle of its cross-sections where the straight line would leave the blade);
   palmate venation adds two or four primaries from the base to the farthest margin points in
   sectors either side of the midrib (the lobes' tips in a lobed leaf); parallel venation lays
   2N + 1 veins through the same fractions of every cross-section from base to apex, so they
   converge at both ends and never cross.
2. Auxin sources are scattered over the blade (a jittered grid). Each source attracts the vein
   node nearest to it; each node that is attracted grows one step D toward the mean direction of
   its sources; sources within the kill distance of a node are removed; repeat until none grows.
   Growth starts only from the secondaries' seeds (stations along the primaries, alternating
   sides), so each seed colonises its own part of the blade.
   Departures, ours: the blade does not grow (Runions' marginal growth is what sets the veins'
   angle to the midrib); a tropism toward the apex stands in for it (secondaries leave at about
   55°), and for arcuate venation it strengthens near the margin so the secondaries curve up along
   it. Each seed's tree is reduced to its longest path (the secondary vein); an open secondary is
   continued straight to just inside the margin, an arcuate one along the margin toward the apex
   until it nears the next vein. In a narrow blade (a linear leaf, 20 or 30 times longer than
   wide) the step shrinks to half its half-width and the seeds leave at the tropism's angle, so
   its secondaries are short and steep, as in rosemary or willow (growth_step); grass-like leaves
   are parallel-veined (venation "parallel").
3. Heights: every vein point stands HEIGHT_RATIO times its distance to the margin above the
   blade's base surface (b(x) through a 3D outline's heights, 0 for a flat one), as the demos'
   midribs do (h = 0.25 w): the blade rises about 14° from the margin to the veins, a roof
   creased along the midrib. Forms ask for relief "dome" instead (relief.py): a smooth membrane
   as high at its top, with no crease for a surface through the veins to follow.

This module checks the input and runs the method; the blade (its plane, axis and inside tests) is
in blade.py, steps 1-2 (the primaries, space colonization) in growth.py.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree
from shapely.geometry import Point, Polygon

from leafstudio.core.prepare.units import Units
from leafstudio.errors import LeafError
from leafstudio.forms.blade import Blade, blade_polygon, find_axis, lifter, plane_of
from leafstudio.forms.growth import (
    SOURCES,
    STEP,
    TROPISM,
    arch,
    arch_ring,
    colonize,
    cut_crossings,
    growth_step,
    lay_midrib,
    palmate_primaries,
    parallel_veins,
    stations,
    to_margin,
)
from leafstudio.forms.relief import dome
from leafstudio.forms.terms import VENATION_KINDS, check_term
from leafstudio.model import SEED_MAX

RELIEFS = ("roof", "dome")
BASE_REACH = 0.05  # a base farther outside the outline than this share of its size is refused
HEIGHT_RATIO = 0.25  # vein height over its distance to the margin (sources/demos.py: h = 0.25 w)
NARROW_TURN = np.deg2rad(35.0)  # a narrow blade's secondaries leave the midrib at 90° - this
PALMATE_TROPISM = 0.3  # palmate secondaries: a gentler pull along their primary
DEFAULT_SECONDARIES = {"pinnate": 6, "arcuate": 6, "palmate": 3, "parallel": 3}


def grow_veins(
    boundary: np.ndarray,
    venation: str = "pinnate",
    secondaries: int | None = None,
    base: np.ndarray | None = None,
    seed: int = 0,
    *,
    apex: np.ndarray | None = None,
    relief: str = "roof",
    round_base: bool = False,
) -> list[np.ndarray]:
    """Veins of the chosen kind grown inside any outline (see the module docstring for the method).

    Parameters
    ----------
    boundary : (n, 2) or (n, 3) float array
        The outline, in order around the leaf (unordered points are ordered first).
    venation : {"pinnate", "palmate", "parallel", "arcuate"}, default: "pinnate"
    secondaries : int, optional
        Secondary veins on each side of the midrib (parallel: veins either side of the middle
        one); default 6 (palmate: 3 per primary side, parallel: 3).
    base : (2,) or (3,) float array, optional
        Where the midrib meets the blade. Default: an end of the outline's longest axis (the one at
        the origin if there is one, else the wider).
    seed : int, default: 0
        Varies the sources and the seeds' places; the same seed gives the same veins.
    apex : (2,) or (3,) float array, optional
        Where the midrib ends; default the margin point farthest from the base.
    relief : {"roof", "dome"}, default: "roof"
        The veins' heights: HEIGHT_RATIO times their distance to the margin (a roof, creased
        along the midrib), or a smooth dome as high at its top (relief.py: the forms' own).
    round_base : bool, default: False
        The base is a smooth arc (a form's rounded base): the dome is not flattened there
        (relief.dome).

    Returns
    -------
    list of (m_i, 3) float arrays
        The midrib first (palmate: then the other primaries), each vein from its start to its
        end, in the boundary's coordinates; z is the height (for a 2D outline, above z = 0).

    Raises
    ------
    LeafError
        For an unknown venation, or an outline too small or degenerate to grow veins in.

    Examples
    --------
    >>> import numpy as np
    >>> from leafstudio.forms import grow_veins
    >>> t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    >>> outline = np.column_stack([0.5 + 0.5 * np.cos(t), 0.25 * np.sin(t)])
    >>> veins = grow_veins(outline, "pinnate", secondaries=4)
    >>> len(veins), veins[0].shape
    (9, (49, 3))
    """
    points = np.asarray(boundary, dtype=float)
    if points.ndim != 2 or points.shape[1] not in (2, 3) or len(points) < 3:
        raise LeafError(
            f"the outline must be an (n, 2) or (n, 3) array, n >= 3, got {points.shape}"
        )
    if not np.all(np.isfinite(points)):
        raise LeafError("the outline contains NaN or infinite coordinates")
    # grown at about unit size whatever the outline's units (1e-90 or 1e300: no overflow), by
    # an exact map, so that a leaf of ordinary size gets the very same veins; then mapped back
    units = Units.exact(points)  # (_grow_unit refuses an outline without area)

    def unit(at: np.ndarray | None) -> np.ndarray | None:
        if at is None:
            return None
        at = np.asarray(at, dtype=float).ravel()
        if not np.all(np.isfinite(at)):
            raise LeafError(f"a point of the midrib's ends is not finite: {at}")
        return (at - units.offset[: len(at)]) / units.scale

    veins = _grow_unit(
        units.to_unit(points),
        venation,
        secondaries,
        unit(base),
        seed,
        apex=unit(apex),
        relief=relief,
        round_base=round_base,
    )
    offset = np.r_[units.offset, 0.0][:3]  # a 2D outline: (x, y, 0), z is the height above 0
    return [offset + units.scale * v for v in veins]


def check_seed(seed: object) -> None:
    """LeafError unless `seed` is a whole number numpy's generators take."""
    whole = isinstance(seed, int | np.integer) and not isinstance(seed, bool)
    if not whole or not 0 <= seed <= SEED_MAX:
        raise LeafError(f"the seed must be a whole number from 0 to {SEED_MAX}, got {seed!r}")


def _grow_unit(
    boundary: np.ndarray,
    venation: str,
    secondaries: int | None,
    base: np.ndarray | None,
    seed: int,
    *,
    apex: np.ndarray | None,
    relief: str,
    round_base: bool,
) -> list[np.ndarray]:
    """grow_veins on an outline of unit size centred on the origin."""
    venation = check_term("venation", venation, VENATION_KINDS)  # any case: "Pinnate"
    if relief not in RELIEFS:
        raise LeafError(f"unknown relief {relief!r}; choose from {', '.join(RELIEFS)}")
    count = DEFAULT_SECONDARIES[venation] if secondaries is None else int(secondaries)
    if not 0 <= count <= 40:
        raise LeafError(f"secondaries must be between 0 and 40, got {count}")
    check_seed(seed)
    rng = np.random.default_rng(seed)
    xy, heights, frame, base_xy = plane_of(boundary, base)
    size = float(np.ptp(xy, axis=0).max())
    if size == 0 or Polygon(xy).convex_hull.area <= 1e-9 * size**2:
        raise LeafError("the outline encloses no area (its points lie on one line)")
    poly = blade_polygon(xy)
    if base_xy is not None and not poly.contains(Point(base_xy)):
        away = poly.exterior.distance(Point(base_xy)) / size
        if not away <= BASE_REACH:  # veins from there would run outside the blade
            how_far = f"{away:.3g} of its size" if np.isfinite(away) else "far"
            raise LeafError(
                f"the base lies outside the outline, {how_far} from the margin; give a point on "
                "the margin"
            )
    origin = None
    if frame is None or not hasattr(frame, "to_plane"):
        origin = np.zeros(2)
    else:
        origin = frame.to_plane(np.zeros((1, 3)))[0][0]
    b, a = find_axis(poly, base_xy, origin)
    if apex is not None:
        a = np.asarray(apex, dtype=float).ravel()[:2]
        if frame is not None and hasattr(frame, "to_plane") and len(np.ravel(apex)) == 3:
            a = frame.to_plane(np.asarray(apex, dtype=float)[None])[0][0]
    length = float(np.linalg.norm(a - b))
    if length <= 0:
        raise LeafError("the outline has no length: base and apex coincide")
    u = (a - b) / length
    v = np.array([-u[1], u[0]])
    local = lambda p: np.column_stack([(p - b) @ u, (p - b) @ v]) / length  # noqa: E731
    world = lambda q: b + length * (q[:, :1] * u + q[:, 1:2] * v)  # noqa: E731
    shape = Polygon(local(np.asarray(poly.exterior.coords)))
    blade = Blade(shape if shape.is_valid else shape.buffer(0))

    midrib = lay_midrib(blade)
    veins: list[np.ndarray] = []
    if venation == "parallel":
        veins = parallel_veins(blade, count)
        veins = [veins[len(veins) // 2]] + [w for i, w in enumerate(veins) if i != len(veins) // 2]
    else:
        primaries = [midrib]
        if venation == "palmate":
            primaries += palmate_primaries(blade, rng)
        seeds = []
        step = growth_step(blade)
        for k, prim in enumerate(primaries):
            along = np.diff(prim, axis=0)
            along = np.vstack([along, along[-1:]])
            along /= np.maximum(np.linalg.norm(along, axis=1), 1e-12)[:, None]
            if k == 0:
                per, lo, hi = count, 0.03, 0.9
            else:
                per, lo, hi = max(1, (count + 1) // 2), 0.25, 0.9
            for index, side in stations(prim, per, lo, hi, rng):
                if k > 0 and side * np.sign(prim[-1, 1]) < 0 and venation == "palmate":
                    continue  # a lateral primary's seeds face away from the midrib
                normal = side * np.array([-along[index, 1], along[index, 0]])
                if step < STEP:  # a narrow blade: room for a few steps only, so the secondary
                    # leaves at the angle the tropism gives it in a broad blade, not square
                    normal = np.cos(NARROW_TURN) * normal + np.sin(NARROW_TURN) * along[index]
                turn = np.deg2rad(rng.uniform(-4, 4))
                c, s = np.cos(turn), np.sin(turn)
                tip = along[index] @ np.array([[c, s], [-s, c]])
                seeds.append((prim[index], prim[index] + 0.5 * step * normal, tip))
        tropism = PALMATE_TROPISM if venation == "palmate" else TROPISM
        paths = (
            colonize(blade, primaries, seeds, venation == "arcuate", rng, tropism, step)
            if seeds
            else []
        )
        h = float(np.sqrt(blade.area / SOURCES))
        veins = list(primaries)
        if venation == "arcuate":
            ring = arch_ring(blade, step)
            every = [*primaries, *paths]
            owners = np.concatenate([np.full(len(v), k) for k, v in enumerate(every)])
            tree = cKDTree(np.vstack(every))
        for k, path in enumerate(paths):
            if venation == "arcuate":
                path = arch(ring, path, len(primaries) + k, tree, owners, h, step)
            else:
                path = to_margin(blade, path, step)
            path = cut_crossings(path, veins, step)
            reaches = venation == "arcuate" or blade.gap(path[-1:])[0] < 1.25 * step
            if len(path) >= 3 and reaches:  # an open secondary cut short of the margin is dropped
                veins.append(path)
    lift = lifter(xy, heights, frame, poly)
    if relief == "dome":
        rise = dome(blade, HEIGHT_RATIO, np.zeros(2), round_base)
        return [lift(world(vein), length * rise(vein)) for vein in veins]
    return [lift(world(vein), HEIGHT_RATIO * length * blade.gap(vein)) for vein in veins]
