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
    "Plain",
    "PlanningError",
    "ResolutionError",
    "SpecError",
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


class SpecError(InvalidParameterError):
    """A specification is missing, malformed or has a value that is not allowed.

    ``name`` is the key at fault as written in the file (``"parameters.L2"``,
    ``"limits.theta1"``, ``"mechanism"``), or the file itself.
    """


class PlanningError(MoveabilityError):
    """No certified motion joins the poses (they lie in no common region, or the
    precision cannot tell)."""


class Plain(str):
    """Text shown as is (not quoted) in an error message: the ``received`` of an
    :class:`InvalidParameterError` that is a description, not a value.

    Examples
    --------
    >>> str(InvalidParameterError("path", "a file", Plain("a folder")))
    'invalid path: expected a file, got a folder'
    """

    __slots__ = ()

    def __repr__(self) -> str:
        return str.__str__(self)
