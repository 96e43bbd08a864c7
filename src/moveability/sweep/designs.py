"""The designs of a sweep: ``--vary NAME=START:STOP:COUNT`` ranges and their product.

A *varied name* is a parameter of the spec's mechanism (``L1``) or an end of a
joint's limit (``theta1.min``, ``theta1.max``). A *design* is the spec with the
varied values substituted, checked again by :func:`moveability.mechanisms.registry.load_spec`:
a design that is not a valid spec (a negative length, ``lo >= hi``) raises a
:class:`~moveability.errors.SpecError` when applied, which the sweep records as
that design's error.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from typing import Any, NamedTuple

import numpy as np

from ..errors import InvalidParameterError, SpecError
from ..mechanisms.registry import load_spec
from ..spec import UNLIMITED, parse_angle

__all__ = [
    "LIMIT_ENDS",
    "Vary",
    "apply_design",
    "check_varies",
    "design_grid",
    "parse_vary",
    "varied_unit",
]

#: the two ends of a joint's limit, as written after the joint's name
LIMIT_ENDS = ("min", "max")

_SYNTAX = "NAME=START:STOP:COUNT (e.g. L1=6:10:5 or theta1.max=pi/2:pi:3)"


class Vary(NamedTuple):
    """One swept name and the values it takes.

    Attributes
    ----------
    name : str
        A parameter (``"L1"``) or a limit end (``"theta1.min"``), as given.
    values : tuple of float
        ``COUNT`` values evenly spaced from ``START`` to ``STOP`` (both included);
        ``START`` alone when ``COUNT`` is 1.
    """

    name: str
    values: tuple[float, ...]


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _names(spec: Mapping[str, Any]) -> tuple[list[str], list[str]]:
    """Varied names the spec allows: its one-number parameters, the ends of its limited joints."""
    parameters = [name for name, value in spec["parameters"].items() if _is_number(value)]
    ends = [
        f"{joint}.{end}"
        for joint, limit in spec["limits"].items()
        if limit != UNLIMITED
        for end in LIMIT_ENDS
    ]
    return parameters, ends


def parse_vary(text: str, spec: Mapping[str, Any]) -> Vary:
    """Read one ``--vary NAME=START:STOP:COUNT`` against a loaded spec.

    Parameters
    ----------
    text : str
        ``NAME=START:STOP:COUNT``. ``NAME`` is a parameter of the spec or
        ``JOINT.min`` / ``JOINT.max`` for a joint with a limit; ``START`` and
        ``STOP`` are numbers (for a limit end, also ``pi`` expressions read by
        :func:`moveability.spec.parse_angle`); ``COUNT`` is an integer >= 1.
        Only parameters given by one number can be varied.
    spec : mapping
        A spec as returned by :func:`moveability.mechanisms.registry.load_spec`.

    Returns
    -------
    Vary

    Raises
    ------
    moveability.errors.InvalidParameterError
        Named ``--vary`` (or ``--vary NAME``): bad syntax, an unknown name, the
        end of an unlimited joint's limit, a bound that is not a finite number,
        a count that is not an integer >= 1.

    Examples
    --------
    >>> from moveability import load_spec
    >>> spec = load_spec("examples/five-bar-paper.toml")
    >>> parse_vary("L2=4:6:3", spec)
    Vary(name='L2', values=(4.0, 5.0, 6.0))
    >>> parse_vary("theta1.max=pi/2:pi:2", spec).values
    (1.5707963267948966, 3.141592653589793)
    >>> parse_vary("L9=1:2:3", spec)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
        ...
    moveability.errors.InvalidParameterError: invalid --vary L9: expected a parameter ...
    """
    name, sep, rest = str(text).partition("=")
    name = name.strip()
    parts = rest.split(":")
    if not sep or not name or len(parts) != 3:
        raise InvalidParameterError("--vary", _SYNTAX, text)
    parameters, ends = _names(spec)
    if name not in parameters and name not in ends:
        if name in spec["parameters"]:
            raise InvalidParameterError(
                f"--vary {name}", "a parameter given by one number", spec["parameters"][name]
            )
        joint, dot, end = name.partition(".")
        if dot and spec["limits"].get(joint) == UNLIMITED and end in LIMIT_ENDS:
            raise InvalidParameterError(
                f"--vary {name}",
                f"a limit end of a joint with a limit ({joint} is {UNLIMITED!r} in the spec)",
                text,
            )
        allowed = ", ".join(parameters + ends)
        raise InvalidParameterError(
            f"--vary {name}",
            f"a parameter or a limit end of the {spec['mechanism']} spec ({allowed})",
            text,
        )
    is_angle = name in ends
    bounds = []
    for part, which in zip(parts[:2], ("START", "STOP"), strict=True):
        bounds.append(_bound(part, f"--vary {name} {which}", is_angle))
    count_text = parts[2].strip()
    try:
        count = int(count_text)
    except ValueError:
        count = 0
    if count < 1:
        raise InvalidParameterError(f"--vary {name} COUNT", "an integer >= 1", parts[2])
    values = np.linspace(bounds[0], bounds[1], count)
    return Vary(name, tuple(float(v) for v in values))


def _bound(text: str, name: str, is_angle: bool) -> float:
    if is_angle:
        try:
            return parse_angle(text.strip(), name)
        except SpecError:
            allowed = 'a finite angle in radians: a number or "pi", "pi/2", "3*pi/4", ...'
            raise InvalidParameterError(name, allowed, text) from None
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise InvalidParameterError(name, "a finite number", text)
    return value


def check_varies(varies: Sequence[Vary]) -> None:
    """Refuse a name varied twice.

    Examples
    --------
    >>> check_varies([Vary("L1", (1.0,)), Vary("L1", (2.0,))])
    Traceback (most recent call last):
        ...
    moveability.errors.InvalidParameterError: invalid --vary L1: expected each name once, got 'L1'
    """
    seen: set[str] = set()
    for vary in varies:
        if vary.name in seen:
            raise InvalidParameterError(f"--vary {vary.name}", "each name once", vary.name)
        seen.add(vary.name)


def design_grid(varies: Sequence[Vary]) -> list[tuple[float, ...]]:
    """The product of the ranges: one tuple of values per design, the last name fastest.

    Examples
    --------
    >>> design_grid([Vary("L1", (1.0, 2.0)), Vary("theta1.max", (3.0, 4.0))])
    [(1.0, 3.0), (1.0, 4.0), (2.0, 3.0), (2.0, 4.0)]
    """
    return list(itertools.product(*(vary.values for vary in varies)))


def apply_design(
    spec: Mapping[str, Any], names: Sequence[str], values: Sequence[float]
) -> dict[str, Any]:
    """The spec with the varied values substituted, checked by :func:`load_spec`.

    Parameters
    ----------
    spec : mapping
        A spec as returned by :func:`moveability.mechanisms.registry.load_spec`.
    names, values : sequences
        Varied names (checked by :func:`parse_vary`) and their values.

    Raises
    ------
    moveability.errors.SpecError
        When the design is not a valid spec; the message names the key.

    Examples
    --------
    >>> from moveability import load_spec
    >>> spec = load_spec("examples/five-bar-paper.toml")
    >>> design = apply_design(spec, ["L2", "theta1.min"], [6.0, -1.0])
    >>> design["parameters"]["L2"], design["limits"]["theta1"]
    (6.0, (-1.0, 3.141592653589793))
    >>> apply_design(spec, ["theta1.max"], [-2.0])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
        ...
    moveability.errors.SpecError: invalid limits.theta1: expected [lo, hi] with lo < hi ...
    """
    parameters = dict(spec["parameters"])
    limits: dict[str, Any] = {
        joint: (list(limit) if limit != UNLIMITED else limit)
        for joint, limit in spec["limits"].items()
    }
    for name, value in zip(names, values, strict=True):
        joint, dot, end = name.partition(".")
        if dot:
            limits[joint][LIMIT_ENDS.index(end)] = float(value)
        else:
            parameters[name] = float(value)
    return load_spec({"mechanism": spec["mechanism"], "parameters": parameters, "limits": limits})


def varied_unit(name: str) -> str:
    """The unit of a varied name, for labels.

    Parameters are lengths; a limit end is in radians for a revolute joint
    (named ``theta...``, as in every spec of the package) and in the joint's
    own units otherwise (a prismatic joint's length).

    Examples
    --------
    >>> varied_unit("theta1.max"), varied_unit("L1"), varied_unit("rho1.min")
    ('rad', 'length', 'joint units')
    """
    joint, dot, _ = name.partition(".")
    if not dot:
        return "length"
    return "rad" if joint.startswith("theta") else "joint units"
