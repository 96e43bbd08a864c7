"""An independent pointwise reference for the 3-RRR and the 3-RPR with passive
limits, obstacles and link collisions.

Each leg is solved in closed form here (the elbow of a 3-RRR leg as an
intersection of two circles, a 3-RPR leg's length as a distance), the points of
the linkage are laid out, and every constraint is checked in plain floats:
joint limits, passive angles (wrapped to ``(-pi, pi]``), segment-disk distances
and segment crossings. Nothing here comes from the library.

Names follow the modules' notation: base joints ``A1..A3``, elbows ``C1..C3``
(3-RRR), platform joints ``B1..B3``; the passive joints are the elbows ``C_i``
(from ``A_i C_i`` to ``C_i B_i``) and the platform joints ``B_i`` (from the
leg's last link to the side ``B_i B_{i+1}``) of a 3-RRR, the base joints ``A_i``
(from the side ``A_i A_{i+1}`` to ``A_i B_i``) and the platform joints of a 3-RPR.
"""

from __future__ import annotations

import itertools

import numpy as np


def wrap(a):
    """Angles wrapped to ``(-pi, pi]`` (as far as floats tell)."""
    return np.pi - np.mod(np.pi - a, 2 * np.pi)


def turned_within(angle, lo, hi):
    """Whether each angle, moved by whole turns into ``[lo, lo + 2 pi)``, is at most ``hi``."""
    return lo + np.mod(angle - lo, 2 * np.pi) <= hi


def direction(u):
    return np.arctan2(u[..., 1], u[..., 0])


def cross(u, v):
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def segment_point_distance(c, p, o):
    """Distance from the points o to the segments [c, p] (rows, broadcast)."""
    u = p - c
    length2 = (u * u).sum(-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.clip(np.where(length2 > 0, ((o - c) * u).sum(-1) / length2, 0.0), 0.0, 1.0)
    q = c + t[..., None] * u - o
    return np.hypot(q[..., 0], q[..., 1])


def segments_cross(a, b, c, d):
    """Whether the segments [a, b] and [c, d] cross properly (each one's ends strictly
    on both sides of the other's line)."""
    o1, o2 = cross(b - a, c - a), cross(b - a, d - a)
    o3, o4 = cross(d - c, a - c), cross(d - c, b - c)
    return (o1 * o2 < 0) & (o3 * o4 < 0)


def platform_joints(platform, poses):
    """``B_i = P + R(phi) b_i`` at poses (m, 3): list of (m, 2)."""
    x, y, phi = poses[:, 0], poses[:, 1], poses[:, 2]
    c, s = np.cos(phi), np.sin(phi)
    return [np.stack([x + c * bx - s * by, y + s * bx + c * by], -1) for bx, by in platform]


def rrr_elbows(base, platform, proximal, distal, poses):
    """Per leg, the two elbows of each pose (intersections of the circle of radius
    l1 about A and l2 about B), shape (m, 2, 2): [elbow on the right of A->B, on
    the left], NaN where the circles do not meet; and the platform joints."""
    joints = platform_joints(platform, poses)
    elbows = []
    for a, b, l1, l2 in zip(base, joints, proximal, distal, strict=True):
        a = np.asarray(a, dtype=float)
        v = b - a
        d = np.hypot(v[:, 0], v[:, 1])
        with np.errstate(invalid="ignore", divide="ignore"):
            along = (l1 * l1 - l2 * l2 + d * d) / (2 * d)
            h = np.sqrt(l1 * l1 - along * along)
            e = v / d[:, None]
        n = np.stack([-e[:, 1], e[:, 0]], -1)  # left of A->B
        right = a + along[:, None] * e - h[:, None] * n
        left = a + along[:, None] * e + h[:, None] * n
        elbows.append(np.stack([right, left], axis=1))
    return elbows, joints


def rrr_configurations(m, poses):
    """The eight postures of a 3-RRR at poses: for each posture (branches b: 0 puts
    the platform joint on the right of A_i C_i, 1 on the left), the actuated angles
    (m, 3) and the named points."""
    elbows, joints = rrr_elbows(m.base, m.platform, m.proximal, m.distal, poses)
    out = []
    for branches in itertools.product((0, 1), repeat=3):
        # B on the right of A->C: the elbow on the left of A->B
        points = {}
        angles = []
        for i, b in enumerate(branches):
            c = elbows[i][:, 1 - b]
            a = np.asarray(m.base[i], dtype=float)
            points[f"A{i + 1}"] = np.broadcast_to(a, c.shape)
            points[f"C{i + 1}"] = c
            points[f"B{i + 1}"] = joints[i]
            angles.append(direction(c - a))
        out.append((np.stack(angles, -1), points))
    return out


def rpr_configurations(m, poses):
    """The one posture of a 3-RPR: the lengths (m, 3) and the named points."""
    joints = platform_joints(m.platform, poses)
    points = {}
    lengths = []
    for i, b in enumerate(joints):
        a = np.asarray(m.base[i], dtype=float)
        points[f"A{i + 1}"] = np.broadcast_to(a, b.shape)
        points[f"B{i + 1}"] = b
        lengths.append(np.hypot(*(b - a).T))
    return [(np.stack(lengths, -1), points)]


def configurations(m, poses):
    return rrr_configurations(m, poses) if m.name == "3-RRR" else rpr_configurations(m, poses)


def links(kind):
    """The moving links of a mechanism, as pairs of names."""
    sides = [("B1", "B2"), ("B2", "B3"), ("B3", "B1")]
    if kind == "3-RRR":
        return [(f"A{i}", f"C{i}") for i in "123"] + [(f"C{i}", f"B{i}") for i in "123"] + sides
    return [(f"A{i}", f"B{i}") for i in "123"] + sides


def passive_angles(kind, points):
    """Each passive joint's angle (wrapped), by name."""
    nxt = {"1": "2", "2": "3", "3": "1"}
    p = points
    out = {}
    for i in "123":
        j = nxt[i]
        side = p[f"B{j}"] - p[f"B{i}"]
        if kind == "3-RRR":
            proximal = p[f"C{i}"] - p[f"A{i}"]
            distal = p[f"B{i}"] - p[f"C{i}"]
            out[f"C{i}"] = wrap(direction(distal) - direction(proximal))
            out[f"B{i}"] = wrap(direction(side) - direction(distal))
        else:
            leg = p[f"B{i}"] - p[f"A{i}"]
            base_side = p[f"A{j}"] - p[f"A{i}"]
            out[f"A{i}"] = wrap(direction(leg) - direction(base_side))
            out[f"B{i}"] = wrap(direction(side) - direction(leg))
    return out


def valid(kind, limits, joints, points, passive=None, obstacles=(), collisions=False):
    """Whether each configuration is within the joint limits and satisfies every
    constraint; NaN joints (unreachable) are not valid."""
    ok = np.isfinite(joints).all(-1)
    for i, (lo, hi) in enumerate(limits):
        if lo is not None:
            # a revolute joint's angle is met modulo a turn (limits may cross pi)
            ok &= turned_within(joints[:, i], lo, hi) if kind == "3-RRR" else (
                (joints[:, i] >= lo) & (joints[:, i] <= hi)
            )
    angles = passive_angles(kind, points)
    for name, (lo, hi) in (passive or {}).items():
        ok &= turned_within(angles[name], lo, hi)
    segs = links(kind)
    for center, radius in obstacles:
        o = np.asarray(center, dtype=float)
        for s, t in segs:
            ok &= segment_point_distance(points[s], points[t], o) > radius
    if collisions:
        for (a, b), (c, d) in itertools.combinations(segs, 2):
            if {a, b} & {c, d}:
                continue
            ok &= ~segments_cross(points[a], points[b], points[c], points[d])
    return ok


def joint_limits(m):
    """The joint limits as (lo, hi) pairs, (None, None) where unlimited."""
    return [(None, None) if lim.periodic else (lim.lo, lim.hi) for lim in m.limits]


def valid_postures(m, poses, **constraints):
    """(m, n_postures): whether each posture at each pose is a valid configuration,
    and the joints (m, n_postures, 3)."""
    out, joints = [], []
    for q, points in configurations(m, poses):
        with np.errstate(invalid="ignore"):
            out.append(valid(m.name, joint_limits(m), q, points, **constraints))
        joints.append(q)
    return np.stack(out, -1), np.stack(joints, 1)


def det_a(m, poses, joints):
    """det A of each configuration (rows ``(B - C, (B - C) x R b)``, C the elbow of
    a 3-RRR or the base joint of a 3-RPR), shape (m,)."""
    x, y, phi = poses[:, 0], poses[:, 1], poses[:, 2]
    c, s = np.cos(phi), np.sin(phi)
    rows = []
    for i in range(3):
        (ax, ay), (bx, by) = m.base[i], m.platform[i]
        rbx, rby = c * bx - s * by, s * bx + c * by
        if m.name == "3-RRR":
            l1 = m.proximal[i]
            ex = x + rbx - (ax + l1 * np.cos(joints[:, i]))
            ey = y + rby - (ay + l1 * np.sin(joints[:, i]))
        else:
            ex, ey = x + rbx - ax, y + rby - ay
        rows.append(np.stack([ex, ey, -ex * rby + ey * rbx], -1))
    return np.linalg.det(np.stack(rows, 1))
