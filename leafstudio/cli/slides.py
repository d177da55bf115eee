"""`leafstudio slides`: a lesson on a leaf as slides, a PNG per step and a PDF, with forms
compared side by side (render/step_slides.py)."""

from __future__ import annotations

import argparse

from leafstudio._shared.safewrite import check_outputs
from leafstudio.cli.options import EXIT_OK, add_run_options, run_pipeline, summary
from leafstudio.errors import LeafError
from leafstudio.render.lesson import LESSON_STEPS
from leafstudio.sources.leafphoto import photo_path


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The `slides` subcommand."""
    sli = sub.add_parser(
        "slides",
        help="the lesson's steps on a leaf (and forms compared) as slides: PNGs and a PDF",
    )
    add_run_options(sli)
    sli.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="DIR|PDF",
        help="a folder (a PNG per slide and lesson.pdf) or a .pdf file",
    )
    sli.add_argument(
        "--compare",
        action="append",
        default=[],
        metavar="TERM,TERM[,...]",
        help="a slide of two to four forms side by side, each named by a term "
        "(ovate,obovate or serrate,dentate; `form --list` lists them); repeatable",
    )


def comparisons(specs: list[str]) -> list[tuple[str, tuple]]:
    """Each --compare as (title, forms), checked before any work."""
    from leafstudio.forms.glossary import form_of_term  # heavy (the forms): not for --help

    found = []
    for spec in specs:
        terms = [t.strip() for t in spec.split(",") if t.strip()]
        if not 2 <= len(terms) <= 4:
            raise LeafError(f"--compare takes two to four terms, got {spec!r}")
        found.append((" beside ".join(terms), tuple(form_of_term(t) for t in terms)))
    return found


def run(args: argparse.Namespace) -> int:
    """Reconstruct the leaf, then write every slide together (all or none)."""
    from leafstudio.render.step_slides import lesson_slides, slide_paths, write_slides
    from leafstudio.sources.files import load_leaf  # heavy (bends: scipy, numba): not for --help

    compared = comparisons(args.compare)
    check_outputs(
        [args.input, photo_path(args.input), *args.vein],
        slide_paths(args.output, len(LESSON_STEPS) + len(compared)),
    )
    _, result = run_pipeline(args, load_leaf(args.input, veins=args.vein))
    shown = lesson_slides(result, compared)
    write_slides(shown, args.output)
    summary(f"{args.output}: {len(shown)} slides")
    return EXIT_OK
