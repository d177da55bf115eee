"""`leafstudio form` and `leafstudio veins`: the command-line side of leafstudio.forms."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from leafstudio.assets.units import UNITS_SAID
from leafstudio.cli.options import first_run_said, log, summary
from leafstudio.errors import LeafError
from leafstudio.forms.terms import (
    APEXES,
    MARGINS,
    SHAPES,
    USER_BASES,
    VENATION_KINDS,
    format_terms,
    term_key,
)
from leafstudio.model import Leaf, Params


def add_form_parser(sub: argparse._SubParsersAction) -> None:
    """The `form` subcommand."""
    p = sub.add_parser("form", help="write a leaf made from botanical terms (--list: every term)")
    p.add_argument("shape", nargs="?", help=f"one of: {', '.join(SHAPES)} (any case)")
    p.add_argument("--list", action="store_true", help="print every term with its definition")
    p.add_argument(
        "--apex", type=term_key, choices=tuple(APEXES), help="default: the shape's usual apex"
    )
    p.add_argument(
        "--base", type=term_key, choices=USER_BASES, help="default: the shape's usual base"
    )
    p.add_argument("--margin", type=term_key, choices=tuple(MARGINS), default="entire")
    p.add_argument("--teeth", type=int, metavar="N", help="N teeth in all (toothed margins)")
    p.add_argument("--lobes", type=int, metavar="N", help="N lobes in all (--margin lobed)")
    p.add_argument(
        "--venation",
        type=term_key,
        choices=VENATION_KINDS,
        help="default: the shape's usual venation (palmate for reniform, else pinnate)",
    )
    p.add_argument(
        "--secondaries",
        type=int,
        metavar="N",
        help="secondary veins per side (default: the shape's usual: 10 deltoid, 8 spatulate, "
        "else the venation's, 6 pinnate)",
    )
    p.add_argument("--aspect", type=float, metavar="L/W", help="length over greatest width")
    kept = " (the blade's area kept, not its margin's length: README, Real size)"
    p.add_argument(
        "--fold", type=float, default=0.0, metavar="DEG", help="halves turned up DEG" + kept
    )
    p.add_argument(
        "--curl",
        type=float,
        default=0.0,
        metavar="C",
        help="midrib bent on a circle, the apex raised about C lengths" + kept,
    )
    p.add_argument(
        "--roll", type=float, default=0.0, metavar="R", help="margins rolled up R half turns"
    )
    p.add_argument("--twist", type=float, default=0.0, metavar="T", help="apex turned T half turns")
    p.add_argument("--wave", type=float, default=0.0, metavar="A", help="margin wave height")
    p.add_argument("--seed", type=int, default=0, metavar="S", help="a variant (default 0)")
    p.add_argument(
        "--length",
        metavar="L",
        help=f"a mesh's real length, base to apex ({UNITS_SAID}); a mesh -o only",
    )
    p.add_argument(
        "-o",
        "--output",
        metavar="FILE",
        help=".leaf.json, .csv, .txt, .xyz, .ply (the leaf) or "
        "a mesh type (reconstructed with default settings)",
    )


def add_veins_parser(sub: argparse._SubParsersAction) -> None:
    """The `veins` subcommand."""
    p = sub.add_parser("veins", help="grow veins inside a leaf's outline")
    p.add_argument("leaf", help="a leaf file: its boundary is kept, its veins replaced")
    p.add_argument("-o", "--output", required=True, metavar="OUT", help="the leaf with new veins")
    p.add_argument("--venation", type=term_key, choices=VENATION_KINDS, default="pinnate")
    p.add_argument("--secondaries", type=int, metavar="N", help="secondary veins per side")
    p.add_argument("--seed", type=int, default=0, metavar="S")
    p.add_argument(
        "--base",
        metavar="X,Y[,Z]",
        help="where the midrib meets the blade (default: the start of the leaf's first vein, "
        "else an end of the outline's longest axis)",
    )


def run_form(args: argparse.Namespace) -> int:
    if args.list:
        print(format_terms())
        return 0
    # heavy (the outlines' splines, the veins' growth: scipy, numba): not for --help nor --list
    from leafstudio.forms.make import SIDE_ON, Form, seen_on_edge
    from leafstudio.sources.files import LEAF_SUFFIXES, bend_not_kept, save_leaf

    if not args.shape:
        raise LeafError("a shape is needed (leafstudio form --list shows them)")
    if not args.output:
        raise LeafError("the output file is needed: -o FILE")
    out = args.output
    mesh = not out.lower().endswith(LEAF_SUFFIXES)
    if args.length is not None:
        from leafstudio.assets.placement import parse_length  # heavy (numba): with --length only

        parse_length(args.length)
        if not mesh:  # a leaf file keeps the forms' convention, length 1: the length is a mesh's
            raise LeafError(
                f"--length sets a mesh's real size, not a leaf file's (length 1); write a mesh "
                f"(-o LEAF.glb, .obj, .usdz, ...), or write {out} without --length and then "
                f"leafstudio reconstruct {out} -o LEAF.glb --length {args.length}"
            )
    if mesh:
        from leafstudio.assets.writers import MESH_SUFFIXES  # heavy (the writers): a mesh only

        if not out.lower().endswith(MESH_SUFFIXES):
            kinds = ", ".join(dict.fromkeys((*LEAF_SUFFIXES, *MESH_SUFFIXES)))
            raise LeafError(f"unknown file type; use one of {kinds}", out)
    names = ("apex", "base", "margin", "teeth", "lobes", "venation", "secondaries", "aspect")
    form = Form(
        args.shape,
        **{n: getattr(args, n) for n in names},
        fold=args.fold,
        curl=args.curl,
        roll=args.roll,
        twist=args.twist,
        wave=args.wave,
        seed=args.seed,
    )
    leaf = form.leaf()
    if note := form.seam_note():
        log.warning(note)
    if mesh and seen_on_edge(leaf):
        raise LeafError(f"{SIDE_ON}; write the leaf (.leaf.json), or lower --fold or --curl")
    if mesh:
        from leafstudio.assets.export import save_mesh  # heavy (the pipeline): for a mesh only
        from leafstudio.core.pipeline import reconstruct

        with first_run_said():
            result = reconstruct(leaf, Params())
        save_mesh(result, out, length=args.length)
    else:
        save_leaf(leaf, out)
        if (lost := bend_not_kept(leaf, out)) is not None:
            log.warning(lost)
    summary(
        f"{out}: {form.shape} leaf ({form.apex_term} apex, {form.base_term} base, {form.margin} "
        f"margin, {form.venation_term} venation): {len(leaf.boundary)} boundary points, "
        f"{len(leaf.veins)} vein{'' if len(leaf.veins) == 1 else 's'}",
    )
    return 0


def _point(text: str) -> np.ndarray:
    try:
        values = [float(v) for v in text.replace(" ", "").split(",")]
    except ValueError:
        values = []
    if len(values) not in (2, 3) or not np.all(np.isfinite(values)):
        raise LeafError(f"--base must be X,Y or X,Y,Z, got {text!r}")
    return np.array(values)


def _on_curves(leaf: Leaf, point: np.ndarray) -> np.ndarray:
    """`point` (X,Y or X,Y,Z) of a bent leaf as a (3,) point: X,Y at the height of the leaf's
    curves' nearest point there (above, a bent blade has one height where it is seen)."""
    if len(point) == 3:
        return point
    curves = np.vstack([leaf.boundary, *leaf.veins])
    nearest = curves[np.argmin(np.linalg.norm(curves[:, :2] - point, axis=1))]
    return np.array([point[0], point[1], nearest[2]])


def run_veins(args: argparse.Namespace) -> int:
    # heavy (the veins' growth: scipy, shapely, numba): not for --help
    from leafstudio.core.bend import flat_curve, flat_leaf
    from leafstudio.core.prepare.vein_order import midrib_turned
    from leafstudio.core.unfolded import unfolded
    from leafstudio.forms.veins import grow_veins
    from leafstudio.sources.files import bend_not_kept, check_leaf_output, load_leaf, save_leaf

    check_leaf_output(args.output, [args.leaf])
    # a bent leaf's veins are grown on its flat blade and bent as it is: grown in its outline as
    # seen from above, a form folded 75° got veins across its side view, the bend was dropped,
    # and its mesh had half the blade's area (curves in 3D without a bend are unfolded first)
    given = load_leaf(args.leaf)
    leaf = unfolded(given)
    flat = flat_leaf(leaf)
    base = _point(args.base) if args.base else None
    if base is not None and leaf.bend is not None:
        base = flat_curve(leaf.bend, _on_curves(leaf, base)[None])[0]
    if base is None and leaf.veins:  # the midrib's base: its last point when written apex first
        base = flat.veins[0][-1 if midrib_turned(list(flat.veins)) else 0]
    try:
        veins = grow_veins(flat.boundary, args.venation, args.secondaries, base, args.seed)
    except LeafError as exc:
        raise LeafError(exc.problem, args.leaf) from None
    if leaf.bend is not None:  # a scan's sheet remembers the points it bent (sheet_bend.Scaled)
        bent = getattr(leaf.bend, "bent", leaf.bend.apply)
        veins = [bent(v) for v in veins]
    grown = Leaf(boundary=leaf.boundary, veins=veins, bend=leaf.bend)
    save_leaf(grown, args.output)
    if given.bend is not None and (lost := bend_not_kept(grown, args.output)) is not None:
        log.warning(lost)
    summary(
        f"{args.output}: {len(veins)} {args.venation} veins grown inside the outline of "
        f"{Path(args.leaf).name}",
    )
    return 0
