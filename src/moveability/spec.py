"""Reading specifications: TOML files, angles, and the check of a mapping against a schema.

A specification names a mechanism, gives its parameters (lengths) and the limits
of its actuated joints, in radians::

    mechanism = "five-bar"
    [parameters]
    L0 = 7.0
    L1 = 8.0
    L2 = 5.0
    L3 = 8.0
    L4 = 5.0
    [limits]          # [lo, hi] in radians, or "unlimited"
    theta1 = [0.0, "pi"]
    theta2 = [0.0, "pi"]

Bounds are numbers or small expressions of ``pi`` (``"pi/2"``, ``"-3*pi/4"``),
read by :func:`parse_angle` without ``eval``. Every joint of the mechanism needs
a limit: a joint that turns freely says so with ``"unlimited"``.

A checked specification (:func:`check_spec`) is a plain dict::

    {"mechanism": "five-bar",
     "parameters": {"L0": 7.0, ...},
     "limits": {"theta1": (0.0, 3.14159...), "theta2": "unlimited"}}

This module knows no mechanism: it reads TOML (:func:`read_toml`), angles
(:func:`parse_angle`) and checks a mapping against a :class:`MechanismSchema`
(:func:`check_spec`). The schemas, and :func:`~moveability.mechanisms.registry.load_spec`
which picks one by the ``mechanism`` key, live in :mod:`moveability.mechanisms.registry`.
"""

from __future__ import annotations

import math
import numbers
import os
import re
import tomllib
from collections.abc import Mapping, Sequence
from typing import Any, NamedTuple

from .errors import Plain, SpecError

__all__ = [
    "NOTHING",
    "UNLIMITED",
    "MechanismSchema",
    "check_spec",
    "describe_spec",
    "format_angle",
    "parse_angle",
    "read_toml",
]

#: the limit of a joint that turns freely
UNLIMITED = "unlimited"

# a range of exactly one turn ([-pi, pi]) is allowed; the slack of one ulp lets
# "-pi" .. "pi" and "0" .. "2*pi" through whatever the rounding
_TWO_PI_MAX = math.nextafter(2.0 * math.pi, math.inf)

_TOP_KEYS = ("mechanism", "parameters", "limits", "passive_limits", "obstacles", "collisions")


class MechanismSchema(NamedTuple):
    """What a specification of one mechanism must give.

    Parameters
    ----------
    parameters : tuple of str
        Names of the parameters.
    joints : tuple of str
        Names of the actuated joints; each needs an entry in ``[limits]``.
    defaults : mapping of str to float, optional
        Values of the parameters that may be left out; ``None`` when all are
        required.
    kinds : mapping of str to str, optional
        Kind of each parameter: ``"length"`` (a positive number, the default),
        ``"lengths"`` (one positive number per joint) or ``"points"`` (one
        ``[x, y]`` pair per joint).
    joint_kind : str, optional
        ``"angle"`` (revolute joints, radians, the default; ``"unlimited"``
        allowed), ``"distance"`` (prismatic joints measuring a length: a stroke
        ``[lo, hi]`` with ``0 <= lo < hi``) or ``"position"`` (prismatic joints
        along a line: any ``lo < hi``).
    passive : tuple of str, optional
        Passive joints whose angle ``[passive_limits]`` may limit.
    shapes : bool, optional
        Whether ``[[obstacles]]`` and ``[collisions]`` apply (the links are
        known as segments).
    """

    parameters: tuple[str, ...]
    joints: tuple[str, ...]
    defaults: Mapping[str, Any] | None = None
    kinds: Mapping[str, str] | None = None
    joint_kind: str = "angle"
    passive: tuple[str, ...] = ()
    shapes: bool = False


#: what an error message says was received for a missing key
NOTHING = Plain("nothing")

_NUMBER = r"(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?"
_PLAIN_RE = re.compile(rf"\s*(?P<sign>[-+]?)\s*(?P<num>{_NUMBER})\s*")
_PI_RE = re.compile(
    rf"\s*(?P<sign>[-+]?)\s*(?:(?P<num>{_NUMBER})\s*\*\s*)?pi(?:\s*/\s*(?P<den>{_NUMBER}))?\s*",
    re.IGNORECASE,
)
_ANGLE_ALLOWED = 'a finite angle in radians: a number or "pi", "-pi", "pi/2", "3*pi/4", ...'


def _is_number(value: object) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def parse_angle(value: object, name: str = "angle") -> float:
    """Read an angle in radians from a number or a small expression of ``pi``.

    Parameters
    ----------
    value : float or str
        A real number, or text of one of the forms ``[-]number``, ``[-]pi``,
        ``[-]pi/number``, ``[-]number*pi``, ``[-]number*pi/number`` (spaces
        allowed around the operators). Nothing is evaluated.
    name : str, default "angle"
        How to name the value in an error message.

    Returns
    -------
    float
        The angle, finite.

    Raises
    ------
    SpecError
        If ``value`` is not a finite number nor one of the forms above
        (``"2pi"``, ``"pi+1"``, ``"nan"`` and ``"pi/0"`` are refused).

    Examples
    --------
    >>> parse_angle("pi/2")
    1.5707963267948966
    >>> parse_angle("-3*pi/4")
    -2.356194490192345
    >>> parse_angle(" 0.5 "), parse_angle(2)
    (0.5, 2.0)
    >>> parse_angle("pi/2 + 1", name="limits.theta1[1]")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
        ...
    moveability.errors.SpecError: invalid limits.theta1[1]: expected ..., got 'pi/2 + 1'
    """
    if _is_number(value):
        angle = float(value)  # type: ignore[arg-type]
    elif isinstance(value, str):
        angle = _parse_angle_text(value, name)
    else:
        raise SpecError(name, _ANGLE_ALLOWED, value)
    if not math.isfinite(angle):
        raise SpecError(name, _ANGLE_ALLOWED, value)
    return angle


def format_angle(value: float) -> str:
    """An angle as :func:`parse_angle` reads it: a simple multiple of ``pi`` where
    it is one (to 1e-12), else the number.

    Examples
    --------
    >>> format_angle(math.pi), format_angle(-math.pi / 2), format_angle(3 * math.pi / 4)
    ('pi', '-pi/2', '3*pi/4')
    >>> format_angle(0.0), format_angle(0.25)
    ('0', '0.25')
    >>> parse_angle(format_angle(-5 * math.pi / 6)) == -5 * math.pi / 6
    True
    """
    v = float(value)
    if v == 0.0 or not math.isfinite(v):
        return f"{v:g}"
    for den in (1, 2, 3, 4, 6, 8, 12):
        num = round(v * den / math.pi)
        if num and abs(v - num * math.pi / den) <= 1e-12 * max(1.0, abs(v)):
            sign, k = ("-" if num < 0 else ""), abs(num) // math.gcd(abs(num), den)
            d = den // math.gcd(abs(num), den)
            text = ("pi" if k == 1 else f"{k}*pi") + ("" if d == 1 else f"/{d}")
            return sign + text
    return f"{v:.12g}"


def describe_spec(spec: Mapping[str, Any]) -> str:
    """A spec mapping in one line for people: the mechanism, its parameters and
    joint limits (angles as multiples of pi where they are).

    Examples
    --------
    >>> describe_spec({"mechanism": "five-bar",
    ...                "parameters": {"L0": 7.0, "L1": 8.0},
    ...                "limits": {"theta1": [0.0, math.pi], "theta2": "unlimited"}})
    'five-bar: L0 = 7, L1 = 8; limits theta1 in [0, pi], theta2 unlimited'
    """

    def show(value: Any) -> str:
        if isinstance(value, int | float) and not isinstance(value, bool):
            return f"{value:g}"
        if isinstance(value, list | tuple):
            return "[" + ", ".join(show(v) for v in value) + "]"
        return str(value)

    parts = [f"{k} = {show(v)}" for k, v in dict(spec.get("parameters") or {}).items()]
    text = f"{spec.get('mechanism', '?')}: " + (", ".join(parts) if parts else "(no parameters)")
    limits = []
    for joint, lim in dict(spec.get("limits") or {}).items():
        if lim == UNLIMITED:
            limits.append(f"{joint} unlimited")
        elif isinstance(lim, list | tuple) and len(lim) == 2:
            limits.append(f"{joint} in [{format_angle(lim[0])}, {format_angle(lim[1])}]")
        else:
            limits.append(f"{joint} {show(lim)}")
    return text + ("; limits " + ", ".join(limits) if limits else "")


def _parse_angle_text(text: str, name: str) -> float:
    plain = _PLAIN_RE.fullmatch(text)
    if plain is not None:
        magnitude = float(plain["num"])
        sign = plain["sign"]
    else:
        match = _PI_RE.fullmatch(text)
        if match is None:
            raise SpecError(name, _ANGLE_ALLOWED, text)
        coefficient = float(match["num"]) if match["num"] else 1.0
        denominator = float(match["den"]) if match["den"] else 1.0
        if denominator == 0.0:
            raise SpecError(name, _ANGLE_ALLOWED, text)
        magnitude = coefficient * math.pi / denominator
        sign = match["sign"]
    return -magnitude if sign == "-" else magnitude


def check_spec(data: Mapping[str, Any], name: str, schema: MechanismSchema) -> dict[str, Any]:
    """Check a parsed specification against the schema of its mechanism and normalise it.

    Parameters
    ----------
    data : mapping
        The parsed TOML: ``mechanism``, ``[parameters]`` and ``[limits]``.
    name : str
        The mechanism's name, as the registry spells it.
    schema : MechanismSchema
        What the mechanism's specification must give.

    Returns
    -------
    dict
        ``{"mechanism": name, "parameters": {name: float}, "limits": {joint:
        (lo, hi) or "unlimited"}}``: parameters and joints in the order of the
        schema, bounds as floats in radians.

    Raises
    ------
    SpecError
        Naming the key at fault: ``parameters.<name>`` (missing, unknown, not a
        positive finite number), ``limits.<joint>`` (missing, unknown, not a
        pair ``[lo, hi]`` nor ``"unlimited"``, a bound that is not an angle,
        ``lo >= hi``, wider than 2 pi), or a top-level key that is not one of
        ``mechanism``, ``parameters``, ``limits``.

    Examples
    --------
    >>> schema = MechanismSchema(parameters=("L",), joints=("q",))
    >>> check_spec({"parameters": {"L": 2}, "limits": {"q": [0, "pi/2"]}}, "toy", schema)
    {'mechanism': 'toy', 'parameters': {'L': 2.0}, 'limits': {'q': (0.0, 1.5707963267948966)}}
    >>> check_spec({"parameters": {"L": -2}, "limits": {"q": "unlimited"}}, "toy", schema)
    Traceback (most recent call last):
        ...
    moveability.errors.SpecError: invalid parameters.L: expected a positive finite length, got -2
    """
    for key in data:
        if key not in _TOP_KEYS:
            raise SpecError(
                str(key), "one of the keys " + ", ".join(map(repr, _TOP_KEYS)), Plain(str(key))
            )
    out: dict[str, Any] = {
        "mechanism": name,
        "parameters": _parameters(data.get("parameters", NOTHING), name, schema),
        "limits": _limits(data.get("limits", NOTHING), name, schema),
    }
    out.update(_beyond_the_paper(data, name, schema))
    return out


def _beyond_the_paper(
    data: Mapping[str, Any], name: str, schema: MechanismSchema
) -> dict[str, Any]:
    """The optional tables ``[passive_limits]``, ``[[obstacles]]`` and
    ``[collisions]``, checked and normalised (absent ones are left out)."""
    out: dict[str, Any] = {}
    for key, check, allowed in (
        ("passive_limits", _passive_limits, bool(schema.passive)),
        ("obstacles", _obstacles, schema.shapes),
        ("collisions", _collisions, schema.shapes),
    ):
        if key in data:
            if not allowed:
                raise SpecError(key, f"no such table for a {name}", Plain("a table"))
            out[key] = check(data[key], schema)
    return out


def _passive_limits(table: object, schema: MechanismSchema) -> dict[str, tuple[float, float]]:
    if not isinstance(table, Mapping):
        raise SpecError("passive_limits", "a table of [lo, hi] per passive joint", table)
    limits = {}
    for joint, limit in table.items():
        key = f"passive_limits.{joint}"
        if joint not in schema.passive:
            raise SpecError(key, f"one of {', '.join(schema.passive)}", Plain(str(joint)))
        if isinstance(limit, str) or not isinstance(limit, Sequence) or len(limit) != 2:
            raise SpecError(key, "[lo, hi] in radians with lo < hi", limit)
        lo, hi = parse_angle(limit[0], f"{key}[0]"), parse_angle(limit[1], f"{key}[1]")
        if not lo < hi:
            raise SpecError(key, "[lo, hi] with lo < hi (an empty or reversed range)", limit)
        if hi - lo > _TWO_PI_MAX:
            raise SpecError(key, "a range no wider than 2*pi", limit)
        limits[str(joint)] = (lo, hi)
    return {j: limits[j] for j in schema.passive if j in limits}


def _obstacles(items: object, schema: MechanismSchema) -> list[dict[str, Any]]:
    if isinstance(items, Mapping | str) or not isinstance(items, Sequence):
        raise SpecError("obstacles", "an array of tables [[obstacles]]", items)
    obstacles = []
    for i, item in enumerate(items):
        key = f"obstacles[{i}]"
        if not isinstance(item, Mapping):
            raise SpecError(key, "a table with center and radius", item)
        for extra in item:
            if extra not in ("center", "radius"):
                raise SpecError(f"{key}.{extra}", "center or radius", Plain(str(extra)))
        center = item.get("center", NOTHING)
        if (
            isinstance(center, str)
            or not isinstance(center, Sequence)
            or len(center) != 2
            or not all(_is_number(v) and math.isfinite(float(v)) for v in center)
        ):
            raise SpecError(f"{key}.center", "[x, y], two finite numbers", center)
        radius = item.get("radius", NOTHING)
        if not (_is_number(radius) and math.isfinite(float(radius)) and float(radius) > 0):
            raise SpecError(f"{key}.radius", "a positive finite length", radius)
        obstacles.append({"center": [float(center[0]), float(center[1])], "radius": float(radius)})
    return obstacles


def _collisions(table: object, schema: MechanismSchema) -> dict[str, bool]:
    if not isinstance(table, Mapping):
        raise SpecError("collisions", "a table such as { links = true }", table)
    for extra in table:
        if extra != "links":
            raise SpecError(f"collisions.{extra}", "links", Plain(str(extra)))
    links = table.get("links", False)
    if not isinstance(links, bool):
        raise SpecError("collisions.links", "true or false", links)
    return {"links": links}


def read_toml(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The mapping a TOML file parses to; a missing, unreadable or malformed file is a
    :class:`~moveability.errors.SpecError` naming it (tomllib's line and column quoted)."""
    shown = os.fspath(path)
    try:
        with open(path, "rb") as stream:
            return tomllib.load(stream)
    except FileNotFoundError:
        raise SpecError("spec", "an existing TOML file", shown) from None
    except OSError as error:
        reason = error.strerror or type(error).__name__
        raise SpecError("spec", f"a readable TOML file ({reason})", shown) from None
    except UnicodeDecodeError as error:
        raise SpecError(f"spec {shown}", "UTF-8 text", Plain(str(error))) from None
    except tomllib.TOMLDecodeError as error:
        # tomllib's message ends with "(at line L, column C)"
        raise SpecError(f"spec {shown}", "valid TOML", Plain(str(error))) from None


def _table(value: object, key: str, allowed: str) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise SpecError(key, allowed, value)
    return value


def _parameters(value: object, mechanism: str, schema: MechanismSchema) -> dict[str, Any]:
    names = ", ".join(schema.parameters)
    table = _table(value, "parameters", f"a table giving {names}")
    defaults = schema.defaults or {}
    kinds = schema.kinds or {}
    for key in table:
        if key not in schema.parameters:
            raise SpecError(
                f"parameters.{key}",
                f"no such parameter ({mechanism} takes {names})",
                table[key],
            )
    out: dict[str, Any] = {}
    for key in schema.parameters:
        if key in table:
            given = table[key]
        elif key in defaults:
            given = defaults[key]
        else:
            given = NOTHING
        out[key] = _parameter(given, f"parameters.{key}", kinds.get(key, "length"), schema)
    return out


def _positive(value: object) -> bool:
    return _is_number(value) and math.isfinite(value) and value > 0  # type: ignore[operator, arg-type]


def _parameter(value: object, key: str, kind: str, schema: MechanismSchema) -> Any:
    """One parameter of the given kind, checked (see :class:`MechanismSchema`)."""
    n = len(schema.joints)
    if kind == "length":
        if not _positive(value):
            raise SpecError(key, "a positive finite length", value)
        return float(value)  # type: ignore[arg-type]
    if kind == "lengths":
        allowed = f"a list of {n} positive finite lengths"
        if not (isinstance(value, Sequence) and not isinstance(value, str) and len(value) == n):
            raise SpecError(key, allowed, value)
        if not all(_positive(v) for v in value):
            raise SpecError(key, allowed, value)
        return [float(v) for v in value]
    if kind == "points":
        allowed = f"a list of {n} points [x, y] with finite coordinates"
        if not (isinstance(value, Sequence) and not isinstance(value, str) and len(value) == n):
            raise SpecError(key, allowed, value)
        points = []
        for i, point in enumerate(value):
            ok = isinstance(point, Sequence) and not isinstance(point, str) and len(point) == 2
            if not ok or not all(_is_number(c) and math.isfinite(c) for c in point):
                raise SpecError(f"{key}[{i}]", "a point [x, y] with finite coordinates", point)
            points.append([float(point[0]), float(point[1])])
        return points
    raise ValueError(f"unknown parameter kind {kind!r}")


def _limit_table(
    value: object, mechanism: str, schema: MechanismSchema, allowed: str
) -> Mapping[str, Any]:
    """The ``[limits]`` table, with no joint the mechanism does not have."""
    joints = ", ".join(schema.joints)
    table = _table(value, "limits", f"a table giving {joints}, each {allowed}")
    for key in table:
        if key not in schema.joints:
            raise SpecError(
                f"limits.{key}", f"no such joint ({mechanism} has {joints})", table[key]
            )
    return table


def _limits(
    value: object, mechanism: str, schema: MechanismSchema
) -> dict[str, tuple[float, float] | str]:
    if schema.joint_kind != "angle":
        return _strokes(value, mechanism, schema)
    allowed = f'[lo, hi] in radians with lo < hi, or "{UNLIMITED}"'
    table = _limit_table(value, mechanism, schema, allowed)
    out: dict[str, tuple[float, float] | str] = {}
    for joint in schema.joints:
        key = f"limits.{joint}"
        limit = table.get(joint, NOTHING)
        if limit is NOTHING:
            raise SpecError(key, allowed, NOTHING)
        if isinstance(limit, str):
            if limit.strip().lower() != UNLIMITED:
                raise SpecError(key, allowed, limit)
            out[joint] = UNLIMITED
            continue
        if not isinstance(limit, Sequence) or len(limit) != 2:
            raise SpecError(key, allowed, limit)
        lo = parse_angle(limit[0], f"{key}[0]")
        hi = parse_angle(limit[1], f"{key}[1]")
        if not lo < hi:
            raise SpecError(key, "[lo, hi] with lo < hi (an empty or reversed range)", limit)
        if hi - lo > _TWO_PI_MAX:
            raise SpecError(
                key, f'a range no wider than 2*pi (use "{UNLIMITED}" for a free joint)', limit
            )
        out[joint] = (lo, hi)
    return out


def _strokes(
    value: object, mechanism: str, schema: MechanismSchema
) -> dict[str, tuple[float, float] | str]:
    """Limits of prismatic joints: finite strokes ``[lo, hi]`` (never unlimited)."""
    distance = schema.joint_kind == "distance"
    allowed = "[lo, hi] with " + ("0 <= lo < hi" if distance else "lo < hi") + ", finite"
    table = _limit_table(value, mechanism, schema, allowed)
    out: dict[str, tuple[float, float] | str] = {}
    for joint in schema.joints:
        key = f"limits.{joint}"
        limit = table.get(joint, NOTHING)
        if not isinstance(limit, Sequence) or isinstance(limit, str) or len(limit) != 2:
            raise SpecError(key, allowed, limit)
        if not all(_is_number(v) and math.isfinite(v) for v in limit):
            raise SpecError(key, allowed, limit)
        lo, hi = float(limit[0]), float(limit[1])
        if not lo < hi:
            raise SpecError(key, "[lo, hi] with lo < hi (an empty or reversed range)", limit)
        if distance and lo < 0:
            raise SpecError(key, "a stroke of lengths, 0 <= lo", limit)
        out[joint] = (lo, hi)
    return out
