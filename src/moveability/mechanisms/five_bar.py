"""The five-bar RR-RRR: two RR legs from A = (0, 0) and B = (L0, 0) meeting at P.

``C = A + L1 (cos t1, sin t1)``, ``D = B + L3 (cos t2, sin t2)``,
``|CP| = L2``, ``|DP| = L4``. Parallel singularities: C, D and P aligned
(``det A = (P - C) x (P - D) = 0``); serial ones: A, C, P or B, D, P aligned.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError
from ..limits import JointLimit
from .base import Mechanism
from .rr_leg import RRLeg

__all__ = ["FiveBar"]

Array = NDArray[np.float64]


class FiveBar(Mechanism):
    """The planar five-bar RR-RRR.

    Parameters
    ----------
    L0, L1, L2, L3, L4 : float
        Base length, then proximal and distal lengths of the legs at A and B.
    limits : tuple of JointLimit
        Limits of theta1 and theta2.

    Examples
    --------
    >>> import numpy as np
    >>> from moveability.limits import JointLimit
    >>> m = FiveBar(7, 8, 5, 8, 5, (JointLimit(0, np.pi), JointLimit(0, np.pi)))
    >>> q = m.joint_angles(np.array([[3.5, 9.0]]))  # (points, postures, joints)
    >>> q.shape
    (1, 4, 2)
    >>> bool(np.allclose(m.constraints(np.array([[3.5, 9.0]] * 4), q[0]), 0.0))
    True
    """

    name = "five-bar"
    pose_names = ("x", "y")

    def __init__(
        self,
        L0: float = 7.0,
        L1: float = 8.0,
        L2: float = 5.0,
        L3: float = 8.0,
        L4: float = 5.0,
        limits: tuple[JointLimit, JointLimit] | None = None,
    ) -> None:
        for name, value in zip(("L0", "L1", "L2", "L3", "L4"), (L0, L1, L2, L3, L4), strict=True):
            if not (np.isfinite(value) and value > 0):
                raise InvalidParameterError(f"parameters.{name}", "a positive length", value)
        self.lengths = tuple(float(v) for v in (L0, L1, L2, L3, L4))
        self.rr_legs = (
            RRLeg((0.0, 0.0), float(L1), float(L2), "theta1"),
            RRLeg((float(L0), 0.0), float(L3), float(L4), "theta2"),
        )
        self.legs = self.rr_legs
        if limits is None:
            limits = (JointLimit(0.0, np.pi), JointLimit(0.0, np.pi))
        if len(limits) != 2:
            raise InvalidParameterError("limits", "two joint limits", limits)
        self.limits = tuple(limits)
        r1, r2 = L1 + L2, L3 + L4
        lo = np.array([max(-r1, L0 - r2), -min(r1, r2)], dtype=np.float64)
        hi = np.array([min(r1, L0 + r2), min(r1, r2)], dtype=np.float64)
        if not (lo < hi).all():
            raise InvalidParameterError(
                "parameters",
                "lengths for which the two legs can meet (L0 < L1+L2+L3+L4)",
                dict(zip(("L0", "L1", "L2", "L3", "L4"), self.lengths, strict=True)),
            )
        pad = 1e-3 * (hi - lo)
        self.bounds = (lo - pad, hi + pad)

    def to_spec(self) -> dict[str, object]:
        """The spec mapping of this mechanism (see :func:`moveability.spec.load_spec`)."""
        names = ("L0", "L1", "L2", "L3", "L4")
        return {
            "mechanism": self.name,
            "parameters": dict(zip(names, self.lengths, strict=True)),
            "limits": {
                leg.joint: "unlimited" if lim.periodic else [lim.lo, lim.hi]
                for leg, lim in zip(self.rr_legs, self.limits, strict=True)
            },
        }

    def __repr__(self) -> str:
        lengths = ", ".join(f"L{i}={v:g}" for i, v in enumerate(self.lengths))
        return f"FiveBar({lengths}, limits={self.limits})"

    def _crossings(self) -> list[Array]:
        """The points where the two outer circles cross."""
        L0 = self.lengths[0]
        r1 = self.rr_legs[0].proximal + self.rr_legs[0].distal
        r2 = self.rr_legs[1].proximal + self.rr_legs[1].distal
        x = (r1 * r1 - r2 * r2 + L0 * L0) / (2 * L0)
        if r1 * r1 - x * x <= 0:
            return []
        y = float(np.sqrt(r1 * r1 - x * x))
        return [np.array([x, y]), np.array([x, -y])]

    def fold_waypoints(
        self, legs: tuple[int, ...], lo: Array, hi: Array, statuses: tuple[int, ...]
    ) -> tuple[Array, Array]:
        if len(legs) == 1:
            return super().fold_waypoints(legs, lo, hi, statuses)
        for point in self._crossings():
            if (lo <= point).all() and (point <= hi).all():
                # pull it into both disks by a hair, so both legs reach it
                inward = point - 0.5 * (np.array([0.0, 0.0]) + np.array([self.lengths[0], 0.0]))
                inner = point - 1e-11 * inward / np.linalg.norm(inward)
                return inner, inner
        raise ValueError("the box holds no crossing of the outer circles")

    def folds_connected(self, legs: tuple[int, ...], lo: Array, hi: Array) -> NDArray[np.bool_]:
        """Both legs stretched in one box: certified where the box holds a crossing
        point of the two outer circles (all four postures meet there, and the
        reachable part of the box, a box cut by two disks, is convex)."""
        out = np.zeros(lo.shape[0], dtype=bool)
        if tuple(sorted(legs)) != (0, 1):
            return out
        L0 = self.lengths[0]
        r1 = self.rr_legs[0].proximal + self.rr_legs[0].distal
        r2 = self.rr_legs[1].proximal + self.rr_legs[1].distal
        x = (r1 * r1 - r2 * r2 + L0 * L0) / (2 * L0)
        if r1 * r1 - x * x <= 0:
            return out
        y = np.sqrt(r1 * r1 - x * x)
        margin = 1e-9 * max(r1, r2, L0)
        for yy in (y, -y):
            out |= (
                (lo[:, 0] + margin < x)
                & (x < hi[:, 0] - margin)
                & (lo[:, 1] + margin < yy)
                & (yy < hi[:, 1] - margin)
            )
        return out
