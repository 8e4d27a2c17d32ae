"""Exceptions with one-line messages meant for users (the CLI prints them without a traceback)."""


class PolyfoldError(Exception):
    """Base class: the message is one line that names the problem (and file/face/edge index)."""

    exit_code = 2


class MeshError(PolyfoldError):
    """The input mesh cannot be used (unreadable, empty, non-finite, non-manifold edge, ...)."""

    exit_code = 2


class NoNetFound(PolyfoldError):
    """No net satisfying the request (e.g. --max-pieces 1) was found within the budget.

    pieces: when a search ran, a function that returns its best net cut into pieces and the
    search's stats (what `unfold` would have returned without the request), so a caller that
    settles for pieces need not search again; None when no search ran."""

    exit_code = 1

    def __init__(self, message: str, pieces=None):
        super().__init__(message)
        self.pieces = pieces


class OutOfTime(PolyfoldError):
    """A run reached its hard time limit in work it cannot skip (`Deadline.check`); `doing` says
    what it was doing. The caller adds what to do about it (e.g. a smaller mesh)."""

    exit_code = 1

    def __init__(self, message: str, doing: str = "") -> None:
        super().__init__(message)
        self.doing = doing


def one_line(exc: BaseException) -> str:
    """An exception as the one line a user sees: a PolyfoldError's message (its first line), any
    other exception as 'internal error (Type): first line'."""
    text = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
    if isinstance(exc, PolyfoldError):
        return text or type(exc).__name__
    return f"internal error ({type(exc).__name__}): {text}".rstrip(": ")
