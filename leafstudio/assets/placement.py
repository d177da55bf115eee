"""Where an exported leaf lands in a 3D tool: which way up, where its base is, and how big.

A leaf's coordinates are whatever its input's were (a scan's millimetres, a photo's pixels made
length 1, a form's unit length), and its relief is along its own plane's normal. Tools expect
otherwise: glTF is Y-up in metres by spec, DCC tools read OBJ and USD as Y-up, and printing and
scanning tools take STL, 3MF and PLY as Z-up millimetres. So each format gets one of two
placements:

- Y-up (glTF, OBJ, USD): the blade lies flat in the XZ plane with its relief along +Y, the base at
  the origin and the midrib along +X (apex on +X); +Z is the leaf's right side seen from above.
- Z-up (PLY, STL, 3MF, VTK): the leaf's own coordinates, as today (a scan's mesh still overlays
  the scan).

The base is where the midrib meets the blade: the midrib (the first vein, as forms and leaf
files order them) followed back from its first point to the outline. A form's base is thus its
origin (the forms' convention) and its apex at +X 1. Without veins, the base is the outline's
end of the leaf plane's long axis. The leaf's length is from the base to the apex along the
midrib's direction (the farthest outline point that way): a form's 1, a cordate leaf's lobes not
counted. A bent leaf's (a posed form, a scan on its sheet) are found on its flat blade and
carried by the bend: the base bent, the axes turned as the bend turns the midrib and the blade
across it at the base, the length the flat blade's. A fold, a roll and a twist keep a form's
apex on +X (its midrib's chord within 0.12° of it, as flat); a curl lifts or lowers the apex
off it, the blade leaving the base along +X.

With a length (`--length 8cm`, `length=0.08`), the leaf is scaled to that real size, and written
in metres for Y-up formats (glTF's unit; USD records metersPerUnit = 1) and in millimetres for
Z-up ones (3MF's unit; what printers assume of STL). Without one, the coordinates keep their
scale.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from leafstudio.assets.solid import boundary_edges
from leafstudio.assets.units import split_length, unit_metres
from leafstudio.core.evaluate import blade_axis, blade_length_width, blade_midrib
from leafstudio.core.plane import Frame, fit_frame
from leafstudio.core.prepare.units import POINT_ARRAY_POWER
from leafstudio.errors import LeafError

Y_UP_SUFFIXES = (".glb", ".gltf", ".obj", ".usda", ".usdc", ".usdz", ".usd")
Y_UP_UNIT, Z_UP_UNIT = 1.0, 1e-3  # metres per unit written with a length: m, mm
STEP = 1e-3  # carried: the bend's differences at the base, a share of the length
OBLIQUE = 5.0  # carried: degrees; a flat midrib's chord this far from both of its pose's axes
# is not the pose's (posed forms: 0; poses fitted to a twist, a curl about a turned frame: 28-61)
OFF_MIDRIB = 0.01  # carried: a flat midrib this share of the length off its pose's is not
# the pose's (forms: 0; poses fitted about the hinge: 0.0004-0.0066 over it; fitted about the
# margin's plane, folded 75 and rolled 1: 0.012-0.10 over it but linear's 0.003; folded 60 and
# twisted 1: 0.03-0.49)
OFF_ROLL = 0.1  # carried: nor is a flat midrib this share of a roll's radius off its pose's
# (fitted about the margin's plane, folded 75 and rolled 1: 0.23-0.35 of it, 7 shapes, linear's
# 0.25 at 0.003 of the length; linear folded 45 and rolled 0.5: 0.24; forms and folds: 0)
LARGEST_LEAF_METRES = 5.0  # no leaf blade is longer (Victoria's pads reach 3 m): units, not metres


def size_note(length: float, suffix: str) -> str | None:
    """A note when a leaf `length` units long, written without a real length, would be read as
    an implausibly large leaf: glTF and USD take units as metres, so a photo's or a scan's
    millimetres arrive as a leaf tens of metres long (issue 23). None when nothing is amiss."""
    if suffix.lower() not in Y_UP_SUFFIXES or length <= LARGEST_LEAF_METRES:
        return None
    return (f"the leaf is {length:.3g} units long, which {suffix} reads as {length:.3g} m; "
            f"--length gives its real size (e.g. --length {length:.3g}mm)")  # fmt: skip


# a real leaf length (metres) taken: 1e308 m wrote infinite coordinates, 1e150 m a glTF of them
# (32-bit floats), 1e-303 m an internal error (curvatures scaled by 1e606)
SHORTEST, LONGEST = 1e-6, 1e3


def parse_length(text: str | float) -> float:
    """A leaf length in metres: '8cm', '0.08m', '80mm', '3in' (units.METRES; a bare number is
    metres).

    Raises
    ------
    LeafError
        If it is not a number with one of the units in units.METRES, or not above 0.
    """
    if isinstance(text, int | float):
        value, unit = float(text), "m"
    else:
        found = split_length(str(text))
        if found is None:
            raise LeafError(f"--length must be a length with its unit (e.g. 8cm, 80mm, 3in), "
                            f"got {text!r}")  # fmt: skip
        value, unit = found[0], found[1] or "m"
    metres = unit_metres(unit, "--length")
    if not np.isfinite(value) or value <= 0:
        raise LeafError(f"--length must be above 0, got {text!r}")
    if not SHORTEST <= value * metres <= LONGEST:  # no leaf; its coordinates overflow
        raise LeafError(f"--length {str(text).strip()} is {value * metres:.3g} m; a leaf's length "
                        "is taken from 1 um to 1 km")  # fmt: skip
    return value * metres


@dataclass(frozen=True)
class Placement:
    """The leaf's base and axes in its own coordinates.

    Attributes
    ----------
    base : (3,) float array
        The point that goes to the origin.
    axes : (3, 3) float array
        Rows: along the midrib (base to apex), across it, and up (the relief's side); a
        right-handed orthonormal frame.
    length : float
        Base to apex along the first axis, in the leaf's units.
    """

    base: np.ndarray
    axes: np.ndarray
    length: float

    def scale(self, metres: float | None, suffix: str) -> float:
        """Written units per leaf unit: 1 without a length, else to metres (Y-up formats) or
        millimetres (Z-up ones)."""
        if metres is None:
            return 1.0
        unit = Y_UP_UNIT if suffix.lower() in Y_UP_SUFFIXES else Z_UP_UNIT
        return metres / unit / self.length

    def transform(self, metres: float | None, suffix: str) -> tuple[np.ndarray, np.ndarray]:
        """(3, 3) linear part A and (3,) offset c of x -> A x + c for the format `suffix`."""
        scale = self.scale(metres, suffix)
        if suffix.lower() not in Y_UP_SUFFIXES:
            return scale * np.eye(3), np.zeros(3)
        along, across, up = self.axes
        rotation = np.stack([along, up, -across])  # X along, Y up, Z = X x Y
        return scale * rotation, -scale * rotation @ self.base


def leaf_placement(
    frame: Any, polygon: np.ndarray, polygon_h: np.ndarray | None, veins: list[np.ndarray]
) -> Placement:
    """The placement of a leaf from its plane frame, (b, 2) outline in that plane, the outline's
    (b,) heights (None: 0) and its (m_i, 3) veins in the leaf's coordinates (module docstring)."""
    up = np.asarray(frame.normal, float)
    midrib = frame.to_plane(veins[0])[0] if veins and len(veins[0]) >= 2 else None
    base_xy, direction = blade_axis(polygon, midrib)
    nearest = np.argmin(np.linalg.norm(polygon - base_xy, axis=1))
    height = 0.0 if polygon_h is None else float(polygon_h[nearest])
    base = frame.to_world(base_xy[None], np.array([height]))[0]
    along = direction[0] * np.asarray(frame.u) + direction[1] * np.asarray(frame.v)
    across = np.cross(up, along)
    length, _ = blade_length_width(polygon, base_xy, direction)
    # no blade length (a degenerate outline): its size; an absolute floor (1e-12) took a leaf
    # at 1e-90 as 1e78 times longer, and --length wrote it with every point at 0
    length = length if length > 0 else float(np.ptp(polygon, axis=0).max()) or 1.0
    return Placement(base=base, axes=np.stack([along, across, up]), length=length)


def result_placement(result: Any) -> Placement:
    """The placement of a pipeline Result (its frame, outline and midrib): a bent leaf's found on
    its flat blade, where the frame and outline are, and carried by its bend (`carried`)."""
    polygon_h = getattr(result, "polygon_h", None)
    leaf = result.leaf
    midrib = blade_midrib(leaf)  # on the flat blade, base first
    veins = [] if midrib is None else [midrib]
    placement = leaf_placement(result.frame, result.polygon, polygon_h, veins)
    return placement if leaf.bend is None else carried(placement, leaf.bend, midrib)


def carried(placement: Placement, bend: Any, midrib: np.ndarray | None = None) -> Placement:
    """The flat blade's `placement` carried by `bend` (model.Bend): the base bent, the axes
    turned as the bend turns the midrib and the blade across it at the base, its length the
    flat blade's. Both are central differences, STEP of the length, on the midrib as it stands
    (a pose's `on_midrib`, a scan's sheet has none): a fold turns each half about that hinge and
    leaves it in place, but it turns points off it, and two taken on the flat sheet under a
    form's raised midrib (slope 0.21 at an ovate form's base) tilted the axes by
    (1 − cos fold) of it: a glb of ovate folded 60° had its apex 6.0° below +X (appreview31,
    finding 1). The turn takes the flat midrib's direction and the blade's across it onto the
    bent ones, so the axes keep their angle to the midrib, which rises off them as on the flat
    blade. A scan's sheet unrolls the blade into a plane of its own, nowhere near the scan's (a
    soybean's base was placed 8.3 mm off its 46 mm mesh).

    A pose fitted to curves (core/unfold.py) need not bend about the leaf's own midrib: an ovate
    folded 60° and twisted 1 was fitted a curl of 1.2 about a turned frame, its flat blade's
    midrib 0.59 of the length across the pose's and 0.38 over it, and its turn at the base put
    +X 63° off the bent midrib's chord; folded 75 and rolled 1, a fold, a roll and a curl of
    0.36 whose flat midrib stands 0.036 over the pose's sheet to make up for it, 19.5°. When
    the flat `midrib` (base first) is not the pose's (`_off_its_midrib`), its terms do not say
    where that midrib goes, and the axes are turned on, the least, to its chord as bent. A curl
    alone keeps its turn at the base (a form curled 1, saved as curves, fitted a curl of 0.93
    without a relief: its midrib's own relief 0.08 over the sheet; 57.2° as the form's 58.1°)."""
    along, across, _ = placement.axes
    step = STEP * placement.length
    ends = placement.base + step * np.stack([along, -along, across, -across])
    standing = getattr(bend, "on_midrib", None)
    flat = ends if standing is None else standing(ends)
    axes = placement.axes @ (_chord_frame(flat).T @ _chord_frame(bend.apply(flat)))
    if midrib is not None and len(midrib) >= 2 and _off_its_midrib(bend, midrib, placement):
        bent = bend.apply(midrib[[0, -1]])
        axes = axes @ _turn_onto(axes[0], _unit(bent[1] - bent[0])).T
    return Placement(bend.apply(placement.base[None])[0], axes, placement.length)


def _off_its_midrib(bend: Any, midrib: np.ndarray, placement: Placement) -> bool:
    """Whether the flat `midrib` is not the midrib `bend` bends about (`carried`; a pose's
    `off_hinge`, a scan's sheet has none). In the pose's frame a midrib runs along u (a curl
    bends it, a fold or a roll turns the blade about it) or along v (a roll bends it: a
    reniform form curled 1 was fitted a roll of 1.78 about a frame turned a quarter); its
    chord oblique to both (more than OBLIQUE from either) leaves the terms nothing to say of
    it (a twist fitted as a curl about a turned frame: 28-61°), and so does a midrib more than
    OFF_MIDRIB of the length over the pose's hinge, their heights making up for a term that
    turns the blade about it (folded 75 and rolled 1: a curl of 0.36), or along u more than
    OFF_ROLL of a roll's radius: a narrow blade's roll is tight, and linear folded 75 and
    rolled 1, its midrib 0.003 of the length over its hinge (0.25 of the roll's radius), was
    fitted a curl of -0.027 whose turn at the base put +X 1.67° off the chord."""
    off_hinge = getattr(bend, "off_hinge", None)
    if off_hinge is None:
        return False
    frame = getattr(bend, "frame", None)  # a placed pose's; a form's is its world
    ends = midrib[[0, -1]]
    chord = ends[1] - ends[0] if frame is None else np.diff(frame.to_plane(ends)[0], axis=0)[0]
    turned = float(np.degrees(np.arctan2(abs(chord[1]), abs(chord[0]))))
    if OBLIQUE < turned < 90.0 - OBLIQUE:
        return True
    over = float(np.abs(off_hinge(midrib)).max())
    terms = getattr(bend, "pose", bend)
    if turned <= OBLIQUE and over * abs(terms.roll) > OFF_ROLL:
        return True
    about = (terms.fold or terms.roll) if turned <= OBLIQUE else (terms.fold or terms.curl)
    return bool(over > OFF_MIDRIB * placement.length and about)


def _turn_onto(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(3, 3) the least rotation taking the unit vector `a` onto the unit vector `b` (about
    a x b; half a turn about any axis square to `a` when they are opposite)."""
    axis, cosine = np.cross(a, b), float(np.clip(a @ b, -1.0, 1.0))
    if np.linalg.norm(axis) < 1e-12:
        if cosine > 0:
            return np.eye(3)
        axis = np.cross(a, np.eye(3)[np.argmin(np.abs(a))])
    axis = _unit(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    sine = np.sqrt(max(0.0, 1.0 - cosine * cosine))
    return np.eye(3) + sine * k + (1.0 - cosine) * (k @ k)


def _chord_frame(ends: np.ndarray) -> np.ndarray:
    """(3, 3) rows: the unit chord of (4, 3) `ends`' first two, the one across of their last
    two made square to it, and the third by the right hand."""
    along = _unit(ends[0] - ends[1])
    across = ends[2] - ends[3]
    across = _unit(across - (across @ along) * along)
    return np.stack([along, across, np.cross(along, across)])


def _unit(vector: np.ndarray) -> np.ndarray:
    return vector / np.linalg.norm(vector)


def mesh_placement(points: np.ndarray, faces: np.ndarray, up: np.ndarray) -> Placement:
    """The placement of a bare mesh ((n, 3) points, (m, 3) faces), without veins: the PCA plane
    of its margin (its boundary edges' vertices, as a leaf's frame is its outline's), `up`'s side
    up, the base at the low end of the long axis."""
    rim = np.unique(boundary_edges(faces))
    frame = fit_frame(points[rim] if len(rim) >= 3 else points, np.zeros((0, 3)))
    if frame.normal @ up < 0:
        frame = Frame(frame.origin, frame.u, -frame.v, -frame.normal)
    xy = frame.to_plane(points)[0]
    return leaf_placement(frame, xy, None, [])


def place(asset: Any, placement: Placement, metres: float | None, suffix: str) -> Any:
    """The MeshAsset moved, turned and scaled for the format `suffix` (module docstring); its
    height scales with it and its curvatures inversely."""
    matrix, offset = placement.transform(metres, suffix)
    # the placement's own scale: the cube root of the matrix's determinant underflowed for a
    # leaf at 1e150 given a length (1e-152 cubed), "ZeroDivisionError"
    scale = placement.scale(metres, suffix)
    if np.allclose(matrix, np.eye(3)) and not offset.any():
        return asset
    rotation = matrix / scale

    def turn(vectors: np.ndarray | None) -> np.ndarray | None:
        return None if vectors is None else np.asarray(vectors) @ rotation.T

    def scaled(values: np.ndarray, power: int) -> np.ndarray:
        for _ in range(abs(power)):  # a factor at a time: scale**-2 overflows at 1e-155
            values = values * scale if power > 0 else values / scale
        return values

    data = {k: scaled(v, POINT_ARRAY_POWER.get(k, 0)) for k, v in asset.point_data.items()}
    return asset.with_(
        points=asset.points @ matrix.T + offset,
        normals=turn(asset.normals),
        plane_normal=turn(asset.plane_normal),
        plane_u=turn(asset.plane_u),
        point_data=data,
    )
