"""Exceptions raised by moveability.

Every exception derives from :class:`MoveabilityError`; those about a bad
argument also derive from :class:`ValueError`, so callers may catch either.
Messages name the parameter, what is allowed and what was received.
"""

from __future__ import annotations

__all__ = [
    "IncompatibleTreesError",
    "InvalidParameterError",
    "MoveabilityError",
    "ResolutionError",
]


class MoveabilityError(Exception):
    """Root of every error raised by moveability."""


class InvalidParameterError(MoveabilityError, ValueError):
    """An argument has a value that is not allowed.

    Parameters
    ----------
    name : str
        The parameter at fault, as the caller spelled it.
    allowed : str
        What the parameter accepts.
    received : object
        What was given.
    """

    def __init__(self, name: str, allowed: str, received: object) -> None:
        self.name = name
        self.allowed = allowed
        self.received = received
        shown = repr(received)
        if len(shown) > 120:
            shown = shown[:117] + "..."
        super().__init__(f"invalid {name}: expected {allowed}, got {shown}")


class IncompatibleTreesError(InvalidParameterError):
    """Two trees cannot be combined (different boxes, dimensions or periodicity)."""


class ResolutionError(InvalidParameterError):
    """The requested precision or depth would not fit in memory or in the keys."""
