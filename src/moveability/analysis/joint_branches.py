"""The joint-space count of two dyads with constraints: one assembly branch at a time.

Without constraints beyond the paper's, the two poses of a joint vector q of
D (see :mod:`moveability.analysis.joint_space`) lie in two regions alike, and the
regions are the components of D, twice. Passive limits, obstacles and link
collisions (:mod:`moveability.mechanisms.constraints`) tell the two apart: the
pose on one side of the line of the knees may hit an obstacle that the mirror
pose misses. But each pose is still a continuous function of q on D, one per
*branch* (``P = F + s h n``, F the foot of P on the line of the knees C_1 C_2,
n the unit normal, h the height, s = +-1), and det A keeps one sign along each
branch. So the configurations within the limits, satisfying the constraints
and with det A != 0, are homeomorphic to the disjoint union over s of

    D_s = {q in D : the constraints hold at (P_s(q), q)},

and the regions are the components of D_+ and of D_-. :class:`BranchCondition`
gives what the quadtree count of Q needs for one D_s:

* ``classify``: IN where d^2 certainly lies inside its bounds and every
  constraint certainly holds at the branch's poses over the cell (enclosed by
  interval arithmetic over the cell: ``P_s`` from the knees' enclosures, the
  constraints by :class:`~moveability.mechanisms.constraints.ConstraintMargins`
  over those); OUT where d^2 is certainly outside or some constraint certainly
  fails, or no configuration of the branch's sign of det A satisfies them;
* ``flows``: for each constant direction v of Q, where moving along v keeps
  every constraint that may be active in the cell. The platform point moves at
  ``P' = adj(M) r / det M``, from differentiating ``|P - C_i|^2 = b_i^2``: the
  rows of M are ``e_i = P - C_i`` and ``r_i = e_i . C_i'``; ``det M = s h |d|``,
  never zero on D. Near a parallel singularity ``P'`` is unbounded, but the
  rates of the constraints are linear in the velocities of the points: every
  velocity multiplied by ``|det M|`` gives rates of the same signs, and bounded
  enclosures (``adj(M) r`` has no division). The count attaches an undecided
  cell along v where both d^2 and the constraints allow it (see
  :func:`moveability.analysis.flows.attached_nodes`);
* ``level_flows``: two more flows, along the level curves of d^2 (both ways).
  They keep d^2, hence the configuration's height above the singularity, and
  the triangle of the knees and P moves rigidly, at bounded speed: where a
  constraint nears the parallel singularity along its curve, the flow along
  the singularity can still certify that a thin valid sliver next to it joins
  the rest;
* ``inside``: where every constraint certainly holds, so that a convex block of
  d^2 needs nothing more (``flows`` gives all three with the constraints
  enclosed once).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from .. import intervals as iv
from ..hypertree.status import BOUNDARY, IN, OUT
from ..intervals import Interval
from ..limits import INSIDE, OUTSIDE
from ..mechanisms.base import Mechanism
from ..mechanisms.constraints import ConstraintMargins
from ..types import Array

__all__ = ["BranchCondition", "takes_branches"]

#: points of Q per axis sampled to find the sign of det A along each branch
_SIGN_SAMPLES = 48

#: (x, y) enclosures of a point over n boxes
_Point = tuple[Interval, Interval]


def takes_branches(mechanism: Mechanism) -> bool:
    """Whether the mechanism's constraints can be counted one branch at a time: it
    has some, over a linkage of named points (as the five-bar's), and encloses
    them by the common :meth:`~moveability.mechanisms.base.Mechanism.constraint_margins`.

    Examples
    --------
    >>> from moveability.mechanisms import FiveBar
    >>> from moveability.mechanisms.constraints import Constraints
    >>> takes_branches(FiveBar()), takes_branches(
    ...     FiveBar().constrained(Constraints(collisions=True)))
    (False, True)
    """
    kind = type(mechanism)
    return (
        not mechanism.restrictions.empty
        and mechanism.linkage is not None
        and kind.constraint_margins is Mechanism.constraint_margins
        and kind.linkage_points is not Mechanism.linkage_points
        and kind.linkage_velocities is not Mechanism.linkage_velocities
    )


class BranchCondition:
    """D_s of one branch ``s`` (+1: the pose :meth:`poses` gives first, -1: the
    second) of a two-dyad mechanism with constraints.

    Parameters
    ----------
    mechanism : Mechanism
        Two dyads (:func:`~moveability.analysis.joint_space.has_dyads`) that
        :func:`takes_branches`.
    distance : object
        The knees' distance over boxes of Q (``terms``, ``classify``,
        ``poses``, ``lower``, ``upper``).
    branch : {1, -1}

    Examples
    --------
    >>> import numpy as np
    >>> from moveability.analysis.joint_space import joint_condition
    >>> from moveability.hypertree.status import IN, OUT
    >>> from moveability.mechanisms import FiveBar
    >>> from moveability.mechanisms.constraints import Constraints
    >>> m = FiveBar(7, 6, 5, 6, 4).constrained(
    ...     Constraints.from_spec({"obstacles": [{"center": [3.5, 9.0], "radius": 1.0}]}))
    >>> up, down = (BranchCondition(m, joint_condition(m), s) for s in (1, -1))
    >>> q = np.array([[0.6, 1.5]])  # one branch's distal link meets the disk
    >>> [up.classify(q, q)[0], down.classify(q, q)[0]] == [OUT, IN]
    True
    """

    def __init__(self, mechanism: Mechanism, distance: Any, branch: int) -> None:
        self.mechanism = mechanism
        self.distance = distance
        self.branch = int(branch)
        self.lower, self.upper = distance.lower, distance.upper
        self.legs = mechanism.legs
        #: the sign of det A along the branch (0 where the samples do not tell)
        self.det_sign = self._det_sign()

    def _det_sign(self) -> int:
        """The sign of det A at the branch's poses of a grid of Q: one sign on D
        (det A vanishes on D's boundary alone), 0 where no sample lies in D or
        they disagree (then no constraint is sharpened by it)."""
        m = self.mechanism
        lo = np.array([lim.lo for lim in m.limits])
        hi = np.array([lim.lo + 2 * np.pi if lim.periodic else lim.hi for lim in m.limits])
        t = (np.arange(_SIGN_SAMPLES) + 0.5) / _SIGN_SAMPLES
        grid = np.stack(np.meshgrid(*(a + t * (b - a) for a, b in zip(lo, hi, strict=True))), -1)
        joints = grid.reshape(-1, lo.size)
        poses = self.distance.poses(joints)[:, 0 if self.branch > 0 else 1]
        with np.errstate(invalid="ignore"):
            det = m.det_a(poses, joints)
        signs = np.unique(np.sign(det[np.isfinite(det) & (det != 0)]))
        return int(signs[0]) if signs.size == 1 else 0

    def _point(self, knees: list[_Point], dist2: Interval) -> tuple[_Point, Interval]:
        """The branch's platform point and ``det M = s h |d|`` from the knees and
        their squared distance (natural enclosures)."""
        b1, b2 = (float(leg.distal) for leg in self.legs)  # type: ignore[attr-defined]
        (c1x, c1y), (c2x, c2y) = knees
        dx, dy = c2x - c1x, c2y - c1y
        # keep d^2 > 0: a box where the knees may meet has no pose there anyway
        dist2 = Interval(np.maximum(dist2.lo, np.finfo(float).tiny), np.maximum(dist2.hi, 0.0))
        # each d^2 once per factor: along = 1/2 + (b_1^2 - b_2^2) / (2 d^2), and
        # (h / |d|)^2 = ((b_1 + b_2)^2 - d^2) (d^2 - (b_1 - b_2)^2) / (4 d^4)
        along = Interval(b1 * b1 - b2 * b2) / (dist2 * 2.0) + 0.5
        rise = (self.upper - dist2) * (dist2 - self.lower) / (iv.square(dist2) * 4.0)
        # h / |d|, with n = (-dy, dx) unnormalised
        height = iv.sqrt(Interval(np.maximum(rise.lo, 0.0), np.maximum(rise.hi, 0.0)))
        s = float(self.branch)
        point = (c1x + along * dx - height * dy * s, c1y + along * dy + height * dx * s)
        return point, height * dist2 * s

    @staticmethod
    def _moments(
        point: _Point, knees: list[_Point], rates: list[_Point]
    ) -> tuple[list[Interval], list[Interval]]:
        """``det M dP/dq_j`` (x parts, y parts): ``adj(M) r`` for the right-hand side
        ``r_j`` on row j and 0 on the other (see the module's notes); bounded where
        ``det M`` is near 0, unlike ``dP/dq_j``."""
        e = [(point[0] - c[0], point[1] - c[1]) for c in knees]
        r = [e[j][0] * rates[j][0] + e[j][1] * rates[j][1] for j in range(2)]
        xs = [r[0] * e[1][1], -(r[1] * e[0][1])]
        ys = [-(e[1][0] * r[0]), e[0][0] * r[1]]
        return xs, ys

    def _frame(self, lo: Array, hi: Array) -> tuple[list[_Point], list[_Point], _Point, Interval]:
        """Over the boxes: the knees, their rates along their joints, the branch's
        platform point, and ``det M``. Where the branch is smooth over the box
        (``det M`` certainly not 0) the point's natural enclosure is met with its
        mean-value form about the box's centre."""
        q = [Interval(lo[:, i], hi[:, i]) for i in range(2)]
        mid = 0.5 * (lo + hi)
        knees, rates, centres = [], [], []
        for i, leg in enumerate(self.legs):
            p, v, _ = leg.knee_boxes(q[i])  # type: ignore[attr-defined]
            knees.append((p[0], p[1]))
            rates.append((v[0], v[1]))
            c, _, _ = leg.knee_boxes(Interval(mid[:, i]))  # type: ignore[attr-defined]
            centres.append((c[0], c[1]))
        dist2, _, _ = self.distance.terms(lo, hi, hessian=False)
        point, det = self._point(knees, dist2)
        mid_d2 = iv.square(centres[1][0] - centres[0][0]) + iv.square(centres[1][1] - centres[0][1])
        at_mid, _ = self._point(centres, mid_d2)
        smooth = (det.lo > 0) | (det.hi < 0)
        for _ in range(2):
            xs, ys = self._moments(point, knees, rates)
            tight = []
            for axis, moments in enumerate((xs, ys)):
                mv = at_mid[axis]
                for j in range(2):
                    mv = mv + moments[j] / det * (q[j] - mid[:, j])
                old = point[axis]
                new_lo = np.where(smooth, np.maximum(old.lo, mv.lo), old.lo)
                new_hi = np.where(smooth, np.minimum(old.hi, mv.hi), old.hi)
                tight.append(Interval(new_lo, new_hi))
            point = (tight[0], tight[1])
        return knees, rates, point, det

    def _margins(self, lo: Array, hi: Array) -> tuple[ConstraintMargins, Any]:
        knees, rates, point, det = self._frame(lo, hi)
        p_lo = np.stack([point[0].lo, point[1].lo], axis=1)
        p_hi = np.stack([point[0].hi, point[1].hi], axis=1)
        angles = [Interval(lo[:, i], hi[:, i]) for i in range(2)]
        margins = self.mechanism.constraint_margins(p_lo, p_hi, angles)
        assert margins is not None  # takes_branches: the mechanism has constraints
        return margins, (knees, rates, point, det, p_lo, p_hi, angles)

    def classify(self, lo: Array, hi: Array) -> NDArray[np.uint8]:
        """IN, OUT or BOUNDARY (see the module's notes) for boxes of Q."""
        status = self.distance.classify(lo, hi)
        rows = np.flatnonzero(status != OUT)
        if not rows.size:
            return status
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            margins, _ = self._margins(lo[rows], hi[rows])
            codes = margins.codes
            fails = codes == OUTSIDE
            if self.det_sign:
                fails |= margins.excluded(self.det_sign)
        out = status.copy()
        out[rows] = np.where(
            fails, OUT, np.where((codes == INSIDE) & (status[rows] == IN), IN, BOUNDARY)
        )
        return out.astype(np.uint8)

    def inside(self, lo: Array, hi: Array) -> NDArray[np.bool_]:
        """Where every configuration of the branch over the boxes satisfies the
        constraints."""
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            margins, _ = self._margins(lo, hi)
        return np.asarray(margins.codes == INSIDE)

    def flows(
        self, lo: Array, hi: Array, vectors: Array, dist2: Interval, grad: list[Interval]
    ) -> tuple[NDArray[np.bool_], NDArray[np.bool_], NDArray[np.bool_], NDArray[np.uint8]]:
        """All that the count asks of the boxes at once, the constraints enclosed
        once: (n, len(vectors)) where moving along each constant direction keeps
        them (:meth:`_kept`), (n,) where they all hold (:meth:`inside`), and the
        level flows with their exit faces (:meth:`level_flows`); ``dist2`` and
        ``grad`` are d^2 and its gradient over the boxes."""
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            margins, frame = self._margins(lo, hi)
            level, faces = self._level(margins, frame, dist2, grad)
            return self._kept(margins, frame, vectors), margins.codes == INSIDE, level, faces

    def _kept(self, margins: ConstraintMargins, frame: Any, vectors: Array) -> NDArray[np.bool_]:
        """(n, len(vectors)): where moving the joints along each direction keeps
        every constraint that may be active over the box (see the module's notes).

        The rates are enclosed twice, and either certificate holds: with the
        platform's velocity ``adj(M) r / det M``, and with every velocity
        multiplied by ``|det M| = s det M`` (the rates are linear in the
        velocities, so their signs are those of the configurations'; bounded near
        a parallel singularity, where the first form is not)."""
        knees, rates, point, det, p_lo, p_hi, angles = frame
        n = p_lo.shape[0]
        out = np.ones((n, vectors.shape[0]), dtype=bool)
        m = self.mechanism
        s = float(self.branch)
        xs, ys = self._moments(point, knees, rates)
        scale = det * s
        for f, v in enumerate(vectors):
            px = xs[0] * float(v[0]) + xs[1] * float(v[1])
            py = ys[0] * float(v[0]) + ys[1] * float(v[1])
            plain = m.linkage_velocities(
                p_lo,
                p_hi,
                angles,
                [px / det, py / det],
                [Interval(np.full(n, float(v[i]))) for i in range(2)],
            )
            scaled = m.linkage_velocities(
                p_lo, p_hi, angles, [px * s, py * s], [scale * float(v[i]) for i in range(2)]
            )
            out[:, f] = margins.kept(plain, self.det_sign) | margins.kept(scaled, self.det_sign)
        return out

    def level_flows(
        self, lo: Array, hi: Array, grad: list[Interval]
    ) -> tuple[NDArray[np.bool_], NDArray[np.uint8]]:
        """The flows along the level curves of d^2, both ways, over the boxes: (n, 2)
        where each keeps every constraint that may be active, and (2, n) the
        faces each may leave the box through (bit ``2 a`` the upper face of axis
        a, ``2 a + 1`` the lower).

        The joints move along ``t = +-(-g_2, g_1)``, g the gradient of d^2
        (``grad``, enclosures over the boxes): d^2 stays constant, so the
        configuration stays in D and on its branch, whatever the height, and the
        triangle of the knees and P moves as a rigid body: ``P' = C_1' + w
        perp(P - C_1)``, ``w = (d x d') / d^2``. A flow counts where one joint
        certainly moves one way (it leaves the box).
        """
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            margins, frame = self._margins(lo, hi)
            dist2, _, _ = self.distance.terms(lo, hi, hessian=False)
            return self._level(margins, frame, dist2, grad)

    def _level(
        self, margins: ConstraintMargins, frame: Any, dist2: Interval, grad: list[Interval]
    ) -> tuple[NDArray[np.bool_], NDArray[np.uint8]]:
        """:meth:`level_flows` from the constraints and the frame over the boxes."""
        knees, rates, point, _, p_lo, p_hi, angles = frame
        n = p_lo.shape[0]
        ok = np.zeros((n, 2), dtype=bool)
        faces = np.zeros((2, n), dtype=np.uint8)
        for f, way in enumerate((1.0, -1.0)):
            t, (px, py) = self.level_velocity(knees, rates, point, dist2, grad, way)
            velocities = self.mechanism.linkage_velocities(p_lo, p_hi, angles, [px, py], t)
            leaves = np.zeros(n, dtype=bool)
            bits = np.zeros(n, dtype=np.uint8)
            for axis in range(2):
                up, down = t[axis].lo > 0, t[axis].hi < 0
                leaves |= up | down
                still = (t[axis].lo == 0) & (t[axis].hi == 0)
                bits |= np.where(up | ~(down | still), 1 << (2 * axis), 0).astype(np.uint8)
                bits |= np.where(down | ~(up | still), 1 << (2 * axis + 1), 0).astype(np.uint8)
            ok[:, f] = leaves & (dist2.lo > 0) & margins.kept(velocities, self.det_sign)
            faces[f] = bits
        return ok, faces

    @staticmethod
    def level_velocity(
        knees: list[_Point],
        rates: list[_Point],
        point: _Point,
        dist2: Interval,
        grad: list[Interval],
        way: float,
    ) -> tuple[list[Interval], _Point]:
        """The joints' rates ``t = way (-g_2, g_1)`` of a level flow, and the
        platform point's velocity then (see :meth:`level_flows`)."""
        (c1x, c1y), (c2x, c2y) = knees
        t = [-grad[1] * way, grad[0] * way]
        moving = [(r[0] * t[i], r[1] * t[i]) for i, r in enumerate(rates)]
        ddx = moving[1][0] - moving[0][0]
        ddy = moving[1][1] - moving[0][1]
        w = ((c2x - c1x) * ddy - (c2y - c1y) * ddx) / dist2
        return t, (moving[0][0] - w * (point[1] - c1y), moving[0][1] + w * (point[0] - c1x))
