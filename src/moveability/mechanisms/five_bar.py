"""The five-bar RR-RRR: two RR legs from A = (0, 0) and B = (L0, 0) meeting at P.

``C = A + L1 (cos t1, sin t1)``, ``D = B + L3 (cos t2, sin t2)``,
``|CP| = L2``, ``|DP| = L4``. Parallel singularities: C, D and P aligned
(``det A = (P - C) x (P - D) = 0``); serial ones: A, C, P or B, D, P aligned.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from .. import intervals as iv
from ..errors import InvalidParameterError
from ..intervals import Interval
from ..limits import JointLimit
from ..types import Array
from . import _rr_kernels as kernels
from .base import Mechanism, interval_det
from .constraints import Linkage, Turning, fixed_point
from .rr_leg import RRLeg, flat_bounds, pose_boxes

__all__ = ["FiveBar"]


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
        #: the legs as :func:`._rr_kernels.det_a_bounds` takes them
        self._leg_constants = np.stack([leg.constants for leg in self.rr_legs])
        if limits is None:
            limits = (JointLimit(0.0, np.pi), JointLimit(0.0, np.pi))
        if len(limits) != 2:
            raise InvalidParameterError("limits", "two joint limits", limits)
        self.limits = tuple(limits)
        # the box holds the intersection of the legs' outer disks; sums are rounded
        # outwards and the pad grows with the lengths, so no reachable pose is lost
        up, down = (
            (lambda v: float(np.nextafter(v, np.inf))),
            (lambda v: float(np.nextafter(v, -np.inf))),
        )
        r1, r2 = up(L1 + L2), up(L3 + L4)
        lo = np.array([down(max(-r1, down(L0 - r2))), -min(r1, r2)], dtype=np.float64)
        hi = np.array([up(min(r1, up(L0 + r2))), min(r1, r2)], dtype=np.float64)
        if not (lo < hi).all():
            raise InvalidParameterError(
                "parameters",
                "lengths for which the two legs can meet (L0 < L1+L2+L3+L4)",
                dict(zip(("L0", "L1", "L2", "L3", "L4"), self.lengths, strict=True)),
            )
        pad = 1e-3 * (hi - lo) + 4 * np.spacing(max(float(L0), r1, r2))
        self.bounds = (lo - pad, hi + pad)

    def to_spec(self) -> dict[str, object]:
        """The spec mapping of this mechanism (see :func:`~.registry.load_spec`)."""
        names = ("L0", "L1", "L2", "L3", "L4")
        return {
            "mechanism": self.name,
            "parameters": dict(zip(names, self.lengths, strict=True)),
            "limits": {
                leg.joint: "unlimited" if lim.periodic else [lim.lo, lim.hi]
                for leg, lim in zip(self.rr_legs, self.limits, strict=True)
            },
            **self.restrictions.to_spec(),
        }

    def __repr__(self) -> str:
        lengths = ", ".join(f"L{i}={v:g}" for i, v in enumerate(self.lengths))
        extra = "" if self.restrictions.empty else f", restrictions={self.restrictions}"
        return f"FiveBar({lengths}, limits={self.limits}{extra})"

    #: the moving links AC, CP, BD, DP; passive angles at P (from CP to DP), C (from
    #: AC to CP) and D (from BD to DP)
    linkage = Linkage(
        links=(("A", "C"), ("C", "P"), ("B", "D"), ("D", "P")),
        passive={
            "P": (("C", "P"), ("D", "P")),
            "C": (("A", "C"), ("C", "P")),
            "D": (("B", "D"), ("D", "P")),
        },
        ends=(("P", ("A", "C"), 0), ("P", ("B", "D"), 1)),
        # det A = (P - D) x (C - D): C is on its side of D-P, D on the other of C-P
        det_sides=(("C", ("D", "P"), 1), ("D", ("C", "P"), -1)),
    )

    def det_a_boxes(
        self, lo: Array, hi: Array, angles: list[Interval], posture: int | None = None
    ) -> Interval:
        """Enclosure of det A over boxes: the rows stacked and, for a known
        posture, intersected with one form per leg in which its branch appears
        as a sign (:func:`branch_det`): sharp where a leg folds, where the
        elbow's angle enclosure is wide but its side is not.

        One compiled pass over the boxes (:func:`._rr_kernels.det_a_bounds`): the
        bounds of :meth:`_det_a_boxes_intervals`, bit for bit.

        Examples
        --------
        >>> import numpy as np
        >>> m = FiveBar()
        >>> lo, hi = np.array([[3.0, 8.5]]), np.array([[3.5, 9.0]])
        >>> point = np.array([[3.2, 8.7]])
        >>> q = m.joint_angles(point)[0]  # (postures, legs)
        >>> angles = [leg.reach(lo, hi).branches[int(b)] for leg, b in zip(m.legs, m.postures[0])]
        >>> det = m.det_a_boxes(lo, hi, angles, posture=0)
        >>> bool(det.lo[0] <= m.det_a(point, q[:1])[0] <= det.hi[0])
        True
        """
        boxes = pose_boxes(lo, hi)
        if boxes is None or len(angles) != 2:
            return self._det_a_boxes_intervals(lo, hi, angles, posture)
        n = boxes[0].shape[0]
        parts = [flat_bounds(a, n) for a in angles]
        if parts[0] is None or parts[1] is None:
            return self._det_a_boxes_intervals(lo, hi, angles, posture)
        angles_lo = np.stack([parts[0][0], parts[1][0]])
        angles_hi = np.stack([parts[0][1], parts[1][1]])
        if posture is None:
            branches = np.full(2, -1, dtype=np.int64)
        else:
            branches = np.asarray(self.postures[posture], dtype=np.int64)
        out_lo, out_hi = np.empty(n), np.empty(n)
        kernels.det_a_bounds(
            *boxes, angles_lo, angles_hi, self._leg_constants, branches, out_lo, out_hi
        )
        return Interval(out_lo, out_hi)

    def det_a_postures(
        self, lo: Array, hi: Array, branch_angles: Sequence[Sequence[Interval | None]]
    ) -> list[Interval]:
        """:meth:`det_a_boxes` of the four postures in one compiled pass
        (:func:`._rr_kernels.det_a_postures`): each elbow once per branch and the
        pose's half of each leg's branch form once, not once per posture; the
        same bounds as :meth:`det_a_boxes` of each posture, bit for bit.

        Examples
        --------
        >>> import numpy as np
        >>> m = FiveBar()
        >>> lo, hi = np.array([[3.0, 8.5]]), np.array([[3.5, 9.0]])
        >>> angles = [list(leg.reach(lo, hi).branches) for leg in m.legs]
        >>> [bool(d.lo[0] < 0 < d.hi[0]) for d in m.det_a_postures(lo, hi, angles)]
        [False, False, False, False]
        """
        boxes = pose_boxes(lo, hi)
        n_boxes = np.shape(lo)[0]
        flat = [
            [None if a is None else flat_bounds(a, n_boxes) for a in leg] for leg in branch_angles
        ]
        if boxes is None or len(flat) != 2 or any(len(f) != 2 or None in f for f in flat):
            return super().det_a_postures(lo, hi, branch_angles)
        n = boxes[0].shape[0]
        angles_lo = np.array([[f[0] for f in leg] for leg in flat])  # type: ignore[index]
        angles_hi = np.array([[f[1] for f in leg] for leg in flat])  # type: ignore[index]
        postures = np.ascontiguousarray(self.postures, dtype=np.int64)
        out_lo, out_hi = np.empty((postures.shape[0], n)), np.empty((postures.shape[0], n))
        kernels.det_a_postures(
            *boxes, angles_lo, angles_hi, self._leg_constants, postures, out_lo, out_hi
        )
        return [Interval(out_lo[p], out_hi[p]) for p in range(postures.shape[0])]

    def _det_a_boxes_intervals(
        self, lo: Array, hi: Array, angles: list[Interval], posture: int | None = None
    ) -> Interval:
        """:meth:`det_a_boxes` by :class:`Interval` operations (the reference)."""
        # the elbows once: the rows P - C, P - D (as each leg's a_row_boxes) and the forms
        knees = [leg._knee_boxes_intervals(angles[i])[0] for i, leg in enumerate(self.rr_legs)]
        pose = [Interval(lo[:, 0], hi[:, 0]), Interval(lo[:, 1], hi[:, 1])]
        out = interval_det([[pose[0] - knee[0], pose[1] - knee[1]] for knee in knees])
        if posture is None:
            return out
        branches = self.postures[posture]
        for leg, other, sign in ((0, 1, 1.0), (1, 0, -1.0)):
            # det A = (P - C) x (P - D) = -(P - D) x (P - C)
            form = branch_det(self.rr_legs[leg], int(branches[leg]), lo, hi, knees[other]) * sign
            with np.errstate(invalid="ignore"):
                lo_, hi_ = np.maximum(out.lo, form.lo), np.minimum(out.hi, form.hi)
                # NaN bounds leave the other enclosure; an empty meet (no
                # configuration) keeps it as well
                keep = np.isnan(lo_) | np.isnan(hi_) | (lo_ > hi_)
            out = Interval(np.where(keep, out.lo, lo_), np.where(keep, out.hi, hi_))
        return out

    def linkage_points(
        self, lo: Array, hi: Array, angles: list[Interval]
    ) -> dict[str, tuple[Interval, Interval]]:
        """A, B (fixed), the elbows C, D over the angle enclosures, and P over the box."""
        n = lo.shape[0]
        points = {"A": fixed_point((0.0, 0.0), n), "B": fixed_point((self.lengths[0], 0.0), n)}
        for name, leg, a in zip(("C", "D"), self.rr_legs, angles, strict=True):
            points[name] = (
                iv.cos(a) * leg.proximal + leg.base[0],
                iv.sin(a) * leg.proximal + leg.base[1],
            )
        points["P"] = (Interval(lo[:, 0], hi[:, 0]), Interval(lo[:, 1], hi[:, 1]))
        return points

    def linkage_velocities(
        self,
        lo: Array,
        hi: Array,
        angles: list[Interval],
        velocity: list[Interval],
        rates: list[Interval],
    ) -> dict[str, tuple[Interval, Interval]]:
        """A and B still, each elbow turning with its joint about its base (``L
        theta' (-sin theta, cos theta)``, kept as a :class:`Turning`: the joint's
        rate is unbounded where the leg may fold), P at the pose's velocity."""
        n = lo.shape[0]
        still = fixed_point((0.0, 0.0), n)
        out = {"A": still, "B": still, "P": (velocity[0], velocity[1])}
        for name, leg, a, rate in zip(("C", "D"), self.rr_legs, angles, rates, strict=True):
            out[name] = Turning(rate, (iv.cos(a) * leg.proximal, iv.sin(a) * leg.proximal))
        return out

    def _crossings(self) -> list[Interval]:
        """Enclosures (x, y intervals, as one Interval of shape (2,)) of the points
        where the two outer circles cross; none when they may not cross."""
        L0 = self.lengths[0]
        r1 = iv.as_interval(self.rr_legs[0].proximal) + self.rr_legs[0].distal
        r2 = iv.as_interval(self.rr_legs[1].proximal) + self.rr_legs[1].distal
        x = (iv.square(r1) - iv.square(r2) + L0 * L0) / (2.0 * L0)
        y2 = iv.square(r1) - iv.square(x)
        if not y2.lo > 0:
            return []
        y = iv.sqrt(y2)
        return [
            Interval(np.array([x.lo, y.lo]), np.array([x.hi, y.hi])),
            Interval(np.array([x.lo, -y.hi]), np.array([x.hi, -y.lo])),
        ]

    def fold_waypoints(
        self, legs: tuple[int, ...], lo: Array, hi: Array, statuses: tuple[int, ...]
    ) -> tuple[Array, Array]:
        if len(legs) == 1:
            return super().fold_waypoints(legs, lo, hi, statuses)
        for crossing in self._crossings():
            if (lo < crossing.lo).all() and (crossing.hi < hi).all():
                point = crossing.mid
                # pull it into both disks by a hair, so both legs reach it
                inward = point - np.array([0.5 * self.lengths[0], 0.0])
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
        for crossing in self._crossings():
            # the box must hold the whole enclosure of the crossing, strictly
            out |= ((lo < crossing.lo) & (crossing.hi < hi)).all(axis=1)
        return out


def branch_det(leg: RRLeg, branch: int, lo: Array, hi: Array, other: list[Interval]) -> Interval:
    """Enclosure of ``(P - C) x (P - Q)`` over boxes of P, for the elbow C of
    ``leg`` on ``branch`` and a point Q in ``other`` (the other leg's elbow).

    With O the leg's base, ``rho = |P - O|^2``, a and b its proximal and distal
    lengths, the elbow is ``C - O = c (P - O) + s k perp(P - O)`` with
    ``c = (rho + a^2 - b^2) / (2 rho)``, ``k = sqrt(4 a^2 rho - (rho + a^2 - b^2)^2)
    / (2 rho) >= 0`` and ``s = +1`` on branch 0 (the elbow turned
    counterclockwise from P - O), ``-1`` on branch 1. Then
    ``(P - C) x w = (1 - c) (P - O) x w + s k (P - O) . w`` for ``w = P - Q``,
    and ``(P - O) x (P - Q) = (Q - O) x (P - O)``: each coefficient depends on
    rho alone, and the fold (k = 0) splits no enclosure.

    Examples
    --------
    >>> import numpy as np
    >>> leg = RRLeg((0.0, 0.0), 8.0, 5.0, "theta1")
    >>> p = np.array([[10.0, 3.0]])
    >>> t = leg.angles(p)[0, 0]
    >>> (u, v), (w, z) = p[0] - leg.elbow(t), p[0] - np.array([4.0, 6.0])
    >>> exact = u * z - v * w
    >>> box = branch_det(leg, 0, p, p, [iv.as_interval(np.array([4.0])),
    ...                                 iv.as_interval(np.array([6.0]))])
    >>> bool(box.lo[0] <= exact <= box.hi[0]) and float(box.hi[0] - box.lo[0]) < 1e-9
    True
    """
    a2, b2 = leg.proximal**2, leg.distal**2
    x = Interval(lo[:, 0], hi[:, 0]) - leg.base[0]
    y = Interval(lo[:, 1], hi[:, 1]) - leg.base[1]
    rho = iv.square(x) + iv.square(y)
    shift = iv.as_interval(a2) - b2
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        one_minus_c = iv.as_interval(0.5) - shift / (rho * 2.0)

        # 4 a^2 rho - (rho + a^2 - b^2)^2 is concave in rho, largest at a^2 + b^2
        def g(r: Interval) -> Interval:
            return r * (4.0 * a2) - iv.square(r + shift)

        ends = iv.hull(g(Interval(rho.lo)), g(Interval(rho.hi)))
        top = g(iv.as_interval(np.full(rho.lo.shape, a2 + b2)))
        inside = (rho.lo <= a2 + b2) & (rho.hi >= a2 + b2)
        g_range = Interval(ends.lo, np.where(inside, np.maximum(ends.hi, top.hi), ends.hi))
        k = iv.sqrt(g_range) / (rho * 2.0)
        qx, qy = other[0] - leg.base[0], other[1] - leg.base[1]
        cross = qx * y - qy * x
        wx = Interval(lo[:, 0], hi[:, 0]) - other[0]
        wy = Interval(lo[:, 1], hi[:, 1]) - other[1]
        dot = x * wx + y * wy
        side = 1.0 if branch == 0 else -1.0
        return one_minus_c * cross + k * dot * side
