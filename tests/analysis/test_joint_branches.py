"""The joint-space count of five-bars with constraints, one assembly branch at a
time (moveability.analysis.joint_branches), against the independent grid of Q
in tests/constraint_references.py and against the poses' own formulas."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from constraint_references import configurations, constrained, grid_count
from moveability import analyze, from_spec, load_analysis, save_analysis
from moveability.analysis.joint_branches import BranchCondition, takes_branches
from moveability.analysis.joint_space import count_in_joint_space, joint_condition
from moveability.hypertree.status import BOUNDARY, IN, OUT

#: two decided designs of the constrained family (bench_counts, seed 17)
OBSTACLES = {
    "mechanism": "five-bar",
    "parameters": {"L0": 7.1, "L1": 3.0, "L2": 5.3, "L3": 4.2, "L4": 3.3},
    "limits": {"theta1": [-0.45, 3.77], "theta2": [-3.05, -0.71]},
    "obstacles": [
        {"center": [-3.6, 0.8], "radius": 1.0},
        {"center": [-4.0, -3.7], "radius": 0.5},
    ],
}
PASSIVE = {
    "mechanism": "five-bar",
    "parameters": {"L0": 9.0, "L1": 8.0, "L2": 5.0, "L3": 5.0, "L4": 8.0},
    "limits": {"theta1": "unlimited", "theta2": "unlimited"},
    "passive_limits": {"P": [-1.5707963267948966, 1.5707963267948966]},
}
#: a five-bar with a disk above it: the branches meet it at different joints
ABOVE = {
    "mechanism": "five-bar",
    "parameters": {"L0": 7.0, "L1": 6.0, "L2": 5.0, "L3": 6.0, "L4": 4.0},
    "limits": {"theta1": [0.0, 3.141592653589793], "theta2": [0.0, 3.141592653589793]},
    "obstacles": [{"center": [3.5, 9.0], "radius": 1.0}],
}


def _reference(spec):
    lengths = tuple(float(spec["parameters"][k]) for k in ("L0", "L1", "L2", "L3", "L4"))
    limits = tuple(
        None if v == "unlimited" else (float(v[0]), float(v[1]))
        for v in (spec["limits"]["theta1"], spec["limits"]["theta2"])
    )
    kwargs = {}
    if "passive_limits" in spec:
        kwargs["passive"] = {k: tuple(v) for k, v in spec["passive_limits"].items()}
    if "obstacles" in spec:
        kwargs["obstacles"] = [(o["center"], o["radius"]) for o in spec["obstacles"]]
    if "collisions" in spec:
        kwargs["collisions"] = True
    return lengths, limits, kwargs


@pytest.mark.parametrize("spec", [OBSTACLES, PASSIVE, ABOVE], ids=["obstacles", "passive", "above"])
def test_decided_counts_match_the_grid(spec):
    m = from_spec(spec)
    found = count_in_joint_space(m)
    assert found is not None and found.decided
    lengths, limits, kwargs = _reference(spec)
    # components of the grid that grow with it: the regions, not grid noise
    _, small = grid_count(lengths, limits, 300, False, **kwargs)
    _, large = grid_count(lengths, limits, 600, False, **kwargs)
    grown = [sum(1 for n in sizes if n >= least) for sizes, least in ((small, 12), (large, 50))]
    assert grown == [found.at_least] * 2, (small, large)
    # one witness per region, each standing for one branch
    assert found.witnesses.shape[0] == found.at_least
    assert found.witnessed.sum() == found.at_least


def test_witnesses_are_valid_configurations_of_their_branch():
    spec = OBSTACLES
    m = from_spec(spec)
    found = count_in_joint_space(m)
    lengths, _, kwargs = _reference(spec)
    distance = joint_condition(m)
    poses = distance.poses(found.witnesses)
    for row, (w, which) in enumerate(zip(found.witnesses, found.witnessed, strict=True)):
        assert which.sum() == 1
        branch = int(np.argmax(which))
        mode = _mode(lengths, w, poses[row, branch])
        assert constrained(mode, **kwargs)[0]


def _mode(lengths, joints, point):
    L0, L1, _, L3, _ = lengths
    c = np.array([[L1 * np.cos(joints[0]), L1 * np.sin(joints[0])]])
    d = np.array([[L0 + L3 * np.cos(joints[1]), L3 * np.sin(joints[1])]])
    return {
        "A": np.zeros(2),
        "B": np.array([L0, 0.0]),
        "C": c,
        "D": d,
        "P": np.asarray(point)[None],
        "valid": np.array([True]),
    }


def test_branches_classify_joint_vectors_as_the_grid_does():
    """Point boxes of Q: IN only where the branch's configuration is valid, OUT only
    where it is not (the reference's own formulas), and the branches differ."""
    m = from_spec(ABOVE)
    lengths, limits, kwargs = _reference(ABOVE)
    (t1, t2), modes = configurations(lengths, limits, 60)
    q = np.column_stack([t1.ravel(), t2.ravel()])
    statuses = []
    for s, mode in zip((1, -1), modes, strict=True):
        branch = BranchCondition(m, joint_condition(m), s)
        status = branch.classify(q, q)
        valid = constrained(mode, **kwargs).ravel()
        assert not (status[~valid] == IN).any()
        assert not (status[valid] == OUT).any()
        # points are decided, but for a few on the boundaries
        assert (status == BOUNDARY).mean() < 0.01
        statuses.append(status)
    assert ((statuses[0] == OUT) & (statuses[1] == IN)).any()
    assert ((statuses[0] == IN) & (statuses[1] == OUT)).any()
    signs = [BranchCondition(m, joint_condition(m), s).det_sign for s in (1, -1)]
    assert signs[0] == -signs[1] != 0


def test_the_analysis_lists_every_counted_region_and_saves_the_branches(tmp_path):
    result = analyze(from_spec(OBSTACLES), precision=0.1)
    joint = result.joint_count
    assert joint is not None and joint.decided
    assert result.count == (joint.at_least, joint.at_most)
    assert len(result.regions) == joint.at_least
    path = tmp_path / "saved.npz"
    save_analysis(result, path)
    back = load_analysis(path)
    assert np.array_equal(back.joint_count.witnessed, joint.witnessed)
    assert back.count == result.count


def test_takes_branches_only_with_constraints_over_a_linkage():
    assert not takes_branches(from_spec({k: v for k, v in ABOVE.items() if k != "obstacles"}))
    assert takes_branches(from_spec(ABOVE))


_SPEC = st.fixed_dictionaries(
    {
        "lengths": st.tuples(*(st.floats(2.0, 8.0) for _ in range(5))),
        "centre": st.tuples(st.floats(-4.0, 10.0), st.floats(-6.0, 6.0)),
        "radius": st.floats(0.3, 1.5),
        "q": st.tuples(st.floats(-np.pi, np.pi), st.floats(-np.pi, np.pi)),
        "size": st.floats(1e-6, 0.2),
        "branch": st.sampled_from([1, -1]),
        "t": st.tuples(st.floats(0.0, 1.0), st.floats(0.0, 1.0)),
    }
)


def _design(x):
    spec = {
        "mechanism": "five-bar",
        "parameters": dict(zip(("L0", "L1", "L2", "L3", "L4"), x["lengths"], strict=True)),
        "limits": {"theta1": "unlimited", "theta2": "unlimited"},
        "obstacles": [{"center": list(x["centre"]), "radius": x["radius"]}],
        "collisions": {"links": True},
    }
    return from_spec(spec)


@settings(max_examples=150, deadline=None)
@given(_SPEC)
def test_enclosures_hold_the_configurations(x):
    """At a point of a box of Q in D: the branch's pose lies in the enclosure of P,
    det M times its derivatives in the moments, and the level flow's velocity of
    P (a finite difference along the level curve) in its enclosure."""
    m = _design(x)
    distance = joint_condition(m)
    branch = BranchCondition(m, distance, x["branch"])
    lo = np.array([x["q"]])
    hi = lo + x["size"]
    q = lo + np.array(x["t"]) * (hi - lo)
    poses = distance.poses(q)[0, 0 if x["branch"] > 0 else 1]
    if not np.isfinite(poses).all():
        return  # q is off D: no configuration
    knees, rates, point, det = branch._frame(lo, hi)
    tol = 1e-9 * (1 + np.abs(poses))
    for axis in range(2):
        assert point[axis].lo[0] - tol[axis] <= poses[axis] <= point[axis].hi[0] + tol[axis]
    # det M: the cross product of P - C_1 and P - C_2
    c = [np.array([k[0].lo[0], k[1].lo[0]]) for k in branch._frame(q, q)[0]]
    e1, e2 = poses - c[0], poses - c[1]
    cross = e1[0] * e2[1] - e1[1] * e2[0]
    assert det.lo[0] - 1e-9 * (1 + abs(cross)) <= cross <= det.hi[0] + 1e-9 * (1 + abs(cross))
    # dP/dq_j by finite differences, times det M, in the moments
    xs, ys = branch._moments(point, knees, rates)
    step = 1e-7
    for j in range(2):
        ahead = q.copy()
        ahead[0, j] += step
        behind = q.copy()
        behind[0, j] -= step
        moved = distance.poses(np.vstack([ahead, behind]))[:, 0 if x["branch"] > 0 else 1]
        if not np.isfinite(moved).all() or abs(cross) < 1e-3:
            continue
        slope = (moved[0] - moved[1]) / (2 * step) * cross
        for axis, m_ in enumerate((xs[j], ys[j])):
            slack = 1e-4 * (1 + abs(slope[axis]))
            assert m_.lo[0] - slack <= slope[axis] <= m_.hi[0] + slack


@settings(max_examples=100, deadline=None)
@given(_SPEC)
def test_level_velocity_is_the_motion_along_the_level_curve(x):
    """The platform's velocity along a level curve of d^2 (the rigid motion of the
    knees' triangle) holds the finite difference of P along the curve's tangent
    at a point of the box, and the flows leave through opposite faces."""
    m = _design(x)
    distance = joint_condition(m)
    which = 0 if x["branch"] > 0 else 1
    branch = BranchCondition(m, distance, x["branch"])
    lo = np.array([x["q"]])
    hi = lo + x["size"]
    q = lo + np.array(x["t"]) * (hi - lo)
    if not np.isfinite(distance.poses(q)[0, which]).all():
        return
    knees, rates, point, _ = branch._frame(lo, hi)
    value, grad, _ = distance.terms(lo, hi, hessian=False)
    ok, faces = branch.level_flows(lo, hi, grad)
    # the two ways are mirror images: each one's upper faces are the other's lower
    one, other = int(faces[0, 0]), int(faces[1, 0])
    mirrored = ((one & 0b0101) << 1) | ((one & 0b1010) >> 1)
    assert other == mirrored
    for f, bits in enumerate((one, other)):
        if ok[0, f]:  # a certified flow leaves the box: some joint moves one way
            assert any(((bits >> (2 * a)) & 0b11) in (0b01, 0b10) for a in range(2))
    _, g, _ = distance.terms(q, q, hessian=False)
    tangent = np.array([-g[1].lo[0], g[0].lo[0]])
    step = 1e-7
    moved = distance.poses(np.vstack([q + step * tangent, q - step * tangent]))[:, which]
    if not np.isfinite(moved).all():
        return
    slope = (moved[0] - moved[1]) / (2 * step)
    t, velocity = BranchCondition.level_velocity(knees, rates, point, value, grad, 1.0)
    for axis in range(2):
        assert t[axis].lo[0] <= tangent[axis] <= t[axis].hi[0]
        slack = 1e-4 * (1 + abs(slope[axis]))
        assert velocity[axis].lo[0] - slack <= slope[axis] <= velocity[axis].hi[0] + slack
