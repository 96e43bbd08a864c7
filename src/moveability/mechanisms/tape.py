"""Compiled enclosures of user-defined expressions: a traced tape run by one kernel.

A constraint of a user-defined leg (:mod:`moveability.mechanisms.custom`) is
printed as Python calling the guarded functions of
:mod:`moveability.mechanisms.expressions`; evaluated on
:class:`~moveability.intervals.Interval` operands, each ``+ - *`` and power
allocates arrays and goes through Python. Here the same function is run once
on *tracers*: every interval operation it would perform on the inputs is
recorded, in order, on a tape (sums, differences, products, negations and
squares), the numbers and constant intervals it meets are kept as constants,
and a function of the inputs alone (``sin(t)``, ``cos(t)``, ...) becomes a
*derived input*, computed outside the tape by the very function the
interpreted path calls (so the remembered sines of a joint enclosure are
shared as before). :func:`run` then evaluates the tape over many boxes in one
compiled loop, element by element, with the compiled forms of the interval
operations (:func:`~moveability.intervals.interval_add`,
:func:`~moveability.intervals.interval_mul`, ...): bit for bit the bounds of
the interpreted path (``tests/mechanisms/test_tape.py``), without its
temporaries. An expression using anything else on a non-input value (``sqrt``
of a sum, a division, a power above 2) gives no tape and stays interpreted.

Examples
--------
>>> import numpy as np
>>> from moveability.intervals import Interval
>>> from moveability.mechanisms import expressions as ex
>>> cos = traced(ex.cos, "cos")
>>> t = trace(lambda x, q: (x - 2.0 * cos(q)) ** 2 + 1.5 * x, 1)
>>> lo, hi = np.array([[0.0], [1.0]]), np.array([[0.5], [2.0]])
>>> q = Interval(np.array([0.0, 1.0]), np.array([0.1, 1.2]))
>>> r = run(t, lo, hi, np.array([0, 1]), q)
>>> x = Interval(lo[:, 0], hi[:, 0])
>>> plain = (x - 2.0 * ex.cos(q)) ** 2 + 1.5 * x
>>> bool(np.array_equal(r.lo, plain.lo) and np.array_equal(r.hi, plain.hi))
True
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..compiled import kernel
from ..intervals import Interval, interval_add, interval_mul, interval_sub, point_sin_cos
from ..types import Array

__all__ = ["Tape", "Untraceable", "constant", "run", "trace", "trace_all", "traced"]

# opcodes: (op, target slot, operand a, operand b)
_ADD, _SUB, _MUL, _NEG, _SQUARE = 0, 1, 2, 3, 4


class Untraceable(Exception):
    """The expression does something the tape does not record."""


@dataclass(frozen=True, eq=False)
class Tape:
    """A traced expression: slots ``[0, k)`` the pose coordinates, ``k`` the joint,
    then the derived inputs, the constants and the temporaries.

    ``derived`` lists, per derived input, the function and the slots of its
    arguments (inputs only) it is computed from, outside the kernel."""

    k: int
    derived: tuple[tuple[Callable[..., Any], tuple[int, ...]], ...]
    const_lo: Array
    const_hi: Array
    code: NDArray[np.int64]
    slots: int
    out: int


class _Recorder:
    def __init__(self, k: int) -> None:
        self.k = k
        self.derived: list[tuple[Callable[..., Any], tuple[int, ...]]] = []
        self.derived_keys: dict[tuple[Any, tuple[int, ...]], _Node] = {}
        self.consts: list[tuple[float, float]] = []
        self.ops: list[tuple[int, int, int, int]] = []
        self.temps = 0

    def const(self, lo: float, hi: float) -> int:
        self.consts.append((lo, hi))
        return -len(self.consts)  # placed after the derived inputs once known

    def op(self, code: int, a: int, b: int) -> _Node:
        self.temps += 1
        target = -(10**9) - self.temps  # a temporary, numbered once the layout is known
        self.ops.append((code, target, a, b))
        return _Node(self, target, leaf=False)


class _Node:
    """A value depending on the inputs, during a trace."""

    __array_ufunc__ = None
    __slots__ = ("leaf", "rec", "slot")

    def __init__(self, rec: _Recorder, slot: int, leaf: bool) -> None:
        self.rec, self.slot, self.leaf = rec, slot, leaf

    def _operand(self, other: Any) -> int:
        if isinstance(other, _Node):
            if other.rec is not self.rec:
                raise Untraceable("two traces")
            return other.slot
        lo, hi = _constant(other)
        return self.rec.const(lo, hi)

    def __add__(self, other: Any) -> _Node:
        return self.rec.op(_ADD, self.slot, self._operand(other))

    def __radd__(self, other: Any) -> _Node:
        return self.rec.op(_ADD, self._operand(other), self.slot)

    def __sub__(self, other: Any) -> _Node:
        return self.rec.op(_SUB, self.slot, self._operand(other))

    def __rsub__(self, other: Any) -> _Node:
        return self.rec.op(_SUB, self._operand(other), self.slot)

    def __mul__(self, other: Any) -> _Node:
        return self.rec.op(_MUL, self.slot, self._operand(other))

    def __rmul__(self, other: Any) -> _Node:
        return self.rec.op(_MUL, self._operand(other), self.slot)

    def __neg__(self) -> _Node:
        return self.rec.op(_NEG, self.slot, self.slot)

    def __pow__(self, n: Any) -> _Node:
        return _power(self, n)

    def __truediv__(self, other: Any) -> _Node:
        raise Untraceable("division")

    __rtruediv__ = __truediv__


class _Const:
    """A constant during a trace (an Interval or a number): operations among
    constants are done for real, with the objects the interpreted path has."""

    __array_ufunc__ = None
    __slots__ = ("value",)

    def __init__(self, value: Any) -> None:
        self.value = value

    def _binary(self, other: Any, f: Callable[[Any, Any], Any]) -> Any:
        if isinstance(other, _Node):
            return NotImplemented
        return _Const(f(self.value, other.value if isinstance(other, _Const) else other))

    def __add__(self, o: Any) -> Any:
        return self._binary(o, lambda a, b: a + b)

    def __radd__(self, o: Any) -> Any:
        return self._binary(o, lambda a, b: b + a)

    def __sub__(self, o: Any) -> Any:
        return self._binary(o, lambda a, b: a - b)

    def __rsub__(self, o: Any) -> Any:
        return self._binary(o, lambda a, b: b - a)

    def __mul__(self, o: Any) -> Any:
        return self._binary(o, lambda a, b: a * b)

    def __rmul__(self, o: Any) -> Any:
        return self._binary(o, lambda a, b: b * a)

    def __truediv__(self, o: Any) -> Any:
        return self._binary(o, lambda a, b: a / b)

    def __rtruediv__(self, o: Any) -> Any:
        return self._binary(o, lambda a, b: b / a)

    def __pow__(self, o: Any) -> Any:
        return self._binary(o, lambda a, b: a**b)

    def __neg__(self) -> Any:
        return _Const(-self.value)


def constant(function: Callable[..., Any]) -> Callable[..., Any]:
    """``function`` (giving a constant Interval, as ``rational``) for a trace."""
    return lambda *args: _Const(function(*args))


def _constant(value: Any) -> tuple[float, float]:
    """The bounds the interpreted path gives a constant operand (``as_interval``)."""
    if isinstance(value, _Const):
        value = value.value
    if isinstance(value, Interval):
        if value.lo.size != 1:
            raise Untraceable("an array constant")
        return float(value.lo.reshape(-1)[0]), float(value.hi.reshape(-1)[0])
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise Untraceable(f"a constant {value!r}")
    v = float(np.asarray(value, dtype=np.float64))
    return v, v


def _power(x: _Node, n: Any) -> _Node:
    if isinstance(n, bool) or not isinstance(n, int | np.integer):
        raise Untraceable("a power that is not an integer")
    if n == 1:
        return x
    if n == 2:
        return x.rec.op(_SQUARE, x.slot, x.slot)
    raise Untraceable(f"power {n}")


def traced(function: Callable[..., Any], name: str) -> Callable[..., Any]:
    """``function`` (one of :mod:`~moveability.mechanisms.expressions`) for a trace:
    on numbers and constants, itself; on inputs only, a derived input; ``power``
    of a value by 1 or 2, a tape operation; anything else is :class:`Untraceable`."""

    def call(*args: Any) -> Any:
        nodes = [a for a in args if isinstance(a, _Node)]
        if not nodes:
            plain = [a.value if isinstance(a, _Const) else a for a in args]
            value = function(*plain)
            return _Const(value) if isinstance(value, Interval) else value
        if name == "power" and len(args) == 2 and isinstance(args[0], _Node):
            return _power(args[0], args[1])
        if any(not n.leaf for n in nodes):
            raise Untraceable(f"{name} of a computed value")
        if any(not isinstance(a, _Node) for a in args):
            raise Untraceable(f"{name} of an input and a constant")
        rec = nodes[0].rec
        key = (function, tuple(n.slot for n in nodes))
        if key not in rec.derived_keys:
            rec.derived.append(key)
            rec.derived_keys[key] = _Node(rec, -(2 * 10**9) - len(rec.derived), leaf=False)
        return rec.derived_keys[key]

    return call


def trace(function: Callable[..., Any], k: int) -> Tape:
    """The tape of ``function(x_1, ..., x_k, q)`` as evaluated on Intervals.

    ``function`` must call the functions of its namespace through :func:`traced`
    (see :func:`moveability.mechanisms.custom.compile_expression`) and use only
    ``+ - *``, negation and powers on its inputs; numbers among its operands are
    constants. Raises :class:`Untraceable` otherwise.
    """
    rec = _Recorder(k)
    inputs = [_Node(rec, i, leaf=True) for i in range(k + 1)]
    result = function(*inputs)
    if not isinstance(result, _Node):
        lo, hi = _constant(result)
        result = _Node(rec, rec.const(lo, hi), leaf=False)
    # the layout: inputs, derived, constants, temporaries
    n_derived = len(rec.derived)
    first_const = k + 1 + n_derived
    first_temp = first_const + len(rec.consts)

    def slot(s: int) -> int:
        if s >= 0:
            return s
        if s <= -(2 * 10**9):
            return k + 1 + (-(2 * 10**9) - s) - 1
        if s <= -(10**9):
            return first_temp + (-(10**9) - s) - 1
        return first_const + (-s) - 1

    code = np.array(
        [(op, slot(t), slot(a), slot(b)) for op, t, a, b in rec.ops], dtype=np.int64
    ).reshape(-1, 4)
    consts = np.array(rec.consts, dtype=np.float64).reshape(-1, 2)
    return Tape(
        k=k,
        derived=tuple((f, tuple(slot(a) for a in args)) for f, args in rec.derived),
        const_lo=np.ascontiguousarray(consts[:, 0]),
        const_hi=np.ascontiguousarray(consts[:, 1]),
        code=code,
        slots=first_temp + rec.temps,
        out=slot(result.slot),
    )


@kernel
def _max0(x: float) -> float:  # pragma: no cover - compiled
    """``np.maximum(x, 0.0)``: NaN kept, and ``x`` when equal."""
    return x if (x >= 0.0 or x != x) else 0.0


#: elements per block of :func:`_run` (its registers stay in cache)
PIECE_BLOCK = 256
#: bracket steps in a row that did not halve it before a bisection (the contraction)
SLOW_STEPS = 3


@kernel
def run_ops(code: NDArray[np.int64], r_lo: Array, r_hi: Array, n: int) -> None:  # pragma: no cover
    """The tape's operations over the first ``n`` columns of the registers."""
    for p in range(code.shape[0]):
        op = code[p, 0]
        t_lo = r_lo[code[p, 1]]
        t_hi = r_hi[code[p, 1]]
        a_lo = r_lo[code[p, 2]]
        a_hi = r_hi[code[p, 2]]
        b_lo = r_lo[code[p, 3]]
        b_hi = r_hi[code[p, 3]]
        if op == 0:
            for e in range(n):
                t_lo[e], t_hi[e] = interval_add(a_lo[e], a_hi[e], b_lo[e], b_hi[e])
        elif op == 1:
            for e in range(n):
                t_lo[e], t_hi[e] = interval_sub(a_lo[e], a_hi[e], b_lo[e], b_hi[e])
        elif op == 2:
            for e in range(n):
                t_lo[e], t_hi[e] = interval_mul(a_lo[e], a_hi[e], b_lo[e], b_hi[e])
        elif op == 3:
            for e in range(n):
                x_lo = a_lo[e]
                t_lo[e] = -a_hi[e]
                t_hi[e] = -x_lo
        else:
            for e in range(n):
                x_lo = a_lo[e]
                x_hi = a_hi[e]
                s_lo, s_hi = interval_mul(x_lo, x_hi, x_lo, x_hi)
                t_lo[e] = 0.0 if (x_lo <= 0.0 and x_hi >= 0.0) else _max0(s_lo)
                t_hi[e] = s_hi


@kernel
def _run(
    code: NDArray[np.int64],
    const_lo: Array,
    const_hi: Array,
    k: int,
    lo: Array,
    hi: Array,
    box: NDArray[np.int64],
    q_lo: Array,
    q_hi: Array,
    extra_lo: Array,
    extra_hi: Array,
    slots: int,
    out: int,
    out_lo: Array,
    out_hi: Array,
) -> None:  # pragma: no cover - compiled
    """The tape over each element ``i``: pose box ``box[i]`` and joint ``q[i]``;
    a block of elements at a time, one operation over the whole block."""
    block = PIECE_BLOCK
    r_lo = np.empty((slots, block))
    r_hi = np.empty((slots, block))
    n_extra = extra_lo.shape[0]
    first_const = k + 1 + n_extra
    for c in range(const_lo.size):
        for e in range(block):
            r_lo[first_const + c, e] = const_lo[c]
            r_hi[first_const + c, e] = const_hi[c]
    m = q_lo.size
    for start in range(0, m, block):
        n = min(block, m - start)
        for e in range(n):
            b = box[start + e]
            for j in range(k):
                r_lo[j, e] = lo[b, j]
                r_hi[j, e] = hi[b, j]
            r_lo[k, e] = q_lo[start + e]
            r_hi[k, e] = q_hi[start + e]
        for x in range(n_extra):
            for e in range(n):
                r_lo[k + 1 + x, e] = extra_lo[x, start + e]
                r_hi[k + 1 + x, e] = extra_hi[x, start + e]
        run_ops(code, r_lo, r_hi, n)
        for e in range(n):
            out_lo[start + e] = r_lo[out, e]
            out_hi[start + e] = r_hi[out, e]


def _flat(x: Any, m: int) -> Array:
    a = np.asarray(x, dtype=np.float64)
    if a.shape == (m,) and a.flags.c_contiguous:
        return a
    return np.ascontiguousarray(np.broadcast_to(a, (m,)))


def run(tape: Tape, lo: Array, hi: Array, box: Any, q: Interval) -> Interval:
    """The tape's enclosure over the boxes ``[lo[box[i]], hi[box[i]]]`` (rows of
    ``(n, k)`` arrays) and the joint enclosures ``q`` (shape ``(m,)``)."""
    m = int(np.size(box))
    box_i = np.asarray(box, dtype=np.int64)
    if box_i.shape != (m,) or not box_i.flags.c_contiguous:
        box_i = np.ascontiguousarray(np.broadcast_to(box_i, (m,)))
    lo_c = np.ascontiguousarray(lo, dtype=np.float64)
    hi_c = np.ascontiguousarray(hi, dtype=np.float64)
    extra_lo = np.empty((len(tape.derived), m))
    extra_hi = np.empty((len(tape.derived), m))
    coords: list[Interval] | None = None
    # derived inputs of pose coordinates alone: over the boxes ``box`` refers to,
    # each once (the functions work element by element: the same bounds), then
    # taken per element
    distinct: tuple[dict[int, Interval], NDArray[np.int64]] | None = None
    memo = _ROWS.get()
    for e, (function, args) in enumerate(tape.derived):
        if memo is not None and args and all(a < tape.k for a in args):
            # within remembered_boxes: over every box of these arrays, once
            v_lo, v_hi = _rows_values(memo, function, args, lo, hi, lo_c, hi_c)
            extra_lo[e] = v_lo[box_i]
            extra_hi[e] = v_hi[box_i]
            continue
        if args and all(a < tape.k for a in args):
            if distinct is None:
                axes = {a for _, a_s in tape.derived if all(x < tape.k for x in a_s) for a in a_s}
                distinct = _distinct_boxes(lo_c, hi_c, box_i, sorted(axes))
            with np.errstate(all="ignore"):
                v = function(*(distinct[0][a] for a in args))
            if not isinstance(v, Interval):
                v = Interval(v)
            rows = distinct[0][args[0]].lo.shape[0]
            extra_lo[e] = np.broadcast_to(v.lo, (rows,))[distinct[1]]
            extra_hi[e] = np.broadcast_to(v.hi, (rows,))[distinct[1]]
            continue
        values: list[Interval] = []
        for a in args:
            if a == tape.k:
                values.append(q)
            else:
                if coords is None:
                    coords = [Interval(lo_c[box_i, j], hi_c[box_i, j]) for j in range(tape.k)]
                values.append(coords[a])
        with np.errstate(all="ignore"):
            v = function(*values)
        if not isinstance(v, Interval):
            v = Interval(v)
        extra_lo[e] = v.lo  # a copy (broadcast where v is one interval)
        extra_hi[e] = v.hi
    out_lo = np.empty(m)
    out_hi = np.empty(m)
    _run(
        tape.code,
        tape.const_lo,
        tape.const_hi,
        tape.k,
        lo_c,
        hi_c,
        box_i,
        _flat(q.lo, m),
        _flat(q.hi, m),
        extra_lo,
        extra_hi,
        tape.slots,
        tape.out,
        out_lo,
        out_hi,
    )
    return Interval(out_lo, out_hi)


#: derived inputs of the pose over every row of (lo, hi) array objects, within
#: :func:`remembered_boxes`: (function, args, lo, hi) -> (lo, hi, values' bounds)
_ROWS: ContextVar[dict[Any, tuple[Any, ...]] | None] = ContextVar("_ROWS", default=None)


@contextmanager
def remembered_boxes() -> Iterator[None]:
    """Within the block, the derived inputs of pose coordinates alone that
    :func:`run` meets are computed once per function and pair of box arrays
    ``lo, hi`` (the same objects; they must not change inside the block), over
    all their rows (the same bounds: the functions work element by element)."""
    token = _ROWS.set({} if _ROWS.get() is None else _ROWS.get())
    try:
        yield
    finally:
        _ROWS.reset(token)


def _rows_values(
    memo: dict[Any, tuple[Any, ...]],
    function: Callable[..., Any],
    args: tuple[int, ...],
    lo: Any,
    hi: Any,
    lo_c: Array,
    hi_c: Array,
) -> tuple[Array, Array]:
    """``function`` of the coordinates ``args`` over every row of ``[lo, hi]``,
    remembered; the coordinates are shared by the functions of one pair ``lo, hi``
    (points when ``lo is hi``: their sine and cosine computed together)."""
    key = (id(function), args, id(lo), id(hi))
    hit = memo.get(key)
    if hit is None or hit[0] is not function or hit[1] is not lo or hit[2] is not hi:
        c_key = ("coords", id(lo), id(hi))
        found = memo.get(c_key)
        if found is None or found[0] is not lo or found[1] is not hi:
            found = (lo, hi, _Coords(lo_c, hi_c, lo is hi))
            memo[c_key] = found
        v_lo, v_hi = _values([(function, args)], found[2])
        hit = (function, lo, hi, v_lo[0], v_hi[0])  # (the objects kept: ids not reused)
        memo[key] = hit
    return hit[3], hit[4]


class _Coords:
    """The pose coordinates of the rows of ``[lo, hi]`` as Intervals, each built
    once; :func:`~moveability.mechanisms.expressions.points` where ``points``
    (``lo`` and ``hi`` the same values), whose sines and cosines are those of
    the degenerate intervals, computed together."""

    def __init__(self, lo: Array, hi: Array, points: bool) -> None:
        self.lo, self.hi, self.points = lo, hi, points
        self.done: dict[int, Interval] = {}

    def __getitem__(self, a: int) -> Interval:
        if a not in self.done:
            from . import expressions as ex

            x = self.lo[:, a]
            self.done[a] = ex.points(x) if self.points else Interval(x, self.hi[:, a])
        value: Interval = self.done[a]
        return value


def _values(
    functions: Sequence[tuple[Callable[..., Any], tuple[int, ...]]], coords: _Coords
) -> tuple[Array, Array]:
    """``functions`` of the coordinates ``coords``: arrays of shape ``(d, n)``."""
    n = coords.lo.shape[0]
    out_lo = np.empty((len(functions), n))
    out_hi = np.empty((len(functions), n))
    for e, (function, args) in enumerate(functions):
        with np.errstate(all="ignore"):
            v = function(*(coords[a] for a in args))
        if not isinstance(v, Interval):
            v = Interval(v)
        out_lo[e] = v.lo  # a copy (broadcast where v is one interval)
        out_hi[e] = v.hi
    return out_lo, out_hi


def _distinct_boxes(
    lo: Array, hi: Array, box: NDArray[np.int64], axes: Sequence[int]
) -> tuple[dict[int, Interval], NDArray[np.int64]]:
    """The pose coordinates ``axes`` (as intervals) of the rows ``box`` refers to,
    in row order, and the position of each element's row among them."""
    n = lo.shape[0]
    mark = np.zeros(n, dtype=bool)
    mark[box] = True
    rows = np.flatnonzero(mark)
    if rows.size == n:
        where = box
    else:
        at = np.empty(n, dtype=np.int64)
        at[rows] = np.arange(rows.size)
        where = at[box]
    return {j: Interval(lo[rows, j], hi[rows, j]) for j in axes}, where


def trace_all(functions: Sequence[Callable[..., Any]], k: int) -> list[Tape | None]:
    """:func:`trace` of each function, None where it is :class:`Untraceable`."""
    out: list[Tape | None] = []
    for f in functions:
        try:
            out.append(trace(f, k))
        except Untraceable:
            out.append(None)
    return out


# --------------------------------------------------------------- contraction
_SIN, _COS, _POSE = 0, 1, 2


def trig_kinds(tape: Tape) -> NDArray[np.int64] | None:
    """Per derived input, 0 for ``sin(q)`` and 1 for ``cos(q)`` of the joint (the
    functions of :mod:`~moveability.mechanisms.expressions`), 2 for a function of
    pose coordinates alone (computed once per box by :func:`contract`); None if
    the tape has any other derived input (:func:`contract` then does not apply)."""
    from . import expressions as ex

    kinds = []
    for function, args in tape.derived:
        if args and all(0 <= a < tape.k for a in args):
            kinds.append(_POSE)
        elif args != (tape.k,):
            return None
        elif function is ex.sin:
            kinds.append(_SIN)
        elif function is ex.cos:
            kinds.append(_COS)
        else:
            return None
    return np.array(kinds, dtype=np.int64)


@kernel(inline=True)
def _falsi_point(
    c: float, o: float, fc: float, fo: float, slow: int, tol: float
) -> float:  # pragma: no cover - compiled
    """``constraint_leg.falsi_points`` of one bracket: the same floats."""
    ratio = fc / (fc - fo) if fc != fo else 0.0
    guess = c + (o - c) * ratio
    low = min(c, o) + tol
    high = max(c, o) - tol
    if np.isfinite(fc) and np.isfinite(fo) and fc != fo and slow < SLOW_STEPS and low <= high:
        return min(max(guess, low), high)
    return 0.5 * (c + o)


@kernel(inline=True)
def _bracket_step(
    c: float, o: float, fc: float, fo: float, last: int, slow: int, m: float, value: float,
    certified: bool,
) -> tuple[float, float, float, float, int, int]:  # pragma: no cover - compiled  # fmt: skip
    """``constraint_leg._Bracket.update`` of one bracket after the point ``m``,
    ``value`` deciding its side there (``certified``: on the bound's side): the new
    ``(c, o, fc, fo, last, slow)``, the same floats."""
    before = abs(o - c)
    if certified:
        if last == 1:
            fo = 0.5 * fo  # the Illinois step: an end moved twice halves the other's value
        c = m
        fc = value
        last = 1
    else:
        if last == -1:
            fc = 0.5 * fc
        o = m
        fo = value
        last = -1
    slow = slow + 1 if abs(o - c) > 0.5 * before else 0
    return c, o, fc, fo, last, slow


@kernel
def _contract(
    code: NDArray[np.int64],
    const_lo: Array,
    const_hi: Array,
    k: int,
    kinds: NDArray[np.int64],
    pose_lo: Array,
    pose_hi: Array,
    slots: int,
    out: int,
    lo: Array,
    hi: Array,
    box: NDArray[np.int64],
    sign: Array,
    b_c: Array,
    b_o: Array,
    b_fc: Array,
    b_fo: Array,
    b_last: NDArray[np.int64],
    b_slow: NDArray[np.int64],
    a_c: Array,
    a_o: Array,
    a_fc: Array,
    a_fo: Array,
    a_last: NDArray[np.int64],
    a_slow: NDArray[np.int64],
    iterations: int,
    rtol: float,
) -> None:  # pragma: no cover - compiled
    """The steps of ``ConstraintLeg._contract`` on its two brackets of each run
    (``b_*`` below the root, ``a_*`` above it: ``c``, ``o``, ``fc``, ``fo``,
    ``last``, ``slow`` as in ``constraint_leg._Bracket``, updated in place), every
    iteration over the runs still active, the tape evaluated at ``[m, m]`` (its
    sines and cosines by ``intervals.point_sin_cos``, its derived inputs of the
    pose ``pose_lo[x, box]``): the same steps on the same floats."""
    block = PIECE_BLOCK
    r_lo = np.empty((slots, block))
    r_hi = np.empty((slots, block))
    n_extra = kinds.size
    first_const = k + 1 + n_extra
    for c in range(const_lo.size):
        for e in range(block):
            r_lo[first_const + c, e] = const_lo[c]
            r_hi[first_const + c, e] = const_hi[c]
    n = box.size
    active = np.arange(n)
    count = n
    # each block evaluates the points of half a block of runs
    half = block // 2
    col1 = np.empty(half, dtype=np.int64)
    col2 = np.empty(half, dtype=np.int64)
    point = np.empty(block)
    for _ in range(iterations):
        kept = 0
        for a in range(count):
            i = active[a]
            width = a_c[i] - b_c[i]
            done = (b_o[i] - b_c[i] <= rtol * width) and (a_c[i] - a_o[i] <= rtol * width)
            if not done:
                active[kept] = i
                kept += 1
        count = kept
        if count == 0:
            break
        for start in range(0, count, half):
            m = min(half, count - start)
            # the points m1 (below) and m2 (above) of each run, one column for both
            # while they are the same point (the same value)
            cols = 0
            for t in range(m):
                i = active[start + t]
                tol = 0.25 * rtol * (a_c[i] - b_c[i])
                m1 = _falsi_point(b_c[i], b_o[i], b_fc[i], b_fo[i], b_slow[i], tol)
                m2 = _falsi_point(a_c[i], a_o[i], a_fc[i], a_fo[i], a_slow[i], tol)
                col1[t] = cols
                point[cols] = m1
                cols += 1
                if m2 == m1 and m1 != 0.0:
                    col2[t] = col1[t]
                else:
                    col2[t] = cols
                    point[cols] = m2
                    cols += 1
            for t in range(m):
                b = box[active[start + t]]
                for e in (col1[t], col2[t]):
                    for j in range(k):
                        r_lo[j, e] = lo[b, j]
                        r_hi[j, e] = hi[b, j]
                    for x in range(n_extra):
                        if kinds[x] == 2:
                            r_lo[k + 1 + x, e] = pose_lo[x, b]
                            r_hi[k + 1 + x, e] = pose_hi[x, b]
            for e in range(cols):
                p = point[e]
                r_lo[k, e] = p
                r_hi[k, e] = p
                if n_extra:
                    s_lo, s_hi, c_lo, c_hi = point_sin_cos(p)
                    for x in range(n_extra):
                        if kinds[x] == 0:
                            r_lo[k + 1 + x, e] = s_lo
                            r_hi[k + 1 + x, e] = s_hi
                        elif kinds[x] == 1:
                            r_lo[k + 1 + x, e] = c_lo
                            r_hi[k + 1 + x, e] = c_hi
            run_ops(code, r_lo, r_hi, cols)
            for t in range(m):
                i = active[start + t]
                e1 = col1[t]
                e2 = col2[t]
                up = sign[i] > 0
                # each bracket after its point: below the root a point is certified
                # where F is certainly on the side below it (phi < 0), above where psi > 0
                phi = r_hi[out, e1] if up else -r_lo[out, e1]
                b_c[i], b_o[i], b_fc[i], b_fo[i], b_last[i], b_slow[i] = _bracket_step(
                    b_c[i], b_o[i], b_fc[i], b_fo[i], b_last[i], b_slow[i], point[e1], phi,
                    -phi > 0,
                )  # fmt: skip
                psi = r_lo[out, e2] if up else -r_hi[out, e2]
                a_c[i], a_o[i], a_fc[i], a_fo[i], a_last[i], a_slow[i] = _bracket_step(
                    a_c[i], a_o[i], a_fc[i], a_fo[i], a_last[i], a_slow[i], point[e2], psi,
                    psi > 0,
                )  # fmt: skip


def contract(
    tape: Tape,
    kinds: NDArray[np.int64],
    lo: Array,
    hi: Array,
    box: NDArray[np.intp],
    sign: Array,
    below: tuple[tuple[Array, Array, Array, Array], tuple[NDArray[np.int64], NDArray[np.int64]]],
    above: tuple[tuple[Array, Array, Array, Array], tuple[NDArray[np.int64], NDArray[np.int64]]],
    iterations: int,
    rtol: float,
) -> None:
    """``ConstraintLeg._contract`` compiled: the runs' two brackets (each ``(c, o,
    fc, fo)`` float64 arrays and ``(last, slow)`` int64 arrays, updated in place)
    after ``iterations`` points at most. ``kinds`` from :func:`trig_kinds`."""
    lo_c = np.ascontiguousarray(lo, dtype=np.float64)
    hi_c = np.ascontiguousarray(hi, dtype=np.float64)
    # the derived inputs of the pose over every box, once (rows of the others unused)
    pose_lo = np.zeros((kinds.size, lo_c.shape[0]))
    pose_hi = np.zeros((kinds.size, lo_c.shape[0]))
    memo = _ROWS.get()
    for x in range(kinds.size):
        if kinds[x] == _POSE:
            if memo is None:
                v_lo, v_hi = _pose_derived_values([tape.derived[x]], lo_c, hi_c)
                pose_lo[x], pose_hi[x] = v_lo[0], v_hi[0]
            else:
                pose_lo[x], pose_hi[x] = _rows_values(memo, *tape.derived[x], lo, hi, lo_c, hi_c)
    _contract(
        tape.code,
        tape.const_lo,
        tape.const_hi,
        tape.k,
        kinds,
        pose_lo,
        pose_hi,
        tape.slots,
        tape.out,
        lo_c,
        hi_c,
        np.ascontiguousarray(box, dtype=np.int64),
        np.ascontiguousarray(sign, dtype=np.float64),
        *below[0],
        *below[1],
        *above[0],
        *above[1],
        int(iterations),
        float(rtol),
    )


# ----------------------------------------------------------------- isolation
@dataclass(frozen=True, eq=False)
class Program:
    """Tapes of one ``k`` over one register file: slots ``[0, k]`` the inputs, then
    the derived inputs of the joint alone (``derived``), those of pose coordinates
    alone (``pose_derived``: function and argument slots, computed once per box,
    :func:`pose_values`), the constants of every tape, and their temporaries.
    Tape ``t``'s operations are the rows ``ranges[t, 0]:ranges[t, 1]`` of
    ``code``, its value slot ``outs[t]``."""

    k: int
    derived: tuple[Callable[..., Any], ...]
    pose_derived: tuple[tuple[Callable[..., Any], tuple[int, ...]], ...]
    const_lo: Array
    const_hi: Array
    code: NDArray[np.int64]
    ranges: NDArray[np.int64]
    outs: NDArray[np.int64]
    slots: int
    #: the operations on the joint, derived inputs and constants alone (``fixed``, in
    #: order, their targets ``fixed_slots``) and the others (``varying``, tape ``t``'s
    #: at rows ``varying_ranges[t, 0]:varying_ranges[t, 1]``)
    fixed: NDArray[np.int64]
    fixed_slots: NDArray[np.int64]
    varying: NDArray[np.int64]
    varying_ranges: NDArray[np.int64]
    #: :func:`hoisted`: the program it comes from, the operations on the pose alone
    #: taken out of it (in its slots) and the slots of their values the others read,
    #: which follow the derived inputs of the pose here (:func:`pose_values`)
    hoist: tuple[Program, NDArray[np.int64], NDArray[np.int64]] | None = None


def program(tapes: Sequence[Tape]) -> Program | None:
    """The tapes merged into one :class:`Program`, their derived inputs shared;
    None if a derived input depends on both the joint and a pose coordinate.

    Examples
    --------
    >>> from moveability.mechanisms import expressions as ex
    >>> sin = traced(ex.sin, "sin")
    >>> p = program([trace(lambda x, q: x * sin(q), 1), trace(lambda x, q: sin(q) - 2.0, 1)])
    >>> len(p.derived), p.ranges.tolist()
    (1, [[0, 1], [1, 2]])
    """
    if not tapes:
        return None
    k = tapes[0].k
    derived: list[Callable[..., Any]] = []
    pose_derived: list[tuple[Callable[..., Any], tuple[int, ...]]] = []
    for t in tapes:
        if t.k != k:
            return None
        for function, args in t.derived:
            if args == (k,):
                if not any(function is f for f in derived):
                    derived.append(function)
            elif args and all(0 <= a < k for a in args):
                if not any(function is f and args == a for f, a in pose_derived):
                    pose_derived.append((function, args))
            else:
                return None
    first_pose = k + 1 + len(derived)
    first_const = first_pose + len(pose_derived)
    n_const = sum(t.const_lo.size for t in tapes)
    const_at, temp_at = first_const, first_const + n_const
    codes, ranges, outs = [], [], []
    row = 0
    for t in tapes:
        t_const = t.k + 1 + len(t.derived)
        t_temp = t_const + t.const_lo.size
        shared = [
            next(i for i, f in enumerate(derived) if f is g)
            if args == (k,)
            else len(derived)
            + next(i for i, (f, a) in enumerate(pose_derived) if f is g and a == args)
            for g, args in t.derived
        ]
        mapping = np.empty(t.slots, dtype=np.int64)
        mapping[: k + 1] = np.arange(k + 1)
        mapping[k + 1 : t_const] = k + 1 + np.array(shared, dtype=np.int64)
        mapping[t_const:t_temp] = const_at + np.arange(t.const_lo.size)
        mapping[t_temp:] = temp_at + np.arange(t.slots - t_temp)
        code = t.code.copy()
        code[:, 1:] = mapping[t.code[:, 1:]]
        codes.append(code)
        ranges.append((row, row + code.shape[0]))
        outs.append(int(mapping[t.out]))
        row += code.shape[0]
        const_at += t.const_lo.size
        temp_at += t.slots - t_temp
    code = np.ascontiguousarray(np.concatenate(codes).reshape(-1, 4))
    # an operation is fixed when no operand depends on a pose coordinate
    fixed, before = _fixed_split(code, k, first_pose, first_const, temp_at)
    bounds = np.array(ranges, dtype=np.int64).reshape(-1, 2)
    return Program(
        k=k,
        derived=tuple(derived),
        pose_derived=tuple(pose_derived),
        const_lo=np.ascontiguousarray(np.concatenate([t.const_lo for t in tapes])),
        const_hi=np.ascontiguousarray(np.concatenate([t.const_hi for t in tapes])),
        code=code,
        ranges=bounds,
        outs=np.array(outs, dtype=np.int64),
        slots=temp_at,
        fixed=np.ascontiguousarray(code[fixed]).reshape(-1, 4),
        fixed_slots=np.ascontiguousarray(code[fixed, 1]),
        varying=np.ascontiguousarray(code[~fixed]).reshape(-1, 4),
        varying_ranges=np.ascontiguousarray(before[bounds]),
    )


def _fixed_split(
    code: NDArray[np.int64], k: int, first_pose: int, first_const: int, slots: int
) -> tuple[NDArray[np.bool_], NDArray[np.int64]]:
    """Which operations of ``code`` are fixed (no operand depends on a pose
    coordinate: slots ``[0, k)`` and ``[first_pose, first_const)``), and the row
    count before each row of the others."""
    on_pose = np.zeros(slots, dtype=bool)
    on_pose[:k] = True
    on_pose[first_pose:first_const] = True
    fixed = np.zeros(code.shape[0], dtype=bool)
    for row, (_, target, a, b) in enumerate(code):
        fixed[row] = not (on_pose[a] or on_pose[b])
        on_pose[target] = not fixed[row]
    return fixed, np.concatenate([[0], np.cumsum(~fixed)]).astype(np.int64)


def hoisted(prog: Program) -> Program:
    """``prog`` with its operations on the pose and constants alone (the 3-RRR's
    ``B - A``, in every tape) taken out: :func:`pose_values` computes them once per
    box (and at its centre), and the values the other operations read become
    derived inputs of the pose, after ``prog``'s. The same operations on the same
    operands: the same bounds, with fewer operations per piece. ``prog`` itself
    where it has none, or no more than two per value the others read.

    Examples
    --------
    >>> from moveability.mechanisms import expressions as ex
    >>> cos, sin = traced(ex.cos, "cos"), traced(ex.sin, "sin")
    >>> f = trace(lambda x, q: (2.0 * x + 1.0) * (x - 3.0) * cos(q), 1)
    >>> df_dq = trace(lambda x, q: (2.0 * x + 1.0) * (x - 3.0) * -sin(q), 1)
    >>> df_dx = trace(lambda x, q: (4.0 * x - 5.0) * cos(q), 1)
    >>> p = program([f, df_dq, df_dx])  # the tapes isolate_level takes
    >>> h = hoisted(p)
    >>> p.code.shape[0] > h.code.shape[0], h.hoist[2].size
    (True, 3)
    >>> lo, hi = np.array([[0.0], [1.0]]), np.array([[0.5], [3.0]])
    >>> box = np.array([0, 1])
    >>> q = (np.array([0.1, 0.2]), np.array([0.3, 0.4]))
    >>> extra = derived_values(p, Interval(*q))
    >>> a, b = (
    ...     isolate_level(g, lo, hi, box, q, extra, np.zeros(2, dtype=np.int64), 8, True)
    ...     for g in (p, h)
    ... )
    >>> all(np.array_equal(u, v) for u, v in zip(a, b))
    True
    """
    k = prog.k
    first_pose = k + 1 + len(prog.derived)
    first_const = first_pose + len(prog.pose_derived)
    n_const = prog.const_lo.size
    first_temp = first_const + n_const
    pose = np.zeros(prog.slots, dtype=bool)
    pose[:k] = True
    pose[first_pose:first_temp] = True
    on_pose = np.zeros(prog.code.shape[0], dtype=bool)
    for row, (_, target, a, b) in enumerate(prog.code):
        on_pose[row] = pose[a] and pose[b]
        pose[target] = on_pose[row]
    if not on_pose.any():
        return prog
    rest = prog.code[~on_pose]
    read = set(rest[:, 2:].ravel().tolist()) | set(prog.outs.tolist())
    needed = np.array(sorted(s for s in read if s >= first_temp and pose[s]), dtype=np.int64)
    if on_pose.sum() <= 2 * needed.size:
        # each value taken out is copied into every piece's registers: not worth it
        # for an operation or two (2 * x in the custom five-bar's dF/dx)
        return prog
    new_const = first_const + needed.size
    mapping = np.full(prog.slots, -1, dtype=np.int64)
    mapping[:first_const] = np.arange(first_const)
    mapping[needed] = first_const + np.arange(needed.size)
    mapping[first_const:first_temp] = new_const + np.arange(n_const)
    mapping[rest[:, 1]] = new_const + n_const + np.arange(rest.shape[0])
    code = rest.copy()
    code[:, 1:] = mapping[rest[:, 1:]]
    assert (code >= 0).all()
    slots = new_const + n_const + rest.shape[0]
    before = np.concatenate([[0], np.cumsum(~on_pose)]).astype(np.int64)
    ranges = np.ascontiguousarray(before[prog.ranges])
    fixed, before_v = _fixed_split(code, k, first_pose, new_const, slots)
    return Program(
        k=k,
        derived=prog.derived,
        pose_derived=prog.pose_derived,
        const_lo=prog.const_lo,
        const_hi=prog.const_hi,
        code=np.ascontiguousarray(code),
        ranges=ranges,
        outs=np.ascontiguousarray(mapping[prog.outs]),
        slots=slots,
        fixed=np.ascontiguousarray(code[fixed]).reshape(-1, 4),
        fixed_slots=np.ascontiguousarray(code[fixed, 1]),
        varying=np.ascontiguousarray(code[~fixed]).reshape(-1, 4),
        varying_ranges=np.ascontiguousarray(before_v[ranges]),
        hoist=(prog, np.ascontiguousarray(prog.code[on_pose]).reshape(-1, 4), needed),
    )


@kernel
def _pose_ops(
    code: NDArray[np.int64],
    const_lo: Array,
    const_hi: Array,
    k: int,
    slots: int,
    first_pose: int,
    lo: Array,
    hi: Array,
    d_lo: Array,
    d_hi: Array,
    needed: NDArray[np.int64],
) -> tuple[Array, Array]:  # pragma: no cover - compiled
    """The operations ``code`` on the pose alone over each box ``[lo[i], hi[i]]``
    (its derived inputs ``d[:, i]``): the values of the slots ``needed``."""
    n = lo.shape[0]
    block = PIECE_BLOCK
    r_lo = np.empty((slots, block))
    r_hi = np.empty((slots, block))
    first_const = first_pose + d_lo.shape[0]
    for c in range(const_lo.size):
        for e in range(block):
            r_lo[first_const + c, e] = const_lo[c]
            r_hi[first_const + c, e] = const_hi[c]
    out_lo = np.empty((needed.size, n))
    out_hi = np.empty((needed.size, n))
    for start in range(0, n, block):
        m = min(block, n - start)
        for j in range(k):
            for e in range(m):
                r_lo[j, e] = lo[start + e, j]
                r_hi[j, e] = hi[start + e, j]
        for x in range(d_lo.shape[0]):
            for e in range(m):
                r_lo[first_pose + x, e] = d_lo[x, start + e]
                r_hi[first_pose + x, e] = d_hi[x, start + e]
        run_ops(code, r_lo, r_hi, m)
        for s in range(needed.size):
            for e in range(m):
                out_lo[s, start + e] = r_lo[needed[s], e]
                out_hi[s, start + e] = r_hi[needed[s], e]
    return out_lo, out_hi


def derived_values(prog: Program, q: Interval) -> tuple[Array, Array]:
    """The derived inputs of ``prog`` over the joint enclosures ``q`` (shape
    ``(m,)``), computed as :func:`run` computes them: arrays of shape ``(d, m)``."""
    m = q.lo.shape[0]
    out_lo = np.empty((len(prog.derived), m))
    out_hi = np.empty((len(prog.derived), m))
    for e, function in enumerate(prog.derived):
        with np.errstate(all="ignore"):
            v = function(q)
        if not isinstance(v, Interval):
            v = Interval(v)
        out_lo[e] = v.lo
        out_hi[e] = v.hi
    return out_lo, out_hi


def _pose_derived_values(
    functions: Sequence[tuple[Callable[..., Any], tuple[int, ...]]], lo: Array, hi: Array
) -> tuple[Array, Array]:
    """Derived inputs of pose coordinates over the boxes ``[lo, hi]`` (rows), each
    computed as :func:`run` computes it on the same Interval operands: arrays of
    shape ``(d, n)``."""
    n = lo.shape[0]
    out_lo = np.empty((len(functions), n))
    out_hi = np.empty((len(functions), n))
    for e, (function, args) in enumerate(functions):
        with np.errstate(all="ignore"):
            v = function(*(Interval(lo[:, a], hi[:, a]) for a in args))
        if not isinstance(v, Interval):
            v = Interval(v)
        out_lo[e] = v.lo  # a copy (broadcast where v is one interval)
        out_hi[e] = v.hi
    return out_lo, out_hi


def pose_values(prog: Program, lo: Array, hi: Array) -> tuple[Array, Array, Array, Array]:
    """The derived inputs of pose coordinates of ``prog`` (``prog.pose_derived``)
    over each box ``[lo, hi]`` (rows of ``(n, k)`` arrays) and at its centre
    ``[c, c]``, ``c = 0.5 * (lo + hi)``, as :func:`run` computes them on those
    boxes: four arrays of shape ``(d, n)`` (box lower and upper bounds, then
    centre lower and upper bounds).

    Examples
    --------
    >>> from moveability.mechanisms import expressions as ex
    >>> cos = traced(ex.cos, "cos")
    >>> p = program([trace(lambda x, q: x * cos(x) + q, 1)])
    >>> lo, hi = np.array([[0.0], [1.0]]), np.array([[0.5], [3.0]])
    >>> b_lo, b_hi, c_lo, c_hi = pose_values(p, lo, hi)
    >>> bool(b_hi[0, 0] == 1.0 and c_lo[0, 1] < np.cos(2.0) < c_hi[0, 1])
    True
    """
    lo_c = np.ascontiguousarray(lo, dtype=np.float64)
    hi_c = np.ascontiguousarray(hi, dtype=np.float64)
    if prog.hoist is not None:
        # the derived inputs of the program it comes from, then the values of the
        # operations taken out, over the boxes and at their centres
        base, code, needed = prog.hoist
        values = pose_values(base, lo, hi)
        centre = 0.5 * (lo_c + hi_c)
        first_pose = base.k + 1 + len(base.derived)
        out = []
        for x_lo, x_hi, d_lo, d_hi in ((lo_c, hi_c, *values[:2]), (centre, centre, *values[2:])):
            with np.errstate(all="ignore"):
                h_lo, h_hi = _pose_ops(
                    code, base.const_lo, base.const_hi, base.k, base.slots, first_pose,
                    x_lo, x_hi, np.ascontiguousarray(d_lo), np.ascontiguousarray(d_hi), needed,
                )  # fmt: skip
            out += [np.concatenate([d_lo, h_lo]), np.concatenate([d_hi, h_hi])]
        return out[0], out[1], out[2], out[3]
    centre = 0.5 * (lo_c + hi_c)
    box = pose_box_values(prog, lo, hi)
    with np.errstate(all="ignore"):
        # (the centres as points: one sine and one cosine each, the same bounds)
        mid = _values(prog.pose_derived, _Coords(centre, centre, True))
    return box[0], box[1], mid[0], mid[1]


def pose_box_values(prog: Program, lo: Array, hi: Array) -> tuple[Array, Array]:
    """The first two arrays of :func:`pose_values`: the derived inputs of pose
    coordinates of ``prog`` over each box ``[lo, hi]``, shape ``(d, n)``
    (remembered within :func:`remembered_boxes`)."""
    lo_c = np.ascontiguousarray(lo, dtype=np.float64)
    hi_c = np.ascontiguousarray(hi, dtype=np.float64)
    with np.errstate(all="ignore"):
        memo = _ROWS.get()
        if memo is None:
            return _pose_derived_values(prog.pose_derived, lo_c, hi_c)
        rows = [_rows_values(memo, f, a, lo, hi, lo_c, hi_c) for f, a in prog.pose_derived]
    return (
        np.array([r[0] for r in rows]).reshape(-1, lo_c.shape[0]),
        np.array([r[1] for r in rows]).reshape(-1, lo_c.shape[0]),
    )


@kernel(inline=True)
def _fill(
    r_lo: Array,
    r_hi: Array,
    n: int,
    k: int,
    x_lo: Array,
    x_hi: Array,
    rows: NDArray[np.int64],
    q_lo: Array,
    q_hi: Array,
    extra_lo: Array,
    extra_hi: Array,
    qis: NDArray[np.int64],
    pose_lo: Array,
    pose_hi: Array,
) -> None:  # pragma: no cover - compiled
    """The inputs of register columns ``[0, n)``: pose box ``rows[e]`` and its
    derived inputs, joint enclosure and its derived inputs ``qis[e]``."""
    for j in range(k):
        for e in range(n):
            r_lo[j, e] = x_lo[rows[e], j]
            r_hi[j, e] = x_hi[rows[e], j]
    for e in range(n):
        r_lo[k, e] = q_lo[qis[e]]
        r_hi[k, e] = q_hi[qis[e]]
    n_extra = extra_lo.shape[0]
    for x in range(n_extra):
        for e in range(n):
            r_lo[k + 1 + x, e] = extra_lo[x, qis[e]]
            r_hi[k + 1 + x, e] = extra_hi[x, qis[e]]
    for x in range(pose_lo.shape[0]):
        for e in range(n):
            r_lo[k + 1 + n_extra + x, e] = pose_lo[x, rows[e]]
            r_hi[k + 1 + n_extra + x, e] = pose_hi[x, rows[e]]


@kernel
def _isolate_level(
    code: NDArray[np.int64],
    const_lo: Array,
    const_hi: Array,
    k: int,
    slots: int,
    ranges: NDArray[np.int64],
    outs: NDArray[np.int64],
    fixed: NDArray[np.int64],
    fixed_slots: NDArray[np.int64],
    lo: Array,
    hi: Array,
    box: NDArray[np.int64],
    tile: int,
    at: NDArray[np.int64],
    q_lo: Array,
    q_hi: Array,
    extra_lo: Array,
    extra_hi: Array,
    pose_lo: Array,
    pose_hi: Array,
    centre_lo: Array,
    centre_hi: Array,
    counts: NDArray[np.int64],
    max_pieces: int,
    split: bool,
    f_point: NDArray[np.int64],
    grid: Array,
    grid_lo: Array,
    grid_hi: Array,
    shift: int,
) -> tuple[
    NDArray[np.int64], Array, Array, NDArray[np.int8], NDArray[np.bool_],
    NDArray[np.int64], Array, Array, NDArray[np.int64], NDArray[np.bool_], Array,
]:  # fmt: skip  # pragma: no cover - compiled
    """One level of ``ConstraintLeg._isolate`` (see :func:`isolate_level`); the
    operations ``fixed`` (on the joint alone, the others in ``code``) evaluated once
    per enclosure ``q`` when the pieces are every box with each ``q``. Piece ``i``
    (``tile`` 0) takes row ``at[i]`` of ``q`` and ``extra``, row ``i`` if ``at`` is
    empty.

    With ``shift >= 0`` the ends of row ``r`` are the points ``grid[r << shift]``
    and ``grid[(r + 1) << shift]`` (their derived inputs ``grid_lo``, ``grid_hi``):
    a final piece of a certified sign is tested there (``f_point``, the code of
    ``F`` alone on the whole register file) and left out where it holds no root
    (``constraint_leg._root_free``).
    The last two outputs: whether each final piece was tested, and ``F``'s bounds
    at its two ends where it was (rows: lower and upper bound at ``lo``, then at
    ``hi``; NaN elsewhere)."""
    n_box = lo.shape[0]
    m = n_box * tile if tile > 0 else box.size
    block = PIECE_BLOCK
    r_lo = np.empty((slots, block))
    r_hi = np.empty((slots, block))
    first_pose = k + 1 + extra_lo.shape[0]
    n_pose = pose_lo.shape[0]
    first_const = first_pose + n_pose
    for c in range(const_lo.size):
        for e in range(block):
            r_lo[first_const + c, e] = const_lo[c]
            r_hi[first_const + c, e] = const_hi[c]
    # the fixed operations over the enclosures q (tile > 0), copied into the columns
    n_fixed = fixed_slots.size if tile > 0 else 0
    base_lo = np.empty((slots, q_lo.size if n_fixed else 0))
    base_hi = np.empty((slots, q_lo.size if n_fixed else 0))
    if n_fixed:
        for c in range(const_lo.size):
            for e in range(q_lo.size):
                base_lo[first_const + c, e] = const_lo[c]
                base_hi[first_const + c, e] = const_hi[c]
        for e in range(q_lo.size):
            for j in range(k):  # (no fixed operation reads them)
                base_lo[j, e] = 0.0
                base_hi[j, e] = 0.0
            base_lo[k, e] = q_lo[e]
            base_hi[k, e] = q_hi[e]
            for x in range(extra_lo.shape[0]):
                base_lo[k + 1 + x, e] = extra_lo[x, e]
                base_hi[k + 1 + x, e] = extra_hi[x, e]
        run_ops(fixed, base_lo, base_hi, q_lo.size)
    f_code = code[ranges[0, 0] : ranges[0, 1]]
    d_code = code[ranges[1, 0] : ranges[1 + k, 1]]  # dF/dq, then dF/dX_j
    out_f = outs[0]
    out_d = outs[1]
    rows = np.empty(block, dtype=np.int64)
    qis = np.empty(block, dtype=np.int64)
    nat_lo = np.empty(block)
    nat_hi = np.empty(block)
    near = np.empty(block, dtype=np.int64)
    dq_lo = np.empty(block)
    dq_hi = np.empty(block)
    dj_lo = np.empty((max(k, 1), block))
    dj_hi = np.empty((max(k, 1), block))
    k_box = np.empty(m, dtype=np.int64)
    k_qi = np.empty(m, dtype=np.int64)
    k_mono = np.empty(m, dtype=np.int8)
    k_finite = np.empty(m, dtype=np.bool_)
    n_kept = 0
    current = np.zeros(n_box, dtype=np.int64)
    b_next = 0
    q_next = 0
    near_rows = np.empty(block, dtype=np.int64)
    near_qis = np.empty(block, dtype=np.int64)
    # each box's mean-value offsets, computed at its first use
    off_lo = np.empty((n_box, max(k, 1)))
    off_hi = np.empty((n_box, max(k, 1)))
    off_done = np.zeros(n_box, dtype=np.bool_)
    mv_lo = np.empty(block)
    mv_hi = np.empty(block)
    for start in range(0, m, block):
        n = min(block, m - start)
        # the natural enclosure of F over box x piece
        for e in range(n):
            if tile > 0:
                rows[e] = b_next
                qis[e] = q_next
                q_next += 1
                if q_next == tile:
                    q_next = 0
                    b_next += 1
            else:
                rows[e] = box[start + e]
                qis[e] = at[start + e] if at.size else start + e
        _fill(r_lo, r_hi, n, k, lo, hi, rows, q_lo, q_hi, extra_lo, extra_hi, qis, pose_lo, pose_hi)
        for x in range(n_fixed):
            slot = fixed_slots[x]
            for e in range(n):
                r_lo[slot, e] = base_lo[slot, qis[e]]
                r_hi[slot, e] = base_hi[slot, qis[e]]
        run_ops(f_code, r_lo, r_hi, n)
        c = 0
        for e in range(n):
            a = r_lo[out_f, e]
            z = r_hi[out_f, e]
            a = -np.inf if a != a else a
            z = np.inf if z != z else z
            nat_lo[e] = a
            nat_hi[e] = z
            if a <= 0.0 and z >= 0.0:
                near[c] = e
                c += 1
        if c == 0:
            continue
        # where it holds 0: dF/dq and dF/dX_j over box x piece (packed in columns 0..c)
        for t in range(c):
            near_rows[t] = rows[near[t]]
            near_qis[t] = qis[near[t]]
        _fill(
            r_lo, r_hi, c, k, lo, hi, near_rows, q_lo, q_hi, extra_lo, extra_hi, near_qis,
            pose_lo, pose_hi,
        )  # fmt: skip
        for x in range(n_fixed):
            slot = fixed_slots[x]
            for t in range(c):
                r_lo[slot, t] = base_lo[slot, near_qis[t]]
                r_hi[slot, t] = base_hi[slot, near_qis[t]]
        run_ops(d_code, r_lo, r_hi, c)
        for t in range(c):
            dq_lo[t] = r_lo[out_d, t]
            dq_hi[t] = r_hi[out_d, t]
            for j in range(k):
                dj_lo[j, t] = r_lo[outs[2 + j], t]
                dj_hi[j, t] = r_hi[outs[2 + j], t]
        # F at the box's centre (the joint and derived inputs are still in place)
        for t in range(c):
            b = rows[near[t]]
            for j in range(k):
                centre = 0.5 * (lo[b, j] + hi[b, j])
                r_lo[j, t] = centre
                r_hi[j, t] = centre
            for x in range(n_pose):
                r_lo[first_pose + x, t] = centre_lo[x, b]
                r_hi[first_pose + x, t] = centre_hi[x, b]
        run_ops(f_code, r_lo, r_hi, c)
        # the mean-value form, each offset widened by an ulp of its bounds (the
        # pieces side by side: each one's sum over j in order)
        for t in range(c):
            b = rows[near[t]]
            if not off_done[b]:
                for j in range(k):
                    centre = 0.5 * (lo[b, j] + hi[b, j])
                    o_lo = lo[b, j] - centre
                    o_hi = hi[b, j] - centre
                    off_lo[b, j] = np.nextafter(
                        o_lo if (o_lo < 0.0 or o_lo != o_lo) else 0.0, -np.inf
                    )
                    off_hi[b, j] = np.nextafter(
                        o_hi if (o_hi > 0.0 or o_hi != o_hi) else 0.0, np.inf
                    )
                off_done[b] = True
            mv_lo[t] = r_lo[out_f, t]
            mv_hi[t] = r_hi[out_f, t]
        for j in range(k):
            for t in range(c):
                b = rows[near[t]]
                p_lo, p_hi = interval_mul(dj_lo[j, t], dj_hi[j, t], off_lo[b, j], off_hi[b, j])
                mv_lo[t], mv_hi[t] = interval_add(mv_lo[t], mv_hi[t], p_lo, p_hi)
        for t in range(c):
            e = near[t]
            b = rows[e]
            m_lo = mv_lo[t]
            m_hi = mv_hi[t]
            m_lo = -np.inf if m_lo != m_lo else m_lo
            m_hi = np.inf if m_hi != m_hi else m_hi
            f_lo = max(nat_lo[e], m_lo)
            f_hi = min(nat_hi[e], m_hi)
            if f_lo > 0.0 or f_hi < 0.0:
                continue
            finite = np.isfinite(f_lo) and np.isfinite(f_hi)
            mono = 0
            if finite and dq_lo[t] > 0.0:
                mono = 1
            elif finite and dq_hi[t] < 0.0:
                mono = -1
            k_box[n_kept] = b
            k_qi[n_kept] = qis[e]
            k_mono[n_kept] = mono
            k_finite[n_kept] = finite
            n_kept += 1
            current[b] += 1
    # the pieces split: no certified sign, and their box not yet at max_pieces
    cut = np.empty(n_kept, dtype=np.bool_)
    n_cut = 0
    for t in range(n_kept):
        b = k_box[t]
        cut[t] = split and k_mono[t] == 0 and counts[b] + current[b] <= max_pieces
        if cut[t]:
            n_cut += 1
    # the final pieces of a certified sign: F at their two ends over the box, a
    # piece of F on one side at both (ConstraintLeg._root_pieces) left out
    free = np.zeros(n_kept, dtype=np.bool_)
    # F's bounds at the two ends of each tested piece (lower end, then upper end)
    end_values = np.full((4, n_kept), np.nan)
    tested = shift >= 0
    if tested:
        ends = np.empty(n_kept, dtype=np.int64)
        n_ends = 0
        for t in range(n_kept):
            if k_mono[t] != 0 and k_finite[t] and not cut[t]:
                ends[n_ends] = t
                n_ends += 1
        half = block // 2
        for start in range(0, n_ends, half):
            m = min(half, n_ends - start)
            for u in range(m):
                t = ends[start + u]
                rows[2 * u] = k_box[t]
                rows[2 * u + 1] = k_box[t]
                qis[2 * u] = k_qi[t] << shift
                qis[2 * u + 1] = (k_qi[t] + 1) << shift
            _fill(
                r_lo, r_hi, 2 * m, k, lo, hi, rows, grid, grid, grid_lo, grid_hi, qis,
                pose_lo, pose_hi,
            )  # fmt: skip
            run_ops(f_point, r_lo, r_hi, 2 * m)
            for u in range(m):
                t = ends[start + u]
                a_lo = r_lo[out_f, 2 * u]
                a_hi = r_hi[out_f, 2 * u]
                z_lo = r_lo[out_f, 2 * u + 1]
                z_hi = r_hi[out_f, 2 * u + 1]
                end_values[0, t] = a_lo
                end_values[1, t] = a_hi
                end_values[2, t] = z_lo
                end_values[3, t] = z_hi
                if k_mono[t] > 0:
                    free[t] = a_lo > 0.0 or z_hi < 0.0
                else:
                    free[t] = a_hi < 0.0 or z_lo > 0.0
    n_free = 0
    for t in range(n_kept):
        if free[t]:
            n_free += 1
    n_final = n_kept - n_cut - n_free
    f_box = np.empty(n_final, dtype=np.int64)
    f_lo = np.empty(n_final)
    f_hi = np.empty(n_final)
    f_mono = np.empty(n_final, dtype=np.int8)
    f_finite = np.empty(n_final, dtype=np.bool_)
    f_tested = np.empty(n_final, dtype=np.bool_)
    f_ends = np.empty((4, n_final))
    s_box = np.empty(2 * n_cut, dtype=np.int64)
    s_lo = np.empty(2 * n_cut)
    s_hi = np.empty(2 * n_cut)
    s_at = np.empty(2 * n_cut, dtype=np.int64)
    u = 0
    v = 0
    for t in range(n_kept):
        b = k_box[t]
        qi = k_qi[t]
        a = q_lo[qi]
        z = q_hi[qi]
        if cut[t]:
            mid = 0.5 * (a + z)
            s_box[v] = b
            s_box[v + 1] = b
            s_lo[v] = a
            s_hi[v] = mid
            s_lo[v + 1] = mid
            s_hi[v + 1] = z
            s_at[v] = 2 * qi
            s_at[v + 1] = 2 * qi + 1
            v += 2
        else:
            # a piece left out still counts towards its box's max_pieces
            counts[b] += 1
            if free[t]:
                continue
            f_box[u] = b
            f_lo[u] = a
            f_hi[u] = z
            f_mono[u] = k_mono[t]
            f_finite[u] = k_finite[t]
            f_tested[u] = tested and k_mono[t] != 0 and k_finite[t]
            for e in range(4):
                f_ends[e, u] = end_values[e, t]
            u += 1
    return f_box, f_lo, f_hi, f_mono, f_finite, s_box, s_lo, s_hi, s_at, f_tested, f_ends


def isolate_level(
    prog: Program,
    lo: Array,
    hi: Array,
    box: NDArray[np.int64] | None,
    q: tuple[Array, Array],
    extra: tuple[Array, Array],
    counts: NDArray[np.int64],
    max_pieces: int,
    split: bool,
    pose: tuple[Array, Array, Array, Array] | None = None,
    at: NDArray[np.int64] | None = None,
    ends: tuple[Array, Array, Array, int] | None = None,
) -> tuple[Any, ...]:
    """One level of the root isolation of ``ConstraintLeg._isolate`` in one
    compiled loop, for the program of the tapes of ``F``, ``dF/dq`` and the
    ``dF/dX_j`` (in that order).

    Over each piece (box ``box[i]`` of ``[lo, hi]``, joint enclosure ``q[i]``):
    the enclosure of ``F``, the natural one met with the mean-value form about
    the box's centre where the natural one holds 0. A piece whose enclosure
    excludes 0 is dropped; the others get the certified sign of ``dF/dq`` (0 if
    none, or if ``F`` is not finite) and are final, or are halved when they have
    no sign, ``split`` holds and their box has at most ``max_pieces`` pieces:
    those of ``counts`` (final ones of the levels before, updated here) and this
    level's kept ones. The same steps on the same floats as the interpreted level
    (``ConstraintLeg._isolate``), which leaves the end test below to
    ``ConstraintLeg._root_pieces``.

    ``extra`` holds the derived inputs of ``q`` (:func:`derived_values`), ``pose``
    those of the pose coordinates over the boxes and at their centres
    (:func:`pose_values`, computed here if None). With ``box`` None the pieces
    are every box with each enclosure of ``q`` in turn. With ``at``, ``q`` and
    ``extra`` are a table: piece ``i``'s joint enclosure is ``q[at[i]]``, its
    derived inputs ``extra[:, at[i]]``.

    With ``ends = (grid, grid_lo, grid_hi, shift)`` the two ends of row ``r`` of
    ``q`` are the points ``grid[r << shift]`` and ``grid[(r + 1) << shift]``, their
    derived inputs ``grid_lo``, ``grid_hi`` (``(d, g)`` arrays): a final piece of
    a certified sign that holds no root, ``F`` (its natural enclosure over the box)
    on that sign's side at the piece's start or on the other side at its end, is
    left out (counted among its box's pieces all the same): the test of
    ``ConstraintLeg._root_pieces`` (``constraint_leg._root_free``).

    Returns the final pieces (box, lo, hi, sign, finite), those of the next level
    (box, lo, hi, row), whether each final piece was tested at its ends and
    ``F``'s enclosures there (a ``(4, m)`` array: lower and upper bound at the
    piece's ``lo``, then at its ``hi``; NaN where not tested): the halves of the
    row ``r`` of ``q`` (``at[i]``, or ``i``, or the enclosure's index where
    ``box`` is None) are the rows ``2 r`` and ``2 r + 1`` of the table of ``q``'s
    enclosures each halved at ``0.5 * (lo + hi)``, in order.
    """
    if pose is None:
        pose = pose_values(prog, lo, hi)
    tile = 0 if box is not None else int(np.size(q[0]))
    box_i = np.zeros(0, dtype=np.int64) if box is None else box
    # every box with each q: the operations on q alone once per q
    code, ranges, fixed, fixed_slots = (
        (prog.varying, prog.varying_ranges, prog.fixed, prog.fixed_slots)
        if tile
        else (prog.code, prog.ranges, prog.fixed[:0], prog.fixed_slots[:0])
    )
    return _isolate_level(
        code,
        prog.const_lo,
        prog.const_hi,
        prog.k,
        prog.slots,
        ranges,
        prog.outs,
        fixed,
        fixed_slots,
        np.ascontiguousarray(lo, dtype=np.float64),
        np.ascontiguousarray(hi, dtype=np.float64),
        np.ascontiguousarray(box_i, dtype=np.int64),
        tile,
        np.zeros(0, dtype=np.int64) if at is None else np.ascontiguousarray(at, dtype=np.int64),
        np.ascontiguousarray(q[0], dtype=np.float64),
        np.ascontiguousarray(q[1], dtype=np.float64),
        np.ascontiguousarray(extra[0], dtype=np.float64),
        np.ascontiguousarray(extra[1], dtype=np.float64),
        np.ascontiguousarray(pose[0], dtype=np.float64),
        np.ascontiguousarray(pose[1], dtype=np.float64),
        np.ascontiguousarray(pose[2], dtype=np.float64),
        np.ascontiguousarray(pose[3], dtype=np.float64),
        counts,
        int(max_pieces),
        bool(split),
        np.ascontiguousarray(prog.code[prog.ranges[0, 0] : prog.ranges[0, 1]]),
        *(_NO_ENDS if ends is None else ends),
    )


#: no end tests (:func:`isolate_level`)
_NO_ENDS = (np.zeros(1), np.zeros((0, 1)), np.zeros((0, 1)), -1)


@kernel
def _merge_order(
    box: NDArray[np.int64], lo: Array, bounds: NDArray[np.int64]
) -> NDArray[np.int64]:  # pragma: no cover - compiled
    """The order of ``np.lexsort((lo, box))`` for segments ``bounds[s]:bounds[s + 1]``
    each already in that order (and no NaN in ``lo``): their stable merge."""
    n = box.size
    segments = bounds.size - 1
    head = bounds[:-1].copy()
    out = np.empty(n, dtype=np.int64)
    for o in range(n):
        best = -1
        best_segment = 0
        for s in range(segments):
            i = head[s]
            if i < bounds[s + 1] and (
                best < 0 or box[i] < box[best] or (box[i] == box[best] and lo[i] < lo[best])
            ):
                best = i
                best_segment = s
        out[o] = best
        head[best_segment] += 1
    return out


def merge_order(box: NDArray[np.int64], lo: Array, sizes: Sequence[int]) -> NDArray[np.int64]:
    """``np.lexsort((lo, box))`` of consecutive segments of ``sizes`` elements, each
    sorted by box, then ``lo`` (not NaN): a merge.

    Examples
    --------
    >>> box, lo = np.array([0, 2, 0, 1, 2]), np.array([0.5, 0.0, 0.7, 0.1, -1.0])
    >>> merge_order(box, lo, [2, 3]).tolist() == np.lexsort((lo, box)).tolist()
    True
    """
    bounds = np.concatenate([[0], np.cumsum(np.asarray(sizes, dtype=np.int64))])
    return _merge_order(
        np.ascontiguousarray(box, dtype=np.int64),
        np.ascontiguousarray(lo, dtype=np.float64),
        bounds.astype(np.int64),
    )
