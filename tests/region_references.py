"""Independent references for counts of regions: closed forms and labelled grids.

The five-bar's regions are the components of
``D = {q : |L2 - L4| < |C(q) - D(q)| < L2 + L4}`` in its joint space, times the
two assembly modes; the biglide's follow in closed form.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from moveability.limits import JointLimit
from moveability.mechanisms import FiveBar, from_spec

# the designs: a five-bar whose assembling pairs are cut by a gap of
# about 0.107 rad, and a biglide with equal legs (two identically singular postures)
GAP_FIVE_BAR = (
    (6.0, 5.0, 6.0, 5.0, 6.0),
    (1.3704384060045658, np.pi),
    (-2.171858256624643, 1.9887034049203582),
)
EQUAL_BIGLIDE = {
    "mechanism": "biglide",
    "parameters": {"L1": 5.0, "L2": 5.0},
    "limits": {"rho1": [-3.0, 8.0], "rho2": [-4.0, -2.0]},
}
THREE_RPR = {
    "mechanism": "3-RPR",
    "parameters": {"base": [[0, 0], [10, 1], [3, 9]], "platform": [[0, 0], [5, -1], [2, 4]]},
    "limits": {"rho1": [4, 14], "rho2": [4, 14], "rho3": [4, 14]},
}


def biglide_count(m) -> int:
    """Regions of a biglide, in closed form.

    det A = y (rho2 - rho1): a region keeps the sign of y (the assembly mode) and
    the side of rho2 - rho1. Its joints lie in D = {|L1 - L2| < |rho1 - rho2| <
    L1 + L2} within the limits' box; each side of D meets the box in a convex set.
    """
    (lo1, hi1), (lo2, hi2) = ((lim.lo, lim.hi) for lim in m.limits)
    a, b = abs(m.lengths[0] - m.lengths[1]), m.lengths[0] + m.lengths[1]
    sides = 0
    for d_lo, d_hi in ((lo1 - hi2, hi1 - lo2), (lo2 - hi1, hi2 - lo1)):  # rho1 - rho2, then -
        sides += max(d_lo, a) < min(d_hi, b)
    return 2 * sides


def five_bar(lengths, lim1, lim2):
    limits = tuple(
        JointLimit.unlimited() if lim is None else JointLimit(*lim) for lim in (lim1, lim2)
    )
    return FiveBar(*lengths, limits=limits)


def joint_space_count(m: FiveBar, n: int) -> int:
    """Regions of a five-bar: components of D on an n x n grid of Q, times 2."""
    L0, L1, L2, L3, L4 = m.lengths
    lo = [lim.lo for lim in m.limits]
    hi = [lim.lo + 2 * np.pi if lim.periodic else lim.hi for lim in m.limits]
    t = [np.linspace(lo[i], hi[i], n + 1) for i in range(2)]
    t1, t2 = np.meshgrid(*[0.5 * (a[1:] + a[:-1]) for a in t], indexing="ij")
    cd = np.hypot(L1 * np.cos(t1) - L0 - L3 * np.cos(t2), L1 * np.sin(t1) - L3 * np.sin(t2))
    labels, count = ndimage.label((cd > abs(L2 - L4)) & (cd < L2 + L4))
    parent = list(range(count + 1))

    def find(x):
        while parent[x] != x:
            x = parent[x]
        return x

    for axis, lim in enumerate(m.limits):
        if lim.periodic:  # glue the two ends of a free joint
            a, b = np.take(labels, 0, axis=axis), np.take(labels, -1, axis=axis)
            for u, v in zip(a[(a > 0) & (b > 0)], b[(a > 0) & (b > 0)], strict=True):
                ru, rv = find(int(u)), find(int(v))
                if ru != rv:
                    parent[max(ru, rv)] = min(ru, rv)
    return 2 * len({find(x) for x in range(1, count + 1)})


def random_biglides(n, seed):
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        lengths = [float(v) for v in np.round(rng.uniform(2.0, 7.0, 2), 1)]
        if len(out) % 3 == 0:
            lengths[1] = lengths[0]  # equal legs: two identically singular postures
        limits = {}
        for name in ("rho1", "rho2"):
            lo = float(np.round(rng.uniform(-8.0, 6.0), 1))
            limits[name] = [lo, lo + float(np.round(rng.uniform(0.5, 10.0), 1))]
        spec = {
            "mechanism": "biglide",
            "parameters": {"L1": lengths[0], "L2": lengths[1]},
            "limits": limits,
        }
        m = from_spec(spec)
        if biglide_count(m):
            out.append(m)
    return out


def joint_space_n_connected(m: FiveBar, nq: int, nx: int) -> tuple[bool, int]:
    """Whether one region of a five-bar holds a configuration of every pose of W,
    on an nx x nx grid of poses (regions as in :func:`joint_space_count`, on an
    nq x nq grid of Q); with the number of grid poses in W."""
    L0, L1, L2, L3, L4 = m.lengths
    lo = np.array([lim.lo for lim in m.limits])
    hi = np.array([lim.lo + 2 * np.pi if lim.periodic else lim.hi for lim in m.limits])
    t = [np.linspace(lo[i], hi[i], nq + 1) for i in range(2)]
    t1, t2 = np.meshgrid(*[0.5 * (a[1:] + a[:-1]) for a in t], indexing="ij")
    cd = np.hypot(L1 * np.cos(t1) - L0 - L3 * np.cos(t2), L1 * np.sin(t1) - L3 * np.sin(t2))
    labels, _ = ndimage.label((cd > abs(L2 - L4)) & (cd < L2 + L4))
    box_lo, box_hi = m.pose_box()
    axes = [np.linspace(box_lo[i], box_hi[i], nx) for i in range(2)]
    poses = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 2)
    joints = m.joint_angles(poses)
    holders = np.zeros((poses.shape[0], 0), dtype=bool)
    keys: list[tuple[int, int]] = []
    in_w = np.zeros(poses.shape[0], dtype=bool)
    for p in range(joints.shape[1]):
        q = joints[:, p]
        ok = np.isfinite(q).all(axis=1)
        wrapped = np.where(ok[:, None], q, 0.0)
        for i in range(len(m.limits)):
            wrapped[:, i] = lo[i] + np.mod(wrapped[:, i] - lo[i], 2 * np.pi)
            ok &= wrapped[:, i] <= hi[i]
        in_w |= ok
        cell = np.clip(((wrapped - lo) / (hi - lo) * nq).astype(int), 0, nq - 1)
        comp = labels[cell[:, 0], cell[:, 1]]
        sign = np.sign(m.det_a(poses, np.where(ok[:, None], q, 0.0)))
        for key in set(
            zip(comp[ok & (comp > 0)].tolist(), sign[ok & (comp > 0)].tolist(), strict=True)
        ):
            if key not in keys:
                keys.append(key)
                holders = np.concatenate([holders, np.zeros((poses.shape[0], 1), bool)], axis=1)
            j = keys.index(key)
            holders[:, j] |= ok & (comp == key[0]) & (sign == key[1])
    return bool(holders[in_w].all(axis=0).any()), int(in_w.sum())
