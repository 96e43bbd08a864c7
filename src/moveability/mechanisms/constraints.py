"""Constraints beyond the paper's: passive joint limits, obstacles, link collisions.

The paper takes the passive joints as unlimited and ignores collisions. A
spec may add, for the mechanisms whose links are known as segments:

``[passive_limits]``
    a range ``[lo, hi]`` (radians) per passive joint: the signed angle from one
    link to the next, wrapped to ``(-pi, pi]``;
``[[obstacles]]``
    disks (``center``, ``radius``) that no moving link may meet;
``[collisions]``
    ``links = true``: moving links may not cross one another, except links
    that share a joint.

They make part of what a valid configuration is. Over a box of poses and
enclosures of the joint angles of one posture, :func:`constraint_codes`
says whether every configuration satisfies them all (``INSIDE``), none does
(``OUTSIDE``: some constraint is certainly violated) or it cannot tell
(``STRADDLES``), by interval arithmetic with outward rounding:

* an angle is the narrower of two enclosures, with the cut of ``atan2`` on
  the negative and on the positive x axis;
* the distance from a disk's centre O to a segment [c, p] is ``|c + t (p -
  c) - O|`` at ``t = clamp(((O - c) . (p - c)) / |p - c|^2, 0, 1)``, the
  closest point, evaluated with t as an interval (which holds the exact t of
  every configuration);
* two segments cross when each one's end points lie strictly on both sides
  of the other's line, and are apart when both ends of one lie strictly on
  one side of the other's line.

Along a motion of the pose, :class:`ConstraintMargins` encloses how fast each
constraint moves toward or away from its bound (the certificate that no
region hides, :mod:`moveability.analysis.flows`, needs it where a constraint
may be active):

* a passive angle turns at ``(v x v') / |v|^2 - (u x u') / |u|^2`` (u, v its
  two links);
* the squared distance from a point O to a segment [c, p] changes at
  ``2 (Q - O) . ((1 - t) c' + t p' - O')``, Q the closest point and t its
  parameter (the closest point is unique, so the distance has this
  derivative);
* two closed segments that are apart can only come to meet where an end
  point of one touches the other (crossing is an open condition), so they
  stay apart while each of the four distances from an end point to the
  other segment stays positive: certainly so over the box, or never
  decreasing.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .. import intervals as iv
from ..intervals import Interval
from ..limits import INSIDE, OUTSIDE, STRADDLES, JointLimit
from ..types import Array

__all__ = [
    "ConstraintMargins",
    "Constraints",
    "Linkage",
    "Obstacle",
    "Turning",
    "constraint_codes",
    "cross_velocity",
    "fixed_point",
    "segment_codes",
    "vector_angle",
]

#: a point of the linkage over n boxes: (x, y) enclosures
Point = tuple[Interval, Interval]


class Turning(tuple):
    """The velocity of a point turning about a centre, ``omega J r`` (``J`` the
    quarter turn, ``r`` the point less the centre): a :data:`Point` of
    enclosures that also keeps its factors, so that a cross product with it
    is ``omega (J r) x w = -omega (r . w)``. The joint's rate ``omega`` may be
    unbounded (a leg that may fold); the product then keeps its sign, which
    the components, each unbounded, would lose.

    Examples
    --------
    >>> v = Turning(Interval(np.array([1.0]), np.array([np.inf])),
    ...             (Interval(np.array([1.0])), Interval(np.array([0.0]))))
    >>> w = (Interval(np.array([2.0])), Interval(np.array([0.5])))
    >>> x = cross_velocity(v, w)   # -(omega) (r . w) = -2 omega
    >>> float(x.lo[0]), float(x.hi[0])
    (-inf, -2.0)
    """

    omega: Interval
    lever: Point

    def __new__(cls, omega: Interval, lever: Point) -> Turning:
        out = super().__new__(cls, (-(lever[1] * omega), lever[0] * omega))
        out.omega = omega
        out.lever = lever
        return out


def cross_velocity(v: Point, w: Point) -> Interval:
    """``v x w`` for a velocity v, factored when v is a :class:`Turning`."""
    if isinstance(v, Turning):
        return -(v.omega * (v.lever[0] * w[0] + v.lever[1] * w[1]))
    return _cross(v, w)


@dataclass(frozen=True)
class Obstacle:
    """A disk no moving link may meet."""

    center: tuple[float, float]
    radius: float


@dataclass(frozen=True)
class Constraints:
    """The optional constraints of a mechanism (all absent by default).

    Examples
    --------
    >>> c = Constraints.from_spec({"passive_limits": {"P": (-1.5, 1.5)},
    ...                            "obstacles": [{"center": [4.5, 0.0], "radius": 1.0}],
    ...                            "collisions": {"links": True}})
    >>> c.passive["P"].lo, c.obstacles[0].radius, c.collisions, c.empty
    (-1.5, 1.0, True, False)
    >>> Constraints().empty
    True
    """

    passive: Mapping[str, JointLimit] = field(default_factory=dict)
    obstacles: tuple[Obstacle, ...] = ()
    collisions: bool = False

    @property
    def empty(self) -> bool:
        """Whether no constraint is set (the paper's hypotheses)."""
        return not (self.passive or self.obstacles or self.collisions)

    @classmethod
    def from_spec(cls, spec: Mapping[str, Any]) -> Constraints:
        """The constraints of a normalised spec (see :func:`moveability.spec.check_spec`)."""
        passive = {
            str(name): JointLimit(float(lo), float(hi))
            for name, (lo, hi) in dict(spec.get("passive_limits") or {}).items()
        }
        obstacles = tuple(
            Obstacle((float(o["center"][0]), float(o["center"][1])), float(o["radius"]))
            for o in spec.get("obstacles") or ()
        )
        collisions = bool(dict(spec.get("collisions") or {}).get("links", False))
        return cls(passive, obstacles, collisions)

    def to_spec(self) -> dict[str, Any]:
        """The tables of a spec that give these constraints (absent ones left out)."""
        out: dict[str, Any] = {}
        if self.passive:
            out["passive_limits"] = {k: (v.lo, v.hi) for k, v in self.passive.items()}
        if self.obstacles:
            out["obstacles"] = [
                {"center": list(o.center), "radius": o.radius} for o in self.obstacles
            ]
        if self.collisions:
            out["collisions"] = {"links": True}
        return out


@dataclass(frozen=True)
class Linkage:
    """How a mechanism's links are laid out, for its constraints.

    Attributes
    ----------
    links : tuple of (str, str)
        The moving links, as segments between named points.
    passive : mapping of str to ((str, str), (str, str))
        Each passive joint's angle: from the first link's direction to the
        second's (a link (a, b) points from a to b).
    ends : tuple of (str, (str, str), int)
        Sides known from the posture: the end of a leg lies on its branch's side
        of the leg's first link, except where the leg folds.
    det_sides : tuple of (str, (str, str), int)
        Sides known from the sign of det A (a parallel singularity is where a
        point crosses a link's line).
    """

    links: tuple[tuple[str, str], ...]
    passive: Mapping[str, tuple[tuple[str, str], tuple[str, str]]]
    #: (point, link, leg): the point lies strictly on side ``2 b - 1`` of the link's
    #: line (b the leg's branch; the side is the sign of ``(l1 - l0) x (point - l0)``)
    #: wherever the leg does not fold, and on the line only where it folds
    ends: tuple[tuple[str, tuple[str, str], int], ...] = ()
    #: (point, link, factor): the point lies strictly on side ``factor * sign(det A)``
    #: of the link's line wherever det A != 0
    det_sides: tuple[tuple[str, tuple[str, str], int], ...] = ()


def vector_angle(x: Interval, y: Interval) -> Interval:
    """An enclosure (unwrapped) of the direction of the vectors of the box x times y:
    the narrower of atan2 with its cut on the negative x axis and on the positive.

    Examples
    --------
    >>> a = vector_angle(Interval(-2.0, -1.0), Interval(-0.1, 0.1))
    >>> bool(a.lo < np.pi < a.hi and a.hi - a.lo < 0.3)
    True
    """
    plain = iv.arctan2(y, x)
    turned = iv.arctan2(-y, -x) + np.pi
    narrow = (turned.hi - turned.lo) < (plain.hi - plain.lo)
    return Interval(np.where(narrow, turned.lo, plain.lo), np.where(narrow, turned.hi, plain.hi))


def _minus(a: Point, b: Point) -> Point:
    return a[0] - b[0], a[1] - b[1]


def _cross(u: Point, v: Point) -> Interval:
    return u[0] * v[1] - u[1] * v[0]


def _clamp01(t: Interval) -> Interval:
    return Interval(np.clip(t.lo, 0.0, 1.0), np.clip(t.hi, 0.0, 1.0))


def _closest(o: Point, c: Point, p: Point) -> tuple[Interval, Point]:
    """The parameter t of the point of the segment [c, p] closest to o, and that
    point less o, enclosed over the boxes."""
    u = _minus(p, c)
    w = _minus(o, c)
    length2 = iv.square(u[0]) + iv.square(u[1])
    dot = w[0] * u[0] + w[1] * u[1]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = _clamp01(dot / length2)
    t = Interval(np.where(length2.lo > 0, t.lo, 0.0), np.where(length2.lo > 0, t.hi, 1.0))
    return t, (c[0] + t * u[0] - o[0], c[1] + t * u[1] - o[1])


def _disk_codes(c: Point, p: Point, obstacle: Obstacle) -> NDArray[np.uint8]:
    """Whether the segment [c, p] certainly misses the disk (INSIDE: the constraint
    holds), certainly meets it (OUTSIDE), or either (STRADDLES)."""
    n = c[0].lo.shape[0]
    _, (qx, qy) = _closest(fixed_point(obstacle.center, n), c, p)
    d2 = iv.square(qx) + iv.square(qy)
    r2 = iv.square(obstacle.radius)
    out = np.full(d2.lo.shape, STRADDLES, dtype=np.uint8)
    out[d2.lo > r2.hi] = INSIDE
    out[d2.hi < r2.lo] = OUTSIDE
    return out


def segment_codes(a: Point, b: Point, c: Point, d: Point) -> NDArray[np.uint8]:
    """Whether the segments [a, b] and [c, d] are certainly apart (INSIDE: the
    constraint holds), certainly cross (OUTSIDE), or either (STRADDLES).

    Examples
    --------
    >>> def pt(x, y):
    ...     return Interval(np.array([x])), Interval(np.array([y]))
    >>> segment_codes(pt(0, 0), pt(2, 2), pt(0, 2), pt(2, 0)).tolist()  # an X: they cross
    [2]
    >>> segment_codes(pt(0, 0), pt(1, 0), pt(0, 1), pt(1, 1)).tolist()  # parallel: apart
    [1]
    """
    ab, cd = _minus(b, a), _minus(d, c)
    o1, o2 = _cross(ab, _minus(c, a)), _cross(ab, _minus(d, a))
    o3, o4 = _cross(cd, _minus(a, c)), _cross(cd, _minus(b, c))
    return _crossing_codes(o1, o2, o3, o4)


def _crossing_codes(o1: Interval, o2: Interval, o3: Interval, o4: Interval) -> NDArray[np.uint8]:
    """:func:`segment_codes` from the sides of c, d of the line of [a, b] (o1, o2)
    and of a, b of the line of [c, d] (o3, o4)."""

    def same_side(s: Interval, t: Interval) -> NDArray[np.bool_]:
        return ((s.lo > 0) & (t.lo > 0)) | ((s.hi < 0) & (t.hi < 0))

    def opposite(s: Interval, t: Interval) -> NDArray[np.bool_]:
        return ((s.lo > 0) & (t.hi < 0)) | ((s.hi < 0) & (t.lo > 0))

    out = np.full(o1.lo.shape, STRADDLES, dtype=np.uint8)
    out[same_side(o1, o2) | same_side(o3, o4)] = INSIDE
    out[opposite(o1, o2) & opposite(o3, o4)] = OUTSIDE
    return out


def constraint_codes(
    constraints: Constraints, linkage: Linkage, points: Mapping[str, Point]
) -> NDArray[np.uint8]:
    """Whether every configuration of the boxes satisfies every constraint (INSIDE),
    none does because one is certainly violated (OUTSIDE), or it cannot tell.

    ``points`` gives the enclosure of each named point of ``linkage`` over n boxes.
    """
    return ConstraintMargins(constraints, linkage, points).codes


#: one way to keep two overlapping links apart: sides (point, line, +-1 per box)
#: that must all keep their sign, and the boxes where it applies
_Option = tuple[list[tuple[str, tuple[str, str], Any]], Any]


#: sides that every configuration keeping all links apart has: (point, line
#: with its names in order) -> (boxes where the side is > 0, where it is < 0)
_Facts = dict[tuple[str, tuple[str, str]], tuple[Any, Any]]


def _oriented(point: str, line: tuple[str, str]) -> tuple[tuple[str, tuple[str, str]], int]:
    """The key of a side in :data:`_Facts`, and +-1: the side's sign relative to
    the key's."""
    if line[0] <= line[1]:
        return (point, line), 1
    return (point, (line[1], line[0])), -1


def _readings(x: str, y: str, z: str) -> list[tuple[tuple[str, str, str], int]]:
    """The six orders of a turn's three points, each with its sign relative to
    ``(x, y, z)``: cyclic orders agree, the others flip."""
    return [
        ((x, y, z), 1),
        ((y, z, x), 1),
        ((z, x, y), 1),
        ((y, x, z), -1),
        ((x, z, y), -1),
        ((z, y, x), -1),
    ]


def _learn(facts: _Facts, point: str, line: tuple[str, str], sign: Any, mask: Any) -> None:
    """Add to ``facts`` that the side has ``sign`` (+-1 per box) in boxes ``mask``."""
    key, flip = _oriented(point, line)
    up, down = facts.get(key, (False, False))
    facts[key] = (up | (mask & (flip * sign > 0)), down | (mask & (flip * sign < 0)))


def _against(facts: _Facts, point: str, line: tuple[str, str], sign: Any) -> Any:
    """Where ``facts`` give the side the sign opposite to ``sign`` (+-1 per box)."""
    key, flip = _oriented(point, line)
    if key not in facts:
        return False
    up, down = facts[key]
    return np.where(flip * sign > 0, down, up)


def _same_facts(one: _Facts, other: _Facts) -> bool:
    return one.keys() == other.keys() and all(
        np.array_equal(one[key][0], other[key][0]) and np.array_equal(one[key][1], other[key][1])
        for key in one
    )


@dataclass(frozen=True)
class _Overlap:
    """What :meth:`ConstraintMargins._overlap` finds for a pair of links: the codes
    it decides (``STRADDLES`` elsewhere), where it leaves them open but knows
    the one side that keeps them apart, and those sides (point, line, +-1, where)."""

    codes: NDArray[np.uint8]
    covered: NDArray[np.bool_]
    sides: list[_Option]


#: a distance that must stay positive: the end point (a point's name, or an
#: obstacle's fixed centre) and the segment's two points' names, and where it
#: may be active
_Distance = tuple[str | Point, str, str, NDArray[np.bool_]]


class ConstraintMargins:
    """The constraints over n boxes of poses and one posture's joint enclosures:
    whether each may be active there, and how fast it moves along a motion.

    Parameters
    ----------
    constraints, linkage
        What to enforce, and the links they are about.
    points : mapping of str to (Interval, Interval)
        The enclosure of each named point of ``linkage`` over the boxes.
    branches, regular : optional
        The posture's branch per leg, and (n, legs) where each leg certainly
        does not fold: they give the sides of :attr:`Linkage.ends`.

    Attributes
    ----------
    codes : (n,) uint8
        ``INSIDE`` where every configuration satisfies every constraint,
        ``OUTSIDE`` where one is certainly violated, ``STRADDLES`` elsewhere.

    Examples
    --------
    A link from the origin to (2 +- 0.1, 0 +- 0.1) and a disk of radius 1 at
    (1, 1.05): the link may touch it. Moving its free end down takes it away,
    moving it up brings it nearer.

    >>> linkage = Linkage(links=(("A", "P"),), passive={})
    >>> box = {"A": fixed_point((0.0, 0.0), 1),
    ...        "P": (Interval([1.9], [2.1]), Interval([-0.1], [0.1]))}
    >>> margins = ConstraintMargins(Constraints(obstacles=(Obstacle((1.0, 1.05), 1.0),)),
    ...                             linkage, box)
    >>> margins.codes.tolist() == [STRADDLES]
    True
    >>> still = fixed_point((0.0, 0.0), 1)
    >>> down = {"A": still, "P": fixed_point((0.0, -1.0), 1)}
    >>> up = {"A": still, "P": fixed_point((0.0, 1.0), 1)}
    >>> margins.kept(down).tolist(), margins.kept(up).tolist()
    ([True], [False])
    """

    def __init__(
        self,
        constraints: Constraints,
        linkage: Linkage,
        points: Mapping[str, Point],
        branches: Sequence[int] | None = None,
        regular: NDArray[np.bool_] | None = None,
    ) -> None:
        self._points = points
        #: (point, link) -> (the branch's side, where the leg may fold)
        self._known: dict[tuple[str, tuple[str, str]], tuple[int, NDArray[np.bool_]]] = {}
        if branches is not None and regular is not None:
            for point, link, leg in linkage.ends:
                self._known[point, link] = (2 * int(branches[leg]) - 1, ~regular[:, leg])
        self._det_known = {(point, link): factor for point, link, factor in linkage.det_sides}
        self._cache: dict[int, tuple[NDArray[np.bool_], Interval, Point]] = {}
        self._signed_list: dict[int, list[tuple[NDArray[np.bool_], list[_Option]]]] = {}
        #: per sign of det A: boxes where no configuration off the folds keeps
        #: every pair apart (see :meth:`_signed_pairs`)
        self._void: dict[int, NDArray[np.bool_]] = {}
        n = self._shape = next(iter(points.values()))[0].lo.shape
        holds = np.ones(n, dtype=bool)
        fails = np.zeros(n, dtype=bool)

        def meet(codes: NDArray[np.uint8]) -> NDArray[np.bool_]:
            nonlocal holds, fails
            holds &= codes == INSIDE
            fails |= codes == OUTSIDE
            return np.asarray(codes != INSIDE)

        #: passive angles: (first link, second link, may meet the lower stop, the upper)
        self._angles: list[tuple[tuple[str, str], tuple[str, str], Any, Any]] = []
        self._distances: list[_Distance] = []
        #: links that may not cross, where they may touch, and where they are
        #: apart at every configuration off a fold (see :meth:`_across_fold`)
        self._pairs: list[tuple[tuple[str, str], tuple[str, str], Any, Any]] = []
        #: per pair: where the links may touch overlapping along one line, the side
        #: of a point of one link's line that keeps them apart (see :meth:`_overlap`)
        self._overlaps: list[list[_Option]] = []
        for name, limit in constraints.passive.items():
            first_link, second_link = linkage.passive[name]
            first = vector_angle(*_minus(points[first_link[1]], points[first_link[0]]))
            second = vector_angle(*_minus(points[second_link[1]], points[second_link[0]]))
            angle = second - first
            active = meet(limit.classify(angle))
            exists, lower, upper = limit.pieces(angle)
            rise = active & (exists & lower).any(axis=0)
            fall = active & (exists & upper).any(axis=0)
            self._angles.append((first_link, second_link, rise, fall))
        for obstacle in constraints.obstacles:
            centre = fixed_point(obstacle.center, int(np.prod(n)))
            for a, b in linkage.links:
                self._distances.append(
                    (centre, a, b, meet(_disk_codes(points[a], points[b], obstacle)))
                )
        if constraints.collisions:
            for i, (a, b) in enumerate(linkage.links):
                for c, d in linkage.links[i + 1 :]:
                    if {a, b} & {c, d}:
                        continue  # links sharing a joint
                    one, other = (a, b), (c, d)
                    code = self._pair_code(one, other)
                    overlap = self._overlap(one, other, code == STRADDLES)
                    code = np.where(overlap.codes != STRADDLES, overlap.codes, code)
                    active = meet(code.astype(np.uint8))
                    fold_apart, fold_cross = self._across_fold(one, other)
                    fails |= fold_cross
                    active &= ~fold_cross
                    keep = active & ~fold_apart
                    self._overlaps.append([(terms, keep & m) for terms, m in overlap.sides])
                    self._pairs.append((one, other, active, fold_apart))
            fails |= _pinched(linkage, points)
        self.codes = np.where(fails, OUTSIDE, np.where(holds, INSIDE, STRADDLES)).astype(np.uint8)

    def rates(
        self, velocities: Mapping[str, Point], pairs: bool = True, det_sign: int = 0
    ) -> list[tuple[NDArray[np.bool_], NDArray[np.bool_], Interval]]:
        """For each constraint that may be active in some box: where it may be
        active at a lower bound (it is kept when its rate is at least 0), at an
        upper bound (kept when at most 0), and an enclosure of its rate when the
        named points move at ``velocities`` (enclosures, per point). With
        ``pairs``, also the sides that keep overlapping links apart where they
        may touch (:meth:`_overlap`): one way among others to keep them apart;
        with ``det_sign`` (+-1), those of the configurations with det A of that
        sign (:meth:`_signed_pairs`)."""
        out = []
        pts = self._points
        for (a, b), (c, d), rise, fall in self._angles:
            if not (rise.any() or fall.any()):
                continue
            rate = _turn_rate(_minus(pts[d], pts[c]), _minus(velocities[d], velocities[c]))
            rate = rate - _turn_rate(_minus(pts[b], pts[a]), _minus(velocities[b], velocities[a]))
            out.append((rise, fall, rate))
        for index, (end, s0, s1, _) in enumerate(self._distances):
            near, t, q = self._closest(index)
            if not near.any():
                continue
            still = fixed_point((0.0, 0.0), near.shape[0])
            o_rate = velocities[end] if isinstance(end, str) else still
            one_minus = 1.0 - t
            move = (
                one_minus * velocities[s0][0] + t * velocities[s1][0] - o_rate[0],
                one_minus * velocities[s0][1] + t * velocities[s1][1] - o_rate[1],
            )
            rate = (q[0] * move[0] + q[1] * move[1]) * 2.0
            out.append((near, np.zeros(near.shape[0], dtype=bool), rate))
        if not pairs:
            overlaps: list[list[_Option]] = []
        elif det_sign and self._det_known:
            overlaps = [options for _, options in self._signed_pairs(det_sign)]
        else:
            overlaps = self._overlaps
        for options in overlaps:
            for terms, mask in options:
                if not mask.any():
                    continue
                for point, line, sign in terms:
                    rate = self._side_rate(point, line, velocities)
                    out.append((mask & (sign > 0), mask & (sign < 0), rate))
        return out

    def _side_rate(
        self, point: str, line: tuple[str, str], velocities: Mapping[str, Point]
    ) -> Interval:
        """The rate of ``(l1 - l0) x (point - l0)`` when the named points move at
        ``velocities``."""
        pts = self._points
        l0, l1 = line
        # (v1 - v0) x (p - l0) + (l1 - l0) x (vp - v0), one term per velocity
        # (a turning point's unbounded rate then appears once)
        return (
            cross_velocity(velocities[l1], _minus(pts[point], pts[l0]))
            + cross_velocity(velocities[l0], _minus(pts[l1], pts[point]))
            + cross_velocity(velocities[point], _minus(pts[l0], pts[l1]))
        )

    def _closest(self, index: int) -> tuple[NDArray[np.bool_], Interval, Point]:
        """Distance ``index``: where it may be active, and the parameter and
        offset of the closest point (computed once)."""
        if index not in self._cache:
            end, s0, s1, active = self._distances[index]
            pts = self._points
            o = pts[end] if isinstance(end, str) else end
            t, q = _closest(o, pts[s0], pts[s1])
            if isinstance(end, str):
                # an end point certainly off the other link over the box needs no rate
                with np.errstate(invalid="ignore"):
                    active = active & ~((iv.square(q[0]) + iv.square(q[1])).lo > 0)
            self._cache[index] = (active, t, q)
        return self._cache[index]

    def kept(self, velocities: Mapping[str, Point], det_sign: int = 0) -> NDArray[np.bool_]:
        """Where the motion at ``velocities`` certainly keeps every constraint that
        may be active: each one's rate is certainly of the safe sign, and each
        pair of links that may touch stays apart (:meth:`_apart_kept`).

        ``det_sign`` (+-1), when given, says that only configurations with det A
        of that sign are moved: a pair of links whose sides that sign fixes
        (:attr:`Linkage.det_sides`) is then apart at all of them, or at none
        (nothing to keep)."""
        n = self.codes.shape[0]
        ok = np.ones(n, dtype=bool)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            for rise, fall, rate in self.rates(velocities, pairs=False):
                ok &= (~rise | (rate.lo >= 0)) & (~fall | (rate.hi <= 0))
            for index, ((first, second, active, fold_apart), options) in enumerate(
                zip(self._pairs, self._overlaps, strict=True)
            ):
                if not active.any():
                    continue
                if det_sign and self._det_known:
                    active, options = self._signed_pairs(det_sign)[index]
                # any one of these keeps the pair apart
                apart = fold_apart | self._apart_kept(first, second, velocities)
                for terms, mask in options:
                    if not mask.any():
                        continue
                    holds = mask.copy()
                    for point, line, sign in terms:
                        rate = self._side_rate(point, line, velocities)
                        holds &= np.where(sign > 0, rate.lo >= 0, rate.hi <= 0)
                    apart |= holds
                ok &= ~active | apart
            if det_sign in self._void:
                # no configuration to keep
                ok |= self._void[det_sign]
        return ok

    def _signed_pairs(self, det_sign: int) -> list[tuple[NDArray[np.bool_], list[_Option]]]:
        """Every pair for the configurations with det A of sign ``det_sign`` alone,
        off the folds: where it may still touch, and the ways to keep it apart
        (:meth:`_overlap`); computed once per sign, with :attr:`_void`, the boxes
        where no such configuration keeps all links apart.

        Let S be the configurations of a box that keep all links apart. A pair
        kept apart by one side alone (a one-term option) is apart exactly where
        that side has its sign, so every configuration of S has it: a *fact*. A
        two-term option holds one of two cases (the first term's side has its
        sign, or the second's); a case whose side a fact gives the other sign
        holds nowhere in S, so the other term alone keeps the pair apart there
        (one more fact). Along a motion that checks every term kept, a
        configuration of S has all facts until it first leaves S, and each term
        it checks keeps its strict sign up to that moment: the pair stays apart.
        Nothing here drops a check, so facts may come from any pair.

        The box is void (S empty) where two facts require one side with both
        signs, where neither case of a two-term option can hold, or where, with
        the facts as known sides (:meth:`_side`), some pair certainly crosses.
        """
        if det_sign in self._signed_list:
            return self._signed_list[det_sign]
        pairs = []
        for first, second, active, _ in self._pairs:
            decided = self._pair_code(first, second, det_sign) != STRADDLES
            overlap = self._overlap(first, second, active & ~decided, det_sign, off_fold=True)
            decided |= overlap.codes != STRADDLES
            active = active & ~decided
            pairs.append((active, [(terms, m & active) for terms, m in overlap.sides]))
        void = np.zeros(self._shape, dtype=bool)
        facts: _Facts = {}
        for options in (options for _, options in pairs):
            for terms, mask in options:
                if len(terms) == 1:
                    _learn(facts, *terms[0], mask)
        for _ in range(len(pairs) + 1):
            grown = dict(facts)
            narrowed = []
            for active, options in pairs:
                new: list[_Option] = []
                for terms, mask in options:
                    if len(terms) != 2:
                        new.append((terms, mask))
                        continue
                    first_off = mask & _against(facts, *terms[0])
                    second_off = mask & _against(facts, *terms[1])
                    void |= first_off & second_off
                    new.append((terms, mask & ~first_off & ~second_off))
                    for term, only in (
                        (terms[1], first_off & ~second_off),
                        (terms[0], second_off & ~first_off),
                    ):
                        if only.any():
                            _learn(grown, *term, only)
                            new.append(([term], only))
                narrowed.append((active, new))
            pairs = narrowed
            if _same_facts(grown, facts):
                break
            facts = grown
        for up, down in facts.values():
            void |= np.asarray(up & down)
        if any(active.any() for active, _ in pairs):
            void |= self._three_turns(det_sign, facts)
        if facts:
            for (first, second, _, _), (active, _) in zip(self._pairs, pairs, strict=True):
                open_ = active & ~void
                if not open_.any():
                    continue
                void |= open_ & (self._pair_code(first, second, det_sign, facts) == OUTSIDE)
                overlap = self._overlap(first, second, open_, det_sign, True, facts)
                void |= open_ & (overlap.codes == OUTSIDE)
        self._signed_list[det_sign] = pairs
        self._void[det_sign] = void
        return pairs

    def _three_turns(self, det_sign: int, facts: _Facts) -> NDArray[np.bool_]:
        """Boxes where the known turns of the named points contradict each other.

        For points X, Y, Z, W with ``u = Y - X``, ``d = Z - X``, ``e = W - X``:
        ``(d x e) |u|^2 = (d . u)(u x e) - (u x d)(e . u)``. Where the turns
        ``u x e`` and ``u x d`` have known signs (:meth:`_side`: from the branches
        off the folds, the sign of det A, the ``facts``, or the enclosures) and
        the dot products certain signs, the right side may have a certain sign;
        a known sign of ``d x e`` opposite to it leaves no configuration.
        Only with at most six named points (the triples grow as their cube)."""
        names = sorted(self._points)
        out = np.zeros(self._shape, dtype=bool)
        if len(names) > 6:
            return out
        # the sign classes of every turn (x, y, z) -> (> 0, < 0) per box
        turn: dict[tuple[str, str, str], tuple[NDArray[np.bool_], NDArray[np.bool_]]] = {}
        for x, y, z in itertools.combinations(names, 3):
            up = np.zeros(self._shape, dtype=bool)
            down = np.zeros(self._shape, dtype=bool)
            for (a, b, c), flip in _readings(x, y, z):
                side = self._side(c, (a, b), det_sign, True, facts)
                positive, negative = side.lo > 0, side.hi < 0
                up |= positive if flip > 0 else negative
                down |= negative if flip > 0 else positive
            for (a, b, c), flip in _readings(x, y, z):
                turn[a, b, c] = (up, down) if flip > 0 else (down, up)
        pts = self._points

        dots: dict[tuple[str, str, str], tuple[NDArray[np.bool_], ...]] = {}

        def dot(p: str, q: str, o: str) -> tuple[NDArray[np.bool_], ...]:
            """The sign classes of ``(p - o) . (q - o)``: > 0, < 0, >= 0, <= 0."""
            key = (min(p, q), max(p, q), o)
            if key not in dots:
                u, v = _minus(pts[p], pts[o]), _minus(pts[q], pts[o])
                value = u[0] * v[0] + u[1] * v[1]
                dots[key] = (value.lo > 0, value.hi < 0, value.lo >= 0, value.hi <= 0)
            return dots[key]

        with np.errstate(invalid="ignore", over="ignore"):
            for x in names:
                others = [n for n in names if n != x]
                for y in others:
                    rest = [n for n in others if n != y]
                    for z, w in itertools.combinations(rest, 2):
                        du_pos, du_neg, du_nn, du_np = dot(z, y, x)
                        eu_pos, eu_neg, eu_nn, eu_np = dot(w, y, x)
                        ue_pos, ue_neg = turn[x, y, w]
                        ud_pos, ud_neg = turn[x, y, z]
                        # first term (d . u)(u x e), second -(u x d)(e . u)
                        one_pos = (du_pos & ue_pos) | (du_neg & ue_neg)
                        one_neg = (du_pos & ue_neg) | (du_neg & ue_pos)
                        one_nn = one_pos | (du_nn & ue_pos) | (du_np & ue_neg)
                        one_np = one_neg | (du_nn & ue_neg) | (du_np & ue_pos)
                        two_pos = (ud_pos & eu_neg) | (ud_neg & eu_pos)
                        two_neg = (ud_pos & eu_pos) | (ud_neg & eu_neg)
                        two_nn = two_pos | (ud_pos & eu_np) | (ud_neg & eu_nn)
                        two_np = two_neg | (ud_pos & eu_nn) | (ud_neg & eu_np)
                        de_pos, de_neg = turn[x, z, w]
                        forced_pos = (one_pos & two_nn) | (one_nn & two_pos)
                        forced_neg = (one_neg & two_np) | (one_np & two_neg)
                        out |= (forced_pos & de_neg) | (forced_neg & de_pos)
        return out

    def void(self, det_sign: int) -> NDArray[np.bool_]:
        """Boxes where no configuration off the folds with det A of sign
        ``det_sign`` (+-1) keeps every pair of links apart: the sides that the
        pairs require contradict each other (see :meth:`_signed_pairs`)."""
        if not self._det_known:
            return np.zeros(self._shape, dtype=bool)
        self._signed_pairs(det_sign)
        return self._void[det_sign]

    def excluded(self, det_sign: int) -> NDArray[np.bool_]:
        """Boxes where no configuration with det A of sign ``det_sign`` (+-1)
        satisfies the constraints: one is certainly violated, or two links
        certainly cross once the sides that sign fixes are known
        (:attr:`Linkage.det_sides`)."""
        out = np.asarray(self.codes == OUTSIDE, dtype=bool)
        if not self._det_known:
            return out
        with np.errstate(invalid="ignore", over="ignore"):
            for first, second, active, _ in self._pairs:
                open_ = active & ~out
                if not open_.any():
                    continue
                code = self._pair_code(first, second, det_sign)
                out |= open_ & (code == OUTSIDE)
                overlap = self._overlap(first, second, open_ & (code == STRADDLES), det_sign)
                out |= open_ & (overlap.codes == OUTSIDE)
        return out

    def _pair_code(
        self,
        first: tuple[str, str],
        second: tuple[str, str],
        det_sign: int = 0,
        facts: _Facts | None = None,
    ) -> NDArray[np.uint8]:
        """:func:`segment_codes` of two links, with the sides known (see :meth:`_side`)."""
        return _crossing_codes(
            self._side(second[0], first, det_sign, facts=facts),
            self._side(second[1], first, det_sign, facts=facts),
            self._side(first[0], second, det_sign, facts=facts),
            self._side(first[1], second, det_sign, facts=facts),
        )

    def _side(
        self,
        point: str,
        link: tuple[str, str],
        det_sign: int = 0,
        off_fold: bool = False,
        facts: _Facts | None = None,
    ) -> Interval:
        """``(l1 - l0) x (point - l0)`` over the boxes; a side known from the
        posture (:attr:`Linkage.ends`) replaces it by +-1 where the leg does not
        fold (everywhere with ``off_fold``: for the configurations off the fold
        alone), and one known from the sign of det A (:attr:`Linkage.det_sides`)
        everywhere, when ``det_sign`` (+-1) is given; ``facts`` give more signs
        (see :meth:`_signed_pairs`)."""
        pts = self._points
        out = _cross(_minus(pts[link[1]], pts[link[0]]), _minus(pts[point], pts[link[0]]))
        for key, flip in (((point, link), 1), ((point, link[::-1]), -1)):
            if key in self._known:
                side, folds = self._known[key]
                if off_fold:
                    folds = np.zeros_like(folds)
                out = Interval(
                    np.where(folds, out.lo, flip * side), np.where(folds, out.hi, flip * side)
                )
            if det_sign and key in self._det_known:
                fixed = float(flip * self._det_known[key] * det_sign)
                out = Interval(np.full(self._shape, fixed))
        if facts:
            key, flip = _oriented(point, link)
            if key in facts:
                up, down = facts[key]
                value = np.where(up, flip, np.where(down, -flip, np.nan))
                known = ~np.isnan(value)
                out = Interval(np.where(known, value, out.lo), np.where(known, value, out.hi))
        return out

    def _overlap(
        self,
        first: tuple[str, str],
        second: tuple[str, str],
        where: NDArray[np.bool_],
        det_sign: int = 0,
        off_fold: bool = False,
        facts: _Facts | None = None,
    ) -> _Overlap:
        """Two links nearly along one line, overlapping: whether they are apart
        comes down to the sides of their end points.

        Let e1 be an end of the first link (f1 its other end) and e2 one of the
        second (f2 its other end), and u a direction along which both links
        point the same way, ordered ``f2 < e1 < e2 < f1``. Over that order each
        link's line is the graph of an affine function of the abscissa along u
        (l1, l2), and the links share the abscissae between e1 and e2: they are
        apart exactly where ``delta = l1 - l2`` has one strict sign at e1 and at
        e2. The sign of delta at each of the four points is a side:
        ``delta(e1) ~ side(e1, f2 e2)``, ``delta(e2) ~ -side(e2, e1 f1)``,
        ``delta(f1) ~ side(f1, f2 e2)``, ``delta(f2) ~ -side(f2, e1 f1)``
        (:meth:`_side`, with the sides the posture and ``det_sign`` fix). Since
        delta is affine, delta(e2) lies strictly between delta(e1) and delta(f1),
        and delta(e1) between delta(f2) and delta(e2): where delta(e2) and
        delta(f1) have opposite signs, delta(e1) has delta(e2)'s (apart), and
        likewise at the other end. Where one of delta(e1), delta(e2) has a certain
        sign and nothing else decides, the constraint is that the other has that
        sign: kept along a motion by that side's rate (:meth:`rates`).

        Only boxes of ``where`` are considered; u is the midpoint of the
        enclosure of ``f1 - e1``. With ``off_fold`` the sides a branch fixes are
        taken as known where the leg may fold too: the answers then hold for
        the configurations off the fold, which is what a flow that keeps them
        off it needs (a configuration on the fold whose known side is 0 touches
        the other link in a strict sign test, so it is never one that starts
        apart; the two convexity tests hold with that side 0 as well).
        """
        pts = self._points
        codes = np.full(self._shape, STRADDLES, dtype=np.uint8)
        covered = np.zeros(self._shape, dtype=bool)
        sides: list[_Option] = []
        todo = where.copy()

        def positive(x: Interval) -> NDArray[np.bool_]:
            return np.asarray(x.lo > 0, dtype=bool)

        def negative(x: Interval) -> NDArray[np.bool_]:
            return np.asarray(x.hi < 0, dtype=bool)

        with np.errstate(invalid="ignore", over="ignore"):
            for (e1, f1), (e2, f2) in itertools.product(
                (first, first[::-1]), (second, second[::-1])
            ):
                if not todo.any():
                    break
                w = _minus(pts[f1], pts[e1])
                u = (np.nan_to_num(w[0].mid), np.nan_to_num(w[1].mid))

                def along(p: Point, u: tuple[Array, Array] = u) -> Interval:
                    return p[0] * u[0] + p[1] * u[1]

                ordered = todo.copy()
                for v in (
                    _minus(pts[e1], pts[f2]),
                    _minus(pts[e2], pts[e1]),
                    _minus(pts[f1], pts[e2]),
                ):
                    ordered &= along(v).lo > 0
                if not ordered.any():
                    continue
                at_e1 = self._side(e1, (f2, e2), det_sign, off_fold, facts)
                at_e2 = -self._side(e2, (e1, f1), det_sign, off_fold, facts)
                at_f1 = self._side(f1, (f2, e2), det_sign, off_fold, facts)
                at_f2 = -self._side(f2, (e1, f1), det_sign, off_fold, facts)
                apart = (
                    (positive(at_e1) & positive(at_e2))
                    | (negative(at_e1) & negative(at_e2))
                    | (positive(at_e2) & negative(at_f1))
                    | (negative(at_e2) & positive(at_f1))
                    | (positive(at_e1) & negative(at_f2))
                    | (negative(at_e1) & positive(at_f2))
                    | (positive(at_f2) & positive(at_f1))
                    | (negative(at_f2) & negative(at_f1))
                )
                meet = ((at_e1.lo >= 0) & (at_e2.hi <= 0)) | ((at_e1.hi <= 0) & (at_e2.lo >= 0))
                codes[ordered & apart] = INSIDE
                codes[ordered & ~apart & meet] = OUTSIDE
                left = ordered & ~apart & ~meet
                # one end's sign known: the other end's side must match it
                for known, point, line, flip in (
                    (at_e2, e1, (f2, e2), 1),
                    (at_e1, e2, (e1, f1), -1),
                ):
                    sure = left & (positive(known) | negative(known))
                    if sure.any():
                        sign = flip * np.where(positive(known), 1, -1)
                        covered |= sure
                        sides.append(([(point, line, sign)], sure))
                        left &= ~sure
                # the outer ends' signs known and opposite: delta vanishes once
                # between them, and the links are apart while that root stays
                # off [e1, e2]: delta(e1) keeps delta(f1)'s sign, or delta(e2)
                # keeps delta(f2)'s (both kept, as either case may hold)
                sure = left & (
                    (positive(at_f2) & negative(at_f1)) | (negative(at_f2) & positive(at_f1))
                )
                if sure.any():
                    up = np.where(positive(at_f1), 1, -1)
                    covered |= sure
                    sides.append(([(e1, (f2, e2), up), (e2, (e1, f1), up)], sure))
                todo &= ~ordered
        return _Overlap(codes, covered, sides)

    def _across_fold(
        self, first: tuple[str, str], second: tuple[str, str]
    ) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        """Where the links are apart at every configuration off the fold, and
        where they certainly meet, from a side known from the posture.

        An end e of one link (f its other end) lies on the branch's side of the
        other link's line [c, d] off the fold and on it at the fold. Where f is
        certainly on one side of that line and c, d certainly on both sides of
        the line of [e, f], the links are apart exactly where e is on f's side
        (on the line, e is where the two lines meet, inside [c, d]): at every
        configuration off the fold when that is the branch's side, at none when
        it is the other."""
        pts = self._points
        apart = np.zeros(self._shape, dtype=bool)
        cross = np.zeros(self._shape, dtype=bool)
        for (e, f), line in (
            (first, second),
            (first[::-1], second),
            (second, first),
            (second[::-1], first),
        ):
            key = (e, line) if (e, line) in self._known else (e, line[::-1])
            if key not in self._known:
                continue
            side, folds = self._known[key]
            side = side if key[1] == line else -side
            other = self._side(f, line)
            own = _minus(pts[f], pts[e])
            across = folds & _opposite(
                _cross(own, _minus(pts[line[0]], pts[e])), _cross(own, _minus(pts[line[1]], pts[e]))
            )
            same = (other.lo > 0) if side > 0 else (other.hi < 0)
            differ = (other.hi < 0) if side > 0 else (other.lo > 0)
            apart |= across & same
            cross |= across & differ
        return apart, cross

    def _apart_kept(
        self, first: tuple[str, str], second: tuple[str, str], velocities: Mapping[str, Point]
    ) -> NDArray[np.bool_]:
        """Where two links that may touch certainly stay apart along the motion.

        Either an end e of one link (f its other end) meets the other link's
        line across it: f certainly on one side of the line of the other link
        [c, d], and c, d certainly on both sides of the line of [e, f]. Then the
        links are apart exactly where e is on f's side, and they stay so where
        ``side(f) * (d - c) x (e - c)`` never decreases. Or each of the four
        distances from an end to the other link is certainly positive over the
        box or never decreases (see the module's notes)."""
        pts = self._points
        n = self.codes.shape[0]
        ok = np.zeros(n, dtype=bool)
        for (e, f), (c, d) in (
            (first, second),
            (first[::-1], second),
            (second, first),
            (second[::-1], first),
        ):
            line = _minus(pts[d], pts[c])
            side = _cross(line, _minus(pts[f], pts[c]))
            own = _minus(pts[f], pts[e])
            across = _opposite(
                _cross(own, _minus(pts[c], pts[e])), _cross(own, _minus(pts[d], pts[e]))
            )
            up, down = across & (side.lo > 0), across & (side.hi < 0)
            if not (up | down).any():
                continue
            rate = _cross(_minus(velocities[d], velocities[c]), _minus(pts[e], pts[c]))
            rate = rate + _cross(line, _minus(velocities[e], velocities[c]))
            ok |= (up & (rate.lo >= 0)) | (down & (rate.hi <= 0))
        # the four distances from an end to the other link
        spread = np.ones(n, dtype=bool)
        for end, (s0, s1) in (
            (first[0], second),
            (first[1], second),
            (second[0], first),
            (second[1], first),
        ):
            t, q = _closest(pts[end], pts[s0], pts[s1])
            near = ~((iv.square(q[0]) + iv.square(q[1])).lo > 0)
            if not near.any():
                continue
            one_minus = 1.0 - t
            move = (
                one_minus * velocities[s0][0] + t * velocities[s1][0] - velocities[end][0],
                one_minus * velocities[s0][1] + t * velocities[s1][1] - velocities[end][1],
            )
            spread &= ~near | ((q[0] * move[0] + q[1] * move[1]).lo >= 0)
        return ok | spread


def _pinched(linkage: Linkage, points: Mapping[str, Point]) -> NDArray[np.bool_]:
    """Where two links X-J and J-Y that share a joint J certainly cannot both miss
    a third link [c, d] that shares no joint with them.

    That is so where X and Y lie strictly on both sides of the line of [c, d],
    and c, d strictly on both sides of the lines of X-J and of J-Y: wherever J
    is, one of the two links crosses [c, d] (J on X's side: J-Y crosses; on Y's
    side: X-J; on the line: J is on [c, d]). Each pair alone may touch there,
    so :func:`segment_codes` cannot tell.
    """
    n = next(iter(points.values()))[0].lo.shape
    out = np.zeros(n, dtype=bool)
    ends: dict[str, list[str]] = {}
    for a, b in linkage.links:
        ends.setdefault(a, []).append(b)
        ends.setdefault(b, []).append(a)
    for joint, others in ends.items():
        for i, x in enumerate(others):
            for y in others[i + 1 :]:
                for c, d in linkage.links:
                    if {c, d} & {joint, x, y}:
                        continue
                    line = _minus(points[d], points[c])
                    split = _opposite(
                        _cross(line, _minus(points[x], points[c])),
                        _cross(line, _minus(points[y], points[c])),
                    )
                    for other in (x, y):
                        own = _minus(points[joint], points[other])
                        split &= _opposite(
                            _cross(own, _minus(points[c], points[other])),
                            _cross(own, _minus(points[d], points[other])),
                        )
                    out |= split
    return out


def _opposite(s: Interval, t: Interval) -> NDArray[np.bool_]:
    """Where s and t certainly have strictly opposite signs."""
    return np.asarray(((s.lo > 0) & (t.hi < 0)) | ((s.hi < 0) & (t.lo > 0)), dtype=bool)


def _turn_rate(u: Point, du: Point) -> Interval:
    """The rate of the direction of a vector u moving at du: ``(u x du) / |u|^2``."""
    return _cross(u, du) / (iv.square(u[0]) + iv.square(u[1]))


def fixed_point(xy: Sequence[float], n: int) -> Point:
    """A point fixed to the base, as enclosures over n boxes."""
    return Interval(np.full(n, float(xy[0]))), Interval(np.full(n, float(xy[1])))
