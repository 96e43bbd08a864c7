"""Compiled part of :func:`moveability.analysis.sheets.classify_sheets`: the
table's rows of every posture in one pass over the boxes.

Each box's row is written once, contiguously (the table is (n, P) and (n, P,
legs): filling it posture by posture and leg by leg from numpy writes every
entry with a stride of a row).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..compiled import kernel
from ..hypertree.status import BOUNDARY, IN, OUT
from ..limits import INSIDE, OUTSIDE

__all__ = ["posture_rows"]


@kernel
def posture_rows(
    postures: NDArray[np.int64],
    codes: NDArray[np.uint8],
    ang_lo: NDArray[np.float64],
    ang_hi: NDArray[np.float64],
    det_lo: NDArray[np.float64],
    det_hi: NDArray[np.float64],
    det_row: NDArray[np.int64],
    beyond: NDArray[np.uint8],
    beyond_row: NDArray[np.int64],
    no_plus: NDArray[np.bool_],
    no_minus: NDArray[np.bool_],
    signs_row: NDArray[np.int64],
    any_out: NDArray[np.bool_],
    any_fold: NDArray[np.bool_],
    fold_ok: NDArray[np.bool_],
    status: NDArray[np.uint8],
    sign: NDArray[np.int8],
    exists: NDArray[np.bool_],
    within: NDArray[np.bool_],
    group: NDArray[np.bool_],
    out_det_lo: NDArray[np.float64],
    out_det_hi: NDArray[np.float64],
    out_ang_lo: NDArray[np.float64],
    out_ang_hi: NDArray[np.float64],
) -> None:  # pragma: no cover - compiled
    """The sheet table's rows of ``n`` boxes and the ``P`` postures
    (``postures`` (P, legs): each leg's branch).

    Inputs per leg and branch: the joint's enclosure ``ang`` and its limit codes
    ``codes`` (legs, branches, n). Per posture ``p``: det A's bounds, row
    ``det_row[p]`` of ``det_lo``, ``det_hi``; the codes of the constraints beyond
    the paper, row ``beyond_row[p]`` of ``beyond`` (-1: none); the boxes where
    no configuration has det A > 0 (``no_plus``) or < 0 (``no_minus``), row
    ``signs_row[p]`` (-1: not known). Per box: some leg out of reach
    (``any_out``), some leg folding (``any_fold``), the fold geometry certified
    (``fold_ok``). Outputs: the table's (n, P) and (n, P, legs) arrays.

    A posture's configurations are within the limits (``within``) where every
    code is ``INSIDE``, beyond them where one is ``OUTSIDE`` or where neither
    sign of det A holds one; det A's bound is clamped at 0 (as ``np.maximum``
    and ``np.minimum`` do: NaN kept, 0.0 on a tie) where a sign holds none."""
    n = any_out.shape[0]
    n_post, n_legs = postures.shape
    for e in range(n):
        dead_box = any_out[e]
        regular = not any_fold[e] and not dead_box
        for p in range(n_post):
            lim_in = True
            lim_out = False
            for i in range(n_legs):
                b = postures[p, i]
                code = codes[i, b, e]
                out_ang_lo[e, p, i] = ang_lo[i, b, e]
                out_ang_hi[e, p, i] = ang_hi[i, b, e]
                lim_in = lim_in and code == INSIDE
                lim_out = lim_out or code == OUTSIDE
            r = beyond_row[p]
            if r >= 0:
                code = beyond[r, e]
                lim_in = lim_in and code == INSIDE
                lim_out = lim_out or code == OUTSIDE
            d_lo = det_lo[det_row[p], e]
            d_hi = det_hi[det_row[p], e]
            r = signs_row[p]
            if r >= 0:
                plus_none = no_plus[r, e]
                minus_none = no_minus[r, e]
                lim_out = lim_out or (plus_none and minus_none)
                if minus_none:
                    d_lo = d_lo if (d_lo > 0.0 or d_lo != d_lo) else 0.0
                if plus_none:
                    d_hi = d_hi if (d_hi < 0.0 or d_hi != d_hi) else 0.0
            out_det_lo[e, p] = d_lo
            out_det_hi[e, p] = d_hi
            s = 1 if d_lo > 0 else (-1 if d_hi < 0 else 0)
            sign[e, p] = s
            exists[e, p] = regular
            within[e, p] = lim_in
            if dead_box or lim_out:
                status[e, p] = OUT
            elif regular and lim_in and s != 0:
                status[e, p] = IN
            else:
                status[e, p] = BOUNDARY
            group[e, p] = fold_ok[e] and lim_in and s != 0
