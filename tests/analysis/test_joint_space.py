"""The count of regions proved in the joint space of two-dyad mechanisms.

Differential tests against the joint-space reference of ``test_counts`` (the
components of the assembling pairs on uniform grids, used where two grids
agree) and the biglide's closed form; the certificates of the module on the
designs that need them (equal distal links, free joints); and the count as
:func:`moveability.analyze` reports it, saved and loaded.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from mpmath import mp, mpf

from moveability import analyze, load_analysis, save_analysis
from moveability.analysis.flows import into_corner
from moveability.analysis.joint_space import (
    count_in_joint_space,
    has_dyads,
    joint_condition,
    witness_configurations,
)
from moveability.hypertree.status import IN
from moveability.limits import JointLimit
from moveability.mechanisms import Delta, FiveBar, from_spec
from region_references import (
    EQUAL_BIGLIDE,
    GAP_FIVE_BAR,
    THREE_RPR,
    biglide_count,
    five_bar,
    joint_space_count,
    random_biglides,
)


def random_five_bars(n, seed):
    """Lengths in [1, 8]; a quarter with equal legs, a quarter with equal distal
    links (the knees may meet: isolated holes in D); a fifth of the joints free."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        lengths = [float(v) for v in np.round(rng.uniform(1.0, 8.0, 5), 2)]
        if len(out) % 4 == 1:
            lengths[3], lengths[4] = lengths[1], lengths[2]
        elif len(out) % 4 == 3:
            lengths[4] = lengths[2]
        limits = []
        for _ in range(2):
            if rng.random() < 0.2:
                limits.append(None)
            else:
                lo = float(rng.uniform(-np.pi, np.pi))
                limits.append((lo, lo + float(rng.uniform(0.5, 2 * np.pi))))
        try:
            out.append(five_bar(tuple(lengths), *limits))
        except ValueError:
            continue
    return out


def reference(m):
    """The reference count where two grids agree (a third, finer one breaks ties)."""
    fine, finer = joint_space_count(m, 800), joint_space_count(m, 1600)
    if fine == finer:
        return fine
    finest = joint_space_count(m, 3200)
    return finest if finest == finer else None


def test_counts_of_random_five_bars_hold_and_are_decided():
    designs = random_five_bars(64, 7)
    decided = 0
    checked = 0
    for m in designs:
        found = count_in_joint_space(m)
        truth = reference(m)
        assert found.at_most is None or found.at_least <= found.at_most
        if truth is not None:
            checked += 1
            assert found.at_least <= truth, (m, found, truth)
            assert found.at_most is None or truth <= found.at_most, (m, found, truth)
        decided += found.decided
    assert checked >= 60
    assert decided >= 61, decided


def tangent_angle(m: FiveBar, distance: float) -> float | None:
    """theta1 at which the elbow C lies at ``distance`` from the base B of leg 2."""
    L0, L1 = m.lengths[0], m.lengths[1]
    c = (L1**2 + L0**2 - distance**2) / (2 * L1 * L0)
    return float(np.arccos(c)) if abs(c) <= 1 else None


def test_limits_at_singular_angles_keep_bounds_that_hold():
    """A stop of theta1 where the curve |CD| = L2 + L4 (or |L2 - L4|) touches the
    edge of Q: the components of D may touch there, a pinch no refinement
    separates. The bounds must still hold."""
    rng = np.random.default_rng(3)
    tried = 0
    while tried < 12:
        lengths = tuple(float(v) for v in np.round(rng.uniform(1.0, 8.0, 5), 2))
        probe = FiveBar(*lengths) if lengths[0] < sum(lengths[1:]) else None
        if probe is None:
            continue
        L2, L3, L4 = lengths[2:]
        target = L2 + L4 - L3 if tried % 2 else abs(L2 - L4) + L3
        t = tangent_angle(probe, target)
        if t is None:
            continue
        lim1 = (t, t + 2.0) if tried % 3 else (t - 2.0, t)
        lo2 = float(rng.uniform(-np.pi, np.pi))
        m = five_bar(lengths, lim1, (lo2, lo2 + float(rng.uniform(1.0, 6.0))))
        tried += 1
        found = count_in_joint_space(m)
        truth = reference(m)
        if truth is not None:
            assert found.at_least <= truth
            assert found.at_most is None or truth <= found.at_most


def test_equal_distal_links_with_free_joints_are_decided():
    """L2 = L4: D misses the isolated points where the knees meet; the leaves
    around such a point attach through a convex block, not one by one."""
    m = five_bar((6.0, 8.0, 3.3, 8.0, 3.3), None, None)
    found = count_in_joint_space(m)
    assert (found.at_least, found.at_most) == (2, 2)
    assert joint_space_count(m, 800) == 2


def test_the_issue_designs():
    assert count_in_joint_space(five_bar(*GAP_FIVE_BAR)).decided
    assert count_in_joint_space(five_bar(*GAP_FIVE_BAR)).at_most == 4
    # equal legs on rails: D misses the diagonal rho1 = rho2 (no convex block
    # there); the bounds hold and the workspace analysis decides it
    found = count_in_joint_space(from_spec(EQUAL_BIGLIDE))
    assert found.at_least <= 4 and (found.at_most is None or found.at_most >= 4)


def test_biglides_against_the_closed_form():
    decided = 0
    for m in random_biglides(30, 5):
        found = count_in_joint_space(m)
        truth = biglide_count(m)
        assert found.at_least <= truth
        assert found.at_most is None or truth <= found.at_most
        decided += found.decided
    # the unequal ones at least (a third have equal legs)
    assert decided >= 20, decided


def test_only_two_dyads():
    assert has_dyads(FiveBar()) and has_dyads(from_spec(EQUAL_BIGLIDE))
    rpr = from_spec(THREE_RPR)
    assert not has_dyads(rpr)
    assert count_in_joint_space(rpr) is None


def test_analyze_reports_the_tighter_bounds_and_saves_them(tmp_path):
    m = five_bar((6.7, 2.1, 2.8, 6.2, 3.9), (1.18, 5.56), (2.6, 7.99))
    plain = analyze(m, precision=0.1, resolve=False)
    assert plain.joint_count is None
    result = analyze(m, precision=0.1)
    assert result.joint_count is not None and result.joint_count.decided
    assert result.count == (4, 4) == (result.joint_count.at_least, result.joint_count.at_most)
    assert reference(m) == 4
    # every region listed: nothing left to hide or detach
    assert result.complete
    assert result.undecided["components"] == 0 and result.undecided["detached"] == 0
    path = tmp_path / "a.npz"
    save_analysis(result, path)
    again = load_analysis(path)
    assert again.count == result.count and again.joint_count == result.joint_count
    # generalized aspects are not the components of D: no joint-space count
    assert analyze(m, precision=0.2, generalized_aspects=True).joint_count is None


def test_direction_into_a_corner():
    # three unit normals of a corner in space whose sum leaves it
    normals = np.array([[1.0, 0.0, 0.0], [-0.9, 0.43588989, 0.0], [-0.9, 0.0, 0.43588989]])
    assert (normals @ normals.sum(axis=0) < 0).any()
    v = into_corner(normals[None])[0]
    assert np.allclose(normals @ v, 1.0)
    # in the plane, two normals: the bisector, as their sum
    pair = np.array([[[1.0, 0.0], [0.0, 1.0]]])
    d = into_corner(pair)[0]
    assert np.allclose(d / np.linalg.norm(d), [2**-0.5, 2**-0.5])
    # dependent normals fall back to the sum; inactive rows are zero
    flat = np.array([[[1.0, 0.0], [1.0, 0.0], [0.0, 0.0]]])
    assert np.allclose(into_corner(flat)[0], [2.0, 0.0])


# ------------------------------------------------------- witnesses and notes
def _joint_box_of(m):
    lo = np.array([lim.lo for lim in m.limits])
    hi = np.array([lim.lo + 2 * np.pi if lim.periodic else lim.hi for lim in m.limits])
    return lo, hi


@pytest.mark.parametrize(
    "m",
    [
        FiveBar(7, 8, 5, 8, 5),
        FiveBar(2.0, 4.0, 4.0, 3.0, 4.0),
        Delta(),
        Delta(10.0, 4.0, 8.0, 10.0),
        from_spec(
            {
                "mechanism": "biglide",
                "parameters": {"L1": 5.0, "L2": 4.0},
                "limits": {"rho1": [-6, 6], "rho2": [-6, 6]},
            }
        ),
    ],
    ids=lambda m: m.name,
)
def test_witness_configurations_are_configurations_of_each_sign(m):
    """Forward kinematics at random joints: both poses satisfy every leg's
    constraint at those joints, with det A of opposite signs; none where D
    does not hold the joints."""
    lo, hi = _joint_box_of(m)
    q = np.random.default_rng(4).uniform(lo, hi, (500, lo.size))
    poses, signs = witness_configurations(m, q)
    found = np.isfinite(poses).all(axis=(1, 2))
    assert found.sum() >= 10
    qq = np.repeat(q[found], 2, axis=0)
    residual = m.constraints(poses[found].reshape(qq.shape[0], -1), qq)
    scale = max(float(np.abs(poses[found]).max()), 1.0) ** 2
    assert np.abs(residual).max() < 1e-9 * scale
    assert (signs[found].sum(axis=1) == 0).all() and (signs[found] != 0).all()
    condition = joint_condition(m)
    inside = condition.classify(q, q) == IN
    assert found[inside].all()


def test_witnesses_stand_for_every_component_of_a_decided_count():
    m = Delta(10.0, 4.0, 8.0, 10.0, tuple(JointLimit(-np.pi / 2, np.pi / 2) for _ in range(3)))
    found = count_in_joint_space(m)
    assert found.decided and found.witnesses.shape == (found.at_least // 2, 3)
    condition = joint_condition(m)
    w = found.witnesses
    assert (condition.classify(w, w) == IN).all()  # each in D
    lo, hi = _joint_box_of(m)
    assert ((w > lo) & (w < hi)).all()  # strictly within the limits


def test_a_corner_of_the_limits_a_hair_off_a_parallel_singularity_is_decided():
    """theta1's stop and theta2's stop meet 1.6e-14 (in d^2) outside D: the stop
    traces decide the count there, as the design whose corner is moved 1e-3
    further out of D (nothing near-degenerate left) has it."""
    theta1, theta2 = (-3.652828432061323, -2.82), (-1.5429887555960375, 1.925532188225774)
    lengths = (5.9, 3.3, 5.3, 6.3, 5.3)
    m = five_bar(lengths, theta1, theta2)
    found = count_in_joint_space(m)
    assert found.decided and not found.notes
    assert count_in_joint_space(m, stop_traces=False).at_most is None

    def margin(stop):  # d^2 - (L2 + L4)^2 at the corner, 50 digits
        with mp.workdps(50):
            l0, l1, _, l3, _ = (mpf(v) for v in lengths)
            a, b = mpf(stop), mpf(theta2[0])
            dx = l1 * mp.cos(a) - l0 - l3 * mp.cos(b)
            d2 = dx**2 + (l1 * mp.sin(a) - l3 * mp.sin(b)) ** 2
            return float(d2 - (mpf(5.3) + mpf(5.3)) ** 2)

    assert 0 < margin(theta1[1]) < 1e-13
    step = 1e-3 if margin(theta1[1] + 1e-3) > margin(theta1[1]) else -1e-3
    far = count_in_joint_space(
        five_bar(lengths, (theta1[0], theta1[1] + step), theta2), stop_traces=False
    )
    assert far.decided and (far.at_least, far.at_most) == (found.at_least, found.at_most)


def test_a_stop_exactly_at_a_parallel_singularity_is_named():
    """theta1 = 0 = theta2, a corner of the limits, puts the knees exactly the
    distal links' sum apart (every float exact): the count stays open about
    that corner alone, and the output says so."""
    m = five_bar((2.0, 1.0, 1.0, 1.0, 1.0), (0.0, 1.5), (0.0, 1.5))
    found = count_in_joint_space(m)
    assert not found.decided
    (note,) = found.notes
    assert note.startswith("degenerate design") and "theta1 = 2.2" in note
    result = analyze(m, precision=0.1)
    assert result.notes == found.notes and result.to_dict()["notes"] == [note]
    assert note in result.summary()


def test_a_trace_undecided_on_a_degenerate_point_is_named():
    """L0 = 2, L1 = L3 = 1: the knees are exactly L2 + L4 = 2 apart wherever
    theta1 = theta2 (a parallelogram), so the stop traces meet a point where d^2
    is exactly its bound and no precision decides: the output says where."""
    m = five_bar((2.0, 1.0, 1.0, 1.0, 1.0), (0.0, 1.5), (-1.5, 1.5))
    found = count_in_joint_space(m)
    assert not found.decided
    (note,) = found.notes
    assert note.startswith("degenerate design") and "exactly or within one float" in note
    values = dict(re.findall(r"(theta\d) = (-?[\d.e+-]+)", note))
    with mp.workdps(50):
        a, b = mpf(values["theta1"]), mpf(values["theta2"])
        d2 = (mp.cos(a) - 2 - mp.cos(b)) ** 2 + (mp.sin(a) - mp.sin(b)) ** 2
        assert abs(d2 - 4) < mpf("1e-40")
