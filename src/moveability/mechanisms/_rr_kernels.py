"""Compiled interval enclosures of the five-bar and its RR legs: det A over boxes
(with the branch forms of a known posture), the elbows over angle enclosures,
the legs' reach and their fold flows.

Each kernel computes what :class:`~.five_bar.FiveBar` and :class:`~.rr_leg.RRLeg`
compute with :class:`~moveability.intervals.Interval` operations (kept there as
the reference, the ``_..._intervals`` methods): the same operations on the same
operands in the same order, each rounded outwards by the compiled primitives
of :mod:`moveability.intervals` that the Interval operators apply element by
element (``mul_into``, ``add_into``, ``sub_into``, ``interval_mul``,
``interval_add``, ``interval_sub``; ``next_below`` in its inlined form
``step_down``; the library functions' widening ``move_below`` with
``_rel(4)``; and the steps of ``intervals._trig_bounds`` for a cosine or sine,
:func:`_trig`). The bounds are thus the same floats, bit for bit
(tests/mechanisms/test_five_bar_kernels.py compares them on random boxes of
every kind). det A runs chunk by chunk, one vectorised pass per operation
(see "passes" below), the others box by box, each quantity a pair of floats:
no array is allocated per operation and no Python runs between the operations.
The sine and cosine of one angle may be computed by one call of the C
library's ``sincos`` (the compiler merges them, :func:`_cos_sin`), which glibc
computes as its ``sin`` and ``cos`` do, bit for bit (16 million arguments from 1
to 1e300 compared on glibc 2.36; the tests compare the elbows too).

Two library functions are left to numpy, between the kernels: ``arccos`` and
``arctan2``. numpy may evaluate them with its own vectorised code (SVML on
AVX-512 machines), whose results differ from the C library's in the last bits,
so the Interval code's ``np.arccos`` and ``np.arctan2`` are called on the same
arrays of arguments as there (and ``np.cos``, ``np.sin`` of a box's direction
from its centre, for the same reason). The cosines and sines of angle
enclosures are compiled in :mod:`moveability.intervals` already
(``_trig_bounds``): :func:`_trig` takes its steps (``trig_ends``).

A leg enters as the float array of ``RRLeg.constants`` (its entries are named
below).
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
    slot_div,
    slot_mul,
    slot_mul_c,
    slot_sub,
    slot_sub_c,
    step_down,
    trig_ends,
)
from ..types import Array

__all__ = [
    "det_a_bounds",
    "det_a_postures",
    "fold_rate_bounds",
    "fold_terms_finish",
    "fold_terms_prepare",
    "knee_bounds",
    "reach_finish",
    "reach_prepare",
]

# the entries of a leg's constants (see RRLeg.constants): its base and lengths,
# then the Interval constants of branch_det, _alpha, reach and _fold_terms
(
    BASE_X, BASE_Y, A, A2, B2, FOUR_A2, TOP, SHIFT_LO, SHIFT_HI, K_LO, K_HI, TWO_A,
    STAR_LO, STAR_HI, G_MIN, K_POSITIVE, OUT_LO, OUT_HI, IN_LO, IN_HI, SLOPE_LO, SLOPE_HI,
    N_CONSTANTS,
) = range(23)  # fmt: skip

# ------------------------------------------------------------------ rounding
# The rounding steps are those of moveability.intervals (step_down, trig_ends):
# the same floats as the Interval code.

_PI_UP = float(np.nextafter(np.pi, np.inf))
#: the smallest positive subnormal
_TINY = 5e-324
#: the widening of the library functions, ``intervals._rel(4)`` and 4 ulps of ``_TINY``
_LIB_REL = 5 * 2.0**-52
_LIB_TINY = 4 * _TINY


@kernel(inline=True)
def _next_below(x: float) -> float:  # pragma: no cover - compiled
    """:func:`~moveability.intervals.next_below` (``move_below`` by one ulp), as its
    inlined form ``intervals.step_down`` computes it: without jumps on the data, so
    that the loops around it vectorise."""
    return step_down(x, False)


@kernel(inline=True)
def _trig_bound(
    fa: float, fb: float, a: float, b: float, sine: bool
) -> tuple[float, float]:  # pragma: no cover - compiled
    """One element of ``intervals._trig_bounds`` from the function's values ``fa``,
    ``fb`` at the ends of ``[a, b]`` (``intervals.trig_ends``)."""
    return trig_ends(fa, fb, a, b, sine, _LIB_REL, _LIB_TINY)


@kernel
def _cos_sin(a: float, b: float) -> tuple[float, float, float, float]:  # pragma: no cover
    """``intervals.cos`` and ``sin`` of ``[a, b]`` (:func:`_trig` of each), the
    four library values in one function: the compiler may merge the sine and
    cosine of one argument into one ``sincos`` call (see the module's notes)."""
    ca, sa, cb, sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
    c_lo, c_hi = _trig_bound(ca, cb, a, b, False)
    s_lo, s_hi = _trig_bound(sa, sb, a, b, True)
    return c_lo, c_hi, s_lo, s_hi


@kernel
def _trig(a: float, b: float, sine: bool) -> tuple[float, float]:  # pragma: no cover
    """``intervals.sin`` (or ``cos``) of ``[a, b]``: the steps of one element of
    ``intervals._trig_bounds``."""
    fa = np.sin(a) if sine else np.cos(a)
    fb = np.sin(b) if sine else np.cos(b)
    return _trig_bound(fa, fb, a, b, sine)


@kernel
def knee_bounds(
    a_lo: Array, a_hi: Array, leg: Array, out_lo: Array, out_hi: Array
) -> None:  # pragma: no cover - compiled
    """``RRLeg.knee_boxes`` of the flat angle enclosures ``[a_lo, a_hi]`` into
    ``out`` (4, n): ``cos * a``, ``sin * a``, and the elbow's x and y."""
    a, bx, by = leg[A], leg[BASE_X], leg[BASE_Y]
    n = a_lo.size
    for j in range(n):
        c_lo, c_hi, s_lo, s_hi = _cos_sin(a_lo[j], a_hi[j])
        out_lo[0, j], out_hi[0, j] = c_lo, c_hi
        out_lo[1, j], out_hi[1, j] = s_lo, s_hi
    # the products and sums, one vectorised pass each
    _knee_passes(out_lo, out_hi, np.int64(0), a, bx, by, n)


@kernel
def _knee_passes(
    lo: Array, hi: Array, c: Slot, a: float, bx: float, by: float, w: int
) -> None:  # pragma: no cover - compiled
    """``RRLeg.knee_boxes`` after its cosine and sine (in slots ``c``, ``c + 1``),
    for a leg of proximal length ``a`` and base ``(bx, by)``: ``c = cos * a``, ``s =
    sin * a`` in place, then the elbow ``(c + bx, s + by)`` into slots ``c + 2``,
    ``c + 3``."""
    slot_mul_c(lo, hi, c, a, a, c, w)
    slot_mul_c(lo, hi, c + 1, a, a, c + 1, w)
    slot_add_c(lo, hi, c, bx, bx, c + 2, w)
    slot_add_c(lo, hi, c + 1, by, by, c + 3, w)


@kernel(inline=True)
def _g(
    r_lo: float, r_hi: float, four_a2: float, shift_lo: float, shift_hi: float
) -> tuple[float, float]:  # pragma: no cover - compiled
    """``branch_det``'s ``g(r) = r * 4 a^2 - (r + a^2 - b^2)^2`` (``four_a2`` the
    number ``4 a^2``, ``shift`` the enclosure of ``a^2 - b^2``)."""
    p_lo, p_hi = interval_mul(r_lo, r_hi, four_a2, four_a2)
    q_lo, q_hi = interval_add(r_lo, r_hi, shift_lo, shift_hi)
    q_lo, q_hi = interval_square(q_lo, q_hi)
    return interval_sub(p_lo, p_hi, q_lo, q_hi)


# ------------------------------------------------------------------ passes
# det A works chunk by chunk (as mechanisms/_rpr_kernels.py does): each quantity
# of a chunk's boxes is a row (a "slot") of two scratch arrays ``lo``, ``hi``
# (slots x _CHUNK), and each interval operation one compiled loop over the
# chunk's boxes, which the compiler vectorises (the primitives are free of jumps
# on the data): several times faster than one box at a time. Slots are passed as
# np.int64 (a constant would have numba compile each pass once per slot number).

#: boxes per chunk: the scratch (about 40 slots, 2 x 8 bytes a box each) stays in cache
_CHUNK = 256


@kernel
def _square_into(lo: Array, hi: Array, a: Slot, o: Slot, w: int) -> None:  # pragma: no cover
    """Slot ``o`` = ``intervals.square`` of slot ``a``."""
    a_lo, a_hi, o_lo, o_hi = lo[a, :w], hi[a, :w], lo[o, :w], hi[o, :w]
    for j in range(w):
        o_lo[j], o_hi[j] = interval_square(a_lo[j], a_hi[j])


@kernel
def _branch_form(
    lo: Array,
    hi: Array,
    leg: Array,
    side: float,
    g_top: float,
    px: Slot,
    q: Slot,
    o: Slot,
    t: Slot,
    w: int,
) -> None:  # pragma: no cover - compiled
    """``five_bar.branch_det`` over the chunk into slot ``o``: the pose in slots
    ``px``, ``px + 1``, the other elbow in ``q``, ``q + 1``, ``side`` +1 on branch
    0 and -1 on branch 1, ``g_top`` the upper bound of ``g(a^2 + b^2)``; slots
    ``t .. t + 16`` are scratch (:func:`_branch_pose`, then :func:`_branch_side`)."""
    _branch_pose(lo, hi, leg, g_top, px, t, t + 8, w)
    _branch_side(lo, hi, leg, side, px, q, o, t, t + 8, w)


@kernel
def _branch_pose(
    lo: Array, hi: Array, leg: Array, g_top: float, px: Slot, t: Slot, s: Slot, w: int
) -> None:  # pragma: no cover - compiled
    """The half of :func:`_branch_form` that depends on the pose alone (the same
    for both branches of the leg and whatever the other elbow): ``x``, ``y`` (the
    pose less the leg's base), their squares, ``rho``, ``2 rho``, ``1 - c`` and
    ``k`` into slots ``t .. t + 7``; slots ``s .. s + 8`` are scratch."""
    x, y, sx, sy, rho, r2, omc, k = t, t + 1, t + 2, t + 3, t + 4, t + 5, t + 6, t + 7
    u, v, wx, wy, dot, shift = s + 2, s + 3, s + 5, s + 6, s + 7, s + 8
    slot_sub_c(lo, hi, px, leg[BASE_X], leg[BASE_X], x, w)
    slot_sub_c(lo, hi, px + 1, leg[BASE_Y], leg[BASE_Y], y, w)
    _square_into(lo, hi, x, sx, w)
    _square_into(lo, hi, y, sy, w)
    slot_add(lo, hi, sx, sy, rho, w)
    # 1 - c = 0.5 - shift / (2 rho)
    slot_mul_c(lo, hi, rho, 2.0, 2.0, r2, w)
    lo[shift, :w] = leg[SHIFT_LO]
    hi[shift, :w] = leg[SHIFT_HI]
    slot_div(lo, hi, shift, r2, omc, w)
    slot_c_sub(lo, hi, 0.5, 0.5, omc, omc, w)
    # k: the square root of the range of g over rho (its ends, and its top where
    # rho may reach a^2 + b^2), over 2 rho
    top, four_a2, shift_lo, shift_hi = leg[TOP], leg[FOUR_A2], leg[SHIFT_LO], leg[SHIFT_HI]
    # g(r) = r 4a^2 - square(r + shift) at each end r of rho (as [r, r]): into u, v
    for end in range(2):
        e = u if end == 0 else v
        for j in range(w):
            r = lo[rho, j] if end == 0 else hi[rho, j]
            lo[wx, j], hi[wx, j] = r, r
        slot_mul_c(lo, hi, wx, four_a2, four_a2, wy, w)
        slot_add_c(lo, hi, wx, shift_lo, shift_hi, dot, w)
        _square_into(lo, hi, dot, dot, w)
        slot_sub(lo, hi, wy, dot, e, w)
    for j in range(w):
        ends_lo, ends_hi = nan_min(lo[u, j], lo[v, j]), nan_max(hi[u, j], hi[v, j])
        inside = (lo[rho, j] <= top) & (hi[rho, j] >= top)
        lo[k, j], hi[k, j] = interval_sqrt(ends_lo, nan_max(ends_hi, g_top) if inside else ends_hi)
    slot_div(lo, hi, k, r2, k, w)


@kernel
def _branch_side(
    lo: Array,
    hi: Array,
    leg: Array,
    side: float,
    px: Slot,
    q: Slot,
    o: Slot,
    t: Slot,
    s: Slot,
    w: int,
) -> None:  # pragma: no cover - compiled
    """The rest of :func:`_branch_form` into slot ``o``, from the pose's half in
    slots ``t .. t + 7`` (:func:`_branch_pose`), the other elbow in ``q``, ``q +
    1`` and the branch's ``side``: ``(1 - c) cross + (k dot) side``; slots ``s ..
    s + 8`` are scratch."""
    x, y, omc, k = t, t + 1, t + 6, t + 7
    ox, oy, u, v, cross, wx, wy, dot = s, s + 1, s + 2, s + 3, s + 4, s + 5, s + 6, s + 7
    # (Q - O) x (P - O) and (P - O) . (P - Q)
    slot_sub_c(lo, hi, q, leg[BASE_X], leg[BASE_X], ox, w)
    slot_sub_c(lo, hi, q + 1, leg[BASE_Y], leg[BASE_Y], oy, w)
    slot_mul(lo, hi, ox, y, u, w)
    slot_mul(lo, hi, oy, x, v, w)
    slot_sub(lo, hi, u, v, cross, w)
    slot_sub(lo, hi, px, q, wx, w)
    slot_sub(lo, hi, px + 1, q + 1, wy, w)
    slot_mul(lo, hi, x, wx, u, w)
    slot_mul(lo, hi, y, wy, v, w)
    slot_add(lo, hi, u, v, dot, w)
    # (1 - c) cross + (k dot) side
    slot_mul(lo, hi, omc, cross, u, w)
    slot_mul(lo, hi, k, dot, v, w)
    slot_mul_c(lo, hi, v, side, side, v, w)
    slot_add(lo, hi, u, v, o, w)


# the slots of det_a_bounds: the box; the legs' cos, sin and elbows (leg k's
# elbow at _TRIG + 4 k + 2); the rows and their products; det A; a branch form
_P, _TRIG, _ROWS, _NAT, _FORM, _TEMP = 0, 2, 10, 16, 17, 18
_SLOTS = _TEMP + 17


@kernel
def _load_boxes(
    lo: Array, hi: Array, s_lo: Array, s_hi: Array, p: Slot, start: int, size: int
) -> None:  # pragma: no cover - compiled
    """The boxes ``start .. start + size`` of the (n, 2) ``[lo, hi]`` into slots
    ``p``, ``p + 1``."""
    for j in range(size):
        s_lo[p, j], s_hi[p, j] = lo[start + j, 0], hi[start + j, 0]
        s_lo[p + 1, j], s_hi[p + 1, j] = lo[start + j, 1], hi[start + j, 1]


@kernel
def _elbow(
    s_lo: Array,
    s_hi: Array,
    a_lo: Array,
    a_hi: Array,
    leg: Array,
    at: Slot,
    start: int,
    size: int,
) -> None:  # pragma: no cover - compiled
    """A leg's cosine and sine of the angles ``[a_lo, a_hi]`` (from ``start``, box
    by box) into slots ``at``, ``at + 1``, then its elbow into ``at + 2``, ``at +
    3`` (vectorised passes)."""
    for j in range(size):
        c_lo, c_hi, n_lo, n_hi = _cos_sin(a_lo[start + j], a_hi[start + j])
        s_lo[at, j], s_hi[at, j] = c_lo, c_hi
        s_lo[at + 1, j], s_hi[at + 1, j] = n_lo, n_hi
    _knee_passes(s_lo, s_hi, at, leg[A], leg[BASE_X], leg[BASE_Y], size)


@kernel
def _rows_det(
    s_lo: Array, s_hi: Array, p: Slot, e0: Slot, e1: Slot, rows: Slot, nat: Slot, size: int
) -> None:  # pragma: no cover - compiled
    """The rows ``P - C``, ``P - D`` (the pose in ``p``, the elbows in ``e0``,
    ``e1``) into slots ``rows .. rows + 3``, their products into ``rows + 4``,
    ``rows + 5`` and their determinant into ``nat``."""
    slot_sub(s_lo, s_hi, p, e0, rows, size)
    slot_sub(s_lo, s_hi, p + 1, e0 + 1, rows + 1, size)
    slot_sub(s_lo, s_hi, p, e1, rows + 2, size)
    slot_sub(s_lo, s_hi, p + 1, e1 + 1, rows + 3, size)
    slot_mul(s_lo, s_hi, rows, rows + 3, rows + 4, size)
    slot_mul(s_lo, s_hi, rows + 1, rows + 2, rows + 5, size)
    slot_sub(s_lo, s_hi, rows + 4, rows + 5, nat, size)


@kernel
def _meet_form(
    s_lo: Array, s_hi: Array, sign: float, form: Slot, nat: Slot, size: int
) -> None:  # pragma: no cover - compiled
    """Slot ``nat`` intersected with ``sign`` times slot ``form`` (scaled in
    place), a NaN bound or an empty meet leaving ``nat`` as it was."""
    slot_mul_c(s_lo, s_hi, form, sign, sign, form, size)
    for j in range(size):
        m_lo = nan_max(s_lo[nat, j], s_lo[form, j])
        m_hi = nan_min(s_hi[nat, j], s_hi[form, j])
        # a NaN bound leaves the other enclosure, and so does an empty meet
        if not (m_lo != m_lo or m_hi != m_hi or m_lo > m_hi):
            s_lo[nat, j], s_hi[nat, j] = m_lo, m_hi


@kernel
def _g_tops(legs: Array) -> Array:  # pragma: no cover - compiled
    """Each leg's upper bound of ``g(a^2 + b^2)`` (the top of :func:`_g`)."""
    g_top = np.empty(2)
    for leg in range(2):
        top = legs[leg, TOP]
        g_top[leg] = _g(top, top, legs[leg, FOUR_A2], legs[leg, SHIFT_LO], legs[leg, SHIFT_HI])[1]
    return g_top


@kernel
def det_a_bounds(
    lo: Array,
    hi: Array,
    angles_lo: Array,
    angles_hi: Array,
    legs: Array,
    branches: NDArray[np.int64],
    out_lo: Array,
    out_hi: Array,
) -> None:  # pragma: no cover - compiled
    """``FiveBar.det_a_boxes`` of the (n, 2) boxes ``[lo, hi]`` with the legs'
    angle enclosures ``angles`` (2, n) into ``out`` (n,), with ``legs`` (2,
    N_CONSTANTS) and ``branches`` (2,) the posture's branch of each leg (-1:
    no posture). The rows ``P - C``, ``P - D`` stacked, their determinant;
    for a posture, intersected with each leg's branch form (times +1 for the
    leg at A, -1 for the one at B), a NaN or empty meet leaving the enclosure
    as it was."""
    w = _CHUNK
    s_lo, s_hi = np.empty((_SLOTS, w)), np.empty((_SLOTS, w))
    # the slots as run-time integers
    p, trig, rows = np.int64(_P), np.int64(_TRIG), np.int64(_ROWS)
    elbows = (trig + 2, trig + 6)
    nat, form, temp = np.int64(_NAT), np.int64(_FORM), np.int64(_TEMP)
    g_top = _g_tops(legs)
    n = lo.shape[0]
    for s in range(0, n, w):
        size = min(w, n - s)
        _load_boxes(lo, hi, s_lo, s_hi, p, s, size)
        # the elbows: leg k's cos, sin in slots trig + 4 k, + 1, its elbow x, y in + 2, + 3
        for leg in range(2):
            _elbow(s_lo, s_hi, angles_lo[leg], angles_hi[leg], legs[leg], trig + 4 * leg, s, size)
        _rows_det(s_lo, s_hi, p, elbows[0], elbows[1], rows, nat, size)
        if branches[0] >= 0:
            for leg in range(2):
                side = 1.0 if branches[leg] == 0 else -1.0
                _branch_form(
                    s_lo, s_hi, legs[leg], side, g_top[leg], p, elbows[1 - leg], form, temp, size
                )
                _meet_form(s_lo, s_hi, 1.0 if leg == 0 else -1.0, form, nat, size)
        out_lo[s : s + size] = s_lo[nat, :size]
        out_hi[s : s + size] = s_hi[nat, :size]


# the slots of det_a_postures: the box; leg k's cos, sin and elbow on branch b
# from _PTRIG + 8 k + 4 b; the rows and their products; det A; a branch form;
# leg k's half of its forms that depends on the pose alone from _PPOSE + 8 k
_PP, _PTRIG, _PROWS, _PNAT, _PFORM, _PPOSE, _PTEMP = 0, 2, 18, 24, 25, 26, 42
_P_SLOTS = _PTEMP + 9


@kernel
def det_a_postures(
    lo: Array,
    hi: Array,
    angles_lo: Array,
    angles_hi: Array,
    legs: Array,
    postures: NDArray[np.int64],
    out_lo: Array,
    out_hi: Array,
) -> None:  # pragma: no cover - compiled
    """:func:`det_a_bounds` of every posture at once: ``angles`` (2, 2, n) each
    leg's enclosure on each branch, ``postures`` (P, 2) each posture's branches,
    ``out`` (P, n). What one leg's branch or the pose alone determines (the
    elbows, the pose's half of the branch forms) is computed once for the
    postures, not once for each: the same operations on the same operands, so
    the bounds of :func:`det_a_bounds` of each posture, bit for bit."""
    w = _CHUNK
    s_lo, s_hi = np.empty((_P_SLOTS, w)), np.empty((_P_SLOTS, w))
    p, trig, rows = np.int64(_PP), np.int64(_PTRIG), np.int64(_PROWS)
    nat, form, pose, temp = np.int64(_PNAT), np.int64(_PFORM), np.int64(_PPOSE), np.int64(_PTEMP)
    g_top = _g_tops(legs)
    n = lo.shape[0]
    for s in range(0, n, w):
        size = min(w, n - s)
        _load_boxes(lo, hi, s_lo, s_hi, p, s, size)
        for leg in range(2):
            for b in range(2):
                at = trig + 8 * leg + 4 * b
                _elbow(s_lo, s_hi, angles_lo[leg, b], angles_hi[leg, b], legs[leg], at, s, size)
            _branch_pose(s_lo, s_hi, legs[leg], g_top[leg], p, pose + 8 * leg, temp, size)
        for q in range(postures.shape[0]):
            elbows = (trig + 4 * postures[q, 0] + 2, trig + 8 + 4 * postures[q, 1] + 2)
            _rows_det(s_lo, s_hi, p, elbows[0], elbows[1], rows, nat, size)
            for leg in range(2):
                side = 1.0 if postures[q, leg] == 0 else -1.0
                _branch_side(
                    s_lo, s_hi, legs[leg], side, p, elbows[1 - leg], form, pose + 8 * leg, temp,
                    size,
                )  # fmt: skip
                _meet_form(s_lo, s_hi, 1.0 if leg == 0 else -1.0, form, nat, size)
            out_lo[q, s : s + size] = s_lo[nat, :size]
            out_hi[q, s : s + size] = s_hi[nat, :size]


# ------------------------------------------------------------------ reach
@kernel(inline=True)
def _near_far(
    lo: float, hi: float, base: float
) -> tuple[float, float]:  # pragma: no cover - compiled
    """One axis of the box's point nearest the base (``np.clip``) and of its
    corner farthest from it."""
    near = nan_min(nan_max(base, lo), hi)
    far = lo if abs(lo - base) > abs(hi - base) else hi
    return near, far


@kernel
def _sqrt_into(lo: Array, hi: Array, a: Slot, o: Slot, w: int) -> None:  # pragma: no cover
    """Slot ``o`` = ``intervals.sqrt`` of slot ``a``."""
    a_lo, a_hi, o_lo, o_hi = lo[a, :w], hi[a, :w], lo[o, :w], hi[o, :w]
    for j in range(w):
        o_lo[j], o_hi[j] = interval_sqrt(a_lo[j], a_hi[j])


# the slots of the legs' chunks (_leg_chunk): the box (x, y); its nearest point and
# farthest corner (x, y each); their squared distances from the base, and g of
# them; the box about the base (dx, dy); scratch; the constants 2a and k; then
# what reach_prepare or fold_terms_prepare add
_LP, _LNEAR, _LFAR, _LN2, _LF2, _LGN, _LGF, _LDX, _LDY = 0, 2, 4, 6, 7, 8, 9, 10, 11
_LA, _LB, _LR, _LTWO_A, _LK, _LMORE = 12, 13, 14, 15, 16, 17
_LSLOTS = _LMORE + 4


@kernel
def _distance_g(
    lo: Array, hi: Array, point: Slot, rho2: Slot, g: Slot, bx: float, by: float, w: int
) -> None:  # pragma: no cover - compiled
    """The squared distance from the base ``(bx, by)`` of the point in slots
    ``point``, ``point + 1`` into ``rho2``, and ``g`` of it into slot ``g``."""
    a, b, r = np.int64(_LA), np.int64(_LB), np.int64(_LR)
    slot_sub_c(lo, hi, point, bx, bx, a, w)
    _square_into(lo, hi, a, a, w)
    slot_sub_c(lo, hi, point + 1, by, by, b, w)
    _square_into(lo, hi, b, b, w)
    slot_add(lo, hi, a, b, rho2, w)
    _sqrt_into(lo, hi, rho2, r, w)
    slot_div(lo, hi, r, np.int64(_LTWO_A), a, w)
    slot_div(lo, hi, np.int64(_LK), r, b, w)
    slot_add(lo, hi, a, b, g, w)


@kernel
def _leg_chunk(
    box_lo: Array, box_hi: Array, s: int, w: int, leg: Array, lo: Array, hi: Array
) -> None:  # pragma: no cover - compiled
    """What ``RRLeg.reach`` and ``_fold_terms`` share, for the boxes ``s:s + w``
    into the slots above: the squared distances ``near2``, ``far2`` of the box's
    point nearest the base (``np.clip``) and corner farthest from it
    (``square(near - base)`` summed over the axes), ``g`` of each
    (``RRLeg._alpha``: ``rho / 2a + k / rho``, ``rho = sqrt(rho2)``), and ``dx``,
    ``dy`` (the box less the base)."""
    bx, by = leg[BASE_X], leg[BASE_Y]
    for j in range(w):
        x_lo, x_hi = box_lo[s + j, 0], box_hi[s + j, 0]
        y_lo, y_hi = box_lo[s + j, 1], box_hi[s + j, 1]
        lo[_LP, j], hi[_LP, j] = x_lo, x_hi
        lo[_LP + 1, j], hi[_LP + 1, j] = y_lo, y_hi
        nx, fx = _near_far(x_lo, x_hi, bx)
        ny, fy = _near_far(y_lo, y_hi, by)
        lo[_LNEAR, j], hi[_LNEAR, j] = nx, nx
        lo[_LNEAR + 1, j], hi[_LNEAR + 1, j] = ny, ny
        lo[_LFAR, j], hi[_LFAR, j] = fx, fx
        lo[_LFAR + 1, j], hi[_LFAR + 1, j] = fy, fy
    lo[_LTWO_A, :w] = leg[TWO_A]
    hi[_LTWO_A, :w] = leg[TWO_A]
    lo[_LK, :w] = leg[K_LO]
    hi[_LK, :w] = leg[K_HI]
    _distance_g(lo, hi, np.int64(_LNEAR), np.int64(_LN2), np.int64(_LGN), bx, by, w)
    _distance_g(lo, hi, np.int64(_LFAR), np.int64(_LF2), np.int64(_LGF), bx, by, w)
    slot_sub_c(lo, hi, np.int64(_LP), bx, bx, np.int64(_LDX), w)
    slot_sub_c(lo, hi, np.int64(_LP + 1), by, by, np.int64(_LDY), w)


@kernel
def _arccos_args(
    lo: Array, hi: Array, j: int, leg: Array
) -> tuple[float, float]:  # pragma: no cover - compiled
    """``RRLeg._alpha`` up to its arccos, for box ``j`` of a chunk (:func:`_leg_chunk`):
    the clipped arguments whose arccos are the lower and upper bounds of alpha (of
    the upper and lower bounds of g)."""
    g_lo = nan_min(lo[_LGN, j], lo[_LGF, j])
    g_hi = nan_max(hi[_LGN, j], hi[_LGF, j])
    if leg[K_POSITIVE] > 0:
        inside = lo[_LN2, j] <= leg[STAR_HI] and hi[_LF2, j] >= leg[STAR_LO]
        if inside:
            g_lo = nan_min(g_lo, leg[G_MIN])
    g_lo = -np.inf if g_lo != g_lo else g_lo
    g_hi = np.inf if g_hi != g_hi else g_hi
    # intervals.arccos: np.clip of each bound to [-1, 1]
    return nan_min(nan_max(g_hi, -1.0), 1.0), nan_min(nan_max(g_lo, -1.0), 1.0)


@kernel(inline=True)
def _alpha(acos_lo: float, acos_hi: float) -> tuple[float, float]:  # pragma: no cover
    """``intervals.arccos`` from the arccos of its two arguments."""
    return nan_max(lib_below(acos_lo), 0.0), nan_min(lib_above(acos_hi), _PI_UP)


@kernel
def reach_prepare(
    lo: Array,
    hi: Array,
    cs: Array,
    sn: Array,
    leg: Array,
    codes: NDArray[np.uint8],
    out: Array,
    status: NDArray[np.uint8],
) -> None:  # pragma: no cover - compiled
    """``RRLeg.reach`` up to its library functions, over the (n, 2) boxes: into
    ``status`` (n,) the reach codes (``codes``: REGULAR, FOLD_OUTER, FOLD_INNER,
    REACH_OUT, REACH_UNKNOWN); into ``out`` (6, n) the arguments of alpha's
    arccos (:func:`_arccos_args`) and the bounds of ``ux``, ``uy``, the box
    about the base rotated by the direction ``(cs, sn)`` of its centre (whose
    corners' arctan2 give the direction's enclosure)."""
    w = _CHUNK
    s_lo, s_hi = np.empty((_LSLOTS, w)), np.empty((_LSLOTS, w))
    cs_at, sn_at, ux, uy = _LMORE, _LMORE + 1, _LMORE + 2, _LMORE + 3
    a, b = np.int64(_LA), np.int64(_LB)
    out_lo, out_hi = leg[OUT_LO], leg[OUT_HI]
    in_lo, in_hi = leg[IN_LO], leg[IN_HI]
    n = lo.shape[0]
    for s in range(0, n, w):
        size = min(w, n - s)
        _leg_chunk(lo, hi, s, size, leg, s_lo, s_hi)
        for j in range(size):
            n_lo, n_hi = s_lo[_LN2, j], s_hi[_LN2, j]
            f_lo, f_hi = s_lo[_LF2, j], s_hi[_LF2, j]
            away = (n_lo > out_hi) or (f_hi < in_lo)
            regular = (n_lo > in_hi) and (f_hi < out_lo) and (n_lo > 0)
            straddle_out = (n_hi < out_lo) and (f_lo > out_hi)
            straddle_in = (n_hi < in_lo) and (f_lo > in_hi)
            fold_outer = straddle_out and (n_lo > in_hi) and not away
            fold_inner = straddle_in and (f_hi < out_lo) and not away and (in_lo > 0)
            code = codes[4]
            if fold_inner:
                code = codes[2]
            if fold_outer:
                code = codes[1]
            if regular:
                code = codes[0]
            if away:
                code = codes[3]
            status[s + j] = code
            out[0, s + j], out[1, s + j] = _arccos_args(s_lo, s_hi, j, leg)
            s_lo[cs_at, j], s_hi[cs_at, j] = cs[s + j], cs[s + j]
            s_lo[sn_at, j], s_hi[sn_at, j] = sn[s + j], sn[s + j]
        # the box about the base, turned by the direction of its centre
        slot_mul(s_lo, s_hi, np.int64(_LDX), np.int64(cs_at), a, size)
        slot_mul(s_lo, s_hi, np.int64(_LDY), np.int64(sn_at), b, size)
        slot_add(s_lo, s_hi, a, b, np.int64(ux), size)
        slot_mul(s_lo, s_hi, np.int64(_LDY), np.int64(cs_at), a, size)
        slot_mul(s_lo, s_hi, np.int64(_LDX), np.int64(sn_at), b, size)
        slot_sub(s_lo, s_hi, a, b, np.int64(uy), size)
        out[2, s : s + size] = s_lo[ux, :size]
        out[3, s : s + size] = s_hi[ux, :size]
        out[4, s : s + size] = s_lo[uy, :size]
        out[5, s : s + size] = s_hi[uy, :size]


#: ``reach``'s enclosure of 2 pi
_TWO_PI_LO = float(np.nextafter(2 * np.pi, 0.0))
_TWO_PI_HI = float(np.nextafter(2 * np.pi, np.inf))


@kernel
def reach_finish(
    lo: Array,
    hi: Array,
    status: NDArray[np.uint8],
    codes: NDArray[np.uint8],
    cs: Array,
    sn: Array,
    ref: Array,
    corners: Array,
    prep: Array,
    acos: Array,
    leg: Array,
    out_lo: Array,
    out_hi: Array,
    fold_connected: NDArray[np.bool_],
) -> None:  # pragma: no cover - compiled
    """``RRLeg.reach`` after its library functions: with ``ref`` the arctan2 of
    ``(sn, cs)``, ``corners`` (4, n) the arctan2 of the corners of ``(uy, ux)``
    (lo lo, lo hi, hi lo, hi hi; ``prep`` from :func:`reach_prepare`) and
    ``acos`` (2, n) the arccos of alpha's arguments, the branches ``theta +
    alpha``, ``theta - alpha`` and the hull of both into ``out`` (3, n), and
    where the leg's configurations join through its fold into
    ``fold_connected``."""
    unknown, outer, inner = codes[4], codes[1], codes[2]
    for j in range(lo.shape[0]):
        a_lo, a_hi = _alpha(acos[0, j], acos[1, j])
        # the direction: the centre's, plus that of the box turned back by it
        v = ref[j]
        r_lo, r_hi = atan_bounds(v, v, cs[j] <= 0 and sn[j] <= 0 and sn[j] >= 0)
        c0, c1, c2, c3 = corners[0, j], corners[1, j], corners[2, j], corners[3, j]
        m_lo = nan_min(nan_min(nan_min(c0, c1), c2), c3)
        m_hi = nan_max(nan_max(nan_max(c0, c1), c2), c3)
        cut = prep[2, j] <= 0 and prep[4, j] <= 0 and prep[5, j] >= 0
        t_lo, t_hi = atan_bounds(m_lo, m_hi, cut)
        th_lo, th_hi = interval_add(r_lo, r_hi, t_lo, t_hi)
        out_lo[0, j], out_hi[0, j] = interval_add(th_lo, th_hi, a_lo, a_hi)
        out_lo[1, j], out_hi[1, j] = interval_sub(th_lo, th_hi, a_lo, a_hi)
        # the hull: theta + [-alpha, alpha] or theta + [alpha, 2 pi - alpha]
        z_lo, z_hi = interval_add(th_lo, th_hi, -a_hi, a_hi)
        q_lo, q_hi = interval_sub(_TWO_PI_LO, _TWO_PI_HI, a_lo, a_lo)
        p_lo, p_hi = interval_add(th_lo, th_hi, nan_min(a_lo, q_lo), nan_max(a_lo, q_hi))
        if z_hi - z_lo <= p_hi - p_lo:
            h_lo, h_hi = z_lo, z_hi
        else:
            h_lo, h_hi = p_lo, p_hi
        code = status[j]
        if code == unknown:
            h_lo, h_hi = -np.inf, np.inf
        out_lo[2, j], out_hi[2, j] = h_lo, h_hi
        bx, by = leg[BASE_X], leg[BASE_Y]
        beyond = (bx < lo[j, 0] or bx > hi[j, 0]) and (by < lo[j, 1] or by > hi[j, 1])
        fold_connected[j] = code == outer or (code == inner and beyond)


# ------------------------------------------------------------------ fold flows
#: the rows of the fold terms (fold_terms_prepare): the box about the base, its
#: distance and squared distance, then g' (the slope), replaced by alpha's scale
DX, DY, RHO, RHO2, SCALE = range(5)


@kernel
def fold_terms_prepare(
    lo: Array, hi: Array, leg: Array, terms_lo: Array, terms_hi: Array, args: Array
) -> None:  # pragma: no cover - compiled
    """``RRLeg._fold_terms`` up to its arccos: ``dx``, ``dy``, ``rho``, ``rho2`` and
    the slope ``g'(rho)`` over the (n, 2) boxes into ``terms`` (5, n), the
    arguments of alpha's arccos into ``args`` (2, n)."""
    w = _CHUNK
    s_lo, s_hi = np.empty((_LSLOTS, w)), np.empty((_LSLOTS, w))
    a, b = np.int64(_LA), np.int64(_LB)
    rho2, rho = np.int64(_LMORE), np.int64(_LMORE + 1)
    q, slope = np.int64(_LMORE + 2), np.int64(_LMORE + 3)
    n = lo.shape[0]
    for s in range(0, n, w):
        size = min(w, n - s)
        _leg_chunk(lo, hi, s, size, leg, s_lo, s_hi)
        _square_into(s_lo, s_hi, np.int64(_LDX), a, size)
        _square_into(s_lo, s_hi, np.int64(_LDY), b, size)
        slot_add(s_lo, s_hi, a, b, rho2, size)
        _sqrt_into(s_lo, s_hi, rho2, rho, size)
        slot_div(s_lo, s_hi, np.int64(_LK), rho2, q, size)
        slot_c_sub(s_lo, s_hi, leg[SLOPE_LO], leg[SLOPE_HI], q, slope, size)
        terms_lo[DX, s : s + size] = s_lo[_LDX, :size]
        terms_hi[DX, s : s + size] = s_hi[_LDX, :size]
        terms_lo[DY, s : s + size] = s_lo[_LDY, :size]
        terms_hi[DY, s : s + size] = s_hi[_LDY, :size]
        terms_lo[RHO, s : s + size] = s_lo[rho, :size]
        terms_hi[RHO, s : s + size] = s_hi[rho, :size]
        terms_lo[RHO2, s : s + size] = s_lo[rho2, :size]
        terms_hi[RHO2, s : s + size] = s_hi[rho2, :size]
        terms_lo[SCALE, s : s + size] = s_lo[slope, :size]
        terms_hi[SCALE, s : s + size] = s_hi[slope, :size]
        for j in range(size):
            args[0, s + j], args[1, s + j] = _arccos_args(s_lo, s_hi, j, leg)


@kernel
def fold_terms_finish(
    acos: Array, terms_lo: Array, terms_hi: Array
) -> None:  # pragma: no cover - compiled
    """``RRLeg._fold_terms`` after its arccos (``acos`` (2, n)): the slope in
    ``terms`` times ``[1 / max sin alpha, inf]``, alpha's scale."""
    for j in range(acos.shape[1]):
        a_lo, a_hi = _alpha(acos[0, j], acos[1, j])
        sin_max = _trig(a_lo, a_hi, True)[1]
        inverse = 0.0
        if sin_max > 0:
            inverse = np.nextafter(1.0 / nan_max(sin_max, 1e-300), 0.0)
        terms_lo[SCALE, j], terms_hi[SCALE, j] = interval_mul(
            terms_lo[SCALE, j], terms_hi[SCALE, j], inverse, np.inf
        )


@kernel
def fold_rate_bounds(
    terms_lo: Array,
    terms_hi: Array,
    velocity_lo: Array,
    velocity_hi: Array,
    status: NDArray[np.uint8],
    codes: NDArray[np.uint8],
    sign: float,
    keeps: NDArray[np.bool_],
    out_lo: Array,
    out_hi: Array,
) -> None:  # pragma: no cover - compiled
    """``RRLeg.fold_flow`` from the fold terms (``terms`` (5, n)) and the velocity
    (2, n): whether the motion keeps the pose reachable (``keeps``), and the
    joint's rate ``turning / rho2 + (-scale (radial / rho)) sign`` into ``out``."""
    outer, inner = codes[1], codes[2]
    for j in range(terms_lo.shape[1]):
        x_lo, x_hi = terms_lo[DX, j], terms_hi[DX, j]
        y_lo, y_hi = terms_lo[DY, j], terms_hi[DY, j]
        u_lo, u_hi = velocity_lo[0, j], velocity_hi[0, j]
        v_lo, v_hi = velocity_lo[1, j], velocity_hi[1, j]
        p_lo, p_hi = interval_mul(x_lo, x_hi, u_lo, u_hi)
        q_lo, q_hi = interval_mul(y_lo, y_hi, v_lo, v_hi)
        radial_lo, radial_hi = interval_add(p_lo, p_hi, q_lo, q_hi)
        p_lo, p_hi = interval_mul(x_lo, x_hi, v_lo, v_hi)
        q_lo, q_hi = interval_mul(y_lo, y_hi, u_lo, u_hi)
        turn_lo, turn_hi = interval_sub(p_lo, p_hi, q_lo, q_hi)
        code = status[j]
        keeps[j] = (code == outer and radial_hi <= 0) or (code == inner and radial_lo >= 0)
        p_lo, p_hi = interval_div(radial_lo, radial_hi, terms_lo[RHO, j], terms_hi[RHO, j])
        p_lo, p_hi = interval_mul(-terms_hi[SCALE, j], -terms_lo[SCALE, j], p_lo, p_hi)
        q_lo, q_hi = interval_div(turn_lo, turn_hi, terms_lo[RHO2, j], terms_hi[RHO2, j])
        p_lo, p_hi = interval_mul(p_lo, p_hi, sign, sign)
        out_lo[j], out_hi[j] = interval_add(q_lo, q_hi, p_lo, p_hi)
