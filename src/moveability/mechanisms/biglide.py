"""The biglide: two prismatic actuators sliding on one line, two legs meeting at P.

Slider i sits at ``(rho_i, 0)`` on the x axis; a leg of fixed length ``L_i``
joins it to the platform point ``P = (x, y)``:
``F_i = (x - rho_i)^2 + y^2 - L_i^2``. Each leg has two inverse-kinematic
solutions, ``rho_i = x + sqrt(L_i^2 - y^2)`` (branch 0, the slider ahead of P)
and ``x - sqrt(L_i^2 - y^2)`` (branch 1): four postures. Half the pose gradient
``(x - rho_i, y)`` is the row of A, so ``det A = y (rho_2 - rho_1)``: parallel
singularities on the line of the sliders and where the sliders meet. Half the
joint derivative, ``rho_i - x``, is the leg's term of B: serial singularities
where a leg stands perpendicular to the line, ``|y| = L_i``.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .. import intervals as iv
from ..errors import InvalidParameterError
from ..intervals import Interval
from ..limits import JointLimit
from ..types import Array
from .base import (
    FOLD_OUTER,
    REACH_OUT,
    REACH_UNKNOWN,
    REGULAR,
    LegReach,
    Mechanism,
    round_down,
    round_up,
)

__all__ = ["Biglide", "SliderLeg"]


@dataclass(frozen=True)
class SliderLeg:
    """A leg of length ``length`` from a slider on the x axis to the platform point.

    Examples
    --------
    >>> import numpy as np
    >>> SliderLeg(5.0, "rho1").angles(np.array([[1.0, 3.0]])).tolist()
    [[5.0, -3.0]]
    """

    length: float
    joint: str

    n_branches = 2
    #: :meth:`reach` encloses each branch where the leg may fold too (``x +- [0, h]``)
    branches_at_folds = True

    @property
    def distal(self) -> float:
        """The link from the slider to the platform point."""
        return self.length

    def knee_boxes(self, angles: Interval) -> tuple[list[Interval], ...]:
        """The slider ``(rho, 0)`` and its first two derivatives along ``rho`` over
        enclosures of ``rho`` (see :mod:`moveability.analysis.joint_space`)."""
        zero = iv.as_interval(np.zeros(np.shape(angles.lo)))
        one = iv.as_interval(np.ones(np.shape(angles.lo)))
        return [angles, zero], [one, zero], [zero, zero]

    def knee_exact(self, angle: Any, ctx: Any) -> tuple[tuple[Any, Any], tuple[Any, Any]]:
        """The slider ``(rho, 0)`` and its derivative at an interval ``angle`` of
        the interval context ``ctx`` (mpmath's ``iv``; see
        :mod:`moveability.analysis.stop_traces`)."""
        return (angle, ctx.mpf(0)), (ctx.mpf(1), ctx.mpf(0))

    def angles(self, points: Array, clip: bool = False) -> Array:
        """Slider positions of both branches, shape (m, 2); NaN where unreachable.

        With ``clip``, poses beyond the reach by rounding only (1e-12 relative)
        get the perpendicular leg.
        """
        p = np.asarray(points, dtype=np.float64)
        h2 = self.length**2 - p[:, 1] ** 2
        if clip:
            h2 = np.where(h2 >= -1e-12 * self.length**2, np.maximum(h2, 0.0), h2)
        with np.errstate(invalid="ignore"):
            h = np.sqrt(h2)
        return np.stack([p[:, 0] + h, p[:, 0] - h], axis=1)

    def links(self, pose: Array, position: float) -> Array:
        """The leg drawn as a polyline: slider, platform point; shape (2, 2)."""
        return np.array([[position, 0.0], [pose[0], pose[1]]])

    def constraint(self, points: Array, angles: Array) -> Array:
        p = np.asarray(points, dtype=np.float64)
        return (p[..., 0] - angles) ** 2 + p[..., 1] ** 2 - self.length**2

    def a_row(self, points: Array, angles: Array) -> Array:
        p = np.asarray(points, dtype=np.float64)
        return np.stack([p[..., 0] - angles, p[..., 1]], axis=-1)

    def serial_term(self, points: Array, angles: Array) -> Array:
        return np.asarray(angles, dtype=np.float64) - np.asarray(points, dtype=np.float64)[..., 0]

    def a_row_boxes(self, lo: Array, hi: Array, angles: Interval) -> list[Interval]:
        return [Interval(lo[:, 0], hi[:, 0]) - angles, Interval(lo[:, 1], hi[:, 1])]

    def offset(self, lo: Array, hi: Array, branch: int) -> Interval:
        """``x - rho`` on a branch over boxes: ``-+sqrt(L^2 - y^2)``, free of x."""
        y2 = iv.square(Interval(lo[:, 1], hi[:, 1]))
        L2 = iv.square(iv.as_interval(self.length))
        with np.errstate(invalid="ignore"):
            h = iv.sqrt(Interval(np.maximum((L2 - y2).lo, 0.0), np.maximum((L2 - y2).hi, 0.0)))
        return -h if branch == 0 else h

    def row_partials(
        self, lo: Array, hi: Array, angles: Interval
    ) -> tuple[list[list[Interval]], list[Interval]]:
        """Partial derivatives of the row ``(x - rho, y)``: the identity along the pose,
        ``(-1, 0)`` along the slider."""
        n = lo.shape[0]
        one, zero = iv.as_interval(np.ones(n)), iv.as_interval(np.zeros(n))
        return [[one, zero], [zero, one]], [-one, zero]

    def joint_gradient(self, lo: Array, hi: Array, branch: int, angles: Interval) -> list[Interval]:
        """``drho/dP = (1, y / (x - rho))`` on a branch, over boxes where the leg is
        regular; ``x - rho = -+sqrt(L^2 - y^2)`` is enclosed free of x."""
        n = lo.shape[0]
        y = Interval(lo[:, 1], hi[:, 1])
        return [iv.as_interval(np.ones(n)), y / self.offset(lo, hi, branch)]

    def fold_flow(
        self,
        lo: Array,
        hi: Array,
        status: NDArray[np.uint8],
        branch: int,
        velocity: list[Interval],
        cache: dict[str, object] | None = None,
    ) -> tuple[NDArray[np.bool_], Interval]:
        """Over boxes where the leg may stand perpendicular to the rail: whether moving
        at ``velocity`` (one enclosure per pose axis) keeps a pose reachable (``|y|``
        never grows), and an enclosure of the slider's rate on ``branch``,
        ``x +- sqrt(L^2 - y^2)``.

        The rate is ``d_x -+ (y / h) d_y`` with ``h = sqrt(L^2 - y^2)`` in
        ``[0, h_max]`` over the reachable part: ``y / h`` is unbounded but at least
        ``y_min / h_max`` in size, with the sign of ``y``.
        """
        dx, dy = velocity
        y = Interval(lo[:, 1], hi[:, 1])
        keeps = (status == FOLD_OUTER) & ((y * dy).hi <= 0)
        h_max = self.offset(lo, hi, 1).hi
        usable = h_max > 0
        pos, neg = (lo[:, 1] > 0) & usable, (hi[:, 1] < 0) & usable
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = Interval(
                np.where(pos, np.nextafter(lo[:, 1] / h_max, -np.inf), -np.inf),
                np.where(neg, np.nextafter(hi[:, 1] / h_max, np.inf), np.inf),
            )
            sign = 1.0 if branch == 0 else -1.0
            rate = ratio * (-sign * dy) + dx
        still = (dy.lo == 0) & (dy.hi == 0)
        return keeps, Interval(np.where(still, dx.lo, rate.lo), np.where(still, dx.hi, rate.hi))

    #: the slider's rate along a turn about :meth:`turn_centre`: it stays
    turn_rate = 0.0

    def turn_centre(self, angles: Interval) -> list[Interval]:
        """The point a pose may turn about with the slider still: the slider
        ``(rho, 0)``; the leg keeps its length."""
        return [angles, iv.as_interval(np.zeros(angles.lo.shape[0]))]

    def turn_arm(self, lo: Array, hi: Array, branch: int, angles: Interval) -> list[Interval]:
        """The pose less the turn centre on a branch over boxes: ``(x - rho, y)`` with
        ``x - rho = -+sqrt(L^2 - y^2)`` enclosed free of x."""
        return [self.offset(lo, hi, branch), Interval(lo[:, 1], hi[:, 1])]

    def turn_keeps(self, lo: Array, hi: Array, branch: int, turn: float) -> NDArray[np.bool_]:
        """Whether a turn (sense ``turn``) about the slider keeps the branch over the
        boxes: it does where it moves the pose away from the rail's normal through
        the slider (``|y|`` never grows), the branch's side of it."""
        toward = 1.0 if branch == 0 else -1.0
        return np.asarray(
            (lo[:, 1] * turn * toward >= 0) & (hi[:, 1] * turn * toward >= 0), dtype=bool
        )

    def reach(self, lo: Array, hi: Array) -> LegReach:
        """REGULAR where ``|y| < L`` on the whole box, REACH_OUT where ``|y| > L``;
        FOLD_OUTER where the box holds poses on both sides. The reachable part of
        a box, the box cut by the strip ``|y| <= L``, is convex and meets the
        fold line, so every configuration joins the fold: the fold is connected."""
        y = Interval(lo[:, 1], hi[:, 1])
        y2 = iv.square(y)
        L2 = iv.square(iv.as_interval(self.length))
        out = y2.lo > L2.hi
        regular = y2.hi < L2.lo
        # the pose of the box nearest the line, and the farthest: on both sides of |y| = L
        near = iv.square(Interval(np.clip(0.0, lo[:, 1], hi[:, 1])))
        far = iv.square(Interval(np.where(-lo[:, 1] > hi[:, 1], lo[:, 1], hi[:, 1])))
        fold = (near.hi < L2.lo) & (far.lo > L2.hi)
        status = np.full(lo.shape[0], REACH_UNKNOWN, dtype=np.uint8)
        status[fold] = FOLD_OUTER
        status[regular] = REGULAR
        status[out] = REACH_OUT
        with np.errstate(invalid="ignore"):
            h = iv.sqrt(Interval(np.maximum(L2.lo - y2.hi, 0.0), np.maximum(L2.hi - y2.lo, 0.0)))
        x = Interval(lo[:, 0], hi[:, 0])
        branches = [x + h, x - h]
        hull = x + Interval(-h.hi, h.hi)
        unknown = status == REACH_UNKNOWN
        hull = Interval(np.where(unknown, -np.inf, hull.lo), np.where(unknown, np.inf, hull.hi))
        return LegReach(
            status=status, branches=branches, hull=hull, fold_connected=status == FOLD_OUTER
        )

    def fold_waypoints(self, lo: Array, hi: Array, status: int) -> tuple[Array, Array]:
        """Hub and fold point of a box where the leg folds: one pose on the fold line
        (just inside the reach), which every reachable pose of the convex
        reachable part joins by a segment."""
        # the box holds y = L or y = -L strictly; there L^2 - y^2 is 0 in floats too
        y = self.length if hi[1] > self.length else -self.length
        point = np.array([0.5 * (lo[0] + hi[0]), y])
        return point, point


class Biglide(Mechanism):
    """The biglide: two sliders on the x axis, legs of lengths L1 and L2 meeting at P.

    Parameters
    ----------
    L1, L2 : float
        Leg lengths.
    limits : tuple of two JointLimit
        Strokes of rho1 and rho2 (prismatic limits on the x axis).

    Examples
    --------
    >>> from moveability.limits import JointLimit
    >>> m = Biglide(5.0, 4.0, (JointLimit(-6, 6, prismatic=True),) * 2)
    >>> m.postures.shape, [round(float(v), 2) for v in m.bounds[1]]
    ((4, 2), [10.02, 4.01])

    With legs of equal lengths, the postures ``++`` and ``--`` put both sliders
    at one place: det A vanishes on their whole sheets and they are never valid.
    """

    name = "biglide"
    pose_names = ("x", "y")

    def __init__(
        self, L1: float = 5.0, L2: float = 4.0, limits: tuple[JointLimit, JointLimit] | None = None
    ) -> None:
        for name, value in (("L1", L1), ("L2", L2)):
            if not (np.isfinite(value) and value > 0):
                raise InvalidParameterError(f"parameters.{name}", "a positive length", value)
        self.lengths = (float(L1), float(L2))
        if limits is None:
            limits = (JointLimit(-6.0, 6.0, prismatic=True), JointLimit(-6.0, 6.0, prismatic=True))
        if len(limits) != 2 or not all(lim.prismatic for lim in limits):
            raise InvalidParameterError("limits", "two prismatic strokes", limits)
        self.limits = tuple(limits)
        self.slider_legs = (SliderLeg(self.lengths[0], "rho1"), SliderLeg(self.lengths[1], "rho2"))
        self.legs = self.slider_legs
        x_lo = max(round_down(lim.lo - L) for lim, L in zip(self.limits, self.lengths, strict=True))
        x_hi = min(round_up(lim.hi + L) for lim, L in zip(self.limits, self.lengths, strict=True))
        if not x_lo < x_hi:
            raise InvalidParameterError(
                "limits", "strokes that let the two legs meet", self._strokes()
            )
        y_max = min(self.lengths)
        lo = np.array([x_lo, -y_max])
        hi = np.array([x_hi, y_max])
        pad = 1e-3 * (hi - lo) + 4 * np.spacing(np.abs(np.concatenate([lo, hi])).max())
        self.bounds = (lo - pad, hi + pad)

    def det_a_boxes(
        self, lo: Array, hi: Array, angles: list[Interval], posture: int | None = None
    ) -> Interval:
        """Enclosure of ``det A = y (rho2 - rho1)``; for a known posture
        ``rho2 - rho1 = s2 h2 - s1 h1`` with ``h_i = sqrt(L_i^2 - y^2)``, free of x
        (and exactly 0 for the identically singular postures)."""
        if posture is None:
            return super().det_a_boxes(lo, hi, angles)
        branches = self.postures[posture]
        if self.identically_singular(posture):
            zero = np.zeros(lo.shape[0])
            return Interval(zero, zero)
        offsets = [
            leg.offset(lo, hi, int(b)) for leg, b in zip(self.slider_legs, branches, strict=True)
        ]
        # x - rho_i = offsets[i], so rho2 - rho1 = offsets[0] - offsets[1]
        y = Interval(lo[:, 1], hi[:, 1])
        return y * (offsets[0] - offsets[1])

    def exact_region_count(self) -> tuple[int, NDArray[np.float64], tuple[str, ...]]:
        """The number of components of D, decided exactly, with a joint vector inside
        each and notes on exact degeneracies.

        With ``t = rho2 - rho1`` the sliders' distance is ``|t|``, so (see
        :mod:`moveability.analysis.joint_space`) D is the union of the open bands
        ``|L1 - L2| < t < L1 + L2`` and ``-(L1 + L2) < t < -|L1 - L2|`` of the
        plane of strokes: each band meets the (convex) box of strokes in a convex
        set, one component or none. A band meets the box exactly when its open
        range of ``t`` meets ``[lo2 - hi1, hi2 - lo1]``; the comparisons are made
        on the floats' exact rational values, so a stroke that overlaps the
        legs' reach by a hair counts, and one that only touches it does not.

        Returns
        -------
        n : int
            Components of D (the regions are twice as many, one per sign of det A).
        witnesses : (n, 2) array
            A pair of strokes inside each component.
        notes : tuple of str
            One line per band whose closure only touches the box: there the design
            is exactly degenerate (the legs meet only at a parallel singularity).

        Examples
        --------
        >>> from moveability.limits import JointLimit
        >>> m = Biglide(5.0, 5.0, (JointLimit(-1.0, 0.0, prismatic=True),
        ...                        JointLimit(10.0 - 1e-9, 12.0, prismatic=True)))
        >>> n, witnesses, notes = m.exact_region_count()
        >>> n, bool(9.9999999 < witnesses[0, 1] - witnesses[0, 0] < 10.0), notes
        (1, True, ())
        """
        (l1, l2), (s1, s2) = self.lengths, self.limits
        a1, b1, a2, b2 = (Fraction(float(v)) for v in (s1.lo, s1.hi, s2.lo, s2.hi))
        t_lo, t_hi = a2 - b1, b2 - a1
        near, far = abs(Fraction(l1) - Fraction(l2)), Fraction(l1) + Fraction(l2)
        witnesses: list[list[float]] = []
        notes: list[str] = []
        for lo, hi in ((near, far), (-far, -near)):
            if lo < t_hi and t_lo < hi:
                t = (max(lo, t_lo) + min(hi, t_hi)) / 2
                r1 = (max(a1, a2 - t) + min(b1, b2 - t)) / 2
                witnesses.append([float(r1), float(r1 + t)])
            elif lo == t_hi or t_lo == hi:
                side = "rho2 - rho1" if lo >= 0 else "rho1 - rho2"
                notes.append(
                    f"exactly degenerate: the strokes reach {side} = "
                    f"{float(abs(lo if lo == t_hi else hi)):g} (the legs' parallel "
                    "singularity) only at their ends, so no region lies there"
                )
        return len(witnesses), np.array(witnesses, dtype=np.float64).reshape(-1, 2), tuple(notes)

    def identically_singular(self, posture: int) -> bool:
        """With legs of equal lengths, ``++`` and ``--`` put both sliders at one place:
        ``det A = y (rho2 - rho1)`` vanishes on their whole sheets."""
        branches = self.postures[posture]
        return self.lengths[0] == self.lengths[1] and branches[0] == branches[1]

    def _strokes(self) -> dict[str, list[float]]:
        return {f"rho{i + 1}": [lim.lo, lim.hi] for i, lim in enumerate(self.limits)}

    def to_spec(self) -> dict[str, object]:
        """The spec mapping of this mechanism (see :func:`~.registry.load_spec`)."""
        return {
            "mechanism": self.name,
            "parameters": {"L1": self.lengths[0], "L2": self.lengths[1]},
            "limits": self._strokes(),
        }

    def __repr__(self) -> str:
        return f"Biglide(L1={self.lengths[0]:g}, L2={self.lengths[1]:g}, limits={self._strokes()})"
