"""`leafstudio reconstruct`: a leaf's mesh, and on request its figures, metrics, turntable and the
distances to a scan of the real leaf."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from leafstudio._shared.safewrite import check_outputs, replace_atomically, staged, write_bytes
from leafstudio.assets.units import UNITS_SAID
from leafstudio.cli.options import EXIT_OK, add_run_options, log, run_pipeline
from leafstudio.errors import LeafError
from leafstudio.sources.leafphoto import photo_path


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The `reconstruct` subcommand."""
    from leafstudio.render.figure import FIGURE_SCALARS  # pyvista and VTK: only when asked for

    rec = sub.add_parser("reconstruct", help="reconstruct a leaf and write its mesh")
    add_run_options(rec)
    rec.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="MESH",
        help=".ply, .obj (+ .mtl, _texture.png), .glb, .gltf, .stl, .3mf, .vtp or .vtk",
    )
    rec.add_argument(
        "--figure", metavar="PNG", help="also render iso and top views with the input points"
    )
    rec.add_argument(
        "--colour-by",
        choices=FIGURE_SCALARS,
        default="height",
        help="what the figure's colours show (default height)",
    )
    rec.add_argument(
        "--metrics",
        metavar="JSON",
        help="write Table-1 distances, mesh facts and measurements here (in mm with --length)",
    )
    rec.add_argument(
        "--against",
        metavar="SCAN",
        help="a scan of the real leaf: report the distances from its points to the surface",
    )

    rec.add_argument(
        "--texture",
        default="auto",
        metavar="auto|none|IMAGE",
        help="the mesh's texture: auto (generated: blade and veins), none, or an image (a photo "
        "the leaf came from by `leafstudio photo` maps back onto itself; default auto)",
    )
    rec.add_argument(
        "--thickness",
        metavar="T",
        help="write a closed solid T thick: a fraction of the leaf length (0.01) or a length "
        "with its unit for a leaf in millimetres (0.4mm)",
    )
    rec.add_argument(
        "--length",
        metavar="L",
        help=f"the leaf's real length, base to apex ({UNITS_SAID}): "
        "glTF, OBJ and USD in metres, STL, 3MF, PLY in millimetres (default: the input's scale)",
    )
    rec.add_argument(
        "--lod",
        type=int,
        default=0,
        metavar="N",
        help="also write N coarser levels of detail, each with half the triangles",
    )
    rec.add_argument(
        "--turntable", metavar="GIF|MP4", help="also render the leaf turning once (for slides)"
    )
    rec.add_argument(
        "--steps-figure", metavar="PNG", help="also render the pipeline's steps side by side"
    )


def run(args: argparse.Namespace) -> int:
    """Read, check, compute everything, then write every output together (safewrite.staged):
    a run that fails anywhere leaves all old outputs as they were."""
    # heavy (the pipeline, the writers, the scans: numba, scipy, trimesh): not for --help
    from leafstudio.analysis.fidelity import distance_summary, scaled_fit, scan_warnings, with_folds
    from leafstudio.assets.export import (
        TEXTURES,
        asset_options,
        check_asset_options,
        leaf_placement_of,
        save_mesh,
    )
    from leafstudio.assets.placement import parse_length, size_note
    from leafstudio.assets.writers import MESH_SUFFIXES, written_paths
    from leafstudio.core.evaluate import point_to_mesh_distance
    from leafstudio.core.prepare.units import scaled_metrics
    from leafstudio.render.figure import check_figure_path  # pyvista and VTK: only when asked for
    from leafstudio.sources.files import load_leaf
    from leafstudio.workflows import check_finite, open_scan

    out = Path(args.output)
    if not out.name.lower().endswith(MESH_SUFFIXES):
        raise LeafError(f"unknown mesh type; use one of {', '.join(MESH_SUFFIXES)}", str(out))
    figure = check_figure_path(args.figure) if args.figure else None
    check_asset_options(args.texture, args.thickness, args.lod, args.length)
    from leafstudio.render.slides import check_turntable_path

    turntable = check_turntable_path(args.turntable) if args.turntable else None
    steps = check_figure_path(args.steps_figure) if args.steps_figure else None
    image = None if args.texture in TEXTURES else args.texture  # an input too
    meshes = written_paths(out, args.lod + 1, textured=True)  # with the levels and companions
    outputs = [*meshes, args.metrics, figure, turntable, steps]  # every file this command writes
    check_outputs([args.input, photo_path(args.input), *args.vein, args.against, image], outputs)
    leaf = load_leaf(args.input, veins=args.vein)
    against = None
    if args.against:  # read (and its blade found, as extract finds it) before the run
        against = open_scan(args.against, force=True)
    params, result = run_pipeline(args, leaf)
    for note in against.notes if against is not None else ():  # NaN points left out, forced
        log.warning(f"{args.against}: {note}")  # refusals: as extract says them (review37:
        args.warnings.append(note)  # they were dropped), and for --metrics
    placement = leaf_placement_of(result)  # where the leaf's base and axes are, found once
    if args.length is None and (note := size_note(placement.length, out.suffix)):
        log.warning(f"{args.input}: {note}")
    # with a real length, every figure out in millimetres, as the PLY and STL are (and batch's)
    mm = None if args.length is None else placement.scale(parse_length(args.length), ".ply")
    fidelity = None
    if against is not None:
        scan, blade = against.scan, against.extraction.blade
        length = placement.length  # the blade's (Result.blade_length), found once
        d = point_to_mesh_distance(result.triangle_mesh, scan)  # the blade's are among them
        fidelity = {
            "all": distance_summary(d, length),
            "blade": with_folds(distance_summary(d[blade], length), result.triangle_mesh),
        }
        for note in scan_warnings(fidelity["blade"]):  # as the app and batch warn
            log.warning(f"{args.against}: {note}")
            args.warnings.append(note)  # for --metrics
        if mm is not None:
            fidelity = {part: scaled_fit(fit, mm) for part, fit in fidelity.items()}
    metrics = None
    if args.metrics:
        try:
            measured = result.metrics  # LeafError: a leaf too large to measure
        except LeafError as exc:
            raise LeafError(exc.problem, args.input) from None
        metrics = {
            "input": args.input,
            "params": params.to_dict(),
            "k": result.fitted_k,
            **({"units": "mm", **scaled_metrics(measured, mm)} if mm is not None else measured),
            "warnings": args.warnings,
        }
        if fidelity is not None:
            metrics["fidelity"] = {"scan": args.against, **fidelity}
        check_finite(metrics, args.input)
    with staged():  # every output is written in this block; renamed over the old ones at its end
        options = asset_options(
            args.texture, args.thickness, args.lod, args.input, result, args.length, placement
        )
        save_mesh(result, out, **options)
        if figure is not None:
            from leafstudio.render.figure import render_figure

            replace_atomically(figure, lambda tmp: render_figure(result, tmp, args.colour_by))
        if metrics is not None:
            write_bytes(args.metrics, json.dumps(metrics, indent=2) + "\n")
        if turntable is not None or steps is not None:
            from leafstudio.render.slides import render_steps, render_turntable

            if turntable is not None:
                replace_atomically(turntable, lambda tmp: render_turntable(result, tmp))
            if steps is not None:
                replace_atomically(steps, lambda tmp: render_steps(result, tmp))
    if fidelity is not None:
        unit = "" if mm is None else " mm"
        for part, what in (("all", "all"), ("blade", "blade (no outliers, no petiole)")):
            f = fidelity[part]
            print(
                f"{args.against}: {what}: {f['points']} points to the surface: mean "
                f"{f['mean']:.4g}, median {f['median']:.4g}, 95% {f['p95']:.4g}, max "
                f"{f['max']:.4g}; beyond 1% of the leaf length {f['beyond_1pct']:.1%}, beyond 2% "
                f"{f['beyond_2pct']:.1%} (leaf length {f['length']:.4g}{unit})"
                + (f"; the mesh's edges folded back {f['folded']:.2%}" if "folded" in f else "")
                + (f", its area crumpled {f['crumpled']:.2%}" if "crumpled" in f else "")
            )
    return EXIT_OK
