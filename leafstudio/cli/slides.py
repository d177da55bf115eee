"""`leafstudio slides`: a lesson on a leaf as slides, a PNG per step and a PDF, with forms
compared side by side (render/step_slides.py); a saved project's drawn leaf at the angle it was
drawn, as the app shows it."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from leafstudio._shared.safewrite import check_outputs
from leafstudio.cli.options import EXIT_OK, add_run_options, run_pipeline, summary
from leafstudio.errors import LeafError
from leafstudio.render.lesson import LESSON_STEPS
from leafstudio.sources.leafphoto import photo_path

if TYPE_CHECKING:
    from leafstudio.core.plane import Frame


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
    from leafstudio.forms.terms import term_key

    found = []
    for spec in specs:
        terms = [t.strip() for t in spec.split(",") if t.strip()]
        if not 2 <= len(terms) <= 4:
            raise LeafError(f"--compare takes two to four terms, got {spec!r}")
        keys = [term_key(t) for t in terms]
        twice = next((k for i, k in enumerate(keys) if k in keys[:i]), None)
        if twice is not None:  # a form beside itself compares nothing
            raise LeafError(f"--compare {spec!r} names {twice!r} twice")
        forms = [form_of_term(t) for t in terms]
        same = next(
            ((i, j) for j in range(len(forms)) for i in range(j) if forms[i] == forms[j]), None
        )
        if same is not None:  # two terms of one form: "entire" is elliptic's margin (review37)
            first, second = terms[same[0]], terms[same[1]]
            raise LeafError(f"--compare {spec!r}: {second!r} shows the same form as {first!r}")
        found.append((" beside ".join(terms), tuple(forms)))
    return found


def drawn_frame(path: str) -> Frame | None:
    """The frame a saved project's sketch was drawn on (sources/sketch_entry.drawn_frame), or
    None for any other input: the slides then draw a drawn leaf at the angle it was drawn, as
    the app's lesson and its File > Export slides do (step_slides.plan_frame), not level."""
    from leafstudio.sources import sketch_entry
    from leafstudio.sources.files import load_project  # heavy (bends: scipy): not for --help

    if not path.lower().endswith(".json"):
        return None
    return sketch_entry.drawn_frame(load_project(path)[2], path)


def run(args: argparse.Namespace) -> int:
    """Reconstruct the leaf, then write every slide together (all or none)."""
    from leafstudio.render.step_slides import lesson_slides, plan_frame, slide_paths, write_slides
    from leafstudio.sources.files import load_leaf  # heavy (bends: scipy, numba): not for --help

    compared = comparisons(args.compare)
    check_outputs(
        [args.input, photo_path(args.input), *args.vein],
        slide_paths(args.output, len(LESSON_STEPS) + len(compared)),
    )
    like = drawn_frame(args.input)
    _, result = run_pipeline(args, load_leaf(args.input, veins=args.vein))
    shown = lesson_slides(result, compared, plan_frame(result, like))
    write_slides(shown, args.output)
    summary(f"{args.output}: {len(shown)} slides")
    return EXIT_OK
