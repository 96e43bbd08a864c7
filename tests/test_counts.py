"""Certified counts of regions: bounds that always hold, and decided counts.

The five-bar reference is its joint space (as in ``test_analysis``): the
regions are the components of ``D = {q : |L2 - L4| < |C(q) - D(q)| < L2 + L4}``
times the two assembly modes. It is labelled on two grids; a design is used
for equality only where both grids give the same count.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner
from scipy import ndimage

from moveability import analyze
from moveability.cli import main
from moveability.intervals import Interval
from moveability.limits import JointLimit
from moveability.mechanisms import FiveBar, from_spec
from moveability.mechanisms.base import REGULAR
from moveability.sheets import classify_sheets

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


def assert_bounds_hold(result, truth):
    at_least, at_most = result.count
    assert at_least <= truth, (result.count, truth)
    if at_most is not None:
        assert truth <= at_most, (result.count, truth)
    if result.n_regions is not None:
        assert result.n_regions == truth


# ------------------------------------------------------------ the designs
@pytest.mark.parametrize("precision", [0.05, 0.02, 0.01])
def test_gap_five_bar_is_decided_with_the_defaults(precision):
    m = five_bar(*GAP_FIVE_BAR)
    result = analyze(m, precision=precision)
    assert result.count == (4, 4)
    assert result.n_regions == 4
    assert result.to_dict()["count"] == {"at_least": 4, "at_most": 4}
    assert "4 regions" in result.summary()


def test_gap_five_bar_reference_has_four_regions():
    m = five_bar(*GAP_FIVE_BAR)
    assert joint_space_count(m, 600) == joint_space_count(m, 1200) == 4


@pytest.mark.parametrize("precision", [0.05, 0.02])
def test_gap_five_bar_plain_pass_gives_bounds_that_hold(precision):
    result = analyze(five_bar(*GAP_FIVE_BAR), precision=precision, resolve=False)
    assert_bounds_hold(result, 4)
    # the plain pass at these precisions does not prove the count
    assert result.n_regions is None


def test_paper_five_bar_is_decided():
    m = five_bar((7.0, 8.0, 5.0, 8.0, 5.0), (0, np.pi), (0, np.pi))
    assert analyze(m, precision=0.05).count == (2, 2)


def test_paper_five_bar_with_whole_turns_is_decided():
    # [-pi, pi]: the stop at +-pi cuts the sheets, every angle is within the limits
    m = five_bar((7.0, 8.0, 5.0, 8.0, 5.0), (-np.pi, np.pi), (-np.pi, np.pi))
    result = analyze(m, precision=0.1)
    assert result.count == (2, 2)
    # near the tips of W every configuration has one sign: W is not N-connected
    assert result.n_connected is False


@pytest.mark.parametrize("precision", [0.1, 0.05])
def test_equal_leg_biglide_is_decided_with_the_defaults(precision):
    m = from_spec(EQUAL_BIGLIDE)
    # ++ and -- put both sliders at one place: never valid
    assert [m.identically_singular(p) for p in range(4)] == [True, False, False, True]
    result = analyze(m, precision=precision)
    assert result.count == (4, 4)
    assert biglide_count(m) == 4
    # the small region (rho1 < rho2) is found: the pose the issue names is in it
    answers = result.locate([[-2.5, 4.99]])["points"][0]["regions"]
    assert "in" in answers.values()


def test_equal_leg_biglide_plain_bounds_hold():
    assert_bounds_hold(analyze(from_spec(EQUAL_BIGLIDE), precision=0.1, resolve=False), 4)


def test_three_rpr_bounds_hold():
    """The issue's 3-RPR has 4 regions (volumes about 279, 278, 170, 169)."""
    m = from_spec(THREE_RPR)
    lo, hi = m.pose_box()
    precision = tuple(float(v) for v in (hi - lo) / 32)
    plain = analyze(m, precision=precision, resolve=False)
    assert_bounds_hold(plain, 4)
    resolved = analyze(m, precision=precision)
    assert_bounds_hold(resolved, 4)
    assert resolved.count[0] >= plain.count[0]


def test_identically_singular_postures_hold_no_region():
    m = from_spec(EQUAL_BIGLIDE)
    lo, hi = np.array([[-2.6, 3.0]]), np.array([[-2.4, 3.1]])
    table = classify_sheets(m, lo, hi)
    assert table.singular[0].tolist() == [True, False, False, True]
    assert not table.may_hold(1)[0, 0] and not table.may_hold(-1)[0, 3]


# --------------------------------------------------------- random designs
def random_designs(n, seed):
    rng = np.random.default_rng(seed)
    designs = []
    while len(designs) < n:
        lengths = tuple(float(v) for v in np.round(rng.uniform(2.0, 8.0, 5), 1))
        if len(designs) % 3 == 1:  # equal legs
            lengths = (lengths[0], lengths[1], lengths[2], lengths[1], lengths[2])
        limits = []
        for _ in range(2):
            if rng.random() < 0.25:
                limits.append(None)
            else:
                lo = float(np.round(rng.uniform(-np.pi, np.pi), 2))
                limits.append((lo, lo + float(np.round(rng.uniform(1.0, 2 * np.pi - 0.01), 2))))
        try:
            m = five_bar(lengths, *limits)
        except ValueError:
            continue
        designs.append(m)
    return designs


@pytest.mark.slow
def test_counts_of_sixty_random_five_bars():
    """Every bound holds, and most counts are definite, at precision 0.05.

    A third of the designs have equal legs (L1 = L3, L2 = L4); a quarter of the
    joints turn freely. The reference is used where two grids agree.
    """
    from joblib import Parallel, delayed

    from moveability.sweep.runner import design_row

    designs = random_designs(60, 21)
    rows = Parallel(n_jobs=2)(delayed(design_row)(m.to_spec(), [], [], 0.05) for m in designs)
    decided = 0
    for m, row in zip(designs, rows, strict=True):
        assert row["error"] is None, row
        at_least, at_most = row["regions_at_least"], row["regions_at_most"]
        fine, finer = joint_space_count(m, 800), joint_space_count(m, 1600)
        if fine == finer:
            assert at_least <= fine, (m, at_least, at_most, fine)
            assert at_most is None or fine <= at_most, (m, at_least, at_most, fine)
        else:  # the grids disagree: only what the tree proves for itself
            assert at_most is None or at_least <= at_most
        decided += at_least == at_most
    assert decided >= 52, decided


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


def test_counts_of_random_biglides():
    """Against the closed form; a third with equal legs."""
    decided = 0
    designs = random_biglides(30, 5)
    for m in designs:
        result = analyze(m, precision=0.1)
        assert_bounds_hold(result, biglide_count(m))
        decided += result.n_regions is not None
    assert decided >= 27, decided


# ----------------------------------------------------------- N-connectivity
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


WHOLE_TURN = (-np.pi, np.pi)


@pytest.mark.parametrize(
    "lengths",
    [(3.8, 7.8, 7.9, 1.7, 7.0), (1.5, 7.4, 6.8, 2.7, 5.9), (2.2, 2.0, 7.1, 7.2, 7.5)],
)
def test_n_connected_five_bars_are_certified(lengths):
    m = five_bar(lengths, WHOLE_TURN, WHOLE_TURN)
    result = analyze(m, precision=0.05)
    assert result.n_connected is True
    assert any(r.equals_workspace for r in result.regions)
    connected, in_w = joint_space_n_connected(m, 400, 200)
    assert connected and in_w > 1000


def test_not_n_connected_is_certified_with_a_witness():
    """W is not N-connected: some pose of W has no configuration in a region."""
    m = five_bar((2.2, 5.7, 5.3, 5.5, 7.5), WHOLE_TURN, WHOLE_TURN)
    result = analyze(m, precision=0.05)
    assert result.n_connected is False
    assert not joint_space_n_connected(m, 600, 300)[0]


# ------------------------------------------------ the certificate's ingredients
@pytest.mark.parametrize(
    "spec",
    [
        {"mechanism": "five-bar", "parameters": dict(zip(["L0", "L1", "L2", "L3", "L4"],
                                                         [7.0, 8.0, 5.0, 8.0, 5.0], strict=True)),
         "limits": {"theta1": [0, 3.14159], "theta2": [0, 3.14159]}},
        {"mechanism": "biglide", "parameters": {"L1": 5.0, "L2": 4.0},
         "limits": {"rho1": [-6, 6], "rho2": [-6, 6]}},
        {"mechanism": "3-RPR", "parameters": {"base": [[0, 0], [10, 1], [3, 9]],
                                             "platform": [[0, 0], [5, -1], [2, 4]]},
         "limits": {"rho1": [4, 14], "rho2": [4, 14], "rho3": [4, 14]}},
    ],
    ids=["five-bar", "biglide", "3-RPR"],
)
def test_rate_enclosures_hold_finite_differences(spec):
    """d(det A)/dX and dq/dX along the sheets enclose central differences."""
    m = from_spec(spec)
    rng = np.random.default_rng(3)
    lo, hi = m.pose_box()
    k = len(lo)
    poses = lo + (hi - lo) * rng.random((400, k))
    joints = m.joint_angles(poses)
    h, w = 1e-6, 1e-3
    box_lo, box_hi = poses - w, poses + w
    table = classify_sheets(m, box_lo, box_hi)
    regular = (table.leg_status == REGULAR).all(axis=1)
    checked = 0
    for p in range(m.postures.shape[0]):
        ok = regular & np.isfinite(joints[:, p]).all(axis=1)
        angles = [
            Interval(table.angles_lo[:, p, i], table.angles_hi[:, p, i]) for i in range(k)
        ]
        gradients = [
            leg.joint_gradient(box_lo, box_hi, int(m.postures[p][i]), angles[i])
            for i, leg in enumerate(m.legs)
        ]
        for axis in range(k):
            step = np.zeros(k)
            step[axis] = h
            up, down = m.joint_angles(poses + step)[:, p], m.joint_angles(poses - step)[:, p]
            dq = (up - down) / (2 * h)
            det = (m.det_a(poses + step, up) - m.det_a(poses - step, down)) / (2 * h)
            unit = [Interval(np.full(len(poses), float(j == axis))) for j in range(k)]
            rate = m.det_a_rate(box_lo, box_hi, angles, unit, [g[axis] for g in gradients])
            tol = 1e-5 * (1 + np.abs(det))
            sel = ok & np.isfinite(det)
            assert ((rate.lo - tol <= det) & (det <= rate.hi + tol))[sel].all()
            for i in range(k):
                tol_q = 1e-5 * (1 + np.abs(dq[:, i]))
                inside = (gradients[i][axis].lo - tol_q <= dq[:, i]) & (
                    dq[:, i] <= gradients[i][axis].hi + tol_q
                )
                assert inside[sel & (np.abs(dq[:, i]) < 1e3)].all()
            checked += int(sel.sum())
    assert checked > 500


def test_exact_zeros_are_not_widened():
    zero = Interval(np.zeros(2))
    product = zero * Interval([1.0, -3.0], [2.0, 5.0])
    assert product.lo.tolist() == [0.0, 0.0] and product.hi.tolist() == [0.0, 0.0]
    difference = Interval([1.5]) - Interval([1.5])
    assert difference.lo[0] == 0.0 and difference.hi[0] == 0.0
    # a product that underflows to zero is not exact: it is still widened
    tiny = Interval([1e-200]) * Interval([1e-200])
    assert tiny.lo[0] < 0.0 < tiny.hi[0]


# ------------------------------------------------------------------------ CLI
def test_regions_command_reports_the_count(tmp_path):
    spec = tmp_path / "gap.toml"
    spec.write_text(
        'mechanism = "five-bar"\n[parameters]\nL0 = 6.0\nL1 = 5.0\nL2 = 6.0\nL3 = 5.0\nL4 = 6.0\n'
        f"[limits]\ntheta1 = [{GAP_FIVE_BAR[1][0]!r}, \"pi\"]\n"
        f"theta2 = [{GAP_FIVE_BAR[2][0]!r}, {GAP_FIVE_BAR[2][1]!r}]\n"
    )
    runner = CliRunner()
    plain = runner.invoke(main, ["regions", str(spec), "-p", "0.05", "--no-resolve", "--json", "-"])
    assert plain.exit_code == 0, plain.output
    count = json.loads(plain.output)["count"]
    assert count["at_least"] <= 4 and (count["at_most"] is None or count["at_most"] >= 4)
    text = runner.invoke(main, ["regions", str(spec), "-p", "0.05", "--no-resolve"])
    assert "N-connected regions: at least" in text.output
    resolved = runner.invoke(main, ["regions", str(spec), "-p", "0.05", "--resolve", "--json", "-"])
    assert resolved.exit_code == 0, resolved.output
    assert_bounds_hold_json(json.loads(resolved.output)["count"], 4)


def assert_bounds_hold_json(count, truth):
    assert count["at_least"] <= truth
    assert count["at_most"] is None or truth <= count["at_most"]
