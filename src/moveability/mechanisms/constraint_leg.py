"""A leg given by its constraint ``F(X, q) = 0``: certified branches by root isolation.

A :class:`ConstraintLeg` has one actuated joint ``q`` and a scalar constraint
``F(X, q)`` between the pose ``X`` (k coordinates) and ``q``; it needs ``F``,
``dF/dq``, ``d2F/dq2`` and ``dF/dX_j`` as functions that evaluate both on
float arrays and on :class:`~moveability.intervals.Interval` (written with
:mod:`moveability.mechanisms.expressions`). Over intervals they must be
*guarded*: a finite enclosure certifies that the function is defined and
continuous there.

Branches
--------
Branch 0 is the root where the serial term ``dF/dq`` is positive, branch 1
where it is negative. Over a box of poses the roots in ``q`` are isolated:
the joint's search range (the full circle of a revolute joint, the stroke
widened by a quarter of its length on both sides for a prismatic one) is cut
into pieces; pieces where the enclosure of ``F`` excludes 0 are dropped, and
pieces where ``dF/dq`` has no definite sign are bisected (to a depth). The
remaining pieces form *runs* of adjacent pieces (on the circle for a revolute
joint). Where ``F`` is finite and ``dF/dq`` has one definite sign on every
piece of a run, ``F`` is monotone in ``q`` over the run for every pose of the
box. Such a run holds no root when ``F`` at its two ends shows no change of
sign (its start on the side of the sign of ``dF/dq``, or its end on the
other), and is dropped; it is certified to hold exactly one root for every
pose when ``F`` has definite opposite signs at its two ends. Then each
root's enclosure is contracted on ``F``'s sign at points of the run (regula
falsi, safeguarded by bisection): its bounds are points certified on either
side of the root. Over the box the leg is

``REGULAR``
    two runs, one certified root of each sign: every pose has exactly these
    two configurations in the search range;
``REACH_OUT``
    no run can hold a root;
``FOLD_OUTER`` (``FOLD_INNER``)
    one run ``Q``; ``F`` is convex (concave) in ``q`` over box x ``Q`` and
    positive (negative) at both ends of ``Q``, so every pose has two roots in
    ``Q``, a double root, or none; one pose of the box (a corner) certainly has
    two and another certainly none. ``hull`` is ``Q``. The fold lies at a
    minimum of ``F`` in ``q`` for ``FOLD_OUTER``, at a maximum for ``FOLD_INNER``;
``REACH_UNKNOWN``
    anything else, including more than two roots in the range (the analysis
    then leaves the box undecided). ``hull`` is the run where there is one,
    else infinite.

A prismatic joint's roots outside the widened stroke are never valid
configurations and are not sought. Where one branch has no root in the
widened stroke over the whole box, it is given an enclosure beyond the
stroke (so the joint limit classifies it out) and the leg counts as REGULAR.

Fold connectivity
-----------------
``fold_connected`` is certified on a fold box B with run Q when, with
``G = F`` for a convex fold and ``G = -F`` for a concave one, some pose axis
``j`` has ``dG/dX_j`` of a definite sign on B x Q (say > 0), and the face of
B at the low end of axis ``j`` is certainly reachable (``G(face, q*) < 0``
for one point ``q*`` of Q). Proof: outside Q no piece holds a root and
``G > 0`` at Q's ends, so ``G > 0`` off Q and the reachable poses of B are
``{X : m(X) <= 0}`` with ``m(X) = min_Q G(X, .)``. Since ``G`` increases with
``X_j`` at every ``q`` of Q, so does ``m``: the reachable set is a union of
segments along axis ``j`` starting on the reachable face, hence
path-connected (the face is convex). The two roots in Q are continuous on
that set (``G`` strictly convex) and meet where ``m = 0``; a pose certified
unreachable exists in B, so the segment through it ends at such a fold pose.
Every configuration thus joins the fold: along axis ``j`` onto the reachable
face, across it, and along axis ``j`` again on that segment; the two
branches' configurations over B form one connected set.
:meth:`ConstraintLeg.fold_path` returns that motion.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np
from numpy.typing import NDArray

from ..intervals import Interval
from ..types import Array
from . import expressions as ex
from . import tape
from .base import FOLD_INNER, FOLD_OUTER, REACH_OUT, REACH_UNKNOWN, REGULAR, LegReach
from .tape import run as run_tape

__all__ = ["ConstraintLeg"]

#: ``f(x_1, ..., x_k, q)`` on arrays or Intervals
Function = Callable[..., Any]

_TWO_PI = Interval(np.nextafter(2 * np.pi, 0.0), np.nextafter(2 * np.pi, np.inf))
_INF = np.inf
#: Newton's steps in floats towards a root at a point (see root_enclosure)
_NEWTON_STEPS = 3
#: the most pieces of an isolation level whose derived inputs are kept in a table
#: (:meth:`ConstraintLeg._level_table`)
_TABLE_CAP = 1 << 14


def _quiet() -> Any:
    return np.errstate(all="ignore")


@dataclass
class _Pieces:
    """Candidate pieces of the search range: struct of arrays, sorted by (box, q)."""

    box: NDArray[np.intp]
    lo: Array
    hi: Array
    mono: NDArray[np.int8]  # sign of dF/dq certified on the piece, 0 if none
    finite: NDArray[np.bool_]  # F finite (defined, continuous) on box x piece
    # F tested at the two ends already (by the compiled isolation): a piece of a
    # certified sign that holds no root is not among them
    tested: NDArray[np.bool_]
    # where tested: F's bounds over the box at lo (rows 0, 1) and at hi (rows 2, 3)
    ends: Array

    def take(self, keep: Any) -> _Pieces:
        return _Pieces(
            self.box[keep], self.lo[keep], self.hi[keep], self.mono[keep], self.finite[keep],
            self.tested[keep], self.ends[:, keep],
        )  # fmt: skip

    def end_values(self, at: NDArray[np.intp], upper: bool) -> Interval:
        """``F`` over the box at the lower (or ``upper``) end of the tested pieces ``at``."""
        row = 2 if upper else 0
        return Interval(self.ends[row, at], self.ends[row + 1, at])


@dataclass
class _Runs:
    """Runs of adjacent pieces, per box."""

    pieces: _Pieces
    run_of_piece: NDArray[np.intp]
    box: NDArray[np.intp]  # box of each run
    start: Array  # first q of the run
    end: Interval  # last q of the run (an enclosure, when unwrapped past the circle's cut)
    mono: NDArray[np.int8]  # certified sign of dF/dq over the run, 0 if none
    finite: NDArray[np.bool_]

    def end_pieces(self) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.bool_]]:
        """Each run's first piece and last piece, and which pieces are one turn on.

        A run unwrapped across the circle's cut starts with the pieces after the
        cut (their q below its start), moved one turn on: they come first in their
        box's pieces and end the run. A run's pieces not moved are consecutive, as
        are those moved, and the runs' indices increase along each kind."""
        run = self.run_of_piece
        turned = self.pieces.lo < self.start[run]
        first = np.empty(self.box.size, dtype=np.intp)
        last = np.empty(self.box.size, dtype=np.intp)
        for moved in (False, True):  # the moved pieces' last ends their runs
            at = np.flatnonzero(turned == moved)
            of = run[at]
            edge = np.ones(at.size + 1, dtype=bool)
            edge[1:-1] = of[1:] != of[:-1]
            if not moved:
                first[of[edge[:-1]]] = at[edge[:-1]]
            last[of[edge[1:]]] = at[edge[1:]]
        return first, last, turned

    def take(self, keep: NDArray[np.intp]) -> _Runs:
        """The runs ``keep`` (increasing indices) and their pieces alone."""
        index = np.full(self.box.size, -1, dtype=np.intp)
        index[keep] = np.arange(keep.size)
        of_piece = index[self.run_of_piece]
        held = of_piece >= 0
        return _Runs(
            self.pieces.take(held), of_piece[held], self.box[keep], self.start[keep],
            self.end[keep], self.mono[keep], self.finite[keep],
        )  # fmt: skip


@dataclass(frozen=True, eq=False)
class ConstraintLeg:
    """A leg with one actuated joint and a scalar constraint ``F(X, q) = 0``.

    Parameters
    ----------
    joint : str
        Name of the actuated joint.
    f, df_dq, d2f_dq2 : callable
        ``F``, ``dF/dq`` and ``d2F/dq2`` as ``g(x_1, ..., x_k, q)``, on float
        arrays and on Intervals (guarded, see :mod:`moveability.mechanisms.expressions`).
    df_dx : sequence of callable
        ``dF/dX_j`` for each pose axis, same signature.
    prismatic : bool
        A prismatic joint searched over ``stroke`` widened by a quarter of its
        length on both sides; otherwise a revolute joint searched over the circle.
    stroke : (float, float), optional
        The prismatic joint's limits.
    closed_form : callable, optional
        ``closed_form(points) -> (m, n)`` candidate joint values at poses (any
        order, NaN where not defined), used first by :meth:`angles` and checked
        there: values that do not solve the constraint are replaced by the
        numerical ones.
    pieces, depth, max_pieces : int
        Initial pieces of the search range, bisections of a piece, and pieces
        per box beyond which a box is no longer refined.
    d2f_dxdx, d2f_dqdx : optional
        ``d2F/dX_j dX_k`` (``d2f_dxdx[j][k]``) and ``d2F/dq dX_j``, same
        signature: the derivatives of the leg's row of A. With both, the
        mechanism's det A may be enclosed along the sheets
        (:mod:`moveability.mechanisms.sheet_det`, :meth:`sheet_rates`).

    Examples
    --------
    The leg of a five-bar at A = (0, 0), lengths 8 and 5:

    >>> import numpy as np
    >>> from moveability.mechanisms.expressions import cos, sin
    >>> leg = ConstraintLeg(
    ...     "t1",
    ...     f=lambda x, y, t: (x - 8 * cos(t)) ** 2 + (y - 8 * sin(t)) ** 2 - 25,
    ...     df_dq=lambda x, y, t: 16 * (x * sin(t) - y * cos(t)),
    ...     d2f_dq2=lambda x, y, t: 16 * (x * cos(t) + y * sin(t)),
    ...     df_dx=(lambda x, y, t: 2 * (x - 8 * cos(t)), lambda x, y, t: 2 * (y - 8 * sin(t))),
    ... )
    >>> lo, hi = np.array([[10.0, 3.0], [20.0, 0.0]]), np.array([[10.1, 3.1], [21.0, 1.0]])
    >>> reach = leg.reach(lo, hi)
    >>> reach.status.tolist()  # REGULAR, REACH_OUT
    [1, 0]
    >>> q = leg.angles(np.array([[10.0, 3.0]]))
    >>> bool(np.allclose(leg.constraint(np.array([[10.0, 3.0]] * 2), q[0]), 0.0))
    True
    >>> bool(reach.branches[0].contains(q[0, 0])[0])
    True
    """

    joint: str
    f: Function
    df_dq: Function
    d2f_dq2: Function
    df_dx: Sequence[Function]
    prismatic: bool = False
    stroke: tuple[float, float] | None = None
    closed_form: Callable[[Array], Array] | None = None
    pieces: int = 32
    depth: int = 8
    max_pieces: int = 64
    d2f_dxdx: Sequence[Sequence[Function]] | None = None
    d2f_dqdx: Sequence[Function] | None = None
    _range: tuple[float, float] = field(init=False, repr=False)

    n_branches = 2
    #: ``reach(lo, hi, folds=False)`` skips the fold certificates (see :meth:`reach`)
    #: and changes no box's tree status: a fold code only names the fold, and the
    #: branches' enclosures where the leg folds are its hull either way
    folds_optional = True
    #: ``reach(lo, hi, branches=False)`` gives the statuses and fold certificates
    #: alone (see :meth:`reach`)
    branches_optional = True

    def __post_init__(self) -> None:
        if self.prismatic:
            if self.stroke is None:
                raise ValueError("a prismatic leg needs its stroke")
            lo, hi = (float(v) for v in self.stroke)
            margin = 0.25 * (hi - lo)
            rng = (lo - margin, hi + margin)
        else:
            # just past pi: the pieces cover the circle although float pi < pi
            rng = (-float(np.pi), float(np.nextafter(np.pi, np.inf)))
        object.__setattr__(self, "_range", rng)

    # ---------------------------------------------------------------- points
    def _call(self, g: Function, points: Array, angles: Array) -> Array:
        """``g`` at poses and joint values, broadcast to their common shape (a
        function that does not depend on them, such as a derivative that is a
        constant, gives that shape too)."""
        p = np.asarray(points, dtype=np.float64)
        coords = [p[..., j] for j in range(p.shape[-1])]
        q = np.asarray(angles, dtype=np.float64)
        shape = np.broadcast_shapes(p.shape[:-1], q.shape)
        with _quiet():
            value = np.asarray(g(*coords, q), dtype=np.float64)
        return value if value.shape == shape else np.array(np.broadcast_to(value, shape))

    def constraint(self, points: Array, angles: Array) -> Array:
        """``F(X, q)`` at poses and joint values."""
        return self._call(self.f, points, angles)

    def serial_term(self, points: Array, angles: Array) -> Array:
        """``dF/dq``: zero at a serial singularity; positive on branch 0."""
        return self._call(self.df_dq, points, angles)

    def a_row(self, points: Array, angles: Array) -> Array:
        """The leg's row of A, ``dF/dX``, shape (..., k)."""
        return np.stack([self._call(g, points, angles) for g in self.df_dx], axis=-1)

    # ------------------------------------------------- along the sheet (sheet_det)
    @property
    def second_derivatives(self) -> tuple[Sequence[Sequence[Function]], Sequence[Function]] | None:
        """``(d2f_dxdx, d2f_dqdx)`` where both were given, else None."""
        if self.d2f_dxdx is None or self.d2f_dqdx is None:
            return None
        return self.d2f_dxdx, self.d2f_dqdx

    def monotone_root(self, lo: Array, hi: Array, angles: Interval) -> NDArray[np.int8]:
        """Per box: 1 where ``F`` certainly rises in ``q`` over the box and the
        enclosure ``angles``, negative at its lower end and positive at its upper
        one; -1 the same falling; 0 otherwise. Where it is not 0 every pose of the
        box has exactly one root in ``angles``, a C^1 function of the pose."""
        box = np.arange(lo.shape[0])
        with tape.remembered_boxes(), _quiet():
            slope = self._box_eval(self.df_dq, lo, hi, box, angles)
            start = self._box_eval(self.f, lo, hi, box, Interval(angles.lo))
            end = self._box_eval(self.f, lo, hi, box, Interval(angles.hi))
        up = (slope.lo > 0) & (start.hi < 0) & (end.lo > 0)
        down = (slope.hi < 0) & (start.lo > 0) & (end.hi < 0)
        return up.astype(np.int8) - down.astype(np.int8)

    def root_enclosure(
        self, points: Array, angles: Interval, rising: NDArray[np.bool_]
    ) -> Interval:
        """A narrow enclosure of the root in ``angles`` at each pose of ``points``
        (m, k), where ``F`` is monotone there (rising where ``rising``, see
        :meth:`monotone_root`): Newton's steps in floats from the middle of
        ``angles``, kept inside it, then a few ulps about the point reached,
        certified where ``F`` has the signs of the two sides of a root at its
        ends; ``angles`` itself where it does not."""
        lo = np.array(angles.lo, dtype=np.float64)
        hi = np.array(angles.hi, dtype=np.float64)
        q = 0.5 * (lo + hi)
        with _quiet():
            for _ in range(_NEWTON_STEPS):
                step = self._call(self.f, points, q) / self._call(self.df_dq, points, q)
                q = np.clip(np.where(np.isfinite(step), q - step, q), lo, hi)
            pad = 64 * np.spacing(np.abs(q)) + 1e-300
            below, above = np.maximum(q - pad, lo), np.minimum(q + pad, hi)
            box = np.arange(points.shape[0])
            f_below = self._box_eval(self.f, points, points, box, Interval(below))
            f_above = self._box_eval(self.f, points, points, box, Interval(above))
        up = (f_below.hi < 0) & (f_above.lo > 0)
        down = (f_below.lo > 0) & (f_above.hi < 0)
        ok = np.where(rising, up, down)
        return Interval(np.where(ok, below, lo), np.where(ok, above, hi))

    def sheet_rates(
        self, lo: Array, hi: Array, angles: Interval
    ) -> tuple[list[Interval], list[list[Interval]], list[Interval]]:
        """Over boxes of poses and joint enclosures: the joint's gradient along the
        sheet ``dq/dX_j = -(dF/dX_j) / (dF/dq)`` (the whole line where ``dF/dq``
        may vanish), and the derivatives of the leg's row of A, ``dF/dX``, along
        the pose axes (``[entry][axis]``) and along the joint.

        Raises ``ValueError`` where the second derivatives were not given."""
        given = self.second_derivatives
        if given is None:
            raise ValueError(f"leg {self.joint!r}: no second derivatives")
        d2f_dxdx, d2f_dqdx = given
        box = np.arange(lo.shape[0])
        with tape.remembered_boxes(), _quiet():
            serial = self._box_eval(self.df_dq, lo, hi, box, angles)
            gradient = [-(self._box_eval(g, lo, hi, box, angles) / serial) for g in self.df_dx]
            # a function given twice (the symmetric second derivatives) evaluated once
            seen: dict[int, Interval] = {}
            for g in (g for row in d2f_dxdx for g in row):
                if id(g) not in seen:
                    seen[id(g)] = self._box_eval(g, lo, hi, box, angles)
            along_x = [[seen[id(g)] for g in row] for row in d2f_dxdx]
            along_q = [self._box_eval(g, lo, hi, box, angles) for g in d2f_dqdx]
        return gradient, along_x, along_q

    def a_row_boxes(self, lo: Array, hi: Array, angles: Interval) -> list[Interval]:
        """Enclosures of ``dF/dX_j`` over boxes of poses and joint enclosures."""
        box = np.arange(lo.shape[0])
        # the derived inputs of the pose (sin and cos of an angle) once for every j
        with tape.remembered_boxes():
            return [self._box_eval(g, lo, hi, box, angles) for g in self.df_dx]

    def angles(self, points: Array, clip: bool = False) -> Array:
        """Joint value of each branch at each pose, shape (m, 2); NaN where unreachable.

        Roots are isolated as in :meth:`reach` on the poses themselves and
        polished in floats; where that cannot separate them (near a fold) the
        range is sampled. With ``clip``, a pose whose minimum of ``|F|`` is within
        rounding of zero (1e-10 relative to the sampled values) gets its double
        root on both branches.
        """
        p = np.asarray(points, dtype=np.float64).reshape(-1, len(self.df_dx))
        out = np.full((p.shape[0], 2), np.nan)
        if p.shape[0] == 0:
            return out
        if self.closed_form is not None:
            out = self._from_closed_form(p)
        todo = np.flatnonzero(~np.isfinite(out).all(axis=1))
        if todo.size:
            out[todo] = self._numerical(p[todo], clip)
        return out

    def _from_closed_form(self, p: Array) -> Array:
        assert self.closed_form is not None
        with _quiet():
            cand = np.asarray(self.closed_form(p), dtype=np.float64).reshape(p.shape[0], -1)
        out = np.full((p.shape[0], 2), np.nan)
        scale = 1.0 + np.abs(p).max(axis=1) ** 2
        for c in range(cand.shape[1]):
            q = cand[:, c]
            residual = np.abs(self.constraint(p, q))
            d = self.serial_term(p, q)
            ok = np.isfinite(q) & (residual <= 1e-9 * scale)
            for b, good in ((0, d > 0), (1, d < 0)):
                slot = ok & good & np.isnan(out[:, b])
                out[slot, b] = q[slot]
        return out

    def _numerical(self, p: Array, clip: bool) -> Array:
        out = np.full((p.shape[0], 2), np.nan)
        reach = self.reach(p, p)
        regular = reach.status == REGULAR
        for b in (0, 1):
            enc = reach.branches[b]
            q = self._polish(p[regular], enc.lo[regular], enc.hi[regular], (1, -1)[b])
            out[regular, b] = q
        if self.prismatic:
            # a branch enclosed beyond the widened stroke has no root there
            beyond = (out < self._range[0]) | (out > self._range[1])
            out[beyond] = np.nan
        rest = np.flatnonzero(~regular & (clip | (reach.status != REACH_OUT)))
        if rest.size:
            out[rest] = self._sampled(p[rest], clip)
        return out

    def _polish(self, p: Array, a: Array, b: Array, sign: int) -> Array:
        """Roots of ``sign * F`` increasing on ``[a, b]`` (certified bracket), in floats."""
        a, b = a.copy(), b.copy()
        for _ in range(80):
            mid = 0.5 * (a + b)
            below = sign * self.constraint(p, mid) < 0
            a = np.where(below, mid, a)
            b = np.where(below, b, mid)
            if (b - a <= 4 * np.spacing(np.abs(a) + np.abs(b))).all():
                break
        return 0.5 * (a + b)

    def _sampled(self, p: Array, clip: bool, n: int = 720) -> Array:
        """Both branches by sampling the range: exactly two sign changes of F, else NaN."""
        m = p.shape[0]
        start, stop = self._range
        grid = np.linspace(start, stop, n + 1)
        if not self.prismatic:
            grid = grid[:-1]
        pp = np.repeat(p, grid.size, axis=0)
        qq = np.tile(grid, m)
        fv = self.constraint(pp, qq).reshape(m, grid.size)
        nxt = np.roll(fv, -1, axis=1) if not self.prismatic else fv[:, 1:]
        cur = fv if not self.prismatic else fv[:, :-1]
        change = (cur * nxt < 0) | (cur == 0)
        count = change.sum(axis=1)
        out = np.full((m, 2), np.nan)
        step = grid[1] - grid[0]
        rows, cols = np.nonzero(change & (count == 2)[:, None])
        if rows.size:
            a = grid[cols]
            b = a + step
            c0, c1 = cur[rows, cols], nxt[rows, cols]
            sign = np.where((c0 < 0) | ((c0 == 0) & (c1 > 0)), 1, -1)
            roots = np.empty(rows.size)
            for s in (1, -1):
                sel = sign == s
                roots[sel] = self._polish(p[rows[sel]], a[sel], b[sel], s)
            d = self.serial_term(p[rows], roots)
            for branch, good in ((0, d > 0), (1, d < 0)):
                out[rows[good], branch] = roots[good]
            bad = ~np.isfinite(out[rows]).all(axis=1)
            out[rows[bad]] = np.nan
        if clip:
            # no crossing, or one (F exactly 0 at a sample): the double root of a fold
            none = np.flatnonzero(count < 2)
            if none.size:
                k = np.argmin(np.abs(fv[none]), axis=1)
                q = self._extremum(p[none], grid[k] - step, grid[k] + step)
                value = np.abs(self.constraint(p[none], q))
                near = value <= 1e-10 * (1.0 + np.abs(fv[none]).max(axis=1))
                out[none[near]] = q[near, None]
        return out

    def _extremum(self, p: Array, a: Array, b: Array) -> Array:
        """A zero of ``dF/dq`` on ``[a, b]`` by bisection (the extremum of F between)."""
        da = self.serial_term(p, a)
        for _ in range(80):
            mid = 0.5 * (a + b)
            dm = self.serial_term(p, mid)
            same = np.sign(dm) == np.sign(da)
            a = np.where(same, mid, a)
            da = np.where(same, dm, da)
            b = np.where(same, b, mid)
        return 0.5 * (a + b)

    # ----------------------------------------------------------------- boxes
    def _edges(self) -> Array:
        """The bounds of the initial pieces of the search range."""
        start, stop = self._range
        edges = np.linspace(start, stop, self.pieces + 1)
        edges[0], edges[-1] = start, stop
        return edges

    def _compiled(self) -> tuple[tape.Program, Array, Array, tuple[Array, Array]] | None:
        """The program of the tapes of ``F``, ``dF/dq`` and the ``dF/dX_j``
        (:func:`moveability.mechanisms.tape.program`), with the initial pieces and
        their derived inputs; None where a function has no tape. Built once."""
        if "_compiled_memo" not in self.__dict__:
            tapes = [getattr(g, "tape", None) for g in (self.f, self.df_dq, *self.df_dx)]
            found = [t for t in tapes if isinstance(t, tape.Tape)]
            prog = tape.program(found) if len(found) == len(tapes) else None
            memo = None
            if prog is not None:
                # the operations on the pose alone once per box (tape.hoisted)
                prog = tape.hoisted(prog)
                edges = self._edges()
                q = Interval(edges[:-1], edges[1:])
                memo = (prog, q.lo, q.hi, tape.derived_values(prog, q))
            self.__dict__["_compiled_memo"] = memo
        memo_: tuple[tape.Program, Array, Array, tuple[Array, Array]] | None
        memo_ = self.__dict__["_compiled_memo"]
        return memo_

    def _isolate(self, lo: Array, hi: Array) -> _Pieces:
        """Pieces of the search range that may hold a root, per box."""
        compiled = self._compiled()
        if compiled is not None:
            return self._isolate_compiled(lo, hi, *compiled)
        n = lo.shape[0]
        edges = self._edges()
        box = np.repeat(np.arange(n), self.pieces)
        # the same pieces for every box: their sines and cosines computed once
        q_first = ex.tiled(Interval(edges[:-1], edges[1:]), n)
        qlo, qhi = q_first.lo, q_first.hi
        done: list[_Pieces] = []
        counts = np.zeros(n, dtype=np.int64)
        for level in range(self.depth + 1):
            if not box.size:
                break
            q = q_first if level == 0 else Interval(qlo, qhi)
            fv = self._f_box(lo, hi, box, q)
            keep = np.flatnonzero(~((fv.lo > 0) | (fv.hi < 0)))
            box, qlo, qhi = box[keep], qlo[keep], qhi[keep]
            fv = fv[keep]
            finite = np.isfinite(fv.lo) & np.isfinite(fv.hi)
            dv = self._box_eval(self.df_dq, lo, hi, box, ex.take(q, keep))
            mono = np.where(finite & (dv.lo > 0), 1, np.where(finite & (dv.hi < 0), -1, 0)).astype(
                np.int8
            )
            total = counts + np.bincount(box, minlength=n)
            split = (mono == 0) & (total[box] <= self.max_pieces) & (level < self.depth)
            final = ~split
            m = int(final.sum())
            untested, no_ends = np.zeros(m, dtype=bool), np.full((4, m), np.nan)
            piece_arrays = (box[final], qlo[final], qhi[final], mono[final], finite[final])
            done.append(_Pieces(*piece_arrays, untested, no_ends))
            counts += np.bincount(box[final], minlength=n)
            mid = 0.5 * (qlo[split] + qhi[split])
            box = np.repeat(box[split], 2)
            new_lo = np.empty(box.size)
            new_hi = np.empty(box.size)
            new_lo[0::2], new_lo[1::2] = qlo[split], mid
            new_hi[0::2], new_hi[1::2] = mid, qhi[split]
            qlo, qhi = new_lo, new_hi
        pieces = _Pieces(
            np.concatenate([d.box for d in done]) if done else np.zeros(0, dtype=np.intp),
            np.concatenate([d.lo for d in done]) if done else np.zeros(0),
            np.concatenate([d.hi for d in done]) if done else np.zeros(0),
            np.concatenate([d.mono for d in done]) if done else np.zeros(0, dtype=np.int8),
            np.concatenate([d.finite for d in done]) if done else np.zeros(0, dtype=bool),
            np.concatenate([d.tested for d in done]) if done else np.zeros(0, dtype=bool),
            np.concatenate([d.ends for d in done], axis=1) if done else np.zeros((4, 0)),
        )
        order = np.lexsort((pieces.lo, pieces.box))
        return pieces.take(order)

    def _isolate_compiled(
        self,
        lo: Array,
        hi: Array,
        prog: tape.Program,
        q_lo: Array,
        q_hi: Array,
        extra: tuple[Array, Array],
    ) -> _Pieces:
        """:meth:`_isolate` a level at a time in one compiled loop
        (:func:`moveability.mechanisms.tape.isolate_level`): the same pieces, except
        those of a certified sign that hold no root, which the levels with a table
        find by the test of :meth:`_root_pieces` at their ends and leave out (the
        others are ``tested``, with ``F``'s bounds at their ends).

        The pieces of level ``k`` are the initial ones halved ``k`` times (at
        ``0.5 * (lo + hi)``, as the isolation halves them), the same for every box:
        their derived inputs (``sin(q)``, ``cos(q)``, ...) come from the level's
        table (:meth:`_level_table`), computed once per leg, and a piece is its
        row there; their ends are points of the finest table's grid
        (:meth:`_end_grid`). A level of more pieces than :data:`_TABLE_CAP` has
        no table: its inputs are computed on its pieces, which are not tested."""
        n = lo.shape[0]
        counts = np.zeros(n, dtype=np.int64)
        done = []
        box: NDArray[np.int64] | None = None  # level 0: each box with every initial piece
        at: NDArray[np.int64] | None = None
        # the derived inputs of pose coordinates (sin(phi), ...): once per box
        pose = tape.pose_values(prog, lo, hi)
        q = (q_lo, q_hi)
        grid = self._end_grid()
        for level in range(self.depth + 1):
            if level:
                if not box.size:  # type: ignore[union-attr]
                    break
                table = self._level_table(level) if at is not None else None
                if table is None:
                    # no table: the pieces' own enclosures, their inputs computed
                    at = None
                    q = (q_lo, q_hi)
                    extra = tape.derived_values(prog, Interval(q_lo, q_hi))
                else:
                    q, extra = table[:2], table[2:]
            ends = None
            if grid is not None and (level == 0 or at is not None) and level <= grid[3]:
                ends = (*grid[:3], grid[3] - level)
            *final, box, q_lo, q_hi, rows, tested, values = tape.isolate_level(
                prog, lo, hi, box, q, extra, counts, self.max_pieces,
                level < self.depth, pose, at, ends,
            )  # fmt: skip
            at = rows
            done.append((*final, tested, values))
        pieces = _Pieces(
            *(np.concatenate(parts, axis=-1) for parts in zip(*done, strict=True))
        )
        # each level's pieces are in (box, q) order already
        order = tape.merge_order(pieces.box, pieces.lo, [d[0].size for d in done])
        return pieces.take(order)

    def _level_table(self, level: int) -> tuple[Array, Array, Array, Array] | None:
        """The pieces of isolation level ``level`` (lower and upper bounds, in q
        order: piece ``r``'s halves are pieces ``2 r`` and ``2 r + 1`` of the next
        level) and their derived inputs (``(d, m)`` lower and upper bounds), built
        once; None beyond :data:`_TABLE_CAP` pieces."""
        memo: dict[int, Any] = self.__dict__.setdefault("_level_memo", {})
        if level not in memo:
            compiled = self._compiled()
            if compiled is None or self.pieces << level > _TABLE_CAP:
                memo[level] = None
            elif level == 0:
                memo[level] = compiled[1:3] + compiled[3]
            else:
                # the pieces of the level before, each halved
                q_lo, q_hi = cast(tuple[Array, Array, Any, Any], self._level_table(level - 1))[:2]
                mid = 0.5 * (q_lo + q_hi)
                q_lo = np.stack([q_lo, mid], axis=1).reshape(-1)
                q_hi = np.stack([mid, q_hi], axis=1).reshape(-1)
                derived = tape.derived_values(compiled[0], Interval(q_lo, q_hi))
                memo[level] = (q_lo, q_hi, *derived)
        table: tuple[Array, Array, Array, Array] | None = memo[level]
        return table

    def _end_grid(self) -> tuple[Array, Array, Array, int] | None:
        """The ends of the pieces of the deepest level ``L`` with a table (those of
        its pieces, then the range's end) and their derived inputs as points
        (``(d, g)`` lower and upper bounds), and ``L``: the ends of row ``r`` of
        level ``k <= L`` are the points ``r << (L - k)`` and ``(r + 1) << (L - k)``
        (the halves of a piece share its middle). None without a table."""
        if "_grid_memo" not in self.__dict__:
            memo = None
            # the deepest level within the cap (none where the initial pieces exceed it)
            deepest = min(self.depth, (_TABLE_CAP // self.pieces).bit_length() - 1)
            table = self._level_table(deepest) if deepest >= 0 else None
            if table is not None:
                points = np.append(table[0], table[1][-1])
                prog = cast(tuple[Any, ...], self._compiled())[0]
                values = tape.derived_values(prog, ex.points(points))
                memo = (points, *values, deepest)
            self.__dict__["_grid_memo"] = memo
        grid: tuple[Array, Array, Array, int] | None = self.__dict__["_grid_memo"]
        return grid

    def _f_box(self, lo: Array, hi: Array, box: Any, q: Interval) -> Interval:
        """Enclosure of F over boxes x q: the natural one met with the mean-value form
        ``F(c, q) + sum_j dF/dX_j(box, q) (X_j - c_j)`` about the box's centre ``c``.

        The mean-value form is computed only where the natural enclosure holds 0:
        elsewhere the natural one already excludes a root (and is returned)."""
        natural = self._box_eval(self.f, lo, hi, box, q)
        with _quiet():
            n_lo = np.where(np.isnan(natural.lo), -_INF, natural.lo)
            n_hi = np.where(np.isnan(natural.hi), _INF, natural.hi)
        near = np.flatnonzero((n_lo <= 0) & (n_hi >= 0))
        if not near.size:
            return Interval(n_lo, n_hi)
        box_n = np.asarray(box)[near]
        q_n = ex.take(q, near)
        # the joint's enclosure q_n one object: its sines and cosines are computed once
        centre = 0.5 * (lo + hi)
        mean = self._box_eval(self.f, centre, centre, box_n, q_n)
        for j, g in enumerate(self.df_dx):
            dj = self._box_eval(g, lo, hi, box_n, q_n)
            offset = Interval(lo[box_n, j] - centre[box_n, j], hi[box_n, j] - centre[box_n, j])
            # the offsets are rounded: widen them by an ulp of the bounds
            offset = Interval(
                np.nextafter(np.minimum(offset.lo, 0.0), -_INF),
                np.nextafter(np.maximum(offset.hi, 0.0), _INF),
            )
            mean = mean + dj * offset
        with _quiet():
            m_lo = np.where(np.isnan(mean.lo), -_INF, mean.lo)
            m_hi = np.where(np.isnan(mean.hi), _INF, mean.hi)
        n_lo[near] = np.maximum(n_lo[near], m_lo)
        n_hi[near] = np.minimum(n_hi[near], m_hi)
        return Interval(n_lo, n_hi)

    def _box_eval(self, g: Function, lo: Array, hi: Array, box: Any, q: Interval) -> Interval:
        """``g`` over the boxes ``[lo[box], hi[box]]`` and ``q``: its compiled tape
        where it has one (the same bounds, :mod:`moveability.mechanisms.tape`)."""
        compiled = getattr(g, "tape", None)
        if compiled is not None:
            return run_tape(compiled, lo, hi, box, q)
        return self._eval(g, self._coords(lo, hi, box), q)

    @staticmethod
    def _coords(lo: Array, hi: Array, box: Any) -> list[Interval]:
        """The pose coordinates of the boxes ``box`` as intervals."""
        return [Interval(lo[box, j], hi[box, j]) for j in range(lo.shape[1])]

    @staticmethod
    def _eval(g: Function, coords: list[Interval], q: Interval) -> Interval:
        with _quiet():
            return _as_iv(g(*coords, q), q.lo.shape[0])

    def _runs(self, pieces: _Pieces, n: int) -> _Runs:
        """Group the pieces into runs; on the circle, a run across the cut is unwrapped."""
        m = pieces.box.size
        start_q, stop_q = self._range
        new = np.ones(m, dtype=bool)
        if m:
            new[1:] = (pieces.box[1:] != pieces.box[:-1]) | (pieces.lo[1:] != pieces.hi[:-1])
        run = np.cumsum(new) - 1
        n_runs = int(run[-1]) + 1 if m else 0
        shifted = np.zeros(m, dtype=bool)
        if m and not self.prismatic:
            first = np.ones(m, dtype=bool)
            first[1:] = pieces.box[1:] != pieces.box[:-1]
            last = np.ones(m, dtype=bool)
            last[:-1] = pieces.box[1:] != pieces.box[:-1]
            i_first, i_last = np.flatnonzero(first), np.flatnonzero(last)
            wrap = (
                (pieces.lo[i_first] == start_q)
                & (pieces.hi[i_last] == stop_q)
                & (run[i_first] != run[i_last])
            )
            # the box's first run continues its last one, one turn on
            pos = np.searchsorted(pieces.box[i_first], pieces.box)
            head = wrap[pos] & (run == run[i_first][pos])
            shifted = head
            run = np.where(head, run[i_last][pos], run)
            if wrap.any():
                _, run = np.unique(run, return_inverse=True)
                n_runs = int(run.max()) + 1
        run_box = np.zeros(n_runs, dtype=np.intp)
        run_box[run] = pieces.box
        start = np.full(n_runs, np.inf)
        np.minimum.at(start, run[~shifted], pieces.lo[~shifted])
        end_plain = np.full(n_runs, -np.inf)
        np.maximum.at(end_plain, run[~shifted], pieces.hi[~shifted])
        end_turn = np.full(n_runs, -np.inf)
        np.maximum.at(end_turn, run[shifted], pieces.hi[shifted])
        wrapped = np.isfinite(end_turn)
        # the last q of a wrapped run, one turn on: an enclosure of end + 2 pi
        end = Interval(end_plain)
        if wrapped.any():
            turned = Interval(end_turn[wrapped]) + _TWO_PI
            e_lo, e_hi = end.lo.copy(), end.hi.copy()
            e_lo[wrapped], e_hi[wrapped] = turned.lo, turned.hi
            end = Interval(e_lo, e_hi)
        mono_lo = np.full(n_runs, 2, dtype=np.int8)
        mono_hi = np.full(n_runs, -2, dtype=np.int8)
        np.minimum.at(mono_lo, run, pieces.mono)
        np.maximum.at(mono_hi, run, pieces.mono)
        mono = np.where(mono_lo == mono_hi, mono_lo, 0).astype(np.int8)
        finite = np.ones(n_runs, dtype=bool)
        np.logical_and.at(finite, run, pieces.finite)
        return _Runs(pieces, run, run_box, start, end, mono, finite)

    def reach(
        self, lo: Array, hi: Array, *, folds: bool = True, branches: bool = True
    ) -> LegReach:
        """Reach code, branch enclosures and fold certificates over boxes ``[lo, hi]`` (n, k).

        With ``folds=False`` the fold certificates are not tried: a box where the
        leg may fold is ``REACH_UNKNOWN`` rather than ``FOLD_OUTER`` or
        ``FOLD_INNER``, and ``fold_connected`` is False. Either status folds, so
        a box's tree status is the same; a subdivision asks so for the cells it
        splits anyway.

        With ``branches=False`` the roots are not contracted: the statuses and
        fold certificates are the same, the branch enclosures and the hull are
        the whole line (for callers that need the statuses alone)."""
        lo = np.asarray(lo, dtype=np.float64)
        hi = np.asarray(hi, dtype=np.float64)
        if not lo.shape[0]:
            # no box: nothing to isolate
            none = Interval(np.zeros(0), np.zeros(0))
            return LegReach(
                status=np.zeros(0, dtype=np.uint8),
                branches=[none, Interval(np.zeros(0), np.zeros(0))],
                hull=Interval(np.zeros(0), np.zeros(0)),
                fold_connected=np.zeros(0, dtype=bool),
            )
        # derived inputs of the pose (sin and cos of an angle, ...) once per box
        with tape.remembered_boxes():
            return self._reach(lo, hi, folds, branches)

    def _root_pieces(self, lo: Array, hi: Array) -> _Pieces:
        """The pieces of :meth:`_isolate`, less those over which ``F`` is monotone
        in ``q`` (finite, ``dF/dq`` of a certified sign) and of one sign at both
        ends, for every pose of the box: they hold no root. Near a fold, the wide
        monotone pieces at the ends of the run go, and the run is the part of the
        range about the fold."""
        pieces = self._isolate(lo, hi)
        mono = np.flatnonzero((pieces.mono != 0) & pieces.finite & ~pieces.tested)
        if not mono.size:
            return pieces
        box = pieces.box[mono]
        at_lo = self._box_eval(self.f, lo, hi, box, ex.points(pieces.lo[mono]))
        at_hi = self._box_eval(self.f, lo, hi, box, ex.points(pieces.hi[mono]))
        free = _root_free(pieces.mono[mono], at_lo, at_hi)
        if not free.any():
            return pieces
        keep = np.ones(pieces.box.size, dtype=bool)
        keep[mono[free]] = False
        return pieces.take(keep)

    def _root_runs(self, lo: Array, hi: Array) -> tuple[_Runs, Interval, Interval]:
        """The runs over boxes ``[lo, hi]`` that may hold a root, with ``F`` at their
        two ends over each box.

        Over a run where dF/dq has a certified sign (and F is finite), F is
        monotone in q for every pose of the box: F of that sign's side at the
        run's start, or of the other side at its end, keeps F off 0 over the
        whole run. Such runs hold no root and are dropped: a box just beyond a
        leg's reach, whose enclosures of F over pieces of the range still hold 0,
        is then out, and one with two roots besides is regular."""
        runs = self._runs(self._root_pieces(lo, hi), lo.shape[0])
        f_start, f_end = self._run_ends(lo, hi, runs)
        free = runs.finite & _root_free(runs.mono, f_start, f_end)
        if free.any():
            keep = np.flatnonzero(~free)
            runs, f_start, f_end = runs.take(keep), f_start[keep], f_end[keep]
        return runs, f_start, f_end

    def _piece_ends(
        self, lo: Array, hi: Array, pieces: _Pieces, at: NDArray[np.intp], upper: bool
    ) -> Interval:
        """``F`` over each piece ``at``'s box at its lower (``upper``: upper) end: the
        compiled isolation's bounds there where it tested the piece, the same
        floats computed elsewhere."""
        out = pieces.end_values(at, upper)
        todo = np.flatnonzero(~pieces.tested[at])
        if todo.size:
            q = (pieces.hi if upper else pieces.lo)[at[todo]]
            v = self._box_eval(self.f, lo, hi, pieces.box[at[todo]], ex.points(q))
            out.lo[todo], out.hi[todo] = v.lo, v.hi
        return out

    def _run_ends(self, lo: Array, hi: Array, runs: _Runs) -> tuple[Interval, Interval]:
        """``F`` over each run's box at its start and its end. A run's start is the
        lower end of its first piece, and its end the upper end of its last one
        (a run unwrapped across the circle's cut ends one turn on, computed):
        their values from :meth:`_piece_ends`."""
        first, last, turned = runs.end_pieces()
        f_start = self._piece_ends(lo, hi, runs.pieces, first, upper=False)
        f_end = self._piece_ends(lo, hi, runs.pieces, last, upper=True)
        wrapped = np.flatnonzero(turned[last])
        if wrapped.size:
            v = self._box_eval(self.f, lo, hi, runs.box[wrapped], runs.end[wrapped])
            f_end.lo[wrapped], f_end.hi[wrapped] = v.lo, v.hi
        return f_start, f_end

    def _reach(
        self, lo: Array, hi: Array, folds: bool = True, branches_wanted: bool = True
    ) -> LegReach:
        n = lo.shape[0]
        runs, f_start, f_end = self._root_runs(lo, hi)
        n_runs = np.bincount(runs.box, minlength=n)

        # certified runs: F of definite opposite signs at the two ends
        s = runs.mono.astype(np.float64)
        cert = (runs.mono != 0) & runs.finite
        cert &= np.where(
            s > 0, (f_start.hi < 0) & (f_end.lo > 0), (f_start.lo > 0) & (f_end.hi < 0)
        )
        n_pos = np.bincount(runs.box[cert & (s > 0)], minlength=n)
        n_neg = np.bincount(runs.box[cert & (s < 0)], minlength=n)
        n_cert = n_pos + n_neg

        status = np.full(n, REACH_UNKNOWN, dtype=np.uint8)
        branches = [Interval(np.full(n, -_INF), np.full(n, _INF)) for _ in range(2)]
        if self.prismatic:
            regular = (n_cert == n_runs) & (n_pos <= 1) & (n_neg <= 1) & (n_runs > 0)
        else:
            regular = (n_runs == 2) & (n_pos == 1) & (n_neg == 1)
        status[regular] = REGULAR
        status[n_runs == 0] = REACH_OUT

        # contract the certified roots of the regular boxes
        use = cert & regular[runs.box] & branches_wanted
        if use.any():
            r_lo, r_hi = self._contract(lo, hi, runs, np.flatnonzero(use), (f_start, f_end))
            idx = np.flatnonzero(use)
            for b, sign in ((0, 1), (1, -1)):
                sel = s[idx] == sign
                branches[b].lo[runs.box[idx[sel]]] = r_lo[sel]
                branches[b].hi[runs.box[idx[sel]]] = r_hi[sel]
        if self.prismatic and branches_wanted:
            # a branch without root in the widened stroke: beyond the stroke
            beyond = self._range[1] + 1.0 + abs(self._range[1])
            for b, count in ((0, n_pos), (1, n_neg)):
                none = regular & (count == 0)
                branches[b].lo[none] = beyond
                branches[b].hi[none] = beyond

        # one run: its hull holds every root; try the fold certificates
        hull = Interval(np.full(n, -_INF), np.full(n, _INF))
        single = np.flatnonzero(n_runs == 1)
        fold_connected = np.zeros(n, dtype=bool)
        if single.size:
            run_of_box = np.full(n, -1, dtype=np.intp)
            run_of_box[runs.box] = np.arange(runs.box.size)
            r = run_of_box[single]
        if single.size and branches_wanted:
            hull.lo[single], hull.hi[single] = self._hull_ends(
                lo, hi, runs, r, (f_start[r], f_end[r])
            )
        if single.size and folds:
            ends = (f_start[r], f_end[r])
            convexity, connected = self._fold(lo, hi, runs, single, r, ends)
            fold = (convexity != 0) & (status[single] == REACH_UNKNOWN)
            status[single[fold & (convexity > 0)]] = FOLD_OUTER
            status[single[fold & (convexity < 0)]] = FOLD_INNER
            fold_connected[single] = fold & connected
        return LegReach(status=status, branches=branches, hull=hull, fold_connected=fold_connected)

    def _hull_ends(
        self,
        lo: Array,
        hi: Array,
        runs: _Runs,
        r: NDArray[np.intp],
        ends: tuple[Interval, Interval],
    ) -> tuple[Array, Array]:
        """The bounds of the roots over the boxes of the runs ``r`` (one run a box;
        ``ends``: ``F`` at their starts and ends): the run's ends, moved in where
        its first (last) piece is monotone in ``q`` for every pose of the box and
        ``F`` at the run's start (end) is certified on the side before (after) a
        root.

        A point of that piece where ``F`` is certified on that side lies before
        (after) every root of the box in the piece, and the run's other pieces
        come after (before) it: the piece's contraction (:meth:`_contract`, its
        bracket on that side, whose points are each certified) moves the end to
        the last such point found. A fold's run keeps wide monotone pieces at its ends
        (the isolation stops at monotone pieces), which would widen the hull by
        up to their width."""
        start = runs.start[r].copy()
        end = runs.end.hi[r].copy()
        pieces = runs.pieces
        run = runs.run_of_piece
        first, last, turned = runs.end_pieces()
        for side, f in ((-1, ends[0]), (1, ends[1])):
            at = (first if side < 0 else last)[r]
            mono = pieces.mono[at]
            ok = pieces.finite[at] & (mono != 0) & _on_side(mono.astype(np.float64), side, f)
            idx = np.flatnonzero(ok)
            if not idx.size:
                continue
            # the end piece as a run of its own: its bound on the run's side moved in
            # by the contraction (its other bound, not certified, is not used)
            p_lo, p_hi = pieces.lo[at[idx]], pieces.hi[at[idx]]
            box = runs.box[r[idx]]
            wrapped = turned[at[idx]]
            own = _Runs(
                pieces, run, box, p_lo.copy(), Interval(p_hi.copy()), mono[idx],
                np.ones(idx.size, dtype=bool),
            )  # fmt: skip
            # F at the run's end is known (one turn on where the run wraps: F is
            # then taken at the piece's own end); at the piece's other end, computed
            known = f[idx]
            if side < 0:
                f_ends = (known, self._piece_ends(lo, hi, pieces, at[idx], upper=True))
            else:
                if wrapped.any():
                    turn = self._piece_ends(lo, hi, pieces, at[idx][wrapped], upper=True)
                    known = Interval(known.lo.copy(), known.hi.copy())
                    known.lo[wrapped], known.hi[wrapped] = turn.lo, turn.hi
                f_ends = (self._piece_ends(lo, hi, pieces, at[idx], upper=False), known)
            below, above = self._contract(lo, hi, own, np.arange(idx.size), f_ends)
            if side < 0:
                start[idx] = below
            else:
                c = above.copy()
                c[wrapped] = (Interval(c[wrapped]) + _TWO_PI).hi
                end[idx] = c
        return start, end

    def _contract(
        self,
        lo: Array,
        hi: Array,
        runs: _Runs,
        idx: NDArray[np.intp],
        ends: tuple[Interval, Interval],
        iterations: int = 40,
        rtol: float = 2.0**-10,
    ) -> tuple[Array, Array]:
        """Enclosures of the roots of certified runs ``idx`` (``ends``: ``F`` over each
        box at the start and the end of every run): the largest point found
        certified below each root and the smallest found certified above it.

        Each bound has a bracket: a point certified on its side (``sign * F < 0``
        below, ``> 0`` above), one not. Its next point comes by regula falsi on
        the bound of ``F`` that decides the side (the Illinois way: the value at
        an end kept twice in a row is halved), at least a quarter of the
        tolerance inside the bracket; by bisection where the values are not
        finite, or after three points in a row that did not halve the bracket
        (:func:`falsi_points`). A run stops once both brackets are within
        ``rtol`` of the enclosure's width (the root's own spread over the box),
        or after ``iterations`` points: a bound's uncertainty then widens the
        enclosure by at most that fraction."""
        box = runs.box[idx]
        sign = runs.mono[idx].astype(np.float64)
        up = sign > 0
        f_start, f_end = ends[0][idx], ends[1][idx]
        # lower bound: the largest point certified below the root (sign * F < 0),
        # decided by the bound phi = sign * F's upper bound; its bracket (c: certified)
        below = _Bracket(
            runs.start[idx].copy(), runs.end.lo[idx].copy(),
            np.where(up, f_start.hi, -f_start.lo), np.where(up, f_end.hi, -f_end.lo),
        )  # fmt: skip
        # upper bound: the smallest point certified above it (sign * F > 0), by psi
        above = _Bracket(
            runs.end.hi[idx].copy(), runs.start[idx].copy(),
            np.where(up, f_end.lo, -f_end.hi), np.where(up, f_start.lo, -f_start.hi),
        )  # fmt: skip
        compiled = getattr(self.f, "tape", None)
        kinds = None if compiled is None else tape.trig_kinds(compiled)
        if compiled is not None and kinds is not None:
            # the same steps in one compiled loop (moveability.mechanisms.tape.contract)
            tape.contract(
                compiled, kinds, lo, hi, box, sign, below.arrays(), above.arrays(),
                iterations, rtol,
            )  # fmt: skip
            return below.c, above.c
        active = np.arange(box.size)
        for _ in range(iterations):
            width = above.c[active] - below.c[active]
            done = (below.o[active] - below.c[active] <= rtol * width) & (
                above.c[active] - above.o[active] <= rtol * width
            )
            active = active[~done]
            if not active.size:
                break
            tol = 0.25 * rtol * (above.c[active] - below.c[active])
            m1 = below.point(active, tol)
            m2 = above.point(active, tol)
            b = box[active]
            v = self._box_eval(
                self.f, lo, hi, np.concatenate([b, b]), ex.points(np.concatenate([m1, m2]))
            )
            k = active.size
            s_up = up[active]
            below.update(active, m1, np.where(s_up, v.hi[:k], -v.lo[:k]), side=-1.0)
            above.update(active, m2, np.where(s_up, v.lo[k:], -v.hi[k:]), side=1.0)
        return below.c, above.c

    def _fold_programs(
        self,
    ) -> tuple[tape.Program, tape.Program, tuple[Any, Any]] | None:
        """The program of the tapes of ``F``, ``dF/dq``, ``d2F/dq2`` and the ``dF/dX_j``,
        that of ``F``'s float tape (:func:`moveability.mechanisms._fold_kernels.float_program`)
        and their operations split (:func:`~moveability.mechanisms._fold_kernels.splits`);
        None where a function has no tape. Built once."""
        if "_fold_memo" not in self.__dict__:
            from ._fold_kernels import float_program, splits

            tapes = [getattr(g, "tape", None) for g in (self.f, self.df_dq, self.d2f_dq2)]
            tapes += [getattr(g, "tape", None) for g in self.df_dx]
            found = [t for t in tapes if isinstance(t, tape.Tape)]
            prog = tape.program(found) if len(found) == len(tapes) else None
            fprog = float_program(self.f) if prog is not None else None
            memo = None
            if prog is not None and fprog is not None:
                memo = (prog, fprog, splits(prog, fprog))
            self.__dict__["_fold_memo"] = memo
        memo_: tuple[tape.Program, tape.Program, tuple[Any, Any]] | None
        memo_ = self.__dict__["_fold_memo"]
        return memo_

    def _fold(
        self,
        lo: Array,
        hi: Array,
        runs: _Runs,
        boxes: NDArray[np.intp],
        r: NDArray[np.intp],
        ends: tuple[Interval, Interval] | None = None,
    ) -> tuple[NDArray[np.int8], NDArray[np.bool_]]:
        """Fold certificates of boxes with one run ``r``: convexity sign (0: none), connected.

        ``ends``: F at the runs' two ends (over each box), when known. The steps of
        :meth:`_fold_interpreted` in one compiled loop where every function has a
        tape and ``F`` a float tape (:mod:`moveability.mechanisms._fold_kernels`)."""
        progs = self._fold_programs()
        if progs is None:
            return self._fold_interpreted(lo, hi, runs, boxes, r)
        from ._fold_kernels import fold

        found = self._fold_pieces(lo, hi, runs, boxes, r, ends)
        if found is None:
            return np.zeros(boxes.size, dtype=np.int8), np.zeros(boxes.size, dtype=bool)
        may_convex, may_concave, p_local, q, finite, mono = found
        prog, fprog, split = progs
        b_lo, b_hi = tape.pose_box_values(prog, lo, hi)
        return fold(
            prog,
            fprog,
            split,
            lo[boxes],
            hi[boxes],
            (b_lo[:, boxes], b_hi[:, boxes]),
            may_convex.astype(np.int64) + 2 * may_concave.astype(np.int64),
            p_local,
            q,
            finite,
            mono,
        )

    def _fold_pieces(
        self,
        lo: Array,
        hi: Array,
        runs: _Runs,
        boxes: NDArray[np.intp],
        r: NDArray[np.intp],
        ends: tuple[Interval, Interval] | None,
    ) -> (
        tuple[
            NDArray[np.bool_], NDArray[np.bool_], NDArray[np.intp], Interval,
            NDArray[np.bool_], NDArray[np.int8],
        ]
        | None
    ):  # fmt: skip
        """The first step of the fold certificates of boxes with one run ``r``: ``F``
        positive (may be convex) or negative (concave) at both ends of each box's run
        (``ends``: ``F`` there, when known), and the pieces of the runs that may pass
        (no certificate else): each one's box index, joint enclosure, whether ``F``
        is finite there and the sign of ``dF/dq`` certified there (0: none). None
        if no box may pass."""
        # G = s2 F positive at both ends of Q: F of one definite sign at both ends
        if ends is None:
            ends = (
                self._box_eval(self.f, lo, hi, boxes, ex.points(runs.start[r])),
                self._box_eval(self.f, lo, hi, boxes, runs.end[r]),
            )
        f_start, f_end = ends
        may_convex = (f_start.lo > 0) & (f_end.lo > 0)
        may_concave = (f_start.hi < 0) & (f_end.hi < 0)
        if not (may_convex | may_concave).any():
            return None
        pc = runs.pieces
        candidate = np.zeros(runs.box.size, dtype=bool)
        candidate[r[may_convex | may_concave]] = True
        p_idx = np.flatnonzero(candidate[runs.run_of_piece])
        local = np.full(runs.box.size, -1, dtype=np.intp)
        local[r] = np.arange(boxes.size)
        return (
            may_convex,
            may_concave,
            local[runs.run_of_piece[p_idx]],
            Interval(pc.lo[p_idx], pc.hi[p_idx]),
            pc.finite[p_idx],
            pc.mono[p_idx],
        )

    def _fold_interpreted(
        self, lo: Array, hi: Array, runs: _Runs, boxes: NDArray[np.intp], r: NDArray[np.intp]
    ) -> tuple[NDArray[np.int8], NDArray[np.bool_]]:
        """Fold certificates of boxes with one run ``r``: convexity sign (0: none), connected."""
        k = lo.shape[1]
        n_b = boxes.size
        found = self._fold_pieces(lo, hi, runs, boxes, r, None)
        if found is None:
            return np.zeros(n_b, dtype=np.int8), np.zeros(n_b, dtype=bool)
        may_convex, may_concave, p_local, q, finite, mono = found
        p_box = boxes[p_local]
        d2 = self._box_eval(self.d2f_dq2, lo, hi, p_box, q)
        d1 = self._box_eval(self.df_dq, lo, hi, p_box, q)
        d1_ok = np.isfinite(d1.lo) & np.isfinite(d1.hi)
        ok_d2 = np.isfinite(d2.lo) & np.isfinite(d2.hi) & finite & d1_ok
        convex_p = (ok_d2 & (d2.lo > 0)).astype(np.int64)
        concave_p = (ok_d2 & (d2.hi < 0)).astype(np.int64)
        n_p = np.bincount(p_local, minlength=n_b)
        convex = np.bincount(p_local, weights=convex_p, minlength=n_b) == n_p
        concave = np.bincount(p_local, weights=concave_p, minlength=n_b) == n_p
        s2 = np.where(convex, 1.0, np.where(concave, -1.0, 0.0))
        ends = np.where(s2 > 0, may_convex, may_concave)
        ok = (s2 != 0) & ends
        # the witnesses below only for the boxes passing so far
        keep_p = ok[p_local]
        # (ex.take: the sines and cosines of q already computed are kept)
        p_box, p_local, q, mono = p_box[keep_p], p_local[keep_p], ex.take(q, keep_p), mono[keep_p]
        n_p = np.bincount(p_local, minlength=n_b)
        s2p = s2[p_local]
        q_mid = ex.points(q.mid)

        def g_at(
            points_lo: Array, points_hi: Array, qq: Interval, at: Any = slice(None)
        ) -> Interval:
            """G = s2 F over pose boxes (one per piece, or per piece ``at``) and q."""
            v = self._box_eval(self.f, points_lo, points_hi, np.arange(qq.lo.shape[0]), qq)
            s2q = s2p[at]
            return Interval(np.where(s2q > 0, v.lo, -v.hi), np.where(s2q > 0, v.hi, -v.lo))

        # a corner certainly reachable (G < 0 at some piece's middle) and one certainly not
        # (G > 0 on every piece): candidates chosen in floats, then certified
        n_corners = 1 << k
        g_min = np.full((n_corners, n_b), np.inf)
        g_low = np.full((n_corners, n_b), np.inf)
        lo_p, hi_p = lo[p_box], hi[p_box]
        # each corner's coordinates (one array object per axis and end, laid out as
        # the columns of the corner's points were) and the three joint values: their
        # sines and cosines computed once (ex.remembered)
        columns = [[e[:, j] for e in (lo_p, hi_p)] for j in range(k)]
        q_float = [np.asarray(v, dtype=np.float64) for v in (q.lo, q.mid, q.hi)]
        with ex.remembered():
            for corner in range(n_corners):
                coords = [columns[j][(corner >> j) & 1] for j in range(k)]
                with _quiet():
                    vals = [
                        s2p * np.asarray(self.f(*coords, v), dtype=np.float64) for v in q_float
                    ]
                np.minimum.at(g_min[corner], p_local, vals[1])
                np.minimum.at(
                    g_low[corner], p_local, np.minimum(np.minimum(vals[0], vals[1]), vals[2])
                )
        g_min = np.where(np.isnan(g_min), np.inf, g_min)
        g_low = np.where(np.isnan(g_low), -np.inf, g_low)
        best_in = np.argmin(g_min, axis=0)
        best_out = np.argmax(g_low, axis=0)
        bits = (1 << np.arange(k))[None, :]
        pick_in = (best_in[p_local][:, None] & bits) > 0
        pick_out = (best_out[p_local][:, None] & bits) > 0
        point_in = np.where(pick_in, hi_p, lo_p)
        point_out = np.where(pick_out, hi_p, lo_p)
        g_mid = g_at(point_in, point_in, q_mid)
        ok &= np.bincount(p_local, weights=g_mid.hi < 0, minlength=n_b) > 0  # reachable
        # the steps below only for the boxes still passing (the others fail anyway)
        keep_p = ok[p_local]
        p_box, p_local, s2p, point_out, mono = (
            a[keep_p] for a in (p_box, p_local, s2p, point_out, mono)
        )
        q, q_mid = ex.take(q, keep_p), ex.take(q_mid, keep_p)
        n_p = np.bincount(p_local, minlength=n_b)
        # unreachable: G > 0 over every piece; over a piece where F is monotone in q
        # (for every pose of the box, the corner's too), at its two ends
        from ._fold_kernels import unreachable_tests

        u_at, u_lo, u_hi = unreachable_tests(mono, q.lo, q.hi)
        g_all = g_at(point_out[u_at], point_out[u_at], Interval(u_lo, u_hi), u_at)
        ok &= np.bincount(p_local[u_at], weights=g_all.lo > 0, minlength=n_b) == np.bincount(
            p_local[u_at], minlength=n_b
        )
        keep_p = ok[p_local]
        p_box, p_local, s2p = (a[keep_p] for a in (p_box, p_local, s2p))
        q, q_mid = ex.take(q, keep_p), ex.take(q_mid, keep_p)
        n_p = np.bincount(p_local, minlength=n_b)
        # connectivity: an axis along which G is monotone, and its low face reachable
        connected = np.zeros(n_b, dtype=bool)
        for j in range(k):
            dj = self._box_eval(self.df_dx[j], lo, hi, p_box, q)
            fin = np.isfinite(dj.lo) & np.isfinite(dj.hi)
            up_p = fin & np.where(s2p > 0, dj.lo > 0, dj.hi < 0)  # dG/dX_j > 0
            down_p = fin & np.where(s2p > 0, dj.hi < 0, dj.lo > 0)
            up = np.bincount(p_local, weights=up_p, minlength=n_b) == n_p
            down = np.bincount(p_local, weights=down_p, minlength=n_b) == n_p
            for direction, mask in ((1, up), (-1, down)):
                if not mask.any():
                    continue
                f_lo, f_hi = lo[p_box].copy(), hi[p_box].copy()
                face = lo[p_box, j] if direction > 0 else hi[p_box, j]
                f_lo[:, j] = face
                f_hi[:, j] = face
                g_face = g_at(f_lo, f_hi, q_mid)
                face_ok = np.bincount(p_local, weights=g_face.hi < 0, minlength=n_b) > 0
                connected |= mask & face_ok
        return np.where(ok, s2, 0.0).astype(np.int8), ok & connected

    # ------------------------------------------------------------------ folds
    def fold_waypoints(self, lo: Array, hi: Array, status: int) -> tuple[Array, Array]:
        """Not available: the reachable part of a fold box need not be star-shaped.

        Use :meth:`fold_path` instead.
        """
        raise NotImplementedError(
            f"leg {self.joint}: no hub for a fold box; plan through fold_path instead"
        )

    def fold_path(self, lo: Array, hi: Array, pose: Array) -> Array:
        """Poses from ``pose`` to a fold pose of a ``fold_connected`` box, shape (m, k).

        The motion of the module's notes, in straight segments: along the
        certified axis ``j`` onto the box's reachable face (``G`` falls, the
        pose stays reachable), across that face (convex, every pose reachable)
        to below a corner beyond the reach, and along axis ``j`` towards that
        corner until the two branches meet (within rounding: the last pose found
        reachable). Every pose on it is reachable.

        Raises
        ------
        ValueError
            If the box is not certified ``fold_connected`` or ``pose`` is unreachable.
        """
        lo = np.asarray(lo, dtype=np.float64).reshape(1, -1)
        hi = np.asarray(hi, dtype=np.float64).reshape(1, -1)
        x0 = np.asarray(pose, dtype=np.float64).reshape(-1)
        reach = self.reach(lo, hi)
        if not reach.fold_connected[0]:
            raise ValueError(f"leg {self.joint}: the box is not certified fold-connected")
        axis, direction, s2, q_lo, q_hi = self._fold_axis(lo, hi)

        def m(points: Array) -> Array:
            """min over Q of G = s2 F at poses (G convex on Q)."""
            a = np.full(points.shape[0], q_lo)
            b = np.full(points.shape[0], q_hi)
            for _ in range(60):
                mid = 0.5 * (a + b)
                rising = s2 * self.serial_term(points, mid) > 0
                a = np.where(rising, a, mid)
                b = np.where(rising, mid, b)
            return s2 * self.constraint(points, 0.5 * (a + b))

        if m(x0[None, :])[0] > 0:
            raise ValueError(f"leg {self.joint}: the pose is not reachable")
        k = x0.size
        corners = np.where((np.arange(1 << k)[:, None] >> np.arange(k)) & 1, hi, lo)
        beyond = corners[int(np.argmax(m(corners)))]
        face = lo[0, axis] if direction > 0 else hi[0, axis]
        anchor, below = x0.copy(), beyond.copy()
        anchor[axis] = below[axis] = face
        t_in, t_out = 0.0, 1.0
        if m(beyond[None, :])[0] <= 0:  # pragma: no cover - a corner is certified beyond
            t_in = 1.0
        for _ in range(55):
            if t_in == 1.0:
                break
            t = 0.5 * (t_in + t_out)
            if m((below + t * (beyond - below))[None, :])[0] <= 0:
                t_in = t
            else:
                t_out = t
        return np.stack([x0, anchor, below, below + t_in * (beyond - below)])

    def fold_anchor(self, lo: Array, hi: Array, pose: Array) -> Array:
        """``pose`` moved along the certified axis onto the box's reachable face.

        Every pose of that face is reachable and the segment from a reachable pose
        to its anchor stays reachable (see the module's notes), so two reachable
        poses of a ``fold_connected`` box join through their anchors.
        """
        lo2 = np.asarray(lo, dtype=np.float64).reshape(1, -1)
        hi2 = np.asarray(hi, dtype=np.float64).reshape(1, -1)
        axis, direction, *_ = self._fold_axis(lo2, hi2)
        out = np.array(pose, dtype=np.float64, copy=True).reshape(-1)
        out[axis] = lo2[0, axis] if direction > 0 else hi2[0, axis]
        return out

    def _fold_axis(self, lo: Array, hi: Array) -> tuple[int, int, float, float, float]:
        """Axis, direction in which G grows, convexity and Q of one fold-connected box."""
        runs = self._root_runs(lo, hi)[0]
        pieces = runs.pieces
        q = Interval(pieces.lo, pieces.hi)
        box = np.zeros(pieces.box.size, dtype=np.intp)
        d2 = self._box_eval(self.d2f_dq2, lo, hi, box, q)
        s2 = 1.0 if (d2.lo > 0).all() else -1.0
        for j in range(lo.shape[1]):
            dj = self._box_eval(self.df_dx[j], lo, hi, box, q)
            for direction in (1, -1):
                g = s2 * direction
                if (np.where(g > 0, dj.lo > 0, dj.hi < 0)).all():
                    lo_f, hi_f = lo.copy(), hi.copy()
                    face = lo[0, j] if direction > 0 else hi[0, j]
                    lo_f[0, j] = hi_f[0, j] = face
                    v = self._box_eval(self.f, lo_f, hi_f, box, ex.points(q.mid))
                    if (np.where(s2 > 0, v.hi < 0, v.lo > 0)).any():
                        return j, direction, s2, float(runs.start[0]), float(runs.end.hi[0])
        raise ValueError(f"leg {self.joint}: no monotone axis")  # pragma: no cover


def _root_free(mono: NDArray[np.int8], start: Interval, end: Interval) -> NDArray[np.bool_]:
    """Where ``F``, monotone in ``q`` over a stretch of the range (``mono`` the sign
    of ``dF/dq`` certified there; 0: not monotone), with enclosures ``start`` and
    ``end`` at its two ends, holds no root: its start on the side of ``mono``'s
    sign, or its end on the other.

    Examples
    --------
    >>> from moveability.intervals import Interval
    >>> _root_free(np.array([1, 1, 0], dtype=np.int8), Interval(np.array([0.5, -1.0, 0.5])),
    ...            Interval(np.array([2.0, 1.0, 2.0]))).tolist()
    [True, False, False]
    """
    return np.where(
        mono > 0,
        (start.lo > 0) | (end.hi < 0),
        (mono < 0) & ((start.hi < 0) | (end.lo > 0)),
    )


def falsi_points(c: Any, o: Any, fc: Any, fo: Any, slow: Any, tol: Any) -> Array:
    """The next points of brackets ``[c, o]`` (either order; ``c`` certified on its
    side, with ``fc`` and ``fo`` the values deciding the side at the two ends):
    regula falsi, kept ``tol`` inside the bracket, or the middle where a value is
    not finite, the two are equal, the bracket is narrower than ``2 tol`` or
    ``slow`` (steps in a row that did not halve it) reached ``tape.SLOW_STEPS``.
    Scalars or arrays; the compiled contraction computes the same floats.

    Examples
    --------
    >>> float(falsi_points(0.0, 1.0, -1.0, 3.0, 0, 0.01))
    0.25
    >>> float(falsi_points(0.0, 1.0, float("nan"), 3.0, 0, 0.01))
    0.5
    """
    with np.errstate(all="ignore"):
        ratio = fc / (fc - fo)
        guess = c + (o - c) * ratio
        low = np.minimum(c, o) + tol
        high = np.maximum(c, o) - tol
        falsi = np.isfinite(fc) & np.isfinite(fo) & (fc != fo)
        falsi &= (slow < tape.SLOW_STEPS) & (low <= high)
        return np.where(falsi, np.minimum(np.maximum(guess, low), high), 0.5 * (c + o))


@dataclass
class _Bracket:
    """The brackets of one bound of the runs being contracted: ``c`` the points
    certified on the bound's side, ``o`` the others, ``fc`` and ``fo`` the values
    deciding the side there (NaN: unknown), ``last`` the end moved last (+1:
    ``c``, -1: ``o``, 0: none), ``slow`` the steps in a row that did not halve
    the bracket."""

    c: Array
    o: Array
    fc: Array
    fo: Array
    last: NDArray[np.int64] = field(init=False)
    slow: NDArray[np.int64] = field(init=False)

    def __post_init__(self) -> None:
        self.last = np.zeros(self.c.size, dtype=np.int64)
        self.slow = np.zeros(self.c.size, dtype=np.int64)

    def arrays(
        self,
    ) -> tuple[tuple[Array, Array, Array, Array], tuple[NDArray[np.int64], NDArray[np.int64]]]:
        """The arrays as :func:`moveability.mechanisms.tape.contract` takes them."""
        return (self.c, self.o, self.fc, self.fo), (self.last, self.slow)

    def point(self, at: NDArray[np.intp], tol: Array) -> Array:
        return falsi_points(self.c[at], self.o[at], self.fc[at], self.fo[at], self.slow[at], tol)

    def update(self, at: NDArray[np.intp], m: Array, value: Array, side: float) -> None:
        """The bracket of the runs ``at`` after the points ``m``, where the value
        deciding the side is ``value``: certified where ``side * value > 0``."""
        c, o, fc, fo = self.c[at], self.o[at], self.fc[at], self.fo[at]
        certified = side * value > 0
        before = np.abs(o - c)
        # the Illinois step: the other end's value halved when an end moves twice
        fo = np.where(certified & (self.last[at] == 1), 0.5 * fo, fo)
        fc = np.where(~certified & (self.last[at] == -1), 0.5 * fc, fc)
        c, fc = np.where(certified, m, c), np.where(certified, value, fc)
        o, fo = np.where(certified, o, m), np.where(certified, fo, value)
        self.c[at], self.o[at], self.fc[at], self.fo[at] = c, o, fc, fo
        self.last[at] = np.where(certified, 1, -1)
        self.slow[at] = np.where(np.abs(o - c) > 0.5 * before, self.slow[at] + 1, 0)


def _on_side(mono: Array, side: int, f: Interval) -> NDArray[np.bool_]:
    """Where ``F`` (enclosures ``f``) is certified before (``side`` -1) or after
    (+1) every root of ``F`` monotone in the joint with sign ``mono``: ``side *
    mono * F > 0`` over the whole enclosure (False where NaN)."""
    with _quiet():
        return np.where(side * mono > 0, f.lo > 0, f.hi < 0)


def _as_iv(value: Any, n: int) -> Interval:
    """An Interval of shape (n,) from an expression's value (constants broadcast)."""
    v = value if isinstance(value, Interval) else Interval(value)
    return Interval(np.broadcast_to(v.lo, (n,)).copy(), np.broadcast_to(v.hi, (n,)).copy())
