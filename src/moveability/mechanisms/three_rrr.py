"""The planar 3-RRR: three legs of two links from fixed base joints to a platform triangle.

Leg i: an actuated revolute joint at ``A_i``, a proximal link of length
``l1_i`` to the elbow ``C_i = A_i + l1_i (cos q_i, sin q_i)``, a distal link of
length ``l2_i`` to the platform point ``B_i = P + R(phi) b_i``. The pose is
``(x, y, phi)`` with ``phi`` periodic. The constraint of leg i is
``F_i = |B_i - C_i|^2 - l2_i^2``; its two branches (elbow on either side of
``A_i B_i``) give eight postures.

The linkage (for ``[passive_limits]``, ``[[obstacles]]`` and ``[collisions]``,
see :mod:`moveability.mechanisms.constraints`) names the base joints ``A1``..
``A3``, the elbows ``C1``..``C3`` and the platform joints ``B1``..``B3``. Its
links are each leg's proximal link ``A_i C_i`` and distal link ``C_i B_i`` and
the platform's sides ``B1 B2``, ``B2 B3``, ``B3 B1``. The passive joints are

``C_i``
    the elbow angle: from the proximal link ``A_i -> C_i`` to the distal link
    ``C_i -> B_i``;
``B_i``
    the platform joint angle: from the distal link ``C_i -> B_i`` to the
    platform side ``B_i -> B_{i+1}`` (``B4`` is ``B1``).

Branch 0 of a leg (``dF_i/dq_i > 0``) puts ``B_i`` on the right of the line
``A_i C_i`` (``(C_i - A_i) x (B_i - A_i) = -dF_i/dq_i / 2 < 0``), branch 1 on
the left: the sides :attr:`Linkage.ends` declares.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .. import intervals as iv
from ..errors import InvalidParameterError
from ..intervals import Interval
from ..limits import JointLimit
from ..types import Array
from . import tape as tp
from .base import Mechanism, three_points
from .constraint_leg import ConstraintLeg, Function
from .constraints import Linkage, fixed_point
from .expressions import cos, sin
from .platform import platform_points, platform_sides, platform_velocities

__all__ = ["ThreeRRR"]

_JOINTS = ("theta1", "theta2", "theta3")
_THREE = ("1", "2", "3")


class _Taped:
    """A leg function evaluated as written (floats or Intervals), with
    :attr:`tape`: the same function traced once (:mod:`moveability.mechanisms.tape`),
    which :class:`ConstraintLeg` runs over many boxes in one compiled loop with the
    bounds of the interpreted path."""

    def __init__(self, make: Callable[[Any, Any], Function], k: int = 3) -> None:
        self._plain = make(cos, sin)
        self._traceable = make(_TRACED_COS, _TRACED_SIN)
        self._tape: tp.Tape | None = None
        self._k = k
        self.__doc__ = self._plain.__doc__

    def __call__(self, *args: Any) -> Any:
        return self._plain(*args)

    @property
    def tape(self) -> tp.Tape:
        """The traced tape (built on first use)."""
        if self._tape is None:
            self._tape = tp.trace(self._traceable, self._k)
        return self._tape

    @property
    def float_tape(self) -> tp.Tape:
        """The operations the function performs on float arrays, in order: those of
        :attr:`tape` (the same Python code; its constants are Python floats, operated
        on as floats in both, and ``** 2`` of a float array is its square)."""
        return self.tape


_TRACED_COS, _TRACED_SIN = tp.traced(cos, "cos"), tp.traced(sin, "sin")


def _leg(
    joint: str, a: tuple[float, float], b: tuple[float, float], l1: float, l2: float
) -> ConstraintLeg:
    ax, ay = a
    bx, by = b

    def functions(cos: Any, sin: Any) -> dict[str, Function]:
        """The leg's constraint and its derivatives, on the given sine and cosine."""

        def target(x: Any, y: Any, phi: Any) -> tuple[Any, Any]:
            """``B_i - A_i``."""
            c, s = cos(phi), sin(phi)
            return x + c * bx - s * by - ax, y + s * bx + c * by - ay

        def f(x: Any, y: Any, phi: Any, q: Any) -> Any:
            u, v = target(x, y, phi)
            return (u - l1 * cos(q)) ** 2 + (v - l1 * sin(q)) ** 2 - l2 * l2

        def df_dq(x: Any, y: Any, phi: Any, q: Any) -> Any:
            u, v = target(x, y, phi)
            return 2 * l1 * (u * sin(q) - v * cos(q))

        def d2f_dq2(x: Any, y: Any, phi: Any, q: Any) -> Any:
            u, v = target(x, y, phi)
            return 2 * l1 * (u * cos(q) + v * sin(q))

        def df_dx(x: Any, y: Any, phi: Any, q: Any) -> Any:
            u, _ = target(x, y, phi)
            return 2 * (u - l1 * cos(q))

        def df_dy(x: Any, y: Any, phi: Any, q: Any) -> Any:
            _, v = target(x, y, phi)
            return 2 * (v - l1 * sin(q))

        def df_dphi(x: Any, y: Any, phi: Any, q: Any) -> Any:
            u, v = target(x, y, phi)
            c, s = cos(phi), sin(phi)
            du = -(s * bx) - c * by
            dv = c * bx - s * by
            return 2 * ((u - l1 * cos(q)) * du + (v - l1 * sin(q)) * dv)

        return {
            "f": f,
            "df_dq": df_dq,
            "d2f_dq2": d2f_dq2,
            "df_dx": df_dx,
            "df_dy": df_dy,
            "df_dphi": df_dphi,
        }

    def taped(name: str) -> _Taped:
        return _Taped(lambda cos, sin: functions(cos, sin)[name])

    def closed_form(points: Array) -> Array:
        """``theta +- alpha`` (as in the RR leg)."""
        u = points[:, 0] + np.cos(points[:, 2]) * bx - np.sin(points[:, 2]) * by - ax
        v = points[:, 1] + np.sin(points[:, 2]) * bx + np.cos(points[:, 2]) * by - ay
        rho = np.hypot(u, v)
        with np.errstate(divide="ignore", invalid="ignore"):
            g = (rho**2 + l1 * l1 - l2 * l2) / (2 * l1 * rho)
            alpha = np.where(np.abs(g) <= 1.0, np.arccos(np.clip(g, -1.0, 1.0)), np.nan)
        theta = np.arctan2(v, u)
        return np.stack([theta + alpha, theta - alpha], axis=1)

    return ConstraintLeg(
        joint,
        f=taped("f"),
        df_dq=taped("df_dq"),
        d2f_dq2=taped("d2f_dq2"),
        df_dx=(taped("df_dx"), taped("df_dy"), taped("df_dphi")),
        closed_form=closed_form,
    )


class ThreeRRR(Mechanism):
    """The planar 3-RRR with actuated base joints.

    Parameters
    ----------
    base : sequence of 3 (x, y)
        Base joints ``A_i``.
    platform : sequence of 3 (x, y)
        Platform points ``b_i`` in the platform frame (origin at P).
    proximal, distal : sequence of 3 float
        Link lengths ``l1_i`` and ``l2_i``.
    limits : sequence of 3 JointLimit, optional
        Limits of theta1..3 (default unlimited).
    bounds : ((x_lo, y_lo), (x_hi, y_hi)), optional
        Range of the platform's position; by default the box holding every
        position for which each platform point is within reach of its base.

    Examples
    --------
    >>> import numpy as np
    >>> m = ThreeRRR.default()
    >>> m.pose_names, m.periodic_axes, m.postures.shape
    (('x', 'y', 'phi'), (2,), (8, 3))
    >>> q = m.joint_angles(np.array([[0.0, 0.0, 0.3]]))
    >>> bool(np.allclose(m.constraints(np.repeat([[0.0, 0.0, 0.3]], 8, axis=0), q[0]), 0.0))
    True
    """

    name = "3-RRR"
    pose_names = ("x", "y", "phi")
    periodic_axes = (2,)

    #: the links A_i C_i, C_i B_i and the platform's sides; passive angles at the
    #: elbows C_i (from A_i C_i to C_i B_i) and the platform joints B_i (from
    #: C_i B_i to B_i B_{i+1}); B_i on its branch's side of A_i C_i (see the module)
    linkage = Linkage(
        links=(
            *((f"A{i}", f"C{i}") for i in _THREE),
            *((f"C{i}", f"B{i}") for i in _THREE),
            *platform_sides(),
        ),
        passive={
            **{f"C{i}": ((f"A{i}", f"C{i}"), (f"C{i}", f"B{i}")) for i in _THREE},
            **{
                f"B{i}": ((f"C{i}", f"B{i}"), side)
                for i, side in zip(_THREE, platform_sides(), strict=True)
            },
        },
        ends=tuple((f"B{i}", (f"A{i}", f"C{i}"), int(i) - 1) for i in _THREE),
    )

    def __init__(
        self,
        base: Sequence[Sequence[float]],
        platform: Sequence[Sequence[float]],
        proximal: Sequence[float],
        distal: Sequence[float],
        limits: Sequence[JointLimit] | None = None,
        bounds: tuple[Sequence[float], Sequence[float]] | None = None,
    ) -> None:
        def lengths(value: Any, key: str) -> tuple[float, ...]:
            try:
                arr = np.asarray(value, dtype=np.float64)
            except (TypeError, ValueError):
                raise InvalidParameterError(key, "three positive lengths", value) from None
            if arr.shape != (3,) or not (np.isfinite(arr) & (arr > 0)).all():
                raise InvalidParameterError(key, "three positive lengths", value)
            return tuple(float(v) for v in arr)

        self.base = three_points(base, "parameters.base")
        self.platform = three_points(platform, "parameters.platform")
        self.proximal = lengths(proximal, "parameters.proximal")
        self.distal = lengths(distal, "parameters.distal")
        if limits is None:
            limits = tuple(JointLimit.unlimited() for _ in range(3))
        if len(limits) != 3:
            raise InvalidParameterError("limits", "three joint limits", limits)
        self.limits = tuple(limits)
        self.legs = tuple(
            _leg(_JOINTS[i], self.base[i], self.platform[i], self.proximal[i], self.distal[i])
            for i in range(3)
        )
        if bounds is None:
            # |P + R b_i - A_i| <= l1 + l2: P within l1 + l2 + |b_i| of A_i, for every i
            reach = [
                self.proximal[i] + self.distal[i] + float(np.hypot(*self.platform[i]))
                for i in range(3)
            ]
            a = np.asarray(self.base)
            r = np.asarray(reach)
            lo_xy = (a - r[:, None]).max(axis=0)
            hi_xy = (a + r[:, None]).min(axis=0)
            if not (lo_xy < hi_xy).all():
                raise InvalidParameterError(
                    "parameters", "a design whose three legs can meet", self.to_spec()
                )
            pad = 1e-3 * (hi_xy - lo_xy) + 1e-9 * (1.0 + np.abs(a).max() + r.max())
            lo_xy, hi_xy = lo_xy - pad, hi_xy + pad
        else:
            lo_xy = np.asarray(bounds[0], dtype=np.float64)
            hi_xy = np.asarray(bounds[1], dtype=np.float64)
            # the user's box: it may cut the workspace, so the analysis keeps it
            self.bounds_hold_workspace = False
        self.bounds = (
            np.array([lo_xy[0], lo_xy[1], -np.pi]),
            np.array([hi_xy[0], hi_xy[1], np.pi]),
        )

    @classmethod
    def default(cls, limits: Sequence[JointLimit] | None = None) -> ThreeRRR:
        """The example design: base circumradius 10 (joints at 90, 210, 330 degrees),
        platform circumradius 3, proximal links 7 and distal links 5 (unequal: with
        equal links a leg reaches its base joint with every angle)."""
        angles = np.deg2rad([90.0, 210.0, 330.0])
        base = [(10 * np.cos(t), 10 * np.sin(t)) for t in angles]
        platform = [(3 * np.cos(t), 3 * np.sin(t)) for t in angles]
        return cls(base, platform, (7.0, 7.0, 7.0), (5.0, 5.0, 5.0), limits)

    def to_spec(self) -> dict[str, Any]:
        """The spec mapping of this mechanism (JSON-ready)."""
        return {
            "mechanism": self.name,
            "parameters": {
                "base": [list(p) for p in self.base],
                "platform": [list(p) for p in self.platform],
                "proximal": list(self.proximal),
                "distal": list(self.distal),
            },
            "limits": {
                j: "unlimited" if lim.periodic else [lim.lo, lim.hi]
                for j, lim in zip(_JOINTS, self.limits, strict=True)
            },
            **self.restrictions.to_spec(),
        }

    def __repr__(self) -> str:
        extra = "" if self.restrictions.empty else f", restrictions={self.restrictions}"
        return (
            f"ThreeRRR(base={[list(p) for p in self.base]}, "
            f"platform={[list(p) for p in self.platform]}, proximal={list(self.proximal)}, "
            f"distal={list(self.distal)}, limits={self.limits}{extra})"
        )

    def linkage_points(
        self, lo: Array, hi: Array, angles: list[Interval]
    ) -> dict[str, tuple[Interval, Interval]]:
        """The base joints A_i (fixed), the elbows ``C_i = A_i + l1_i (cos q_i, sin q_i)``
        over the joint enclosures, and the platform joints ``B_i = P + R(phi) b_i``
        over the boxes of poses."""
        n = lo.shape[0]
        points, _ = platform_points(lo, hi, self.platform)
        for i, (a, q) in enumerate(zip(self.base, angles, strict=True)):
            points[f"A{i + 1}"] = fixed_point(a, n)
            points[f"C{i + 1}"] = (
                iv.cos(q) * self.proximal[i] + a[0],
                iv.sin(q) * self.proximal[i] + a[1],
            )
        return points

    def linkage_velocities(
        self,
        lo: Array,
        hi: Array,
        angles: list[Interval],
        velocity: list[Interval],
        rates: list[Interval],
    ) -> dict[str, tuple[Interval, Interval]]:
        """A_i still, each elbow turning with its joint about its base (``l1_i q_i'
        (-sin q_i, cos q_i)``), each platform joint moving with the pose
        (``P' + phi' (-(R b_i)_y, (R b_i)_x)``)."""
        n = lo.shape[0]
        _, turned = platform_points(lo, hi, self.platform)
        out = platform_velocities(turned, velocity)
        still = fixed_point((0.0, 0.0), n)
        for i, (q, rate) in enumerate(zip(angles, rates, strict=True)):
            speed = rate * self.proximal[i]
            out[f"A{i + 1}"] = still
            out[f"C{i + 1}"] = (-(iv.sin(q) * speed), iv.cos(q) * speed)
        return out
