"""Exceptions raised by moveability.

Every exception derives from :class:`MoveabilityError`; those about a bad
argument also derive from :class:`ValueError`, so callers may catch either.
Messages name the parameter, what is allowed and what was received.
"""

from __future__ import annotations

__all__ = [
    "IncompatibleTreesError",
    "InputError",
    "InvalidParameterError",
    "MissingExtraError",
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


class InputError(MoveabilityError, ValueError):
    """Bad input to a command that is not the value of one library parameter: an output
    that cannot be written, an option that does not fit the command. The message is
    ready to show (one line); the command line exits with status 2.

    Examples
    --------
    >>> str(InputError("refusing to overwrite out.json: it exists (use --overwrite)"))
    'refusing to overwrite out.json: it exists (use --overwrite)'
    """

    def __init__(self, message: str) -> None:
        super().__init__(" ".join(str(message).splitlines()))


class MissingExtraError(MoveabilityError, ImportError):
    """A feature needs an optional dependency group that is not installed.

    Parameters
    ----------
    extra : str
        The group: ``pip install "moveability[extra]"`` installs it.
    feature : str
        What needs it, in words.
    module : str or None
        The module that could not be imported.

    Examples
    --------
    >>> print(MissingExtraError("plot", "figures", "matplotlib"))
    matplotlib is not installed (figures): pip install "moveability[plot]"
    """

    def __init__(self, extra: str, feature: str, module: str | None) -> None:
        self.extra = extra
        needed = module or f"the {extra} extra"
        super().__init__(
            f'{needed} is not installed ({feature}): pip install "moveability[{extra}]"'
        )


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
