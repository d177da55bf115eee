"""The one exception type that carries a user-facing message."""


class LeafError(ValueError):
    """Bad input or a leaf that cannot be reconstructed; the message is shown to the user as is.

    Parameters
    ----------
    message : str
        What is wrong, in plain words.
    source : str, optional
        The file (or other origin) the problem belongs to; prefixed to the message.

    Attributes
    ----------
    problem, source : str, str or None
        The two parts, apart (a caller that knows the file adds it: `LeafError(e.problem, path)`).

    Examples
    --------
    >>> import leafstudio as ls
    >>> try:
    ...     ls.load_leaf("missing.csv")
    ... except ls.LeafError as exc:
    ...     print(exc.source, "|", exc.problem)
    missing.csv | no such file
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
    """The one line the command line prints for a failure, after "leafstudio: error: " (bad
    input: "FILE: problem") or "leafstudio: " (a bug: "internal error: Type: text"); a batch's
    failed rows carry the same text."""
    if isinstance(exc, LeafError):
        return shorten(str(exc), 400)
    if isinstance(exc, MemoryError):
        return "out of memory: the input is too large for this machine"
    if isinstance(exc, OSError):
        where = f"{exc.filename}: " if exc.filename else ""
        return shorten(f"{where}{exc.strerror or exc}", 400)
    return f"internal error: {shorten(f'{type(exc).__name__}: {exc}', 300)}"
