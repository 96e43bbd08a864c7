"""Functions that evaluate on float arrays and on :class:`~moveability.intervals.Interval`.

A constraint written once with these functions serves both: at points (numpy
arrays, NaN where undefined) and over boxes (outward-rounded enclosures).
Over intervals, every function is *guarded*: where the argument may leave
the function's domain or cross a discontinuity (``sqrt`` or ``log`` of a
possibly negative number, ``tan`` at a pole, ``atan2`` across its cut along
the negative x axis, a division by an interval holding 0) the enclosure is
the whole real line. A finite enclosure of an expression over a box is thus a
certificate that the expression is defined and continuous on the box, which
the root isolation of :class:`~moveability.mechanisms.constraint_leg.ConstraintLeg`
relies on.

Examples
--------
>>> import numpy as np
>>> from moveability.intervals import Interval
>>> from moveability.mechanisms import expressions as ex
>>> float(ex.sqrt(np.float64(4.0)))
2.0
>>> r = ex.sqrt(Interval([-1.0], [4.0]))
>>> float(r.lo[0]), float(r.hi[0])
(-inf, inf)
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any

import numpy as np

from .. import intervals as iv
from ..compiled import kernel
from ..intervals import Interval, point_sin_cos
from ..types import Array

__all__ = [
    "FUNCTIONS",
    "absolute",
    "atan2",
    "atan2_turn",
    "cos",
    "exp",
    "is_interval",
    "log",
    "points",
    "power",
    "remembered",
    "sin",
    "sqrt",
    "take",
    "tan",
    "tiled",
]

_INF = np.inf


def is_interval(*values: Any) -> bool:
    """Whether any of the values is an :class:`Interval` (the others are then lifted)."""
    return any(isinstance(v, Interval) for v in values)


def _whole(x: Interval, where: Any) -> Interval:
    """``x``, replaced by the whole real line where ``where``."""
    return Interval(np.where(where, -_INF, x.lo), np.where(where, _INF, x.hi))


_SHARED = "_shared"


def _once(name: str, x: Interval, f: Any) -> Interval:
    """``f(x)`` computed once per interval object: a leg's constraint and its
    derivatives are evaluated on one enclosure of the joint and call ``sin(q)``,
    ``cos(q)`` each; the enclosure remembers them (intervals are not changed once
    evaluated, and the memory goes with the object)."""
    memo: dict[str, Interval] = x.__dict__.setdefault(_SHARED, {})
    if name not in memo:
        tile = x.__dict__.get(_TILE)
        if name in ("sin", "cos") and x.__dict__.get(_POINTS):
            # points: both at once, one sine and one cosine per point
            flat = np.ascontiguousarray(x.lo, dtype=np.float64).reshape(-1)
            s_lo, s_hi, c_lo, c_hi = _point_trig(flat)
            shape = x.lo.shape
            memo["sin"] = Interval(s_lo.reshape(shape), s_hi.reshape(shape))
            memo["cos"] = Interval(c_lo.reshape(shape), c_hi.reshape(shape))
        elif tile is not None:
            # x repeats one base interval array: f of the base, repeated (f works
            # element by element, so these are the bounds f(x) gives)
            v = _once(name, tile[0], f)
            memo[name] = Interval(np.tile(v.lo, tile[1]), np.tile(v.hi, tile[1]))
        else:
            memo[name] = f(x)
    return memo[name]


_TILE = "_tile"
_POINTS = "_points"


def points(values: Any) -> Interval:
    """The degenerate intervals ``[v, v]`` of floats ``values``, whose :func:`sin` and
    :func:`cos` are computed together, one sine and one cosine per point (the
    bounds :func:`moveability.intervals.sin` and ``cos`` give).

    Examples
    --------
    >>> p = points(np.array([0.5, 3.0]))
    >>> q = Interval(np.array([0.5, 3.0]))
    >>> all((a.lo == b.lo).all() and (a.hi == b.hi).all()
    ...     for a, b in ((sin(p), iv.sin(q)), (cos(p), iv.cos(q))))
    True
    """
    out = Interval(values)
    out.__dict__[_POINTS] = True
    return out


@kernel
def _point_trig(x: Array) -> tuple[Array, Array, Array, Array]:  # pragma: no cover - compiled
    """:func:`~moveability.intervals.point_sin_cos` of each element of ``x``."""
    n = x.size
    s_lo = np.empty(n)
    s_hi = np.empty(n)
    c_lo = np.empty(n)
    c_hi = np.empty(n)
    for i in range(n):
        s_lo[i], s_hi[i], c_lo[i], c_hi[i] = point_sin_cos(x[i])
    return s_lo, s_hi, c_lo, c_hi


def tiled(base: Interval, n: int) -> Interval:
    """``base`` repeated ``n`` times (1-d), whose :func:`sin`, :func:`cos`, ... are
    computed on ``base`` once and repeated.

    Examples
    --------
    >>> q = tiled(Interval([0.0, 1.0], [0.5, 1.5]), 3)
    >>> q.lo.tolist()
    [0.0, 1.0, 0.0, 1.0, 0.0, 1.0]
    >>> s = sin(q)
    >>> bool((s.lo == iv.sin(q).lo).all() and (s.hi == iv.sin(q).hi).all())
    True
    """
    out = Interval(np.tile(base.lo, n), np.tile(base.hi, n))
    out.__dict__[_TILE] = (base, n)
    return out


def take(x: Interval, index: Any) -> Interval:
    """``x[index]``, with the values remembered for ``x`` (see :func:`sin`) taken too.

    Examples
    --------
    >>> q = Interval([0.0, 1.0], [0.5, 1.5])
    >>> s = sin(q)
    >>> sin(take(q, [1])).lo.tolist() == s.lo[[1]].tolist()
    True
    """
    out = x[index]
    memo = x.__dict__.get(_SHARED)
    if memo:
        out.__dict__[_SHARED] = {name: value[index] for name, value in memo.items()}
    return out


#: float arrays' sines and cosines remembered within :func:`remembered`
_FLOATS: ContextVar[dict[tuple[str, int], tuple[Any, Array]] | None] = ContextVar(
    "_FLOATS", default=None
)


@contextmanager
def remembered() -> Iterator[None]:
    """Within the block, :func:`sin` and :func:`cos` of one float array object are
    computed once (each call gets a copy: the same values as ``np.sin``). The
    arrays must not change inside the block.

    Examples
    --------
    >>> x = np.array([0.5, 3.0])
    >>> with remembered():
    ...     a, b = sin(x), sin(x)
    >>> bool((a == np.sin(x)).all() and (b == a).all() and a is not b)
    True
    """
    token = _FLOATS.set({} if _FLOATS.get() is None else _FLOATS.get())
    try:
        yield
    finally:
        _FLOATS.reset(token)


def _float(name: str, f: Callable[[Any], Any], x: Any) -> Any:
    memo = _FLOATS.get()
    if memo is None or type(x) is not np.ndarray:
        return f(x)
    key = (name, id(x))
    hit = memo.get(key)
    if hit is None or hit[0] is not x:
        hit = (x, f(x))
        memo[key] = hit  # (x kept alive: its id is not reused meanwhile)
    return hit[1].copy()


def sin(x: Any) -> Any:
    """Sine (over an interval, computed once per interval object)."""
    return _once("sin", x, iv.sin) if isinstance(x, Interval) else _float("sin", np.sin, x)


def cos(x: Any) -> Any:
    """Cosine (over an interval, computed once per interval object)."""
    return _once("cos", x, iv.cos) if isinstance(x, Interval) else _float("cos", np.cos, x)


def tan(x: Any) -> Any:
    """Tangent (the whole line over an interval that may hold a pole)."""
    return _once("tan", x, iv.tan) if isinstance(x, Interval) else np.tan(x)


def exp(x: Any) -> Any:
    """Exponential."""
    return _once("exp", x, iv.exp) if isinstance(x, Interval) else np.exp(x)


def log(x: Any) -> Any:
    """Natural logarithm (the whole line over an interval reaching 0 or below)."""
    if isinstance(x, Interval):
        return _whole(iv.log(x), ~(x.lo > 0))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(np.asarray(x) > 0, np.log(np.maximum(x, 0.0)), np.nan)


def sqrt(x: Any) -> Any:
    """Square root (the whole line over an interval reaching below 0)."""
    if isinstance(x, Interval):
        return _whole(iv.sqrt(x), ~(x.lo >= 0))
    with np.errstate(invalid="ignore"):
        return np.where(np.asarray(x) >= 0, np.sqrt(np.maximum(x, 0.0)), np.nan)


def absolute(x: Any) -> Any:
    """Absolute value."""
    return iv.absolute(x) if isinstance(x, Interval) else np.abs(x)


def power(x: Any, n: int) -> Any:
    """``x ** n`` for an integer ``n`` (the whole line over ``1 / [.., 0, ..]``)."""
    if isinstance(x, Interval):
        if n < 0:
            return _whole(iv.power(x, n), ~((x.lo > 0) | (x.hi < 0)))
        return iv.power(x, n)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return np.power(np.asarray(x, dtype=np.float64), n)


def atan2(y: Any, x: Any) -> Any:
    """``atan2(y, x)`` in ``[-pi, pi]`` (the whole line over boxes meeting its cut)."""
    if is_interval(y, x):
        yi, xi = iv.as_interval(y), iv.as_interval(x)
        cut = (xi.lo <= 0) & (yi.lo <= 0) & (yi.hi >= 0)
        return _whole(iv.arctan2(yi, xi), cut)
    return np.arctan2(y, x)


_PI = Interval(np.float64(np.pi), np.nextafter(np.pi, np.inf))


def atan2_turn(y: Any, x: Any) -> Any:
    """``atan2(y, x)`` up to whole turns, for a value read modulo 2 pi only.

    Over intervals: an unwrapped enclosure, the narrower of ``atan2`` with its
    cut on the negative x axis and ``atan2(-y, -x) + pi`` with its cut on the
    positive one (as :func:`~moveability.mechanisms.constraints.vector_angle`),
    so that a box crossing either cut keeps a narrow enclosure. Every value
    of the box is enclosed up to a multiple of 2 pi; the whole turn
    ``[-pi, pi]`` where the box may hold the origin.

    Examples
    --------
    >>> a = atan2_turn(Interval([-0.1], [0.1]), Interval([-2.0], [-1.0]))
    >>> bool(a.lo[0] < np.pi < a.hi[0] and a.hi[0] - a.lo[0] < 0.3)
    True
    """
    if is_interval(y, x):
        yi, xi = iv.as_interval(y), iv.as_interval(x)
        plain = iv.arctan2(yi, xi)
        turned = iv.arctan2(-yi, -xi) + _PI
        narrow = (turned.hi - turned.lo) < (plain.hi - plain.lo)
        return Interval(
            np.where(narrow, turned.lo, plain.lo), np.where(narrow, turned.hi, plain.hi)
        )
    return np.arctan2(y, x)


#: the functions an expression may call, by the name it calls them
FUNCTIONS: dict[str, Callable[..., Any]] = {
    "sin": sin,
    "cos": cos,
    "tan": tan,
    "exp": exp,
    "log": log,
    "sqrt": sqrt,
    "abs": absolute,
    "atan2": atan2,
}
