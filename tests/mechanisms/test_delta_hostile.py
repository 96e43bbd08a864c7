"""The Delta's certificates on hostile designs, against a brute-force reference.

The reference here shares no code with the package (nor with test_delta.py):

* a configuration is the joints q; the sphere centres are ``c_i = elbow_i - r u_i``
  and the platform centre lies on the line through their circumcentre normal to
  their plane, at the height ``+-sqrt(lb^2 - rho^2)`` (``rho`` the circumradius,
  from ``abc / (4 area)``); det A, with rows ``P - c_i``, has the sign of that
  height along ``(c_2 - c_1) x (c_3 - c_1)``;
* the regions are (side, component of ``{q in the limits: rho(q) < lb}``), the
  components labelled on a grid of q (wrapped across unlimited joints);
* the inverse kinematics of leg i: ``(D.u) cos t - D_z sin t = (|D|^2 + la^2 -
  lb^2) / (2 la)`` with ``D = P + (r - R) u``.

Designs: the arm as long as the rod (la = lb) or nearly, the platform radius
close to the base radius, a rod barely long enough for the legs to meet, limits
exactly at 0, pi/2, -pi/2 or across pi, unlimited joints, limits 0.02 rad wide;
precisions from 0.02 to 1 (one number or one per axis). Checked: every definite
answer of locate (workspace and regions, on poses whose reference answer is
stable under small moves), feasible (True: one reference region holds both
poses, witnesses valid; False: none does), count (at_least at most the
reference's number, at_most at least its large regions), volume bounds against
Monte Carlo, planned motions followed between their configurations by the
reference (valid, one sign of det A, joints within the limits), the pose box,
box enclosures, and generalized aspects on one design.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy import ndimage

from moveability import analyze, load_analysis, plan_motion, save_analysis
from moveability.analysis.joint_space import count_in_joint_space
from moveability.errors import InvalidParameterError
from moveability.intervals import Interval
from moveability.mechanisms import from_spec
from moveability.mechanisms.base import REACH_OUT, REGULAR

PI = np.pi
U = np.array([[np.cos(a), np.sin(a), 0.0] for a in np.arange(3) * 2 * PI / 3])


# ------------------------------------------------------------------ reference
class Ref:
    """Brute-force Delta: limits a list of (lo, hi) or None (unlimited)."""

    def __init__(self, design, limits, n=41):
        self.R, self.r, self.la, self.lb = design
        self.periodic = [lim is None for lim in limits]
        self.limits = np.array([(-PI, PI) if lim is None else lim for lim in limits], float)
        self.n = n
        axes = [
            np.linspace(lo, hi, n, endpoint=not per)
            for (lo, hi), per in zip(self.limits, self.periodic, strict=True)
        ]
        q = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
        mask = self.circumradius(q) < self.lb
        # unlimited joints: pad with the opposite face, label, join each pad cell's
        # label with that of the cell it copies
        pad = [(1, 1) if per else (0, 0) for per in self.periodic]
        lab, _ = ndimage.label(np.pad(mask, pad, mode="wrap"), structure=np.ones((3, 3, 3)))
        core = lab[tuple(slice(p[0], p[0] + n) for p in pad)]
        parent: dict[int, int] = {}

        def find(a):
            while parent.get(a, a) != a:
                a = parent[a]
            return a

        for ax, per in enumerate(self.periodic):
            if not per:
                continue
            for src, dst in ((0, n), (n + 1, 1)):
                s, d = [slice(None)] * 3, [slice(None)] * 3
                s[ax], d[ax] = src, dst
                a, b = lab[tuple(s)].ravel(), lab[tuple(d)].ravel()
                for x, y in zip(a[a > 0], b[a > 0], strict=True):
                    rx, ry = find(int(x)), find(int(y))
                    if rx != ry:
                        parent[rx] = ry
        roots = np.vectorize(lambda v: find(int(v)) if v else 0, otypes=[int])(core)
        uniq = np.unique(roots[roots > 0])
        self.labels = np.searchsorted(uniq, roots) + 1
        self.labels[roots == 0] = 0
        self.n_components = len(uniq)
        self.sizes = np.bincount(self.labels.ravel(), minlength=len(uniq) + 1)[1:]

    def centres(self, q):
        q = np.asarray(q, float)
        c = (self.R - self.r + self.la * np.cos(q))[..., None] * U
        c[..., 2] = -self.la * np.sin(q)
        return c

    def circumradius(self, q):
        c = self.centres(q)
        e = [c[..., (k + 1) % 3, :] - c[..., k, :] for k in range(3)]
        sides = np.prod([np.linalg.norm(v, axis=-1) for v in e], axis=0)
        area2 = np.linalg.norm(np.cross(e[0], -e[2]), axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            rho = sides / (2 * area2)
        return np.where(np.isfinite(rho), rho, np.inf)

    def forward(self, q, side):
        c = self.centres(q)
        e1, e2 = c[..., 1, :] - c[..., 0, :], c[..., 2, :] - c[..., 0, :]
        n = np.cross(e1, e2)
        n = n / np.linalg.norm(n, axis=-1, keepdims=True)
        m = np.stack([e1, e2, n], axis=-2)
        rhs = np.stack([0.5 * (e1 * e1).sum(-1), 0.5 * (e2 * e2).sum(-1), 0 * e1[..., 0]], -1)
        x = np.linalg.solve(m, rhs[..., None])[..., 0]
        h = np.sqrt(self.lb**2 - (x * x).sum(-1))
        return c[..., 0, :] + x + np.asarray(side)[..., None] * h[..., None] * n

    def det_a(self, pose, q):
        return np.linalg.det(np.asarray(pose)[..., None, :] - self.centres(q))

    def leg_angles(self, pose, i, tol=0.0):
        d = pose + (self.r - self.R) * U[i]
        a, b = d @ U[i], d[2]
        k = (d @ d + self.la**2 - self.lb**2) / (2 * self.la)
        rho = np.hypot(a, b)
        if rho == 0 or abs(k) > rho * (1 + tol):
            return []
        phi, g = np.arctan2(b, a), np.arccos(np.clip(k / rho, -1, 1))
        return [-phi + g, -phi - g]

    def within(self, i, t, slack=0.0):
        if self.periodic[i]:
            return True
        lo, hi = self.limits[i]
        return lo + np.mod(t - lo + slack, 2 * PI) - slack <= hi + slack

    def wrapped(self, i, t):
        lo = self.limits[i, 0]
        return t if self.periodic[i] else lo + np.mod(t - lo, 2 * PI)

    def inverse(self, pose):
        per = []
        for i in range(3):
            found = [self.wrapped(i, t) for t in self.leg_angles(pose, i) if self.within(i, t)]
            if not found:
                return []
            per.append(found)
        return [np.array(q) for q in itertools.product(*per)]

    def in_w(self, poses):
        """Vectorised workspace membership."""
        poses = np.asarray(poses, float)
        ok = np.ones(len(poses), bool)
        for i in range(3):
            d = poses + (self.r - self.R) * U[i]
            a, b = d @ U[i], d[:, 2]
            k = ((d * d).sum(1) + self.la**2 - self.lb**2) / (2 * self.la)
            rho = np.hypot(a, b)
            with np.errstate(all="ignore"):
                g = np.arccos(np.clip(k / rho, -1, 1))
            phi = np.arctan2(b, a)
            inside = np.zeros(len(poses), bool)
            for t in (-phi + g, -phi - g):
                inside |= self.within(i, t)
            ok &= (np.abs(k) <= rho) & inside
        return ok

    def label(self, q):
        k = []
        for i, (lo, hi) in enumerate(self.limits):
            if self.periodic[i]:
                k.append(int(np.round(np.mod(q[i] - lo, 2 * PI) / (2 * PI) * self.n)) % self.n)
            else:
                k.append(
                    int(np.clip(np.round((q[i] - lo) / (hi - lo) * (self.n - 1)), 0, self.n - 1))
                )
        return int(self.labels[tuple(k)])

    def regions_of(self, pose):
        """{(side, component)} of the pose's configurations; None near det A = 0 or
        off the labelled grid."""
        out = set()
        for q in self.inverse(pose):
            d = self.det_a(pose, q)
            if abs(d) < 1e-3 * np.linalg.norm(pose - self.centres(q), axis=-1).prod():
                return None
            lab = self.label(q)
            if lab == 0:
                return None
            out.add((int(np.sign(d)), lab))
        return out

    def stable_regions(self, pose, step):
        here = self.regions_of(pose)
        if here is None:
            return None
        for e in np.eye(3):
            for s in (1, -1):
                if self.regions_of(pose + s * step * e) != here:
                    return None
        return here

    def config_ok(self, pose, q, tol):
        for i in range(3):
            elbow = (self.R + self.la * np.cos(q[i])) * U[i] - [0, 0, self.la * np.sin(q[i])]
            if abs(np.linalg.norm(pose + self.r * U[i] - elbow) - self.lb) > tol:
                return False
            if not self.within(i, q[i], 1e-9):
                return False
        return True

    def follow(self, a, b, qa, sign, n=40):
        """The configuration from ``(a, qa)`` followed along the segment to ``b``
        (nearest solution each step); (end joints, problem or None)."""
        q = np.array(qa, float)
        for s in np.linspace(0, 1, n + 1)[1:]:
            p = a + s * (b - a)
            new = []
            for i in range(3):
                sols = np.array(self.leg_angles(p, i, tol=1e-9))
                if sols.size == 0:
                    return q, f"leg {i} unreachable at {p.tolist()}"
                dd = np.angle(np.exp(1j * (sols - q[i])))
                new.append(q[i] + dd[np.argmin(np.abs(dd))])
            new = np.array(new)
            if np.abs(new - q).max() > 0.3:
                return q, f"joint jump at {p.tolist()}"
            q = new
            if not all(self.within(i, q[i], 1e-9) for i in range(3)):
                return q, f"joint limit at {p.tolist()}"
            if np.sign(self.det_a(p, q)) != sign:
                return q, f"det A changes sign at {p.tolist()}"
        return q, None


def _spec(design, limits):
    names = ("base_radius", "platform_radius", "arm", "rod")
    return {
        "mechanism": "delta",
        "parameters": dict(zip(names, design, strict=True)),
        "limits": {
            f"theta{i + 1}": "unlimited" if lim is None else list(lim)
            for i, lim in enumerate(limits)
        },
    }


def _close(a, b, tol=1e-4):
    return np.abs(np.angle(np.exp(1j * (np.asarray(a) - np.asarray(b))))).max() <= tol


# ------------------------------------------------------------------- designs
#: name: (R, r, la, lb), limits, precision, analysis options
CASES = {
    # the arm as long as the rod, limits at -pi/2 and pi/2: 4 regions, count proved
    "arm-equals-rod": ((10.0, 4.0, 8.0, 8.0), [(-PI / 2, PI / 2)] * 3, 0.5, {"resolve": False}),
    "arm-near-rod": ((10.0, 4.0, 8.0, 8.05), [(-PI / 2, PI / 2)] * 3, 1.0, {"resolve": False}),
    # the rod barely reaches the legs' meeting point, limits at 0 and pi/2
    "rod-barely": ((10.0, 4.0, 8.0, 6.05), [(0.0, PI / 2)] * 3, 0.02, {"resolve": False}),
    "unlimited": ((10.0, 4.0, 8.0, 10.0), [None] * 3, 1.0, {"resolve": False}),
    "radii-close": ((4.01, 4.0, 8.0, 10.0), [(0.0, PI / 2)] * 3, 1.0, {"resolve": False}),
    "across-pi": (
        (10.0, 4.0, 8.0, 10.0),
        [(-PI / 2, PI), None, (PI / 2, 3 * PI / 2)],
        2.0,
        {"resolve": False},
    ),
    "example-per-axis": (
        (0.2, 0.05, 0.35, 0.8),
        [(-PI / 3, PI / 2)] * 3,
        (0.06, 0.06, 0.12),
        {"resolve": False},
    ),
}


@pytest.fixture(scope="module", params=list(CASES))
def case(request):
    design, limits, precision, options = CASES[request.param]
    spec = _spec(design, limits)
    m = from_spec(spec)
    return request.param, m, Ref(design, limits), analyze(m, precision=precision, **options)


def _labelled(m, ref, rng, n, step_frac=0.005):
    lo, hi = m.pose_box()
    poses = lo + (hi - lo) * rng.random((n, 3))
    step = step_frac * (hi - lo)
    return poses, [ref.stable_regions(p, step) for p in poses]


def test_locate_feasible_count_and_volumes(case):
    _check_answers(*case)


def _check_answers(name, m, ref, result):
    """locate, count, volumes and feasible against the reference (see the module)."""
    rng = np.random.default_rng(11)
    lo, hi = m.pose_box()
    box = float(np.prod(hi - lo))
    poses, labels = _labelled(m, ref, rng, 700)
    located = result.locate(poses)["points"]
    inside = ref.in_w(poses)
    for p, point, here in zip(poses, located, inside, strict=True):
        assert point["workspace"] in (None, bool(here)), (name, p.tolist())
    # region answers: one reference region of the region's sign in every YES, in no NO
    yes = {r.id: [] for r in result.regions}
    no = {r.id: [] for r in result.regions}
    for lab, point in zip(labels, located, strict=True):
        if lab is None:
            continue
        for rid, answer in point["regions"].items():
            if answer is True:
                assert lab, (name, rid)
                yes[int(rid)].append(lab)
            elif answer is False:
                no[int(rid)].append(lab)
    mapped = {}
    for region in result.regions:
        if not yes[region.id]:
            continue
        common = set.intersection(*yes[region.id]) - set().union(*no[region.id])
        common = {c for c in common if c[0] == region.sign}
        assert common, (name, region.id)
        mapped[region.id] = common
    singles = [next(iter(v)) for v in mapped.values() if len(v) == 1]
    assert len(singles) == len(set(singles))
    # the count
    at_least, at_most = result.count
    assert at_least <= 2 * ref.n_components
    large = 2 * int((ref.sizes >= 0.005 * ref.labels.size).sum())
    assert at_most is None or at_most >= large
    # volumes against Monte Carlo over the pose box (vectorised)
    sample = lo + (hi - lo) * rng.random((300_000, 3))
    frac = ref.in_w(sample).mean()
    estimate, se = frac * box, np.sqrt(frac * (1 - frac) / 300_000) * box
    inner, outer = result.workspace["volume"]
    assert inner - 4 * se - 1e-12 <= estimate <= outer + 4 * se + 1e-12, (name, inner, outer)
    for region in result.regions:
        if len(mapped.get(region.id, ())) != 1:
            continue
        target = next(iter(mapped[region.id]))
        f = np.mean([lab is not None and target in lab for lab in labels])
        unknown = np.mean([lab is None for lab in labels])
        s = np.sqrt(max(f, 1e-9) * (1 - f) / len(labels)) * box
        assert region.area[1] >= f * box - 4 * s, (name, region.id)
        assert region.area[0] <= (f + unknown) * box + 4 * s, (name, region.id)
    # feasible on pairs of labelled poses
    idx = [i for i, lab in enumerate(labels) if lab]
    decided = 0
    for _ in range(30 if len(idx) >= 2 else 0):
        a, b = rng.choice(idx, 2, replace=False)
        answer = result.feasible([poses[a], poses[b]])
        shared = labels[a] & labels[b]
        if answer["feasible"] is True:
            decided += 1
            assert shared, (name, poses[a].tolist(), poses[b].tolist())
            for p, q in zip((poses[a], poses[b]), answer["postures"], strict=True):
                assert ref.config_ok(p, np.array(q), 1e-7 * ref.lb)
        elif answer["feasible"] is False:
            decided += 1
            assert not shared, (name, poses[a].tolist(), poses[b].tolist())
    if name != "rod-barely":  # its workspace is 1e-4 of the box
        assert decided > 0 and mapped


def test_planned_motions_are_valid_between_their_configurations(case):
    name, m, ref, result = case
    rng = np.random.default_rng(12)
    lo, hi = m.pose_box()
    poses = lo + (hi - lo) * rng.random((3000, 3))
    located = result.locate(poses)["points"]
    planned = 0
    for region in result.regions:
        ins = [i for i, p in enumerate(located) if p["regions"][str(region.id)] is True]
        for _ in range(1 if len(ins) >= 3 else 0):
            pick = rng.choice(ins, 3, replace=False)
            motion = plan_motion(result, poses[pick])
            assert motion["feasible"] is True
            sign = next(r.sign for r in result.regions if r.id == motion["region"])
            path = np.array([s["pose"] for s in motion["path"]])
            joints = np.array([s["joints"] for s in motion["path"]])
            for k in motion["waypoints"][:1]:
                assert np.allclose(path[k], poses[pick[0]])
            for k in range(len(path)):
                assert ref.config_ok(path[k], joints[k], 1e-7 * ref.lb), (name, k)
                assert np.sign(ref.det_a(path[k], joints[k])) == sign
            for k in range(len(path) - 1):
                if np.allclose(path[k], path[k + 1]):  # a posture change: at a fold
                    assert _close(joints[k], joints[k + 1], 1e-3), (name, k)
                    continue
                end, problem = ref.follow(path[k], path[k + 1], joints[k], sign)
                if problem is None and _close(end, joints[k + 1]):
                    continue
                # from a fold the branch is set by the far end: follow backwards
                start, back = ref.follow(path[k + 1], path[k], joints[k + 1], sign)
                assert back is None and _close(start, joints[k]), (name, k, problem, back)
            planned += 1
    if name != "rod-barely":
        assert planned > 0


# ------------------------------------------------------- counts proved
#: designs whose count of regions the analysis proves (in the joint space, see
#: moveability.analysis.joint_space): (R, r, la, lb), limits, the reference's
#: count (a check of its grid: the symmetric design has six pockets of a few
#: nodes at 61 per joint, in corners of the joint box)
PROVED = {
    "symmetric": ((10.0, 4.0, 8.0, 10.0), [(-PI / 2, PI / 2)] * 3, 16),
    "asymmetric": (
        (10.0, 4.0, 8.0, 10.0),
        [(-PI / 3, PI / 2), (-PI / 2, PI / 3), (0.0, PI)],
        6,
    ),
    "unlimited": ((10.0, 2.0, 5.0, 14.0), [None] * 3, 2),
    "example": ((0.2, 0.05, 0.35, 0.8), [(-PI / 3, PI / 2)] * 3, 2),
}


@pytest.fixture(scope="module", params=list(PROVED))
def proved(request):
    """The design analysed at 1/16 of each span of its pose box, the count proved
    in the joint space and no refinement of the poses below the precision."""
    design, limits, _ = PROVED[request.param]
    m = from_spec(_spec(design, limits))
    lo, hi = m.pose_box()
    result = analyze(m, precision=tuple((hi - lo) / 16), resolve_levels=0)
    return request.param, m, Ref(design, limits, n=61), result


def test_proved_counts_equal_the_reference(proved):
    name, _, ref, result = proved
    expected = 2 * ref.n_components
    assert expected == PROVED[name][2], (name, ref.sizes)
    assert result.count == (expected, expected), name
    assert result.n_regions == expected
    assert result.joint_count is not None and result.joint_count.decided
    # the regions listed at this precision are distinct ones of the reference
    assert 1 <= len(result.regions) <= expected


def test_proved_designs_locate_and_bracket_volumes(proved):
    _check_answers(*proved)


@pytest.mark.parametrize("name", ["symmetric", "asymmetric"])
def test_every_region_the_count_proves_is_listed(name):
    """With the resolution on, the regions the joint-space count proves are all
    listed, each with a certified part (refined at a configuration of each), and
    every answer about them holds against the reference."""
    design, limits, expected = PROVED[name]
    m = from_spec(_spec(design, limits))
    lo, hi = m.pose_box()
    result = analyze(m, precision=tuple((hi - lo) / 16))
    assert result.count == (expected, expected)
    assert len(result.regions) == expected
    assert all(r.area[0] > 0 for r in result.regions)
    assert not result.unlisted_witnesses().any()
    _check_answers(name, m, Ref(design, limits, n=61), result)


def test_regions_listed_at_the_witnesses_are_saved_and_read_back(tmp_path):
    design, limits, expected = PROVED["asymmetric"]
    m = from_spec(_spec(design, limits))
    lo, hi = m.pose_box()
    result = analyze(m, precision=tuple((hi - lo) / 16))
    path = tmp_path / "delta.npz"
    save_analysis(result, path)
    again = load_analysis(path)
    assert len(again.regions) == expected
    assert again.to_dict() == result.to_dict()
    poses = lo + (hi - lo) * np.random.default_rng(2).random((300, 3))
    assert again.locate(poses) == result.locate(poses)


@pytest.mark.parametrize("name", ["arm-equals-rod", "unlimited", "across-pi", "example-per-axis"])
def test_the_joint_condition_and_its_enclosures(name):
    """``F = 4 lb^2 |a x b|^2 - |a|^2 |b|^2 |a - b|^2`` of the reference's centres:
    positive exactly where the circumradius is below lb; the package's boxes hold
    F and its finite-difference gradient at sampled joints."""
    design, limits, _, _ = CASES[name]
    ref = Ref(design, limits, n=3)
    condition = from_spec(_spec(design, limits)).joint_condition()
    rng = np.random.default_rng(14)
    lo, hi = ref.limits.T

    def f_ref(q):
        c = ref.centres(q)
        a, b = c[..., 0, :] - c[..., 2, :], c[..., 1, :] - c[..., 2, :]
        sq = lambda v: (v * v).sum(-1)  # noqa: E731
        return 4 * ref.lb**2 * sq(np.cross(a, b)) - sq(a) * sq(b) * sq(a - b)

    centre = lo + (hi - lo) * rng.random((400, 3))
    half = 0.05 * rng.random((400, 1)) * (hi - lo)
    value, grad, _ = condition.terms(centre - half, centre + half)
    scale = ref.lb**6
    for _ in range(10):
        q = centre - half + 2 * half * rng.random(centre.shape)
        f = f_ref(q)
        rho = ref.circumradius(q)
        clear = np.abs(f) > 1e-9 * scale
        assert ((f > 0) == (rho < ref.lb))[clear].all()
        slack = 1e-9 * scale
        assert ((f >= value.lo - slack) & (f <= value.hi + slack)).all()
        for i in range(3):
            step = np.zeros(3)
            step[i] = 1e-6
            d = (f_ref(q + step) - f_ref(q - step)) / 2e-6
            assert ((d >= grad[i].lo - 1e-4 * scale) & (d <= grad[i].hi + 1e-4 * scale)).all()


@pytest.mark.parametrize("name", list(CASES))
def test_joint_space_counts_bracket_the_reference(name):
    """The count in the joint space on the hostile designs: equal to the
    reference's where it is proved; else its bounds hold it. It stays open where
    two centres may meet (``la >= R - r`` and joints reaching ``cos theta = (r -
    R) / la``): there the circumradius condition has a singular point, where no
    flow attaches the cells about it."""
    design, limits, _, _ = CASES[name]
    found = count_in_joint_space(from_spec(_spec(design, limits)), max_leaves=1 << 16)
    assert found is not None
    expected = 2 * Ref(design, limits, n=61).n_components
    assert found.at_least <= expected
    if found.at_most is not None:
        assert found.at_most >= expected
    if name in ("arm-equals-rod", "arm-near-rod", "rod-barely", "example-per-axis"):
        assert found.decided and found.at_least == expected


# ------------------------------------------------------------ small, tight
def test_narrow_limits_volume_and_locate():
    """Joints 0.02 rad wide: W is two thin sheets far apart in a large pose box;
    the volume bounds hold the Monte Carlo estimate sampled about them."""
    design, limits = (10.0, 4.0, 8.0, 15.0), [(0.3, 0.32)] * 3
    ref = Ref(design, limits)
    m = from_spec(_spec(design, limits))
    result = analyze(m, precision=0.05, resolve=False)
    rng = np.random.default_rng(13)
    axis = np.linspace(0.3, 0.32, 11)
    q = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), -1).reshape(-1, 3)
    total, var = 0.0, 0.0
    near = []
    for side in (1, -1):
        f = ref.forward(q, side)
        lo, hi = f.min(0), f.max(0)
        lo, hi = lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo)
        vol = float(np.prod(hi - lo))
        p = lo + (hi - lo) * rng.random((200_000, 3))
        inside = ref.in_w(p)
        total += inside.mean() * vol
        var += inside.mean() * (1 - inside.mean()) / p.shape[0] * vol**2
        near.append(p[:3000])
    inner, outer = result.workspace["volume"]
    assert inner - 4 * np.sqrt(var) <= total <= outer + 4 * np.sqrt(var)
    poses = np.concatenate(near)
    located = result.locate(poses)["points"]
    for p, point, here in zip(poses, located, ref.in_w(poses), strict=True):
        assert point["workspace"] in (None, bool(here)), p.tolist()


def test_tiny_workspace_of_a_barely_long_rod():
    """lb = 6.05 with the legs meeting at rho = 6 when all arms point down: the
    workspace (about 0.01) is bracketed and its count proved 2."""
    design, limits = (10.0, 4.0, 8.0, 6.05), [(0.0, PI / 2)] * 3
    ref = Ref(design, limits)
    result = analyze(from_spec(_spec(design, limits)), precision=0.02, resolve=False)
    q = PI / 2 - 0.007 * np.random.default_rng(14).random((4000, 3))
    q = q[ref.circumradius(q) < ref.lb]
    rng = np.random.default_rng(15)
    for side in (1, -1):
        f = ref.forward(q, side)
        lo, hi = f.min(0) - 0.01, f.max(0) + 0.01
        p = lo + (hi - lo) * rng.random((400_000, 3))
        inside = ref.in_w(p)
        est = inside.mean() * float(np.prod(hi - lo))
        se = np.sqrt(inside.mean() * (1 - inside.mean()) / p.shape[0]) * float(np.prod(hi - lo))
        region = next(r for r in result.regions if r.sign == side)
        assert region.area[0] - 4 * se <= est <= region.area[1] + 4 * se
        located = result.locate(p[:4000])["points"]
        for point, here in zip(located, inside[:4000], strict=True):
            assert point["workspace"] in (None, bool(here))
            if point["regions"][str(region.id)] is True:
                assert here
    assert result.count == (2, 2) and ref.n_components == 1


def test_pose_box_holds_every_configuration_of_random_designs():
    """Random lengths and limits (at 0, +-pi/2, +-pi, across pi, nearly a full turn,
    unlimited): the pose box holds the forward kinematics of every sampled valid q,
    and a design is refused only when no q within the limits closes the legs."""
    rng = np.random.default_rng(16)
    refused = built = 0
    for _ in range(120):
        R, r, la = rng.uniform(0.5, 10.0, 3)
        lb = rng.uniform(0.3, 20.0)
        limits = []
        for _ in range(3):
            if rng.random() < 0.15:
                limits.append(None)
                continue
            start = float(rng.choice([-PI, -PI / 2, 0.0, PI / 2, PI, rng.uniform(-4, 4)]))
            width = float(rng.choice([1e-3, 0.05, PI / 2, PI, 2 * PI - 1e-3, rng.uniform(0, 6)]))
            limits.append((start, start + width))
        ref = Ref((R, r, la, lb), limits, n=3)
        q = ref.limits[:, 0] + np.diff(ref.limits, axis=1)[:, 0] * rng.random((5000, 3))
        corners = [[ref.limits[i, (k >> i) & 1] for i in range(3)] for k in range(8)]
        q = np.concatenate([np.array(corners), q])
        ok = ref.circumradius(q) < lb
        try:
            m = from_spec(_spec((R, r, la, lb), limits))
        except InvalidParameterError:
            refused += 1
            assert not ok.any()
            continue
        built += 1
        lo, hi = m.pose_box()
        for side in (1, -1):
            p = ref.forward(q[ok], side)
            assert ((p >= lo) & (p <= hi)).all()
    assert refused > 5 and built > 30


@pytest.mark.parametrize(
    "design",
    [
        (10.0, 4.0, 8.0, 8.0),
        (4.0, 4.0, 8.0, 8.0),
        (4.0, 10.0, 8.0, 10.0),
        (10.0, 4.0, 8.0, 8.05),
        (10.0, 4.0, 12.0, 9.0),
    ],
    ids=["la=lb", "R=r,la=lb", "r>R", "la~lb", "la>lb"],
)
def test_box_enclosures_hold_sampled_configurations(design):
    """det A, each leg's reach and its joint enclosures over small boxes (some about
    the base axis, where t = 0 when R = r), per posture."""
    m = from_spec(_spec(design, [None] * 3))
    ref = Ref(design, [None] * 3, n=3)
    rng = np.random.default_rng(17)
    lo, hi = m.pose_box()
    n = 6000
    centre = lo + (hi - lo) * rng.random((n, 3))
    centre[:600] = 0.5 * rng.standard_normal((600, 3))
    # boxes about leg 1's lateral reach (|d| near lb, t near la), where g is
    # smallest inside the box's range of t, not at its ends
    R, r, la, lb = design
    phi = rng.uniform(-PI, PI, 600)
    lateral = lb * (1 - 0.01 * rng.random(600)) * rng.choice([-1.0, 1.0], 600)
    centre[600:1200] = np.stack([la * np.cos(phi) + R - r, lateral, la * np.sin(phi)], axis=1)
    half = 0.03 * (hi - lo).max() * rng.random((n, 1))
    half[-1000:] *= 15.0  # boxes as large as the coarse cells of a tree
    blo, bhi = centre - half, centre + half
    reaches = [leg.reach(blo, bhi) for leg in m.legs]
    checked = 0
    for posture in range(8):
        branch = m.postures[posture]
        angles = []
        for i, r in enumerate(reaches):
            regular = r.status == REGULAR
            b = r.branches[branch[i]]
            angles.append(
                Interval(np.where(regular, b.lo, r.hull.lo), np.where(regular, b.hi, r.hull.hi))
            )
        det = m.det_a_boxes(blo, bhi, angles, posture=posture)
        p = blo + (bhi - blo) * rng.random((n, 3))
        q = np.stack([m.legs[i].angles(p)[:, branch[i]] for i in range(3)], axis=1)
        for i in range(3):
            st, qi, e = reaches[i].status, q[:, i], angles[i]
            assert not (np.isfinite(qi) & (st == REACH_OUT)).any()
            assert np.isfinite(qi[st == REGULAR]).all()
            with np.errstate(invalid="ignore"):
                v = qi + 2 * PI * np.round((e.mid - qi) / (2 * PI))
            known = np.isfinite(qi) & np.isfinite(e.lo) & np.isfinite(e.hi)
            assert ((v >= e.lo) & (v <= e.hi))[known].all()
        ok = np.isfinite(q).all(axis=1)
        d = ref.det_a(p[ok], q[ok])
        slack = 1e-9 * (1 + np.abs(d))
        assert ((d >= det.lo[ok] - slack) & (d <= det.hi[ok] + slack)).all()
        checked += int(ok.sum())
    assert checked > 5000


def _serial_terms(ref, pose, q):
    """Half dF_i/dtheta_i of each leg: (P + r u_i - E_i) . (-dE_i/dtheta_i)."""
    out = []
    for i in range(3):
        c, s = np.cos(q[..., i]), np.sin(q[..., i])
        zero = 0 * c
        elbow = (ref.R + ref.la * c)[..., None] * U[i] + np.stack([zero, zero, -ref.la * s], -1)
        d_elbow = (-ref.la * s)[..., None] * U[i] + np.stack([zero, zero, -ref.la * c], -1)
        out.append(-((pose + ref.r * U[i] - elbow) * d_elbow).sum(-1))
    return np.stack(out, -1)


def test_generalized_aspects_of_an_arm_as_long_as_the_rod():
    """Generalized aspects (det A and det B of one sign each): the reference labels
    {q: rho < lb} per side of the centres' plane and sign pattern of the legs'
    serial terms; the count and the region answers agree with it."""
    design, limits = (10.0, 4.0, 8.0, 8.0), [(-PI / 2, PI / 2)] * 3
    ref = Ref(design, limits, n=3)
    n = 41
    axes = [np.linspace(lo, hi, n) for lo, hi in ref.limits]
    q = np.stack(np.meshgrid(*axes, indexing="ij"), -1)
    closed = ref.circumradius(q) < ref.lb
    labels, total = {}, 0
    for side in (1, -1):
        with np.errstate(all="ignore"):
            signs = np.sign(_serial_terms(ref, ref.forward(q, side), q))
        for pattern in itertools.product((1, -1), repeat=3):
            mask = closed & (signs == np.array(pattern)).all(-1)
            labels[side, pattern], k = ndimage.label(mask, structure=np.ones((3, 3, 3)))
            total += k

    def aspects_of(pose):
        out = set()
        for qq in ref.inverse(pose):
            d = ref.det_a(pose, qq)
            terms = _serial_terms(ref, pose, qq)
            scale = np.linalg.norm(pose - ref.centres(qq), axis=-1).prod()
            if abs(d) < 1e-3 * scale or (np.abs(terms) < 1e-3 * ref.la * ref.lb).any():
                return None
            lo, hi = ref.limits[:, 0], ref.limits[:, 1]
            k = np.clip(np.round((qq - lo) / (hi - lo) * (n - 1)).astype(int), 0, n - 1)
            key = (int(np.sign(d)), tuple(int(v) for v in np.sign(terms)))
            lab = int(labels[key][tuple(k)])
            if lab == 0:
                return None
            out.add((*key, lab))
        return out

    m = from_spec(_spec(design, limits))
    result = analyze(m, precision=1.0, generalized_aspects=True, resolve=False)
    assert total == 4 and 1 <= result.count[0] <= total
    rng = np.random.default_rng(18)
    lo, hi = m.pose_box()
    poses = lo + (hi - lo) * rng.random((800, 3))
    step = 0.005 * (hi - lo)
    found = []
    for p in poses:
        here = aspects_of(p)
        moves = [p + s * step * e for e in np.eye(3) for s in (1, -1)]
        found.append(
            here if here is not None and all(aspects_of(x) == here for x in moves) else None
        )
    located = result.locate(poses)["points"]
    yes = {r.id: [] for r in result.regions}
    no = {r.id: [] for r in result.regions}
    for here, point in zip(found, located, strict=True):
        if here is None:
            continue
        for rid, answer in point["regions"].items():
            if answer is True:
                assert here
                yes[int(rid)].append(here)
            elif answer is False:
                no[int(rid)].append(here)
    checked = 0
    for region in result.regions:
        if yes[region.id]:
            common = set.intersection(*yes[region.id]) - set().union(*no[region.id])
            assert {c for c in common if c[0] == region.sign}, region.id
            checked += 1
    assert checked >= 2
