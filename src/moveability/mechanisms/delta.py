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
the ranges of ``t`` and ``d^2`` (:meth:`DeltaLeg.reach`). Where that leaves
the leg undecided, the leg's constraint is handed to a
:class:`~moveability.mechanisms.constraint_leg.ConstraintLeg`, which
certifies folds (and their connectivity) by root isolation.

The rows of A are ``P + r u_i - E_i`` (``A t + B theta' = 0`` with ``t = P'``);
B is diagonal, with terms ``la (s_i sin theta_i + z cos theta_i)`` (half
``dF_i/dtheta_i``).

``u_2 = (-1/2, sqrt(3)/2)`` and ``u_3 = (-1/2, -sqrt(3)/2)`` are the exact unit
vectors: enclosures use an enclosure of ``sqrt(3)/2``, points its float.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .. import intervals as iv
from ..errors import InvalidParameterError
from ..intervals import Interval
from ..limits import JointLimit
from ..types import Array
from . import expressions as ex
from .base import (
    REACH_OUT,
    REACH_UNKNOWN,
    REGULAR,
    LegReach,
    Mechanism,
    round_down,
    round_up,
)
from .constraint_leg import ConstraintLeg

__all__ = ["Delta", "DeltaLeg"]

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
    _inner: ConstraintLeg = field(init=False, repr=False)

    n_branches = 2

    def __post_init__(self) -> None:
        object.__setattr__(self, "_inner", self._constraint_leg())

    # ------------------------------------------------------------ helpers
    @property
    def unit(self) -> tuple[float, float]:
        """``u_i`` in floats."""
        return _unit(self.index)[0]

    def _offset(self) -> Interval:
        """``r - R``, enclosed."""
        return iv.as_interval(self.platform_radius) - self.base_radius

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

    def _constraint_leg(self) -> ConstraintLeg:
        """The same constraint written for root isolation (folds)."""
        (fx, fy), (ix, iy) = _unit(self.index)
        la, lb = self.arm, self.rod
        c_float = self.platform_radius - self.base_radius
        c_iv = self._offset()
        lb2_iv = iv.square(iv.as_interval(lb))

        def consts(*values: Any) -> tuple[Any, Any, Any, Any]:
            if ex.is_interval(*values):
                return ix, iy, c_iv, lb2_iv
            return fx, fy, c_float, lb * lb

        def plane(x: Any, y: Any, c: Any, ux: Any, uy: Any) -> tuple[Any, Any]:
            return x * ux + y * uy + c, y * ux - x * uy

        def f(x: Any, y: Any, z: Any, q: Any) -> Any:
            ux, uy, c, lb2 = consts(x, y, z, q)
            s, d = plane(x, y, c, ux, uy)
            return (
                ex.power(s - la * ex.cos(q), 2)
                + ex.power(z + la * ex.sin(q), 2)
                + (ex.power(d, 2) - lb2)
            )

        def df_dq(x: Any, y: Any, z: Any, q: Any) -> Any:
            ux, uy, c, _ = consts(x, y, z, q)
            s, _ = plane(x, y, c, ux, uy)
            return 2.0 * la * (s * ex.sin(q) + z * ex.cos(q))

        def d2f_dq2(x: Any, y: Any, z: Any, q: Any) -> Any:
            ux, uy, c, _ = consts(x, y, z, q)
            s, _ = plane(x, y, c, ux, uy)
            return 2.0 * la * (s * ex.cos(q) - z * ex.sin(q))

        def df_dx(x: Any, y: Any, z: Any, q: Any) -> Any:
            ux, uy, c, _ = consts(x, y, z, q)
            s, d = plane(x, y, c, ux, uy)
            return 2.0 * ((s - la * ex.cos(q)) * ux - d * uy)

        def df_dy(x: Any, y: Any, z: Any, q: Any) -> Any:
            ux, uy, c, _ = consts(x, y, z, q)
            s, d = plane(x, y, c, ux, uy)
            return 2.0 * ((s - la * ex.cos(q)) * uy + d * ux)

        def df_dz(x: Any, y: Any, z: Any, q: Any) -> Any:
            return 2.0 * (z + la * ex.sin(q))

        return ConstraintLeg(
            self.joint,
            f=f,
            df_dq=df_dq,
            d2f_dq2=d2f_dq2,
            df_dx=(df_dx, df_dy, df_dz),
            closed_form=lambda points: self.angles(points),
        )

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

    def reach(self, lo: Array, hi: Array) -> LegReach:
        """Reachability and angle enclosures of the leg over boxes ``[lo, hi]`` (n, 3).

        REGULAR and REACH_OUT from the range of ``g`` (see the module's notes);
        the other boxes are handed to the root isolation of the same constraint,
        which certifies folds.
        """
        n = lo.shape[0]
        s, d, z = self._plane_boxes(lo, hi)
        t = iv.sqrt(iv.square(s) + iv.square(z))
        g_lo, g_hi = self._g_range(t, iv.square(d))
        out = (g_lo > 1.0) | (g_hi < -1.0)
        regular = (t.lo > 0) & (g_lo > -1.0) & (g_hi < 1.0) & ~out
        status = np.full(n, REACH_UNKNOWN, dtype=np.uint8)
        status[regular] = REGULAR
        status[out] = REACH_OUT
        direction = self._direction(s, -z)
        alpha = iv.arccos(Interval(g_lo, g_hi))
        branches = [direction + alpha, direction - alpha]
        hull = Interval(np.full(n, -_INF), np.full(n, _INF))
        fold_connected = np.zeros(n, dtype=bool)
        rest = np.flatnonzero(status == REACH_UNKNOWN)
        if rest.size:
            inner = self._inner.reach(lo[rest], hi[rest])
            status[rest] = inner.status
            fold_connected[rest] = inner.fold_connected
            for mine, theirs in zip(branches, inner.branches, strict=True):
                mine.lo[rest] = theirs.lo
                mine.hi[rest] = theirs.hi
            hull.lo[rest] = inner.hull.lo
            hull.hi[rest] = inner.hull.hi
            unknown = status == REACH_UNKNOWN
            hull.lo[unknown] = -_INF
            hull.hi[unknown] = _INF
        return LegReach(status=status, branches=branches, hull=hull, fold_connected=fold_connected)

    # -------------------------------------------------------------- folds
    def fold_waypoints(self, lo: Array, hi: Array, status: int) -> tuple[Array, Array]:
        """Not available: plan through :meth:`fold_path`."""
        return self._inner.fold_waypoints(lo, hi, status)

    def fold_path(self, lo: Array, hi: Array, pose: Array) -> Array:
        """Poses from ``pose`` to a fold pose of a fold-connected box (see
        :meth:`ConstraintLeg.fold_path`)."""
        return self._inner.fold_path(lo, hi, pose)

    def fold_anchor(self, lo: Array, hi: Array, pose: Array) -> Array:
        """``pose`` moved onto the box's reachable face (see
        :meth:`ConstraintLeg.fold_anchor`)."""
        return self._inner.fold_anchor(lo, hi, pose)


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

    def folds_connected(self, legs: tuple[int, ...], lo: Array, hi: Array) -> NDArray[np.bool_]:
        """Several legs folding in one box: nothing certified."""
        return np.zeros(lo.shape[0], dtype=bool)
