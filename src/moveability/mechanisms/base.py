"""What the analysis needs of a fully-parallel manipulator with independent legs.

Each leg has one actuated joint and a few closed-form inverse-kinematic
branches. Over a box of poses a leg is:

``REACH_OUT``
    unreachable from every pose of the box;
``REGULAR``
    reachable from every pose, its branches distinct (no serial singularity),
    each branch's joint angle enclosed in an interval;
``FOLD_OUTER`` / ``FOLD_INNER``
    the box certainly holds poses on both sides of the leg's serial-singular
    locus (the stretched, or folded, leg); the hull of its branches is enclosed;
``REACH_UNKNOWN``
    anything else.

A *posture* picks one branch per leg; over a box where every leg is REGULAR the
configurations of one posture form a sheet, the graph of a continuous function
of the pose.
"""

from __future__ import annotations

import copy
import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol, cast

import numpy as np
from numpy.typing import NDArray

from .. import intervals as iv
from ..compiled import kernel
from ..errors import InvalidParameterError
from ..intervals import Interval, add_into, mul_into, sub_into
from ..limits import INSIDE, STRADDLES, JointLimit
from ..types import Array
from .constraints import ConstraintMargins, Constraints, Linkage

__all__ = [
    "FOLD_INNER",
    "FOLD_OUTER",
    "REACH_OUT",
    "REACH_UNKNOWN",
    "REGULAR",
    "Leg",
    "LegReach",
    "Mechanism",
    "fitted_span",
    "interval_det",
    "round_down",
    "round_up",
    "three_points",
]

REACH_OUT, REGULAR, FOLD_OUTER, FOLD_INNER, REACH_UNKNOWN = 0, 1, 2, 3, 4

_TWO_PI_UP = float(np.nextafter(2.0 * np.pi, np.inf))  # above the true 2 pi


@dataclass(frozen=True)
class LegReach:
    """A leg over n boxes of poses.

    Attributes
    ----------
    status : ndarray of uint8, shape (n,)
        One of the reach codes above.
    branches : list of Interval
        Joint-angle enclosure of each branch (meaningful where REGULAR; the whole
        line where the leg was asked for its statuses alone).
    hull : Interval
        Enclosure of all branches together (where folding; infinite where unknown).
    fold_connected : ndarray of bool
        Where folding: the reachable poses of the box form a path-connected set
        that meets the serial-singular locus, so every configuration of the leg
        over the box joins every other through the fold.
    """

    status: NDArray[np.uint8]
    branches: list[Interval]
    hull: Interval
    fold_connected: NDArray[np.bool_]


class Leg(Protocol):
    """A leg: one actuated joint, closed-form branches, point and box evaluation."""

    @property
    def joint(self) -> str: ...

    @property
    def n_branches(self) -> int: ...

    def angles(self, points: Array, clip: bool = False) -> Array: ...

    def constraint(self, points: Array, angles: Array) -> Array: ...

    def serial_term(self, points: Array, angles: Array) -> Array: ...

    def a_row(self, points: Array, angles: Array) -> Array: ...

    def a_row_boxes(self, lo: Array, hi: Array, angles: Interval) -> list[Interval]: ...

    def fold_waypoints(self, lo: Array, hi: Array, status: int) -> tuple[Array, Array]: ...

    def reach(self, lo: Array, hi: Array) -> LegReach: ...


def leg_reach(
    leg: Leg, lo: Array, hi: Array, *, folds: bool = True, branches: bool = True
) -> LegReach:
    """``leg.reach(lo, hi)``, leaving out what the caller does not need where the
    leg can: its fold certificates (``folds=False``, a leg's ``folds_optional``;
    they change no box's tree status) and its branches' enclosures
    (``branches=False``, a leg's ``branches_optional``; the statuses alone)."""
    options: dict[str, bool] = {}
    if not folds and getattr(leg, "folds_optional", False):
        options["folds"] = False
    if not branches and getattr(leg, "branches_optional", False):
        options["branches"] = False
    return cast(Any, leg).reach(lo, hi, **options) if options else leg.reach(lo, hi)


def three_points(value: object, name: str) -> tuple[tuple[float, float], ...]:
    """Three points ``[x, y]`` with finite coordinates (a base or a platform triangle).

    Examples
    --------
    >>> three_points([[0, 0], [1, 0], [0, 2]], "parameters.base")
    ((0.0, 0.0), (1.0, 0.0), (0.0, 2.0))
    """
    try:
        pts = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError(name, "three points [x, y]", value) from None
    if pts.shape != (3, 2) or not np.isfinite(pts).all():
        raise InvalidParameterError(name, "three points [x, y] with finite coordinates", value)
    return tuple((float(p[0]), float(p[1])) for p in pts)


def round_up(value: float) -> float:
    """The next float above ``value``: a sum or product rounded outwards."""
    return float(np.nextafter(value, np.inf))


def round_down(value: float) -> float:
    """The next float below ``value``."""
    return float(np.nextafter(value, -np.inf))


def fitted_span(lo: float, hi: float, width: float) -> tuple[float, float]:
    """``[lo, hi]`` widened upwards to ``width`` (kept where it is as wide already).

    ``lo`` stays: a mechanism's bounds sit a little outside its workspace, so the
    first cells' edges stay off the extreme poses of W (a tangency of W's boundary
    with a cell's edge is a case no subdivision decides). The float width of the
    result is at most ``width`` (a tree of that box halved ``d`` times has cells
    at most ``width / 2**d`` wide) and it holds ``[lo, hi]``; where floats cannot
    give both, ``[lo, hi]`` is returned.

    Examples
    --------
    >>> fitted_span(-6.0, 13.0, 32.0)
    (-6.0, 26.0)
    >>> fitted_span(0.0, 8.0, 8.0)
    (0.0, 8.0)
    """
    span = hi - lo
    if not (np.isfinite(span) and np.isfinite(width) and width > span > 0):
        return lo, hi
    new_hi = lo + width
    # the float width may round above the width: step the top down into it
    for _ in range(4):
        if new_hi - lo <= width:
            break
        new_hi = float(np.nextafter(new_hi, -np.inf))
    if new_hi - lo > width or new_hi < hi:
        return lo, hi
    return lo, new_hi


def interval_det(rows: list[list[Interval]]) -> Interval:
    """Enclosure of the determinant of a square matrix of intervals (cofactor expansion).

    Matrices of size 1 to 3 are expanded in compiled passes (:func:`_det_chunk`:
    the same operations in the same order, so the same bounds).

    Examples
    --------
    >>> from moveability.intervals import Interval
    >>> d = interval_det([[Interval(1.0), Interval(2.0)], [Interval(3.0), Interval(4.0)]])
    >>> bool(d.lo <= -2.0 <= d.hi)
    True
    """
    n = len(rows)
    if 1 <= n <= 3:
        return _compiled([iv.as_interval(x) for row in rows for x in row], _det_bounds)
    return _interval_det(rows)


def _interval_det(rows: list[list[Interval]]) -> Interval:
    """:func:`interval_det` by recursion on Interval operations (any size)."""
    n = len(rows)
    if n == 1:
        return rows[0][0]
    total: Interval | None = None
    for j in range(n):
        minor = [row[:j] + row[j + 1 :] for row in rows[1:]]
        term = rows[0][j] * _interval_det(minor)
        if total is None:
            total = term
        elif j % 2:
            total = total - term
        else:
            total = total + term
    assert total is not None
    return total


#: elements per pass of the compiled determinant kernels (their scratch stays in cache)
_CHUNK = 2048


def _compiled(
    items: list[Interval], kernel: Any, at: NDArray[np.int64] | None = None
) -> Interval:
    """``kernel(lo, hi, out_lo, out_hi)`` over intervals broadcast together: their
    bounds as tuples of flat read-only arrays (views where they can be: no stacked
    copy), the result's bounds written into ``out``. With ``at`` (flat indices),
    ``kernel(lo, hi, at, out_lo, out_hi)`` and a result at those elements only."""
    shape = np.broadcast_shapes(*(x.lo.shape for x in items))
    m = int(np.prod(shape, dtype=np.int64))

    def flat(bound: Array) -> Array:
        b = np.asarray(bound, dtype=np.float64)
        b = np.ascontiguousarray(b if b.shape == shape else np.broadcast_to(b, shape))
        view = b.reshape(-1).view()
        view.flags.writeable = False  # one array type for every item
        return view

    lo = tuple(flat(x.lo) for x in items)
    hi = tuple(flat(x.hi) for x in items)
    if at is not None:
        out_lo, out_hi = np.empty(at.size), np.empty(at.size)
        kernel(lo, hi, np.ascontiguousarray(at, dtype=np.int64), out_lo, out_hi)
        return Interval(out_lo, out_hi)
    out_lo, out_hi = np.empty(m), np.empty(m)
    kernel(lo, hi, out_lo, out_hi)
    return Interval(out_lo.reshape(shape), out_hi.reshape(shape))


@kernel
def _det_chunk(
    a_lo: Array, a_hi: Array, out_lo: Array, out_hi: Array, t_lo: Array, t_hi: Array
) -> None:  # pragma: no cover - compiled
    """The determinants of a (k, k, w) stack of interval matrices, k <= 3, into
    ``out`` (w,), as :func:`_interval_det` expands them (the first row's
    cofactors, the terms alternately subtracted and added, each product
    ``row[0][j] * minor``), one operation over the whole stack at a time;
    ``t`` holds (2, w) scratch."""
    k = a_lo.shape[0]
    if k == 1:
        out_lo[:] = a_lo[0, 0]
        out_hi[:] = a_hi[0, 0]
        return
    if k == 2:
        mul_into(a_lo[0, 0], a_hi[0, 0], a_lo[1, 1], a_hi[1, 1], out_lo, out_hi)
        mul_into(a_lo[0, 1], a_hi[0, 1], a_lo[1, 0], a_hi[1, 0], t_lo[0], t_hi[0])
        sub_into(out_lo, out_hi, t_lo[0], t_hi[0], out_lo, out_hi)
        return
    for j in range(3):
        # the 2 x 2 minor of rows 1, 2 without column j: columns c0 < c1
        c0 = 1 if j == 0 else 0
        c1 = 1 if j == 2 else 2
        mul_into(a_lo[1, c0], a_hi[1, c0], a_lo[2, c1], a_hi[2, c1], t_lo[0], t_hi[0])
        mul_into(a_lo[1, c1], a_hi[1, c1], a_lo[2, c0], a_hi[2, c0], t_lo[1], t_hi[1])
        sub_into(t_lo[0], t_hi[0], t_lo[1], t_hi[1], t_lo[0], t_hi[0])
        if j == 0:
            mul_into(a_lo[0, 0], a_hi[0, 0], t_lo[0], t_hi[0], out_lo, out_hi)
            continue
        mul_into(a_lo[0, j], a_hi[0, j], t_lo[0], t_hi[0], t_lo[1], t_hi[1])
        if j == 1:
            sub_into(out_lo, out_hi, t_lo[1], t_hi[1], out_lo, out_hi)
        else:
            add_into(out_lo, out_hi, t_lo[1], t_hi[1], out_lo, out_hi)


@kernel
def _det_bounds(
    lo: Any, hi: Any, out_lo: Array, out_hi: Array
) -> None:  # pragma: no cover - compiled
    """:func:`_det_chunk` of the k x k matrices whose entries (row by row) are the
    flat arrays of the tuples ``lo`` and ``hi``, chunk by chunk."""
    k = 1 if len(lo) == 1 else (2 if len(lo) == 4 else 3)
    m = out_lo.size
    t_lo, t_hi = np.empty((2, _CHUNK)), np.empty((2, _CHUNK))
    a_lo, a_hi = np.empty((k, k, _CHUNK)), np.empty((k, k, _CHUNK))
    for s in range(0, m, _CHUNK):
        e = min(s + _CHUNK, m)
        if e - s < _CHUNK:
            t_lo, t_hi = np.empty((2, e - s)), np.empty((2, e - s))
            a_lo, a_hi = np.empty((k, k, e - s)), np.empty((k, k, e - s))
        for r in range(k):
            for c in range(k):
                a_lo[r, c] = lo[r * k + c][s:e]
                a_hi[r, c] = hi[r * k + c][s:e]
        _det_chunk(a_lo, a_hi, out_lo[s:e], out_hi[s:e], t_lo, t_hi)


@kernel
def _det_rate_bounds(
    lo: Any, hi: Any, out_lo: Array, out_hi: Array
) -> None:  # pragma: no cover - compiled
    """:meth:`Mechanism.det_a_rate` of flat arrays (tuples ``lo``, ``hi``), in
    its order of operations, chunk by chunk. The arrays are: the rows (k x k),
    ``d row / dX`` (leg, entry, axis: k x k x k), ``d row / dq`` (leg, entry: k x
    k), the velocity (k) and the joint rates (k)."""
    k = 1 if len(lo) == 5 else (2 if len(lo) == 20 else 3)
    m = out_lo.size
    term_lo, term_hi = np.empty(_CHUNK), np.empty(_CHUNK)
    t_lo, t_hi = np.empty((2, _CHUNK)), np.empty((2, _CHUNK))
    a_lo, a_hi = np.empty((k, k, _CHUNK)), np.empty((k, k, _CHUNK))
    for s in range(0, m, _CHUNK):
        e = min(s + _CHUNK, m)
        if e - s < _CHUNK:
            term_lo, term_hi = np.empty(e - s), np.empty(e - s)
            t_lo, t_hi = np.empty((2, e - s)), np.empty((2, e - s))
            a_lo, a_hi = np.empty((k, k, e - s)), np.empty((k, k, e - s))
        _det_rate_span(
            lo, hi, s, e, k, out_lo[s:e], out_hi[s:e], term_lo, term_hi, t_lo, t_hi, a_lo, a_hi
        )


@kernel
def _det_rate_bounds_at(
    lo: Any, hi: Any, at: NDArray[np.int64], out_lo: Array, out_hi: Array
) -> None:  # pragma: no cover - compiled
    """:func:`_det_rate_bounds` at the elements ``at`` of the flat arrays only
    (``out`` has one element per index): each chunk's elements gathered, then
    the same operations."""
    n_items = len(lo)
    k = 1 if n_items == 5 else (2 if n_items == 20 else 3)
    m = out_lo.size
    g_lo, g_hi = np.empty((n_items, _CHUNK)), np.empty((n_items, _CHUNK))
    term_lo, term_hi = np.empty(_CHUNK), np.empty(_CHUNK)
    t_lo, t_hi = np.empty((2, _CHUNK)), np.empty((2, _CHUNK))
    a_lo, a_hi = np.empty((k, k, _CHUNK)), np.empty((k, k, _CHUNK))
    for s in range(0, m, _CHUNK):
        e = min(s + _CHUNK, m)
        w = e - s
        if w < _CHUNK:
            g_lo, g_hi = np.empty((n_items, w)), np.empty((n_items, w))
            term_lo, term_hi = np.empty(w), np.empty(w)
            t_lo, t_hi = np.empty((2, w)), np.empty((2, w))
            a_lo, a_hi = np.empty((k, k, w)), np.empty((k, k, w))
        for item in range(n_items):
            src_lo, src_hi = lo[item], hi[item]
            for j in range(w):
                g_lo[item, j] = src_lo[at[s + j]]
                g_hi[item, j] = src_hi[at[s + j]]
        _det_rate_span(
            g_lo, g_hi, 0, w, k, out_lo[s:e], out_hi[s:e], term_lo, term_hi, t_lo, t_hi, a_lo, a_hi
        )


@kernel
def _det_rate_span(
    lo: Any,
    hi: Any,
    s: int,
    e: int,
    k: int,
    o_lo: Array,
    o_hi: Array,
    term_lo: Array,
    term_hi: Array,
    t_lo: Array,
    t_hi: Array,
    a_lo: Array,
    a_hi: Array,
) -> None:  # pragma: no cover - compiled
    """One chunk of :func:`_det_rate_bounds`: elements ``s:e`` of the items
    ``lo[i]``, ``hi[i]`` into ``o`` (``e - s`` elements; the scratch as wide)."""
    at_x = k * k
    at_q = at_x + k * k * k
    at_v = at_q + k * k
    at_r = at_v + k
    for i in range(k):
        # the matrix with row i differentiated
        for r in range(k):
            if r == i:
                continue
            for c in range(k):
                a_lo[r, c] = lo[r * k + c][s:e]
                a_hi[r, c] = hi[r * k + c][s:e]
        for j in range(k):
            q = at_q + i * k + j
            mul_into(
                lo[q][s:e], hi[q][s:e], lo[at_r + i][s:e], hi[at_r + i][s:e],
                a_lo[i, j], a_hi[i, j],
            )  # fmt: skip
            for axis in range(k):
                x = at_x + (i * k + j) * k + axis
                mul_into(
                    lo[x][s:e], hi[x][s:e], lo[at_v + axis][s:e], hi[at_v + axis][s:e],
                    t_lo[0], t_hi[0],
                )  # fmt: skip
                add_into(a_lo[i, j], a_hi[i, j], t_lo[0], t_hi[0], a_lo[i, j], a_hi[i, j])
        if i == 0:
            _det_chunk(a_lo, a_hi, o_lo, o_hi, t_lo, t_hi)
        else:
            _det_chunk(a_lo, a_hi, term_lo, term_hi, t_lo, t_hi)
            add_into(o_lo, o_hi, term_lo, term_hi, o_lo, o_hi)



def kept_in(cache: dict[str, Any] | None, key: str, make: Any) -> Any:
    """``cache[key]``, made by ``make()`` and kept there the first time; ``make()``
    alone without a cache (None)."""
    if cache is None:
        return make()
    if key not in cache:
        cache[key] = make()
    return cache[key]

class Mechanism:
    """Base class of fully-parallel manipulators with independent legs.

    Subclasses set ``name``, ``pose_names``, ``legs``, ``limits`` and
    ``bounds`` and implement :meth:`det_a` (points) and :meth:`det_a_boxes`.
    """

    name: str
    pose_names: tuple[str, ...]
    legs: tuple[Leg, ...]
    limits: tuple[JointLimit, ...]
    #: box of poses holding the workspace: (lo, hi)
    bounds: tuple[Array, Array]
    #: orientation angles that turn freely (radians); their bounds span one turn
    periodic_axes: tuple[int, ...] = ()
    #: passive joint limits, obstacles, link collisions (none: the paper's case; see
    #: :mod:`moveability.mechanisms.constraints`)
    restrictions: Constraints = Constraints()
    #: the links as segments, for the constraints (None: the mechanism takes none)
    linkage: Linkage | None = None
    #: whether :attr:`bounds` hold every pose with a configuration (a box derived
    #: from the design), so that the analysis may widen them (see :meth:`pose_box`);
    #: False where they are a box the user gave, which may cut the workspace
    bounds_hold_workspace: bool = True

    def constrained(self, constraints: Constraints) -> Mechanism:
        """A copy of this mechanism with ``constraints`` (see
        :mod:`moveability.mechanisms.constraints`)."""
        if not constraints.empty and self.linkage is None:
            raise InvalidParameterError("constraints", f"none for a {self.name}", constraints)
        if self.linkage is not None:
            unknown = set(constraints.passive) - set(self.linkage.passive)
            if unknown:
                raise InvalidParameterError(
                    "passive_limits", f"one of {', '.join(self.linkage.passive)}", sorted(unknown)
                )
        out = copy.copy(self)
        out.restrictions = constraints
        return out

    def linkage_points(
        self, lo: Array, hi: Array, angles: list[Interval]
    ) -> dict[str, tuple[Interval, Interval]]:
        """Enclosures of the named points of :attr:`linkage` over boxes of poses with
        joint-angle enclosures per leg."""
        raise NotImplementedError

    def linkage_velocities(
        self,
        lo: Array,
        hi: Array,
        angles: list[Interval],
        velocity: list[Interval],
        rates: list[Interval],
    ) -> dict[str, tuple[Interval, Interval]]:
        """Enclosures of the velocities of the named points of :attr:`linkage`
        when the pose moves at ``velocity`` (one enclosure per pose axis) and each
        leg's joint at ``rates``, over boxes of poses with joint enclosures
        ``angles``."""
        raise NotImplementedError

    def constraint_codes(
        self,
        lo: Array,
        hi: Array,
        angles: list[Interval],
        posture: int | None = None,
        regular: NDArray[np.bool_] | None = None,
    ) -> NDArray[np.uint8] | None:
        """Whether every configuration over each box satisfies the constraints
        (``INSIDE``), none does (``OUTSIDE``) or it cannot tell; None when the
        mechanism has none. ``posture`` and ``regular`` ((n, legs): where each
        leg certainly does not fold) sharpen it (see :meth:`constraint_margins`)."""
        margins = self.constraint_margins(lo, hi, angles, posture, regular)
        return None if margins is None else margins.codes

    def constraint_signs(
        self,
        lo: Array,
        hi: Array,
        angles: list[Interval],
        posture: int,
        regular: NDArray[np.bool_],
    ) -> tuple[NDArray[np.bool_], NDArray[np.bool_]] | None:
        """Over each box: whether no configuration with det A > 0, and whether no
        configuration with det A < 0, satisfies the constraints (see
        :meth:`ConstraintMargins.excluded`); None when nothing beyond the sheets'
        own codes can be said (no constraints, or no side fixed by det A)."""
        if self.restrictions.empty or self.linkage is None or not self.linkage.det_sides:
            return None
        margins = self.constraint_margins(lo, hi, angles, posture, regular)
        if margins is None:
            return None
        return margins.excluded(1), margins.excluded(-1)

    def constraint_checks(
        self,
        lo: Array,
        hi: Array,
        angles: list[Interval],
        posture: int,
        regular: NDArray[np.bool_],
    ) -> tuple[NDArray[np.uint8] | None, tuple[NDArray[np.bool_], NDArray[np.bool_]] | None]:
        """:meth:`constraint_codes`, and :meth:`constraint_signs` where some box
        straddles the constraints (else None), as the sheets need them: the
        constraints enclosed once (one :meth:`constraint_margins`) for both. A
        mechanism with its own codes or signs (a custom one) gets its own
        methods called.

        Examples
        --------
        >>> import numpy as np
        >>> from moveability.intervals import Interval
        >>> from moveability.mechanisms import FiveBar
        >>> m = FiveBar()  # the paper's: no constraint beyond the sheets
        >>> box = np.array([[1.0, 5.0]])
        >>> m.constraint_checks(box, box, [Interval([1.0]), Interval([2.0])], 0,
        ...                     np.ones((1, 2), dtype=bool))
        (None, None)
        """
        mine = type(self)
        if (
            mine.constraint_codes is not Mechanism.constraint_codes
            or mine.constraint_signs is not Mechanism.constraint_signs
        ):
            codes = self.constraint_codes(lo, hi, angles, posture, regular)
            if codes is None or not (codes == STRADDLES).any():
                return codes, None
            return codes, self.constraint_signs(lo, hi, angles, posture, regular)
        margins = self.constraint_margins(lo, hi, angles, posture, regular)
        if margins is None:
            return None, None
        codes = margins.codes
        if (
            not (codes == STRADDLES).any()
            or self.restrictions.empty
            or self.linkage is None
            or not self.linkage.det_sides
        ):
            return codes, None
        return codes, (margins.excluded(1), margins.excluded(-1))

    def constraint_margins(
        self,
        lo: Array,
        hi: Array,
        angles: list[Interval],
        posture: int | None = None,
        regular: NDArray[np.bool_] | None = None,
    ) -> ConstraintMargins | None:
        """The constraints over boxes of poses and one posture's joint enclosures,
        with their rates along motions (:class:`ConstraintMargins`); None when the
        mechanism has none. With the ``posture`` and where its legs do not fold
        (``regular``), the sides that the branches fix are known."""
        if self.restrictions.empty or self.linkage is None:
            return None
        points = self.linkage_points(lo, hi, angles)
        branches = None if posture is None else self.postures[posture]
        return ConstraintMargins(self.restrictions, self.linkage, points, branches, regular)

    def constraints_hold(self, points: Array, joints: Array) -> NDArray[np.bool_]:
        """Whether each configuration (one posture each) certainly satisfies the
        constraints (evaluated over the degenerate box of the configuration)."""
        codes = self.constraint_codes(
            points, points, [Interval(joints[:, i]) for i in range(joints.shape[1])]
        )
        return np.ones(points.shape[0], dtype=bool) if codes is None else codes == INSIDE

    def pose_box(self, widths: Array | None = None) -> tuple[Array, Array]:
        """The box the analysis subdivides: the bounds, with each periodic axis
        widened to a little more than one turn (the float 2 pi is short of it), so
        that the leaves cover every angle.

        Given ``widths`` (one per pose axis) and bounds that hold the workspace
        (:attr:`bounds_hold_workspace`), every other axis is widened upwards to
        its width where it is narrower (see :func:`fitted_span`); the cells added
        hold no pose of W. The analysis asks for the precision times a power of
        two, so that its cells at the precision are that wide.

        Examples
        --------
        >>> from moveability.mechanisms import FiveBar
        >>> m = FiveBar(7, 8, 5, 8, 5)
        >>> lo, hi = m.pose_box([32.0, 32.0])
        >>> [float(v) for v in (hi - lo)]
        [32.0, 32.0]
        >>> bool((lo <= m.bounds[0]).all() and (hi >= m.bounds[1]).all())
        True
        """
        lo = np.array(self.bounds[0], dtype=np.float64)
        hi = np.array(self.bounds[1], dtype=np.float64)
        for axis in self.periodic_axes:
            hi[axis] = round_up(lo[axis] + _TWO_PI_UP)
        if widths is None or not self.bounds_hold_workspace:
            return lo, hi
        want = np.broadcast_to(np.asarray(widths, dtype=np.float64), lo.shape)
        for axis in range(lo.size):
            if axis not in self.periodic_axes:
                span = fitted_span(float(lo[axis]), float(hi[axis]), float(want[axis]))
                lo[axis], hi[axis] = span
        return lo, hi

    def wrap_poses(self, points: Array) -> Array:
        """Poses with their periodic angles brought into ``[lo, lo + 2 pi)`` of the bounds."""
        if not self.periodic_axes:
            return points
        out = np.array(points, dtype=np.float64, copy=True)
        for axis in self.periodic_axes:
            lo = float(self.bounds[0][axis])
            v = out[:, axis]
            inside = (v >= lo) & (v < lo + 2.0 * np.pi)  # left as given, to the last bit
            out[:, axis] = np.where(inside, v, lo + np.mod(v - lo, 2.0 * np.pi))
        return out

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(leg.joint for leg in self.legs)

    @property
    def postures(self) -> NDArray[np.int64]:
        """Branch of each leg in each posture, shape (n_postures, n_legs)."""
        return np.array(
            list(itertools.product(*[range(leg.n_branches) for leg in self.legs])),
            dtype=np.int64,
        ).reshape(-1, len(self.legs))

    def posture_name(self, index: int) -> str:
        """A short label of a posture: one sign per leg (``+`` for branch 0)."""
        return "".join("+-"[b] if b < 2 else str(b) for b in self.postures[index])

    # ---------------------------------------------------------------- points
    def joint_angles(self, points: Array, clip: bool = False) -> Array:
        """Joint angles of every posture at each point, shape (m, n_postures, n_legs).

        NaN where a leg cannot reach; ``clip`` forgives the rounding of poses
        certified reachable (see the legs' ``angles``).
        """
        per_leg = [leg.angles(points, clip=clip) for leg in self.legs]
        post = self.postures
        return np.stack([per_leg[i][:, post[:, i]] for i in range(len(self.legs))], axis=-1)

    def constraints(self, points: Array, joints: Array) -> Array:
        """``F(X, q)``, one value per leg, shape (m, n_legs)."""
        return np.stack(
            [leg.constraint(points, joints[:, i]) for i, leg in enumerate(self.legs)], axis=-1
        )

    def det_b(self, points: Array, joints: Array) -> Array:
        """det B, the product of the legs' serial terms."""
        terms = [leg.serial_term(points, joints[:, i]) for i, leg in enumerate(self.legs)]
        return np.prod(np.stack(terms, axis=-1), axis=-1)

    def det_a(self, points: Array, joints: Array) -> Array:
        """det A at points and joint angles (one posture each): the legs' rows stacked."""
        rows = [leg.a_row(points, joints[..., i]) for i, leg in enumerate(self.legs)]
        with np.errstate(invalid="ignore"):  # NaN rows of unreachable poses give NaN
            return np.asarray(np.linalg.det(np.stack(rows, axis=-2)), dtype=np.float64)

    def to_spec(self) -> dict[str, object]:
        """The spec mapping that rebuilds this mechanism."""
        raise NotImplementedError

    # ----------------------------------------------------------------- boxes
    def det_a_boxes(
        self, lo: Array, hi: Array, angles: list[Interval], posture: int | None = None
    ) -> Interval:
        """Enclosure of det A over boxes of poses with joint-angle enclosures per leg
        (``posture``, when given, is the posture whose configurations they hold)."""
        rows = [leg.a_row_boxes(lo, hi, angles[i]) for i, leg in enumerate(self.legs)]
        return interval_det(rows)

    def det_a_postures(
        self, lo: Array, hi: Array, branch_angles: Sequence[Sequence[Interval | None]]
    ) -> list[Interval]:
        """:meth:`det_a_boxes` of every posture over the same boxes, from each leg's
        joint-angle enclosure on each branch (``branch_angles[i][b]``, leg ``i`` on
        branch ``b``; None for a branch no posture takes): posture ``p`` has leg
        ``i``'s enclosure on its branch ``postures[p][i]``. Here, where det A is the
        determinant of the legs' rows (:meth:`det_a_boxes` not overridden), each
        leg's rows on a branch once for every posture that takes it, else one
        :meth:`det_a_boxes` call per posture; a mechanism may share more.

        Examples
        --------
        >>> import numpy as np
        >>> from moveability.mechanisms import FiveBar
        >>> m = FiveBar()
        >>> lo, hi = np.array([[3.0, 8.5]]), np.array([[3.5, 9.0]])
        >>> reach = [leg.reach(lo, hi) for leg in m.legs]
        >>> angles = [list(r.branches) for r in reach]
        >>> every = m.det_a_postures(lo, hi, angles)
        >>> one = m.det_a_boxes(lo, hi, [angles[0][1], angles[1][0]], posture=2)
        >>> m.postures[2].tolist()
        [1, 0]
        >>> bool(every[2].lo[0] == one.lo[0] and every[2].hi[0] == one.hi[0])
        True
        """
        out = []
        # with det A the determinant of the legs' rows, a leg's rows on a branch
        # are computed once for every posture that takes it
        shared = type(self).det_a_boxes is Mechanism.det_a_boxes
        rows: dict[tuple[int, int], list[Interval]] = {}
        for p, branches in enumerate(self.postures):
            angles = [branch_angles[i][int(b)] for i, b in enumerate(branches)]
            if any(a is None for a in angles):
                raise ValueError(f"branch_angles: no enclosure for a branch of posture {p}")
            if not shared:
                out.append(self.det_a_boxes(lo, hi, angles, posture=p))  # type: ignore[arg-type]
                continue
            for i, b in enumerate(branches):
                if (i, int(b)) not in rows:
                    rows[i, int(b)] = self.legs[i].a_row_boxes(lo, hi, angles[i])  # type: ignore[arg-type]
            out.append(interval_det([rows[i, int(b)] for i, b in enumerate(branches)]))
        return out

    def reaches_and_det(
        self, lo: Array, hi: Array, *, folds: bool = True
    ) -> tuple[list[LegReach], Interval | None]:
        """Each leg's reach over boxes of poses and, for a mechanism whose det A
        depends on the pose alone (whatever the posture and the joint angles), its
        enclosure as :meth:`det_a_boxes` gives it, computed together. Here each
        leg's ``reach`` and None: det A comes from :meth:`det_a_boxes` per posture.

        ``folds=False``: a leg whose fold certificates are optional skips them
        (:func:`leg_reach`)."""
        return [leg_reach(leg, lo, hi, folds=folds) for leg in self.legs], None

    def exact_region_count(self) -> tuple[int, NDArray[np.float64], tuple[str, ...]] | None:
        """The number of components of the joint space's non-singular set D (see
        :mod:`moveability.analysis.joint_space`) decided in closed form, with a
        joint vector inside each and notes on exact degeneracies, where the
        mechanism knows it (the biglide); None here."""
        return None

    def identically_singular(self, posture: int) -> bool:
        """Whether det A vanishes on every configuration of a posture (it then holds
        no configuration of any region). Mechanisms that know such postures say so."""
        return False

    def rows_and_partials(
        self, lo: Array, hi: Array, angles: list[Interval]
    ) -> tuple[list[list[Interval]], list[tuple[list[list[Interval]], list[Interval]]]] | None:
        """The rows of A over boxes and their partial derivatives (each leg's
        ``row_partials``); None when a leg gives none."""
        if not all(hasattr(leg, "row_partials") for leg in self.legs):
            return None
        rows = [leg.a_row_boxes(lo, hi, angles[i]) for i, leg in enumerate(self.legs)]
        partials = [
            leg.row_partials(lo, hi, angles[i])  # type: ignore[attr-defined]
            for i, leg in enumerate(self.legs)
        ]
        return rows, partials

    def det_a_rate(
        self,
        lo: Array,
        hi: Array,
        angles: list[Interval],
        velocity: list[Interval],
        joint_rates: list[Interval],
        rows_and_partials: (
            tuple[list[list[Interval]], list[tuple[list[list[Interval]], list[Interval]]]] | None
        ) = None,
        at: NDArray[np.intp] | None = None,
    ) -> Interval | None:
        """Enclosure of the rate of det A over boxes when the pose moves at
        ``velocity`` (one enclosure per pose axis) and each joint at its rate.

        det A is linear in each row: each leg's row is differentiated in turn,
        ``d row = (d row / dX) velocity + (d row / dq) rate``. None when a leg
        gives no ``row_partials``. ``rows_and_partials`` may be given, as
        :meth:`rows_and_partials` returns them, to spare computing them again.
        ``at`` (indices of boxes), when given, asks for the enclosures at those
        boxes only (the same bounds: each box's operations are its own).
        """
        known = rows_and_partials or self.rows_and_partials(lo, hi, angles)
        if known is None:
            return None
        rows, partials = known
        k = len(velocity)
        if at is not None:
            at = np.asarray(at, dtype=np.int64)
            if not (1 <= k <= 3 and len(self.legs) == k):
                n = lo.shape[0]

                def take(x: Interval) -> Interval:
                    x = iv.as_interval(x)
                    return x[at] if x.lo.ndim and x.lo.shape[0] == n else x

                return self.det_a_rate(
                    lo[at],
                    hi[at],
                    [take(a) for a in angles],
                    [take(v) for v in velocity],
                    [take(r) for r in joint_rates],
                    rows_and_partials=(
                        [[take(x) for x in row] for row in rows],
                        [
                            ([[take(x) for x in entry] for entry in along_x],
                             [take(x) for x in along_q])
                            for along_x, along_q in partials
                        ],
                    ),
                )  # fmt: skip
        if 1 <= k <= 3 and len(self.legs) == k:
            # one compiled pass, the same operations in the same order as below
            items = [iv.as_interval(x) for row in rows for x in row]
            items += [
                iv.as_interval(x) for along_x, _ in partials for entry in along_x for x in entry
            ]
            items += [iv.as_interval(x) for _, along_q in partials for x in along_q]
            items += [iv.as_interval(v) for v in velocity]
            items += [iv.as_interval(r) for r in joint_rates]
            if at is not None:
                return _compiled(items, _det_rate_bounds_at, at)
            return _compiled(items, _det_rate_bounds)
        total: Interval | None = None
        for i in range(len(self.legs)):
            along_x, along_q = partials[i]
            moved = []
            for j in range(k):
                rate = along_q[j] * joint_rates[i]
                for axis in range(k):
                    rate = rate + along_x[j][axis] * velocity[axis]
                moved.append(rate)
            term = interval_det([*rows[:i], moved, *rows[i + 1 :]])
            total = term if total is None else total + term
        return total

    def fold_waypoints(
        self, legs: tuple[int, ...], lo: Array, hi: Array, statuses: tuple[int, ...]
    ) -> tuple[Array, Array]:
        """Hub and fold point of one box where ``legs`` fold (a certified fold group).

        Every reachable pose of the box joins the hub by a segment, and the hub
        joins the fold point, where the postures of the group meet.
        """
        if len(legs) == 1:
            return self.legs[legs[0]].fold_waypoints(lo, hi, statuses[0])
        raise NotImplementedError("no fold waypoints for several legs")

    def folds_connected(self, legs: tuple[int, ...], lo: Array, hi: Array) -> NDArray[np.bool_]:
        """Where several legs fold in one box: whether their configurations all join.

        The default certifies nothing; mechanisms may know better.
        """
        return np.zeros(lo.shape[0], dtype=bool)
