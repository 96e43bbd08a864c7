"""A planar leg of two links: an actuated revolute joint at a fixed base, a
passive revolute joint at the elbow, and the platform point at the tip.

The leg's constraint is ``F(P, t) = |P - C(t)|^2 - b^2`` with
``C(t) = base + a (cos t, sin t)``. For a pose ``P`` at distance ``rho`` from
the base, ``t = theta +- alpha`` where ``theta`` is the direction of
``P - base`` and ``alpha = arccos((rho^2 + a^2 - b^2) / (2 a rho))``. The two
branches meet (a serial singularity) on the circles ``rho = a + b`` (the leg
stretched) and ``rho = |a - b|`` (the leg folded).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .. import intervals as iv
from ..errors import InvalidParameterError
from ..intervals import Interval
from ..types import Array
from . import _rr_kernels as kernels
from .base import (
    FOLD_INNER,
    FOLD_OUTER,
    REACH_OUT,
    REACH_UNKNOWN,
    REGULAR,
    LegReach,
    kept_in,
)

__all__ = ["RRLeg"]

#: the reach codes, in the order the kernels of :mod:`._rr_kernels` take them
_CODES = np.array([REGULAR, FOLD_OUTER, FOLD_INNER, REACH_OUT, REACH_UNKNOWN], dtype=np.uint8)


def pose_boxes(lo: Array, hi: Array) -> tuple[Array, Array] | None:
    """Boxes of planar poses as the compiled kernels take them: (n, 2)
    C-contiguous float arrays of one shape; None for anything else (the
    Interval code takes it)."""
    lo_a, hi_a = np.asarray(lo), np.asarray(hi)
    if lo_a.ndim != 2 or lo_a.shape[1] != 2 or lo_a.shape != hi_a.shape:
        return None
    return (
        np.ascontiguousarray(lo_a, dtype=np.float64),
        np.ascontiguousarray(hi_a, dtype=np.float64),
    )


def flat_bounds(x: Interval, n: int) -> tuple[Array, Array] | None:
    """The bounds of ``x`` broadcast to (n,), contiguous; None where they do not
    broadcast to it."""
    x = iv.as_interval(x)
    if x.lo.ndim > 1 or x.hi.ndim > 1:
        return None
    try:
        lo, hi = np.broadcast_to(x.lo, (n,)), np.broadcast_to(x.hi, (n,))
    except ValueError:
        return None
    return (
        np.ascontiguousarray(lo, dtype=np.float64),
        np.ascontiguousarray(hi, dtype=np.float64),
    )


def fold_terms_bounds(
    prepare: Any, finish: Any, lo: Array, hi: Array, constants: Array, n_terms: int
) -> tuple[Array, Array]:
    """The bounds of a leg's fold terms, (``n_terms``, n) each, by the compiled
    ``prepare`` (``fold_terms_prepare`` of :mod:`._rr_kernels` or
    :mod:`._delta_leg_kernels`), numpy's arc cosines of the two arguments it
    leaves, and ``finish`` (its ``fold_terms_finish``)."""
    n = lo.shape[0]
    terms_lo, terms_hi, args = np.empty((n_terms, n)), np.empty((n_terms, n)), np.empty((2, n))
    prepare(lo, hi, constants, terms_lo, terms_hi, args)
    acos = np.empty((2, n))
    np.arccos(args[0], out=acos[0])
    np.arccos(args[1], out=acos[1])
    finish(acos, terms_lo, terms_hi)
    return terms_lo, terms_hi


@dataclass(frozen=True)
class RRLeg:
    """A revolute-revolute leg.

    Parameters
    ----------
    base : tuple of float
        The actuated joint's centre.
    proximal, distal : float
        Lengths ``a`` (base to elbow) and ``b`` (elbow to platform point).
    joint : str
        Name of the actuated joint.

    Examples
    --------
    >>> import numpy as np
    >>> leg = RRLeg((0.0, 0.0), 8.0, 5.0, "theta1")
    >>> angles = leg.angles(np.array([[10.0, 3.0]]))
    >>> np.allclose(leg.constraint(np.array([[10.0, 3.0]] * 2), angles[0]), 0.0)
    True
    """

    base: tuple[float, float]
    proximal: float
    distal: float
    joint: str

    n_branches = 2

    def __post_init__(self) -> None:
        for name, value in (("proximal", self.proximal), ("distal", self.distal)):
            if not (np.isfinite(value) and value > 0):
                raise InvalidParameterError(
                    f"{self.joint} {name} length", "a positive length", value
                )

    @cached_property
    def constants(self) -> Array:
        """The leg as the kernels of :mod:`._rr_kernels` take it: its base and
        lengths, and the enclosures of the constants of :func:`.five_bar.branch_det`,
        :meth:`_alpha`, :meth:`reach` and :meth:`_fold_terms`, computed by the same
        Interval operations as there."""
        a, b = self.proximal, self.distal
        a2, b2 = self.proximal**2, self.distal**2
        out = np.zeros(kernels.N_CONSTANTS)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            shift = iv.as_interval(a2) - b2
            k = (iv.as_interval(a) * a - iv.as_interval(b) * b) / (2.0 * a)
            star = iv.as_interval(2.0 * a) * k
            g_min = iv.sqrt(k * 2.0 / a).lo
            r_out2 = iv.square(iv.as_interval(a) + b)
            r_in2 = iv.square(iv.as_interval(a) - b)
            slope = 1.0 / (2.0 * iv.as_interval(a))
        values: dict[int, Any] = {
            kernels.BASE_X: self.base[0],
            kernels.BASE_Y: self.base[1],
            kernels.A: a,
            kernels.A2: a2,
            kernels.B2: b2,
            kernels.FOUR_A2: 4.0 * a2,
            kernels.TOP: a2 + b2,
            kernels.SHIFT_LO: shift.lo,
            kernels.SHIFT_HI: shift.hi,
            kernels.K_LO: k.lo,
            kernels.K_HI: k.hi,
            kernels.TWO_A: 2.0 * a,
            kernels.STAR_LO: star.lo,
            kernels.STAR_HI: star.hi,
            kernels.G_MIN: g_min,
            kernels.K_POSITIVE: 1.0 if k.lo > 0 else 0.0,
            kernels.OUT_LO: r_out2.lo,
            kernels.OUT_HI: r_out2.hi,
            kernels.IN_LO: r_in2.lo,
            kernels.IN_HI: r_in2.hi,
            kernels.SLOPE_LO: slope.lo,
            kernels.SLOPE_HI: slope.hi,
        }
        for index, value in values.items():
            out[index] = float(value)
        out.flags.writeable = False
        return out

    # ------------------------------------------------------------- points
    def elbow(self, angles: Array) -> Array:
        """Elbow positions ``C(t)`` for joint angles, shape (..., 2)."""
        t = np.asarray(angles, dtype=np.float64)
        return np.stack(
            [self.base[0] + self.proximal * np.cos(t), self.base[1] + self.proximal * np.sin(t)],
            axis=-1,
        )

    def knee_boxes(self, angles: Interval) -> tuple[list[Interval], ...]:
        """The elbow ``C(t)`` and its first two derivatives along ``t`` over angle
        enclosures: ``([Cx, Cy], [Cx', Cy'], [Cx'', Cy''])``; the distal link
        joins the elbow to the platform point (see :mod:`moveability.analysis.joint_space`).

        One compiled pass (:func:`._rr_kernels.knee_bounds`): the bounds of
        :meth:`_knee_boxes_intervals`, bit for bit."""
        angles = iv.as_interval(angles)
        lo, hi = np.broadcast_arrays(angles.lo, angles.hi)
        shape = lo.shape
        flat_lo = np.ascontiguousarray(lo, dtype=np.float64).reshape(-1)
        flat_hi = np.ascontiguousarray(hi, dtype=np.float64).reshape(-1)
        out_lo, out_hi = np.empty((4, flat_lo.size)), np.empty((4, flat_lo.size))
        kernels.knee_bounds(flat_lo, flat_hi, self.constants, out_lo, out_hi)
        c, s, x, y = (
            Interval(out_lo[i].reshape(shape), out_hi[i].reshape(shape)) for i in range(4)
        )
        return [x, y], [-s, c], [-c, -s]

    def knee_exact(self, angle: Any, ctx: Any) -> tuple[tuple[Any, Any], tuple[Any, Any]]:
        """The elbow ``C(t)`` and ``C'(t)`` at an interval ``angle`` of the interval
        context ``ctx`` (mpmath's ``iv``, at its working precision): the stop
        traces of :mod:`moveability.analysis.stop_traces`.

        Examples
        --------
        >>> from mpmath import iv
        >>> (x, y), _ = RRLeg((1.0, 0.0), 2.0, 3.0, "t").knee_exact(iv.mpf(0), iv)
        >>> float(x.a), float(y.b)
        (3.0, 0.0)
        """
        r = ctx.mpf(self.proximal)
        c, s = ctx.cos(angle) * r, ctx.sin(angle) * r
        return (c + ctx.mpf(self.base[0]), s + ctx.mpf(self.base[1])), (-s, c)

    def _knee_boxes_intervals(self, angles: Interval) -> tuple[list[Interval], ...]:
        """:meth:`knee_boxes` by :class:`Interval` operations (the reference)."""
        c, s = iv.cos(angles) * self.proximal, iv.sin(angles) * self.proximal
        return [c + self.base[0], s + self.base[1]], [-s, c], [-c, -s]

    def links(self, pose: Array, angle: float) -> Array:
        """The leg drawn as a polyline: base, elbow, platform point; shape (3, 2)."""
        return np.stack([np.asarray(self.base), self.elbow(np.asarray(angle)), pose[:2]])

    def constraint(self, points: Array, angles: Array) -> Array:
        """``F(P, t) = |P - C(t)|^2 - b^2``."""
        d = np.asarray(points, dtype=np.float64) - self.elbow(angles)
        return (d**2).sum(axis=-1) - self.distal**2

    def angles(self, points: Array, clip: bool = False) -> Array:
        """Joint angle of each branch at each point, shape (m, 2); NaN where unreachable.

        Branch 0 is ``theta + alpha``, branch 1 ``theta - alpha``. With ``clip``,
        poses beyond the reach by rounding only (1e-12 relative) get the folded
        configuration instead of NaN: for poses already certified reachable.
        """
        p = np.asarray(points, dtype=np.float64)
        d = p - np.asarray(self.base)
        rho = np.hypot(d[:, 0], d[:, 1])
        a, b = self.proximal, self.distal
        # with unequal links a pose next to the base overflows g: out of reach (NaN)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            g = (rho**2 + a * a - b * b) / (2 * a * rho)
        ok = np.abs(g) <= (1.0 + 1e-12 if clip else 1.0)
        alpha = np.where(ok, np.arccos(np.clip(g, -1.0, 1.0)), np.nan)
        theta = np.arctan2(d[:, 1], d[:, 0])
        return np.stack([theta + alpha, theta - alpha], axis=1)

    def a_row(self, points: Array, angles: Array) -> Array:
        """The leg's row of A, ``dF/dP / 2 = P - C(t)``, shape (..., 2)."""
        return np.asarray(points, dtype=np.float64) - self.elbow(angles)

    def a_row_boxes(self, lo: Array, hi: Array, angles: Interval) -> list[Interval]:
        """Enclosure of the row of A over boxes of poses and an angle enclosure."""
        return [
            Interval(lo[:, 0], hi[:, 0]) - (iv.cos(angles) * self.proximal + self.base[0]),
            Interval(lo[:, 1], hi[:, 1]) - (iv.sin(angles) * self.proximal + self.base[1]),
        ]

    def row_partials(
        self, lo: Array, hi: Array, angles: Interval
    ) -> tuple[list[list[Interval]], list[Interval]]:
        """Partial derivatives of the row of A, ``P - C(t)``, over boxes: along the
        pose axes (``rows[j][k]``: the identity) and along the joint
        (``-C'(t) = a (sin t, -cos t)``)."""
        n = lo.shape[0]
        one, zero = iv.as_interval(np.ones(n)), iv.as_interval(np.zeros(n))
        a = self.proximal
        return [[one, zero], [zero, one]], [iv.sin(angles) * a, -(iv.cos(angles) * a)]

    def joint_gradient(self, lo: Array, hi: Array, branch: int, angles: Interval) -> list[Interval]:
        """``dt/dP`` on a branch over boxes where the leg is regular (``angles`` its
        enclosure): ``-(P - C) / (a ((P - C) x (cos t, sin t)))``, the constraint
        differentiated."""
        u = self.a_row_boxes(lo, hi, angles)
        den = (u[0] * iv.sin(angles) - u[1] * iv.cos(angles)) * self.proximal
        return [-(u[0] / den), -(u[1] / den)]

    #: the joint's rate along a unit turn about :meth:`turn_centre`
    turn_rate = 1.0

    def turn_centre(self, angles: Interval) -> list[Interval]:
        """The point a pose may turn about with the leg rigid: the base. The
        leg's reach and elbow stay, and its joint turns at the same rate."""
        n = angles.lo.shape[0]
        return [iv.as_interval(np.full(n, float(c))) for c in self.base]

    def turn_keeps(self, lo: Array, hi: Array, branch: int, turn: float) -> NDArray[np.bool_]:
        """Whether a turn about :meth:`turn_centre` keeps the branch: always (the
        leg turns rigidly)."""
        return np.ones(lo.shape[0], dtype=bool)

    def fold_flow(
        self,
        lo: Array,
        hi: Array,
        status: NDArray[np.uint8],
        branch: int,
        velocity: list[Interval],
        cache: dict[str, Any] | None = None,
    ) -> tuple[NDArray[np.bool_], Interval]:
        """Over boxes where the leg may fold (``status`` FOLD_OUTER or FOLD_INNER): whether
        moving a pose at ``velocity`` (one enclosure per pose axis) keeps it
        reachable, and an enclosure of the rate of the joint of ``branch``.

        The joint is ``t = theta + s alpha(rho)`` (``s = +1`` on branch 0, ``-1`` on
        branch 1), with ``theta`` the direction and ``rho`` the distance of the
        pose from the base; ``cos alpha = g(rho) = rho / 2a + (a^2 - b^2) / (2 a rho)``.
        The rate ``d theta + s alpha'(rho) d rho`` is unbounded at the fold, where
        ``alpha' = -g' / sin alpha`` and ``sin alpha`` falls to 0: its enclosure
        keeps the lower bound ``1 / max sin alpha`` of ``1 / sin alpha``. ``cache``
        (one per boxes and branch) keeps what does not depend on the velocity.

        Compiled (:func:`._rr_kernels.fold_terms_prepare`, ``fold_terms_finish``
        and ``fold_rate_bounds``): the results of :meth:`_fold_flow_intervals`,
        bit for bit.
        """
        boxes = pose_boxes(lo, hi)
        if boxes is None or len(velocity) != 2:
            return self._fold_flow_intervals(lo, hi, status, branch, velocity, cache)
        n = boxes[0].shape[0]
        parts = [flat_bounds(v, n) for v in velocity]
        if parts[0] is None or parts[1] is None:
            return self._fold_flow_intervals(lo, hi, status, branch, velocity, cache)
        terms = kept_in(cache, "fold_compiled", lambda: self._fold_terms_compiled(*boxes))
        v_lo = np.stack([parts[0][0], parts[1][0]])
        v_hi = np.stack([parts[0][1], parts[1][1]])
        codes = np.ascontiguousarray(np.broadcast_to(status, (n,)), dtype=np.uint8)
        keeps = np.empty(n, dtype=bool)
        out_lo, out_hi = np.empty(n), np.empty(n)
        sign = 1.0 if branch == 0 else -1.0
        kernels.fold_rate_bounds(
            terms[0], terms[1], v_lo, v_hi, codes, _CODES, sign, keeps, out_lo, out_hi
        )
        return keeps, Interval(out_lo, out_hi)

    def _fold_terms_compiled(self, lo: Array, hi: Array) -> tuple[Array, Array]:
        """The bounds of :meth:`_fold_terms` (but the sign), (5, n) each."""
        return fold_terms_bounds(
            kernels.fold_terms_prepare, kernels.fold_terms_finish, lo, hi, self.constants, 5
        )

    def _fold_flow_intervals(
        self,
        lo: Array,
        hi: Array,
        status: NDArray[np.uint8],
        branch: int,
        velocity: list[Interval],
        cache: dict[str, Any] | None = None,
    ) -> tuple[NDArray[np.bool_], Interval]:
        """:meth:`fold_flow` by :class:`Interval` operations (the reference)."""
        terms = kept_in(cache, "fold", lambda: self._fold_terms(lo, hi, branch))
        dx, dy, rho, rho2, alpha_scale, sign = terms
        d = velocity
        radial = dx * d[0] + dy * d[1]  # rho times d rho
        turning = dx * d[1] - dy * d[0]  # rho^2 times d theta
        outer = status == FOLD_OUTER
        inner = status == FOLD_INNER
        keeps = (outer & (radial.hi <= 0)) | (inner & (radial.lo >= 0))
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            alpha_rate = -alpha_scale * (radial / rho)
            theta_rate = turning / rho2
            rate = theta_rate + alpha_rate * sign
        return keeps, rate

    def _fold_terms(self, lo: Array, hi: Array, branch: int) -> tuple[Any, ...]:
        """What :meth:`fold_flow` needs of the boxes alone, for every velocity."""
        base = np.asarray(self.base)
        dx = Interval(lo[:, 0], hi[:, 0]) - base[0]
        dy = Interval(lo[:, 1], hi[:, 1]) - base[1]
        a, b = self.proximal, self.distal
        k = (iv.as_interval(a) * a - iv.as_interval(b) * b) / (2.0 * a)
        rho2 = iv.square(dx) + iv.square(dy)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            rho = iv.sqrt(rho2)
            slope = 1.0 / (2.0 * iv.as_interval(a)) - k / rho2  # g'(rho)
            # sin alpha over the box, from the enclosure of alpha (at most pi)
            near = np.clip(base[None, :], lo, hi)
            far = np.where(np.abs(lo - base) > np.abs(hi - base), lo, hi)
            near2 = iv.square(Interval(near[:, 0]) - base[0]) + iv.square(
                Interval(near[:, 1]) - base[1]
            )
            far2 = iv.square(Interval(far[:, 0]) - base[0]) + iv.square(
                Interval(far[:, 1]) - base[1]
            )
            sin_max = iv.sin(self._alpha(near2, far2)).hi
            inverse = Interval(
                np.where(sin_max > 0, np.nextafter(1.0 / np.maximum(sin_max, 1e-300), 0.0), 0.0),
                np.full(lo.shape[0], np.inf),
            )
            alpha_scale = slope * inverse
        return dx, dy, rho, rho2, alpha_scale, 1.0 if branch == 0 else -1.0

    def serial_term(self, points: Array, angles: Array) -> Array:
        """The leg's term of B, ``-(P - C) x (C - base)``: zero at a serial singularity."""
        c = self.elbow(angles)
        pc = np.asarray(points, dtype=np.float64) - c
        ca = c - np.asarray(self.base)
        return -(pc[..., 0] * ca[..., 1] - pc[..., 1] * ca[..., 0])

    # ------------------------------------------------------------- boxes
    def reach(self, lo: Array, hi: Array) -> LegReach:
        """Reachability and angle enclosures of the leg over boxes ``[lo, hi]`` (n, 2).

        Compiled (:func:`._rr_kernels.reach_prepare` and ``reach_finish``, with
        numpy's arctan2 and arccos between them): the results of
        :meth:`_reach_intervals`, bit for bit.

        Examples
        --------
        >>> import numpy as np
        >>> leg = RRLeg((0.0, 0.0), 8.0, 5.0, "theta1")
        >>> reach = leg.reach(np.array([[9.0, 2.0]]), np.array([[9.5, 2.5]]))
        >>> int(reach.status[0]) == REGULAR
        True
        >>> t = leg.angles(np.array([[9.2, 2.3]]))[0]
        >>> bool(reach.branches[0].contains(t[0])[0] and reach.branches[1].contains(t[1])[0])
        True
        """
        boxes = pose_boxes(lo, hi)
        if boxes is None:
            return self._reach_intervals(lo, hi)
        lo, hi = boxes
        n = lo.shape[0]
        # the direction of each box's centre, by numpy as _direction has it
        base = np.asarray(self.base)
        mid = 0.5 * (lo + hi) - base
        theta_m = np.arctan2(mid[:, 1], mid[:, 0])
        cs, sn = np.cos(theta_m), np.sin(theta_m)
        ref = np.arctan2(sn, cs)
        prep, status = np.empty((6, n)), np.empty(n, dtype=np.uint8)
        kernels.reach_prepare(lo, hi, cs, sn, self.constants, _CODES, prep, status)
        acos, corners = np.empty((2, n)), np.empty((4, n))
        np.arccos(prep[0], out=acos[0])
        np.arccos(prep[1], out=acos[1])
        # the corners of (uy, ux): lo lo, lo hi, hi lo, hi hi
        for i, (y, x) in enumerate(((4, 2), (4, 3), (5, 2), (5, 3))):
            np.arctan2(prep[y], prep[x], out=corners[i])
        out_lo, out_hi = np.empty((3, n)), np.empty((3, n))
        fold_connected = np.empty(n, dtype=bool)
        kernels.reach_finish(
            lo, hi, status, _CODES, cs, sn, ref, corners, prep, acos, self.constants,
            out_lo, out_hi, fold_connected,
        )  # fmt: skip
        return LegReach(
            status=status,
            branches=[Interval(out_lo[0], out_hi[0]), Interval(out_lo[1], out_hi[1])],
            hull=Interval(out_lo[2], out_hi[2]),
            fold_connected=fold_connected,
        )

    def _reach_intervals(self, lo: Array, hi: Array) -> LegReach:
        """:meth:`reach` by :class:`Interval` operations (the reference)."""
        cx, cy = self.base
        a, b = self.proximal, self.distal
        n = lo.shape[0]
        # exact nearest point and farthest corner, then their squared distances
        near = np.clip(np.asarray(self.base)[None, :], lo, hi)
        far = np.where(np.abs(lo - self.base) > np.abs(hi - self.base), lo, hi)
        d_near = Interval(near) - np.asarray(self.base)[None, :]
        d_far = Interval(far) - np.asarray(self.base)[None, :]
        near2 = iv.square(d_near[:, 0]) + iv.square(d_near[:, 1])
        far2 = iv.square(d_far[:, 0]) + iv.square(d_far[:, 1])
        r_out2 = iv.square(iv.as_interval(a) + b)
        r_in2 = iv.square(iv.as_interval(a) - b)

        out = (near2.lo > r_out2.hi) | (far2.hi < r_in2.lo)
        regular = (near2.lo > r_in2.hi) & (far2.hi < r_out2.lo) & (near2.lo > 0)
        # a fold is certified where the box holds points on both sides of the circle
        straddle_out = (near2.hi < r_out2.lo) & (far2.lo > r_out2.hi)
        straddle_in = (near2.hi < r_in2.lo) & (far2.lo > r_in2.hi)
        fold_outer = straddle_out & (near2.lo > r_in2.hi) & ~out
        fold_inner = straddle_in & (far2.hi < r_out2.lo) & ~out & (r_in2.lo > 0)
        status = np.full(n, REACH_UNKNOWN, dtype=np.uint8)
        status[fold_inner] = FOLD_INNER
        status[fold_outer] = FOLD_OUTER
        status[regular] = REGULAR
        status[out] = REACH_OUT

        theta = self._direction(lo, hi)
        alpha = self._alpha(near2, far2)
        branches = [theta + alpha, theta - alpha]
        # both branches together, as one unwrapped interval: theta + [-alpha, alpha] and
        # theta + [alpha, 2 pi - alpha] both hold them; the narrower is kept (the first
        # where the branches meet at alpha = 0, the second where they meet at pi)
        two_pi = Interval(np.nextafter(2 * np.pi, 0.0), np.nextafter(2 * np.pi, np.inf))
        about_zero = theta + Interval(-alpha.hi, alpha.hi)
        about_pi = theta + iv.hull(Interval(alpha.lo), two_pi - Interval(alpha.lo))
        use_zero = about_zero.width <= about_pi.width
        hull = Interval(
            np.where(use_zero, about_zero.lo, about_pi.lo),
            np.where(use_zero, about_zero.hi, about_pi.hi),
        )
        unknown = status == REACH_UNKNOWN
        hull = Interval(np.where(unknown, -np.inf, hull.lo), np.where(unknown, np.inf, hull.hi))
        # the set of reachable points of the box is path-connected and meets the fold:
        # box and disk are convex (outer fold); box minus disk is star-shaped about the
        # corner farthest from the base when the base is beyond both ranges (inner fold)
        beyond = ((cx < lo[:, 0]) | (cx > hi[:, 0])) & ((cy < lo[:, 1]) | (cy > hi[:, 1]))
        fold_connected = (status == FOLD_OUTER) | ((status == FOLD_INNER) & beyond)
        return LegReach(
            status=status,
            branches=branches,
            hull=hull,
            fold_connected=fold_connected,
        )

    def fold_waypoints(self, lo: Array, hi: Array, status: int) -> tuple[Array, Array]:
        """A hub and a fold point of one box where the leg folds (see :meth:`reach`).

        The reachable part of the box is star-shaped about the hub, and the fold
        point is a reachable pose of the box where the two branches meet, so a
        motion can go from any reachable pose to the hub, to the fold point
        (where the posture may change), and back.
        """
        base = np.asarray(self.base)
        near = np.clip(base, lo, hi)
        far = np.where(np.abs(lo - base) > np.abs(hi - base), lo, hi)
        a, b = self.proximal, self.distal
        radius = a + b if status == FOLD_OUTER else abs(a - b)
        # the distance to the base decreases from the far corner to the nearest point:
        # bisect for the circle, keeping the reachable end
        t_lo, t_hi = 0.0, 1.0  # reachable side at t_lo (far corner for an inner fold)
        if status == FOLD_OUTER:
            start, end = near, far
        else:
            start, end = far, near
        for _ in range(200):
            mid = 0.5 * (t_lo + t_hi)
            rho = np.hypot(*(start + mid * (end - start) - base))
            inside = rho <= radius if status == FOLD_OUTER else rho >= radius
            if inside:
                t_lo = mid
            else:
                t_hi = mid
        fold = start + t_lo * (end - start)
        hub = fold if status == FOLD_OUTER else far
        return hub, fold

    def _direction(self, lo: Array, hi: Array) -> Interval:
        """Enclosure of the direction of ``P - base`` over each box, unwrapped near its centre."""
        base = np.asarray(self.base)
        mid = 0.5 * (lo + hi) - base
        theta_m = np.arctan2(mid[:, 1], mid[:, 0])
        cs, sn = np.cos(theta_m), np.sin(theta_m)
        # (cs, sn) is a vector of direction atan2(sn, cs): rotating by it is exact up to a
        # scale, which leaves angles unchanged
        ref = iv.arctan2(Interval(sn), Interval(cs))
        dx = Interval(lo[:, 0], hi[:, 0]) - base[0]
        dy = Interval(lo[:, 1], hi[:, 1]) - base[1]
        ux = dx * cs + dy * sn
        uy = dy * cs - dx * sn
        return ref + iv.arctan2(uy, ux)

    def _alpha(self, near2: Interval, far2: Interval) -> Interval:
        """Enclosure of ``alpha`` for distances between the nearest and farthest points."""
        a, b = self.proximal, self.distal
        k = (iv.as_interval(a) * a - iv.as_interval(b) * b) / (2.0 * a)

        def g(rho2: Interval) -> Interval:
            rho = iv.sqrt(rho2)
            with np.errstate(divide="ignore", invalid="ignore"):
                return rho / (2.0 * a) + k / rho

        g_near, g_far = g(near2), g(far2)
        g_lo = np.minimum(g_near.lo, g_far.lo)
        g_hi = np.maximum(g_near.hi, g_far.hi)
        # g(rho) = rho / 2a + k / rho has its minimum sqrt(2k / a) at rho = sqrt(2 a k)
        if k.lo > 0:
            rho_star2 = iv.as_interval(2.0 * a) * k
            inside = (near2.lo <= rho_star2.hi) & (far2.hi >= rho_star2.lo)
            g_min = iv.sqrt(k * 2.0 / a).lo
            g_lo = np.where(inside, np.minimum(g_lo, g_min), g_lo)
        g_lo = np.where(np.isnan(g_lo), -np.inf, g_lo)
        g_hi = np.where(np.isnan(g_hi), np.inf, g_hi)
        return iv.arccos(Interval(g_lo, g_hi))
