"""The Delta robot (Clavel's 3-RUU, translational): three arms on a base circle,
three parallelogram rods to a platform that keeps its orientation.

Geometry (``z`` up). Leg ``i`` (``i = 1, 2, 3``) lies in the vertical plane of
``u_i = (cos phi_i, sin phi_i, 0)``, ``phi_i = (i - 1) 2 pi / 3``:

* the actuated joint at ``R u_i`` (``R`` the base radius), its axis along
  ``v_i = (-sin phi_i, cos phi_i, 0)``;
* the elbow ``E_i = (R + la cos theta_i) u_i + (0, 0, -la sin theta_i)`` (``la`` the
  arm): ``theta_i = 0`` points the arm outwards, ``theta_i > 0`` down;
* the platform joint ``P + r u_i`` (``r`` the platform radius), at the rod's
  length ``lb`` from the elbow: ``F_i = |P + r u_i - E_i|^2 - lb^2 = 0``.

The pose is the platform's centre ``P = (x, y, z)``; no axis is periodic.

The leg as a planar RR leg
--------------------------
Write ``Q_i = P + (r - R) u_i``, its component along the joint axis
``d_i = Q_i . v_i = P . v_i`` and its in-plane coordinates ``s_i = Q_i . u_i =
P . u_i + r - R`` and ``z``. With ``w = -z`` the elbow is ``la (cos theta, sin
theta)`` in the plane ``(s, w)`` and the constraint reads

``|(s, w) - la (cos theta, sin theta)|^2 = lb^2 - d^2``:

an RR leg with its base at the origin, proximal link ``la`` and a distal link
``sqrt(lb^2 - d^2)`` that depends on the pose. With ``t = |(s, w)|`` the
in-plane distance, ``theta = atan2(w, s) +- alpha``, ``cos alpha = g =
(t^2 + d^2 + la^2 - lb^2) / (2 la t)``. The leg reaches the pose iff ``|g| <= 1``
(``d^2 > lb^2`` gives ``g > 1``); its two branches meet where ``|g| = 1`` (a
serial singularity: the rod's projection on the leg's plane aligned with the
arm). Branch 0 is ``+ alpha``, where ``dF/dtheta > 0``.

``g = t / 2la + (d^2 + la^2 - lb^2) / (2 la t)`` increases with ``d^2`` and is,
in ``t``, monotone or convex with its minimum ``sqrt(d^2 + la^2 - lb^2) / la`` at
``t = sqrt(d^2 + la^2 - lb^2)``: over a box of poses its range is enclosed from
the ranges of ``t`` and ``d^2`` (:meth:`DeltaLeg.reach`). Folds (boxes with
poses on both sides of ``|g| = 1``) are certified from the box's corners, and
their connectivity along an axis on which ``g`` is monotone
(:meth:`DeltaLeg._fold_axes`); a motion crosses them by :meth:`DeltaLeg.fold_path`.

The rows of A are ``P + r u_i - E_i`` (``A t + B theta' = 0`` with ``t = P'``);
B is diagonal, with terms ``la (s_i sin theta_i + z cos theta_i)`` (half
``dF_i/dtheta_i``).

``u_2 = (-1/2, sqrt(3)/2)`` and ``u_3 = (-1/2, -sqrt(3)/2)`` are the exact unit
vectors: enclosures use an enclosure of ``sqrt(3)/2``, points its float.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .. import intervals as iv
from ..errors import InvalidParameterError
from ..intervals import Interval
from ..limits import JointLimit
from ..types import Array
from . import _delta_kernels as kernels
from . import _delta_leg_kernels as leg_kernels
from .base import (
    FOLD_INNER,
    FOLD_OUTER,
    REACH_OUT,
    REACH_UNKNOWN,
    REGULAR,
    LegReach,
    Mechanism,
    interval_det,
    kept_in,
    round_down,
    round_up,
)
from .rr_leg import flat_bounds, fold_terms_bounds

#: the reach codes, in the order the kernels of :mod:`._delta_leg_kernels` take them
_CODES = np.array([REGULAR, FOLD_OUTER, FOLD_INNER, REACH_OUT, REACH_UNKNOWN], dtype=np.uint8)

__all__ = ["Circumradius", "Delta", "DeltaLeg"]

_JOINTS = ("theta1", "theta2", "theta3")
_PARAMETERS = ("base_radius", "platform_radius", "arm", "rod")
_HALF_ROOT3 = iv.sqrt(3.0) * 0.5  # exact scaling by 1/2
_INF = np.inf


def _unit(index: int) -> tuple[tuple[float, float], tuple[Interval, Interval]]:
    """``u_i`` for leg ``index`` (0, 1, 2): floats, and exact enclosures."""
    if index == 0:
        return (1.0, 0.0), (Interval(1.0), Interval(0.0))
    uy = _HALF_ROOT3 if index == 1 else -_HALF_ROOT3
    sign = 1.0 if index == 1 else -1.0
    return (-0.5, sign * float(np.sqrt(3.0) / 2.0)), (Interval(-0.5), uy)


def _quiet() -> Any:
    return np.errstate(all="ignore")


def _pose_boxes(lo: Array, hi: Array) -> tuple[Array, Array] | None:
    """Boxes of poses as the compiled kernels take them: (n, 3) C-contiguous
    float arrays of one shape; None for anything else (the Interval code takes
    it)."""
    lo_a, hi_a = np.asarray(lo), np.asarray(hi)
    if lo_a.ndim != 2 or lo_a.shape[1] != 3 or lo_a.shape != hi_a.shape:
        return None
    return (
        np.ascontiguousarray(lo_a, dtype=np.float64),
        np.ascontiguousarray(hi_a, dtype=np.float64),
    )


@dataclass(frozen=True, eq=False)
class DeltaLeg:
    """One leg of a Delta robot (see the module's notes).

    Parameters
    ----------
    index : int
        0, 1 or 2: the leg's plane is that of ``u_{index+1}``.
    base_radius, platform_radius, arm, rod : float
        ``R``, ``r``, ``la``, ``lb``.
    joint : str
        Name of the actuated joint.

    Examples
    --------
    >>> import numpy as np
    >>> leg = DeltaLeg(0, 10.0, 4.0, 8.0, 15.0, "theta1")
    >>> p = np.array([[1.0, 2.0, -12.0]])
    >>> q = leg.angles(p)
    >>> bool(np.allclose(leg.constraint(np.repeat(p, 2, axis=0), q[0]), 0.0))
    True
    >>> bool((leg.serial_term(np.repeat(p, 2, axis=0), q[0]) * [1, -1] > 0).all())
    True
    """

    index: int
    base_radius: float
    platform_radius: float
    arm: float
    rod: float
    joint: str

    n_branches = 2

    # ------------------------------------------------------------ helpers
    @property
    def unit(self) -> tuple[float, float]:
        """``u_i`` in floats."""
        return _unit(self.index)[0]

    def _offset(self) -> Interval:
        """``r - R``, enclosed."""
        return iv.as_interval(self.platform_radius) - self.base_radius

    @cached_property
    def constants(self) -> Array:
        """The leg as the kernels of :mod:`._delta_kernels` and
        :mod:`._delta_leg_kernels` take it (``N_CONSTANTS``,): the enclosures of
        ``u``, of ``r - R``, of ``la^2 - lb^2`` and of ``1 / la``, computed by
        the same Interval operations as the reference."""
        out = np.zeros(kernels.N_CONSTANTS)
        la = self.arm
        c = iv.square(iv.as_interval(la)) - iv.square(iv.as_interval(self.rod))
        divisor = iv.as_interval(la)
        # Interval.__truediv__'s [1 / hi, 1 / lo], each rounded outwards
        inv_lo, inv_hi = iv.widen_down(1.0 / divisor.hi), iv.widen_up(1.0 / divisor.lo)
        _, (ux, uy) = _unit(self.index)
        offset = self._offset()
        values: dict[int, Any] = {
            kernels.UX_LO: ux.lo, kernels.UX_HI: ux.hi,
            kernels.UY_LO: uy.lo, kernels.UY_HI: uy.hi,
            kernels.OFF_LO: offset.lo, kernels.OFF_HI: offset.hi,
            kernels.ARM: la, kernels.TWO_ARM: 2.0 * la,
            kernels.C_LO: c.lo, kernels.C_HI: c.hi,
            kernels.INV_LO: inv_lo, kernels.INV_HI: inv_hi,
        }  # fmt: skip
        for index, value in values.items():
            out[index] = float(value)
        out.flags.writeable = False
        return out

    def _plane(self, points: Array) -> tuple[Array, Array, Array]:
        """``(s, d, z)`` at poses, in floats."""
        p = np.asarray(points, dtype=np.float64)
        ux, uy = self.unit
        s = p[..., 0] * ux + p[..., 1] * uy + (self.platform_radius - self.base_radius)
        d = -p[..., 0] * uy + p[..., 1] * ux
        return s, d, p[..., 2]

    def _plane_boxes(self, lo: Array, hi: Array) -> tuple[Interval, Interval, Interval]:
        """Enclosures of ``(s, d, z)`` over boxes of poses."""
        _, (ux, uy) = _unit(self.index)
        x = Interval(lo[:, 0], hi[:, 0])
        y = Interval(lo[:, 1], hi[:, 1])
        s = x * ux + y * uy + self._offset()
        d = y * ux - x * uy
        return s, d, Interval(lo[:, 2], hi[:, 2])

    # ------------------------------------------------------------- points
    def elbow(self, angles: Array) -> Array:
        """Elbow positions ``E(theta)``, shape (..., 3)."""
        t = np.asarray(angles, dtype=np.float64)
        ux, uy = self.unit
        h = self.base_radius + self.arm * np.cos(t)
        return np.stack([h * ux, h * uy, -self.arm * np.sin(t)], axis=-1)

    def links(self, pose: Array, angle: float) -> Array:
        """The leg as a polyline: actuated joint, elbow, platform joint; shape (3, 3)."""
        ux, uy = self.unit
        p = np.asarray(pose, dtype=np.float64)[:3]
        base = np.array([self.base_radius * ux, self.base_radius * uy, 0.0])
        tip = p + self.platform_radius * np.array([ux, uy, 0.0])
        return np.stack([base, self.elbow(np.asarray(angle)), tip])

    def angles(self, points: Array, clip: bool = False) -> Array:
        """Joint angle of each branch at each pose, shape (m, 2); NaN where unreachable.

        Branch 0 is ``atan2(-z, s) + alpha``, branch 1 ``atan2(-z, s) - alpha``.
        With ``clip``, poses beyond the reach by rounding only (1e-12 relative) get
        the folded configuration.
        """
        s, d, z = self._plane(np.asarray(points, dtype=np.float64).reshape(-1, 3))
        la, lb = self.arm, self.rod
        t = np.hypot(s, z)
        with _quiet():
            g = (s * s + z * z + d * d + (la * la - lb * lb)) / (2.0 * la * t)
        ok = np.abs(g) <= (1.0 + 1e-12 if clip else 1.0)
        alpha = np.where(ok, np.arccos(np.clip(g, -1.0, 1.0)), np.nan)
        direction = np.arctan2(-z, s)
        return np.stack([direction + alpha, direction - alpha], axis=1)

    def _row(self, points: Array, angles: Array) -> tuple[Array, Array, Array]:
        p = np.asarray(points, dtype=np.float64)
        t = np.asarray(angles, dtype=np.float64)
        ux, uy = self.unit
        h = self.platform_radius - self.base_radius - self.arm * np.cos(t)
        return p[..., 0] + h * ux, p[..., 1] + h * uy, p[..., 2] + self.arm * np.sin(t)

    def constraint(self, points: Array, angles: Array) -> Array:
        """``F = |P + r u - E(theta)|^2 - lb^2``."""
        rx, ry, rz = self._row(points, angles)
        return rx * rx + ry * ry + rz * rz - self.rod * self.rod

    def a_row(self, points: Array, angles: Array) -> Array:
        """The leg's row of A, ``P + r u - E(theta)``, shape (..., 3)."""
        return np.stack(self._row(points, angles), axis=-1)

    def serial_term(self, points: Array, angles: Array) -> Array:
        """Half ``dF/dtheta``: ``la (s sin theta + z cos theta)``; zero at a serial
        singularity, positive on branch 0."""
        s, _, z = self._plane(points)
        t = np.asarray(angles, dtype=np.float64)
        return self.arm * (s * np.sin(t) + z * np.cos(t))

    # -------------------------------------------------------------- boxes
    def a_row_boxes(self, lo: Array, hi: Array, angles: Interval) -> list[Interval]:
        """Enclosure of the row of A over boxes of poses and an angle enclosure."""
        _, (ux, uy) = _unit(self.index)
        h = self._offset() - iv.cos(angles) * self.arm
        return [
            Interval(lo[:, 0], hi[:, 0]) + h * ux,
            Interval(lo[:, 1], hi[:, 1]) + h * uy,
            Interval(lo[:, 2], hi[:, 2]) + iv.sin(angles) * self.arm,
        ]

    def centre_boxes(self, angles: Interval) -> list[Interval]:
        """Enclosure of the sphere centre ``E(theta) - r u`` (the platform joint lies
        on the sphere of radius ``lb`` about it; the platform's centre on the same
        sphere about it shifted by ``-r u``), over joint enclosures."""
        _, (ux, uy) = _unit(self.index)
        h = iv.cos(angles) * self.arm - self._offset()
        return [h * ux, h * uy, -(iv.sin(angles) * self.arm)]

    def row_partials(
        self, lo: Array, hi: Array, angles: Interval
    ) -> tuple[list[list[Interval]], list[Interval]]:
        """Partial derivatives of the row of A, ``P + (r - R - la cos theta) u +
        la sin theta e_z``, over boxes: the identity along the pose, ``la (sin theta
        u + cos theta e_z)`` along the joint."""
        n = lo.shape[0]
        one, zero = iv.as_interval(np.ones(n)), iv.as_interval(np.zeros(n))
        _, (ux, uy) = _unit(self.index)
        sin_a = iv.sin(angles) * self.arm
        return (
            [[one, zero, zero], [zero, one, zero], [zero, zero, one]],
            [sin_a * ux, sin_a * uy, iv.cos(angles) * self.arm],
        )

    def joint_gradient(self, lo: Array, hi: Array, branch: int, angles: Interval) -> list[Interval]:
        """``dtheta/dP`` over boxes (``angles`` the branch's enclosure): the
        constraint differentiated, ``-row / (la (s sin theta + z cos theta))``;
        unbounded where the serial term may vanish.

        Compiled (:func:`._delta_leg_kernels.joint_gradient_bounds`): the bounds
        of :meth:`_joint_gradient_intervals`, bit for bit.

        Examples
        --------
        >>> import numpy as np
        >>> leg = DeltaLeg(0, 10.0, 4.0, 8.0, 15.0, "theta1")
        >>> p = np.array([[1.0, 2.0, -12.0]])
        >>> q = leg.angles(p)[0, 0]
        >>> grad = leg.joint_gradient(p, p, 0, Interval(q))
        >>> step = np.array([[1e-7, 0.0, 0.0]])
        >>> rate = (leg.angles(p + step)[0, 0] - q) / 1e-7
        >>> bool(abs(rate - grad[0].mid[0]) < 1e-5)
        True
        """
        boxes = _pose_boxes(lo, hi)
        if boxes is None:
            return self._joint_gradient_intervals(lo, hi, branch, angles)
        lo, hi = boxes
        n = lo.shape[0]
        bounds = flat_bounds(angles, n)
        if bounds is None:
            return self._joint_gradient_intervals(lo, hi, branch, angles)
        out_lo, out_hi = np.empty((3, n)), np.empty((3, n))
        leg_kernels.joint_gradient_bounds(
            lo, hi, bounds[0], bounds[1], self.constants, out_lo, out_hi
        )
        return [Interval(out_lo[e], out_hi[e]) for e in range(3)]

    def _joint_gradient_intervals(
        self, lo: Array, hi: Array, branch: int, angles: Interval
    ) -> list[Interval]:
        """:meth:`joint_gradient` by :class:`Interval` operations (the reference)."""
        s, _, z = self._plane_boxes(lo, hi)
        den = (s * iv.sin(angles) + z * iv.cos(angles)) * self.arm
        with _quiet():
            return [-(r / den) for r in self.a_row_boxes(lo, hi, angles)]

    def _g_range(self, t: Interval, d2: Interval) -> tuple[Array, Array]:
        """Bounds of ``g(t, d^2)`` for ``t`` in ``[t.lo, t.hi]`` and ``d^2`` in ``d2``."""
        la = self.arm
        c = iv.square(iv.as_interval(la)) - iv.square(iv.as_interval(self.rod))

        def g(tv: Array, dv: Array) -> Interval:
            tt = Interval(tv)
            with _quiet():
                return (iv.square(tt) + Interval(dv) + c) / (tt * (2.0 * la))

        with _quiet():
            g_hi = np.maximum(g(t.lo, d2.hi).hi, g(t.hi, d2.hi).hi)
            g_lo = np.minimum(g(t.lo, d2.lo).lo, g(t.hi, d2.lo).lo)
            # convex in t where d^2 + la^2 - lb^2 > 0: its minimum may lie inside
            k = Interval(d2.lo) + c
            root = iv.sqrt(k)
            inside = (k.lo > 0) & (root.lo <= t.hi) & (root.hi >= t.lo)
            g_lo = np.where(inside, np.minimum(g_lo, (root / la).lo), g_lo)
        g_lo = np.where(np.isnan(g_lo), -_INF, g_lo)
        g_hi = np.where(np.isnan(g_hi), _INF, g_hi)
        return g_lo, g_hi

    @staticmethod
    def _direction(s: Interval, w: Interval) -> Interval:
        """Enclosure of ``atan2(w, s)`` over boxes, unwrapped near the boxes' centre."""
        theta_m = np.arctan2(w.mid, s.mid)
        cs, sn = np.cos(theta_m), np.sin(theta_m)
        # (cs, sn) has the direction atan2(sn, cs): multiplying by its conjugate
        # turns by that angle exactly, up to a scale that leaves angles unchanged
        ref = iv.arctan2(Interval(sn), Interval(cs))
        us = s * cs + w * sn
        uw = w * cs - s * sn
        return ref + iv.arctan2(uw, us)

    def _g_boxes(self, lo: Array, hi: Array) -> tuple[Array, Array, Array]:
        """Bounds of ``g`` over boxes of poses, and a lower bound of ``t``."""
        s, d, z = self._plane_boxes(lo, hi)
        t = iv.sqrt(iv.square(s) + iv.square(z))
        g_lo, g_hi = self._g_range(t, iv.square(d))
        return g_lo, g_hi, t.lo

    def branch_boxes(self, lo: Array, hi: Array, branch: int) -> Interval:
        """Enclosure of the joint of ``branch`` over boxes where the leg is regular
        (as :meth:`reach` gives it; meaningless elsewhere)."""
        s, d, z = self._plane_boxes(lo, hi)
        t = iv.sqrt(iv.square(s) + iv.square(z))
        g_lo, g_hi = self._g_range(t, iv.square(d))
        alpha = iv.arccos(Interval(g_lo, g_hi))
        direction = self._direction(s, -z)
        return direction + alpha if branch == 0 else direction - alpha

    def reach(self, lo: Array, hi: Array) -> LegReach:
        """Reachability and angle enclosures of the leg over boxes ``[lo, hi]`` (n, 3).

        From the range of ``g`` (see the module's notes): REACH_OUT where
        ``|g| > 1`` on the whole box, REGULAR where ``|g| < 1`` and ``t > 0``.
        FOLD_OUTER where ``g > -1`` on the box and two of its corners (or its
        centre) have ``g < 1`` and ``g > 1``; FOLD_INNER likewise about ``-1``.
        ``fold_connected`` by the monotone-axis argument of :meth:`_fold_axes`.

        Compiled (:func:`._delta_leg_kernels.reach_prepare`, ``reach_turn`` and
        ``reach_finish``, with numpy's arctan2, cos, sin and arccos between
        them): the results of :meth:`_reach_intervals`, bit for bit.

        Examples
        --------
        >>> import numpy as np
        >>> leg = DeltaLeg(0, 10.0, 4.0, 8.0, 15.0, "theta1")
        >>> reach = leg.reach(np.array([[0.9, 1.9, -12.1]]), np.array([[1.1, 2.1, -11.9]]))
        >>> int(reach.status[0]) == REGULAR
        True
        >>> q = leg.angles(np.array([[1.0, 2.0, -12.0]]))[0]
        >>> bool(reach.branches[0].contains(q[0])[0] and reach.branches[1].contains(q[1])[0])
        True
        """
        boxes = _pose_boxes(lo, hi)
        if boxes is None:
            return self._reach_intervals(lo, hi)
        lo, hi = boxes
        n = lo.shape[0]
        status, fold = np.empty(n, dtype=np.uint8), np.empty(n, dtype=np.uint8)
        connected = np.empty(n, dtype=bool)
        prep = np.empty((leg_kernels.N_PREP, n))
        leg_kernels.reach_prepare(lo, hi, self.constants, _CODES, status, fold, connected, prep)
        # the library functions of _direction and arccos, by numpy on contiguous
        # arrays of the same arguments (see the kernels' notes)
        theta_m = np.arctan2(prep[leg_kernels.P_W_MID], prep[leg_kernels.P_S_MID])
        cs, sn = np.cos(theta_m), np.sin(theta_m)
        ref = np.arctan2(sn, cs)
        acos = np.arccos(prep[: leg_kernels.P_ACOS_HI + 1])
        turned = np.empty((4, n))
        leg_kernels.reach_turn(prep, cs, sn, turned)
        corners = np.empty((4, n))
        # (uw, us): lo lo, lo hi, hi lo, hi hi
        for i, (y, x) in enumerate(((2, 0), (2, 1), (3, 0), (3, 1))):
            np.arctan2(turned[y], turned[x], out=corners[i])
        out_lo, out_hi = np.empty((3, n)), np.empty((3, n))
        leg_kernels.reach_finish(fold, cs, sn, ref, corners, turned, acos, out_lo, out_hi)
        return LegReach(
            status=status,
            branches=[Interval(out_lo[0], out_hi[0]), Interval(out_lo[1], out_hi[1])],
            hull=Interval(out_lo[2], out_hi[2]),
            fold_connected=connected,
        )

    def _reach_intervals(self, lo: Array, hi: Array) -> LegReach:
        """:meth:`reach` by :class:`Interval` operations (the reference)."""
        n = lo.shape[0]
        s, d, z = self._plane_boxes(lo, hi)
        t = iv.sqrt(iv.square(s) + iv.square(z))
        g_lo, g_hi = self._g_range(t, iv.square(d))
        out = (g_lo > 1.0) | (g_hi < -1.0)
        positive = t.lo > 0
        regular = positive & (g_lo > -1.0) & (g_hi < 1.0) & ~out
        # folds: poses of the box certainly on both sides of g = 1 (or -1)
        maybe_outer = positive & (g_lo > -1.0) & ~regular & ~out
        maybe_inner = positive & (g_hi < 1.0) & ~regular & ~out
        below_one = np.zeros(n, dtype=bool)
        above_one = np.zeros(n, dtype=bool)
        below_minus = np.zeros(n, dtype=bool)
        above_minus = np.zeros(n, dtype=bool)
        todo = np.flatnonzero(maybe_outer | maybe_inner)
        if todo.size:
            for point in self._witness_points(lo[todo], hi[todo]):
                p_lo, p_hi, _ = self._g_boxes(point, point)
                below_one[todo] |= p_hi < 1.0
                above_one[todo] |= p_lo > 1.0
                below_minus[todo] |= p_hi < -1.0
                above_minus[todo] |= p_lo > -1.0
        fold_outer = maybe_outer & below_one & above_one
        fold_inner = maybe_inner & above_minus & below_minus
        status = np.full(n, REACH_UNKNOWN, dtype=np.uint8)
        status[fold_outer] = FOLD_OUTER
        status[fold_inner] = FOLD_INNER
        status[regular] = REGULAR
        status[out] = REACH_OUT

        direction = self._direction(s, -z)
        alpha = iv.arccos(Interval(g_lo, g_hi))
        branches = [direction + alpha, direction - alpha]
        # both branches: theta + [-alpha, alpha] about a stretched leg (alpha near 0),
        # theta + [alpha, 2 pi - alpha] about a folded one (alpha near pi)
        two_pi = Interval(np.nextafter(2 * np.pi, 0.0), np.nextafter(2 * np.pi, np.inf))
        about_zero = direction + Interval(-alpha.hi, alpha.hi)
        about_pi = direction + iv.hull(Interval(alpha.lo), two_pi - Interval(alpha.lo))
        hull = Interval(
            np.where(fold_outer, about_zero.lo, np.where(fold_inner, about_pi.lo, -_INF)),
            np.where(fold_outer, about_zero.hi, np.where(fold_inner, about_pi.hi, _INF)),
        )
        fold_connected = np.zeros(n, dtype=bool)
        folds = np.flatnonzero(fold_outer | fold_inner)
        if folds.size:
            axis, _ = self._fold_axes(lo[folds], hi[folds], fold_outer[folds])
            fold_connected[folds] = axis >= 0
        return LegReach(status=status, branches=branches, hull=hull, fold_connected=fold_connected)

    @staticmethod
    def _witness_points(lo: Array, hi: Array) -> list[Array]:
        """The corners and the centre of each box."""
        out = [0.5 * lo + 0.5 * hi]
        for corner in range(8):
            pick = np.array([(corner >> j) & 1 for j in range(3)], dtype=bool)
            out.append(np.where(pick, hi, lo))
        return out

    def _g_gradient(self, lo: Array, hi: Array) -> list[Interval]:
        """Enclosures of ``dg/dx``, ``dg/dy``, ``dg/dz`` over boxes (where ``t > 0``).

        ``dg/ds = s e / (2 la t^3)``, ``dg/dz = z e / (2 la t^3)`` with ``e = t^2 -
        d^2 - la^2 + lb^2``, ``dg/dd = d / (la t)``; ``s`` and ``d`` turn with ``u``.
        """
        _, (ux, uy) = _unit(self.index)
        la = self.arm
        s, d, z = self._plane_boxes(lo, hi)
        t2 = iv.square(s) + iv.square(z)
        t = iv.sqrt(t2)
        c = iv.square(iv.as_interval(la)) - iv.square(iv.as_interval(self.rod))
        with _quiet():
            scale = (t2 - iv.square(d) - c) / (t2 * t * (2.0 * la))
            gs = s * scale
            gd = d / (t * la)
            return [gs * ux - gd * uy, gs * uy + gd * ux, z * scale]

    def _fold_axes(
        self, lo: Array, hi: Array, outer: NDArray[np.bool_]
    ) -> tuple[NDArray[np.intp], NDArray[np.int8]]:
        """For fold boxes (``outer``: about ``g = 1``, else about ``g = -1``): an axis
        along which the leg's reach certifiably joins its fold, and the face.

        With ``G = g`` (outer) or ``-g`` (inner), the reachable poses of the box are
        those with ``G <= 1`` (``|g| < 1`` holds on the other side, and ``t > 0``).
        If ``dG/dx_j > 0`` on the box and every pose of the face at the low end of
        ``x_j`` is reachable, the reachable poses form segments along ``x_j`` from
        that face (convex, wholly reachable): a connected set. A corner of the box
        is certainly unreachable, so the segment through it meets ``G = 1``, where
        the branches meet; they are continuous elsewhere. Every configuration of
        the leg over the box thus joins every other. Returns ``axis`` (-1: none)
        and ``direction`` (+1: the face at the low end, -1: at the high end).
        """
        n = lo.shape[0]
        axis = np.full(n, -1, dtype=np.intp)
        direction = np.zeros(n, dtype=np.int8)
        grads = self._g_gradient(lo, hi)
        for j in range(3):
            g = grads[j]
            finite = np.isfinite(g.lo) & np.isfinite(g.hi)
            rising = finite & np.where(outer, g.lo > 0, g.hi < 0)  # dG/dx_j > 0
            falling = finite & np.where(outer, g.hi < 0, g.lo > 0)
            for sense, mask in ((1, rising), (-1, falling)):
                mask = mask & (axis < 0)
                if not mask.any():
                    continue
                f_lo, f_hi = lo.copy(), hi.copy()
                face = lo[:, j] if sense > 0 else hi[:, j]
                f_lo[:, j] = face
                f_hi[:, j] = face
                g_lo, g_hi, t_lo = self._g_boxes(f_lo, f_hi)
                reachable = (t_lo > 0) & (g_lo > -1.0) & (g_hi < 1.0)
                ok = mask & reachable
                axis[ok] = j
                direction[ok] = sense
        return axis, direction

    def fold_flow(
        self,
        lo: Array,
        hi: Array,
        status: NDArray[np.uint8],
        branch: int,
        velocity: list[Interval],
        cache: dict[str, Any] | None = None,
    ) -> tuple[NDArray[np.bool_], Interval]:
        """Over boxes where the leg may fold (``status`` FOLD_OUTER or FOLD_INNER):
        whether moving a pose at ``velocity`` (one enclosure per pose axis) keeps it
        reachable, and an enclosure of the rate of the joint of ``branch``.

        The pose stays reachable where ``g`` does not grow (outer fold; ``g > -1``
        holds over the box) or does not fall (inner fold). The joint is
        ``theta = atan2(w, s) + sign alpha`` with ``cos alpha = g``: its rate is
        ``(s w' - w s') / t^2 - sign g' / sin alpha``, unbounded at the fold, where
        ``sin alpha`` falls to 0: the enclosure keeps the lower bound ``1 / max sin
        alpha`` of ``1 / sin alpha``. ``cache`` (one per boxes and branch) keeps what
        does not depend on the velocity.

        Compiled (:func:`._delta_leg_kernels.fold_terms_prepare`,
        ``fold_terms_finish`` and ``fold_rate_bounds``), over the boxes where the
        leg may fold only: there the results of :meth:`_fold_flow_intervals`,
        bit for bit; elsewhere ``keeps`` is false (as there) and the rate the
        whole line (the reference's rate there is meaningless).
        """
        boxes = _pose_boxes(lo, hi)
        if boxes is None or len(velocity) != 3:
            return self._fold_flow_intervals(lo, hi, status, branch, velocity, cache)
        n = boxes[0].shape[0]
        parts = [flat_bounds(v, n) for v in velocity]
        if parts[0] is None or parts[1] is None or parts[2] is None:
            return self._fold_flow_intervals(lo, hi, status, branch, velocity, cache)
        codes = np.ascontiguousarray(np.broadcast_to(status, (n,)), dtype=np.uint8)
        kept = None if cache is None else cache.get("fold_compiled")
        if kept is None or not np.array_equal(kept[0], codes):
            folds = np.flatnonzero((codes == FOLD_OUTER) | (codes == FOLD_INNER))
            terms = self._fold_terms_compiled(boxes[0][folds], boxes[1][folds])
            kept = (codes.copy(), folds, terms)
            if cache is not None:
                cache["fold_compiled"] = kept
        _, folds, terms = kept
        v_lo = np.stack([parts[0][0][folds], parts[1][0][folds], parts[2][0][folds]])
        v_hi = np.stack([parts[0][1][folds], parts[1][1][folds], parts[2][1][folds]])
        sub_keeps = np.empty(folds.size, dtype=bool)
        sub_lo, sub_hi = np.empty(folds.size), np.empty(folds.size)
        leg_kernels.fold_rate_bounds(
            terms[0], terms[1], v_lo, v_hi, codes[folds], _CODES, 1.0 if branch == 0 else -1.0,
            self.constants, sub_keeps, sub_lo, sub_hi,
        )  # fmt: skip
        keeps = np.zeros(n, dtype=bool)
        out_lo, out_hi = np.full(n, -_INF), np.full(n, _INF)
        keeps[folds], out_lo[folds], out_hi[folds] = sub_keeps, sub_lo, sub_hi
        return keeps, Interval(out_lo, out_hi)

    def _fold_terms_compiled(self, lo: Array, hi: Array) -> tuple[Array, Array]:
        """The bounds of :meth:`_fold_terms`, (``N_TERMS``, n) each (see
        :func:`._delta_leg_kernels.fold_terms_prepare`)."""
        return fold_terms_bounds(
            leg_kernels.fold_terms_prepare,
            leg_kernels.fold_terms_finish,
            lo,
            hi,
            self.constants,
            leg_kernels.N_TERMS,
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
        terms = kept_in(cache, "fold", lambda: self._fold_terms(lo, hi))
        grads, s, w, t2, inverse = terms
        _, (ux, uy) = _unit(self.index)
        v = velocity
        with _quiet():
            g_rate = grads[0] * v[0] + grads[1] * v[1] + grads[2] * v[2]
            s_rate = v[0] * ux + v[1] * uy
            turning = (s * (-v[2]) - w * s_rate) / t2
            alpha_rate = -(g_rate * inverse)
            rate = turning + alpha_rate if branch == 0 else turning - alpha_rate
        outer = status == FOLD_OUTER
        inner = status == FOLD_INNER
        keeps = (outer & (g_rate.hi <= 0)) | (inner & (g_rate.lo >= 0))
        return keeps, rate

    def _fold_terms(self, lo: Array, hi: Array) -> tuple[Any, ...]:
        """What :meth:`fold_flow` needs of the boxes alone, for every velocity."""
        s, _, z = self._plane_boxes(lo, hi)
        t2 = iv.square(s) + iv.square(z)
        g_lo, g_hi, _ = self._g_boxes(lo, hi)
        sin_max = iv.sin(iv.arccos(Interval(g_lo, g_hi))).hi
        with _quiet():
            low = np.where(sin_max > 0, np.nextafter(1.0 / np.maximum(sin_max, 1e-300), 0.0), 0.0)
        inverse = Interval(low, np.full(lo.shape[0], _INF))
        return self._g_gradient(lo, hi), s, -z, t2, inverse

    # -------------------------------------------------------------- folds
    def _fold_box(self, lo: Array, hi: Array) -> tuple[int, int, bool]:
        """Axis, face and kind (outer) of one fold-connected box."""
        lo2 = np.asarray(lo, dtype=np.float64).reshape(1, 3)
        hi2 = np.asarray(hi, dtype=np.float64).reshape(1, 3)
        reach = self.reach(lo2, hi2)
        if not reach.fold_connected[0]:
            raise ValueError(f"leg {self.joint}: the box is not certified fold-connected")
        outer = bool(reach.status[0] == FOLD_OUTER)
        axis, direction = self._fold_axes(lo2, hi2, np.array([outer]))
        return int(axis[0]), int(direction[0]), outer

    def fold_waypoints(self, lo: Array, hi: Array, status: int) -> tuple[Array, Array]:
        """Not available: the reachable part of a fold box need not be star-shaped;
        plan through :meth:`fold_path`."""
        raise NotImplementedError(
            f"leg {self.joint}: no hub for a fold box; plan through fold_path instead"
        )

    def fold_anchor(self, lo: Array, hi: Array, pose: Array) -> Array:
        """``pose`` moved along the certified axis onto the box's reachable face (see
        :meth:`_fold_axes`): the segment stays reachable, and so does the face."""
        axis, direction, _ = self._fold_box(lo, hi)
        out = np.array(pose, dtype=np.float64, copy=True).reshape(-1)
        out[axis] = np.reshape(lo, -1)[axis] if direction > 0 else np.reshape(hi, -1)[axis]
        return out

    def fold_path(self, lo: Array, hi: Array, pose: Array) -> Array:
        """Reachable poses from ``pose`` to a fold pose of a fold-connected box, shape
        (4, 3): ``pose``, its anchor on the reachable face, the anchor of a corner
        certified unreachable, and the last pose found reachable on the segment
        from there to that corner (where the two branches meet, within rounding).
        """
        lo1 = np.asarray(lo, dtype=np.float64).reshape(-1)
        hi1 = np.asarray(hi, dtype=np.float64).reshape(-1)
        _, _, outer = self._fold_box(lo1, hi1)
        x0 = np.asarray(pose, dtype=np.float64).reshape(-1)
        corners = np.stack(self._witness_points(lo1[None, :], hi1[None, :]))[:, 0, :]
        g_lo, g_hi, _ = self._g_boxes(corners, corners)
        beyond = g_lo > 1.0 if outer else g_hi < -1.0
        target = corners[int(np.flatnonzero(beyond)[0])]
        a0 = self.fold_anchor(lo1, hi1, x0)
        a1 = self.fold_anchor(lo1, hi1, target)
        t_in, t_out = 0.0, 1.0
        for _ in range(60):
            mid = 0.5 * (t_in + t_out)
            point = (a1 + mid * (target - a1))[None, :]
            if np.isfinite(self.angles(point)).all():
                t_in = mid
            else:
                t_out = mid
        return np.stack([x0, a0, a1, a1 + t_in * (target - a1)])


def _cross(a: list[Interval], b: list[Interval]) -> list[Interval]:
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _dot(a: list[Interval], b: list[Interval]) -> Interval:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _minus(a: list[Interval], b: list[Interval]) -> list[Interval]:
    return [x - y for x, y in zip(a, b, strict=True)]


def _no_nan(x: Interval) -> Interval:
    """``x`` with NaN bounds made infinite (none is expected: every term is
    bounded; a NaN bound would say nothing, and compare false)."""
    return Interval(np.where(np.isnan(x.lo), -_INF, x.lo), np.where(np.isnan(x.hi), _INF, x.hi))


class Circumradius:
    """The Delta's condition in the joint space: ``F(q) > 0`` where

    ``F = 4 lb^2 |a x b|^2 - |a|^2 |b|^2 |a - b|^2``, ``a = c_1 - c_3``,
    ``b = c_2 - c_3``,

    ``c_i(theta_i) = E_i - r u_i = (R - r + la cos theta_i) u_i - la sin theta_i
    e_z`` the centres of the spheres the platform's centre lies on. ``|a|^2
    |b|^2 |a - b|^2 / (4 |a x b|^2)`` is the square of their circumradius
    ``rho``: ``F > 0`` iff the centres are not collinear and ``rho < lb``. Then
    the platform's centre is one of two poses, at the height ``sqrt(lb^2 -
    rho^2)`` on either side of the centres' plane, continuous in q, and det A
    (rows ``P - c_i``) is that signed height times ``|a x b|``: not zero. Where
    ``F <= 0`` no pose has det A != 0. So the regions are the components of
    ``{q : F(q) > 0}`` in the box of joint ranges, twice (see
    :mod:`moveability.analysis.joint_space`).

    Examples
    --------
    >>> import numpy as np
    >>> from moveability.intervals import Interval
    >>> f = Circumradius(Delta(10.0, 4.0, 8.0, 15.0))
    >>> q = np.array([[0.3, 0.5, 0.7]])
    >>> value, grad, _ = f.terms(q, q)
    >>> bool(value.lo[0] > 0), len(grad)
    (True, 3)
    """

    def __init__(self, delta: Delta) -> None:
        self.legs = delta.delta_legs
        self.rod = delta.rod
        self.arm = delta.arm
        #: ``F`` must lie above ``lower`` (and below ``upper``: no bound)
        self.lower = Interval(0.0)
        self.upper = Interval(_INF)

    def _centres(self, lo: Array, hi: Array) -> tuple[list[list[Interval]], list[list[Interval]]]:
        """The centres ``c_i`` and their derivatives ``dc_i / dtheta_i`` over boxes."""
        centres, rates = [], []
        for i, leg in enumerate(self.legs):
            angle = Interval(lo[:, i], hi[:, i])
            centres.append(leg.centre_boxes(angle))
            _, (ux, uy) = _unit(i)
            sin_a = iv.sin(angle) * self.arm
            rates.append([-(sin_a * ux), -(sin_a * uy), -(iv.cos(angle) * self.arm)])
        return centres, rates

    def _value(self, c: list[list[Interval]]) -> tuple[Interval, Any]:
        a, b = _minus(c[0], c[2]), _minus(c[1], c[2])
        ab = _minus(a, b)
        n = _cross(a, b)
        big_a, big_b, big_c = _dot(a, a), _dot(b, b), _dot(ab, ab)
        four_lb2 = iv.square(iv.as_interval(self.rod)) * 4.0
        value = four_lb2 * _dot(n, n) - big_a * big_b * big_c
        return value, (a, b, ab, n, big_a, big_b, big_c, four_lb2)

    def terms(
        self, lo: Array, hi: Array, hessian: bool = True
    ) -> tuple[Interval, list[Interval], list[Interval]]:
        """``F`` over boxes of joints (natural and mean-value forms intersected) and
        its gradient; no Hessian (an empty list)."""
        c, dc = self._centres(lo, hi)
        natural, (a, b, ab, n, big_a, big_b, big_c, k) = self._value(c)
        # dF/dtheta_1: a' = c_1', b' = 0, (a - b)' = c_1'
        g1 = (
            k * _dot(n, _cross(dc[0], b)) * 2.0
            - _dot(a, dc[0]) * big_b * big_c * 2.0
            - big_a * big_b * _dot(ab, dc[0]) * 2.0
        )
        # dF/dtheta_2: b' = c_2', (a - b)' = -c_2'
        g2 = (
            k * _dot(n, _cross(a, dc[1])) * 2.0
            - big_a * _dot(b, dc[1]) * big_c * 2.0
            + big_a * big_b * _dot(ab, dc[1]) * 2.0
        )
        # dF/dtheta_3: a' = b' = -c_3', (a - b)' = 0
        turned = [x + y for x, y in zip(_cross(dc[2], b), _cross(a, dc[2]), strict=True)]
        g3 = (
            -(k * _dot(n, turned) * 2.0)
            + _dot(a, dc[2]) * big_b * big_c * 2.0
            + big_a * _dot(b, dc[2]) * big_c * 2.0
        )
        grad = [g1, g2, g3]
        mid = 0.5 * lo + 0.5 * hi
        mean, _ = self._value(self._centres(mid, mid)[0])
        with _quiet():
            for i in range(3):
                mean = mean + grad[i] * (Interval(lo[:, i], hi[:, i]) - mid[:, i])
        good = np.isfinite(mean.lo) & np.isfinite(mean.hi)
        value = Interval(
            np.where(good, np.maximum(natural.lo, mean.lo), natural.lo),
            np.where(good, np.minimum(natural.hi, mean.hi), natural.hi),
        )
        return _no_nan(value), [_no_nan(g) for g in grad], []

    def poses(self, joints: Array) -> NDArray[np.float64]:
        """(m, 2, 3): the platform's centres of the joints (m, 3), on the spheres of
        radius ``lb`` about the centres ``c_i``, on either side of their plane
        (NaN where the spheres do not meet)."""
        c = np.stack(
            [
                np.stack([v.lo for v in leg.centre_boxes(Interval(joints[:, i]))], axis=1)
                for i, leg in enumerate(self.legs)
            ],
            axis=1,
        )
        a, b = c[:, 0] - c[:, 2], c[:, 1] - c[:, 2]
        n = np.cross(a, b)
        n2 = np.sum(n * n, axis=1)
        # the circumcentre of the three centres, from c_3
        aa, bb = np.sum(a * a, axis=1), np.sum(b * b, axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            centre = (
                np.cross(aa[:, None] * b - bb[:, None] * a, n) / (2.0 * n2[:, None])
            )
            rho2 = np.sum(centre * centre, axis=1)
            height = np.sqrt(float(self.rod) ** 2 - rho2) / np.sqrt(n2)
        foot = c[:, 2] + centre
        up = n * height[:, None]
        return np.stack([foot + up, foot - up], axis=1)

    def classify(self, lo: Array, hi: Array) -> NDArray[np.uint8]:
        """IN where ``F > 0`` over the whole box, OUT where ``F <= 0``, else BOUNDARY."""
        from ..hypertree.status import BOUNDARY, IN, OUT

        value, _, _ = self.terms(lo, hi, hessian=False)
        return np.where(value.lo > 0, IN, np.where(value.hi <= 0, OUT, BOUNDARY)).astype(np.uint8)


def _length(name: str, value: object) -> float:
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InvalidParameterError(f"parameters.{name}", "a positive length", value) from None
    if not (np.isfinite(v) and v > 0):
        raise InvalidParameterError(f"parameters.{name}", "a positive length", value)
    return v


class Delta(Mechanism):
    """The Delta robot (translational 3-RUU), actuated at the base.

    Parameters
    ----------
    base_radius, platform_radius : float
        ``R`` and ``r``: the actuated joints at ``R u_i``, the platform joints at
        ``P + r u_i``.
    arm, rod : float
        ``la`` and ``lb``.
    limits : tuple of three JointLimit, optional
        Limits of theta1..3 (default ``[-pi/3, pi/2]`` each).

    Examples
    --------
    >>> import numpy as np
    >>> m = Delta(10.0, 4.0, 8.0, 15.0)
    >>> m.pose_names, m.periodic_axes, m.postures.shape
    (('x', 'y', 'z'), (), (8, 3))
    >>> p = np.array([[0.5, -1.0, -14.0]])
    >>> q = m.joint_angles(p)
    >>> bool(np.allclose(m.constraints(np.repeat(p, 8, axis=0), q[0]), 0.0))
    True
    """

    name = "delta"
    pose_names = ("x", "y", "z")

    def __init__(
        self,
        base_radius: float = 10.0,
        platform_radius: float = 4.0,
        arm: float = 8.0,
        rod: float = 15.0,
        limits: tuple[JointLimit, ...] | None = None,
    ) -> None:
        values = (base_radius, platform_radius, arm, rod)
        lengths = [_length(n, v) for n, v in zip(_PARAMETERS, values, strict=True)]
        self.base_radius, self.platform_radius, self.arm, self.rod = lengths
        if limits is None:
            limits = tuple(JointLimit(-np.pi / 3, np.pi / 2) for _ in range(3))
        if len(limits) != 3 or any(lim.prismatic for lim in limits):
            raise InvalidParameterError("limits", "three revolute joint limits", limits)
        self.limits = tuple(limits)
        self.delta_legs = tuple(
            DeltaLeg(i, self.base_radius, self.platform_radius, self.arm, self.rod, _JOINTS[i])
            for i in range(3)
        )
        self.legs = self.delta_legs
        self.bounds = self._bounds()

    def _bounds(self) -> tuple[Array, Array]:
        """A box holding every pose with a configuration within the limits: the
        platform joint ``P + r u_i`` is within ``lb`` of the elbow, whose
        enclosure over the joint's range is a box."""
        lo = np.full(3, -_INF)
        hi = np.full(3, _INF)
        for i, lim in enumerate(self.limits):
            if lim.periodic:
                cos_t, sin_t = Interval(-1.0, 1.0), Interval(-1.0, 1.0)
            else:
                cos_t, sin_t = iv.cos(Interval(lim.lo, lim.hi)), iv.sin(Interval(lim.lo, lim.hi))
            _, (ux, uy) = _unit(i)
            h = iv.as_interval(self.base_radius) - self.platform_radius + cos_t * self.arm
            centre = [h * ux, h * uy, -(sin_t * self.arm)]
            for axis in range(3):
                lo[axis] = max(lo[axis], float((centre[axis] - self.rod).lo))
                hi[axis] = min(hi[axis], float((centre[axis] + self.rod).hi))
        if not (lo < hi).all():
            raise InvalidParameterError(
                "parameters.rod",
                "a rod long enough for the three legs to meet within the joint limits",
                self.rod,
            )
        scale = max(self.base_radius, self.platform_radius, self.arm, self.rod)
        pad = 1e-3 * (hi - lo) + 8 * np.spacing(scale)
        return (
            np.array([round_down(v) for v in lo - pad]),
            np.array([round_up(v) for v in hi + pad]),
        )

    @cached_property
    def _leg_constants(self) -> Array:
        """The legs as the kernels of :mod:`._delta_kernels` take them (3,
        ``N_CONSTANTS``): their :attr:`DeltaLeg.constants` stacked."""
        out = np.stack([leg.constants for leg in self.delta_legs])
        out.flags.writeable = False
        return out

    def det_a_boxes(
        self, lo: Array, hi: Array, angles: list[Interval], posture: int | None = None
    ) -> Interval:
        """Enclosure of det A over boxes: the rows stacked, intersected with
        ``(P - c_1) . ((c_1 - c_2) x (c_1 - c_3))`` (rows subtracted; ``c_i`` the
        sphere centres, which depend on the joints only: the pose occurs once).

        With the ``posture``, over boxes where every leg is regular (its branch a
        smooth function of the pose over the whole box, ``angles`` its
        enclosure), also the mean-value form along the sheet, ``D(m) + sum_j
        dD/dx_j (x_j - m_j)`` about the centre ``m``: ``dD/dx_j`` is the rate of
        det A along ``e_j`` with the joints at their gradients' rates
        (:meth:`det_a_rate`). It is far narrower on small boxes, where the
        natural form counts the joints' spread several times.

        Compiled (:mod:`._delta_kernels`, with numpy's arccos and arctan2
        between the kernels): the bounds of :meth:`_det_a_boxes_intervals`, bit
        for bit.

        Examples
        --------
        >>> import numpy as np
        >>> m = Delta(10.0, 4.0, 8.0, 15.0)
        >>> lo, hi = np.array([[0.4, -1.1, -14.1]]), np.array([[0.6, -0.9, -13.9]])
        >>> point = np.array([[0.5, -1.0, -14.0]])
        >>> q = m.joint_angles(point)[0]  # (postures, legs)
        >>> angles = [leg.reach(lo, hi).branches[int(b)] for leg, b in zip(m.legs, m.postures[0])]
        >>> det = m.det_a_boxes(lo, hi, angles, posture=0)
        >>> bool(det.lo[0] <= m.det_a(point, q[:1])[0] <= det.hi[0])
        True
        """
        boxes = _pose_boxes(lo, hi)
        if boxes is None or len(angles) != 3:
            return self._det_a_boxes_intervals(lo, hi, angles, posture)
        lo, hi = boxes
        n = lo.shape[0]
        parts = [flat_bounds(a, n) for a in angles]
        if parts[0] is None or parts[1] is None or parts[2] is None:
            return self._det_a_boxes_intervals(lo, hi, angles, posture)
        a_lo = np.stack([parts[0][0], parts[1][0], parts[2][0]])
        a_hi = np.stack([parts[0][1], parts[1][1], parts[2][1]])
        legs = self._leg_constants
        out_lo, out_hi = np.empty(n), np.empty(n)
        trig = np.empty((4, 3, n))
        kernels.det_a_prepare(lo, hi, a_lo, a_hi, legs, out_lo, out_hi, trig)
        if posture is None:
            return Interval(out_lo, out_hi)
        idx, centre_trig = self._centres(lo, hi)
        if idx.size:
            sub_lo, sub_hi = out_lo[idx], out_hi[idx]
            branches = np.asarray(self.postures[posture], dtype=np.int64)
            kernels.mean_value_bounds(
                lo[idx], hi[idx], np.ascontiguousarray(trig[:, :, idx]), branches, centre_trig,
                legs, sub_lo, sub_hi,
            )  # fmt: skip
            out_lo[idx], out_hi[idx] = sub_lo, sub_hi
        return Interval(out_lo, out_hi)

    def det_a_postures(
        self, lo: Array, hi: Array, branch_angles: Sequence[Sequence[Interval | None]]
    ) -> list[Interval]:
        """:meth:`det_a_boxes` of every posture, bit for bit, in two passes over the
        boxes for all the postures: the stacked rows by
        :func:`._delta_kernels.det_a_all` and the mean-value form by
        ``mean_value_all``, each computing what one leg's branch determines once
        for the postures that take it (the same operations on the same operands
        as ``det_a_prepare`` and ``mean_value_bounds`` of each posture)."""
        boxes = _pose_boxes(lo, hi)
        if boxes is None or len(branch_angles) != 3:
            return super().det_a_postures(lo, hi, branch_angles)
        lo, hi = boxes
        n = lo.shape[0]
        a_lo, a_hi = np.empty((2, 3, n)), np.empty((2, 3, n))
        for k in range(3):
            for b in range(2):
                part = None if len(branch_angles[k]) <= b else branch_angles[k][b]
                bounds = None if part is None else flat_bounds(part, n)
                if bounds is None:
                    return super().det_a_postures(lo, hi, branch_angles)
                a_lo[b, k], a_hi[b, k] = bounds
        postures = np.ascontiguousarray(self.postures, dtype=np.int64)
        n_post = postures.shape[0]
        legs = self._leg_constants
        out_lo, out_hi = np.empty((n_post, n)), np.empty((n_post, n))
        kernels.det_a_all(lo, hi, a_lo, a_hi, postures, legs, out_lo, out_hi)
        idx, centre_trig = self._centres(lo, hi)
        if idx.size:
            m = idx.size
            forms_lo, forms_hi = np.empty((n_post, m)), np.empty((n_post, m))
            kernels.mean_value_all(
                lo[idx], hi[idx], np.ascontiguousarray(a_lo[:, :, idx]),
                np.ascontiguousarray(a_hi[:, :, idx]), postures, centre_trig, legs,
                forms_lo, forms_hi,
            )  # fmt: skip
            for p in range(n_post):
                sub_lo, sub_hi = out_lo[p, idx], out_hi[p, idx]
                kernels.intersect_finite(forms_lo[p], forms_hi[p], sub_lo, sub_hi)
                out_lo[p, idx], out_hi[p, idx] = sub_lo, sub_hi
        return [Interval(out_lo[p], out_hi[p]) for p in range(n_post)]

    def _centres(self, lo: Array, hi: Array) -> tuple[NDArray[np.intp], Array]:
        """The boxes where every leg is regular, and the cosines and sines of both
        branches' angles at their centres (2, 4, 3, m: see
        ``_delta_kernels.centre_trig``), for the mean-value form of det A."""
        legs = self._leg_constants
        regular = np.empty(lo.shape[0], dtype=bool)
        kernels.regular_boxes(lo, hi, legs, regular)
        idx = np.flatnonzero(regular)
        blo, bhi = lo[idx], hi[idx]
        m = idx.size
        # the library functions of branch_boxes at the centres, by numpy on
        # contiguous arrays (see the kernels' notes): alpha's arccos, the
        # directions of the centres and of the corners of the turned boxes
        args = np.empty((4, 3, m))
        kernels.centre_args(blo, bhi, legs, args)
        acos = np.arccos(args[:2])
        theta_m = np.arctan2(args[3], args[2])
        cs, sn = np.cos(theta_m), np.sin(theta_m)
        ref = np.arctan2(sn, cs)
        turned = np.empty((4, 3, m))
        kernels.centre_turn(blo, bhi, cs, sn, legs, turned)
        corners = np.empty((4, 3, m))
        # (uw, us): lo lo, lo hi, hi lo, hi hi
        for i, (y, x) in enumerate(((2, 0), (2, 1), (3, 0), (3, 1))):
            np.arctan2(turned[y], turned[x], out=corners[i])
        centre = np.empty((4, 3, m))
        kernels.centre_angles(cs, sn, ref, corners, turned, acos, centre)
        trig = np.empty((2, 4, 3, m))
        kernels.centre_trig(centre, trig)
        return idx, trig

    def _det_a_boxes_intervals(
        self, lo: Array, hi: Array, angles: list[Interval], posture: int | None = None
    ) -> Interval:
        """:meth:`det_a_boxes` by :class:`Interval` operations (the reference)."""
        out = self._det_a_plain(lo, hi, angles)
        if posture is None or not lo.shape[0]:
            return out
        branches = self.postures[posture]
        regular = np.ones(lo.shape[0], dtype=bool)
        for leg in self.delta_legs:
            g_lo, g_hi, t_lo = leg._g_boxes(lo, hi)
            regular &= (t_lo > 0) & (g_lo > -1.0) & (g_hi < 1.0)
        idx = np.flatnonzero(regular)
        if not idx.size:
            return out
        blo, bhi = lo[idx], hi[idx]
        mid = 0.5 * blo + 0.5 * bhi
        box_angles = [Interval(a.lo[idx], a.hi[idx]) for a in angles]
        centre_angles = [
            leg.branch_boxes(mid, mid, int(branches[i])) for i, leg in enumerate(self.delta_legs)
        ]
        with _quiet():
            total = self._det_a_plain(mid, mid, centre_angles)
            gradients = [
                leg.joint_gradient(blo, bhi, int(branches[i]), box_angles[i])
                for i, leg in enumerate(self.delta_legs)
            ]
            known = self.rows_and_partials(blo, bhi, box_angles)
            n = idx.size
            for axis in range(3):
                along = [Interval(np.full(n, float(axis == j))) for j in range(3)]
                rate = self.det_a_rate(
                    blo, bhi, box_angles, along, [g[axis] for g in gradients], known
                )
                assert rate is not None
                total = total + rate * (Interval(blo[:, axis], bhi[:, axis]) - mid[:, axis])
        good = np.isfinite(total.lo) & np.isfinite(total.hi)
        lo_out, hi_out = out.lo.copy(), out.hi.copy()
        lo_out[idx] = np.where(good, np.maximum(out.lo[idx], total.lo), out.lo[idx])
        hi_out[idx] = np.where(good, np.minimum(out.hi[idx], total.hi), out.hi[idx])
        return Interval(lo_out, hi_out)

    def _det_a_plain(self, lo: Array, hi: Array, angles: list[Interval]) -> Interval:
        """det A over boxes and joint enclosures: the natural form and the centres'
        form intersected (see :meth:`det_a_boxes`)."""
        rows = [leg.a_row_boxes(lo, hi, angles[i]) for i, leg in enumerate(self.delta_legs)]
        natural = interval_det(rows)
        c = [leg.centre_boxes(angles[i]) for i, leg in enumerate(self.delta_legs)]
        first = [Interval(lo[:, k], hi[:, k]) - c[0][k] for k in range(3)]
        second = [c[0][k] - c[1][k] for k in range(3)]
        third = [c[0][k] - c[2][k] for k in range(3)]
        alt = interval_det([first, second, third])
        return Interval(np.maximum(natural.lo, alt.lo), np.minimum(natural.hi, alt.hi))

    def to_spec(self) -> dict[str, object]:
        """The spec mapping of this mechanism (see :func:`~.registry.load_spec`)."""
        return {
            "mechanism": self.name,
            "parameters": dict(
                zip(
                    _PARAMETERS,
                    (self.base_radius, self.platform_radius, self.arm, self.rod),
                    strict=True,
                )
            ),
            "limits": {
                j: "unlimited" if lim.periodic else [lim.lo, lim.hi]
                for j, lim in zip(_JOINTS, self.limits, strict=True)
            },
            **self.restrictions.to_spec(),
        }

    def __repr__(self) -> str:
        return (
            f"Delta(base_radius={self.base_radius:g}, platform_radius={self.platform_radius:g}, "
            f"arm={self.arm:g}, rod={self.rod:g}, limits={self.limits})"
        )

    def joint_condition(self) -> Circumradius:
        """The condition whose components in the joint space are the regions (see
        :class:`Circumradius` and :mod:`moveability.analysis.joint_space`)."""
        return Circumradius(self)

    def folds_connected(self, legs: tuple[int, ...], lo: Array, hi: Array) -> NDArray[np.bool_]:
        """Several legs folding in one box: nothing certified."""
        return np.zeros(lo.shape[0], dtype=bool)
