"""Planned motions: continuity, validity, staying in one region, and shortening."""

import itertools

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from moveability import analyze, default_poses, load_spec, plan_motion
from moveability.analysis.planning import PlanningError
from moveability.cli import main
from moveability.errors import InvalidParameterError
from moveability.limits import JointLimit
from moveability.mechanisms import FiveBar, ThreeRPR

DESIGNS = [
    ((7, 8, 5, 8, 5), (0.0, np.pi)),
    ((7, 8, 5, 8, 5), None),
    ((6, 5, 7, 5, 7), (-np.pi / 2, np.pi)),
    ((5, 6, 4, 5, 4.5), (-np.pi, np.pi)),
]


def _check_motion(m, result, points, motion, eps):
    path = motion["path"]
    poses = np.array([c["pose"] for c in path])
    joints = np.array([c["joints"] for c in path])
    assert np.allclose(poses[0], points[0]) and np.allclose(poses[-1], points[-1])
    # every given pose is visited, in order
    visits = [int(np.flatnonzero(np.all(np.isclose(poses, p), axis=1))[0]) for p in points]
    assert visits == sorted(visits)
    assert np.linalg.norm(np.diff(poses, axis=0), axis=1).max() <= eps + 1e-12
    turn = np.abs(np.angle(np.exp(1j * np.diff(joints, axis=0))))
    assert turn.max() <= eps + 1e-12
    assert np.abs(m.constraints(poses, joints)).max() <= 1e-9
    region = result.regions[motion["region"]]
    assert (np.sign(m.det_a(poses, joints)) == region.sign).all()
    for i, lim in enumerate(m.limits):
        assert lim.contains(joints[:, i]).all()
        if not lim.periodic:
            assert (joints[:, i] >= lim.lo).all() and (joints[:, i] <= lim.hi).all()
    # postures change only where the changing leg is at a serial singularity
    names = [c["posture"] for c in path]
    for k in range(1, len(path)):
        if names[k] != names[k - 1]:
            leg = [i for i in range(2) if names[k][i] != names[k - 1][i]]
            for i in leg:
                term = m.legs[i].serial_term(poses[k : k + 1], joints[k : k + 1, i])
                assert abs(term[0]) < 1e-4


@pytest.mark.parametrize(("lengths", "limit"), DESIGNS)
def test_planned_motions_are_valid(lengths, limit):
    joint = JointLimit.unlimited() if limit is None else JointLimit(*limit)
    m = FiveBar(*lengths, limits=(joint, joint))
    eps = 0.1
    result = analyze(m, precision=eps)
    rng = np.random.default_rng(4)
    cand = rng.uniform(*m.bounds, (4000, 2))
    planned = 0
    for region in result.regions:
        answers = result.locate(cand)["points"]
        inside = cand[[a["regions"][str(region.id)] is True for a in answers]]
        for _ in range(4):
            points = inside[rng.choice(len(inside), 3, replace=False)]
            motion = plan_motion(result, points)
            _check_motion(m, result, points, motion, eps)
            planned += 1
    assert planned >= 4 * len(result.regions)


def test_changing_posture_on_the_way():
    m = load_spec("examples/five-bar-unlimited.toml")
    result = analyze(m, precision=0.1)
    motion = plan_motion(result, [[0.0, 8.0], [6.0, -7.0], [-4.0, 1.0]])
    names = [c["posture"] for c in motion["path"]]
    assert len(set(names)) > 1
    _check_motion(
        result.mechanism, result, np.array([[0.0, 8.0], [6.0, -7.0], [-4.0, 1.0]]), motion, 0.1
    )


def test_poses_in_different_regions_are_refused():
    result = analyze(load_spec("examples/five-bar-full-turn.toml"), precision=0.1)
    with pytest.raises(PlanningError, match="poses 0 and 1"):
        plan_motion(result, [[3.5, 12.4], [3.5, -12.4]])


def test_cli_plan_exit_codes(tmp_path):
    ok = tmp_path / "ok.csv"
    ok.write_text("x,y\n1.0,3.0\n5.0,3.0\n")
    apart = tmp_path / "apart.csv"
    apart.write_text("x,y\n-4.0,-1.0\n3.5,1.5\n")
    runner = CliRunner()
    spec = "examples/five-bar-paper.toml"
    done = runner.invoke(main, ["plan", spec, str(ok), "--precision", "0.2", "--json", "-"])
    assert done.exit_code == 0, done.output
    assert '"path"' in done.output
    refused = runner.invoke(main, ["plan", spec, str(apart), "--precision", "0.2"])
    assert refused.exit_code == 3
    assert "poses 0 and 1 lie in no common region" in refused.output


# ------------------------------------------------------------ shortened, smoothed motions
def _analysis(spec, precision):
    return _ANALYSES.setdefault((spec, precision), analyze(load_spec(spec), precision=precision))


_ANALYSES: dict = {}
RPR_SEAM = ThreeRPR(
    [[0, 0], [12, 1], [-2, 9]],
    [[1, -1], [6, 0], [3, 5]],
    (JointLimit(3.0, 14.0, prismatic=True),) * 3,
)


def _moves(m, dq):
    """How far each joint moves: revolute ones the shorter way round."""
    turn = np.abs(np.angle(np.exp(1j * dq)))
    prismatic = np.array([lim.prismatic for lim in m.limits])
    return np.where(prismatic, np.abs(dq), turn)


def _check_smoothed(result, points, motion, step):
    """An independent check of a motion: valid everywhere in its region, steps within
    ``step``, the poses asked reached at the waypoints, and the lengths reported."""
    m = result.mechanism
    path = motion["path"]
    poses = np.array([c["pose"] for c in path])
    joints = np.array([c["joints"] for c in path])
    region = next(r for r in result.regions if r.id == motion["region"])
    assert np.abs(m.constraints(poses, joints)).max() <= 1e-9
    assert (np.sign(m.det_a(poses, joints)) == region.sign).all()
    for i, lim in enumerate(m.limits):
        assert lim.contains(joints[:, i]).all()
    assert np.linalg.norm(np.diff(poses, axis=0), axis=1).max(initial=0.0) <= step + 1e-12
    assert _moves(m, np.diff(joints, axis=0)).max(initial=0.0) <= step + 1e-12
    # the poses asked, in order, at the waypoints (periodic angles up to whole turns)
    waypoints = motion["waypoints"]
    assert len(waypoints) == len(points)
    assert waypoints[0] == 0 and waypoints[-1] == len(path) - 1
    assert waypoints == sorted(waypoints)
    gap = poses[waypoints] - np.asarray(points, dtype=float)
    for axis in m.periodic_axes:
        gap[:, axis] = np.angle(np.exp(1j * gap[:, axis]))
    assert np.abs(gap).max() <= 1e-9
    # the lengths reported are those of the path, and smoothing never lengthens
    length = motion["length"]
    pose_length = np.linalg.norm(np.diff(poses, axis=0), axis=1).sum()
    joint_length = np.linalg.norm(_moves(m, np.diff(joints, axis=0)), axis=1).sum()
    assert length["pose"]["after"] == pytest.approx(pose_length, rel=1e-9, abs=1e-12)
    assert length["joints"]["after"] == pytest.approx(joint_length, rel=1e-9, abs=1e-12)
    assert length["pose"]["after"] <= length["pose"]["before"] + 1e-9
    # postures change only in place, where the changing leg is at a serial singularity
    for k in range(1, len(path)):
        if path[k]["posture"] != path[k - 1]["posture"]:
            assert np.allclose(poses[k], poses[k - 1])
            before, after = path[k - 1]["posture"], path[k]["posture"]
            for i, (a, b) in enumerate(zip(before, after, strict=True)):
                if a != b:
                    term = m.legs[i].serial_term(poses[k : k + 1], joints[k : k + 1, i])
                    assert abs(term[0]) < 1e-4


CASES = [
    ("examples/five-bar-paper.toml", 0.1),
    ("examples/five-bar-full-turn.toml", 0.1),
    ("examples/five-bar-unlimited.toml", 0.1),
    ("examples/biglide.toml", 0.1),
    ("examples/three-rpr.toml", (2.0, 2.0, 0.3)),
]


@pytest.mark.parametrize(("spec", "precision"), CASES)
def test_smoothed_motions_are_valid_and_no_longer(spec, precision):
    result = _analysis(spec, precision)
    points = default_poses(result)
    motion = plan_motion(result, points)
    step = float(np.min(precision))
    _check_smoothed(result, points, motion, step)
    # the raw chain is still there, and it is what "before" measured
    raw = plan_motion(result, points, smooth=False)
    _check_smoothed(result, points, raw, step)
    assert raw["length"]["pose"]["before"] == raw["length"]["pose"]["after"]
    assert raw["length"]["joints"]["before"] == raw["length"]["joints"]["after"]
    assert motion["length"]["pose"]["before"] == pytest.approx(raw["length"]["pose"]["after"])
    assert motion["length"]["joints"]["before"] == pytest.approx(raw["length"]["joints"]["after"])


def _straight_is_invalid(m, a, b, sign):
    """Whether every posture leaves the valid configurations of ``sign`` somewhere on
    the straight segment from a to b (sampled finely)."""
    s = np.linspace(0.0, 1.0, 4001)[:, None]
    poses = a + s * (b - a)
    q = m.joint_angles(poses)
    for p in range(q.shape[1]):
        ok = np.isfinite(q[:, p]).all(axis=1)
        qp = np.nan_to_num(q[:, p])
        ok &= np.all([lim.contains(qp[:, i]) for i, lim in enumerate(m.limits)], axis=0)
        ok &= np.sign(m.det_a(poses, qp)) == sign
        if ok.all():
            return False
    return True


def test_smoothing_goes_around_what_the_straight_line_crosses():
    # the paper's five-bar: the default poses of the largest region are on both sides
    # of a hole of its W_N; the straight segment between them crosses it in every
    # posture, so every shortcut must be proved (skipping the proof fails here)
    result = _analysis("examples/five-bar-paper.toml", 0.1)
    points = default_poses(result)
    motion = plan_motion(result, points)
    region = next(r for r in result.regions if r.id == motion["region"])
    assert _straight_is_invalid(result.mechanism, points[0], points[1], region.sign)
    _check_smoothed(result, points, motion, 0.1)
    # the raw chain zigzags: smoothing takes off more than 10 % (measured: 24.7 -> 21.0)
    length = motion["length"]
    assert length["pose"]["after"] < 0.9 * length["pose"]["before"]
    assert length["joints"]["after"] < 0.9 * length["joints"]["before"]
    # and it is still longer than the straight line it may not take
    assert length["pose"]["after"] > np.linalg.norm(points[1] - points[0])


def test_smoothing_through_several_poses_and_posture_changes():
    points = np.array([[0.0, 8.0], [6.0, -7.0], [-4.0, 1.0]])
    result = _analysis("examples/five-bar-unlimited.toml", 0.1)
    motion = plan_motion(result, points)
    raw = plan_motion(result, points, smooth=False)
    _check_smoothed(result, points, motion, 0.1)
    # the posture changes stay as planned
    changes = [
        (c["posture"], d["posture"])
        for path in (motion["path"], raw["path"])
        for c, d in itertools.pairwise(path)
        if c["posture"] != d["posture"]
    ]
    assert len(changes) % 2 == 0 and len(changes) > 0
    half = len(changes) // 2
    assert changes[:half] == changes[half:]
    assert motion["length"]["pose"]["after"] < 0.95 * motion["length"]["pose"]["before"]


def test_smoothing_across_the_seam_of_a_periodic_angle():
    result = analyze(RPR_SEAM, precision=(0.5, 0.5, 0.3))
    points = np.array(
        [[4.80684312, 0.23712648, 2.84706834], [7.92276276, 11.12599958, -2.89615573]]
    )
    motion = plan_motion(result, points)
    _check_smoothed(result, points, motion, 0.3)
    phi = np.array([c["pose"][2] for c in motion["path"]])
    assert phi.max() > np.pi  # it went on past pi rather than turning back
    assert motion["length"]["pose"]["after"] < 0.95 * motion["length"]["pose"]["before"]


def test_one_pose_and_a_repeated_pose():
    result = _analysis("examples/five-bar-paper.toml", 0.1)
    alone = plan_motion(result, [[1.0, 3.0]])
    assert alone["waypoints"] == [0] and len(alone["path"]) == 1
    assert alone["length"]["pose"] == {"before": 0.0, "after": 0.0}
    points = np.array([[1.0, 3.0], [1.0, 3.0], [5.0, 3.0]])
    _check_smoothed(result, points, plan_motion(result, points), 0.1)


@pytest.mark.parametrize("step", [0.0, -1.0, float("nan"), "fast"])
def test_bad_steps_are_refused(step):
    result = _analysis("examples/five-bar-paper.toml", 0.1)
    with pytest.raises(InvalidParameterError, match="step"):
        plan_motion(result, [[1.0, 3.0], [5.0, 3.0]], step=step)


def _region_poses(spec, precision):
    """Centres of the certified cells of each region of an analysis."""
    result = _analysis(spec, precision)
    leaves = result.tree.leaves()
    centres = []
    for j in range(len(result.regions)):
        sure = np.flatnonzero(result.region_cells(j)[0])
        centres.append(0.5 * (leaves.lo[sure] + leaves.hi[sure]))
    return result, centres


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_random_pairs_of_poses_of_one_region(data):
    result, centres = _region_poses("examples/five-bar-paper.toml", 0.1)
    j = data.draw(st.integers(0, len(centres) - 1), label="region")
    i = data.draw(st.lists(st.integers(0, len(centres[j]) - 1), min_size=2, max_size=2))
    points = centres[j][i]
    step = data.draw(st.sampled_from([0.05, 0.1, 0.3]), label="step")
    motion = plan_motion(result, points, step=step)
    # (the poses may also lie in another region, which the plan may take)
    _check_smoothed(result, points, motion, step)
