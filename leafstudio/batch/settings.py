"""A batch's settings and its trait table's columns: what every input is run with, and the key
that tells `resume` which earlier rows still stand."""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field

from leafstudio.core.prepare.units import POINT_ARRAY_POWER
from leafstudio.model import Params
from leafstudio.sources.scan import OUTLINE_POINTS

FORMATS = ("ply", "glb", "obj", "vtp", "none")  # mesh types save_mesh writes, or none
DEFAULT_TABLE = "traits.csv"
RESULTS = 35  # the session whose change last moved a row's figures for the same input and
# settings (35: a scan's cubes cut in its own frame, core/plane.grid_frame; 34: a scan's
# sheet's normal on one side where the blade curls past upright, core/sheet.py; 33: its sheet
# weighed per cell; a posed outline's sag points' curvatures):
# `--resume` runs the rows of an older table again (review33: it kept pot1_15's area 985.63
# from the old sheet beside 968.59 from the new); bump it with such a change

SHAPE_COLUMNS = (
    "area",
    "projected_area",
    "perimeter",
    "length",
    "width",
    "aspect_ratio",
    "height",
)
CURVATURE_COLUMNS = tuple(
    f"{name}_{stat}"
    for name in ("mean_curvature", "gaussian_curvature")
    for stat in ("mean", "min", "max")
)
#: the power of a real length's scale each column goes with (its unit: mm, mm², 1/mm, 1/mm²)
TRAIT_POWERS = {
    "area": 2,
    "projected_area": 2,
    "perimeter": 1,
    "length": 1,
    "width": 1,
    "aspect_ratio": 0,
    "height": 1,
    **{name: POINT_ARRAY_POWER[name.rsplit("_", 1)[0]] for name in CURVATURE_COLUMNS},
    "scan_mean": 1,  # distances from the scan's points to the surface
    "scan_p95": 1,
}
SCAN_COLUMNS = (
    "scan_points",
    "scan_mean",
    "scan_p95",
    "scan_beyond_1pct",
    "scan_beyond_2pct",
    "scan_folded",
    "scan_crumpled",
)
INT_COLUMNS = frozenset({"k", "grid", "scan_points"})
FLOAT_COLUMNS = frozenset(
    {*SHAPE_COLUMNS, *CURVATURE_COLUMNS, *SCAN_COLUMNS, "seconds"} - INT_COLUMNS
)


def columns(scans: bool) -> tuple[str, ...]:
    """The trait table's columns, in order (the scan distances only for scans)."""
    return (
        "input",
        "status",
        "error",
        "mesh",
        "k",
        "grid",
        *SHAPE_COLUMNS,
        *CURVATURE_COLUMNS,
        *(SCAN_COLUMNS if scans else ()),
        "warnings",
        "seconds",
        "sha256",
        "mesh_sha256",
        "settings",
    )


@dataclass(frozen=True)
class Settings:
    """What every input of a batch is run with.

    Parameters
    ----------
    params : Params
        The reconstruction settings (the same for every input, so traits compare; a project's
        saved parameters are not applied).
    scans : bool, default: False
        Inputs are 3D scans: extract boundary and veins, then reconstruct, then measure the
        distances from the scan's blade points to the surface.
    format : str, default: "ply"
        Mesh format (one of FORMATS; "none" writes no meshes).
    force : bool, default: False
        With scans: a scan that does not look like one leaf (extract's plausibility check) is
        reconstructed anyway, its problems the row's warnings, as `extract --force`; without it
        the row fails with extract's line.
    """

    params: Params = field(default_factory=Params)
    scans: bool = False
    format: str = "ply"
    force: bool = False
    length: float | None = None  # each leaf's real length in metres (save_mesh's length); the
    # traits are then in millimetres

    def key(self) -> str:
        """A short hash of the settings: rows made with other settings are not resumed."""
        text = json.dumps(
            {
                "params": self.params.to_dict(),
                "scans": self.scans,
                "format": self.format,
                "points": OUTLINE_POINTS,
                "force": self.force,
                "results": RESULTS,
                # with a length the traits are in millimetres: a table written when they stayed
                # in the input's units is not resumed into one
                **({"length": self.length, "traits": "mm"} if self.length is not None else {}),
            },
            sort_keys=True,
        )
        return hashlib.sha256(text.encode()).hexdigest()[:16]
