"""`leafstudio gui` (and `leafstudio` alone): open the app."""

from __future__ import annotations

import argparse

from leafstudio._shared.inputs import check_file_kind
from leafstudio._shared.safewrite import refuse_overlap
from leafstudio.errors import LeafError
from leafstudio.sources.leafphoto import photo_path


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The `gui` subcommand."""
    gui = sub.add_parser("gui", help="open the app (on FILE, or on the nested demo)")
    gui.add_argument("file", nargs="?", help="a leaf file, project or leaf scan to open")
    gui.add_argument(
        "--screenshot", metavar="PNG", help="save the window once reconstructed, then exit"
    )
    gui.add_argument(
        "--lesson",
        metavar="FILE",
        help="open FILE in the lesson mode: the method one step per screen, full screen "
        "(arrow keys or space to move, Esc to leave)",
    )


def run(args: argparse.Namespace) -> int:
    """Run the app on the file given (the nested demo without one); a folder, a named pipe or a
    device given as the file, and a screenshot that would replace the file opened, are refused
    before the app starts."""
    from leafstudio.gui.qt.app import run_app  # Qt: only for the app

    path, screenshot = getattr(args, "file", None), getattr(args, "screenshot", None)
    lesson = getattr(args, "lesson", None)
    if lesson is not None and path is not None and path != lesson:
        raise LeafError(f"give one leaf to open, FILE or --lesson FILE, not both ({path})")
    path = lesson if lesson is not None else path
    if path is not None:
        check_file_kind(path)
    refuse_overlap([path, photo_path(path)], [screenshot])
    return run_app(path, screenshot, lesson=lesson is not None)
