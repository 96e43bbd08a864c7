"""An independent reference for five-bars with passive limits, obstacles and collisions.

A grid over the joint space Q (both actuated joints, wrapped when unlimited):
for each joint vector the two assembly modes give the configurations (the two
intersections of the circles about C and D), each is checked pointwise in
plain floats (joint limits, passive angles, segment-disk distances,
segment-segment crossings), and the valid cells are labelled by their signs:
det A alone (regions) or det A, det B1, det B2 (generalized aspects).
Components are 4-connected cells of one label, glued across the seams of
unlimited joints. Nothing here comes from the library.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage


def _wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def _segment_point_distance(c, p, o):
    u = p - c
    t = np.clip(((o - c) * u).sum(-1) / (u * u).sum(-1), 0.0, 1.0)
    q = c + t[..., None] * u
    return np.hypot(*(q - o).transpose(-1, *range(q.ndim - 1)))


def _cross2(u, v):
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def _segments_cross(a, b, c, d):
    o1, o2 = _cross2(b - a, c - a), _cross2(b - a, d - a)
    o3, o4 = _cross2(d - c, a - c), _cross2(d - c, b - c)
    return (o1 * o2 < 0) & (o3 * o4 < 0)


def configurations(lengths, limits, n):
    """Grid of Q and, per assembly mode, the points and the validity of the
    configuration (ignoring the constraints beyond the joint limits)."""
    L0, L1, L2, L3, L4 = lengths
    axes = []
    for lim in limits:
        lo, hi = (-np.pi, np.pi) if lim is None else lim
        axes.append(lo + (np.arange(n) + 0.5) * (hi - lo) / n)
    t1, t2 = np.meshgrid(*axes, indexing="ij")
    A, B = np.zeros(2), np.array([L0, 0.0])
    C = np.stack([L1 * np.cos(t1), L1 * np.sin(t1)], -1)
    D = np.stack([L0 + L3 * np.cos(t2), L3 * np.sin(t2)], -1)
    cd = D - C
    d = np.hypot(cd[..., 0], cd[..., 1])
    meet = (d > abs(L2 - L4)) & (d < L2 + L4)
    with np.errstate(invalid="ignore", divide="ignore"):
        a = (L2**2 - L4**2 + d**2) / (2 * d)
        h = np.sqrt(np.maximum(L2**2 - a**2, 0.0))
    e = cd / np.where(d > 0, d, 1.0)[..., None]
    normal = np.stack([-e[..., 1], e[..., 0]], -1)
    modes = []
    for s in (1.0, -1.0):
        P = C + a[..., None] * e + s * h[..., None] * normal
        modes.append({"A": A, "B": B, "C": C, "D": D, "P": P, "valid": meet.copy()})
    return (t1, t2), modes


def constrained(mode, passive=None, obstacles=(), collisions=False):
    """Pointwise: whether each configuration of a mode satisfies the constraints."""
    A, B, C, D, P = (mode[k] for k in "ABCDP")
    ok = mode["valid"].copy()
    A = np.broadcast_to(A, C.shape)
    B = np.broadcast_to(B, D.shape)

    def angle(u):
        return np.arctan2(u[..., 1], u[..., 0])

    for name, (lo, hi) in (passive or {}).items():
        first, second = {
            "P": (P - C, P - D),
            "C": (C - A, P - C),
            "D": (D - B, P - D),
        }[name]
        value = _wrap(angle(second) - angle(first))
        ok &= (value >= lo) & (value <= hi)
    links = [(A, C), (C, P), (B, D), (D, P)]
    for center, radius in obstacles:
        o = np.asarray(center, dtype=float)
        for s, t in links:
            ok &= _segment_point_distance(s, t, o) > radius
    if collisions:
        for i, j in ((0, 2), (0, 3), (1, 2)):
            ok &= ~_segments_cross(*links[i], *links[j])
    return ok


def grid_count(lengths, limits, n, aspects, min_cells=1, **constraints):
    """Components of the valid configurations on the grid, by their signs; only
    components of at least ``min_cells`` cells are counted (grid noise aside)."""
    _, modes = configurations(lengths, limits, n)
    total = 0
    sizes = []
    for mode in modes:
        valid = constrained(mode, **constraints)
        A, B, C, D, P = (mode[k] for k in "ABCDP")
        b1 = np.sign(_cross2(C - A, P - C))
        b2 = np.sign(_cross2(D - B, P - D))
        keys = [np.ones_like(b1)] if not aspects else [b1, b2]
        combos = {tuple(k[i, j] for k in keys) for i, j in zip(*np.nonzero(valid), strict=True)}
        for combo in combos:
            mask = valid.copy()
            for k, v in zip(keys, combo, strict=True):
                mask &= k == v
            labels, count = ndimage.label(mask)
            # glue across the seams of unlimited joints
            parent = list(range(count + 1))

            def find(x, parent=parent):
                while parent[x] != x:
                    parent[x] = parent[parent[x]]
                    x = parent[x]
                return x

            for axis, lim in enumerate(limits):
                if lim is not None:
                    continue
                first = np.take(labels, 0, axis=axis)
                last = np.take(labels, -1, axis=axis)
                for x, y in zip(first.ravel(), last.ravel(), strict=True):
                    if x and y:
                        parent[find(x)] = find(y)
            roots = {}
            for lab in range(1, count + 1):
                r = find(lab)
                roots[r] = roots.get(r, 0) + int((labels == lab).sum())
            for size in roots.values():
                sizes.append(size)
                total += size >= min_cells
    return total, sorted(sizes, reverse=True)


def pose_configurations(lengths, pose):
    """Every configuration (C, D) at a pose P: the elbows on the circles about A and
    P (and B and P), up to two each; returns the mode dicts of :func:`constrained`,
    one per combination, with the actuated angles."""
    L0, L1, L2, L3, L4 = lengths
    P = np.asarray(pose, dtype=float)
    out = []

    def elbows(base, r1, r2):
        v = P - base
        d = np.hypot(*v)
        if not abs(r1 - r2) < d < r1 + r2:
            return []
        a = (r1**2 - r2**2 + d**2) / (2 * d)
        h = np.sqrt(max(r1**2 - a**2, 0.0))
        e = v / d
        n = np.array([-e[1], e[0]])
        return [base + a * e + s * h * n for s in (1.0, -1.0)]

    A, B = np.zeros(2), np.array([L0, 0.0])
    for C in elbows(A, L1, L2):
        for D in elbows(B, L3, L4):
            t1 = np.arctan2(C[1], C[0])
            t2 = np.arctan2(D[1], D[0] - L0)
            mode = {"A": A, "B": B, "C": C[None], "D": D[None], "P": P[None],
                    "valid": np.array([True])}  # fmt: skip
            out.append((t1, t2, mode))
    return out
