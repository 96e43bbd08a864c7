"""Compiled interval enclosures of the Delta's legs: their reach over boxes of
poses (``DeltaLeg.reach``), the joints' gradients (``DeltaLeg.joint_gradient``)
and the flows across their folds (``DeltaLeg.fold_flow``).

As in :mod:`._delta_kernels` (whose one-box helpers ``plane`` and ``g_boxes``
these kernels share, with ``intervals.atan_bounds``), each kernel repeats the
:class:`~moveability.intervals.Interval` operations of the reference kept in
:class:`~.delta.DeltaLeg` (``_reach_intervals``, ``_joint_gradient_intervals``,
``_fold_flow_intervals``) box by box: the same operations on the same operands
in the same order, each rounded outwards by the compiled one-element steps of
:mod:`moveability.intervals`, so the bounds are the same floats, bit for bit
(tests/mechanisms/test_delta_leg_kernels.py compares them on boxes of every
kind). The cosines and sines of angle enclosures are ``intervals.trig_bounds``
itself.

The library functions of numpy (``arccos``, ``arctan2``, the ``cos`` and ``sin``
of a box's direction from its centre) are left to numpy between the kernels,
on contiguous arrays of the same arguments as in the Interval code: numpy may
evaluate them with its own vectorised code, whose results differ from the C
library's in the last bits. So the reach runs in three kernels:
:func:`reach_prepare` (the range of ``g``, the reach codes, whether a fold
connects, alpha's arccos arguments and the centre of ``(s, w)``),
:func:`reach_turn` (the box of ``(s, w)`` turned by its centre's direction,
whose corners' arctan2 numpy takes) and :func:`reach_finish` (the direction,
alpha, the branches and the hull); the fold terms in two
(:func:`fold_terms_prepare`, :func:`fold_terms_finish`, about alpha's arccos),
then :func:`fold_rate_bounds` for each velocity.

A leg enters as its row of ``Delta``'s constants (``DeltaLeg.constants``, the
entries of :mod:`._delta_kernels`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..compiled import kernel
from ..intervals import (
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
    trig_bounds,
)
from ..types import Array
from ._delta_kernels import (
    ARM,
    C_HI,
    C_LO,
    LIB_REL,
    LIB_TINY,
    OFF_HI,
    OFF_LO,
    PI_UP,
    TWO_ARM,
    UX_HI,
    UX_LO,
    UY_HI,
    UY_LO,
    clip_mid,
    g_boxes,
    plane,
)

__all__ = [
    "fold_rate_bounds",
    "fold_terms_finish",
    "fold_terms_prepare",
    "joint_gradient_bounds",
    "reach_finish",
    "reach_prepare",
    "reach_turn",
]

#: the enclosure of 2 pi of ``DeltaLeg.reach``'s hull about a folded leg
_TWO_PI_LO = float(np.nextafter(2 * np.pi, 0.0))
_TWO_PI_HI = float(np.nextafter(2 * np.pi, np.inf))

#: the rows of :func:`reach_prepare`'s ``out``: alpha's arccos arguments (of its
#: lower, then upper bound), the centres of ``s`` and ``w = -z``, the bounds of
#: ``s`` and ``w``
(
    P_ACOS_LO, P_ACOS_HI, P_S_MID, P_W_MID, P_S_LO, P_S_HI, P_W_LO, P_W_HI, N_PREP,
) = range(9)  # fmt: skip
#: the kinds of fold of :func:`reach_prepare` (which the hull takes)
NO_FOLD, OUTER, INNER = 0, 1, 2
#: the terms of :func:`fold_terms_prepare`: dg/dx, dg/dy, dg/dz, s, w, t^2, and the
#: enclosure of 1 / sin alpha
T_GX, T_GY, T_GZ, T_S, T_W, T_T2, T_INV, N_TERMS = range(8)


# ------------------------------------------------------------------ one box
@kernel(inline=True)
def _reachable(
    x_lo: float, x_hi: float, y_lo: float, y_hi: float, z_lo: float, z_hi: float, leg: Array
) -> bool:  # pragma: no cover - compiled
    """Whether the leg is regular over the box (``t > 0`` and ``|g| < 1``)."""
    g_lo, g_hi, t_lo, _, _ = g_boxes(x_lo, x_hi, y_lo, y_hi, z_lo, z_hi, leg)
    return (t_lo > 0) and (g_lo > -1.0) and (g_hi < 1.0)


@kernel
def _g_gradient(
    x_lo: float, x_hi: float, y_lo: float, y_hi: float, z_lo: float, z_hi: float, leg: Array
) -> tuple[float, float, float, float, float, float]:  # pragma: no cover - compiled
    """``DeltaLeg._g_gradient`` of one box: the bounds of ``dg/dx``, ``dg/dy``,
    ``dg/dz``. ``scale = (t^2 - d^2 - c) / (t^2 t 2 la)``, ``gs = s scale``, ``gd =
    d / (t la)``: ``(gs u_x - gd u_y, gs u_y + gd u_x, z scale)``."""
    s_lo, s_hi, d_lo, d_hi = plane(x_lo, x_hi, y_lo, y_hi, leg)
    a_lo, a_hi = interval_square(s_lo, s_hi)
    b_lo, b_hi = interval_square(z_lo, z_hi)
    t2_lo, t2_hi = interval_add(a_lo, a_hi, b_lo, b_hi)
    t_lo, t_hi = interval_sqrt(t2_lo, t2_hi)
    d2_lo, d2_hi = interval_square(d_lo, d_hi)
    n_lo, n_hi = interval_sub(t2_lo, t2_hi, d2_lo, d2_hi)
    n_lo, n_hi = interval_sub(n_lo, n_hi, leg[C_LO], leg[C_HI])
    m_lo, m_hi = interval_mul(t2_lo, t2_hi, t_lo, t_hi)
    m_lo, m_hi = interval_mul(m_lo, m_hi, leg[TWO_ARM], leg[TWO_ARM])
    k_lo, k_hi = interval_div(n_lo, n_hi, m_lo, m_hi)
    gs_lo, gs_hi = interval_mul(s_lo, s_hi, k_lo, k_hi)
    m_lo, m_hi = interval_mul(t_lo, t_hi, leg[ARM], leg[ARM])
    gd_lo, gd_hi = interval_div(d_lo, d_hi, m_lo, m_hi)
    p_lo, p_hi = interval_mul(gs_lo, gs_hi, leg[UX_LO], leg[UX_HI])
    q_lo, q_hi = interval_mul(gd_lo, gd_hi, leg[UY_LO], leg[UY_HI])
    gx_lo, gx_hi = interval_sub(p_lo, p_hi, q_lo, q_hi)
    p_lo, p_hi = interval_mul(gs_lo, gs_hi, leg[UY_LO], leg[UY_HI])
    q_lo, q_hi = interval_mul(gd_lo, gd_hi, leg[UX_LO], leg[UX_HI])
    gy_lo, gy_hi = interval_add(p_lo, p_hi, q_lo, q_hi)
    gz_lo, gz_hi = interval_mul(z_lo, z_hi, k_lo, k_hi)
    return gx_lo, gx_hi, gy_lo, gy_hi, gz_lo, gz_hi


@kernel
def _fold_axis(box: Array, outer: bool, leg: Array) -> tuple[int, int]:  # pragma: no cover
    """``DeltaLeg._fold_axes`` of one fold box (``box`` (6,): the bounds of x, y,
    z): the axis along which ``G`` (``g``, or ``-g`` about an inner fold) rises
    certifiably and whose face at the low end (``+1``) or the high end
    (``-1``) is wholly reachable; ``-1`` and 0 for none."""
    grads = _g_gradient(box[0], box[1], box[2], box[3], box[4], box[5], leg)
    face = box.copy()
    axis, direction = -1, 0
    for j in range(3):
        g_lo, g_hi = grads[2 * j], grads[2 * j + 1]
        finite = np.isfinite(g_lo) and np.isfinite(g_hi)
        rising = finite and ((g_lo > 0) if outer else (g_hi < 0))
        falling = finite and ((g_hi < 0) if outer else (g_lo > 0))
        for sense in (1, -1):
            if not (rising if sense > 0 else falling) or axis >= 0:
                continue
            face[:] = box
            at = box[2 * j] if sense > 0 else box[2 * j + 1]
            face[2 * j], face[2 * j + 1] = at, at
            if _reachable(face[0], face[1], face[2], face[3], face[4], face[5], leg):
                axis, direction = j, sense
    return axis, direction


# ------------------------------------------------------------------ the reach
@kernel
def reach_prepare(
    lo: Array,
    hi: Array,
    leg: Array,
    codes: NDArray[np.uint8],
    status: NDArray[np.uint8],
    fold: NDArray[np.uint8],
    connected: NDArray[np.bool_],
    out: Array,
) -> None:  # pragma: no cover - compiled
    """``DeltaLeg.reach`` over the (n, 3) boxes up to its library functions.

    Into ``status`` (n,) the reach codes (``codes``: REGULAR, FOLD_OUTER,
    FOLD_INNER, REACH_OUT, REACH_UNKNOWN, in this order), into ``fold`` the kind
    of certified fold (:data:`OUTER` first where both would hold, as the hull
    takes them, :data:`INNER`, :data:`NO_FOLD`), into ``connected`` whether the
    fold connects (:func:`_fold_axis`), into ``out`` (N_PREP, n) the rows
    ``P_*``. A fold is certified from the box's centre and corners, in the
    order of ``DeltaLeg._witness_points``."""
    point = np.empty(3)
    box = np.empty(6)
    for j in range(lo.shape[0]):
        g_lo, g_hi, t_lo, s_lo, s_hi = g_boxes(
            lo[j, 0], hi[j, 0], lo[j, 1], hi[j, 1], lo[j, 2], hi[j, 2], leg
        )
        away = (g_lo > 1.0) or (g_hi < -1.0)
        positive = t_lo > 0
        regular = positive and (g_lo > -1.0) and (g_hi < 1.0) and not away
        maybe_outer = positive and (g_lo > -1.0) and not regular and not away
        maybe_inner = positive and (g_hi < 1.0) and not regular and not away
        fold_outer, fold_inner = False, False
        if maybe_outer or maybe_inner:
            below_one, above_one, below_minus, above_minus = False, False, False, False
            for w in range(9):
                for axis in range(3):
                    if w == 0:
                        point[axis] = 0.5 * lo[j, axis] + 0.5 * hi[j, axis]
                    else:
                        point[axis] = hi[j, axis] if ((w - 1) >> axis) & 1 else lo[j, axis]
                p_lo, p_hi, _, _, _ = g_boxes(
                    point[0], point[0], point[1], point[1], point[2], point[2], leg
                )
                below_one = below_one or p_hi < 1.0
                above_one = above_one or p_lo > 1.0
                below_minus = below_minus or p_hi < -1.0
                above_minus = above_minus or p_lo > -1.0
            fold_outer = maybe_outer and below_one and above_one
            fold_inner = maybe_inner and above_minus and below_minus
        code = codes[4]
        if fold_outer:
            code = codes[1]
        if fold_inner:
            code = codes[2]
        if regular:
            code = codes[0]
        if away:
            code = codes[3]
        status[j] = code
        fold[j] = OUTER if fold_outer else (INNER if fold_inner else NO_FOLD)
        linked = False
        if fold_outer or fold_inner:
            for axis in range(3):
                box[2 * axis], box[2 * axis + 1] = lo[j, axis], hi[j, axis]
            linked = _fold_axis(box, fold_outer, leg)[0] >= 0
        connected[j] = linked
        # intervals.arccos of [g_lo, g_hi]: np.clip of each bound to [-1, 1]
        out[P_ACOS_LO, j] = nan_min(nan_max(g_hi, -1.0), 1.0)
        out[P_ACOS_HI, j] = nan_min(nan_max(g_lo, -1.0), 1.0)
        w_lo, w_hi = -hi[j, 2], -lo[j, 2]
        out[P_S_MID, j] = clip_mid(s_lo, s_hi)
        out[P_W_MID, j] = clip_mid(w_lo, w_hi)
        out[P_S_LO, j], out[P_S_HI, j] = s_lo, s_hi
        out[P_W_LO, j], out[P_W_HI, j] = w_lo, w_hi


@kernel
def reach_turn(prep: Array, cs: Array, sn: Array, out: Array) -> None:  # pragma: no cover
    """``DeltaLeg._direction`` up to its arctan2 of the corners: ``s``, ``w`` (in
    ``prep``, see :func:`reach_prepare`) turned by the direction ``(cs, sn)``
    (n,) of their centre, ``us = s cs + w sn`` and ``uw = w cs - s sn``, into
    ``out`` (4, n): the bounds of ``us``, then of ``uw``."""
    for j in range(cs.shape[0]):
        s_lo, s_hi = prep[P_S_LO, j], prep[P_S_HI, j]
        w_lo, w_hi = prep[P_W_LO, j], prep[P_W_HI, j]
        c, s = cs[j], sn[j]
        p_lo, p_hi = interval_mul(s_lo, s_hi, c, c)
        q_lo, q_hi = interval_mul(w_lo, w_hi, s, s)
        out[0, j], out[1, j] = interval_add(p_lo, p_hi, q_lo, q_hi)
        p_lo, p_hi = interval_mul(w_lo, w_hi, c, c)
        q_lo, q_hi = interval_mul(s_lo, s_hi, s, s)
        out[2, j], out[3, j] = interval_sub(p_lo, p_hi, q_lo, q_hi)


@kernel
def reach_finish(
    fold: NDArray[np.uint8],
    cs: Array,
    sn: Array,
    ref: Array,
    corners: Array,
    turned: Array,
    acos: Array,
    out_lo: Array,
    out_hi: Array,
) -> None:  # pragma: no cover - compiled
    """``DeltaLeg.reach`` after its library functions, into ``out`` (3, n): the
    branches (the direction plus alpha, minus alpha) and the hull (about 0
    where ``fold`` is OUTER, about pi where INNER, else the whole line). From
    the arctan2 ``ref`` (n,) of the centres' directions ``(cs, sn)``, the
    arctan2 ``corners`` (4, n) of the corners of the turned box (``turned``,
    from :func:`reach_turn`: lo lo, lo hi, hi lo, hi hi of ``(uw, us)``) and
    the arccos ``acos`` (2, n) of alpha's arguments."""
    for j in range(cs.shape[0]):
        c, s = cs[j], sn[j]
        r_lo, r_hi = atan_bounds(ref[j], ref[j], (c <= 0) & (s <= 0) & (s >= 0))
        c0, c1, c2, c3 = corners[0, j], corners[1, j], corners[2, j], corners[3, j]
        least = nan_min(nan_min(nan_min(c0, c1), c2), c3)
        most = nan_max(nan_max(nan_max(c0, c1), c2), c3)
        cut = (turned[0, j] <= 0) & (turned[2, j] <= 0) & (turned[3, j] >= 0)
        t_lo, t_hi = atan_bounds(least, most, cut)
        d_lo, d_hi = interval_add(r_lo, r_hi, t_lo, t_hi)
        a_lo = nan_max(lib_below(acos[0, j]), 0.0)
        a_hi = nan_min(lib_above(acos[1, j]), PI_UP)
        out_lo[0, j], out_hi[0, j] = interval_add(d_lo, d_hi, a_lo, a_hi)
        out_lo[1, j], out_hi[1, j] = interval_sub(d_lo, d_hi, a_lo, a_hi)
        kind = fold[j]
        if kind == OUTER:
            out_lo[2, j], out_hi[2, j] = interval_add(d_lo, d_hi, -a_hi, a_hi)
        elif kind == INNER:
            p_lo, p_hi = interval_sub(_TWO_PI_LO, _TWO_PI_HI, a_lo, a_lo)
            out_lo[2, j], out_hi[2, j] = interval_add(
                d_lo, d_hi, nan_min(a_lo, p_lo), nan_max(a_lo, p_hi)
            )
        else:
            out_lo[2, j], out_hi[2, j] = -np.inf, np.inf


# ------------------------------------------------------------------ gradients
@kernel
def joint_gradient_bounds(
    lo: Array, hi: Array, a_lo: Array, a_hi: Array, leg: Array, out_lo: Array, out_hi: Array
) -> None:  # pragma: no cover - compiled
    """``DeltaLeg.joint_gradient`` over the (n, 3) boxes and the angle enclosures
    ``[a_lo, a_hi]`` (n,), into ``out`` (3, n): ``-row / (la (s sin + z cos))``,
    the row ``(x + h u_x, y + h u_y, z + la sin)`` with ``h = (r - R) - la
    cos``."""
    c_lo, c_hi = trig_bounds(a_lo, a_hi, False, LIB_REL, LIB_TINY)
    s_lo, s_hi = trig_bounds(a_lo, a_hi, True, LIB_REL, LIB_TINY)
    la = leg[ARM]
    for j in range(lo.shape[0]):
        x_lo, x_hi, y_lo, y_hi = lo[j, 0], hi[j, 0], lo[j, 1], hi[j, 1]
        z_lo, z_hi = lo[j, 2], hi[j, 2]
        p_lo, p_hi, _, _ = plane(x_lo, x_hi, y_lo, y_hi, leg)
        e_lo, e_hi = interval_mul(p_lo, p_hi, s_lo[j], s_hi[j])
        f_lo, f_hi = interval_mul(z_lo, z_hi, c_lo[j], c_hi[j])
        e_lo, e_hi = interval_add(e_lo, e_hi, f_lo, f_hi)
        den_lo, den_hi = interval_mul(e_lo, e_hi, la, la)
        # the row of A (a_row_boxes)
        f_lo, f_hi = interval_mul(c_lo[j], c_hi[j], la, la)
        h_lo, h_hi = interval_sub(leg[OFF_LO], leg[OFF_HI], f_lo, f_hi)
        f_lo, f_hi = interval_mul(h_lo, h_hi, leg[UX_LO], leg[UX_HI])
        r0 = interval_add(x_lo, x_hi, f_lo, f_hi)
        f_lo, f_hi = interval_mul(h_lo, h_hi, leg[UY_LO], leg[UY_HI])
        r1 = interval_add(y_lo, y_hi, f_lo, f_hi)
        f_lo, f_hi = interval_mul(s_lo[j], s_hi[j], la, la)
        r2 = interval_add(z_lo, z_hi, f_lo, f_hi)
        for e, (r_lo, r_hi) in enumerate((r0, r1, r2)):
            q_lo, q_hi = interval_div(r_lo, r_hi, den_lo, den_hi)
            out_lo[e, j], out_hi[e, j] = -q_hi, -q_lo


# ------------------------------------------------------------------ fold flows
@kernel
def fold_terms_prepare(
    lo: Array, hi: Array, leg: Array, terms_lo: Array, terms_hi: Array, args: Array
) -> None:  # pragma: no cover - compiled
    """``DeltaLeg._fold_terms`` of the (n, 3) boxes up to its arccos: into
    ``terms`` (N_TERMS, n) the gradient of ``g``, ``s``, ``w = -z`` and ``t^2``
    (the rows ``T_*``; ``T_INV`` is left to :func:`fold_terms_finish`), into
    ``args`` (2, n) the arccos arguments of alpha's bounds."""
    for j in range(lo.shape[0]):
        x_lo, x_hi, y_lo, y_hi = lo[j, 0], hi[j, 0], lo[j, 1], hi[j, 1]
        z_lo, z_hi = lo[j, 2], hi[j, 2]
        s_lo, s_hi, _, _ = plane(x_lo, x_hi, y_lo, y_hi, leg)
        a_lo, a_hi = interval_square(s_lo, s_hi)
        b_lo, b_hi = interval_square(z_lo, z_hi)
        terms_lo[T_T2, j], terms_hi[T_T2, j] = interval_add(a_lo, a_hi, b_lo, b_hi)
        terms_lo[T_S, j], terms_hi[T_S, j] = s_lo, s_hi
        terms_lo[T_W, j], terms_hi[T_W, j] = -z_hi, -z_lo
        g_lo, g_hi, _, _, _ = g_boxes(x_lo, x_hi, y_lo, y_hi, z_lo, z_hi, leg)
        args[0, j] = nan_min(nan_max(g_hi, -1.0), 1.0)
        args[1, j] = nan_min(nan_max(g_lo, -1.0), 1.0)
        grads = _g_gradient(x_lo, x_hi, y_lo, y_hi, z_lo, z_hi, leg)
        for e in range(3):
            terms_lo[T_GX + e, j], terms_hi[T_GX + e, j] = grads[2 * e], grads[2 * e + 1]


@kernel
def fold_terms_finish(acos: Array, terms_lo: Array, terms_hi: Array) -> None:  # pragma: no cover
    """``DeltaLeg._fold_terms`` after its arccos (``acos`` (2, n)): into the row
    ``T_INV`` of ``terms`` ``[1 / max sin alpha, inf]`` (0 below where ``sin
    alpha`` may reach no positive value)."""
    n = acos.shape[1]
    a_lo, a_hi = np.empty(n), np.empty(n)
    for j in range(n):
        a_lo[j] = nan_max(lib_below(acos[0, j]), 0.0)
        a_hi[j] = nan_min(lib_above(acos[1, j]), PI_UP)
    sin_max = trig_bounds(a_lo, a_hi, True, LIB_REL, LIB_TINY)[1]
    for j in range(n):
        low = 0.0
        if sin_max[j] > 0:
            low = np.nextafter(1.0 / nan_max(sin_max[j], 1e-300), 0.0)
        terms_lo[T_INV, j], terms_hi[T_INV, j] = low, np.inf


@kernel
def fold_rate_bounds(
    terms_lo: Array,
    terms_hi: Array,
    v_lo: Array,
    v_hi: Array,
    status: NDArray[np.uint8],
    codes: NDArray[np.uint8],
    sign: float,
    leg: Array,
    keeps: NDArray[np.bool_],
    out_lo: Array,
    out_hi: Array,
) -> None:  # pragma: no cover - compiled
    """``DeltaLeg.fold_flow`` from the fold terms (``terms`` (N_TERMS, n)) and the
    velocity (3, n): whether the motion keeps the pose reachable (``keeps``:
    ``g`` does not grow where ``status`` is ``codes[1]`` (FOLD_OUTER), does not
    fall where ``codes[2]`` (FOLD_INNER)), and the joint's rate ``turning +
    sign alpha_rate`` into ``out`` (n,)."""
    for j in range(status.shape[0]):
        g_lo, g_hi = interval_mul(terms_lo[T_GX, j], terms_hi[T_GX, j], v_lo[0, j], v_hi[0, j])
        p_lo, p_hi = interval_mul(terms_lo[T_GY, j], terms_hi[T_GY, j], v_lo[1, j], v_hi[1, j])
        g_lo, g_hi = interval_add(g_lo, g_hi, p_lo, p_hi)
        p_lo, p_hi = interval_mul(terms_lo[T_GZ, j], terms_hi[T_GZ, j], v_lo[2, j], v_hi[2, j])
        g_lo, g_hi = interval_add(g_lo, g_hi, p_lo, p_hi)
        # s' = v_x u_x + v_y u_y; turning = (s (-v_z) - w s') / t^2
        p_lo, p_hi = interval_mul(v_lo[0, j], v_hi[0, j], leg[UX_LO], leg[UX_HI])
        q_lo, q_hi = interval_mul(v_lo[1, j], v_hi[1, j], leg[UY_LO], leg[UY_HI])
        r_lo, r_hi = interval_add(p_lo, p_hi, q_lo, q_hi)
        p_lo, p_hi = interval_mul(terms_lo[T_S, j], terms_hi[T_S, j], -v_hi[2, j], -v_lo[2, j])
        q_lo, q_hi = interval_mul(terms_lo[T_W, j], terms_hi[T_W, j], r_lo, r_hi)
        p_lo, p_hi = interval_sub(p_lo, p_hi, q_lo, q_hi)
        t_lo, t_hi = interval_div(p_lo, p_hi, terms_lo[T_T2, j], terms_hi[T_T2, j])
        # alpha's rate: -(g' [1 / max sin alpha, inf])
        q_lo, q_hi = interval_mul(g_lo, g_hi, terms_lo[T_INV, j], terms_hi[T_INV, j])
        if sign > 0:
            out_lo[j], out_hi[j] = interval_add(t_lo, t_hi, -q_hi, -q_lo)
        else:
            out_lo[j], out_hi[j] = interval_sub(t_lo, t_hi, -q_hi, -q_lo)
        code = status[j]
        keeps[j] = ((code == codes[1]) and (g_hi <= 0)) or ((code == codes[2]) and (g_lo >= 0))
