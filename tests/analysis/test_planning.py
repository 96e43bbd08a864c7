"""Planned motions: continuity, validity and staying in one region."""

import numpy as np
import pytest
from click.testing import CliRunner

from moveability import analyze, load_spec, plan_motion
from moveability.analysis.planning import PlanningError
from moveability.cli import main
from moveability.limits import JointLimit
from moveability.mechanisms import FiveBar

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
