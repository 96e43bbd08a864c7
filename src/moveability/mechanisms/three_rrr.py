"""The planar 3-RRR: three legs of two links from fixed base joints to a platform triangle.

Leg i: an actuated revolute joint at ``A_i``, a proximal link of length
``l1_i`` to the elbow ``C_i = A_i + l1_i (cos q_i, sin q_i)``, a distal link of
length ``l2_i`` to the platform point ``B_i = P + R(phi) b_i``. The pose is
``(x, y, phi)`` with ``phi`` periodic. The constraint of leg i is
``F_i = |B_i - C_i|^2 - l2_i^2``; its two branches (elbow on either side of
``A_i B_i``) give eight postures.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..errors import InvalidParameterError
from ..limits import JointLimit
from ..types import Array
from .base import Mechanism, three_points
from .constraint_leg import ConstraintLeg
from .expressions import cos, sin

__all__ = ["ThreeRRR"]

_JOINTS = ("theta1", "theta2", "theta3")


def _leg(
    joint: str, a: tuple[float, float], b: tuple[float, float], l1: float, l2: float
) -> ConstraintLeg:
    ax, ay = a
    bx, by = b

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

    def closed_form(points: Array) -> Array:
        """``theta +- alpha`` (as in the RR leg)."""
        u, v = target(points[:, 0], points[:, 1], points[:, 2])
        rho = np.hypot(u, v)
        with np.errstate(divide="ignore", invalid="ignore"):
            g = (rho**2 + l1 * l1 - l2 * l2) / (2 * l1 * rho)
            alpha = np.where(np.abs(g) <= 1.0, np.arccos(np.clip(g, -1.0, 1.0)), np.nan)
        theta = np.arctan2(v, u)
        return np.stack([theta + alpha, theta - alpha], axis=1)

    return ConstraintLeg(
        joint,
        f=f,
        df_dq=df_dq,
        d2f_dq2=d2f_dq2,
        df_dx=(df_dx, df_dy, df_dphi),
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
        }

    def __repr__(self) -> str:
        return (
            f"ThreeRRR(base={[list(p) for p in self.base]}, "
            f"platform={[list(p) for p in self.platform]}, proximal={list(self.proximal)}, "
            f"distal={list(self.distal)}, limits={self.limits})"
        )
