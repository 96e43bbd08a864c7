"""Compiled interval enclosures of the Delta: det A over boxes of poses, the
stacked rows and the sheet's mean-value form (``Delta.det_a_boxes``).

Each kernel computes what :class:`~.delta.Delta` and :class:`~.delta.DeltaLeg`
compute with :class:`~moveability.intervals.Interval` operations (kept there as
the reference, ``Delta._det_a_boxes_intervals``): the same operations on the
same operands in the same order, each rounded outwards by the compiled
primitives of :mod:`moveability.intervals` that the Interval operators apply
element by element (``mul_into`` and the slots' passes, ``interval_mul``,
``interval_add``, ``interval_sub``; ``next_below`` in its inlined form
``step_down``; the library functions' widening ``move_below`` with
``_rel(4)``; the cosines and sines of angle enclosures by ``intervals.trig_bounds``
itself). The bounds are thus the same floats, bit for bit
(tests/mechanisms/test_delta_kernels.py compares them on random boxes of every
kind). det A runs chunk by chunk, one vectorised pass per operation over the
chunk's boxes (the "slots" of :mod:`moveability.intervals`), the legs' ``g``
box by box: no array is allocated per operation and no Python runs between
the operations.

The library functions ``arccos``, ``arctan2`` and the ``cos`` and ``sin`` of a
box's direction from its centre are left to numpy, between the kernels (as in
:mod:`._rr_kernels`): numpy may evaluate them with its own vectorised code
(SVML), whose results differ from the C library's in the last bits, so they
are called on contiguous arrays of the same arguments as in the Interval code.
:func:`det_a_prepare` gives the stacked rows' enclosure of every box. The
mean-value form needs, at the centres of the boxes where every leg is regular
(:func:`regular_boxes`), the angles of the legs' branches: :func:`centre_args`
(the arguments of alpha's arccos and of the direction's arctan2),
:func:`centre_turn` (the box of the centre turned by its direction, whose
corners' arctan2 numpy takes), :func:`centre_angles` (the direction and alpha)
and :func:`centre_trig` (the cosines and sines of both branches' angles). None
of these depends on the posture: ``Delta`` keeps them for the last boxes, and
:func:`mean_value_bounds` computes the form for each posture.

A leg enters as a row of ``Delta``'s constants (its entries are named below):
the enclosures of its unit vector ``u`` and of ``r - R``, the arm, and the
constants of ``DeltaLeg._g_range``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..compiled import kernel
from ..intervals import (
    Slot,
    atan_bounds,
    interval_add,
    interval_div,
    interval_mul,
    interval_sqrt,
    interval_square,
    interval_sub,
    lib_above,
    lib_below,
    nan_max,
    nan_min,
    slot_add,
    slot_add_c,
    slot_c_sub,
    slot_det3,
    slot_div,
    slot_mul,
    slot_mul_c,
    slot_negate,
    slot_sub,
    slot_sub_c,
    trig_bounds,
)
from ..types import Array

__all__ = [
    "centre_angles",
    "centre_args",
    "centre_trig",
    "centre_turn",
    "det_a_all",
    "det_a_prepare",
    "intersect_finite",
    "mean_value_all",
    "mean_value_bounds",
    "regular_boxes",
]

# the entries of a leg's constants (Delta._leg_constants): the enclosures of u_x,
# u_y and of r - R, the arm la and 2 la, the enclosure of la^2 - lb^2, and that of
# 1 / la (as Interval.__truediv__ takes it)
(
    UX_LO, UX_HI, UY_LO, UY_HI, OFF_LO, OFF_HI, ARM, TWO_ARM, C_LO, C_HI, INV_LO, INV_HI,
    N_CONSTANTS,
) = range(13)  # fmt: skip

PI_UP = float(np.nextafter(np.pi, np.inf))
#: the smallest positive subnormal
_TINY = 5e-324
#: ``intervals._rel(4)`` and 4 ulps of ``_TINY``: the library functions' widening
LIB_REL = 5 * 2.0**-52
LIB_TINY = 4 * _TINY


# ------------------------------------------------------------------ one element
@kernel(inline=True)
def clip_mid(lo: float, hi: float) -> float:  # pragma: no cover - compiled
    """``Interval.mid``: ``np.clip(0.5 * lo + 0.5 * hi, lo, hi)``."""
    return nan_min(nan_max(0.5 * lo + 0.5 * hi, lo), hi)


@kernel(inline=True)
def plane(
    x_lo: float, x_hi: float, y_lo: float, y_hi: float, leg: Array
) -> tuple[float, float, float, float]:  # pragma: no cover - compiled
    """``DeltaLeg._plane_boxes``: ``s = x u_x + y u_y + (r - R)`` and ``d = y u_x -
    x u_y`` over a box of ``(x, y)``."""
    p_lo, p_hi = interval_mul(x_lo, x_hi, leg[UX_LO], leg[UX_HI])
    q_lo, q_hi = interval_mul(y_lo, y_hi, leg[UY_LO], leg[UY_HI])
    s_lo, s_hi = interval_add(p_lo, p_hi, q_lo, q_hi)
    s_lo, s_hi = interval_add(s_lo, s_hi, leg[OFF_LO], leg[OFF_HI])
    p_lo, p_hi = interval_mul(y_lo, y_hi, leg[UX_LO], leg[UX_HI])
    q_lo, q_hi = interval_mul(x_lo, x_hi, leg[UY_LO], leg[UY_HI])
    d_lo, d_hi = interval_sub(p_lo, p_hi, q_lo, q_hi)
    return s_lo, s_hi, d_lo, d_hi


@kernel(inline=True)
def _g_at(tv: float, dv: float, leg: Array) -> tuple[float, float]:  # pragma: no cover
    """``g`` of ``DeltaLeg._g_range`` at the numbers ``t``, ``d^2``:
    ``(square(t) + d^2 + c) / (t * 2 la)``."""
    a_lo, a_hi = interval_square(tv, tv)
    a_lo, a_hi = interval_add(a_lo, a_hi, dv, dv)
    a_lo, a_hi = interval_add(a_lo, a_hi, leg[C_LO], leg[C_HI])
    b_lo, b_hi = interval_mul(tv, tv, leg[TWO_ARM], leg[TWO_ARM])
    return interval_div(a_lo, a_hi, b_lo, b_hi)


@kernel
def _g_range(
    t_lo: float, t_hi: float, d_lo: float, d_hi: float, leg: Array
) -> tuple[float, float]:  # pragma: no cover - compiled
    """``DeltaLeg._g_range``: the bounds of ``g`` for ``t`` in ``[t_lo, t_hi]`` and
    ``d^2`` in ``[d_lo, d_hi]`` (the ends of ``t``, and the minimum inside where
    ``g`` is convex in ``t``); a NaN bound made infinite."""
    g_hi = nan_max(_g_at(t_lo, d_hi, leg)[1], _g_at(t_hi, d_hi, leg)[1])
    g_lo = nan_min(_g_at(t_lo, d_lo, leg)[0], _g_at(t_hi, d_lo, leg)[0])
    k_lo, k_hi = interval_add(d_lo, d_lo, leg[C_LO], leg[C_HI])
    r_lo, r_hi = interval_sqrt(k_lo, k_hi)
    if (k_lo > 0) & (r_lo <= t_hi) & (r_hi >= t_lo):
        g_lo = nan_min(g_lo, interval_mul(r_lo, r_hi, leg[INV_LO], leg[INV_HI])[0])
    g_lo = -np.inf if g_lo != g_lo else g_lo
    g_hi = np.inf if g_hi != g_hi else g_hi
    return g_lo, g_hi


@kernel
def g_boxes(
    x_lo: float,
    x_hi: float,
    y_lo: float,
    y_hi: float,
    z_lo: float,
    z_hi: float,
    leg: Array,
) -> tuple[float, float, float, float, float]:  # pragma: no cover - compiled
    """``DeltaLeg._g_boxes`` of one box: the bounds of ``g`` and the lower bound of
    ``t = sqrt(s^2 + z^2)``, then ``s`` (its bounds)."""
    s_lo, s_hi, d_lo, d_hi = plane(x_lo, x_hi, y_lo, y_hi, leg)
    a_lo, a_hi = interval_square(s_lo, s_hi)
    b_lo, b_hi = interval_square(z_lo, z_hi)
    a_lo, a_hi = interval_add(a_lo, a_hi, b_lo, b_hi)
    t_lo, t_hi = interval_sqrt(a_lo, a_hi)
    d2_lo, d2_hi = interval_square(d_lo, d_hi)
    g_lo, g_hi = _g_range(t_lo, t_hi, d2_lo, d2_hi, leg)
    return g_lo, g_hi, t_lo, s_lo, s_hi


# ------------------------------------------------------------------ passes
# det A works chunk by chunk (as mechanisms/_rpr_kernels.py does): each quantity
# of a chunk's boxes is a row (a "slot") of two scratch arrays ``lo``, ``hi``
# (slots x _CHUNK), and each interval operation one compiled loop over the
# chunk's boxes. Slots are passed as np.int64 (see intervals.Slot).

#: boxes per chunk: the scratch (80 slots, 2 x 8 bytes a box each) stays in cache
_CHUNK = 128


# the slots of a chunk: the box (x, y, z) and its centre; the cosine and sine of
# each leg's angle enclosure (leg k's at + 2 k, + 2 k + 1); the rows of A (leg k's
# at + 3 k); la cos and la sin of each leg's angle (leg k's at + 2 k, + 2 k + 1);
# the centres' matrix of _plain_rest; the joints' gradients (leg k's at + 3 k);
# det A's enclosures and sums; scratch
_X, _M, _TRIG, _MTRIG, _ROWS, _MROWS, _ARM_TRIG, _MARM_TRIG = 0, 3, 6, 12, 18, 27, 36, 42
_CENTRES, _GRAD, _NAT, _ALT, _TOT, _RATE, _TERM, _WIDTH, _DEN, _S = (
    48, 57, 66, 67, 68, 69, 70, 71, 72, 73,
)  # fmt: skip
_TEMP = 74  # 6 slots
_SLOTS = _TEMP + 6


@kernel
def _rows(
    lo: Array, hi: Array, x: Slot, trig: Slot, legs: Array, rows: Slot, arm_trig: Slot, w: int
) -> None:  # pragma: no cover - compiled
    """The rows of A (``DeltaLeg.a_row_boxes``) into slots ``rows + 3 k``, from the
    pose in ``x .. x + 2`` and the cosine and sine of leg ``k``'s angle in
    ``trig + 2 k``, ``+ 1``: ``P + (r - R - la cos) u + la sin e_z``; ``la cos``,
    ``la sin`` into ``arm_trig + 2 k``, ``+ 1``. Slot ``_TEMP`` is scratch."""
    h = np.int64(_TEMP)
    for k in range(3):
        leg = legs[k]
        ca, sa, row = arm_trig + 2 * k, arm_trig + 2 * k + 1, rows + 3 * k
        slot_mul_c(lo, hi, trig + 2 * k, leg[ARM], leg[ARM], ca, w)
        slot_c_sub(lo, hi, leg[OFF_LO], leg[OFF_HI], ca, h, w)
        slot_mul_c(lo, hi, h, leg[UX_LO], leg[UX_HI], row, w)
        slot_add(lo, hi, x, row, row, w)
        slot_mul_c(lo, hi, h, leg[UY_LO], leg[UY_HI], row + 1, w)
        slot_add(lo, hi, x + 1, row + 1, row + 1, w)
        slot_mul_c(lo, hi, trig + 2 * k + 1, leg[ARM], leg[ARM], sa, w)
        slot_add(lo, hi, x + 2, sa, row + 2, w)


@kernel
def _plain_rest(
    lo: Array,
    hi: Array,
    x: Slot,
    rows: Slot,
    arm_trig: Slot,
    legs: Array,
    o: Slot,
    w: int,
) -> None:  # pragma: no cover - compiled
    """``Delta._det_a_plain`` after the rows (:func:`_rows`) into slot ``o``: the
    rows' determinant intersected with ``(P - c_1) . ((c_1 - c_2) x (c_1 -
    c_3))``, ``c_k = (la cos - (r - R)) u_k - la sin e_z`` the sphere centres."""
    h, t = np.int64(_TEMP), np.int64(_TEMP + 2)
    nat, alt, cm = np.int64(_NAT), np.int64(_ALT), np.int64(_CENTRES)
    matrix = np.arange(9, dtype=np.int64)
    for i in range(9):
        matrix[i] = rows + i
    slot_det3(lo, hi, matrix, nat, t, w)
    # the centres into the rows of cm (leg k's at + 3 k), in place below
    for k in range(3):
        leg = legs[k]
        c = cm + 3 * k
        slot_sub_c(lo, hi, arm_trig + 2 * k, leg[OFF_LO], leg[OFF_HI], h, w)
        slot_mul_c(lo, hi, h, leg[UX_LO], leg[UX_HI], c, w)
        slot_mul_c(lo, hi, h, leg[UY_LO], leg[UY_HI], c + 1, w)
        slot_negate(lo, hi, arm_trig + 2 * k + 1, c + 2, w)
    # P - c_1, c_1 - c_2, c_1 - c_3 (the first row last: it overwrites c_1)
    for e in range(3):
        slot_sub(lo, hi, cm + e, cm + 3 + e, cm + 3 + e, w)
        slot_sub(lo, hi, cm + e, cm + 6 + e, cm + 6 + e, w)
        slot_sub(lo, hi, x + e, cm + e, cm + e, w)
    for i in range(9):
        matrix[i] = cm + i
    slot_det3(lo, hi, matrix, alt, t, w)
    for j in range(w):
        lo[o, j] = nan_max(lo[nat, j], lo[alt, j])
        hi[o, j] = nan_min(hi[nat, j], hi[alt, j])


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
    t: Slot,
) -> None:  # pragma: no cover - compiled
    """The boxes ``s:s + w``: their coordinates into slots ``x .. x + 2``, the
    cosines and sines of the legs' angles (``trig`` (4, 3, n): the bounds of the
    cosines, then of the sines) into slots ``t + 2 k``, ``t + 2 k + 1``."""
    for j in range(w):
        for axis in range(3):
            lo[x + axis, j] = box_lo[s + j, axis]
            hi[x + axis, j] = box_hi[s + j, axis]
        for k in range(3):
            lo[t + 2 * k, j], hi[t + 2 * k, j] = trig[0, k, s + j], trig[1, k, s + j]
            lo[t + 2 * k + 1, j], hi[t + 2 * k + 1, j] = trig[2, k, s + j], trig[3, k, s + j]


@kernel
def _trig_of(a_lo: Array, a_hi: Array) -> Array:  # pragma: no cover - compiled
    """``intervals.cos`` and ``sin`` of the angle enclosures ``[a_lo, a_hi]`` (3,
    n), by ``intervals.trig_bounds``: (4, 3, n), the bounds of the cosines, then
    of the sines."""
    n = a_lo.shape[1]
    out = np.empty((4, 3, n))
    flat_lo, flat_hi = a_lo.copy().reshape(-1), a_hi.copy().reshape(-1)
    c_lo, c_hi = trig_bounds(flat_lo, flat_hi, False, LIB_REL, LIB_TINY)
    s_lo, s_hi = trig_bounds(flat_lo, flat_hi, True, LIB_REL, LIB_TINY)
    out[0] = c_lo.reshape(3, n)
    out[1] = c_hi.reshape(3, n)
    out[2] = s_lo.reshape(3, n)
    out[3] = s_hi.reshape(3, n)
    return out


@kernel
def det_a_prepare(
    lo: Array,
    hi: Array,
    a_lo: Array,
    a_hi: Array,
    legs: Array,
    out_lo: Array,
    out_hi: Array,
    trig: Array,
) -> None:  # pragma: no cover - compiled
    """``Delta._det_a_plain`` of the (n, 3) boxes with the legs' angle enclosures
    ``[a_lo, a_hi]`` (3, n) into ``out`` (n,), and the cosines and sines of
    the angles into ``trig`` (4, 3, n; see :func:`_trig_of`). ``legs`` (3,
    N_CONSTANTS)."""
    w = _CHUNK
    s_lo, s_hi = np.empty((_SLOTS, w)), np.empty((_SLOTS, w))
    x, at, rows = np.int64(_X), np.int64(_TRIG), np.int64(_ROWS)
    arm_trig, nat = np.int64(_ARM_TRIG), np.int64(_TOT)
    trig[:] = _trig_of(a_lo, a_hi)
    n = lo.shape[0]
    for s in range(0, n, w):
        size = min(w, n - s)
        _load(s_lo, s_hi, lo, hi, trig, s, size, x, at)
        _rows(s_lo, s_hi, x, at, legs, rows, arm_trig, size)
        _plain_rest(s_lo, s_hi, x, rows, arm_trig, legs, nat, size)
        out_lo[s : s + size] = s_lo[nat, :size]
        out_hi[s : s + size] = s_hi[nat, :size]


@kernel
def regular_boxes(
    lo: Array, hi: Array, legs: Array, regular: NDArray[np.bool_]
) -> None:  # pragma: no cover - compiled
    """Into ``regular`` (n,) where every leg is regular over the (n, 3) box
    (``DeltaLeg._g_boxes``: ``t > 0`` and ``|g| < 1``)."""
    for j in range(lo.shape[0]):
        ok = True
        for k in range(3):
            g_lo, g_hi, t_lo, _, _ = g_boxes(
                lo[j, 0], hi[j, 0], lo[j, 1], hi[j, 1], lo[j, 2], hi[j, 2], legs[k]
            )
            ok = ok and (t_lo > 0) and (g_lo > -1.0) and (g_hi < 1.0)
        regular[j] = ok


@kernel
def centre_args(lo: Array, hi: Array, legs: Array, out: Array) -> None:  # pragma: no cover
    """``DeltaLeg.branch_boxes`` at the centres ``0.5 lo + 0.5 hi`` of the (n, 3)
    boxes, up to its library functions, into ``out`` (4, 3, n): for each leg,
    the clipped arguments whose arccos are alpha's lower and upper bounds, and
    the centres ``s.mid``, ``w.mid`` of ``s`` and ``w = -z`` (whose arctan2 is
    the direction of the box's centre)."""
    for j in range(lo.shape[0]):
        mx = 0.5 * lo[j, 0] + 0.5 * hi[j, 0]
        my = 0.5 * lo[j, 1] + 0.5 * hi[j, 1]
        mz = 0.5 * lo[j, 2] + 0.5 * hi[j, 2]
        for k in range(3):
            g_lo, g_hi, _, s_lo, s_hi = g_boxes(mx, mx, my, my, mz, mz, legs[k])
            # intervals.arccos: np.clip of each bound to [-1, 1]
            out[0, k, j] = nan_min(nan_max(g_hi, -1.0), 1.0)
            out[1, k, j] = nan_min(nan_max(g_lo, -1.0), 1.0)
            out[2, k, j] = clip_mid(s_lo, s_hi)
            out[3, k, j] = clip_mid(-mz, -mz)


@kernel
def centre_turn(
    lo: Array, hi: Array, cs: Array, sn: Array, legs: Array, out: Array
) -> None:  # pragma: no cover - compiled
    """``DeltaLeg._direction`` at the centres of the (n, 3) boxes, up to its
    arctan2 of the corners: ``s``, ``w`` turned by the direction ``(cs, sn)``
    (3, n), ``us = s cs + w sn`` and ``uw = w cs - s sn``, into ``out`` (4, 3,
    n): the bounds of ``us``, then of ``uw``."""
    for j in range(lo.shape[0]):
        mx = 0.5 * lo[j, 0] + 0.5 * hi[j, 0]
        my = 0.5 * lo[j, 1] + 0.5 * hi[j, 1]
        mz = 0.5 * lo[j, 2] + 0.5 * hi[j, 2]
        for k in range(3):
            s_lo, s_hi, _, _ = plane(mx, mx, my, my, legs[k])
            w_lo, w_hi = -mz, -mz
            c_k, s_k = cs[k, j], sn[k, j]
            p_lo, p_hi = interval_mul(s_lo, s_hi, c_k, c_k)
            q_lo, q_hi = interval_mul(w_lo, w_hi, s_k, s_k)
            out[0, k, j], out[1, k, j] = interval_add(p_lo, p_hi, q_lo, q_hi)
            p_lo, p_hi = interval_mul(w_lo, w_hi, c_k, c_k)
            q_lo, q_hi = interval_mul(s_lo, s_hi, s_k, s_k)
            out[2, k, j], out[3, k, j] = interval_sub(p_lo, p_hi, q_lo, q_hi)


@kernel
def centre_angles(
    cs: Array, sn: Array, ref: Array, corners: Array, turned: Array, acos: Array, out: Array
) -> None:  # pragma: no cover - compiled
    """``DeltaLeg.branch_boxes`` at the boxes' centres after its library
    functions, both branches' parts into ``out`` (4, 3, n): the bounds of the
    direction, then of alpha. From the arctan2 ``ref`` (3, n) of the centres'
    directions ``(cs, sn)`` (3, n), the arctan2 ``corners`` (4, 3, n) of the
    corners of the turned box (``turned``, from :func:`centre_turn`: lo lo, lo
    hi, hi lo, hi hi of ``(uw, us)``) and the arccos ``acos`` (2, 3, n) of
    alpha's arguments (:func:`centre_args`)."""
    for k in range(3):
        for j in range(cs.shape[1]):
            out[2, k, j] = nan_max(lib_below(acos[0, k, j]), 0.0)
            out[3, k, j] = nan_min(lib_above(acos[1, k, j]), PI_UP)
            c_k, s_k = cs[k, j], sn[k, j]
            r_lo, r_hi = atan_bounds(ref[k, j], ref[k, j], (c_k <= 0) & (s_k <= 0) & (s_k >= 0))
            c0, c1, c2, c3 = corners[0, k, j], corners[1, k, j], corners[2, k, j], corners[3, k, j]
            least = nan_min(nan_min(nan_min(c0, c1), c2), c3)
            most = nan_max(nan_max(nan_max(c0, c1), c2), c3)
            cut = (turned[0, k, j] <= 0) & (turned[2, k, j] <= 0) & (turned[3, k, j] >= 0)
            t_lo, t_hi = atan_bounds(least, most, cut)
            out[0, k, j], out[1, k, j] = interval_add(r_lo, r_hi, t_lo, t_hi)


@kernel
def centre_trig(centre: Array, out: Array) -> None:  # pragma: no cover - compiled
    """The cosines and sines of both branches' angles at the boxes' centres
    (``DeltaLeg.branch_boxes``: the direction plus alpha on branch 0, minus
    alpha on branch 1, from ``centre`` (4, 3, n) of :func:`centre_angles`)
    into ``out`` (2, 4, 3, n): branch ``b``'s at ``out[b]`` (see
    :func:`_trig_of`)."""
    n = centre.shape[2]
    m_lo, m_hi = np.empty((3, n)), np.empty((3, n))
    for branch in range(2):
        for k in range(3):
            for j in range(n):
                d_lo, d_hi = centre[0, k, j], centre[1, k, j]
                al_lo, al_hi = centre[2, k, j], centre[3, k, j]
                if branch == 0:
                    m_lo[k, j], m_hi[k, j] = interval_add(d_lo, d_hi, al_lo, al_hi)
                else:
                    m_lo[k, j], m_hi[k, j] = interval_sub(d_lo, d_hi, al_lo, al_hi)
        out[branch] = _trig_of(m_lo, m_hi)


# the slots of the mean-value form beyond those of det_a_prepare: for each branch b,
# from _BRANCH + _PER_BRANCH b, the cosines and sines of the legs' angles (leg k's at
# + 2 k, + 2 k + 1), the rows of A over the box (leg k's at + 6 + 3 k), la cos and
# la sin (leg k's at + 15 + 2 k, + 1), and the rows moved along each axis (leg k's
# along axis a at + 21 + 9 k + 3 a); then the boxes' widths about their centres
_BRANCH, _PER_BRANCH = _SLOTS, 48
_B_TRIG, _B_ROWS, _B_ARM_TRIG, _B_MOVED = 0, 6, 15, 21
_WIDTHS = _BRANCH + 2 * _PER_BRANCH  # 3 slots
_ALL_SLOTS = _WIDTHS + 3


@kernel
def _moved_rows(
    lo: Array,
    hi: Array,
    x: Slot,
    base: Slot,
    legs: Array,
    one_lo: float,
    one_hi: float,
    zero_lo: float,
    zero_hi: float,
    w: int,
) -> None:  # pragma: no cover - compiled
    """One branch's part of the mean-value form (the legs on that branch, its slots
    from ``base``, the cosines and sines of the angles loaded): the rows of A over
    the box, the joints' gradients and each leg's row moved along each axis, for
    :func:`mean_value_bounds` and :func:`mean_value_all`."""
    trig, rows, arm_trig = base + _B_TRIG, base + _B_ROWS, base + _B_ARM_TRIG
    grad, den, sp, t = np.int64(_GRAD), np.int64(_DEN), np.int64(_S), np.int64(_TEMP)
    _rows(lo, hi, x, trig, legs, rows, arm_trig, w)
    for k in range(3):
        leg = legs[k]
        slot_mul_c(lo, hi, x, leg[UX_LO], leg[UX_HI], t, w)
        slot_mul_c(lo, hi, x + 1, leg[UY_LO], leg[UY_HI], t + 1, w)
        slot_add(lo, hi, t, t + 1, sp, w)
        slot_add_c(lo, hi, sp, leg[OFF_LO], leg[OFF_HI], sp, w)
        slot_mul(lo, hi, sp, trig + 2 * k + 1, t, w)
        slot_mul(lo, hi, x + 2, trig + 2 * k, t + 1, w)
        slot_add(lo, hi, t, t + 1, den, w)
        slot_mul_c(lo, hi, den, leg[ARM], leg[ARM], den, w)
        for e in range(3):
            slot_div(lo, hi, rows + 3 * k + e, den, grad + 3 * k + e, w)
            slot_negate(lo, hi, grad + 3 * k + e, grad + 3 * k + e, w)
    for axis in range(3):
        for i in range(3):
            leg = legs[i]
            moved = base + _B_MOVED + 9 * i + 3 * axis
            for j in range(3):
                if j < 2:
                    slot_mul_c(
                        lo, hi, arm_trig + 2 * i + 1,
                        leg[UX_LO] if j == 0 else leg[UY_LO],
                        leg[UX_HI] if j == 0 else leg[UY_HI],
                        moved + j, w,
                    )  # fmt: skip
                    slot_mul(lo, hi, moved + j, grad + 3 * i + axis, moved + j, w)
                else:
                    slot_mul(lo, hi, arm_trig + 2 * i, grad + 3 * i + axis, moved + j, w)
                for ax in range(3):
                    unit = j == ax and ax == axis
                    slot_add_c(
                        lo, hi, moved + j,
                        one_lo if unit else zero_lo, one_hi if unit else zero_hi,
                        moved + j, w,
                    )  # fmt: skip


@kernel
def _centre_widths(
    s_lo: Array, s_hi: Array, lo: Array, hi: Array, s: int, w: int
) -> None:  # pragma: no cover - compiled
    """The centres ``m`` of the chunk's boxes from ``s`` into the slots from ``_M``
    and the widths ``x - m`` into those from ``_WIDTHS`` (the box loaded)."""
    mx, x, widths = np.int64(_M), np.int64(_X), np.int64(_WIDTHS)
    for j in range(w):
        for axis in range(3):
            m = 0.5 * lo[s + j, axis] + 0.5 * hi[s + j, axis]
            s_lo[mx + axis, j] = m
            s_hi[mx + axis, j] = m
    for axis in range(3):
        slot_sub(s_lo, s_hi, x + axis, mx + axis, widths + axis, w)


@kernel
def _form(
    s_lo: Array,
    s_hi: Array,
    centre_trig: Array,
    branches: NDArray[np.int64],
    bases: NDArray[np.int64],
    legs: Array,
    s: int,
    w: int,
    matrix: NDArray[np.int64],
) -> None:  # pragma: no cover - compiled
    """The mean-value form ``D(m) + sum_j dD/dx_j (x_j - m_j)`` of the chunk's
    boxes from ``s`` into slot ``_TOT``, leg ``k`` on branch ``branches[k]``: the
    centres and widths in their slots (:func:`_centre_widths`), leg ``k``'s rows
    over the box and moved along each axis in the block from ``bases[k]``
    (:func:`_moved_rows`). ``D(m)`` as ``Delta._det_a_plain`` at the centre, with
    the cosines and sines of the legs' angles there from ``centre_trig``;
    ``dD/dx_j`` as ``Mechanism.det_a_rate`` (``base._det_rate_span``'s order)."""
    mx, mtrig = np.int64(_M), np.int64(_MTRIG)
    mrows, marm_trig = np.int64(_MROWS), np.int64(_MARM_TRIG)
    tot, rate, term = np.int64(_TOT), np.int64(_RATE), np.int64(_TERM)
    t, widths = np.int64(_TEMP), np.int64(_WIDTHS)
    for j in range(w):
        for k in range(3):
            b = branches[k]
            s_lo[mtrig + 2 * k, j] = centre_trig[b, 0, k, s + j]
            s_hi[mtrig + 2 * k, j] = centre_trig[b, 1, k, s + j]
            s_lo[mtrig + 2 * k + 1, j] = centre_trig[b, 2, k, s + j]
            s_hi[mtrig + 2 * k + 1, j] = centre_trig[b, 3, k, s + j]
    # D(m)
    _rows(s_lo, s_hi, mx, mtrig, legs, mrows, marm_trig, w)
    _plain_rest(s_lo, s_hi, mx, mrows, marm_trig, legs, tot, w)
    for axis in range(3):
        for i in range(3):
            # det A with row i moved along the axis
            for k in range(3):
                for j in range(3):
                    matrix[3 * k + j] = bases[k] + _B_ROWS + 3 * k + j
            for j in range(3):
                matrix[3 * i + j] = bases[i] + _B_MOVED + 9 * i + 3 * axis + j
            if i == 0:
                slot_det3(s_lo, s_hi, matrix, rate, t, w)
            else:
                slot_det3(s_lo, s_hi, matrix, term, t, w)
                slot_add(s_lo, s_hi, rate, term, rate, w)
        slot_mul(s_lo, s_hi, rate, widths + axis, term, w)
        slot_add(s_lo, s_hi, tot, term, tot, w)


@kernel
def mean_value_bounds(
    lo: Array,
    hi: Array,
    box_trig: Array,
    branches: NDArray[np.int64],
    centre_trig: Array,
    legs: Array,
    out_lo: Array,
    out_hi: Array,
) -> None:  # pragma: no cover - compiled
    """``Delta.det_a_boxes``' mean-value form over the (n, 3) boxes where every leg
    is regular, intersected with the enclosures in ``out`` (n,) where its bounds
    are finite: ``D(m) + sum_j dD/dx_j (x_j - m_j)``.

    ``D(m)`` as ``Delta._det_a_plain`` at the centre ``m``, with the cosines and
    sines of the angles of each leg's branch (``branches`` (3,)) there
    (``centre_trig`` (2, 4, 3, n), from :func:`centre_trig`); ``dD/dx_j`` as
    ``Mechanism.det_a_rate`` (``base._det_rate_span``'s order) with the rows of
    A over the box (the cosines and sines of the angle enclosures in
    ``box_trig`` (4, 3, n), see :func:`_trig_of`), their partials
    (``DeltaLeg.row_partials``) and the joints' gradients
    (``DeltaLeg.joint_gradient``)."""
    n = lo.shape[0]
    # the products of the partials along the pose (the identity) with the
    # velocity (a unit vector): 1 * 1, and 0 * 1, 1 * 0 or 0 * 0
    one_lo, one_hi = interval_mul(1.0, 1.0, 1.0, 1.0)
    zero_lo, zero_hi = interval_mul(0.0, 0.0, 1.0, 1.0)
    w = _CHUNK
    s_lo, s_hi = np.empty((_ALL_SLOTS, w)), np.empty((_ALL_SLOTS, w))
    # the first branch's block holds each leg on its own branch
    base = np.int64(_BRANCH)
    bases = np.full(3, _BRANCH, dtype=np.int64)
    matrix = np.empty(9, dtype=np.int64)
    tot = np.int64(_TOT)
    for s in range(0, n, w):
        size = min(w, n - s)
        _load(s_lo, s_hi, lo, hi, box_trig, s, size, np.int64(_X), base + _B_TRIG)
        _moved_rows(s_lo, s_hi, np.int64(_X), base, legs, one_lo, one_hi, zero_lo, zero_hi, size)
        _centre_widths(s_lo, s_hi, lo, hi, s, size)
        _form(s_lo, s_hi, centre_trig, branches, bases, legs, s, size, matrix)
        intersect_finite(
            s_lo[tot, :size], s_hi[tot, :size], out_lo[s : s + size], out_hi[s : s + size]
        )


@kernel
def mean_value_all(
    lo: Array,
    hi: Array,
    a_lo: Array,
    a_hi: Array,
    postures: NDArray[np.int64],
    centre_trig: Array,
    legs: Array,
    out_lo: Array,
    out_hi: Array,
) -> None:  # pragma: no cover - compiled
    """:func:`mean_value_bounds`' form ``D(m) + sum_j dD/dx_j (x_j - m_j)`` over the
    (n, 3) boxes where every leg is regular, for every posture at once, into
    ``out`` (P, n) (not intersected). The legs' angle enclosures on each branch
    are ``[a_lo, a_hi]`` (2, 3, n); ``postures`` (P, 3) the branches of each
    posture; ``centre_trig`` as :func:`mean_value_bounds` takes it.

    Each posture's form is computed by the operations of
    :func:`mean_value_bounds` in the same order, so its bounds are the same
    floats; what depends on one leg's branch alone (the rows of A over the box,
    the joints' gradients, the rows moved along each axis) is computed once per
    branch, not once per posture."""
    n = lo.shape[0]
    one_lo, one_hi = interval_mul(1.0, 1.0, 1.0, 1.0)
    zero_lo, zero_hi = interval_mul(0.0, 0.0, 1.0, 1.0)
    box_trig = np.empty((2, 4, 3, n))
    for b in range(2):
        box_trig[b] = _trig_of(a_lo[b], a_hi[b])
    w = _CHUNK
    s_lo, s_hi = np.empty((_ALL_SLOTS, w)), np.empty((_ALL_SLOTS, w))
    x, tot = np.int64(_X), np.int64(_TOT)
    bases = np.empty(3, dtype=np.int64)
    matrix = np.empty(9, dtype=np.int64)
    for s in range(0, n, w):
        size = min(w, n - s)
        for b in range(2):
            base = np.int64(_BRANCH + _PER_BRANCH * b)
            _load(s_lo, s_hi, lo, hi, box_trig[b], s, size, x, base + _B_TRIG)
            _moved_rows(s_lo, s_hi, x, base, legs, one_lo, one_hi, zero_lo, zero_hi, size)
        _centre_widths(s_lo, s_hi, lo, hi, s, size)
        for p in range(postures.shape[0]):
            for k in range(3):
                bases[k] = _BRANCH + _PER_BRANCH * postures[p, k]
            _form(s_lo, s_hi, centre_trig, postures[p], bases, legs, s, size, matrix)
            out_lo[p, s : s + size] = s_lo[tot, :size]
            out_hi[p, s : s + size] = s_hi[tot, :size]


@kernel
def intersect_finite(
    t_lo: Array, t_hi: Array, out_lo: Array, out_hi: Array
) -> None:  # pragma: no cover - compiled
    """``out`` (n,) intersected with ``[t_lo, t_hi]`` where both bounds are finite,
    as :func:`mean_value_bounds` ends."""
    for j in range(out_lo.shape[0]):
        lo_j, hi_j = t_lo[j], t_hi[j]
        if np.isfinite(lo_j) and np.isfinite(hi_j):
            out_lo[j] = nan_max(out_lo[j], lo_j)
            out_hi[j] = nan_min(out_hi[j], hi_j)


# the slots of det_a_all beyond those of det_a_prepare: for each branch b, from
# _PLAIN + _PER_PLAIN b, the cosines and sines of the legs' angles (leg k's at + 2 k,
# + 2 k + 1), the rows of A (leg k's at + 6 + 3 k), la cos and la sin (leg k's at +
# 15 + 2 k, + 1) and the sphere centres (leg k's at + 21 + 3 k)
_PLAIN, _PER_PLAIN = _SLOTS, 30
_P_TRIG, _P_ROWS, _P_ARM_TRIG, _P_CENTRES = 0, 6, 15, 21
_PLAIN_SLOTS = _PLAIN + 2 * _PER_PLAIN


@kernel
def det_a_all(
    lo: Array,
    hi: Array,
    a_lo: Array,
    a_hi: Array,
    postures: NDArray[np.int64],
    legs: Array,
    out_lo: Array,
    out_hi: Array,
) -> None:  # pragma: no cover - compiled
    """:func:`det_a_prepare`'s enclosure (``Delta._det_a_plain``) of the (n, 3)
    boxes for every posture at once, into ``out`` (P, n): the legs' angle
    enclosures on each branch are ``[a_lo, a_hi]`` (2, 3, n), ``postures`` (P,
    3) the branches of each posture.

    Each posture's enclosure comes from the operations of :func:`_rows` and
    :func:`_plain_rest` in the same order, so its bounds are the same floats;
    what depends on one leg's angle alone (their cosines and sines, the leg's
    row of A, its sphere centre) is computed once per branch, not once per
    posture."""
    n = lo.shape[0]
    trig = np.empty((2, 4, 3, n))
    for b in range(2):
        trig[b] = _trig_of(a_lo[b], a_hi[b])
    w = _CHUNK
    s_lo, s_hi = np.empty((_PLAIN_SLOTS, w)), np.empty((_PLAIN_SLOTS, w))
    x, h, t = np.int64(_X), np.int64(_TEMP), np.int64(_TEMP + 2)
    nat, alt, cm = np.int64(_NAT), np.int64(_ALT), np.int64(_CENTRES)
    matrix = np.empty(9, dtype=np.int64)
    for s in range(0, n, w):
        size = min(w, n - s)
        for b in range(2):
            base = np.int64(_PLAIN + _PER_PLAIN * b)
            arm_trig = base + _P_ARM_TRIG
            _load(s_lo, s_hi, lo, hi, trig[b], s, size, x, base + _P_TRIG)
            _rows(s_lo, s_hi, x, base + _P_TRIG, legs, base + _P_ROWS, arm_trig, size)
            # the centres, as _plain_rest has them
            for k in range(3):
                leg = legs[k]
                c = base + _P_CENTRES + 3 * k
                slot_sub_c(s_lo, s_hi, arm_trig + 2 * k, leg[OFF_LO], leg[OFF_HI], h, size)
                slot_mul_c(s_lo, s_hi, h, leg[UX_LO], leg[UX_HI], c, size)
                slot_mul_c(s_lo, s_hi, h, leg[UY_LO], leg[UY_HI], c + 1, size)
                slot_negate(s_lo, s_hi, arm_trig + 2 * k + 1, c + 2, size)
        for p in range(postures.shape[0]):
            for k in range(3):
                base = _PLAIN + _PER_PLAIN * postures[p, k]
                for j in range(3):
                    matrix[3 * k + j] = base + _P_ROWS + 3 * k + j
            slot_det3(s_lo, s_hi, matrix, nat, t, size)
            c1 = _PLAIN + _PER_PLAIN * postures[p, 0] + _P_CENTRES
            c2 = _PLAIN + _PER_PLAIN * postures[p, 1] + _P_CENTRES + 3
            c3 = _PLAIN + _PER_PLAIN * postures[p, 2] + _P_CENTRES + 6
            # P - c_1, c_1 - c_2, c_1 - c_3
            for e in range(3):
                slot_sub(s_lo, s_hi, c1 + e, c2 + e, cm + 3 + e, size)
                slot_sub(s_lo, s_hi, c1 + e, c3 + e, cm + 6 + e, size)
                slot_sub(s_lo, s_hi, x + e, c1 + e, cm + e, size)
            for i in range(9):
                matrix[i] = cm + i
            slot_det3(s_lo, s_hi, matrix, alt, t, size)
            for j in range(size):
                out_lo[p, s + j] = nan_max(s_lo[nat, j], s_lo[alt, j])
                out_hi[p, s + j] = nan_min(s_hi[nat, j], s_hi[alt, j])
