"""Compiled interval enclosures of the 3-RPR: det A, the rows of A and their
partials, the legs' lengths and joint gradients over boxes of poses.

Each kernel computes what :class:`~.three_rpr.ThreeRPR` and
:class:`~.three_rpr.RPRLeg` compute with :class:`~moveability.intervals.Interval`
operations: the same operations on the same operands in the same order, each
rounded outwards by the compiled primitives of :mod:`moveability.intervals`
that the Interval operators apply element by element (``mul_into``,
``add_into``, ``sub_into``, ``interval_mul``, ``interval_sub``, ``next_below``
and ``point_sin_cos``; the cosine and sine of the boxes' phi come from
``intervals.cos`` and ``sin``, one compiled pass each, or element by element
in :func:`pose_bounds`: ``interval_cos``, ``interval_sin``). The bounds are
thus the same floats, bit for bit (tests/mechanisms/test_three_rpr_kernels.py
compares them on random boxes of every kind), computed chunk by chunk in
scratch that stays in cache, with no array allocated per operation and no
Python between the operations.

A leg enters as ``(A_x, A_y, b_x, b_y)``: its base joint and its platform joint
in the platform frame. Boxes of poses are (n, 3) C-contiguous arrays ``lo``,
``hi`` of ``(x, y, phi)``, with ``trig`` (4, n): the bounds of the cosine of
their phi, then of its sine (``intervals.cos`` and ``sin``), or (4, 0)
(:data:`NO_TRIG`): the kernel computes them itself, box by box (the same
floats), as :func:`pose_bounds` always does.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..compiled import kernel
from ..intervals import (
    Slot,
    interval_cos,
    interval_mul,
    interval_sin,
    next_below,
    point_sin_cos,
    reciprocal,
    slot_add,
    slot_det3,
    slot_mul,
    slot_mul_c,
    slot_negate,
    slot_sub,
    slot_sub_c,
)
from ..types import Array

__all__ = [
    "det_a_bounds",
    "joint_gradient_bounds",
    "pose_bounds",
    "reach_bounds",
    "row_bounds",
]


#: the entries of one leg in :func:`row_bounds`: the row (dx, dy, turn), then
#: the partials that are not constants (-rby, rbx, -(rbx px + rby py))
ROW_ITEMS = 6


@kernel(inline=True)
def _up(x: float) -> float:  # pragma: no cover - compiled
    """An upper bound moved up as :func:`~moveability.intervals.next_below` moves a
    lower bound down (``intervals._above`` by one ulp: ``-_below(-x)``)."""
    return -next_below(-x)


@kernel(inline=True)
def _max(a: float, b: float) -> float:  # pragma: no cover - compiled
    """``np.maximum`` of two floats: NaN if either is, else ``a`` when ``a >= b``."""
    return a if (a >= b or a != a) else b


@kernel(inline=True)
def _min(a: float, b: float) -> float:  # pragma: no cover - compiled
    """``np.minimum`` of two floats: NaN if either is, else ``a`` when ``a <= b``."""
    return a if (a <= b or a != a) else b


# ------------------------------------------------------------------ passes
# A kernel works chunk by chunk: each quantity of a chunk's boxes is a row (a
# "slot") of two scratch arrays ``lo``, ``hi`` (slots x _CHUNK), and each
# interval operation one compiled loop over the chunk's boxes (mul_into and the
# like: the same rounding as the Interval operators, element by element).

#: boxes per chunk: the scratch (about 50 slots, 2 x 8 bytes a box each) stays in cache
_CHUNK = 256


@kernel
def _load(
    lo: Array,
    hi: Array,
    box_lo: Array,
    box_hi: Array,
    trig: Array,
    s: int,
    w: int,
    x: Slot,
    c: Slot,
) -> None:  # pragma: no cover - compiled
    """The boxes ``s:s + w``: their coordinates into slots ``x``, ``x + 1``, ``x +
    2``, the cosine and sine of their phi into slots ``c``, ``c + 1``: from
    ``trig`` ((4, n): the bounds of the cosine then of the sine), or computed here
    when ``trig`` holds no column ((4, 0): ``interval_cos`` and ``interval_sin``,
    the elements of ``intervals.cos`` and ``sin``)."""
    given = trig.shape[1] > 0
    for j in range(w):
        for axis in range(3):
            lo[x + axis, j] = box_lo[s + j, axis]
            hi[x + axis, j] = box_hi[s + j, axis]
        if given:
            lo[c, j], hi[c, j] = trig[0, s + j], trig[1, s + j]
            lo[c + 1, j], hi[c + 1, j] = trig[2, s + j], trig[3, s + j]
        else:
            a, b = box_lo[s + j, 2], box_hi[s + j, 2]
            lo[c, j], hi[c, j] = interval_cos(a, b)
            lo[c + 1, j], hi[c + 1, j] = interval_sin(a, b)


#: the ``trig`` of the kernels that compute the cosine and sine themselves
NO_TRIG = np.empty((4, 0))


#: the ``partials`` of :func:`_leg`: none; none and no turn either
_NONE, _TARGET = -1, -2


@kernel
def _leg(
    lo: Array,
    hi: Array,
    x: Slot,
    c: Slot,
    ab: Array,
    row: Slot,
    partials: Slot,
    t: Slot,
    w: int,
) -> None:  # pragma: no cover - compiled
    """One leg over the chunk, as ``RPRLeg._target_boxes``, ``a_row_boxes`` and
    ``a_row_derivatives`` compute it, from the pose in slots ``x, x + 1`` (x, y)
    and the cosine and sine of phi in ``c, c + 1``, with ``ab`` = (A_x, A_y,
    b_x, b_y): the row ``dx, dy, rbx py - rby px`` into slots ``row .. row + 2``;
    when ``partials >= 0``, ``-rby, rbx, -(rbx px + rby py)`` into ``partials ..
    partials + 2``; when ``partials`` is ``_TARGET`` (-2), ``dx, dy`` alone.
    Slots ``t .. t + 5`` are scratch."""
    ax, ay, bx, by = ab[0], ab[1], ab[2], ab[3]
    p, q, rbx, rby, px, py = t, t + 1, t + 2, t + 3, t + 4, t + 5
    # R(phi) b: rbx = c bx - s by, rby = s bx + c by
    slot_mul_c(lo, hi, c, bx, bx, p, w)
    slot_mul_c(lo, hi, c + 1, by, by, q, w)
    slot_sub(lo, hi, p, q, rbx, w)
    slot_mul_c(lo, hi, c + 1, bx, bx, p, w)
    slot_mul_c(lo, hi, c, by, by, q, w)
    slot_add(lo, hi, p, q, rby, w)
    # d = (P + R b) - A
    slot_add(lo, hi, x, rbx, row, w)
    slot_sub_c(lo, hi, row, ax, ax, row, w)
    slot_add(lo, hi, x + 1, rby, row + 1, w)
    slot_sub_c(lo, hi, row + 1, ay, ay, row + 1, w)
    if partials == _TARGET:
        return
    # the turn (R b) x (P - A)
    slot_sub_c(lo, hi, x, ax, ax, px, w)
    slot_sub_c(lo, hi, x + 1, ay, ay, py, w)
    slot_mul(lo, hi, rbx, py, p, w)
    slot_mul(lo, hi, rby, px, q, w)
    slot_sub(lo, hi, p, q, row + 2, w)
    if partials < 0:
        return
    slot_negate(lo, hi, rby, partials, w)
    lo[partials + 1, :w] = lo[rbx, :w]
    hi[partials + 1, :w] = hi[rbx, :w]
    slot_mul(lo, hi, rbx, px, p, w)
    slot_mul(lo, hi, rby, py, q, w)
    slot_add(lo, hi, p, q, partials + 2, w)
    slot_negate(lo, hi, partials + 2, partials + 2, w)


@kernel
def _length(
    s_lo: Array,
    s_hi: Array,
    row: Slot,
    sq: Slot,
    s: int,
    size: int,
    out_lo: Array,
    out_hi: Array,
) -> None:  # pragma: no cover - compiled
    """The length ``sqrt(dx^2 + dy^2)`` of a leg whose ``dx, dy`` are in slots ``row,
    row + 1``, into ``out[s:s + size]``, as ``intervals.square`` and ``sqrt`` give
    it (slots ``sq, sq + 1`` are scratch)."""
    # squares: x * x, from 0 where x straddles 0
    for e in range(2):
        slot_mul(s_lo, s_hi, row + e, row + e, sq + e, size)
        for j in range(size):
            straddles = s_lo[row + e, j] <= 0 and s_hi[row + e, j] >= 0
            s_lo[sq + e, j] = 0.0 if straddles else _max(s_lo[sq + e, j], 0.0)
    slot_add(s_lo, s_hi, sq, sq + 1, sq, size)
    for j in range(size):
        # the square root of the non-negative part; NaN above where there is none
        r_lo, r_hi = s_lo[sq, j], s_hi[sq, j]
        low = 0.0 if r_lo <= 0 else next_below(np.sqrt(_max(r_lo, 0.0)))
        high = np.nan if r_hi < 0 else _up(np.sqrt(_max(r_hi, 0.0)))
        out_lo[s + j] = _max(low, 0.0)
        out_hi[s + j] = high


@kernel
def _mul_known(
    lo: Array, hi: Array, a: Slot, b: Slot, o: Slot, w: int, one: Slot, zero: Slot
) -> None:  # pragma: no cover - compiled
    """``slot_mul`` where a factor may be the constant slot ``one`` ([1, 1]) or
    ``zero`` ([0, 0]): a product with ``[0, 0]`` is ``[0.0, 0.0]`` whatever the
    other factor (each bound product is a zero, or NaN taken as 0; none is an
    underflow), and one with ``[1, 1]`` is ``interval_mul`` with the constant
    known (its products exact): the floats of ``slot_mul``, with less work."""
    if a == zero or b == zero:
        for j in range(w):
            lo[o, j] = 0.0
            hi[o, j] = 0.0
    elif a == one:
        for j in range(w):
            lo[o, j], hi[o, j] = interval_mul(1.0, 1.0, lo[b, j], hi[b, j])
    elif b == one:
        for j in range(w):
            lo[o, j], hi[o, j] = interval_mul(lo[a, j], hi[a, j], 1.0, 1.0)
    else:
        slot_mul(lo, hi, a, b, o, w)


@kernel
def _det3_known(
    lo: Array, hi: Array, m: NDArray[np.int64], o: Slot, t: Slot, w: int, one: Slot, zero: Slot
) -> None:  # pragma: no cover - compiled
    """``intervals.slot_det3`` (the same steps) with its products by
    :func:`_mul_known`, for matrices holding the slots ``one`` and ``zero``."""
    p, q = t, t + 1
    _mul_known(lo, hi, m[4], m[8], p, w, one, zero)
    _mul_known(lo, hi, m[5], m[7], q, w, one, zero)
    slot_sub(lo, hi, p, q, p, w)
    _mul_known(lo, hi, m[0], p, o, w, one, zero)
    _mul_known(lo, hi, m[3], m[8], p, w, one, zero)
    _mul_known(lo, hi, m[5], m[6], q, w, one, zero)
    slot_sub(lo, hi, p, q, p, w)
    _mul_known(lo, hi, m[1], p, q, w, one, zero)
    slot_sub(lo, hi, o, q, o, w)
    _mul_known(lo, hi, m[3], m[7], p, w, one, zero)
    _mul_known(lo, hi, m[4], m[6], q, w, one, zero)
    slot_sub(lo, hi, p, q, p, w)
    _mul_known(lo, hi, m[2], p, q, w, one, zero)
    slot_add(lo, hi, o, q, o, w)


# the slots of det_a_bounds
_X, _C, _MX, _MC = 0, 3, 5, 8  # box (x, y, phi), its cos, sin; the same at the centre
_ROWS, _MROWS, _PARTS = 10, 19, 28  # leg k's row at + 3 k; its partials at _PARTS + 3 k
_ONE, _ZERO = 37, 38
_NAT, _TOT, _SUM, _TERM, _WIDTH = 39, 40, 41, 42, 43
_TEMP = 44  # 6 slots of scratch
_SLOTS = 50


@kernel
def _rows(
    s_lo: Array,
    s_hi: Array,
    lo: Array,
    hi: Array,
    s: int,
    size: int,
    legs: Array,
    rows: NDArray[np.int64],
    centre: NDArray[np.int64],
) -> None:  # pragma: no cover - compiled
    """For :func:`det_a_bounds`, from the chunk's boxes ``s:s + size`` loaded (with
    their cosine and sine): the centres and their cosine and sine, then each leg's
    row and partials over the box, and its row at the centre."""
    x, c, mx, mc, temp = np.int64(_X), np.int64(_C), np.int64(_MX), np.int64(_MC), np.int64(_TEMP)
    for j in range(size):
        for axis in range(3):
            # as numpy rounds 0.5 * (lo + hi)
            m = 0.5 * (lo[s + j, axis] + hi[s + j, axis])
            s_lo[mx + axis, j] = m
            s_hi[mx + axis, j] = m
        # the sine, then the cosine, of [m, m]
        sl, sh, cl, ch = point_sin_cos(s_lo[mx + 2, j])
        s_lo[mc, j], s_hi[mc, j], s_lo[mc + 1, j], s_hi[mc + 1, j] = cl, ch, sl, sh
    for k in range(3):
        part = np.int64(_PARTS) + 3 * k
        _leg(s_lo, s_hi, x, c, legs[k], rows[3 * k], part, temp, size)
        _leg(s_lo, s_hi, mx, mc, legs[k], centre[3 * k], np.int64(_NONE), temp, size)


@kernel
def _det(
    s_lo: Array,
    s_hi: Array,
    s: int,
    size: int,
    rows: NDArray[np.int64],
    centre: NDArray[np.int64],
    matrix: NDArray[np.int64],
    out_lo: Array,
    out_hi: Array,
) -> None:  # pragma: no cover - compiled
    """For :func:`det_a_bounds`, from the slots :func:`_rows` fills: det A over the
    chunk's boxes into ``out[s:s + size]``."""
    x, mx, one, zero = np.int64(_X), np.int64(_MX), np.int64(_ONE), np.int64(_ZERO)
    nat, tot, total = np.int64(_NAT), np.int64(_TOT), np.int64(_SUM)
    term, width, temp = np.int64(_TERM), np.int64(_WIDTH), np.int64(_TEMP)
    slot_det3(s_lo, s_hi, rows, nat, temp, size)
    slot_det3(s_lo, s_hi, centre, tot, temp, size)
    for axis in range(3):
        for k in range(3):
            # the rows with leg k's differentiated along the axis: along x
            # (1, 0, -rby), along y (0, 1, rbx), along phi (-rby, rbx, spin)
            matrix[:] = rows
            part = np.int64(_PARTS) + 3 * k
            if axis == 0:
                matrix[3 * k], matrix[3 * k + 1], matrix[3 * k + 2] = one, zero, part
            elif axis == 1:
                matrix[3 * k], matrix[3 * k + 1], matrix[3 * k + 2] = zero, one, part + 1
            else:
                matrix[3 * k], matrix[3 * k + 1], matrix[3 * k + 2] = part, part + 1, part + 2
            if k == 0:
                _det3_known(s_lo, s_hi, matrix, total, temp, size, one, zero)
            else:
                _det3_known(s_lo, s_hi, matrix, term, temp, size, one, zero)
                slot_add(s_lo, s_hi, total, term, total, size)
        # + dD/dx_j * (x_j - c_j)
        slot_sub(s_lo, s_hi, x + axis, mx + axis, width, size)
        slot_mul(s_lo, s_hi, total, width, term, size)
        slot_add(s_lo, s_hi, tot, term, tot, size)
    for j in range(size):
        out_lo[s + j] = _max(s_lo[nat, j], s_lo[tot, j])
        out_hi[s + j] = _min(s_hi[nat, j], s_hi[tot, j])


@kernel
def _scratch() -> tuple[
    Array, Array, NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]
]:  # pragma: no cover - compiled
    """A chunk's scratch (``_SLOTS`` x ``_CHUNK``, the constants 1 and 0 set), the
    slots of the rows over the box and at the centre as run-time integers (see
    Slot), and room for a determinant's nine slots."""
    s_lo, s_hi = np.empty((_SLOTS, _CHUNK)), np.empty((_SLOTS, _CHUNK))
    s_lo[_ONE], s_hi[_ONE] = 1.0, 1.0
    s_lo[_ZERO], s_hi[_ZERO] = 0.0, 0.0
    rows = np.arange(_ROWS, _ROWS + 9, dtype=np.int64)
    centre = np.arange(_MROWS, _MROWS + 9, dtype=np.int64)
    return s_lo, s_hi, rows, centre, np.empty(9, dtype=np.int64)


@kernel
def det_a_bounds(
    lo: Array, hi: Array, trig: Array, legs: Array, out_lo: Array, out_hi: Array
) -> None:  # pragma: no cover - compiled
    """``ThreeRPR.det_a_boxes`` of the (n, 3) boxes ``[lo, hi]`` into ``out``
    (n,), with ``legs`` (3, 4) the legs' (A_x, A_y, b_x, b_y): the natural
    enclosure of the 3 x 3 determinant of the rows intersected with the
    mean-value form about the centre ``c``, ``det(c) + sum_j dD/dx_j (x_j -
    c_j)``, where ``dD/dx_j`` is the sum of the three determinants with one row
    differentiated along ``x_j`` (leg 0's first)."""
    w = _CHUNK
    s_lo, s_hi, rows, centre, matrix = _scratch()
    n = lo.shape[0]
    for s in range(0, n, w):
        size = min(w, n - s)
        _load(s_lo, s_hi, lo, hi, trig, s, size, np.int64(_X), np.int64(_C))
        _rows(s_lo, s_hi, lo, hi, s, size, legs, rows, centre)
        _det(s_lo, s_hi, s, size, rows, centre, matrix, out_lo, out_hi)


@kernel
def pose_bounds(
    lo: Array,
    hi: Array,
    legs: Array,
    len_lo: Array,
    len_hi: Array,
    out_lo: Array,
    out_hi: Array,
) -> None:  # pragma: no cover - compiled
    """:func:`reach_bounds` of the three legs into ``len`` (3, n) and
    :func:`det_a_bounds` into ``out`` (n,) in one pass over the (n, 3) boxes: the
    cosine and sine of their phi computed once (``intervals.cos`` and ``sin``
    element by element), the legs' ``dx, dy`` (the first entries of their rows)
    shared. The same floats as those kernels, bit for bit."""
    w = _CHUNK
    s_lo, s_hi, rows, centre, matrix = _scratch()
    x, c, temp = np.int64(_X), np.int64(_C), np.int64(_TEMP)
    n = lo.shape[0]
    for s in range(0, n, w):
        size = min(w, n - s)
        _load(s_lo, s_hi, lo, hi, np.empty((4, 0)), s, size, x, c)
        _rows(s_lo, s_hi, lo, hi, s, size, legs, rows, centre)
        for k in range(3):
            _length(s_lo, s_hi, rows[3 * k], temp, s, size, len_lo[k], len_hi[k])
        _det(s_lo, s_hi, s, size, rows, centre, matrix, out_lo, out_hi)


@kernel
def row_bounds(
    lo: Array, hi: Array, trig: Array, legs: Array, out_lo: Array, out_hi: Array
) -> None:  # pragma: no cover - compiled
    """The rows of A over the (n, 3) boxes and their partials that are not
    constants, into ``out`` (3 * ROW_ITEMS, n): for leg ``k`` at ``ROW_ITEMS *
    k``, ``dx``, ``dy``, the turn (``a_row_boxes``), then ``-rby``, ``rbx`` and
    ``-(rbx px + rby py)`` (``a_row_derivatives``)."""
    w = _CHUNK
    # slots: x, y, phi; cos, sin; the legs' items; scratch
    x, c, items, temp = np.int64(0), np.int64(3), np.int64(5), np.int64(5 + 3 * ROW_ITEMS)
    s_lo, s_hi = np.empty((temp + 6, w)), np.empty((temp + 6, w))
    n = lo.shape[0]
    for s in range(0, n, w):
        size = min(w, n - s)
        _load(s_lo, s_hi, lo, hi, trig, s, size, x, c)
        for k in range(3):
            at = items + ROW_ITEMS * k
            _leg(s_lo, s_hi, x, c, legs[k], at, at + 3, temp, size)
        out_lo[:, s : s + size] = s_lo[items:temp, :size]
        out_hi[:, s : s + size] = s_hi[items:temp, :size]


@kernel
def joint_gradient_bounds(
    lo: Array,
    hi: Array,
    trig: Array,
    leg: Array,
    rho_lo: Array,
    rho_hi: Array,
    out_lo: Array,
    out_hi: Array,
) -> None:  # pragma: no cover - compiled
    """``RPRLeg.joint_gradient``: the row of the leg ``leg`` = (A_x, A_y, b_x,
    b_y) over the (n, 3) boxes divided by the length's enclosure ``[rho_lo,
    rho_hi]`` (n,), into ``out`` (3, n). The division is ``Interval.__truediv__``:
    the product with ``[1 / hi, 1 / lo]`` rounded outwards, or with the whole
    line where the length may vanish."""
    w = _CHUNK
    # slots: x, y, phi; cos, sin; the row; 1 / rho; scratch
    x, c, row, inv, temp = np.int64(0), np.int64(3), np.int64(5), np.int64(8), np.int64(9)
    s_lo, s_hi = np.empty((temp + 6, w)), np.empty((temp + 6, w))
    n = lo.shape[0]
    for s in range(0, n, w):
        size = min(w, n - s)
        _load(s_lo, s_hi, lo, hi, trig, s, size, x, c)
        _leg(s_lo, s_hi, x, c, leg, row, np.int64(_NONE), temp, size)
        for j in range(size):
            r_lo, r_hi = rho_lo[s + j], rho_hi[s + j]
            straddles = r_lo <= 0 and r_hi >= 0
            i_lo = next_below(reciprocal(r_hi))
            i_hi = _up(reciprocal(r_lo))
            s_lo[inv, j] = -np.inf if straddles else i_lo
            s_hi[inv, j] = np.inf if straddles else i_hi
        for e in range(3):
            slot_mul(s_lo, s_hi, row + e, inv, row + e, size)
        out_lo[:, s : s + size] = s_lo[row : row + 3, :size]
        out_hi[:, s : s + size] = s_hi[row : row + 3, :size]


@kernel
def reach_bounds(
    lo: Array, hi: Array, trig: Array, leg: Array, out_lo: Array, out_hi: Array
) -> None:  # pragma: no cover - compiled
    """``RPRLeg.reach``'s enclosure of the length ``sqrt(dx^2 + dy^2)`` of the leg
    ``leg`` = (A_x, A_y, b_x, b_y) over the (n, 3) boxes into ``out`` (n,), as
    ``intervals.square`` and ``sqrt`` give it."""
    w = _CHUNK
    # slots: x, y, phi; cos, sin; dx, dy (and the turn's slot, unused); dx^2, dy^2; scratch
    x, c, row, sq, temp = np.int64(0), np.int64(3), np.int64(5), np.int64(8), np.int64(10)
    s_lo, s_hi = np.empty((temp + 6, w)), np.empty((temp + 6, w))
    n = lo.shape[0]
    for s in range(0, n, w):
        size = min(w, n - s)
        _load(s_lo, s_hi, lo, hi, trig, s, size, x, c)
        _leg(s_lo, s_hi, x, c, leg, row, np.int64(_TARGET), temp, size)
        _length(s_lo, s_hi, row, sq, s, size, out_lo, out_hi)
