"""Hunting for wrong definite answers of the certified five-bar analysis.

Every definite answer (a pose in/out of W, in/out of a region W_Nj, a set of
poses feasible/infeasible, area bounds, ``equals_workspace``, ``n_connected``)
must hold exactly, for any five-bar; "unknown" is always allowed. The tests
below only assert what must hold, against independent evidence:

* a joint-space reference: det A = 0 exactly where the circles (C, L2) and
  (D, L4) are tangent, so the regions are (component of
  D = {q : |L2 - L4| < |C(q) - D(q)| < L2 + L4} in the joint box, sign of det A)
  pairs; D is labelled on a grid of Q, and a configuration is trusted to its
  grid label only away from the grid's blind spots (joint limits, boundary of
  D, det A ~ 0);
* closed-form postures (``joint_angles``, ``det_a``) at sampled poses;
* exact rational arithmetic (``fractions``) for reachability and high-precision
  decimals for det A where floats cannot decide.

Failing tests document unsound answers (see the docstring of each).
"""

from __future__ import annotations

import math
from decimal import Decimal, localcontext
from fractions import Fraction

import numpy as np
import pytest
from scipy import ndimage

from moveability import analyze
from moveability.analysis.sheets import classify_sheets
from moveability.hypertree.measurement import locate
from moveability.hypertree.status import IN, OUT
from moveability.intervals import Interval
from moveability.limits import INSIDE, OUTSIDE, JointLimit, classify_angles
from moveability.mechanisms import FiveBar
from moveability.mechanisms.base import FOLD_INNER, FOLD_OUTER, REGULAR
from references import pi_fraction

PI = np.pi
UNLIMITED = JointLimit.unlimited()
N_GRID = 500


def _possible_label(result, row, leaf, posture, point):
    """Possible component of the sub-node holding the configuration of ``posture`` at
    ``point``: the piece of each limited joint's range its value lies in."""
    from moveability.analysis.regions import joint_pieces, split_legs

    g, t, m = result.graph, result.table, result.mechanism
    q = m.joint_angles(point[None, :], clip=True)[0, posture]
    slot = 0
    for bit, i in enumerate(split_legs(m.limits)):
        lim = m.limits[i]
        lo, hi, ok = joint_pieces(
            t.angles_lo[leaf : leaf + 1, posture, i], t.angles_hi[leaf : leaf + 1, posture, i], lim
        )
        v = lim.wrap(q[i]) if not lim.periodic else q[i]
        inside = [bool(ok[j, 0] and lo[j, 0] - 1e-9 <= v <= hi[j, 0] + 1e-9) for j in (0, 1)]
        if not inside[0] and inside[1]:
            slot |= 1 << bit
    return int(g.possible[row][leaf, posture * g.slots + slot])


def _pi_fraction(digits: int = 80) -> Fraction:
    return pi_fraction(digits)


EXACT_TWO_PI = 2 * _pi_fraction()


# ------------------------------------------------------------------ reference
class Reference:
    """Regions of a five-bar from a labelled grid of its joint space."""

    def __init__(self, m: FiveBar, n: int = N_GRID) -> None:
        self.m, self.n = m, n
        L0, L1, L2, L3, L4 = m.lengths
        self.lo = np.array([lim.lo for lim in m.limits])
        self.hi = np.array([lim.lo + 2 * PI if lim.periodic else lim.hi for lim in m.limits])
        t = [np.linspace(self.lo[i], self.hi[i], n + 1) for i in range(2)]
        centres = [0.5 * (a[1:] + a[:-1]) for a in t]
        t1, t2 = np.meshgrid(*centres, indexing="ij")
        cd = np.hypot(L1 * np.cos(t1) - L0 - L3 * np.cos(t2), L1 * np.sin(t1) - L3 * np.sin(t2))
        self.cd = cd
        labels, count = ndimage.label((cd > abs(L2 - L4)) & (cd < L2 + L4))
        parent = list(range(count + 1))

        def find(x: int) -> int:
            while parent[x] != x:
                x = parent[x]
            return x

        for axis, lim in enumerate(m.limits):
            if not lim.periodic:
                continue
            a, b = np.take(labels, 0, axis=axis), np.take(labels, -1, axis=axis)
            both = (a > 0) & (b > 0)
            for u, v in zip(a[both], b[both], strict=True):
                ru, rv = find(int(u)), find(int(v))
                if ru != rv:
                    parent[max(ru, rv)] = min(ru, rv)
        roots = np.array([find(x) for x in range(count + 1)])
        # label 0 (outside D) stays -1 even when every cell is inside D
        uniq = np.unique(roots[1:]) if count else np.zeros(0, dtype=int)
        relabel = np.full(count + 1, -1)
        for k, root in enumerate(uniq):
            relabel[roots == root] = k
        relabel[0] = -1
        self.labels = relabel[labels]
        self.n_components = len(uniq)
        self.cell = (self.hi - self.lo) / n

    def configurations(self, pts: np.ndarray):
        """Per pose and posture: reference region label (-1 if not valid and
        non-singular), sign of det A, whether the label is trustworthy, and
        whether the posture is valid (reachable, within the limits)."""
        m = self.m
        _, L1, L2, L3, L4 = m.lengths
        pts = np.asarray(pts, dtype=np.float64).reshape(-1, 2)
        q = m.joint_angles(pts)
        n = pts.shape[0]
        finite = np.isfinite(q).all(axis=-1)
        qz = np.where(finite[..., None], q, 0.0)
        det = m.det_a(np.repeat(pts, 4, axis=0), qz.reshape(-1, 2)).reshape(n, 4)
        ok = finite.copy()
        robust = np.ones((n, 4), dtype=bool)
        idx = np.zeros((n, 4, 2), dtype=int)
        for i, lim in enumerate(m.limits):
            a = qz[..., i]
            w = lim.wrap(a)
            ok &= lim.contains(a)
            f = (w - self.lo[i]) / (self.hi[i] - self.lo[i]) * self.n
            idx[..., i] = np.clip(np.floor(f).astype(int), 0, self.n - 1)
            if not lim.periodic:
                gap = np.minimum(np.abs(w - lim.lo), np.abs(w - lim.hi))
                gap = np.minimum(gap, np.abs(w - 2 * PI - lim.lo))
                robust &= ~(finite & (gap < 4 * self.cell[i]))
        label = self.labels[idx[..., 0], idx[..., 1]]
        cd = self.cd[idx[..., 0], idx[..., 1]]
        slope = 3 * (L1 * self.cell[0] + L3 * self.cell[1])
        near_edge = (np.abs(cd - (L2 + L4)) < slope) | (np.abs(cd - abs(L2 - L4)) < slope)
        robust &= ~(finite & near_edge)
        robust &= ~(finite & (np.abs(det) < 1e-3 * max(m.lengths) ** 2))
        sign = np.where(finite, np.sign(det), 0).astype(int)
        label = np.where(ok & (sign != 0), label, -1)
        return label, sign, robust, ok, det

    def regions_at(self, pts: np.ndarray):
        """Set of (label, sign) regions at each pose, whether every posture is
        trustworthy, and which postures are valid."""
        label, sign, robust, ok, _ = self.configurations(pts)
        sets = [
            {(int(label[i, p]), int(sign[i, p])) for p in range(4) if label[i, p] >= 0}
            for i in range(label.shape[0])
        ]
        return sets, robust.all(axis=1), ok


def _mechanism(lengths, lim1, lim2) -> FiveBar:
    def limit(x):
        if x is None:
            return UNLIMITED
        return x if isinstance(x, JointLimit) else JointLimit(*x)

    return FiveBar(*lengths, limits=(limit(lim1), limit(lim2)))


# ------------------------------------------------------------ the big check
def _check_analysis(m: FiveBar, precision: float, rng: np.random.Generator, n_pts: int = 2500):
    """Every definite answer of ``analyze(m, precision)`` against the reference.

    Returns the list of violations (empty when sound)."""
    ref = Reference(m)
    result = analyze(m, precision=precision)
    g, t = result.graph, result.table
    leaves = result.tree.leaves()
    bad: list[tuple] = []

    # 1. certified sheets: valid configurations of the recorded sign, and every
    #    certain component inside one reference region
    certain_ref: dict[int, set] = {}
    nodes = np.argwhere((g.certain >= 0) & (t.status == IN))
    if len(nodes) > 2500:
        nodes = nodes[rng.choice(len(nodes), 2500, replace=False)]
    for frac in ([0.5, 0.5], [0.0, 0.0], [1.0, 1.0], [0.0, 1.0], [1.0, 0.0], [0.5, 1.0]):
        if not len(nodes):
            break
        box_lo, box_hi = leaves.lo[nodes[:, 0]], leaves.hi[nodes[:, 0]]
        pts = box_lo + np.array(frac) * (box_hi - box_lo)
        label, sign, robust, ok, _ = ref.configurations(pts)
        rows = np.arange(len(nodes))
        p = nodes[:, 1]
        for k in np.flatnonzero(~ok[rows, p]):
            bad.append(("IN sheet holds an invalid configuration", nodes[k], pts[k]))
        for k in np.flatnonzero(ok[rows, p] & (sign[rows, p] != t.sign[nodes[:, 0], p])):
            bad.append(("IN sheet of the wrong sign", nodes[k], pts[k]))
        for k in np.flatnonzero(robust[rows, p] & (label[rows, p] >= 0)):
            c = int(g.certain[nodes[k, 0], nodes[k, 1]])
            certain_ref.setdefault(c, set()).add((int(label[k, p[k]]), int(sign[k, p[k]])))
    for c, regions in certain_ref.items():
        if len(regions) > 1:
            bad.append(("certain component spans several regions", c, regions))

    # 2. every reference region inside one possible component, on live nodes
    lo, hi = m.bounds
    pts = rng.uniform(lo, hi, (n_pts, 2))
    label, sign, robust, ok, _ = ref.configurations(pts)
    _, leaf = locate(result.tree, pts)
    possible_of: dict[tuple, set] = {}
    for k, p in zip(*np.nonzero((label >= 0) & robust), strict=True):
        key = (int(label[k, p]), int(sign[k, p]))
        if leaf[k] < 0:
            bad.append(("valid configuration outside the tree box", pts[k]))
            continue
        u = _possible_label(result, 0 if sign[k, p] > 0 else 1, leaf[k], p, pts[k])
        if u < 0:
            bad.append(("valid configuration on a dead node", pts[k], p))
            continue
        possible_of.setdefault(key, set()).add((0 if key[1] > 0 else 1, u))
    for key, comps in possible_of.items():
        if len(comps) > 1:
            bad.append(("region spans several possible components", key, comps))

    # reference region of each listed region (when unambiguous)
    target = {}
    for r in result.regions:
        s = certain_ref.get(r.certain)
        target[r.id] = next(iter(s)) if s and len(s) == 1 else None

    # 3. point answers
    answers = result.locate(pts)["points"]
    sets, rob, okp = ref.regions_at(pts)
    for k, a in enumerate(answers):
        if a["workspace"] is False and okp[k].any():
            bad.append(("pose with a valid configuration answered out of W", pts[k]))
        if a["workspace"] is True and rob[k] and not okp[k].any():
            bad.append(("pose without a valid configuration answered in W", pts[k]))
        if not rob[k]:
            continue
        for r in result.regions:
            tg = target[r.id]
            v = a["regions"][str(r.id)]
            if v is True and not any(s == r.sign for _, s in sets[k]):
                bad.append(("in a region without a configuration of its sign", r.id, pts[k]))
            if tg is None:
                continue
            if v is True and tg not in sets[k]:
                bad.append(("answered in a region it is not in", r.id, pts[k], sets[k], tg))
            if v is False and tg in sets[k]:
                bad.append(("answered out of a region it is in", r.id, pts[k], sets[k], tg))

    # 4. feasibility of random sets of poses of W
    in_w = pts[okp.any(axis=1) & rob]
    for _ in range(40):
        if len(in_w) < 3:
            break
        sel = in_w[rng.choice(len(in_w), int(rng.integers(1, 4)), replace=False)]
        answer = result.feasible(sel)
        s_sets, s_rob, _ = ref.regions_at(sel)
        common = set.intersection(*s_sets)
        if answer["feasible"] is False and common and s_rob.all():
            bad.append(("feasible poses answered infeasible", sel.tolist(), common))
        if answer["feasible"]:
            q = np.array(answer["postures"])
            if np.abs(m.constraints(sel, q)).max() > 1e-7 * max(m.lengths) ** 2:
                bad.append(("witness is not a configuration", sel.tolist(), q.tolist()))
            for i, lim in enumerate(m.limits):
                if not lim.contains(q[:, i]).all():
                    bad.append(("witness beyond a joint limit", sel.tolist(), q.tolist()))
            region = result.regions[answer["region"]]
            if not (np.sign(m.det_a(sel, q)) == region.sign).all():
                bad.append(("witness of the wrong sign", sel.tolist(), q.tolist()))
            tg = target[answer["region"]]
            if tg is not None and s_rob.all() and tg not in common:
                bad.append(("feasible in a region not holding every pose", sel.tolist()))

    # 5. equals_workspace and n_connected: witness leaves are in W and miss the region
    for r in result.regions:
        tg = target[r.id]
        if r.equals_workspace and tg is not None:
            for k in np.flatnonzero(rob & okp.any(axis=1)):
                if tg not in sets[k]:
                    bad.append(("equals_workspace but a pose of W is not in it", r.id, pts[k]))
    comps_to_check = []
    for j, r in enumerate(result.regions):
        if r.equals_workspace is False:
            row, u = result.regions[j].row, result.regions[j].possible
            comps_to_check.append((row, u))
    if result.n_connected is False:
        comps_to_check += [(row, u) for row in (0, 1) for u in range(g.n_possible[row])]
    for row, u in set(comps_to_check):
        inside = {key for key, comps in possible_of.items() if comps == {(row, u)}}
        touch = (g.possible[row] == u).any(axis=1)
        witness = np.flatnonzero(result.workspace_cells()[0] & ~touch)
        if not witness.size:
            bad.append(("no witness leaf for a negative answer", row, u))
            continue
        for w_leaf in witness[:: max(1, witness.size // 40)]:
            sp = leaves.lo[w_leaf] + rng.random((4, 2)) * (leaves.hi[w_leaf] - leaves.lo[w_leaf])
            w_sets, w_rob, w_ok = ref.regions_at(sp)
            for k in range(4):
                if not w_ok[k].any():
                    bad.append(("leaf certified in W holds a pose out of W", sp[k]))
                if w_rob[k] and w_sets[k] & inside:
                    bad.append(("witness leaf meets the region", row, u, sp[k]))

    # 6. area bounds bracket a grid estimate (error ~ boundary length x spacing)
    n = 240
    xs = lo[0] + (np.arange(n) + 0.5) * (hi[0] - lo[0]) / n
    ys = lo[1] + (np.arange(n) + 0.5) * (hi[1] - lo[1]) / n
    grid = np.stack(np.meshgrid(xs, ys), -1).reshape(-1, 2)
    cell = (hi[0] - lo[0]) * (hi[1] - lo[1]) / n**2
    g_sets, _, g_ok = ref.regions_at(grid)
    estimate = cell * g_ok.any(axis=1).sum()
    perimeter = 2 * np.pi * (sum(m.lengths[1:]) + 2 * max(m.lengths))
    slack = 2 * perimeter * max(hi - lo) / n
    w_in, w_out = result.workspace["area"]
    if not (w_in - slack <= estimate <= w_out + slack):
        bad.append(("workspace area", w_in, estimate, w_out))
    for r in result.regions:
        tg = target[r.id]
        if tg is None:
            continue
        est = cell * sum(1 for s in g_sets if tg in s)
        if not (r.area[0] - slack <= est <= r.area[1] + slack):
            bad.append(("region area", r.id, r.area, est))
    return result, ref, bad


# ------------------------------------------------------------ random designs
def _random_limit(rng: np.random.Generator) -> JointLimit:
    kind = int(rng.integers(0, 6))
    if kind == 0:
        return UNLIMITED
    if kind == 1:
        return JointLimit(-PI, PI)
    if kind == 2:
        return JointLimit(0.0, PI)
    if kind == 3:  # exactly one turn, starting anywhere
        a = float(rng.uniform(-PI, PI))
        return JointLimit(a, a + 2 * PI)
    a = float(rng.uniform(-4.0, 4.0))
    return JointLimit(a, a + float(rng.uniform(0.4, 2 * PI)))


def _random_design(rng: np.random.Generator) -> FiveBar:
    while True:
        L = rng.uniform(1.0, 10.0, 5)
        kind = int(rng.integers(0, 7))
        if kind == 1:
            L[2] = L[1]  # a leg of equal links
        elif kind == 2:
            L[4] = L[3]
        elif kind == 3:
            L[0] = rng.uniform(0.02, 0.5)  # bases almost together
        elif kind == 4:
            L[3], L[4] = L[1], L[2]  # symmetric
        elif kind == 5:
            L[0] = L[1] + L[2] + L[3] + L[4] - rng.uniform(0.3, 1.5)  # legs barely meet
        if L[0] < L[1] + L[2] + L[3] + L[4] - 0.2:
            return FiveBar(*L, limits=(_random_limit(rng), _random_limit(rng)))


@pytest.mark.parametrize("seed", range(30))
def test_random_designs_give_only_true_answers(seed):
    rng = np.random.default_rng(1000 + seed)
    m = _random_design(rng)
    precision = float(rng.choice([0.4, 0.25, 0.15])) * max(m.lengths[1:]) / 8
    _, _, bad = _check_analysis(m, precision, rng)
    assert not bad, (m, bad[:5])


DEGENERATE = [
    # bases almost together, equal links everywhere
    ((1e-6, 5.0, 5.0, 5.0, 5.0), None, None),
    ((1e-6, 5.0, 5.0, 5.0, 5.0), (-PI, PI), (-PI, PI)),
    ((1e-3, 5.0, 3.0, 5.0, 3.0), (0.0, PI), (0.0, PI)),
    # L2 == L4 (det A's circles of equal radii: |L2 - L4| = 0)
    ((2.0, 4.0, 4.0, 3.0, 4.0), None, (-PI, PI)),
    # one-turn limits starting off -pi, and mixed stops / free joints
    ((7.0, 8.0, 5.0, 8.0, 5.0), (1.0, 1.0 + 2 * PI), (-2.0, -2.0 + 2 * PI)),
    ((7.0, 8.0, 5.0, 8.0, 5.0), (-PI, PI), None),
    ((2.0, 4.0, 4.0, 3.0, 3.0), (-PI, PI), (0.0, 2 * PI)),
    ((0.5, 3.0, 3.0, 3.0, 3.0), (-PI, PI), (-PI, PI)),
    # legs that barely meet, long and short links
    ((15.9, 5.0, 3.0, 5.0, 3.0), None, None),
    ((5.0, 1.0, 7.0, 1.0, 7.0), None, None),
    ((5.0, 7.0, 1.0, 7.0, 1.0), None, None),
    ((5.0, 7.0, 1.0, 2.0, 6.0), (-PI / 2, PI / 2), (PI / 2, 3 * PI / 2)),
    ((3.0, 5.0, 5.0, 2.0, 2.0), None, (-PI, PI)),
    # narrow joint ranges
    ((7.0, 8.0, 5.0, 8.0, 5.0), (1.0, 1.3), (1.5, 2.2)),
    # tangent circles: outer 1 / outer 2 (2 + 6 = 8), outer 1 / inner 2 (4 = 10 - 6),
    # inner 1 / inner 2 (2 + 2 = 4)
    ((2.0, 5.0, 3.0, 3.0, 3.0), (0.0, PI), (-PI, PI)),
    ((10.0, 2.5, 1.5, 8.0, 2.0), None, None),
    ((4.0, 3.0, 1.0, 3.0, 1.0), (-PI, PI), (-PI, PI)),
]


@pytest.mark.parametrize("design", DEGENERATE, ids=lambda d: repr(d[0]))
def test_degenerate_designs_give_only_true_answers(design):
    m = _mechanism(*design)
    rng = np.random.default_rng(7)
    precision = 0.15 * max(m.lengths[1:]) / 8
    _, _, bad = _check_analysis(m, precision, rng, n_pts=1500)
    assert not bad, (m, bad[:5])


@pytest.mark.parametrize("precision", [100.0, 3.0, 0.9])
def test_coarse_precisions_give_only_true_answers(precision):
    m = _mechanism((7.0, 8.0, 5.0, 8.0, 5.0), (0.0, PI), (-PI, PI))
    _, _, bad = _check_analysis(m, precision, np.random.default_rng(3), n_pts=1500)
    assert not bad, bad[:5]


# --------------------------------------------------------- adversarial poses
def _exact_reach(m: FiveBar, pts: np.ndarray) -> np.ndarray:
    """(n, 2) -1 unreachable, 0 on a fold circle, 1 strictly reachable (exact)."""
    out = np.zeros((len(pts), 2), dtype=int)
    for i, leg in enumerate(m.rr_legs):
        a, b = Fraction(leg.proximal), Fraction(leg.distal)
        bx, by = Fraction(leg.base[0]), Fraction(leg.base[1])
        for k, (x, y) in enumerate(pts):
            d2 = (Fraction(x) - bx) ** 2 + (Fraction(y) - by) ** 2
            if d2 > (a + b) ** 2 or d2 < (a - b) ** 2:
                out[k, i] = -1
            elif d2 == (a + b) ** 2 or d2 == (a - b) ** 2:
                out[k, i] = 0
            else:
                out[k, i] = 1
    return out


def _circle_points(m: FiveBar, n: int, rng: np.random.Generator) -> np.ndarray:
    """Poses on (or one or two ulps off) the fold circles of both legs."""
    pts = []
    for leg in m.rr_legs:
        for r in (leg.proximal + leg.distal, abs(leg.proximal - leg.distal)):
            phi = rng.uniform(-PI, PI, n)
            p = np.c_[leg.base[0] + r * np.cos(phi), leg.base[1] + r * np.sin(phi)]
            pts += [p, np.nextafter(p, np.inf), np.nextafter(p, -np.inf)]
            pts.append(np.nextafter(np.nextafter(p, np.inf), np.inf))
    return np.concatenate(pts)


def _crossings(m: FiveBar) -> np.ndarray:
    """Crossing points of the circles of the two legs (outer/inner pairs)."""
    L0 = m.lengths[0]
    a, b = m.rr_legs
    out = []
    for r1 in (a.proximal + a.distal, abs(a.proximal - a.distal)):
        for r2 in (b.proximal + b.distal, abs(b.proximal - b.distal)):
            x = (r1 * r1 - r2 * r2 + L0 * L0) / (2 * L0)
            if r1 * r1 > x * x:
                y = math.sqrt(r1 * r1 - x * x)
                out += [[x, y], [x, -y]]
    return np.array(out).reshape(-1, 2)


def _limit_points(m: FiveBar, n: int, rng: np.random.Generator) -> np.ndarray:
    """Poses whose configuration puts a joint exactly at a stop, or at +-pi."""
    pts = []
    for i, (leg, lim) in enumerate(zip(m.rr_legs, m.limits, strict=True)):
        other = m.rr_legs[1 - i]
        stops = [PI, -PI, 0.0] + ([] if lim.periodic else [lim.lo, lim.hi])
        for t in stops:
            cx = leg.base[0] + leg.proximal * np.cos(t)
            cy = leg.base[1] + leg.proximal * np.sin(t)
            psi = rng.uniform(-PI, PI, n)
            p = np.c_[cx + leg.distal * np.cos(psi), cy + leg.distal * np.sin(psi)]
            d = np.hypot(p[:, 0] - other.base[0], p[:, 1] - other.base[1])
            reach = (d <= other.proximal + other.distal) & (d >= abs(other.proximal - other.distal))
            pts.append(p[reach])
    return np.concatenate(pts)


ADVERSARIAL = [
    ((7.0, 8.0, 5.0, 8.0, 5.0), None, None),
    ((7.0, 8.0, 5.0, 8.0, 5.0), (-PI, PI), (-PI, PI)),
    ((7.0, 8.0, 5.0, 8.0, 5.0), (0.0, PI), (0.0, PI)),
    ((3.0, 4.0, 4.0, 5.0, 3.0), None, (-2.0, 2.5)),
    ((5.0, 6.0, 4.0, 5.0, 5.0), (0.3, 2.8), (-0.5, 2.0)),
    ((2.0, 4.0, 4.0, 3.0, 3.0), (1.0, 1.0 + 2 * PI), None),
]


@pytest.mark.parametrize("design", ADVERSARIAL, ids=lambda d: f"{d[0]}-{d[1]}-{d[2]}")
def test_adversarial_poses(design):
    """Leaf corners and face midpoints, poses on and next to the fold circles,
    the crossings of the legs' circles, poses at joint stops and at +-pi, and
    poses just outside the tree box."""
    m = _mechanism(*design)
    rng = np.random.default_rng(11)
    result = analyze(m, precision=0.12)
    ref = Reference(m)
    leaves = result.tree.leaves()
    live = np.flatnonzero(result.tree.status != OUT)
    pick = live[rng.choice(live.size, min(400, live.size), replace=False)]
    lo_l, hi_l = leaves.lo[pick], leaves.hi[pick]
    mid = 0.5 * (lo_l + hi_l)
    corners = [lo_l, hi_l, np.c_[lo_l[:, 0], hi_l[:, 1]], np.c_[hi_l[:, 0], lo_l[:, 1]]]
    faces = [np.c_[mid[:, 0], lo_l[:, 1]], np.c_[lo_l[:, 0], mid[:, 1]]]
    blo, bhi = m.bounds
    outside = np.array(
        [
            [np.nextafter(blo[0], -np.inf), 0.0],
            [np.nextafter(bhi[0], np.inf), 0.0],
            [0.5 * (blo[0] + bhi[0]), np.nextafter(bhi[1], np.inf)],
            [0.5 * (blo[0] + bhi[0]), np.nextafter(blo[1], -np.inf)],
            [blo[0], blo[1]],
            [bhi[0], bhi[1]],
        ]
    )
    pts = np.concatenate(
        [
            *corners,
            *faces,
            _circle_points(m, 60, rng),
            _crossings(m),
            _limit_points(m, 60, rng),
            outside,
        ]
    )
    answers = result.locate(pts)["points"]
    sets, robust, ok = ref.regions_at(pts)
    _, sign, _, ok_p, det = ref.configurations(pts)
    unlimited = all(lim.periodic for lim in m.limits)
    exact = _exact_reach(m, pts) if unlimited else None
    scale = max(m.lengths) ** 2
    # the region each listed region stands for, from poses certainly in it
    target = {}
    for r in result.regions:
        seen = [
            {x for x in s if x[1] == r.sign}
            for a, s, rb in zip(answers, sets, robust, strict=True)
            if rb and a["regions"][str(r.id)] is True
        ]
        common = set.intersection(*seen) if seen else set()
        target[r.id] = next(iter(common)) if len(common) == 1 else None
    for k, a in enumerate(answers):
        ws = a["workspace"]
        if exact is not None:
            # without stops W is exactly the set of poses both legs reach
            if ws is True:
                assert (exact[k] >= 0).all(), (pts[k], exact[k])
            if ws is False:
                assert (exact[k] < 0).any(), (pts[k], exact[k])
        elif ws is False:
            assert not ok[k].any(), pts[k]
        for r in result.regions:
            v = a["regions"][str(r.id)]
            if v is True:
                # a valid configuration of the region's sign, clearly
                good = ok_p[k] & (sign[k] == r.sign)
                assert good.any() or (np.abs(det[k][ok_p[k]]) < 1e-9 * scale).any(), (
                    pts[k],
                    r.id,
                )
                if exact is not None:
                    assert (exact[k] >= 0).all(), (pts[k], exact[k])
            if target[r.id] is not None and robust[k]:
                if v is True:
                    assert target[r.id] in sets[k], (pts[k], r.id)
                if v is False:
                    assert target[r.id] not in sets[k], (pts[k], r.id)


# ------------------------------------------------------- sheet certificates
def _boxes_around(centres: np.ndarray, rng: np.random.Generator, n: int, size: float):
    c = centres[rng.integers(0, len(centres), n)]
    width = np.exp(rng.uniform(np.log(1e-4), np.log(size), (n, 2)))
    shift = rng.uniform(-1.0, 1.0, (n, 2)) * width
    lo = c + shift - 0.5 * width
    return lo, lo + width


GROUP_DESIGNS = [
    ((7.0, 8.0, 5.0, 8.0, 5.0), (0.0, PI), (0.0, PI)),
    ((7.0, 8.0, 5.0, 8.0, 5.0), (-PI, PI), None),
    ((6.0, 5.0, 7.0, 5.0, 7.0), (-PI / 2, PI), (0.0, 1.5 * PI)),
    ((3.0, 4.0, 4.0, 5.0, 3.0), None, (-2.0, 2.5)),
    ((2.0, 3.0, 1.0, 2.0, 5.0), None, None),
]


@pytest.mark.parametrize("design", GROUP_DESIGNS, ids=lambda d: repr(d[0]))
def test_fold_group_certificates(design):
    """Where a fold group is certified, every configuration of its postures over
    the box is valid with the recorded sign, the folding legs really fold in the
    box, and two folding legs really meet at a crossing of their outer circles
    inside the box (the four postures coincide there)."""
    m = _mechanism(*design)
    rng = np.random.default_rng(5)
    circles = _circle_points(m, 200, rng)
    crossings = _crossings(m)
    centres = np.concatenate([circles, np.repeat(crossings, 50, axis=0)])
    lo, hi = _boxes_around(centres, rng, 6000, 0.6)
    table = classify_sheets(m, lo, hi)
    group_boxes = np.flatnonzero(table.group.any(axis=1))
    assert group_boxes.size > 50
    postures = m.postures
    scale = max(m.lengths) ** 2
    n_pairs = 0
    pairs = np.flatnonzero(table.group.any(axis=1) & (table.folding.sum(axis=1) == 2))
    for b in np.union1d(group_boxes[:500], pairs):
        folding = np.flatnonzero(table.folding[b])
        # samples over the box, its corners included
        t = np.r_[rng.random((60, 2)), [[0, 0], [1, 1], [0, 1], [1, 0]]]
        pts = lo[b] + t * (hi[b] - lo[b])
        q = m.joint_angles(pts)
        finite = np.isfinite(q).all(axis=-1)
        for p in np.flatnonzero(table.group[b]):
            s = table.sign[b, p]
            assert s != 0
            for i, lim in enumerate(m.limits):
                assert lim.contains(q[finite[:, p], p, i]).all(), (b, p)
            qp = np.where(finite[:, p : p + 1], q[:, p], 0.0)
            d = m.det_a(pts, qp)[finite[:, p]]
            assert (np.sign(d[np.abs(d) > 1e-9 * scale]) == s).all(), (b, p)
        # the folding legs reach both sides of their fold inside the box
        for i in folding:
            leg = m.rr_legs[i]
            g = np.stack(
                np.meshgrid(
                    np.linspace(lo[b, 0], hi[b, 0], 40), np.linspace(lo[b, 1], hi[b, 1], 40)
                ),
                -1,
            ).reshape(-1, 2)
            reach = np.isfinite(leg.angles(g)).all(axis=1)
            assert reach.any() and (~reach).any(), b
            assert table.leg_status[b, i] in (FOLD_OUTER, FOLD_INNER)
            # the reachable part of the box is connected (a box cut by a disk is an
            # up-set towards the far corner when certified, so its grid is connected)
            _, n_parts = ndimage.label(reach.reshape(40, 40), structure=np.ones((3, 3)))
            assert n_parts == 1, (b, i, lo[b], hi[b])
        if folding.size == 2:
            n_pairs += 1
            assert (table.leg_status[b] == FOLD_OUTER).all()
            # the exact crossing of the two outer circles lies in the box
            with localcontext() as ctx:
                ctx.prec = 60
                L0 = Decimal(m.lengths[0])
                r1 = Decimal(m.rr_legs[0].proximal) + Decimal(m.rr_legs[0].distal)
                r2 = Decimal(m.rr_legs[1].proximal) + Decimal(m.rr_legs[1].distal)
                x = (r1 * r1 - r2 * r2 + L0 * L0) / (2 * L0)
                y = (r1 * r1 - x * x).sqrt()
                inside = [
                    Decimal(lo[b, 0]) < x < Decimal(hi[b, 0])
                    and Decimal(lo[b, 1]) < yy < Decimal(hi[b, 1])
                    for yy in (y, -y)
                ]
            assert any(inside), (b, lo[b], hi[b])
        else:
            # one folding leg, the other regular over the whole box
            assert folding.size == 1
            others = [j for j in range(2) if j != folding[0]]
            assert (table.leg_status[b, others] == REGULAR).all()
        # the certified postures of one fold group share their sign (they meet at
        # the fold); a posture's own det A enclosure may certify it alone
        for p in np.flatnonzero(table.group[b]):
            for q_ in np.flatnonzero(table.group[b]):
                differ = np.flatnonzero(postures[p] != postures[q_])
                if set(differ) <= set(folding):
                    assert table.sign[b, q_] == table.sign[b, p]
    a, b_ = m.rr_legs
    r1, r2 = a.proximal + a.distal, b_.proximal + b_.distal
    if abs(r1 - r2) < m.lengths[0] < r1 + r2:  # the outer circles cross
        assert n_pairs > 0


def test_folds_connected_needs_a_real_crossing():
    """FAILS (latent): ``FiveBar.folds_connected`` locates the crossing of the
    outer circles in floats, ``y = sqrt(r1^2 - x^2)``, and certifies boxes that
    hold it with a margin of 1e-9 * max length. Here L1 + L2 = L0 + L3 + L4
    exactly: the outer circles are internally tangent at (L1 + L2, 0) and never
    cross, yet the float formula gives a crossing at y = 2.9e-7 and a box around
    it (y > 2.4e-7, both legs FOLD_OUTER) is certified: there the reachable part
    of the box lies inside the circle of B, where leg 1 cannot stretch, so its
    two branches do not join in the box. The fold group is not certified only
    because det A (~ y near the tangency) keeps sign 0 over such a box."""
    L = (2.48, 9.77, 1.85, 4.46, 4.68)
    m = _mechanism(L, None, None)
    L0, L1, L2, L3, L4 = (Fraction(v) for v in L)
    assert L1 + L2 == L0 + L3 + L4  # internally tangent outer circles
    r1, r2 = L[1] + L[2], L[3] + L[4]
    x = (r1 * r1 - r2 * r2 + L[0] ** 2) / (2 * L[0])
    y = math.sqrt(r1 * r1 - x * x)
    lo = np.array([[x - 5e-8, y - 5e-8]])
    hi = np.array([[x + 5e-8, y + 5e-8]])
    table = classify_sheets(m, lo, hi)
    assert (table.leg_status[0] == FOLD_OUTER).all()
    assert not table.group.any()  # masked by the sign of det A
    # the only common point of the two outer circles is (L1 + L2, 0): not in the box
    assert lo[0, 1] > 0
    assert not m.folds_connected((0, 1), lo, hi)[0]


# ------------------------------------------------------------- joint limits
def _exact_classify(a_lo: float, a_hi: float, lo: float, hi: float) -> tuple[bool, bool]:
    """(every angle inside [lo, hi] modulo 2 pi, no angle inside), exactly."""
    alo, ahi, flo, fhi = (Fraction(v) for v in (a_lo, a_hi, lo, hi))
    two_pi = EXACT_TWO_PI
    if ahi - alo >= two_pi:
        return fhi - flo >= two_pi, False
    m = math.floor((alo - flo) / two_pi)
    inside = alo - m * two_pi >= flo and ahi - m * two_pi <= fhi
    outside = all(ahi - j * two_pi < flo or alo - j * two_pi > fhi for j in range(m - 2, m + 3))
    return inside, outside


def test_classify_angles_is_exact_on_the_angles_of_a_five_bar():
    """Angle enclosures within a few turns of zero (what a five-bar produces),
    including ranges of exactly one turn and bounds next to the stops."""
    rng = np.random.default_rng(0)
    cases = []
    for _ in range(3000):
        lo = float(rng.choice([-PI, 0.0, rng.uniform(-4, 4)]))
        width = float(rng.choice([2 * PI, PI, rng.uniform(0.1, 2 * PI)]))
        hi = lo + width
        centre = float(rng.choice([lo, hi, lo + 2 * PI, hi - 2 * PI, rng.uniform(-7, 7)]))
        centre += float(rng.choice([-1, 1])) * float(rng.choice([0, 1e-16, 1e-15, 1e-9]))
        half = float(rng.choice([0.0, 1e-15, 1e-6, rng.uniform(0, 3.5)]))
        cases.append((centre - half, centre + half, lo, hi))
    a = np.array(cases)
    codes = classify_angles(Interval(a[:, 0], a[:, 1]), a[:, 2], a[:, 3])
    for (a_lo, a_hi, lo, hi), code in zip(cases, codes, strict=True):
        inside, outside = _exact_classify(a_lo, a_hi, lo, hi)
        if code == INSIDE:
            assert inside, (a_lo, a_hi, lo, hi)
        if code == OUTSIDE:
            assert outside, (a_lo, a_hi, lo, hi)


def test_classify_angles_many_turns_away():
    """FAILS (latent): ``classify_angles`` promises soundness for any unwrapped
    interval, but the shift by k turns is enclosed as ``[k * 2pi_lo, k * 2pi_hi]``
    with the products rounded to nearest: for k = 327, ``327 * nextafter(2 pi)``
    rounds below 327 * 2 pi, and when the shifted interval is small next to the
    shift (here ~0.8 against ~2054) the final one-ulp widening cannot make up
    for it: an interval poking out of the range is called INSIDE. Not reachable
    from ``analyze`` as far as I can tell: a five-bar's angle enclosures stay
    within +-4 pi, so either k < 327 (every such product rounds safely, checked
    exactly) or the limits themselves lie ~k turns away, the shifted bounds are
    about as large as the shift and their own ulp covers the error."""
    a_lo, a_hi = -2054.2682621143913, -2053.7682621143913
    lo, hi = -1.0, 0.8333333333334868
    inside, _ = _exact_classify(a_lo, a_hi, lo, hi)
    assert not inside  # the interval exceeds hi by less than an ulp of hi
    code = classify_angles(Interval([a_lo], [a_hi]), lo, hi)[0]
    assert code != INSIDE


# ------------------------------------------------- the box of the workspace
def _dec(v: float) -> Decimal:
    f = Fraction(v)
    return Decimal(f.numerator) / Decimal(f.denominator)


def _det_a_decimal(m: FiveBar, x: float, y: float) -> list[Decimal]:
    """det A of the four postures at (x, y) in 60-digit decimals (branch 0 is
    theta + alpha, as in ``RRLeg.angles``)."""
    with localcontext() as ctx:
        ctx.prec = 60
        px, py = _dec(x), _dec(y)
        elbows = []
        for leg in m.rr_legs:
            bx, by = _dec(leg.base[0]), _dec(leg.base[1])
            a, b = _dec(leg.proximal), _dec(leg.distal)
            dx, dy = px - bx, py - by
            d2 = dx * dx + dy * dy
            d = d2.sqrt()
            along = (a * a - b * b + d2) / (2 * d)
            h = (a * a - along * along).sqrt()
            ux, uy = dx / d, dy / d
            elbows.append(
                [
                    (bx + along * ux - h * uy, by + along * uy + h * ux),
                    (bx + along * ux + h * uy, by + along * uy - h * ux),
                ]
            )
        out = []
        for c in elbows[0]:
            for e in elbows[1]:
                out.append((px - c[0]) * (py - e[1]) - (py - c[1]) * (px - e[0]))
        return out


# a short leg at A, a very long one at B whose circle cuts the short leg's
# disk: W is a lens at x ~ 1. fl(L3 + L4) rounds down by 7.6e-6 and L0 - r2 is
# computed from it, while the box is padded by 1e-3 of its own width (4e-6).
LENS = (86000000000.996, 0.6, 0.4, 41000000000.00001, 45000000000.0)


def test_bounds_hold_the_workspace():
    """FAILS: ``FiveBar.bounds`` must hold W (the analysis answers 'out' beyond
    it). The x bounds are computed in round-to-nearest (``L0 - (L3 + L4)``)
    and padded relative to the box width only, so when L0 and L3 + L4 are
    large next to the box, part of W falls outside."""
    m = _mechanism(LENS, None, None)
    lo, hi = m.bounds
    L0, L1, L2, L3, L4 = (Fraction(v) for v in m.lengths)
    # the leftmost pose of W, both legs stretched along y = 0, and a float pose
    # of W next to it, strictly reachable by both legs
    x_min = L0 - (L3 + L4)
    assert (L1 - L2) ** 2 < x_min**2 < (L1 + L2) ** 2
    x = 0.9959963836669922
    assert (_exact_reach(m, np.array([[x, 0.0]])) == 1).all()
    assert Fraction(lo[0]) <= x_min, (float(x_min), lo[0])
    assert lo[0] <= x <= hi[0], (x, lo[0])


def test_pose_outside_the_tree_box_is_not_declared_out():
    """FAILS: a pose of W just outside the tree box is answered 'out' of a
    region it is in, and a feasible pair of poses is answered infeasible.

    X = (0.99599638..., 0) lies outside the box (see the test above) but both
    legs reach it strictly and its four configurations are non-singular
    (|det A| ~ 2e9, checked in 60-digit decimals; both joints are free). Y lies
    in the box and is certified in region 0 with a witness posture p. Along the
    segment X -> Y both legs stay strictly reachable, so posture p's
    configuration moves continuously, and det A stays < -1.9e9: X's posture-p
    configuration is in region 0 too. The analysis still says X is out of
    region 0, and {X, Y} (and {X} alone) infeasible."""
    m = _mechanism(LENS, None, None)
    # the lens is 0.004 wide: cells of 1e-6 across it (the box's x span over 4096)
    result = analyze(m, precision=(1e-6, 0.0005), resolve=False)
    x = 0.9959963836669922
    X = np.array([[x, 0.0]])
    assert (_exact_reach(m, X) == 1).all()
    dets = _det_a_decimal(m, x, 0.0)
    assert all(abs(d) > 1e9 for d in dets)
    Y = np.array([[0.9962575314552862, 0.0]])
    witness = result.feasible(Y)
    assert witness["feasible"] is True
    j = witness["region"]
    q_y = np.array(witness["postures"][0])
    q_all = m.joint_angles(Y)[0]
    gap = np.abs(np.angle(np.exp(1j * (q_all - q_y)))).max(axis=1)
    p = int(np.argmin(gap))
    assert gap[p] < 1e-12
    assert (_exact_reach(m, np.array([[v, 0.0] for v in (x, Y[0, 0])])) == 1).all()
    along = [_det_a_decimal(m, float(v), 0.0)[p] for v in np.linspace(x, Y[0, 0], 300)]
    sign = result.regions[j].sign
    assert all(d * sign > Decimal("1e9") for d in along)
    # so X is in region j and {X, Y} is feasible
    assert result.locate(X)["points"][0]["regions"][str(j)] is not False
    assert result.feasible(np.r_[X, Y])["feasible"] is not False
    assert result.feasible(X)["feasible"] is not False
