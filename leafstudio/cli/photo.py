"""`leafstudio photo`: the command-line side of sources/photo.py."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from leafstudio.cli.options import summary
from leafstudio.errors import LeafError
from leafstudio.sources.leafphoto import BASE_ENDS, VEIN_CHOICES

if TYPE_CHECKING:
    from leafstudio.sources.photo import PhotoLeaf


def add_photo_parser(sub: argparse._SubParsersAction) -> None:
    """The `photo` subcommand."""
    p = sub.add_parser("photo", help="a leaf's boundary (and grown veins) from a photo or scan")
    p.add_argument("image", help="a photo of one leaf on a plain background (.png, .jpg, ...)")
    p.add_argument(
        "-o", "--output", required=True, metavar="LEAF",
        help=".leaf.json (keeps the photo's pixel map for --texture), .csv, .txt, .xyz or .ply",
    )  # fmt: skip
    p.add_argument(
        "--length", type=photo_length, metavar="L",
        help="base to apex: with a unit (6cm, 60mm, 2.5in) in millimetres, else in the leaf's own "
        "units (default: the photo's own scale in millimetres when its file records a "
        "resolution, as a flatbed scan's DPI; else 1)",
    )  # fmt: skip
    p.add_argument(
        "--base-end", choices=BASE_ENDS, default="auto",
        help="where the base is when no petiole shows it, or when a long narrow apex was taken "
        "for one (default auto: the end of the blade's mirror axis with a basal notch, else "
        "the one the veins lean away from, else the wider)",
    )  # fmt: skip
    p.add_argument(
        "--veins", choices=VEIN_CHOICES, default="auto",
        help="trace: the veins the photo shows; grow: grown inside the outline; auto (default): "
        "traced where the photo shows a midrib, else grown; none",
    )  # fmt: skip
    p.add_argument("--venation", default="pinnate", help="for grown veins (default pinnate)")
    p.add_argument("--seed", type=int, default=0, metavar="S", help="vein growth's variant")


def photo_length(text: str) -> float:
    """`--length`: a bare number as it is, a length with its unit (6cm, as `form` and
    `reconstruct` take it) in millimetres, the unit a photo's own scale gives."""
    try:
        return float(text)
    except ValueError:
        from leafstudio.assets.placement import parse_length  # heavy (numba): not for --help

        try:
            return parse_length(text) * 1e3
        except LeafError as error:  # argparse names the option itself
            said = str(error).removeprefix("--length").lstrip(": ")
            raise argparse.ArgumentTypeError(said) from None


def run_photo(args: argparse.Namespace) -> int:
    """Find the leaf in the photo and write it."""
    # heavy (scipy, scikit-image, the forms' veins): not for --help
    from leafstudio.sources.files import check_leaf_output
    from leafstudio.sources.photo import read_photo_leaf, save_photo_leaf

    check_leaf_output(args.output, [args.image])
    found = read_photo_leaf(
        args.image, length=args.length, base_end=args.base_end, veins=args.veins,
        venation=args.venation, seed=args.seed,
    )  # fmt: skip
    save_photo_leaf(found, args.image, args.output)
    guess = "; base at the wider end (a guess: --base-end names it)"
    summary(
        f"{args.image}: leaf of {int(found.blade.sum())} pixels"
        f"{', petiole cut off' if found.petiole else ''}"
        f"{guess if found.base_cue == 'wider end' else ''}"
        f"{_size(found)}"
        f"; wrote {len(found.leaf.boundary)} "
        f"boundary points and {len(found.leaf.veins)} veins "
        f"({_veins_from(found.veins_from, args.veins)}) to {args.output}",
    )
    return 0


def _veins_from(found: str, asked: str) -> str:
    """Where the veins written came from, in words."""
    if found == "photo":
        return "traced in the photo"
    if found == "grown":
        return "grown: the photo shows no midrib" if asked == "auto" else "grown"
    return "none: the photo shows no midrib" if asked == "trace" else "none asked for"


def _size(found: PhotoLeaf) -> str:
    """The leaf's size and what set it, when the photo's own scale did or nothing did."""
    if found.scale.startswith("the photo's"):
        return f"; {found.length:.4g} mm long ({found.scale}; --length overrides)"
    if not found.scale:
        return "; length 1 (the photo records no scale: --length gives its real one)"
    return ""
