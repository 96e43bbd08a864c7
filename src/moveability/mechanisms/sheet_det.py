"""det A along the sheets: a mean-value form for legs given by their constraint.

Over a box of poses, the determinant of the legs' rows on intervals (the
*natural* enclosure) treats each joint as free in its enclosure, although on a
sheet the joints are functions of the pose. Where those enclosures are wide
next to the box (legs given by their constraint alone, whose roots are
isolated and contracted), the natural enclosure can be many times the range
det A takes on the sheets, and the cells near det A = 0 stay undecided.

:func:`det_along_sheets` intersects it with a mean-value form of ``D(X) = det
A(X, q(X))`` taken along the sheet. The argument, for one posture over a box
``B``: where each leg's constraint ``F_i`` is monotone in ``q_i`` over its
enclosure ``Q_i`` (``dF_i/dq_i`` of one certified sign) and of opposite
certified signs at the two ends of ``Q_i``, every pose ``X`` of ``B`` has
exactly one root ``q_i(X)`` in ``Q_i``, a C^1 function of ``X`` (the implicit
function theorem), so ``D`` is C^1 on ``B`` (convex) and

``D(X) = D(c) + sum_j dD/dX_j(xi) (X_j - c_j)``

for a pose ``xi`` of ``B``, ``c`` its middle. ``dD/dX_j`` is the rate of det A
when the pose moves along axis ``j`` and each joint at its gradient ``-(dF_i/dX_j)
/ (dF_i/dq_i)``; det A is linear in each row, so the rate is the sum over the
legs of det A with that leg's row replaced by its derivative
(:meth:`Mechanism.det_a_rate`), enclosed over ``B`` and the ``Q_i`` with the
second derivatives of the constraints (``d2F/dX dX`` and ``d2F/dq dX``).
``q_i(c)`` is enclosed by a few ulps about Newton's float iterate, certified
by the signs of ``F_i(c, .)`` at their ends (``Q_i`` where they do not show).
Elsewhere the natural enclosure stands.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..intervals import Interval
from ..types import Array
from .base import Mechanism, interval_det

__all__ = ["det_along_sheets", "dets_along_sheets", "gives_second_derivatives"]

def gives_second_derivatives(mechanism: Mechanism) -> bool:
    """Whether every leg of the mechanism is given by its constraint with the
    second derivatives (see :class:`~moveability.mechanisms.constraint_leg.ConstraintLeg`)."""
    return all(getattr(leg, "second_derivatives", None) is not None for leg in mechanism.legs)


def det_along_sheets(
    mechanism: Mechanism,
    lo: Array,
    hi: Array,
    angles: Sequence[Interval],
    rows: list[list[Interval]],
) -> Interval:
    """det A over boxes of poses (n, k) for one posture, its legs' joint
    enclosures ``angles`` and their rows over them ``rows``: the natural
    enclosure intersected with the mean-value form along the sheet where the
    module's conditions hold (every leg monotone in its joint over its
    enclosure, with a root in it for every pose of the box), on the boxes
    where the natural enclosure holds 0 (the sign of det A is what decides a
    cell; elsewhere the natural enclosure is kept). One posture of
    :func:`dets_along_sheets`.

    Examples
    --------
    A biglide written with its constraints (two sliders, rails y = 0 and y = 2):

    >>> import numpy as np
    >>> from moveability import load_spec
    >>> from moveability.mechanisms.custom import CustomMechanism
    >>> spec = {
    ...     "mechanism": "custom", "pose": ["x", "y"], "joints": ["r1", "r2"],
    ...     "parameters": {"a": 5.0, "b": 4.0},
    ...     "legs": [
    ...         {"joint": "r1", "kind": "prismatic", "constraint": "(x - r1)**2 + y**2 - a**2"},
    ...         {"joint": "r2", "kind": "prismatic",
    ...          "constraint": "(x - r2)**2 + (y - 2)**2 - b**2"},
    ...     ],
    ...     "limits": {"r1": [-10.0, 10.0], "r2": [-10.0, 10.0]},
    ...     "bounds": {"x": [-10.0, 10.0], "y": [-6.0, 6.0]},
    ... }
    >>> m = CustomMechanism(load_spec(spec))
    >>> lo, hi = np.array([[2.1, 1.0]]), np.array([[2.2, 1.1]])
    >>> reach = [leg.reach(lo, hi) for leg in m.legs]
    >>> angles = [reach[0].branches[0], reach[1].branches[1]]
    >>> rows = [leg.a_row_boxes(lo, hi, a) for leg, a in zip(m.legs, angles)]
    >>> natural, along = interval_det(rows), det_along_sheets(m, lo, hi, angles, rows)
    >>> bool(natural.lo[0] < 0 < natural.hi[0]), bool(along.lo[0] > 0)
    (True, True)
    """
    return dets_along_sheets(
        mechanism, lo, hi, [[a] for a in angles], np.zeros((1, len(angles)), dtype=np.intp),
        {(i, 0): row for i, row in enumerate(rows)},
    )[0]  # fmt: skip


class _LegTerms:
    """What the form needs of one leg on one branch over the boxes ``need``: at the
    boxes where the leg's conditions hold, the root at the middle of each box,
    the joint's gradient and the derivatives of the row; ``row[box]`` is the
    box's row in them (-1: not needed, or the conditions fail)."""

    def __init__(
        self, leg: Any, lo: Array, hi: Array, angle: Interval, need: NDArray[np.bool_]
    ) -> None:
        at = np.flatnonzero(need)
        q = Interval(angle.lo[at], angle.hi[at])
        sense = leg.monotone_root(lo[at], hi[at], q)
        keep = sense != 0
        at = at[keep]
        self.row = np.full(lo.shape[0], -1, dtype=np.intp)
        self.row[at] = np.arange(at.size)
        with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
            lo_k, hi_k = lo[at], hi[at]
            q_k = Interval(q.lo[keep], q.hi[keep])
            centre = 0.5 * (lo_k + hi_k)
            centre_q = leg.root_enclosure(centre, q_k, sense[keep] > 0)
            self.centre_row = leg.a_row_boxes(centre, centre, centre_q)
            self.gradient, self.along_x, self.along_q = leg.sheet_rates(lo_k, hi_k, q_k)


def dets_along_sheets(
    mechanism: Mechanism,
    lo: Array,
    hi: Array,
    branch_angles: Sequence[Sequence[Interval | None]],
    postures: NDArray[np.intp],
    rows: dict[tuple[int, int], list[Interval]],
) -> list[Interval]:
    """:func:`det_along_sheets` of every posture (``postures``: one row of
    branches per posture; ``branch_angles[i][b]`` leg ``i``'s joint enclosure on
    branch ``b``, ``rows[i, b]`` its rows over them), what each leg needs on a
    branch computed once for every posture that takes it, over the boxes where
    one of them needs it."""
    n = lo.shape[0]
    legs: Sequence[Any] = mechanism.legs
    naturals = [
        interval_det([rows[i, int(b)] for i, b in enumerate(branches)]) for branches in postures
    ]
    if not n or not gives_second_derivatives(mechanism):
        return naturals
    # per posture: the boxes whose natural enclosure holds 0 and whose joints'
    # enclosures are finite
    wanted = []
    for branches, natural in zip(postures, naturals, strict=True):
        use = (natural.lo <= 0) & (natural.hi >= 0)
        for i, b in enumerate(branches):
            a = branch_angles[i][int(b)]
            assert a is not None
            use &= np.isfinite(a.lo) & np.isfinite(a.hi)
        wanted.append(use)
    terms: dict[tuple[int, int], _LegTerms] = {}
    for i in range(len(legs)):
        for b in sorted({int(branches[i]) for branches in postures}):
            need = np.zeros(n, dtype=bool)
            for branches, use in zip(postures, wanted, strict=True):
                if int(branches[i]) == b:
                    need |= use
            if need.any():
                angle = branch_angles[i][b]
                assert angle is not None
                terms[i, b] = _LegTerms(legs[i], lo, hi, angle, need)
    out = []
    for branches, natural, use in zip(postures, naturals, wanted, strict=True):
        legs_terms = [terms.get((i, int(b))) for i, b in enumerate(branches)]
        if not use.any() or any(t is None for t in legs_terms):
            out.append(natural)
            continue
        # the boxes where every leg's conditions hold, and each one's term rows
        found_terms = [t for t in legs_terms if t is not None]
        at = np.flatnonzero(use & np.logical_and.reduce([t.row >= 0 for t in found_terms]))
        if not at.size:
            out.append(natural)
            continue
        found = [(t, t.row[at]) for t in found_terms]
        out.append(
            _narrowed(mechanism, lo, hi, branches, branch_angles, rows, natural, at, found)
        )
    return out


def _narrowed(
    mechanism: Mechanism,
    lo: Array,
    hi: Array,
    branches: NDArray[np.intp],
    branch_angles: Sequence[Sequence[Interval | None]],
    rows: dict[tuple[int, int], list[Interval]],
    natural: Interval,
    at: NDArray[np.intp],
    legs_terms: list[tuple[Any, NDArray[np.intp]]],
) -> Interval:
    """The natural enclosure ``natural`` of one posture intersected, at the boxes
    ``at``, with the mean-value form along the sheet from the legs' terms (each
    leg's :class:`_LegTerms` and the rows of ``at`` in it)."""
    k = lo.shape[1]
    box_lo, box_hi = lo[at], hi[at]
    q = []
    for i, b in enumerate(branches):
        a = branch_angles[i][int(b)]
        assert a is not None
        q.append(Interval(a.lo[at], a.hi[at]))
    centre = 0.5 * (box_lo + box_hi)
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        at_centre = interval_det([[x[r] for x in t.centre_row] for t, r in legs_terms])
        known = (
            [[x[at] for x in rows[i, int(b)]] for i, b in enumerate(branches)],
            [
                ([[x[r] for x in entry] for entry in t.along_x], [x[r] for x in t.along_q])
                for t, r in legs_terms
            ],
        )
        total = at_centre
        for j in range(k):
            velocity = [Interval(np.full(at.size, 1.0 if a == j else 0.0)) for a in range(k)]
            rates = [t.gradient[j][r] for t, r in legs_terms]
            slope = mechanism.det_a_rate(
                box_lo, box_hi, q, velocity, rates, rows_and_partials=known
            )
            if slope is None:
                return natural
            total = total + slope * (Interval(box_lo[:, j], box_hi[:, j]) - centre[:, j])
    out_lo, out_hi = natural.lo.copy(), natural.hi.copy()
    ok = ~(np.isnan(total.lo) | np.isnan(total.hi))
    sel = at[ok]
    out_lo[sel] = np.maximum(out_lo[sel], total.lo[ok])
    out_hi[sel] = np.minimum(out_hi[sel], total.hi[ok])
    return Interval(out_lo, out_hi)
