"""The fold certificates of :class:`~moveability.mechanisms.constraint_leg.ConstraintLeg`
on tapes, in one compiled loop.

``ConstraintLeg._fold_interpreted`` certifies, over boxes with one run of
pieces, that ``F`` is convex (concave) in the joint, that one corner of the box
is reachable and another not, and that the box is fold-connected along an axis
(see :mod:`moveability.mechanisms.constraint_leg`). Each step evaluates a tape
(:mod:`moveability.mechanisms.tape`) over the pieces, or the constraint in
floats at the corners, and reduces the values per box. :func:`fold` takes the
same steps, on the same floats, in one kernel: the interval tapes by the
compiled operations of :func:`moveability.mechanisms.tape.run_ops`, the float
constraint by its *float tape* (the same operations in floats, in the same
order), every derived input (sines and cosines of the joint and of the pose)
computed beforehand in Python by the very functions the interpreted steps call.
``tests/mechanisms/test_tape.py`` compares both bit for bit.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..compiled import kernel
from ..intervals import Interval
from ..types import Array
from . import expressions as ex
from . import tape as tp
from .tape import PIECE_BLOCK, run_ops

__all__ = ["float_program", "fold", "unreachable_tests"]


@kernel
def _fops(code: NDArray[np.int64], r: Array, n: int) -> None:  # pragma: no cover - compiled
    """The tape's operations in floats over the first ``n`` columns of ``r``: what
    numpy computes for ``+ - *``, negation and ``** 2`` of float arrays."""
    for p in range(code.shape[0]):
        op = code[p, 0]
        t = r[code[p, 1]]
        a = r[code[p, 2]]
        b = r[code[p, 3]]
        if op == 0:
            for e in range(n):
                t[e] = a[e] + b[e]
        elif op == 1:
            for e in range(n):
                t[e] = a[e] - b[e]
        elif op == 2:
            for e in range(n):
                t[e] = a[e] * b[e]
        elif op == 3:
            for e in range(n):
                t[e] = -a[e]
        else:
            for e in range(n):
                x = a[e]
                t[e] = x * x


@kernel(inline=True)
def _put(
    r_lo: Array, r_hi: Array, e: int, first: int, v_lo: Array, v_hi: Array, col: int
) -> None:  # pragma: no cover - compiled
    """Slots ``first + x`` of column ``e``: the values ``v[x, col]``."""
    for x in range(v_lo.shape[0]):
        r_lo[first + x, e] = v_lo[x, col]
        r_hi[first + x, e] = v_hi[x, col]


@kernel(inline=True)
def _nan_min(m: float, x: float) -> float:  # pragma: no cover - compiled
    """``np.minimum(m, x)`` for the value only (NaN propagated; a zero's sign aside)."""
    if m != m:
        return m
    if x != x or x < m:
        return x
    return m


@kernel(inline=True)
def _contexts(
    code: NDArray[np.int64],
    needed: NDArray[np.int64],
    r_lo: Array,
    r_hi: Array,
    k: int,
    first_pose: int,
    x_lo: Array,
    x_hi: Array,
    d_lo: Array,
    d_hi: Array,
    use: NDArray[np.bool_],
    idx: NDArray[np.int64],
    pv_lo: Array,
    pv_hi: Array,
) -> None:  # pragma: no cover - compiled
    """The operations ``code`` on the pose alone over each context ``c`` with
    ``use[c]``: pose ``[x_lo[c], x_hi[c]]``, its derived inputs ``d[:, c]``; the
    slots ``needed`` into ``pv[:, c]``."""
    n = x_lo.shape[0]
    block = r_lo.shape[1]
    c = 0
    while c < n:
        m = 0
        while c < n and m < block:
            if use[c]:
                for j in range(k):
                    r_lo[j, m] = x_lo[c, j]
                    r_hi[j, m] = x_hi[c, j]
                _put(r_lo, r_hi, m, first_pose, d_lo, d_hi, c)
                idx[m] = c
                m += 1
            c += 1
        if m == 0:
            continue
        run_ops(code, r_lo, r_hi, m)
        for e in range(m):
            for s in range(needed.size):
                pv_lo[s, idx[e]] = r_lo[needed[s], e]
                pv_hi[s, idx[e]] = r_hi[needed[s], e]


@kernel(inline=True)
def _fill(
    r_lo: Array,
    r_hi: Array,
    e: int,
    needed: NDArray[np.int64],
    pv_lo: Array,
    pv_hi: Array,
    ctx: int,
    k: int,
    a: float,
    z: float,
    qd_lo: Array,
    qd_hi: Array,
    t: int,
) -> None:  # pragma: no cover - compiled
    """Column ``e``: the pose slots ``needed`` of context ``ctx``, the joint
    ``[a, z]`` and its derived inputs ``qd[:, t]``."""
    for s in range(needed.size):
        r_lo[needed[s], e] = pv_lo[s, ctx]
        r_hi[needed[s], e] = pv_hi[s, ctx]
    r_lo[k, e] = a
    r_hi[k, e] = z
    _put(r_lo, r_hi, e, k + 1, qd_lo, qd_hi, t)


@kernel(inline=True)
def _pieces(
    code: NDArray[np.int64],
    r_lo: Array,
    r_hi: Array,
    t: int,
    p_local: NDArray[np.int64],
    use: NDArray[np.bool_],
    needed: NDArray[np.int64],
    pv_lo: Array,
    pv_hi: Array,
    k: int,
    a: Array,
    z: Array,
    qd_lo: Array,
    qd_hi: Array,
    cols: NDArray[np.int64],
) -> tuple[int, int]:  # pragma: no cover - compiled
    """The next block of pieces from ``t`` on whose box ``p_local[t]`` has ``use``:
    each filled (:func:`_fill`: joint ``[a[t], z[t]]``, its derived inputs
    ``qd[:, t]``) in a column, its piece in ``cols``, the operations ``code`` run
    over them. Returns their count and the next piece."""
    c = 0
    while t < p_local.size and c < r_lo.shape[1]:
        i = p_local[t]
        if use[i]:
            _fill(r_lo, r_hi, c, needed, pv_lo, pv_hi, i, k, a[t], z[t], qd_lo, qd_hi, t)
            cols[c] = t
            c += 1
        t += 1
    if c > 0:
        run_ops(code, r_lo, r_hi, c)
    return c, t


@kernel(inline=True)
def _corner(
    lo: Array, hi: Array, corner: NDArray[np.int64], out: Array
) -> None:  # pragma: no cover
    """The corner ``corner[i]`` of each box ``i`` (bit ``j``: the upper end of axis ``j``)."""
    for i in range(lo.shape[0]):
        for j in range(lo.shape[1]):
            out[i, j] = hi[i, j] if (corner[i] >> j) & 1 else lo[i, j]


@kernel(inline=True)
def _at_corner(
    cd: Array, corner: NDArray[np.int64], out: Array
) -> None:  # pragma: no cover - compiled
    """``out[x, i] = cd[corner[i], x, i]``."""
    for x in range(cd.shape[1]):
        for i in range(cd.shape[2]):
            out[x, i] = cd[corner[i], x, i]


@kernel(inline=True)
def _reached(
    code: NDArray[np.int64],
    r_lo: Array,
    r_hi: Array,
    p_local: NDArray[np.int64],
    use: NDArray[np.bool_],
    needed: NDArray[np.int64],
    pv_lo: Array,
    pv_hi: Array,
    k: int,
    q_mid: Array,
    md_lo: Array,
    md_hi: Array,
    cols: NDArray[np.int64],
    s2: Array,
    out_f: int,
    reach: NDArray[np.bool_],
) -> None:  # pragma: no cover - compiled
    """``reach[i] = True`` where ``G = s2 F < 0`` at the middle of some piece of box
    ``i`` (with ``use[i]``), the pose slots ``needed`` of ``F`` in ``pv``."""
    t = 0
    while t < p_local.size:
        c, t = _pieces(
            code, r_lo, r_hi, t, p_local, use, needed, pv_lo, pv_hi, k, q_mid, q_mid,
            md_lo, md_hi, cols,
        )  # fmt: skip
        for e in range(c):
            i = p_local[cols[e]]
            g_hi = r_hi[out_f, e] if s2[i] > 0 else -r_lo[out_f, e]
            if g_hi < 0.0:
                reach[i] = True


@kernel(inline=True)
def _corner_contexts(
    code: NDArray[np.int64],
    needed: NDArray[np.int64],
    r_lo: Array,
    r_hi: Array,
    k: int,
    first_pose: int,
    lo: Array,
    hi: Array,
    corner: NDArray[np.int64],
    cd_lo: Array,
    cd_hi: Array,
    use: NDArray[np.bool_],
    idx: NDArray[np.int64],
    point: Array,
    point_d_lo: Array,
    point_d_hi: Array,
    pv_lo: Array,
    pv_hi: Array,
) -> None:  # pragma: no cover - compiled
    """:func:`_contexts` at the corner ``corner[i]`` of each box ``i`` (its derived
    inputs ``cd[corner[i], :, i]``), the corners in ``point``, ``point_d``."""
    _corner(lo, hi, corner, point)
    _at_corner(cd_lo, corner, point_d_lo)
    _at_corner(cd_hi, corner, point_d_hi)
    _contexts(
        code, needed, r_lo, r_hi, k, first_pose, point, point, point_d_lo, point_d_hi, use, idx,
        pv_lo, pv_hi,
    )  # fmt: skip


@kernel
def _fold(
    code: NDArray[np.int64],
    const_lo: Array,
    const_hi: Array,
    k: int,
    slots: int,
    outs: NDArray[np.int64],
    n_q: int,
    codes: tuple[NDArray[np.int64], ...],
    needs: tuple[NDArray[np.int64], ...],
    f_const: Array,
    f_slots: int,
    f_out: int,
    f_nq: int,
    lo: Array,
    hi: Array,
    ends: NDArray[np.int64],
    p_local: NDArray[np.int64],
    q_lo: Array,
    q_hi: Array,
    q_mid: Array,
    finite: NDArray[np.bool_],
    qd_lo: Array,
    qd_hi: Array,
    md_lo: Array,
    md_hi: Array,
    pd_lo: Array,
    pd_hi: Array,
    cd_lo: Array,
    cd_hi: Array,
    fd_lo: Array,
    fd_hi: Array,
    fq: Array,
    fc: Array,
    u_local: NDArray[np.int64],
    u_lo: Array,
    u_hi: Array,
    ud_lo: Array,
    ud_hi: Array,
) -> tuple[NDArray[np.int8], NDArray[np.bool_]]:  # pragma: no cover - compiled
    """The fold certificates of the boxes ``[lo[i], hi[i]]`` (see :func:`fold`).

    ``codes`` holds, for ``F``, ``(dF/dq, d2F/dq2)``, the ``dF/dX_j`` and ``F``'s
    float tape in turn, the operations on the pose alone and the others, ``needs``
    the slots of the former the latter read: the former are evaluated once per
    pose (box, corner or face), the others per piece (:func:`splits`). ``u_*``
    are the joint enclosures of the test that a corner is beyond the reach
    (box, bounds, derived inputs; :func:`unreachable_tests`)."""
    f_pose, f_rest, f_need = codes[0], codes[1], needs[0]
    d_pose, d_rest, d_need = codes[2], codes[3], needs[1]
    x_pose, x_rest, x_need = codes[4], codes[5], needs[2]
    g_pose, g_rest, g_need = codes[6], codes[7], needs[3]
    n_b = lo.shape[0]
    n_p = p_local.size
    n_corners = 1 << k
    block = PIECE_BLOCK
    first_pose = k + 1 + n_q
    first_const = first_pose + pd_lo.shape[0]
    r_lo = np.empty((slots, block))
    r_hi = np.empty((slots, block))
    for c in range(const_lo.size):
        for e in range(block):
            r_lo[first_const + c, e] = const_lo[c]
            r_hi[first_const + c, e] = const_hi[c]
    per = 3 * n_corners
    f_block = max(block, per)
    f_first_pose = k + 1 + f_nq
    f_first_const = f_first_pose + fc.shape[1]
    r_f = np.empty((f_slots, f_block))
    for c in range(f_const.size):
        for e in range(f_block):
            r_f[f_first_const + c, e] = f_const[c]
    cols = np.empty(f_block, dtype=np.int64)
    tag = np.empty(f_block, dtype=np.int64)
    idx = np.empty(f_block, dtype=np.int64)
    out_f = outs[0]
    use = np.empty(n_b, dtype=np.bool_)
    for i in range(n_b):
        use[i] = ends[i] != 0

    # convexity: d2F/dq2 of one sign (and F, dF/dq finite) on every piece
    pv_lo = np.empty((d_need.size, n_b))
    pv_hi = np.empty((d_need.size, n_b))
    _contexts(
        d_pose, d_need, r_lo, r_hi, k, first_pose, lo, hi, pd_lo, pd_hi, use, idx, pv_lo, pv_hi
    )
    convex = np.ones(n_b, dtype=np.bool_)
    concave = np.ones(n_b, dtype=np.bool_)
    t = 0
    while t < n_p:
        c, t = _pieces(
            d_rest, r_lo, r_hi, t, p_local, use, d_need, pv_lo, pv_hi, k, q_lo, q_hi,
            qd_lo, qd_hi, cols,
        )  # fmt: skip
        for e in range(c):
            u = cols[e]
            i = p_local[u]
            d1_lo = r_lo[outs[1], e]
            d1_hi = r_hi[outs[1], e]
            d2_lo = r_lo[outs[2], e]
            d2_hi = r_hi[outs[2], e]
            ok_d2 = (
                np.isfinite(d2_lo)
                and np.isfinite(d2_hi)
                and finite[u]
                and np.isfinite(d1_lo)
                and np.isfinite(d1_hi)
            )
            if not (ok_d2 and d2_lo > 0.0):
                convex[i] = False
            if not (ok_d2 and d2_hi < 0.0):
                concave[i] = False
    s2 = np.zeros(n_b)
    ok = np.zeros(n_b, dtype=np.bool_)
    for i in range(n_b):
        if ends[i] == 0:
            continue
        if convex[i]:
            s2[i] = 1.0
            ok[i] = (ends[i] & 1) != 0
        elif concave[i]:
            s2[i] = -1.0
            ok[i] = (ends[i] & 2) != 0

    # the corners: G = s2 F in floats at each piece's ends and middle
    n_ctx = n_b * n_corners
    x_f = np.empty((n_ctx, k))
    d_f = np.empty((fc.shape[1], n_ctx))
    use_f = np.empty(n_ctx, dtype=np.bool_)
    for i in range(n_b):
        for corner in range(n_corners):
            ctx = i * n_corners + corner
            use_f[ctx] = ok[i]
            for j in range(k):
                x_f[ctx, j] = hi[i, j] if (corner >> j) & 1 else lo[i, j]
            for x in range(fc.shape[1]):
                d_f[x, ctx] = fc[corner, x, i]
    fv = np.empty((g_need.size, n_ctx))
    m = 0
    for ctx in range(n_ctx):
        if use_f[ctx]:
            for j in range(k):
                r_f[j, m] = x_f[ctx, j]
            for x in range(d_f.shape[0]):
                r_f[f_first_pose + x, m] = d_f[x, ctx]
            idx[m] = ctx
            m += 1
        if m == f_block or (ctx == n_ctx - 1 and m > 0):
            _fops(g_pose, r_f, m)
            for e in range(m):
                for s in range(g_need.size):
                    fv[s, idx[e]] = r_f[g_need[s], e]
            m = 0
    g_min = np.full((n_b, n_corners), np.inf)
    g_low = np.full((n_b, n_corners), np.inf)
    t = 0
    while t < n_p:
        c = 0
        while t < n_p and c + per <= f_block:
            i = p_local[t]
            if ok[i]:
                for corner in range(n_corners):
                    ctx = i * n_corners + corner
                    for v in range(3):
                        for s in range(g_need.size):
                            r_f[g_need[s], c] = fv[s, ctx]
                        r_f[k, c] = q_lo[t] if v == 0 else (q_mid[t] if v == 1 else q_hi[t])
                        for x in range(f_nq):
                            r_f[k + 1 + x, c] = fq[v, x, t]
                        cols[c] = t
                        tag[c] = corner * 3 + v
                        c += 1
            t += 1
        if c == 0:
            continue
        _fops(g_rest, r_f, c)
        for e in range(c):
            i = p_local[cols[e]]
            corner = tag[e] // 3
            value = s2[i] * r_f[f_out, e]
            if tag[e] % 3 == 1:
                g_min[i, corner] = _nan_min(g_min[i, corner], value)
            g_low[i, corner] = _nan_min(g_low[i, corner], value)
    best_in = np.zeros(n_b, dtype=np.int64)
    best_out = np.zeros(n_b, dtype=np.int64)
    for i in range(n_b):
        if not ok[i]:
            continue
        a_best = np.inf
        z_best = -np.inf
        for corner in range(n_corners):
            a = g_min[i, corner]
            a = np.inf if a != a else a
            z = g_low[i, corner]
            z = -np.inf if z != z else z
            if corner == 0 or a < a_best:
                a_best = a
                best_in[i] = corner
            if corner == 0 or z > z_best:
                z_best = z
                best_out[i] = corner

    # reachable: G < 0 at the middle of some piece, at the corner best_in
    point = np.empty((n_b, k))
    point_d_lo = np.empty((cd_lo.shape[1], n_b))
    point_d_hi = np.empty((cd_lo.shape[1], n_b))
    pv_lo = np.empty((f_need.size, n_b))
    pv_hi = np.empty((f_need.size, n_b))
    _corner_contexts(
        f_pose, f_need, r_lo, r_hi, k, first_pose, lo, hi, best_in, cd_lo, cd_hi, ok, idx,
        point, point_d_lo, point_d_hi, pv_lo, pv_hi,
    )  # fmt: skip
    reach = np.zeros(n_b, dtype=np.bool_)
    _reached(
        f_rest, r_lo, r_hi, p_local, ok, f_need, pv_lo, pv_hi, k, q_mid, md_lo, md_hi, cols, s2,
        out_f, reach,
    )  # fmt: skip
    for i in range(n_b):
        ok[i] = ok[i] and reach[i]

    # unreachable: G > 0 on every piece, at the corner best_out
    _corner_contexts(
        f_pose, f_need, r_lo, r_hi, k, first_pose, lo, hi, best_out, cd_lo, cd_hi, ok, idx,
        point, point_d_lo, point_d_hi, pv_lo, pv_hi,
    )  # fmt: skip
    out = np.ones(n_b, dtype=np.bool_)
    t = 0
    while t < u_local.size:
        c, t = _pieces(
            f_rest, r_lo, r_hi, t, u_local, ok, f_need, pv_lo, pv_hi, k, u_lo, u_hi,
            ud_lo, ud_hi, cols,
        )  # fmt: skip
        for e in range(c):
            i = u_local[cols[e]]
            g_lo = r_lo[out_f, e] if s2[i] > 0 else -r_hi[out_f, e]
            if not g_lo > 0.0:
                out[i] = False
    for i in range(n_b):
        ok[i] = ok[i] and out[i]

    # connectivity: dG/dX_j of one sign on every piece, and that face reachable
    xv_lo = np.empty((x_need.size, n_b))
    xv_hi = np.empty((x_need.size, n_b))
    _contexts(
        x_pose, x_need, r_lo, r_hi, k, first_pose, lo, hi, pd_lo, pd_hi, ok, idx, xv_lo, xv_hi
    )
    up = np.ones((n_b, max(k, 1)), dtype=np.bool_)
    down = np.ones((n_b, max(k, 1)), dtype=np.bool_)
    t = 0
    while t < n_p:
        c, t = _pieces(
            x_rest, r_lo, r_hi, t, p_local, ok, x_need, xv_lo, xv_hi, k, q_lo, q_hi,
            qd_lo, qd_hi, cols,
        )  # fmt: skip
        for e in range(c):
            i = p_local[cols[e]]
            for j in range(k):
                a = r_lo[outs[3 + j], e]
                z = r_hi[outs[3 + j], e]
                fin = np.isfinite(a) and np.isfinite(z)
                rising = fin and ((a > 0.0) if s2[i] > 0 else (z < 0.0))
                falling = fin and ((z < 0.0) if s2[i] > 0 else (a > 0.0))
                if not rising:
                    up[i, j] = False
                if not falling:
                    down[i, j] = False
    connected = np.zeros(n_b, dtype=np.bool_)
    face_lo = np.empty((n_b, k))
    face_hi = np.empty((n_b, k))
    for j in range(k):
        for side in range(2):
            for i in range(n_b):
                use[i] = ok[i] and not connected[i] and (up[i, j] if side == 0 else down[i, j])
                for a_ in range(k):
                    face_lo[i, a_] = lo[i, a_]
                    face_hi[i, a_] = hi[i, a_]
                face = lo[i, j] if side == 0 else hi[i, j]
                face_lo[i, j] = face
                face_hi[i, j] = face
            _contexts(
                f_pose, f_need, r_lo, r_hi, k, first_pose, face_lo, face_hi,
                fd_lo[2 * j + side], fd_hi[2 * j + side], use, idx, pv_lo, pv_hi,
            )  # fmt: skip
            _reached(
                f_rest, r_lo, r_hi, p_local, use, f_need, pv_lo, pv_hi, k, q_mid, md_lo, md_hi,
                cols, s2, out_f, connected,
            )  # fmt: skip
    convexity = np.zeros(n_b, dtype=np.int8)
    for i in range(n_b):
        if ok[i]:
            convexity[i] = 1 if s2[i] > 0 else -1
        connected[i] = connected[i] and ok[i]
    return convexity, connected


def _split(
    code: NDArray[np.int64], pose: NDArray[np.bool_], outs: Any
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
    """The operations of ``code`` on the pose and constants alone (``pose``: the
    slots that are so, the inputs' marked), the others, and the slots of the
    former (or inputs) that the others or the outputs ``outs`` read."""
    pose = pose.copy()
    first, rest = [], []
    for row in code:
        _, target, a, b = (int(v) for v in row)
        if pose[a] and pose[b]:
            first.append(row)
            pose[target] = True
        else:
            rest.append(row)
    needed = {int(s) for row in rest for s in row[2:] if pose[s]}
    needed |= {int(o) for o in outs if pose[o]}
    return (
        np.array(first, dtype=np.int64).reshape(-1, 4),
        np.array(rest, dtype=np.int64).reshape(-1, 4),
        np.array(sorted(needed), dtype=np.int64),
    )


def _pose_slots(prog: tp.Program) -> NDArray[np.bool_]:
    """The slots of ``prog`` on the pose or constants alone before any operation:
    the pose coordinates, their derived inputs and the constants."""
    k = prog.k
    first_pose = k + 1 + len(prog.derived)
    out = np.zeros(prog.slots, dtype=bool)
    out[:k] = True
    out[first_pose : first_pose + len(prog.pose_derived) + prog.const_lo.size] = True
    return out


def splits(
    prog: tp.Program, fprog: tp.Program
) -> tuple[tuple[NDArray[np.int64], ...], tuple[NDArray[np.int64], ...]]:
    """The ``codes`` and ``needs`` arguments of :func:`_fold`: :func:`_split` of
    ``F``, of ``dF/dq`` with ``d2F/dq2``, of the ``dF/dX_j`` and of ``F``'s float tape."""
    k, rows, outs = prog.k, prog.ranges, prog.outs
    pose = _pose_slots(prog)
    parts = [
        _split(prog.code[rows[0, 0] : rows[0, 1]], pose, outs[:1]),
        _split(prog.code[rows[1, 0] : rows[2, 1]], pose, outs[1:3]),
        _split(prog.code[rows[3, 0] : rows[2 + k, 1]], pose, outs[3 : 3 + k]),
        _split(fprog.code, _pose_slots(fprog), fprog.outs[:1]),
    ]
    codes = tuple(np.ascontiguousarray(a) for part in parts for a in part[:2])
    needs = tuple(np.ascontiguousarray(part[2]) for part in parts)
    return codes, needs


def float_program(f: Any) -> tp.Program | None:
    """The program of ``f``'s float tape (``f.float_tape``: the operations ``f``
    performs on float arrays, its constants floats), None if it has none."""
    t = getattr(f, "float_tape", None)
    if not isinstance(t, tp.Tape) or not np.array_equal(t.const_lo, t.const_hi):
        return None
    return tp.program([t])


def _float_values(functions: Any, values: list[Array], out: Array) -> None:
    """Each function of the float arrays ``values`` (one per argument slot) into the
    rows of ``out``."""
    with np.errstate(all="ignore"):
        for e, (function, args) in enumerate(functions):
            out[e] = function(*(values[a] for a in args))


def unreachable_tests(
    mono: NDArray[np.int8], q_lo: Array, q_hi: Array
) -> tuple[NDArray[np.intp], Array, Array]:
    """The joint enclosures over which a fold certificate tests that a pose is
    beyond the reach: each piece, or its two ends (points) where ``F`` is monotone
    in ``q`` there. Returns each one's piece and its bounds, in piece order.

    Examples
    --------
    >>> import numpy as np
    >>> at, lo, hi = unreachable_tests(np.array([0, 1], dtype=np.int8),
    ...                                np.array([0.0, 1.0]), np.array([1.0, 2.0]))
    >>> at.tolist(), lo.tolist(), hi.tolist()
    ([0, 1, 1], [0.0, 1.0, 2.0], [1.0, 1.0, 2.0])
    """
    ends = mono != 0
    at = np.repeat(np.arange(mono.size), np.where(ends, 2, 1))
    second = np.zeros(at.size, dtype=bool)
    second[1:] = at[1:] == at[:-1]
    first = ends[at] & ~second
    lo = np.where(second, q_hi[at], q_lo[at])
    hi = np.where(first, q_lo[at], q_hi[at])
    return at, lo, hi


def fold(
    prog: tp.Program,
    fprog: tp.Program,
    split: tuple[tuple[NDArray[np.int64], ...], tuple[NDArray[np.int64], ...]],
    lo: Array,
    hi: Array,
    box_pose: tuple[Array, Array],
    ends: NDArray[np.int64],
    p_local: NDArray[np.int64],
    q: Interval,
    finite: NDArray[np.bool_],
    mono: NDArray[np.int8],
) -> tuple[NDArray[np.int8], NDArray[np.bool_]]:
    """The fold certificates of ``ConstraintLeg._fold_interpreted`` in one kernel.

    ``prog`` is the program of the tapes of ``F``, ``dF/dq``, ``d2F/dq2`` and the
    ``dF/dX_j`` (in that order), ``fprog`` that of ``F``'s float tape
    (:func:`float_program`), ``split`` their operations (:func:`splits`). Over
    the boxes ``[lo[i], hi[i]]`` (rows of ``(n, k)`` arrays; ``box_pose`` the
    derived inputs of the pose over them, as
    :func:`~moveability.mechanisms.tape.pose_values` gives them) and their pieces
    (joint enclosures ``q``, box ``p_local``, in box order, ``F`` finite there or
    not; ``mono`` the sign of ``dF/dq`` certified there, 0 for none):
    ``ends[i]`` says whether ``F > 0`` (bit 1) or ``F < 0`` (bit 2) at both
    ends of box ``i``'s run. Returns the convexity sign (0: no certificate) and
    the fold connectivity of each box.
    """
    n_b, k = lo.shape
    n_p = q.lo.shape[0]
    q_mid = np.ascontiguousarray(q.mid, dtype=np.float64)
    qd = tp.derived_values(prog, q)
    md = tp.derived_values(prog, ex.points(q_mid))
    # the derived inputs of the pose at the corners (points) and over the faces
    bits = [(1 << j) for j in range(k)]
    corners = [np.where([(c & b) != 0 for b in bits], hi, lo) for c in range(1 << k)]
    cd = [tp._values(prog.pose_derived, tp._Coords(p, p, True)) for p in corners]
    fd = []
    for j in range(k):
        for side in (lo, hi):
            f_lo, f_hi = lo.copy(), hi.copy()
            f_lo[:, j] = side[:, j]
            f_hi[:, j] = side[:, j]
            fd.append(tp._values(prog.pose_derived, tp._Coords(f_lo, f_hi, False)))
    # the float derived inputs: of the joint at the pieces' ends and middles, of
    # the pose at the corners
    q_float = [np.ascontiguousarray(v, dtype=np.float64) for v in (q.lo, q_mid, q.hi)]
    joint = [(g, (0,)) for g in fprog.derived]
    fq = np.empty((3, len(joint), n_p))
    for v, values in enumerate(q_float):
        _float_values(joint, [values], fq[v])
    fc = np.empty((len(corners), len(fprog.pose_derived), n_b))
    for c, p in enumerate(corners):
        _float_values(fprog.pose_derived, list(p.T), fc[c])

    # the test that a corner is beyond the reach: over each piece, or at its ends
    u_at, u_lo, u_hi = unreachable_tests(mono, q.lo, q.hi)
    ud = tp.derived_values(prog, Interval(u_lo, u_hi))

    def c3(parts: list[tuple[Array, Array]], which: int, d: int) -> Array:
        out = np.stack([p[which] for p in parts]) if parts else np.empty((0, d, n_b))
        return np.ascontiguousarray(out, dtype=np.float64)

    d_pose = len(prog.pose_derived)
    convexity, connected = _fold(
        prog.code, prog.const_lo, prog.const_hi, k, prog.slots, prog.outs, len(prog.derived),
        split[0], split[1], np.ascontiguousarray(fprog.const_lo), fprog.slots, int(fprog.outs[0]),
        len(fprog.derived),
        np.ascontiguousarray(lo, dtype=np.float64), np.ascontiguousarray(hi, dtype=np.float64),
        np.ascontiguousarray(ends, dtype=np.int64), np.ascontiguousarray(p_local, dtype=np.int64),
        np.ascontiguousarray(q.lo, dtype=np.float64), np.ascontiguousarray(q.hi, dtype=np.float64),
        q_mid, np.ascontiguousarray(finite, dtype=np.bool_),
        qd[0], qd[1], md[0], md[1],
        np.ascontiguousarray(box_pose[0], dtype=np.float64),
        np.ascontiguousarray(box_pose[1], dtype=np.float64),
        c3(cd, 0, d_pose), c3(cd, 1, d_pose), c3(fd, 0, d_pose), c3(fd, 1, d_pose),
        fq, fc,
        np.ascontiguousarray(p_local, dtype=np.int64)[u_at], u_lo, u_hi, ud[0], ud[1],
    )  # fmt: skip
    return convexity, connected
