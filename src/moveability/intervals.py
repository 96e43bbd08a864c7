"""Interval arithmetic on numpy arrays, with outward rounding.

An :class:`Interval` holds two float arrays ``lo <= hi`` of one shape: an
array of closed intervals. Every operation returns an enclosure of the exact
range of the operation over its operands: the numpy result is computed in
round-to-nearest and then widened outwards, by one unit in the last place for
the correctly rounded operations (``+ - * /`` and ``sqrt``) and by a few units
for the library functions (``sin``, ``cos``, ``arccos``, ``arctan2``), whose
error is below one unit on the platforms numpy supports.

Examples
--------
>>> import numpy as np
>>> from moveability.intervals import Interval, sqrt
>>> x = Interval(np.array([1.0]), np.array([4.0]))
>>> r = sqrt(x * x + 1.0)
>>> bool(r.lo[0] <= np.sqrt(2.0) and np.sqrt(17.0) <= r.hi[0])
True
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .compiled import kernel
from .types import Array

__all__ = [
    "Interval",
    "Slot",
    "absolute",
    "add_into",
    "arccos",
    "arctan2",
    "atan_bounds",
    "bound_above",
    "cos",
    "exp",
    "flat_arrays",
    "holds_angle",
    "hull",
    "interval_add",
    "interval_cos",
    "interval_div",
    "interval_mul",
    "interval_sin",
    "interval_sqrt",
    "interval_square",
    "interval_sub",
    "lib_above",
    "lib_below",
    "log",
    "may_contain_angle",
    "move_below",
    "mul_into",
    "nan_max",
    "nan_min",
    "next_below",
    "point_sin_cos",
    "power",
    "rational",
    "reciprocal",
    "sin",
    "slot_add",
    "slot_add_c",
    "slot_c_sub",
    "slot_det3",
    "slot_div",
    "slot_mul",
    "slot_mul_c",
    "slot_negate",
    "slot_sub",
    "slot_sub_c",
    "sqrt",
    "square",
    "step_down",
    "sub_into",
    "tan",
    "trig_bounds",
    "trig_ends",
    "trig_one",
    "widen_down",
    "widen_up",
]

_INF = np.inf
_PI_UP = float(np.nextafter(np.pi, np.inf))
_TWO_PI = 2.0 * np.pi
#: ulps added to the results of library functions
_LIB_ULPS = 4


_MAX = float(np.finfo(np.float64).max)
#: beyond this magnitude a widening away from zero gives the infinity
_HUGE = _MAX / 2.0
#: the smallest positive subnormal
_TINY = 5e-324


@kernel
def _below(x: float, rel: float, tiny: float, keep_zero: bool) -> float:  # pragma: no cover
    """``x`` moved down by ``|x| * rel + tiny``; a zero kept when ``keep_zero``."""
    if x != x or (keep_zero and x == 0.0):
        return x
    if x > _MAX:
        # +inf: an overflow, the exact value is finite and above; one float below is
        # the largest, more than one (tiny holds the number of ulps) are further
        if tiny <= _TINY:
            return _MAX
        x = _MAX
    if x < -_HUGE:
        return -np.inf
    return x - (abs(x) * rel + tiny)


@kernel
def _above(x: float, rel: float, tiny: float, keep_zero: bool) -> float:  # pragma: no cover
    """``x`` moved up by ``|x| * rel + tiny``; a zero kept when ``keep_zero``."""
    return -_below(-x, rel, tiny, keep_zero)


@kernel
def _widen(x: Array, rel: float, tiny: float, up: bool) -> Array:  # pragma: no cover
    """:func:`_below` (or :func:`_above`) of each element of a flat array."""
    out = np.empty_like(x)
    for i in range(x.size):
        out[i] = _above(x[i], rel, tiny, False) if up else _below(x[i], rel, tiny, False)
    return out


@kernel
def _sum_bounds(
    a: Array, b: Array, up: bool
) -> Array:  # pragma: no cover - compiled
    """``a + b`` widened down (or up) by an ulp or a few, element by element of two flat
    arrays of one size; a zero sum is exact."""
    out = np.empty_like(a)
    for i in range(a.size):
        s = a[i] + b[i]
        out[i] = _above(s, _REL_1, _TINY, True) if up else _below(s, _REL_1, _TINY, True)
    return out


def flat_arrays(*arrays: ArrayLike) -> tuple[tuple[int, ...], list[Array]]:
    """The arrays broadcast together, as flat contiguous float arrays, and their shape:
    what a compiled loop takes (no copy for contiguous arrays of one shape)."""
    parts = [np.asarray(a, dtype=np.float64) for a in arrays]
    shape = parts[0].shape
    if any(a.shape != shape for a in parts):
        shape = np.broadcast_shapes(*(a.shape for a in parts))
        parts = [a if a.shape == shape else np.broadcast_to(a, shape) for a in parts]
    return shape, [np.ascontiguousarray(a).reshape(-1) for a in parts]


def _rel(ulps: int) -> float:
    # x -/+ (|x| * (ulps + 1) * 2**-52 + ulps * 2**-1074), rounded to nearest, lies
    # at least ``ulps`` floats away from x, and at most 2 * (ulps + 1) + 1: |x| *
    # 2**-52 is one to two ulps of x, and the product and the sum each round by at
    # most half an ulp (tests/test_intervals.py compares with repeated nextafter,
    # subnormals, binade edges and overflows included)
    return (ulps + 1) * 2.0**-52


_REL_1 = _rel(1)


@kernel
def next_below(x: float) -> float:  # pragma: no cover - compiled
    """A float at least one float below ``x`` (a few at most): the outward rounding of
    a lower bound, for compiled code.

    Examples
    --------
    >>> next_below(1.0) < 1.0 and next_below(0.0) < 0.0
    True
    """
    return _below(x, _REL_1, _TINY, False)


def widen_down(x: ArrayLike, ulps: int = 1) -> Array:
    """Outward rounding of lower bounds: each float moved at least ``ulps`` floats
    down (at most ``2 * ulps + 3``), in one compiled pass; NaN stays, +inf (an
    overflow) becomes a finite bound.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.array([1.0, 0.0, -2.5])
    >>> bool((widen_down(x, 2) <= np.nextafter(np.nextafter(x, -np.inf), -np.inf)).all())
    True
    """
    shape, (flat,) = flat_arrays(x)
    return _widen(flat, _rel(ulps), ulps * _TINY, False).reshape(shape)


def widen_up(x: ArrayLike, ulps: int = 1) -> Array:
    """Outward rounding of upper bounds: each float moved at least ``ulps`` floats up
    (see :func:`widen_down`)."""
    shape, (flat,) = flat_arrays(x)
    return _widen(flat, _rel(ulps), ulps * _TINY, True).reshape(shape)


@kernel
def _product_bounds(
    a_lo: Array, a_hi: Array, b_lo: Array, b_hi: Array
) -> tuple[Array, Array]:  # pragma: no cover - compiled
    """Bounds of ``[a_lo, a_hi] * [b_lo, b_hi]``, widened outward by one ulp (or a few).

    The four bound products give the range; ``0 * inf`` (nan) is taken as 0, the
    product of a zero bound. A zero bound is exact, and kept, unless a zero
    product comes from two non-zero factors (an underflow)."""
    n = a_lo.size
    out_lo = np.empty(n)
    out_hi = np.empty(n)
    for i in range(n):
        low = np.inf
        high = -np.inf
        underflow = False
        for j in range(4):
            x = a_lo[i] if j < 2 else a_hi[i]
            y = b_lo[i] if j % 2 == 0 else b_hi[i]
            p = x * y
            if p != p:
                p = 0.0
            if p < low:
                low = p
            if p > high:
                high = p
            if p == 0.0 and x != 0.0 and y != 0.0:
                underflow = True
        out_lo[i] = 0.0 if (low == 0.0 and not underflow) else _below(low, _REL_1, _TINY, False)
        out_hi[i] = 0.0 if (high == 0.0 and not underflow) else _above(high, _REL_1, _TINY, False)
    return out_lo, out_hi


@kernel(inline=True)
def _down(x: float, keep_zero: bool) -> float:  # pragma: no cover - compiled
    """:func:`_below` by one ulp (or a few), inlined into the compiled interval
    helpers below (a call per element to a separately compiled function costs
    several times the arithmetic), and without jumps on the data (selects)."""
    y = x - (abs(x) * _REL_1 + _TINY)
    y = -np.inf if x < -_HUGE else y
    y = _MAX if x > _MAX else y  # +inf: an overflow, the exact value is finite
    return x if (x != x or (keep_zero and x == 0.0)) else y


@kernel(inline=True)
def _up(x: float, keep_zero: bool) -> float:  # pragma: no cover - compiled
    """:func:`_above` by one ulp (or a few), inlined (see :func:`_down`)."""
    return -_down(-x, keep_zero)


@kernel(inline=True)
def interval_mul(
    a_lo: float, a_hi: float, b_lo: float, b_hi: float
) -> tuple[float, float]:  # pragma: no cover - compiled
    """One element of :func:`_product_bounds`: ``[a_lo, a_hi] * [b_lo, b_hi]``,
    widened as :meth:`Interval.__mul__` does, for compiled code.

    Branch-free (selects, no jumps on the data): the four bound products (``0 *
    inf`` taken as 0), their least and greatest (of equal products either: a
    zero's sign is lost below), and the underflow flag of the kernel's loop."""
    p1 = a_lo * b_lo
    p2 = a_lo * b_hi
    p3 = a_hi * b_lo
    p4 = a_hi * b_hi
    p1 = 0.0 if p1 != p1 else p1
    p2 = 0.0 if p2 != p2 else p2
    p3 = 0.0 if p3 != p3 else p3
    p4 = 0.0 if p4 != p4 else p4
    l12 = p1 if p1 < p2 else p2
    l34 = p3 if p3 < p4 else p4
    h12 = p1 if p1 > p2 else p2
    h34 = p3 if p3 > p4 else p4
    low = l12 if l12 < l34 else l34
    high = h12 if h12 > h34 else h34
    # a zero product of two non-zero factors: an underflow, not an exact zero
    under = (
        ((p1 == 0.0) & (a_lo != 0.0) & (b_lo != 0.0))
        | ((p2 == 0.0) & (a_lo != 0.0) & (b_hi != 0.0))
        | ((p3 == 0.0) & (a_hi != 0.0) & (b_lo != 0.0))
        | ((p4 == 0.0) & (a_hi != 0.0) & (b_hi != 0.0))
    )
    out_lo = 0.0 if (low == 0.0 and not under) else _down(low, False)
    out_hi = 0.0 if (high == 0.0 and not under) else _up(high, False)
    return out_lo, out_hi


@kernel(inline=True)
def interval_add(
    a_lo: float, a_hi: float, b_lo: float, b_hi: float
) -> tuple[float, float]:  # pragma: no cover - compiled
    """One element of :meth:`Interval.__add__`, for compiled code."""
    return _down(a_lo + b_lo, True), _up(a_hi + b_hi, True)


@kernel(inline=True)
def interval_sub(
    a_lo: float, a_hi: float, b_lo: float, b_hi: float
) -> tuple[float, float]:  # pragma: no cover - compiled
    """One element of :meth:`Interval.__sub__`, for compiled code."""
    return _down(a_lo + -b_hi, True), _up(a_hi + -b_lo, True)


@kernel
def mul_into(
    a_lo: Array, a_hi: Array, b_lo: Array, b_hi: Array, out_lo: Array, out_hi: Array
) -> None:  # pragma: no cover - compiled
    """:func:`interval_mul` of flat arrays of one size, into ``out`` (which may be
    one of the operands): a whole array per call, so compiled code that chains
    interval operations pays no call per element."""
    for i in range(out_lo.size):
        out_lo[i], out_hi[i] = interval_mul(a_lo[i], a_hi[i], b_lo[i], b_hi[i])


@kernel
def add_into(
    a_lo: Array, a_hi: Array, b_lo: Array, b_hi: Array, out_lo: Array, out_hi: Array
) -> None:  # pragma: no cover - compiled
    """:func:`interval_add` of flat arrays, into ``out`` (see :func:`mul_into`)."""
    for i in range(out_lo.size):
        out_lo[i], out_hi[i] = interval_add(a_lo[i], a_hi[i], b_lo[i], b_hi[i])


@kernel
def sub_into(
    a_lo: Array, a_hi: Array, b_lo: Array, b_hi: Array, out_lo: Array, out_hi: Array
) -> None:  # pragma: no cover - compiled
    """:func:`interval_sub` of flat arrays, into ``out`` (see :func:`mul_into`)."""
    for i in range(out_lo.size):
        out_lo[i], out_hi[i] = interval_sub(a_lo[i], a_hi[i], b_lo[i], b_hi[i])


# The mechanisms' compiled enclosures work chunk by chunk: each quantity of a
# chunk's boxes is a row (a "slot") of two scratch arrays ``lo``, ``hi`` (slots x
# boxes), and each interval operation one loop over the chunk's boxes.

#: a slot (a row of the scratch); kernels pass them as np.int64: a constant would
#: have numba compile each pass once for each slot number
Slot = int | np.int64


@kernel
def slot_mul(lo: Array, hi: Array, a: Slot, b: Slot, o: Slot, w: int) -> None:  # pragma: no cover
    """Slot ``o`` = slot ``a`` * slot ``b`` (the first ``w`` boxes), by :func:`mul_into`."""
    mul_into(lo[a, :w], hi[a, :w], lo[b, :w], hi[b, :w], lo[o, :w], hi[o, :w])


@kernel
def slot_add(lo: Array, hi: Array, a: Slot, b: Slot, o: Slot, w: int) -> None:  # pragma: no cover
    """Slot ``o`` = slot ``a`` + slot ``b``, by :func:`add_into`."""
    add_into(lo[a, :w], hi[a, :w], lo[b, :w], hi[b, :w], lo[o, :w], hi[o, :w])


@kernel
def slot_sub(lo: Array, hi: Array, a: Slot, b: Slot, o: Slot, w: int) -> None:  # pragma: no cover
    """Slot ``o`` = slot ``a`` - slot ``b``, by :func:`sub_into`."""
    sub_into(lo[a, :w], hi[a, :w], lo[b, :w], hi[b, :w], lo[o, :w], hi[o, :w])


@kernel
def slot_mul_c(
    lo: Array, hi: Array, a: Slot, c_lo: float, c_hi: float, o: Slot, w: int
) -> None:  # pragma: no cover - compiled
    """Slot ``o`` = slot ``a`` * the interval ``[c_lo, c_hi]`` (``Interval * c``)."""
    a_lo, a_hi, o_lo, o_hi = lo[a, :w], hi[a, :w], lo[o, :w], hi[o, :w]
    for j in range(w):
        o_lo[j], o_hi[j] = interval_mul(a_lo[j], a_hi[j], c_lo, c_hi)


@kernel
def slot_add_c(
    lo: Array, hi: Array, a: Slot, c_lo: float, c_hi: float, o: Slot, w: int
) -> None:  # pragma: no cover - compiled
    """Slot ``o`` = slot ``a`` + the interval ``[c_lo, c_hi]``."""
    a_lo, a_hi, o_lo, o_hi = lo[a, :w], hi[a, :w], lo[o, :w], hi[o, :w]
    for j in range(w):
        o_lo[j], o_hi[j] = interval_add(a_lo[j], a_hi[j], c_lo, c_hi)


@kernel
def slot_sub_c(
    lo: Array, hi: Array, a: Slot, c_lo: float, c_hi: float, o: Slot, w: int
) -> None:  # pragma: no cover - compiled
    """Slot ``o`` = slot ``a`` - the interval ``[c_lo, c_hi]``."""
    a_lo, a_hi, o_lo, o_hi = lo[a, :w], hi[a, :w], lo[o, :w], hi[o, :w]
    for j in range(w):
        o_lo[j], o_hi[j] = interval_sub(a_lo[j], a_hi[j], c_lo, c_hi)


@kernel
def slot_c_sub(
    lo: Array, hi: Array, c_lo: float, c_hi: float, a: Slot, o: Slot, w: int
) -> None:  # pragma: no cover - compiled
    """Slot ``o`` = the interval ``[c_lo, c_hi]`` - slot ``a``."""
    a_lo, a_hi, o_lo, o_hi = lo[a, :w], hi[a, :w], lo[o, :w], hi[o, :w]
    for j in range(w):
        o_lo[j], o_hi[j] = interval_sub(c_lo, c_hi, a_lo[j], a_hi[j])


@kernel
def slot_negate(lo: Array, hi: Array, a: Slot, o: Slot, w: int) -> None:  # pragma: no cover
    """Slot ``o`` = - slot ``a`` (exact)."""
    for j in range(w):
        a_lo = lo[a, j]
        lo[o, j] = -hi[a, j]
        hi[o, j] = -a_lo


@kernel
def slot_det3(
    lo: Array, hi: Array, m: NDArray[np.int64], o: Slot, t: Slot, w: int
) -> None:  # pragma: no cover - compiled
    """Slot ``o`` = the determinant of the 3 x 3 matrix of slots ``m`` (9, row by
    row) as ``mechanisms.base._det_chunk`` expands it: the first row's cofactors,
    alternately subtracted and added. Slots ``t``, ``t + 1`` are scratch."""
    p, q = t, t + 1
    slot_mul(lo, hi, m[4], m[8], p, w)
    slot_mul(lo, hi, m[5], m[7], q, w)
    slot_sub(lo, hi, p, q, p, w)
    slot_mul(lo, hi, m[0], p, o, w)
    slot_mul(lo, hi, m[3], m[8], p, w)
    slot_mul(lo, hi, m[5], m[6], q, w)
    slot_sub(lo, hi, p, q, p, w)
    slot_mul(lo, hi, m[1], p, q, w)
    slot_sub(lo, hi, o, q, o, w)
    slot_mul(lo, hi, m[3], m[7], p, w)
    slot_mul(lo, hi, m[4], m[6], q, w)
    slot_sub(lo, hi, p, q, p, w)
    slot_mul(lo, hi, m[2], p, q, w)
    slot_add(lo, hi, o, q, o, w)


@kernel
def _sum_bounds_one(a: Array, b: float, up: bool) -> Array:  # pragma: no cover - compiled
    """:func:`_sum_bounds` with one number ``b`` for every element (no broadcast copy)."""
    out = np.empty_like(a)
    for i in range(a.size):
        s = a[i] + b
        out[i] = _above(s, _REL_1, _TINY, True) if up else _below(s, _REL_1, _TINY, True)
    return out


@kernel
def _product_bounds_one(
    a_lo: Array, a_hi: Array, b_lo: float, b_hi: float
) -> tuple[Array, Array]:  # pragma: no cover - compiled
    """:func:`_product_bounds` with one interval ``[b_lo, b_hi]`` for every element."""
    n = a_lo.size
    out_lo = np.empty(n)
    out_hi = np.empty(n)
    for i in range(n):
        out_lo[i], out_hi[i] = interval_mul(a_lo[i], a_hi[i], b_lo, b_hi)
    return out_lo, out_hi


def _full_and_one(a: Interval, b: Interval) -> tuple[Interval, Interval] | None:
    """``(full, one)`` when one operand holds a single interval that broadcasts to
    the other's shape (the other first), else None."""
    if b.lo.size == 1 and b.lo.ndim <= a.lo.ndim and a.lo.size != 1:
        return a, b
    if a.lo.size == 1 and a.lo.ndim <= b.lo.ndim and b.lo.size != 1:
        return b, a
    return None


def _flat(x: Array) -> Array:
    return np.ascontiguousarray(x).reshape(-1)


@dataclass(frozen=True)
class Interval:
    """An array of closed intervals ``[lo, hi]``.

    Parameters
    ----------
    lo, hi : array_like
        Bounds of one shape (broadcast together).
    """

    lo: Array
    hi: Array
    #: numpy defers to the reflected operators, so ``array * interval`` is an Interval
    __array_ufunc__ = None

    def __init__(self, lo: ArrayLike, hi: ArrayLike | None = None) -> None:
        lo_a = np.asarray(lo, dtype=np.float64)
        hi_a = lo_a if hi is None else np.asarray(hi, dtype=np.float64)
        if lo_a.shape != hi_a.shape:
            # (numpy returns arrays of one shape as they are)
            lo_a, hi_a = np.broadcast_arrays(lo_a, hi_a)
        object.__setattr__(self, "lo", lo_a)
        object.__setattr__(self, "hi", hi_a)

    # ------------------------------------------------------------------ basics
    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(self.lo.shape)

    @property
    def mid(self) -> Array:
        """A point inside each interval (the midpoint, rounded)."""
        m = 0.5 * self.lo + 0.5 * self.hi
        return np.clip(m, self.lo, self.hi)

    @property
    def width(self) -> Array:
        return self.hi - self.lo

    def __getitem__(self, index: Any) -> Interval:
        return Interval(self.lo[index], self.hi[index])

    def contains(self, x: ArrayLike) -> NDArray[np.bool_]:
        """Whether each point lies in its interval."""
        xa = np.asarray(x, dtype=np.float64)
        return (self.lo <= xa) & (xa <= self.hi)

    def positive(self) -> NDArray[np.bool_]:
        """Whether every value of each interval is > 0 (certainly positive)."""
        return self.lo > 0

    def negative(self) -> NDArray[np.bool_]:
        """Whether every value of each interval is < 0."""
        return self.hi < 0

    # -------------------------------------------------------------- operators
    def __neg__(self) -> Interval:
        return Interval(-self.hi, -self.lo)

    def __add__(self, other: IntervalLike) -> Interval:
        o = as_interval(other)
        pair = _full_and_one(self, o)
        if pair is not None:
            # one number for every element: no broadcast copy (a sum is commutative)
            full, one = pair
            shape = full.lo.shape
            return Interval(
                _sum_bounds_one(_flat(full.lo), float(one.lo.flat[0]), False).reshape(shape),
                _sum_bounds_one(_flat(full.hi), float(one.hi.flat[0]), True).reshape(shape),
            )
        with np.errstate(over="ignore"):
            shape, (a_lo, a_hi, b_lo, b_hi) = flat_arrays(self.lo, self.hi, o.lo, o.hi)
        return Interval(
            _sum_bounds(a_lo, b_lo, False).reshape(shape),
            _sum_bounds(a_hi, b_hi, True).reshape(shape),
        )

    __radd__ = __add__

    def __sub__(self, other: IntervalLike) -> Interval:
        o = as_interval(other)
        if _full_and_one(self, o) is not None:
            # self - o = self + (-o): negation is exact
            return self + Interval(-o.hi, -o.lo)
        with np.errstate(over="ignore"):
            shape, (a_lo, a_hi, b_lo, b_hi) = flat_arrays(self.lo, self.hi, o.lo, o.hi)
        return Interval(
            _sum_bounds(a_lo, -b_hi, False).reshape(shape),
            _sum_bounds(a_hi, -b_lo, True).reshape(shape),
        )

    def __rsub__(self, other: IntervalLike) -> Interval:
        return as_interval(other) - self

    def __mul__(self, other: IntervalLike) -> Interval:
        o = as_interval(other)
        parts = (self.lo, self.hi, o.lo, o.hi)
        shape = parts[0].shape
        if all(x.shape == shape for x in parts):
            # one shape: no broadcast (reshape copies only what is not contiguous)
            lo, hi = _product_bounds(*(x.reshape(-1) for x in parts))
            return Interval(lo.reshape(shape), hi.reshape(shape))
        pair = _full_and_one(self, o)
        if pair is not None:
            # one interval for every element (a product's four bounds are symmetric)
            full, one = pair
            lo, hi = _product_bounds_one(
                _flat(full.lo), _flat(full.hi), float(one.lo.flat[0]), float(one.hi.flat[0])
            )
            return Interval(lo.reshape(full.lo.shape), hi.reshape(full.lo.shape))
        shape = np.broadcast_shapes(*(x.shape for x in parts))

        def flat(x: Array) -> Array:
            # read-only views or copies: the kernel only reads them
            return np.ascontiguousarray(np.broadcast_to(x, shape)).reshape(-1)

        lo, hi = _product_bounds(flat(self.lo), flat(self.hi), flat(o.lo), flat(o.hi))
        return Interval(lo.reshape(shape), hi.reshape(shape))

    __rmul__ = __mul__

    def __truediv__(self, other: IntervalLike) -> Interval:
        o = as_interval(other)
        straddles = (o.lo <= 0) & (o.hi >= 0)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            inv_lo = np.where(straddles, -_INF, widen_down(1.0 / o.hi))
            inv_hi = np.where(straddles, _INF, widen_up(1.0 / o.lo))
        return self * Interval(inv_lo, inv_hi)

    def __rtruediv__(self, other: IntervalLike) -> Interval:
        return as_interval(other) / self

    def __pow__(self, n: int) -> Interval:
        """``x ** n`` for an integer ``n`` (see :func:`power`)."""
        if isinstance(n, bool) or not isinstance(n, int | np.integer):
            return NotImplemented
        return power(self, int(n))


IntervalLike = Interval | ArrayLike


def as_interval(x: IntervalLike) -> Interval:
    """An interval from an :class:`Interval` or from exact numbers (degenerate intervals)."""
    if isinstance(x, Interval):
        return x
    return Interval(x, x)


def hull(a: Interval, b: Interval) -> Interval:
    """The smallest intervals holding both ``a`` and ``b``."""
    return Interval(np.minimum(a.lo, b.lo), np.maximum(a.hi, b.hi))


def square(x: IntervalLike) -> Interval:
    """``x ** 2``, tighter than ``x * x`` when ``x`` straddles zero."""
    x = as_interval(x)
    xx = x * x
    straddles = (x.lo <= 0) & (x.hi >= 0)
    return Interval(np.where(straddles, 0.0, np.maximum(xx.lo, 0.0)), xx.hi)


def sqrt(x: IntervalLike) -> Interval:
    """Square root of the non-negative part of each interval (``nan`` where empty)."""
    x = as_interval(x)
    with np.errstate(invalid="ignore"):
        lo = np.where(x.lo <= 0, 0.0, widen_down(np.sqrt(np.maximum(x.lo, 0.0))))
        hi = np.where(x.hi < 0, np.nan, widen_up(np.sqrt(np.maximum(x.hi, 0.0))))
    return Interval(np.maximum(lo, 0.0), hi)


@kernel
def _holds_angle(lo: float, hi: float, phase: float) -> bool:  # pragma: no cover - compiled
    """Whether ``[lo, hi]`` may contain an angle ``phase + 2 k pi`` (conservative)."""
    # the quotient's rounding error grows with |x|: the margin is relative
    tol = 1e-12 * max(1.0, max(abs(lo), abs(hi)))
    k = np.ceil((lo - tol - phase) / _TWO_PI)
    return phase + k * _TWO_PI <= hi + tol


@kernel
def _holds_angles(lo: Array, hi: Array, phase: Array) -> NDArray[np.bool_]:  # pragma: no cover
    out = np.empty(lo.size, dtype=np.bool_)
    for i in range(lo.size):
        out[i] = _holds_angle(lo[i], hi[i], phase[i])
    return out


#: the rounding steps, public for the compiled code of the mechanisms (the same
#: kernels, so the same floats as the Interval operations): ``x`` moved down by
#: ``|x| * rel + tiny``, by one ulp (or a few) without jumps on the data, and
#: whether an interval may contain an angle ``phase + 2 k pi``
move_below = _below
step_down = _down
holds_angle = _holds_angle

def may_contain_angle(x: Interval, phase: float | NDArray[np.float64]) -> NDArray[np.bool_]:
    """Whether each ``[lo, hi]`` may contain an angle ``phase + 2 k pi`` (conservative).

    Examples
    --------
    >>> may_contain_angle(Interval([6.0, 0.5], [6.5, 1.0]), 0.0).tolist()
    [True, False]
    """
    shape, (lo, hi, ph) = flat_arrays(x.lo, x.hi, phase)
    return _holds_angles(lo, hi, ph).reshape(shape)


@kernel(inline=True)
def trig_ends(
    fa: float, fb: float, a: float, b: float, sine: bool, rel: float, tiny: float
) -> tuple[float, float]:  # pragma: no cover - compiled
    """One element of :func:`_trig_bounds` from the values ``fa``, ``fb`` of ``sin``
    (or ``cos``) at the ends of ``[a, b]``, for compiled code (inlined: the same
    floats)."""
    top = 0.5 * np.pi if sine else 0.0
    bottom = -0.5 * np.pi if sine else np.pi
    if fa != fa or fb != fb:
        low = np.nan
        high = np.nan
    else:
        low = min(fa, fb)
        high = max(fa, fb)
    wide = b - a >= _TWO_PI
    if wide or _holds_angle(a, b, bottom):
        low = -1.0
    else:
        low = _below(low, rel, tiny, False)
    if wide or _holds_angle(a, b, top):
        high = 1.0
    else:
        high = _above(high, rel, tiny, False)
    return (low if low != low else max(low, -1.0)), (high if high != high else min(high, 1.0))


@kernel(inline=True)
def trig_one(
    a: float, b: float, sine: bool, rel: float, tiny: float
) -> tuple[float, float]:  # pragma: no cover - compiled
    """One element of :func:`_trig_bounds`: the range of ``sin`` (or ``cos``) over
    ``[a, b]``, for compiled code (inlined: the same floats)."""
    fa = np.sin(a) if sine else np.cos(a)
    fb = np.sin(b) if sine else np.cos(b)
    return trig_ends(fa, fb, a, b, sine, rel, tiny)


@kernel
def _trig_bounds(
    lo: Array, hi: Array, sine: bool, rel: float, tiny: float
) -> tuple[Array, Array]:  # pragma: no cover - compiled
    """Range of ``sin`` (or ``cos``) over each ``[lo[i], hi[i]]``: the values at the
    ends widened outwards, or -1 / 1 where the interval may hold a minimum /
    maximum (or spans a turn); NaN where an end gives NaN and no extremum."""
    n = lo.size
    out_lo = np.empty(n)
    out_hi = np.empty(n)
    for i in range(n):
        out_lo[i], out_hi[i] = trig_one(lo[i], hi[i], sine, rel, tiny)
    return out_lo, out_hi


#: the cosine (``sine=False``) or sine bounds of angle enclosures, public for the
#: compiled code of the mechanisms (the same kernel, so the same floats)
trig_bounds = _trig_bounds


def _trig(x: Interval, sine: bool) -> Interval:
    lo, hi = np.broadcast_arrays(x.lo, x.hi)
    shape = lo.shape
    out_lo, out_hi = _trig_bounds(
        np.ascontiguousarray(lo).reshape(-1),
        np.ascontiguousarray(hi).reshape(-1),
        sine,
        _rel(_LIB_ULPS),
        _LIB_ULPS * _TINY,
    )
    return Interval(out_lo.reshape(shape), out_hi.reshape(shape))


def cos(x: IntervalLike) -> Interval:
    """Cosine: exact range of ``cos`` over each interval, widened outwards."""
    return _trig(as_interval(x), sine=False)


def sin(x: IntervalLike) -> Interval:
    """Sine: exact range of ``sin`` over each interval, widened outwards."""
    return _trig(as_interval(x), sine=True)


@kernel
def point_sin_cos(a: float) -> tuple[float, float, float, float]:  # pragma: no cover
    """:func:`sin` and :func:`cos` of the interval ``[a, a]``, for compiled code:
    the steps of :func:`_trig_bounds` with ``lo = hi``, one libm call per function
    (tests/mechanisms/test_tape.py compares them bit for bit). Returns the bounds
    of the sine, then of the cosine."""
    rel = _LIB_REL
    tiny = _LIB_TINY
    s_lo = 0.0
    s_hi = 0.0
    c_lo = 0.0
    c_hi = 0.0
    for sine in (True, False):
        fa = np.sin(a) if sine else np.cos(a)
        low, high = trig_ends(fa, fa, a, a, sine, rel, tiny)
        if sine:
            s_lo = low
            s_hi = high
        else:
            c_lo = low
            c_hi = high
    return s_lo, s_hi, c_lo, c_hi


#: the widening of the library functions' results, for compiled code
_LIB_REL = _rel(_LIB_ULPS)
_LIB_TINY = _LIB_ULPS * _TINY


@kernel(inline=True)
def interval_cos(a: float, b: float) -> tuple[float, float]:  # pragma: no cover - compiled
    """One element of :func:`cos`: the bounds of the cosine over ``[a, b]``, for
    compiled code (the same floats)."""
    return trig_one(a, b, False, _LIB_REL, _LIB_TINY)


@kernel(inline=True)
def interval_sin(a: float, b: float) -> tuple[float, float]:  # pragma: no cover - compiled
    """One element of :func:`sin`: the bounds of the sine over ``[a, b]``, for
    compiled code (the same floats)."""
    return trig_one(a, b, True, _LIB_REL, _LIB_TINY)


# one-element steps of the Interval operations, for the compiled code of the
# mechanisms (inlined: the same floats as the Interval code)
@kernel(inline=True)
def bound_above(x: float) -> float:  # pragma: no cover - compiled
    """An upper bound moved up by one ulp (or a few): ``-step_down(-x)``."""
    return -_down(-x, False)


@kernel(inline=True)
def lib_below(x: float) -> float:  # pragma: no cover - compiled
    """``widen_down(x, _LIB_ULPS)``: a library function's lower bound."""
    return _below(x, _LIB_REL, _LIB_TINY, False)


@kernel(inline=True)
def lib_above(x: float) -> float:  # pragma: no cover - compiled
    """``widen_up(x, _LIB_ULPS)``: a library function's upper bound."""
    return -_below(-x, _LIB_REL, _LIB_TINY, False)


@kernel(inline=True)
def nan_max(a: float, b: float) -> float:  # pragma: no cover - compiled
    """``np.maximum`` of two floats: NaN if either is, else ``a`` when ``a >= b``."""
    return np.nan if ((a != a) | (b != b)) else (a if a >= b else b)


@kernel(inline=True)
def nan_min(a: float, b: float) -> float:  # pragma: no cover - compiled
    """``np.minimum`` of two floats: NaN if either is, else ``a`` when ``a <= b``."""
    return np.nan if ((a != a) | (b != b)) else (a if a <= b else b)


@kernel(inline=True)
def reciprocal(x: float) -> float:  # pragma: no cover - compiled
    """``1.0 / x`` as numpy rounds it, an infinity of the zero's sign for a zero
    (compiled code would raise)."""
    return np.copysign(np.inf, x) if x == 0.0 else 1.0 / x


@kernel(inline=True)
def interval_div(
    a_lo: float, a_hi: float, b_lo: float, b_hi: float
) -> tuple[float, float]:  # pragma: no cover - compiled
    """``Interval.__truediv__``: the product with ``[1 / hi, 1 / lo]`` rounded
    outwards, or with the whole line where the divisor may vanish."""
    straddles = (b_lo <= 0) & (b_hi >= 0)
    i_lo = -np.inf if straddles else _down(reciprocal(b_hi), False)
    i_hi = np.inf if straddles else bound_above(reciprocal(b_lo))
    return interval_mul(a_lo, a_hi, i_lo, i_hi)


@kernel(inline=True)
def interval_square(lo: float, hi: float) -> tuple[float, float]:  # pragma: no cover
    """``square``: ``x * x``, from 0 where ``x`` straddles 0."""
    s_lo, s_hi = interval_mul(lo, hi, lo, hi)
    straddles = (lo <= 0) & (hi >= 0)
    return (0.0 if straddles else nan_max(s_lo, 0.0)), s_hi


@kernel(inline=True)
def interval_sqrt(lo: float, hi: float) -> tuple[float, float]:  # pragma: no cover
    """``sqrt``: the square root of the non-negative part; NaN above where there
    is none."""
    low = 0.0 if lo <= 0 else _down(np.sqrt(nan_max(lo, 0.0)), False)
    high = np.nan if hi < 0 else bound_above(np.sqrt(nan_max(hi, 0.0)))
    return nan_max(low, 0.0), high


@kernel
def slot_div(lo: Array, hi: Array, a: Slot, b: Slot, o: Slot, w: int) -> None:  # pragma: no cover
    """Slot ``o`` = slot ``a`` / slot ``b`` (``Interval.__truediv__``), element by
    element by :func:`interval_div` (``o`` may be ``a`` or ``b``)."""
    for j in range(w):
        o_lo_j, o_hi_j = interval_div(lo[a, j], hi[a, j], lo[b, j], hi[b, j])
        lo[o, j], hi[o, j] = o_lo_j, o_hi_j


@kernel(inline=True)
def atan_bounds(lo: float, hi: float, cut: bool) -> tuple[float, float]:  # pragma: no cover
    """One element of :func:`arctan2` from the least and greatest arctan2 of the
    corners: widened, the whole ``[-pi, pi]`` where the box meets the cut."""
    low = -_PI_UP if cut else lib_below(lo)
    high = _PI_UP if cut else lib_above(hi)
    return nan_max(low, -_PI_UP), nan_min(high, _PI_UP)


def arccos(x: IntervalLike) -> Interval:
    """Arc cosine of the part of each interval inside ``[-1, 1]`` (decreasing)."""
    x = as_interval(x)
    lo_arg = np.clip(x.hi, -1.0, 1.0)
    hi_arg = np.clip(x.lo, -1.0, 1.0)
    lo = np.maximum(widen_down(np.arccos(lo_arg), _LIB_ULPS), 0.0)
    hi = np.minimum(widen_up(np.arccos(hi_arg), _LIB_ULPS), _PI_UP)
    return Interval(lo, hi)


def arctan2(y: IntervalLike, x: IntervalLike) -> Interval:
    """Angle of the points of the box ``y x x``, as an interval within ``[-pi, pi]``.

    Where the box contains the origin or crosses the negative x axis (the
    cut of ``atan2``), the result is the whole ``[-pi, pi]``.
    """
    y, x = as_interval(y), as_interval(x)
    corners = np.stack(
        [
            np.arctan2(y.lo, x.lo),
            np.arctan2(y.lo, x.hi),
            np.arctan2(y.hi, x.lo),
            np.arctan2(y.hi, x.hi),
        ]
    )
    lo = widen_down(corners.min(axis=0), _LIB_ULPS)
    hi = widen_up(corners.max(axis=0), _LIB_ULPS)
    # the angle is monotone in each coordinate on boxes that avoid the cut
    # and the origin, so the corners give its range there
    cut = (x.lo <= 0) & (y.lo <= 0) & (y.hi >= 0)
    lo = np.maximum(np.where(cut, -_PI_UP, lo), -_PI_UP)
    hi = np.minimum(np.where(cut, _PI_UP, hi), _PI_UP)
    return Interval(lo, hi)


# ------------------------------------------------------------------------------
# Further functions, for constraints written as expressions (see
# moveability.mechanisms.expressions). Each returns an enclosure of the exact
# range; where the function is undefined or unbounded on part of an interval
# the result is infinite on that side.


def power(x: IntervalLike, n: int) -> Interval:
    """``x ** n`` for an integer ``n`` (``1 / x ** -n`` when ``n < 0``).

    The float power is widened by ``|n| + 4`` ulps (each of its at most ``|n|``
    roundings is below one ulp).

    Examples
    --------
    >>> r = power(Interval([-2.0], [1.0]), 3)
    >>> bool(r.lo[0] <= -8.0 and 1.0 <= r.hi[0])
    True
    >>> power(Interval([-2.0], [1.0]), 2).lo.tolist()
    [0.0]
    """
    x = as_interval(x)
    n = int(n)
    if n == 0:
        return Interval(np.ones_like(x.lo))
    if n < 0:
        return as_interval(1.0) / power(x, -n)
    if n == 1:
        return x
    if n == 2:
        return square(x)
    ulps = n + 4
    with np.errstate(over="ignore"):
        if n % 2:
            # odd powers are increasing
            lo = widen_down(np.power(x.lo, n), ulps)
            hi = widen_up(np.power(x.hi, n), ulps)
            return Interval(lo, hi)
        a, b = np.abs(x.lo), np.abs(x.hi)
        small, large = np.minimum(a, b), np.maximum(a, b)
        straddles = (x.lo <= 0) & (x.hi >= 0)
        lo = np.where(straddles, 0.0, widen_down(np.power(small, n), ulps))
        hi = widen_up(np.power(large, n), ulps)
    return Interval(np.maximum(lo, 0.0), hi)


def exp(x: IntervalLike) -> Interval:
    """Exponential (increasing).

    Examples
    --------
    >>> r = exp(Interval([0.0], [1.0]))
    >>> bool(r.lo[0] <= 1.0 and 2.718281828459045 <= r.hi[0])
    True
    """
    x = as_interval(x)
    with np.errstate(over="ignore"):
        lo = np.maximum(widen_down(np.exp(x.lo), _LIB_ULPS), 0.0)
        hi = widen_up(np.exp(x.hi), _LIB_ULPS)
    return Interval(lo, hi)


def log(x: IntervalLike) -> Interval:
    """Natural logarithm of the positive part of each interval (increasing).

    ``-inf`` as the lower bound where the interval reaches 0 or below; ``nan``
    bounds where it holds no positive number.

    Examples
    --------
    >>> r = log(Interval([1.0], [np.e]))
    >>> bool(r.lo[0] <= 0.0 and 1.0 <= r.hi[0])
    True
    """
    x = as_interval(x)
    with np.errstate(invalid="ignore", divide="ignore"):
        lo = np.where(x.lo <= 0, -_INF, widen_down(np.log(np.maximum(x.lo, 0.0)), _LIB_ULPS))
        hi = np.where(x.hi <= 0, np.nan, widen_up(np.log(np.maximum(x.hi, 0.0)), _LIB_ULPS))
    lo = np.where(x.hi <= 0, np.nan, lo)
    return Interval(lo, hi)


def tan(x: IntervalLike) -> Interval:
    """Tangent; the whole real line where the interval may hold a pole.

    Examples
    --------
    >>> r = tan(Interval([0.0, 1.0], [0.5, 2.0]))
    >>> bool(r.lo[0] <= 0.0 and 0.5463 <= r.hi[0]), float(r.hi[1])
    (True, inf)
    """
    x = as_interval(x)
    with np.errstate(over="ignore", invalid="ignore"):
        wide = (x.hi - x.lo) >= np.pi
    # poles at pi/2 + k pi
    pole = wide | may_contain_angle(x, 0.5 * np.pi) | may_contain_angle(x, -0.5 * np.pi)
    pole |= ~np.isfinite(x.lo) | ~np.isfinite(x.hi)
    with np.errstate(invalid="ignore"):
        lo = widen_down(np.tan(x.lo), _LIB_ULPS)
        hi = widen_up(np.tan(x.hi), _LIB_ULPS)
    return Interval(np.where(pole, -_INF, lo), np.where(pole, _INF, hi))


def absolute(x: IntervalLike) -> Interval:
    """``|x|`` (exact: no rounding).

    Examples
    --------
    >>> absolute(Interval([-2.0, 1.0], [1.0, 3.0])).lo.tolist()
    [0.0, 1.0]
    """
    x = as_interval(x)
    a, b = np.abs(x.lo), np.abs(x.hi)
    straddles = (x.lo <= 0) & (x.hi >= 0)
    return Interval(np.where(straddles, 0.0, np.minimum(a, b)), np.maximum(a, b))


def rational(p: int, q: int) -> Interval:
    """The tightest interval of floats holding the rational number ``p / q``.

    Examples
    --------
    >>> third = rational(1, 3)
    >>> bool(third.lo < third.hi and third.lo <= 1 / 3 <= third.hi)
    True
    >>> rational(1, 4).lo.tolist(), rational(1, 4).hi.tolist()
    (0.25, 0.25)
    """
    from fractions import Fraction

    exact = Fraction(int(p), int(q))
    near = float(exact)
    lo = near if Fraction(near) <= exact else float(np.nextafter(near, -_INF))
    hi = near if Fraction(near) >= exact else float(np.nextafter(near, _INF))
    return Interval(np.float64(lo), np.float64(hi))
