"""The Delta robot written as a user-defined mechanism (three translational pose
axes, three constraint legs) against the built-in Delta and a closed-form check.

Closed form (no code of the package): with ``u_i = (cos phi_i, sin phi_i, 0)``
and ``W = P + (r - R) u_i``, leg i's constraint is ``F = |W|^2 + la^2 - lb^2 -
(A cos t + B sin t)`` with ``A = 2 la W . u_i``, ``B = -2 la W_z``: writing
``A cos t + B sin t = h cos(t - beta)``, the roots are ``beta +- gamma``,
``cos gamma = C / h``, and ``dF/dt = h sin(t - beta)`` is positive at ``beta +
gamma`` (branch 0, as the package orders branches) and negative at ``beta -
gamma`` (branch 1). det A has the rows ``P + r u_i - E_i`` (the custom rows are
twice these). The regions are the two sides of the sphere centres' plane times the
components of the joints' box where the centres' circumradius is below ``lb``,
labelled here on a grid of the joints.
"""

from __future__ import annotations

import pathlib
import time
import tomllib

import numpy as np
import pytest
from scipy import ndimage

from custom_specs import custom_delta_spec
from moveability import analyze
from moveability.analysis.result import analysis_box
from moveability.hypertree.status import IN, OUT
from moveability.limits import JointLimit
from moveability.mechanisms import Delta
from moveability.mechanisms.custom import CustomMechanism, normalise_custom_spec

EXAMPLES = pathlib.Path(__file__).parents[2] / "examples"
PHI = np.arange(3) * 2.0 * np.pi / 3.0
U = np.stack([np.cos(PHI), np.sin(PHI), np.zeros(3)], axis=1)
# u_i's components as written in the constraints (exact: sqrt(3) is enclosed)
#: every choice of branches of the three legs
BRANCHES = [(b0, b1, b2) for b0 in (0, 1) for b1 in (0, 1) for b2 in (0, 1)]

#: (R, r, la, lb), joint limits (radians), precision
DESIGNS = {
    "example": ((0.2, 0.05, 0.35, 0.8), [(-np.pi / 3, np.pi / 2)] * 3, 0.1),
    "other": (
        (10.0, 4.0, 8.0, 15.0),
        [(-np.pi / 2, np.pi / 3), (-np.pi / 3, np.pi / 2), (-np.pi / 4, 2 * np.pi / 3)],
        1.0,
    ),
}


# ------------------------------------------------------------------ closed form
def leg_roots(design, poses, i):
    """Both roots of leg i at poses, shape (m, 2) (branch 0, branch 1); NaN if none."""
    R, r, la, lb = design
    w = poses + (r - R) * U[i]
    a = 2 * la * (w @ U[i])
    b = -2 * la * w[:, 2]
    c = (w * w).sum(axis=1) + la * la - lb * lb
    h = np.hypot(a, b)
    beta = np.arctan2(b, a)
    with np.errstate(invalid="ignore", divide="ignore"):
        gamma = np.where(np.abs(c) <= h, np.arccos(np.clip(c / h, -1.0, 1.0)), np.nan)
    return np.stack([beta + gamma, beta - gamma], axis=1)


def within(t, lo, hi):
    """Whether angles lie in [lo, hi] modulo 2 pi."""
    with np.errstate(invalid="ignore"):
        return np.isfinite(t) & (lo + np.mod(t - lo, 2 * np.pi) <= hi)


def det_a(design, poses, joints):
    R, r, la, _ = design
    rows = poses[:, None, :] + (r - R - la * np.cos(joints))[..., None] * U
    rows[..., 2] = poses[:, None, 2] + la * np.sin(joints)
    return np.linalg.det(rows)


def valid_postures(design, limits, poses, postures=BRANCHES):
    """(m, P) validity of each posture (a row of branches per posture) and det A
    there (NaN where invalid)."""
    roots = [leg_roots(design, poses, i) for i in range(3)]
    valid = np.zeros((poses.shape[0], len(postures)), dtype=bool)
    dets = np.full((poses.shape[0], len(postures)), np.nan)
    for p, branches in enumerate(postures):
        q = np.stack([roots[i][:, b] for i, b in enumerate(branches)], axis=1)
        ok = np.ones(poses.shape[0], dtype=bool)
        for i in range(3):
            ok &= within(q[:, i], *limits[i])
        valid[:, p] = ok
        dets[ok, p] = det_a(design, poses[ok], q[ok])
    return valid, dets


def in_workspace(design, limits, poses):
    return valid_postures(design, limits, poses)[0].any(axis=1)


def reference_count(design, limits, n=41):
    """Regions: two sides times the components of {rho < lb} on a joint grid."""
    R, r, la, lb = design
    axes = [np.linspace(lo, hi, n) for lo, hi in limits]
    q = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
    hh = R - r + la * np.cos(q)
    c = hh[..., None] * U
    c[..., 2] = -la * np.sin(q)
    a, b = c[..., 0, :] - c[..., 2, :], c[..., 1, :] - c[..., 2, :]
    n2 = (np.cross(a, b) ** 2).sum(-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        rho = np.sqrt((a * a).sum(-1) * (b * b).sum(-1) * ((a - b) ** 2).sum(-1)) / (
            2 * np.sqrt(n2)
        )
    mask = np.where(np.isfinite(rho), rho, np.inf) < lb
    _, components = ndimage.label(mask, structure=np.ones((3, 3, 3)))
    return 2 * components


# --------------------------------------------------------------------- fixture
@pytest.fixture(scope="module", params=list(DESIGNS))
def pair(request):
    design, limits, precision = DESIGNS[request.param]
    builtin = Delta(*design, tuple(JointLimit(lo, hi) for lo, hi in limits))
    # the box the built-in's analysis subdivides: both split the same cells
    box = analysis_box(builtin, np.full(3, float(precision)))[:2]
    custom = CustomMechanism(custom_delta_spec(design, limits, box))
    t0 = time.perf_counter()
    a = analyze(custom, precision, resolve=False)
    t1 = time.perf_counter()
    b = analyze(builtin, precision, resolve=False)
    t2 = time.perf_counter()
    print(f"\n{request.param}: custom {t1 - t0:.1f} s, built-in {t2 - t1:.1f} s")
    return design, limits, a, b


def test_example_file_is_the_built_in_example():
    with open(EXAMPLES / "delta-custom.toml", "rb") as stream:
        spec = tomllib.load(stream)
    builtin = Delta(*DESIGNS["example"][0])
    expected = custom_delta_spec(*DESIGNS["example"][:2], builtin.pose_box())
    got = normalise_custom_spec(spec)
    want = normalise_custom_spec(expected)
    assert got["parameters"] == want["parameters"] and got["bounds"] == want["bounds"]
    assert got["limits"] == want["limits"]
    # the constraints, written differently, are the same functions
    m, e = CustomMechanism(spec), CustomMechanism(expected)
    rng = np.random.default_rng(0)
    lo, hi = builtin.pose_box()
    poses = rng.uniform(lo, hi, (500, 3))
    q = rng.uniform(-np.pi, np.pi, (500, 3))
    assert np.allclose(m.constraints(poses, q), e.constraints(poses, q), atol=1e-12)
    assert np.allclose(m.constraints(poses, q), builtin.constraints(poses, q), atol=1e-12)


def test_three_pose_axes_and_the_built_in_postures(pair):
    design, _, a, b = pair
    m = a.mechanism
    assert m.pose_names == ("x", "y", "z") and m.periodic_axes == ()
    assert np.array_equal(m.postures, b.mechanism.postures)
    rng = np.random.default_rng(1)
    lo, hi = b.mechanism.pose_box()
    poses = rng.uniform(lo, hi, (400, 3))
    qa, qb = m.joint_angles(poses), b.mechanism.joint_angles(poses)
    assert np.array_equal(np.isnan(qa), np.isnan(qb))
    ok = np.isfinite(qa)
    assert ok.any()
    assert np.abs(np.angle(np.exp(1j * (qa[ok] - qb[ok])))).max() < 1e-9
    # the closed form's branches too (branch 0 where dF/dt > 0)
    for i in range(3):
        roots = leg_roots(design, poses, i)
        for p in range(8):
            branch = m.postures[p, i]
            sel = np.isfinite(qa[:, p, i])
            diff = np.angle(np.exp(1j * (qa[sel, p, i] - roots[sel, branch])))
            assert np.abs(diff).max() < 1e-7


def test_locate_agrees_with_the_built_in(pair):
    _, _, a, b = pair
    rng = np.random.default_rng(2)
    lo, hi = b.mechanism.pose_box()
    poses = rng.uniform(lo, hi, (2000, 3))
    la, lb = a.locate(poses)["points"], b.locate(poses)["points"]
    # one region per sign of det A in both (the designs hold one component of joints)
    by_sign_a = {r.sign: str(r.id) for r in a.regions}
    by_sign_b = {r.sign: str(r.id) for r in b.regions}
    assert sorted(by_sign_a) == sorted(by_sign_b) == [-1, 1]
    assert len(a.regions) == len(b.regions) == 2
    agree = agree_in_w = 0
    for pa, pb in zip(la, lb, strict=True):
        answers = [(pa["workspace"], pb["workspace"])] + [
            (pa["regions"][by_sign_a[s]], pb["regions"][by_sign_b[s]]) for s in (-1, 1)
        ]
        for x, y in answers:
            assert None in (x, y) or x == y, (pa, pb)
        definite = all(None not in pair for pair in answers)
        agree += definite
        agree_in_w += definite and pa["workspace"] is True
    # most of the box lies outside W: count the agreements inside it too
    assert agree >= 1000 and agree_in_w >= 100, (agree, agree_in_w)


def test_volumes_overlap_and_bracket_a_monte_carlo_estimate(pair):
    design, limits, a, b = pair
    va, vb = a.workspace["volume"], b.workspace["volume"]
    assert max(va[0], vb[0]) <= min(va[1], vb[1])
    rng = np.random.default_rng(3)
    lo, hi = b.mechanism.pose_box()
    box = float(np.prod(hi - lo))
    n = 40000
    inside = in_workspace(design, limits, rng.uniform(lo, hi, (n, 3)))
    frac = inside.mean()
    estimate = frac * box
    margin = 4 * np.sqrt(frac * (1 - frac) / n) * box
    for inner, outer in (va, vb):
        assert inner - margin <= estimate <= outer + margin
    for ra in a.regions:
        rb = next(r for r in b.regions if r.sign == ra.sign)
        assert max(ra.area[0], rb.area[0]) <= min(ra.area[1], rb.area[1])


def test_count_at_least_is_bounded_by_the_true_count(pair):
    design, limits, a, b = pair
    at_least, at_most = a.count
    b_least, b_most = b.count
    true = b_least if b_most == b_least else reference_count(design, limits)
    assert 1 <= at_least <= true
    assert at_most is None or at_most >= true  # the legs give no flows: expected open


def test_certified_sheets_hold_pointwise(pair):
    """Configurations sampled in the custom's leaves: where a sheet is certified
    valid (IN), the closed form's configuration of that posture is valid with det A
    of the sheet's sign; where it is certified empty (OUT), it is not valid; and the
    leaves certainly in W (or certainly out) agree with the closed form."""
    design, limits, a, _ = pair
    leaves = a.tree.leaves()
    table = a.table
    rng = np.random.default_rng(4)
    samples = 4
    lo, hi = leaves.lo, leaves.hi
    u = rng.random((lo.shape[0], samples, 3))
    poses = (lo[:, None, :] + u * (hi - lo)[:, None, :]).reshape(-1, 3)
    valid, dets = valid_postures(design, limits, poses, a.mechanism.postures)
    valid = valid.reshape(-1, samples, 8)
    dets = dets.reshape(-1, samples, 8)
    checked_in = checked_out = 0
    for p in range(8):
        certified = table.status[:, p] == IN
        assert valid[certified, :, p].all()
        sign = table.sign[certified, p]
        assert (np.sign(dets[certified, :, p]) == sign[:, None]).all()
        empty = table.status[:, p] == OUT
        assert not valid[empty, :, p].any()
        checked_in += int(certified.sum())
        checked_out += int(empty.sum())
    assert checked_in >= 100 and checked_out >= 100, (checked_in, checked_out)
    # the leaves certainly in W hold only poses of W; those it cannot meet, none
    certain, possible = a.workspace_cells()
    reached = valid.any(axis=2)
    assert reached[certain].all() and not reached[~possible].any()
    assert certain.sum() >= 100
