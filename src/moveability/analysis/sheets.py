"""Posture sheets over boxes of poses: the certified evidence of the analysis.

Over a box of poses where every leg is REGULAR, the configurations of one
posture form a *sheet*, the graph of a continuous function of the pose. The
sheet's status for the analysis is

``IN``
    every configuration is valid: within the joint limits, det A of one sign
    (recorded in ``sign``), so the whole sheet lies in one region;
``OUT``
    no valid configuration (a leg cannot reach, or a joint is beyond its limits);
``BOUNDARY``
    undecided.

Where some legs fold (their branches meet inside the box), the postures that
differ only on those legs form a *fold group*; it is certified when the
configurations over the box all join through the fold (a geometric fact the
mechanism certifies) and are all valid with one sign of det A. A certified
group is where a region changes posture.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..hypertree.status import BOUNDARY, IN, OUT
from ..intervals import Interval
from ..mechanisms.base import FOLD_INNER, FOLD_OUTER, REACH_OUT, REACH_UNKNOWN, REGULAR, Mechanism
from ..types import Array
from ._sheet_kernels import posture_rows

__all__ = ["SheetTable", "classify_sheets", "stack_tables"]


@dataclass(frozen=True)
class SheetTable:
    """Evidence for n boxes and P postures.

    Attributes
    ----------
    leg_status : (n, n_legs) uint8
        Reach code of each leg. A leg that may fold is ``REACH_UNKNOWN`` where
        its fold certificates were not tried (``classify_sheets(folds=False)``).
    status : (n, P) uint8
        IN / OUT / BOUNDARY of each posture sheet.
    sign : (n, P) int8
        Sign of det A over the sheet: +1, -1, or 0 when it may vanish.
    exists : (n, P) bool
        Every pose of the box has a configuration of this posture (all legs REGULAR).
    within : (n, P) bool
        Those configurations are within the joint limits.
    group : (n, P) bool
        The posture belongs to a certified fold group of its box.
    singular : (n, P) bool
        det A vanishes on every configuration of the node (a posture the
        mechanism knows to be identically singular): it holds no configuration
        of any region.
    det_lo, det_hi : (n, P) float
        Enclosure of det A over the node's configurations (NaN where unknown):
        a node whose det A is never positive holds no configuration of a region
        with det A > 0, and likewise for negative.
        Where a constraint beyond the joint limits excludes every configuration
        of one sign of det A (:meth:`Mechanism.constraint_signs`), the bound on
        that side is 0: the enclosure then holds det A over the valid
        configurations (and 0), which is what ``sign`` and :meth:`may_hold` read.
    angles_lo, angles_hi : (n, P, n_legs) float
        Enclosure (unwrapped) of each leg's joint angle over the sheet: its
        branch where the leg is regular, both branches where it may fold.
    """

    leg_status: NDArray[np.uint8]
    status: NDArray[np.uint8]
    sign: NDArray[np.int8]
    exists: NDArray[np.bool_]
    within: NDArray[np.bool_]
    group: NDArray[np.bool_]
    singular: NDArray[np.bool_]
    det_lo: NDArray[np.float64]
    det_hi: NDArray[np.float64]
    angles_lo: NDArray[np.float64]
    angles_hi: NDArray[np.float64]

    @property
    def folding(self) -> NDArray[np.bool_]:
        """(n, n_legs): legs whose branches may meet in the box."""
        return (self.leg_status != REGULAR) & (self.leg_status != REACH_OUT)

    def may_hold(self, s: int) -> NDArray[np.bool_]:
        """(n, P): nodes that may hold a valid configuration with det A of sign ``s``."""
        with np.errstate(invalid="ignore"):
            room = ~(self.det_hi <= 0) if s > 0 else ~(self.det_lo >= 0)
        return (self.status != OUT) & (self.sign != -s) & ~self.singular & room

    def take(self, index: NDArray[np.intp]) -> SheetTable:
        """The rows of some boxes, in the order given."""
        # np.take along the rows: one copy of each row's bytes (a fancy index of a
        # table of a million rows takes about three times as long)
        at = np.asarray(index)
        if at.dtype == np.bool_:
            at = np.flatnonzero(at)
        return SheetTable(
            **{f.name: np.take(getattr(self, f.name), at, axis=0) for f in fields(self)}
        )

    def statuses(self) -> NDArray[np.uint8]:
        """A tree status per box: OUT where no sheet holds a valid configuration, IN
        where every sheet is decided, BOUNDARY elsewhere.

        Computed once per table (its arrays are not changed in place: a table is
        rebuilt, by :meth:`take` or :func:`stack_tables`); each call returns a copy."""
        cached = self.__dict__.get("_statuses")
        if cached is None:
            dead = _rows_all(self.status == OUT)
            cached = np.where(dead, OUT, np.where(self.decided(), IN, BOUNDARY)).astype(np.uint8)
            # a frozen dataclass: the cache is set past its __setattr__ (not a field)
            object.__setattr__(self, "_statuses", cached)
        return np.array(cached)

    def decided(self) -> NDArray[np.bool_]:
        """Boxes where no leg folds and every sheet is IN, OUT or identically singular."""
        settled = (self.status != BOUNDARY) | self.singular
        return ~_rows_any(self.folding) & _rows_all(settled)


# reductions along the rows of (n, m) tables of few columns (legs, postures): one
# pass per column (numpy reduces a short axis row by row, several times slower)
def _rows_any(a: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """``a.any(axis=1)``."""
    out = np.zeros(a.shape[0], dtype=bool)
    for j in range(a.shape[1]):
        out |= a[:, j]
    return out


def _rows_all(a: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """``a.all(axis=1)``."""
    out = np.ones(a.shape[0], dtype=bool)
    for j in range(a.shape[1]):
        out &= a[:, j]
    return out


def _rows_count(a: NDArray[np.bool_]) -> NDArray[np.int64]:
    """``a.sum(axis=1)``: the True entries of each row."""
    out = np.zeros(a.shape[0], dtype=np.int64)
    for j in range(a.shape[1]):
        out += a[:, j]
    return out


def classify_sheets(
    mechanism: Mechanism, lo: Array, hi: Array, *, folds: bool = True
) -> SheetTable:
    """Certify the posture sheets of ``mechanism`` over boxes ``[lo, hi]`` (n, k).

    ``folds=False`` lets the legs whose fold certificates are optional skip them
    (:meth:`~moveability.mechanisms.base.Mechanism.reaches_and_det`): the
    statuses are the same, the fold groups and fold codes of the table are not
    certified (for boxes about to be split)."""
    legs = mechanism.legs
    n = lo.shape[0]
    # det A too where it depends on the pose alone (computed with the reaches)
    reaches, pose_det = mechanism.reaches_and_det(lo, hi, folds=folds)
    leg_status = np.stack([r.status for r in reaches], axis=1).astype(np.uint8)
    postures = mechanism.postures
    n_post = postures.shape[0]

    singular = np.array([mechanism.identically_singular(p) for p in range(n_post)], dtype=bool)
    # limits of each leg's hull where it folds, and of each branch (the hull's
    # codes where a leg's branch is its hull)
    hull_limits = [mechanism.limits[i].classify(reaches[i].hull) for i in range(len(legs))]
    branch_limits = [
        [
            hull_limits[i] if b is reaches[i].hull else mechanism.limits[i].classify(b)
            for b in reaches[i].branches
        ]
        for i in range(len(legs))
    ]
    folding = (leg_status != REGULAR) & (leg_status != REACH_OUT)
    any_out = _rows_any(leg_status == REACH_OUT)
    any_unknown = _rows_any(leg_status == REACH_UNKNOWN)
    # the legs that fold in some box (a leg that folds in none joins no group)
    leg_folds = folding.any(axis=0)
    fold_legs = [i for i in range(len(legs)) if leg_folds[i]]
    any_fold = _rows_any(folding)

    # geometry: the configurations of the folding legs over the box all join
    fold_ok = np.zeros(n, dtype=bool)
    if fold_legs:
        fold_count = _rows_count(folding)
        single = fold_count == 1
        for i in fold_legs:
            fold_ok |= single & folding[:, i] & reaches[i].fold_connected
        for i in fold_legs:
            for j in (j for j in fold_legs if j > i):
                pair = (fold_count == 2) & folding[:, i] & folding[:, j]
                pair &= (leg_status[:, i] == FOLD_OUTER) | (leg_status[:, i] == FOLD_INNER)
                pair &= (leg_status[:, j] == FOLD_OUTER) | (leg_status[:, j] == FOLD_INNER)
                if pair.any():
                    fold_ok |= pair & mechanism.folds_connected((i, j), lo, hi)
    fold_ok &= ~any_out & ~any_unknown

    # each leg's enclosure on each branch a posture takes, and its limit codes:
    # a branch's own enclosure where the leg is regular, or folds and the leg
    # encloses each branch there too; else the hull of both
    branch_angles: list[list[Interval | None]] = []
    branch_codes: list[list[Any]] = []
    for i in range(len(legs)):
        r = reaches[i]
        used = set(postures[:, i].tolist())
        leg_angles: list[Interval | None] = [None] * len(r.branches)
        leg_codes: list[Any] = [None] * len(r.branches)
        for b in sorted(used):
            if r.branches[b] is r.hull:
                # the leg's branch is its hull: the same enclosure and codes everywhere
                leg_angles[b] = Interval(np.array(r.hull.lo), np.array(r.hull.hi))
                leg_codes[b] = hull_limits[i]
                continue
            regular = leg_status[:, i] == REGULAR
            if getattr(legs[i], "branches_at_folds", False):
                regular = regular | (folding[:, i] & (leg_status[:, i] != REACH_UNKNOWN))
            leg_angles[b] = Interval(
                np.where(regular, r.branches[b].lo, r.hull.lo),
                np.where(regular, r.branches[b].hi, r.hull.hi),
            )
            leg_codes[b] = np.where(regular, branch_limits[i][b], hull_limits[i])
        branch_angles.append(leg_angles)
        branch_codes.append(leg_codes)
    dets: list[Interval] | None = None
    if pose_det is None:
        with np.errstate(invalid="ignore"):
            dets = mechanism.det_a_postures(lo, hi, branch_angles)

    # the constraints beyond the paper (passive limits, obstacles, collisions: part
    # of what a valid configuration is; and a sign of det A whose every
    # configuration violates one), posture by posture as the mechanism checks them
    beyond_rows: list[Any] = []
    sign_rows: list[Any] = []
    beyond_row = np.full(n_post, -1, dtype=np.int64)
    signs_row = np.full(n_post, -1, dtype=np.int64)
    regular_legs = leg_status == REGULAR
    for p in range(n_post):
        angles: list[Interval] = []
        for i, b in enumerate(postures[p]):
            a = branch_angles[i][b]
            assert a is not None
            angles.append(a)
        with np.errstate(invalid="ignore"):
            beyond, signs = mechanism.constraint_checks(lo, hi, angles, p, regular_legs)
        if beyond is not None:
            beyond_row[p] = len(beyond_rows)
            beyond_rows.append(np.broadcast_to(beyond, (n,)))
        if signs is not None:
            signs_row[p] = len(sign_rows)
            sign_rows.append([np.broadcast_to(np.asarray(v, dtype=bool), (n,)) for v in signs])
    # then every posture's row of the table in one pass over the boxes
    n_branch = max(len(r.branches) for r in reaches) if legs else 0
    codes = np.zeros((len(legs), n_branch, n), dtype=np.uint8)
    ang_lo = np.zeros((len(legs), n_branch, n))
    ang_hi = np.zeros((len(legs), n_branch, n))
    for i in range(len(legs)):
        for b, a in enumerate(branch_angles[i]):
            if a is not None:
                codes[i, b] = branch_codes[i][b]
                ang_lo[i, b], ang_hi[i, b] = a.lo, a.hi
    if dets is not None:
        det_lo_in = np.stack([np.broadcast_to(d.lo, (n,)) for d in dets])
        det_hi_in = np.stack([np.broadcast_to(d.hi, (n,)) for d in dets])
        det_row = np.arange(n_post, dtype=np.int64)
    else:
        assert pose_det is not None
        det_lo_in = np.broadcast_to(pose_det.lo, (n,))[None, :].astype(np.float64)
        det_hi_in = np.broadcast_to(pose_det.hi, (n,))[None, :].astype(np.float64)
        det_row = np.zeros(n_post, dtype=np.int64)
    status = np.empty((n, n_post), dtype=np.uint8)
    sign = np.empty((n, n_post), dtype=np.int8)
    exists = np.empty((n, n_post), dtype=bool)
    within = np.empty((n, n_post), dtype=bool)
    group = np.empty((n, n_post), dtype=bool)
    det_lo = np.empty((n, n_post))
    det_hi = np.empty((n, n_post))
    angles_lo = np.empty((n, n_post, len(legs)))
    angles_hi = np.empty((n, n_post, len(legs)))
    no_sign = np.zeros((1, n), dtype=bool)
    posture_rows(
        np.ascontiguousarray(postures, dtype=np.int64), codes, ang_lo, ang_hi,
        det_lo_in, det_hi_in, det_row,
        np.stack(beyond_rows).astype(np.uint8) if beyond_rows else np.zeros((1, n), np.uint8),
        beyond_row,
        np.stack([s[0] for s in sign_rows]) if sign_rows else no_sign,
        np.stack([s[1] for s in sign_rows]) if sign_rows else no_sign,
        signs_row, any_out, any_fold, fold_ok,
        status, sign, exists, within, group, det_lo, det_hi, angles_lo, angles_hi,
    )  # fmt: skip
    return SheetTable(
        leg_status=leg_status,
        status=status,
        sign=sign,
        exists=exists,
        within=within,
        group=group,
        singular=np.broadcast_to(singular[None, :], (n, n_post)),
        det_lo=det_lo,
        det_hi=det_hi,
        angles_lo=angles_lo,
        angles_hi=angles_hi,
    )


def stack_tables(tables: list[SheetTable]) -> SheetTable:
    """The rows of several tables, one after the other."""
    return SheetTable(
        **{f.name: np.concatenate([getattr(t, f.name) for t in tables]) for f in fields(SheetTable)}
    )
