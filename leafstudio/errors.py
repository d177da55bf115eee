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
