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
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .. import intervals as iv
from ..intervals import Interval
from ..limits import INSIDE, OUTSIDE, STRADDLES, JointLimit

__all__ = [
    "Constraints",
    "Linkage",
    "Obstacle",
    "constraint_codes",
    "fixed_point",
    "segment_codes",
    "vector_angle",
]

#: a point of the linkage over n boxes: (x, y) enclosures
Point = tuple[Interval, Interval]


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
    """

    links: tuple[tuple[str, str], ...]
    passive: Mapping[str, tuple[tuple[str, str], tuple[str, str]]]


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


def _disk_codes(c: Point, p: Point, obstacle: Obstacle) -> NDArray[np.uint8]:
    """Whether the segment [c, p] certainly misses the disk (INSIDE: the constraint
    holds), certainly meets it (OUTSIDE), or either (STRADDLES)."""
    ox, oy = obstacle.center
    u = _minus(p, c)
    w = (ox - c[0], oy - c[1])
    length2 = iv.square(u[0]) + iv.square(u[1])
    dot = w[0] * u[0] + w[1] * u[1]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = _clamp01(dot / length2)
    t = Interval(np.where(length2.lo > 0, t.lo, 0.0), np.where(length2.lo > 0, t.hi, 1.0))
    qx, qy = c[0] + t * u[0] - ox, c[1] + t * u[1] - oy
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
    n = next(iter(points.values()))[0].lo.shape
    holds = np.ones(n, dtype=bool)
    fails = np.zeros(n, dtype=bool)

    def meet(codes: NDArray[np.uint8]) -> None:
        nonlocal holds, fails
        holds &= codes == INSIDE
        fails |= codes == OUTSIDE

    for name, limit in constraints.passive.items():
        (a, b), (c, d) = linkage.passive[name]
        first = vector_angle(*_minus(points[b], points[a]))
        second = vector_angle(*_minus(points[d], points[c]))
        meet(limit.classify(second - first))
    for obstacle in constraints.obstacles:
        for a, b in linkage.links:
            meet(_disk_codes(points[a], points[b], obstacle))
    if constraints.collisions:
        for i, (a, b) in enumerate(linkage.links):
            for c, d in linkage.links[i + 1 :]:
                if {a, b} & {c, d}:
                    continue  # links sharing a joint
                meet(segment_codes(points[a], points[b], points[c], points[d]))
    return np.where(fails, OUTSIDE, np.where(holds, INSIDE, STRADDLES)).astype(np.uint8)


def fixed_point(xy: Sequence[float], n: int) -> Point:
    """A point fixed to the base, as enclosures over n boxes."""
    return Interval(np.full(n, float(xy[0]))), Interval(np.full(n, float(xy[1])))
