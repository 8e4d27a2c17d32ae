"""Exceptions with one-line messages meant for users (the CLI prints them without a traceback)."""


class PolyfoldError(Exception):
    """Base class: the message is one line that names the problem (and file/face/edge index)."""

    exit_code = 2


class MeshError(PolyfoldError):
    """The input mesh cannot be used (unreadable, empty, non-finite, non-manifold edge, ...)."""

    exit_code = 2


class NoNetFound(PolyfoldError):
    """No net satisfying the request (e.g. --max-pieces 1) was found within the budget."""

    exit_code = 1
