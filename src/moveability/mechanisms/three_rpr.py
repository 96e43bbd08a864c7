"""The planar 3-RPR: three legs from base joints A_i to platform points B_i.

The pose is ``(x, y, phi)``: the platform frame's origin P and its orientation.
In that frame the platform points are ``b_i``, so ``B_i = P + R(phi) b_i``. Each
leg's prismatic actuator measures ``rho_i = |B_i - A_i|``: one inverse-kinematic
solution, hence one posture. The constraint is
``F_i = |B_i - A_i|^2 - rho_i^2``; half its pose gradient is the row of A,

``(d_x, d_y, (R b_i) x (P - A_i))`` with ``d = B_i - A_i``,

and half its joint derivative, ``-rho_i``, is the leg's term of B (a serial
singularity only where a leg has zero length). ``phi`` turns freely: the third
pose axis is periodic, over ``[-pi, pi]``.

The linkage (for ``[passive_limits]``, ``[[obstacles]]`` and ``[collisions]``,
see :mod:`moveability.mechanisms.constraints`) names the base joints ``A1``..
``A3`` and the platform joints ``B1``..``B3``. Its links are the legs
``A_i B_i`` and the platform's sides ``B1 B2``, ``B2 B3``, ``B3 B1``. Both
revolute joints of a leg are passive:

``A_i``
    the base joint angle: from the base side ``A_i -> A_{i+1}`` (``A4`` is
    ``A1``) to the leg ``A_i -> B_i``;
``B_i``
    the platform joint angle: from the leg ``A_i -> B_i`` to the platform side
    ``B_i -> B_{i+1}`` (``B4`` is ``B1``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .. import intervals as iv
from ..errors import InvalidParameterError
from ..intervals import Interval
from ..limits import JointLimit
from ..types import Array
from . import _rpr_kernels as kernels
from .base import (
    REACH_UNKNOWN,
    REGULAR,
    LegReach,
    Mechanism,
    interval_det,
    round_down,
    round_up,
    three_points,
)
from .constraints import Linkage, fixed_point
from .platform import platform_points, platform_sides, platform_velocities

__all__ = ["RPRLeg", "ThreeRPR"]

_THREE = ("1", "2", "3")
#: each joint's index and the next one's, cyclically
_NEXT = (("1", "2"), ("2", "3"), ("3", "1"))


def _trig(lo: Array, hi: Array) -> tuple[Interval, Interval]:
    """Enclosures of the cosine and sine of phi over boxes of poses."""
    phi = Interval(lo[:, 2], hi[:, 2])
    return iv.cos(phi), iv.sin(phi)


def _pose_boxes(lo: Array, hi: Array) -> tuple[Array, Array, Array] | None:
    """The boxes as the compiled kernels take them: (n, 3) contiguous float arrays
    (the first three columns) and :data:`._rpr_kernels.NO_TRIG` (the kernels
    compute the bounds of the cosine and sine of phi box by box); None when they
    are not (n, k >= 3) arrays."""
    lo_a = np.asarray(lo, dtype=np.float64)
    hi_a = np.asarray(hi, dtype=np.float64)
    if lo_a.ndim != 2 or lo_a.shape[1] < 3 or hi_a.shape != lo_a.shape:
        return None
    lo_a, hi_a = np.ascontiguousarray(lo_a[:, :3]), np.ascontiguousarray(hi_a[:, :3])
    return lo_a, hi_a, kernels.NO_TRIG


def _length_reach(rho: Interval) -> LegReach:
    """A leg's reach from the enclosure of its length: REGULAR where it certainly
    does not vanish."""
    return LegReach(
        status=np.where(rho.lo > 0, REGULAR, REACH_UNKNOWN).astype(np.uint8),
        branches=[rho],
        hull=rho,
        fold_connected=np.zeros(rho.lo.shape[0], dtype=bool),
    )


def _leg_geometry(base: tuple[float, float], platform: tuple[float, float]) -> Array:
    """A leg as the compiled kernels take it: ``(A_x, A_y, b_x, b_y)``."""
    return np.array([*base, *platform], dtype=np.float64)


@dataclass(frozen=True)
class RPRLeg:
    """A revolute-prismatic-revolute leg from ``base`` to the platform point ``platform``.

    Examples
    --------
    >>> import numpy as np
    >>> leg = RPRLeg((0.0, 0.0), (1.0, 0.0), "rho1")
    >>> leg.angles(np.array([[3.0, 4.0, 0.0]])).round(6).tolist()
    [[5.656854]]
    """

    base: tuple[float, float]
    platform: tuple[float, float]
    joint: str

    n_branches = 1

    # ------------------------------------------------------------- points
    def _target(self, points: Array) -> tuple[Array, Array, Array, Array]:
        """``d = B - A`` and ``R(phi) b`` at poses (x, y, phi)."""
        p = np.asarray(points, dtype=np.float64)
        c, s = np.cos(p[..., 2]), np.sin(p[..., 2])
        bx, by = self.platform
        rbx, rby = c * bx - s * by, s * bx + c * by
        return p[..., 0] + rbx - self.base[0], p[..., 1] + rby - self.base[1], rbx, rby

    def angles(self, points: Array, clip: bool = False) -> Array:
        """The actuator length at each pose, shape (m, 1) (every pose is reachable)."""
        dx, dy, _, _ = self._target(points)
        return np.hypot(dx, dy)[:, None]

    def links(self, pose: Array, length: float) -> Array:
        """The leg drawn as a polyline: base joint, platform joint; shape (2, 2)."""
        dx, dy, _, _ = self._target(np.asarray(pose, dtype=np.float64)[None, :])
        return np.array([list(self.base), [self.base[0] + dx[0], self.base[1] + dy[0]]])

    def constraint(self, points: Array, angles: Array) -> Array:
        """``F = |B - A|^2 - rho^2``."""
        dx, dy, _, _ = self._target(points)
        rho = np.asarray(angles, dtype=np.float64)
        return dx * dx + dy * dy - rho * rho

    def a_row(self, points: Array, angles: Array) -> Array:
        """Half the pose gradient of F, shape (..., 3)."""
        p = np.asarray(points, dtype=np.float64)
        dx, dy, rbx, rby = self._target(p)
        turn = rbx * (p[..., 1] - self.base[1]) - rby * (p[..., 0] - self.base[0])
        return np.stack([dx, dy, turn], axis=-1)

    def serial_term(self, points: Array, angles: Array) -> Array:
        """Half the joint derivative of F: ``-rho``."""
        return -np.asarray(angles, dtype=np.float64)

    # ------------------------------------------------------------- boxes
    def _target_boxes(
        self, lo: Array, hi: Array, trig: tuple[Interval, Interval] | None = None
    ) -> tuple[Interval, Interval, Interval, Interval]:
        c, s = _trig(lo, hi) if trig is None else trig
        bx, by = self.platform
        rbx = c * bx - s * by
        rby = s * bx + c * by
        dx = Interval(lo[:, 0], hi[:, 0]) + rbx - self.base[0]
        dy = Interval(lo[:, 1], hi[:, 1]) + rby - self.base[1]
        return dx, dy, rbx, rby

    def a_row_boxes(
        self,
        lo: Array,
        hi: Array,
        angles: Interval,
        trig: tuple[Interval, Interval] | None = None,
    ) -> list[Interval]:
        """Enclosure of the row of A over boxes of poses (``trig``: the cosine and
        sine of the boxes' phi, when already known)."""
        dx, dy, rbx, rby = self._target_boxes(lo, hi, trig)
        px = Interval(lo[:, 0], hi[:, 0]) - self.base[0]
        py = Interval(lo[:, 1], hi[:, 1]) - self.base[1]
        return [dx, dy, rbx * py - rby * px]

    def a_row_derivatives(
        self, lo: Array, hi: Array, trig: tuple[Interval, Interval] | None = None
    ) -> list[list[Interval]]:
        """Enclosures of the derivatives of the row of A along x, y and phi over boxes."""
        c, s = _trig(lo, hi) if trig is None else trig
        bx, by = self.platform
        rbx = c * bx - s * by
        rby = s * bx + c * by
        px = Interval(lo[:, 0], hi[:, 0]) - self.base[0]
        py = Interval(lo[:, 1], hi[:, 1]) - self.base[1]
        one, zero = iv.as_interval(np.ones(lo.shape[0])), iv.as_interval(np.zeros(lo.shape[0]))
        return [
            [one, zero, -rby],
            [zero, one, rbx],
            [-rby, rbx, -(rbx * px + rby * py)],
        ]

    def row_partials(
        self,
        lo: Array,
        hi: Array,
        angles: Interval,
        trig: tuple[Interval, Interval] | None = None,
    ) -> tuple[list[list[Interval]], list[Interval]]:
        """Partial derivatives of the row of A: along x, y, phi (the row depends on the
        pose alone), and none along the length."""
        zero = iv.as_interval(np.zeros(lo.shape[0]))
        return self.a_row_derivatives(lo, hi, trig), [zero, zero, zero]

    def joint_gradient(self, lo: Array, hi: Array, branch: int, angles: Interval) -> list[Interval]:
        """``drho/dX = row / rho`` (``angles`` encloses rho), in one compiled pass
        (the bounds of :meth:`_joint_gradient_intervals`, bit for bit)."""
        boxes = _pose_boxes(lo, hi)
        n = -1 if boxes is None else boxes[0].shape[0]
        if boxes is None or angles.lo.shape not in ((n,), ()):
            return self._joint_gradient_intervals(lo, hi, branch, angles)
        rho_lo = np.ascontiguousarray(np.broadcast_to(angles.lo, (n,)), dtype=np.float64)
        rho_hi = np.ascontiguousarray(np.broadcast_to(angles.hi, (n,)), dtype=np.float64)
        out_lo, out_hi = np.empty((3, n)), np.empty((3, n))
        kernels.joint_gradient_bounds(
            *boxes, _leg_geometry(self.base, self.platform), rho_lo, rho_hi, out_lo, out_hi
        )
        return [Interval(out_lo[j], out_hi[j]) for j in range(3)]

    def _joint_gradient_intervals(
        self, lo: Array, hi: Array, branch: int, angles: Interval
    ) -> list[Interval]:
        """:meth:`joint_gradient` by :class:`Interval` operations (the reference)."""
        return [r / angles for r in self.a_row_boxes(lo, hi, angles)]

    #: the length's rate along a turn about :meth:`turn_centre`: it stays
    turn_rate = 0.0

    def turn_centre(self, angles: Interval) -> list[Interval]:
        """The point the platform may turn about with the length still: the base
        joint (the pose's x, y turn about it and phi turns at the same rate)."""
        n = angles.lo.shape[0]
        return [iv.as_interval(np.full(n, float(c))) for c in self.base]

    def turn_keeps(self, lo: Array, hi: Array, branch: int, turn: float) -> NDArray[np.bool_]:
        """A turn about the base keeps the (only) branch."""
        return np.ones(lo.shape[0], dtype=bool)

    def reach(self, lo: Array, hi: Array) -> LegReach:
        """Every pose is reachable; REGULAR where the length certainly does not vanish.

        The length's enclosure in one compiled pass (the bounds of
        :meth:`_length_intervals`, bit for bit)."""
        boxes = _pose_boxes(lo, hi)
        if boxes is None:
            rho = self._length_intervals(lo, hi)
        else:
            n = boxes[0].shape[0]
            r_lo, r_hi = np.empty(n), np.empty(n)
            kernels.reach_bounds(*boxes, _leg_geometry(self.base, self.platform), r_lo, r_hi)
            rho = Interval(r_lo, r_hi)
        return _length_reach(rho)

    def _length_intervals(self, lo: Array, hi: Array) -> Interval:
        """The enclosure of the length over boxes by :class:`Interval` operations
        (the reference of :meth:`reach`)."""
        dx, dy, _, _ = self._target_boxes(lo, hi)
        return iv.sqrt(iv.square(dx) + iv.square(dy))

    def fold_waypoints(self, lo: Array, hi: Array, status: int) -> tuple[Array, Array]:
        raise ValueError("an RPR leg has one branch: it never changes posture")


class ThreeRPR(Mechanism):
    """The planar 3-RPR parallel manipulator.

    Parameters
    ----------
    base : (3, 2) array_like
        Base joints A_i.
    platform : (3, 2) array_like
        Platform joints b_i in the platform frame.
    limits : tuple of three JointLimit
        Strokes of rho1..rho3 (prismatic limits).

    Examples
    --------
    >>> from moveability.limits import JointLimit
    >>> stroke = JointLimit(10.0, 25.0, prismatic=True)
    >>> m = ThreeRPR([[0, 0], [15.91, 0], [0, 10]], [[0, 0], [17.04, 0], [13.24, 16.1]],
    ...              (stroke, stroke, stroke))
    >>> m.pose_names, m.periodic_axes, m.postures.shape
    (('x', 'y', 'phi'), (2,), (1, 3))
    """

    name = "3-RPR"
    pose_names = ("x", "y", "phi")
    periodic_axes = (2,)

    #: the legs A_i B_i and the platform's sides; passive angles at the base joints
    #: A_i (from A_i A_{i+1} to A_i B_i) and the platform joints B_i (from A_i B_i
    #: to B_i B_{i+1})
    linkage = Linkage(
        links=(*((f"A{i}", f"B{i}") for i in _THREE), *platform_sides()),
        passive={
            **{f"A{i}": ((f"A{i}", f"A{j}"), (f"A{i}", f"B{i}")) for i, j in _NEXT},
            **{f"B{i}": ((f"A{i}", f"B{i}"), (f"B{i}", f"B{j}")) for i, j in _NEXT},
        },
    )

    def __init__(
        self,
        base: object,
        platform: object,
        limits: tuple[JointLimit, JointLimit, JointLimit],
    ) -> None:
        self.base = three_points(base, "parameters.base")
        self.platform = three_points(platform, "parameters.platform")
        if len(limits) != 3 or not all(lim.prismatic for lim in limits):
            raise InvalidParameterError("limits", "three prismatic strokes", limits)
        for i, lim in enumerate(limits):
            if lim.lo < 0:
                raise InvalidParameterError(
                    f"limits.rho{i + 1}", "a stroke with 0 <= lo", (lim.lo, lim.hi)
                )
        self.limits = tuple(limits)
        self.rpr_legs = tuple(
            RPRLeg(a, b, f"rho{i + 1}")
            for i, (a, b) in enumerate(zip(self.base, self.platform, strict=True))
        )
        self.legs = self.rpr_legs
        # the legs as the compiled kernels take them, one (A_x, A_y, b_x, b_y) a row
        self._leg_geometry = np.stack(
            [_leg_geometry(a, b) for a, b in zip(self.base, self.platform, strict=True)]
        )
        # |P - A_i| <= rho_max_i + |b_i|: the box holds the intersection of those disks
        lo = np.full(2, -np.inf)
        hi = np.full(2, np.inf)
        for a, b, lim in zip(self.base, self.platform, self.limits, strict=True):
            r = round_up(round_up(lim.hi) + round_up(float(np.hypot(*b))))
            lo = np.maximum(lo, [round_down(a[0] - r), round_down(a[1] - r)])
            hi = np.minimum(hi, [round_up(a[0] + r), round_up(a[1] + r)])
        if not (lo < hi).all():
            raise InvalidParameterError(
                "limits", "strokes long enough for the three legs to meet", self._strokes()
            )
        pad = 1e-3 * (hi - lo) + 4 * np.spacing(np.abs(np.concatenate([lo, hi])).max())
        self.bounds = (
            np.array([lo[0] - pad[0], lo[1] - pad[1], -np.pi]),
            np.array([hi[0] + pad[0], hi[1] + pad[1], np.pi]),
        )

    def det_a_boxes(
        self, lo: Array, hi: Array, angles: list[Interval], posture: int | None = None
    ) -> Interval:
        """Enclosure of det A over boxes: the rows depend on the pose only, so the
        mean-value form ``D(c) + sum_j dD/dx_j(box) (x_j - c_j)`` about the centre
        ``c`` encloses it too; the narrower of the two (intersected) is kept.

        One compiled pass over the boxes (:func:`._rpr_kernels.det_a_bounds`): the
        bounds of :meth:`_det_a_boxes_intervals`, bit for bit.

        Examples
        --------
        >>> import numpy as np
        >>> from moveability.limits import JointLimit
        >>> stroke = JointLimit(10.0, 25.0, prismatic=True)
        >>> m = ThreeRPR([[0, 0], [15.91, 0], [0, 10]], [[0, 0], [17.04, 0], [13.24, 16.1]],
        ...              (stroke, stroke, stroke))
        >>> lo, hi = np.array([[5.0, 8.0, 0.2]]), np.array([[5.5, 8.5, 0.25]])
        >>> points = np.array([[5.0, 8.0, 0.2], [5.5, 8.5, 0.25], [5.2, 8.4, 0.22]])
        >>> det = m.det_a_boxes(lo, hi, [])
        >>> exact = m.det_a(points, m.joint_angles(points)[:, 0])
        >>> bool(((det.lo <= exact) & (exact <= det.hi)).all())
        True
        """
        boxes = _pose_boxes(lo, hi)
        if boxes is None:
            return self._det_a_boxes_intervals(lo, hi, angles, posture)
        n = boxes[0].shape[0]
        out_lo, out_hi = np.empty(n), np.empty(n)
        kernels.det_a_bounds(*boxes, self._leg_geometry, out_lo, out_hi)
        return Interval(out_lo, out_hi)

    def reaches_and_det(
        self, lo: Array, hi: Array, *, folds: bool = True
    ) -> tuple[list[LegReach], Interval | None]:
        """The legs' reaches and det A over boxes (det A depends on the pose alone) in
        one compiled pass (:func:`._rpr_kernels.pose_bounds`: the cosine and sine of
        phi once for all): the bounds of :meth:`RPRLeg.reach` and :meth:`det_a_boxes`,
        bit for bit. The legs' folds cost nothing apart: ``folds`` is not used.

        Examples
        --------
        >>> import numpy as np
        >>> from moveability.limits import JointLimit
        >>> stroke = JointLimit(10.0, 25.0, prismatic=True)
        >>> m = ThreeRPR([[0, 0], [15.91, 0], [0, 10]], [[0, 0], [17.04, 0], [13.24, 16.1]],
        ...              (stroke, stroke, stroke))
        >>> lo, hi = np.array([[5.0, 8.0, 0.2]]), np.array([[5.5, 8.5, 0.25]])
        >>> reaches, det = m.reaches_and_det(lo, hi)
        >>> alone = m.det_a_boxes(lo, hi, [])
        >>> bool(det.lo[0] == alone.lo[0] and det.hi[0] == alone.hi[0])
        True
        >>> bool(reaches[1].hull.lo[0] == m.legs[1].reach(lo, hi).hull.lo[0])
        True
        """
        boxes = _pose_boxes(lo, hi)
        fused = type(self).det_a_boxes is ThreeRPR.det_a_boxes and all(
            type(leg).reach is RPRLeg.reach for leg in self.legs
        )
        if boxes is None or not fused:
            return super().reaches_and_det(lo, hi)
        lo_a, hi_a, _ = boxes
        n = lo_a.shape[0]
        len_lo, len_hi = np.empty((3, n)), np.empty((3, n))
        det_lo, det_hi = np.empty(n), np.empty(n)
        kernels.pose_bounds(lo_a, hi_a, self._leg_geometry, len_lo, len_hi, det_lo, det_hi)
        reaches = [_length_reach(Interval(len_lo[k], len_hi[k])) for k in range(3)]
        return reaches, Interval(det_lo, det_hi)

    def _det_a_boxes_intervals(
        self, lo: Array, hi: Array, angles: list[Interval], posture: int | None = None
    ) -> Interval:
        """:meth:`det_a_boxes` by :class:`Interval` operations (the reference)."""
        # the legs share the cosine and sine of phi
        trig = _trig(lo, hi)
        rows = [leg.a_row_boxes(lo, hi, angles[i], trig) for i, leg in enumerate(self.rpr_legs)]
        natural = interval_det(rows)
        mid = 0.5 * (lo + hi)
        trig_mid = _trig(mid, mid)
        total = interval_det(
            [leg.a_row_boxes(mid, mid, angles[i], trig_mid) for i, leg in enumerate(self.rpr_legs)]
        )
        grads = [leg.a_row_derivatives(lo, hi, trig) for leg in self.rpr_legs]
        for axis in range(3):
            # d/dx_j of the determinant: one row differentiated at a time
            d = interval_det([grads[0][axis], rows[1], rows[2]])
            d = d + interval_det([rows[0], grads[1][axis], rows[2]])
            d = d + interval_det([rows[0], rows[1], grads[2][axis]])
            total = total + d * (Interval(lo[:, axis], hi[:, axis]) - mid[:, axis])
        return Interval(np.maximum(natural.lo, total.lo), np.minimum(natural.hi, total.hi))

    def rows_and_partials(
        self, lo: Array, hi: Array, angles: list[Interval]
    ) -> tuple[list[list[Interval]], list[tuple[list[list[Interval]], list[Interval]]]]:
        """The rows of A over boxes and their partial derivatives, as the base class
        gives them, in one compiled pass (:func:`._rpr_kernels.row_bounds`: the
        bounds of :meth:`_rows_and_partials_intervals`, bit for bit)."""
        boxes = _pose_boxes(lo, hi)
        if boxes is None:
            return self._rows_and_partials_intervals(lo, hi, angles)
        n = boxes[0].shape[0]
        size = kernels.ROW_ITEMS
        out_lo, out_hi = np.empty((3 * size, n)), np.empty((3 * size, n))
        kernels.row_bounds(*boxes, self._leg_geometry, out_lo, out_hi)
        one, zero = iv.as_interval(np.ones(n)), iv.as_interval(np.zeros(n))
        rows, partials = [], []
        for k in range(3):
            dx, dy, turn, minus_rby, rbx, spin = (
                Interval(out_lo[size * k + j], out_hi[size * k + j]) for j in range(size)
            )
            rows.append([dx, dy, turn])
            partials.append(
                ([[one, zero, minus_rby], [zero, one, rbx], [minus_rby, rbx, spin]], [zero] * 3)
            )
        return rows, partials

    def _rows_and_partials_intervals(
        self, lo: Array, hi: Array, angles: list[Interval]
    ) -> tuple[list[list[Interval]], list[tuple[list[list[Interval]], list[Interval]]]]:
        """:meth:`rows_and_partials` by :class:`Interval` operations (the reference),
        the legs sharing the cosine and sine of phi."""
        trig = _trig(lo, hi)
        rows = [leg.a_row_boxes(lo, hi, angles[i], trig) for i, leg in enumerate(self.rpr_legs)]
        partials = [
            leg.row_partials(lo, hi, angles[i], trig) for i, leg in enumerate(self.rpr_legs)
        ]
        return rows, partials

    def _strokes(self) -> dict[str, list[float]]:
        return {f"rho{i + 1}": [lim.lo, lim.hi] for i, lim in enumerate(self.limits)}

    def to_spec(self) -> dict[str, object]:
        """The spec mapping of this mechanism (see :func:`~.registry.load_spec`)."""
        return {
            "mechanism": self.name,
            "parameters": {
                "base": [list(a) for a in self.base],
                "platform": [list(b) for b in self.platform],
            },
            "limits": self._strokes(),
            **self.restrictions.to_spec(),
        }

    def __repr__(self) -> str:
        extra = "" if self.restrictions.empty else f", restrictions={self.restrictions}"
        return (
            f"ThreeRPR(base={self.base}, platform={self.platform}, limits={self._strokes()}{extra})"
        )

    def linkage_points(
        self, lo: Array, hi: Array, angles: list[Interval]
    ) -> dict[str, tuple[Interval, Interval]]:
        """The base joints A_i (fixed) and the platform joints ``B_i = P + R(phi) b_i``
        over the boxes of poses (the lengths are not needed)."""
        n = lo.shape[0]
        points, _ = platform_points(lo, hi, self.platform)
        for i, a in enumerate(self.base):
            points[f"A{i + 1}"] = fixed_point(a, n)
        return points

    def linkage_velocities(
        self,
        lo: Array,
        hi: Array,
        angles: list[Interval],
        velocity: list[Interval],
        rates: list[Interval],
    ) -> dict[str, tuple[Interval, Interval]]:
        """A_i still, each platform joint moving with the pose (``P' + phi' (-(R
        b_i)_y, (R b_i)_x)``); the lengths' rates follow from it."""
        n = lo.shape[0]
        _, turned = platform_points(lo, hi, self.platform)
        out = platform_velocities(turned, velocity)
        still = fixed_point((0.0, 0.0), n)
        for i in range(3):
            out[f"A{i + 1}"] = still
        return out
