"""The one exception type that carries a user-facing message."""


class LeafError(ValueError):
    """Bad input or a leaf that cannot be reconstructed; the message is shown to the user as is.

    Parameters
    ----------
    message : str
        What is wrong, in plain words.
    source : str, optional
        The file (or other origin) the problem belongs to; prefixed to the message.
    """

    def __init__(self, message: str, source: str | None = None) -> None:
        self.problem = message
        self.source = source
        super().__init__(f"{source}: {message}" if source else message)


def shorten(text: object, limit: int = 60) -> str:
    """`text` cut to at most `limit` characters, marking the cut, so that a long value (a seed of
    5,000 digits, a whole line of a file) cannot flood a one-line message."""
    text = str(text)
    if len(text) <= limit:
        return text
    keep = max(limit - 20, 1)
    return f"{text[:keep]}… ({len(text)} characters)"


def error_line(exc: BaseException) -> str:
    """What the command line says of a failure, after "leafstudio: error: ": "FILE: problem".
    An unexpected exception (a bug, not bad input) reads "internal error: Type: text"."""
    if isinstance(exc, LeafError):
        return str(exc)
    if isinstance(exc, OSError):
        where = f"{exc.filename}: " if exc.filename else ""
        return f"{where}{exc.strerror or exc}"
    return f"internal error: {type(exc).__name__}: {exc}"
