"""The 3-RRR: spec round trip, closed-form postures, and the analysis' answers at
sampled poses against a brute-force reference (the eight postures in closed form)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from moveability import analyze
from moveability.errors import SpecError
from moveability.limits import JointLimit
from moveability.mechanisms import from_spec
from moveability.mechanisms.registry import load_spec
from moveability.mechanisms.three_rrr import ThreeRRR

PRECISION = 0.75


def reference_configurations(m: ThreeRRR, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint angles (m, 8, 3) of the eight postures (NaN where a leg cannot reach) and
    det A of each (written independently: rows (B - C, (B - C) x R b))."""
    x, y, phi = poses[:, 0], poses[:, 1], poses[:, 2]
    c, s = np.cos(phi), np.sin(phi)
    per_leg = []
    rows = []
    for i in range(3):
        (ax, ay), (bx, by) = m.base[i], m.platform[i]
        l1, l2 = m.proximal[i], m.distal[i]
        rbx, rby = c * bx - s * by, s * bx + c * by
        px, py = x + rbx, y + rby
        dx, dy = px - ax, py - ay
        rho = np.hypot(dx, dy)
        cos_alpha = (rho**2 + l1**2 - l2**2) / (2 * l1 * rho)
        with np.errstate(invalid="ignore"):
            alpha = np.where(np.abs(cos_alpha) <= 1, np.arccos(np.clip(cos_alpha, -1, 1)), np.nan)
        theta = np.arctan2(dy, dx)
        q = np.stack([theta + alpha, theta - alpha], axis=1)
        per_leg.append(q)
        ex = px[:, None] - (ax + l1 * np.cos(q))
        ey = py[:, None] - (ay + l1 * np.sin(q))
        rows.append(np.stack([ex, ey, ex * -rby[:, None] + ey * rbx[:, None]], axis=-1))
    joints = np.empty((poses.shape[0], 8, 3))
    dets = np.empty((poses.shape[0], 8))
    for p, branches in enumerate(itertools.product((0, 1), repeat=3)):
        joints[:, p] = np.stack([per_leg[i][:, b] for i, b in enumerate(branches)], axis=1)
        a = np.stack([rows[i][:, b] for i, b in enumerate(branches)], axis=1)
        dets[:, p] = np.linalg.det(np.nan_to_num(a))
        dets[~np.isfinite(joints[:, p]).all(axis=1), p] = np.nan
    return joints, dets


@pytest.fixture(scope="module")
def result():
    # the middle of the workspace only, to keep the test short
    m = ThreeRRR.default()
    small = ThreeRRR(m.base, m.platform, m.proximal, m.distal, m.limits, ((-3.0, -2.0), (3.0, 4.0)))
    return analyze(small, PRECISION)


def test_spec_round_trip_and_errors():
    m = ThreeRRR.default(limits=[JointLimit(0.0, np.pi), JointLimit.unlimited(), JointLimit(-1, 1)])
    spec = m.to_spec()
    assert spec["mechanism"] == "3-RRR"
    assert spec["limits"]["theta2"] == "unlimited"
    assert from_spec(load_spec(spec)).to_spec() == spec
    bad = {**spec, "limits": {"theta1": [0, "pi"], "theta2": "unlimited"}}
    with pytest.raises(SpecError, match=r"limits\.theta3"):
        from_spec(load_spec(bad))
    bad = {**spec, "parameters": {**spec["parameters"], "proximal": [6, -1, 6]}}
    with pytest.raises(SpecError, match=r"parameters\.proximal"):
        from_spec(load_spec(bad))
    assert "ThreeRRR" in repr(m)


def test_postures_match_the_reference():
    m = ThreeRRR.default()
    poses = np.random.default_rng(0).uniform(m.bounds[0], m.bounds[1], (500, 3))
    q = m.joint_angles(poses)
    q_ref, det_ref = reference_configurations(m, poses)
    assert (np.isfinite(q) == np.isfinite(q_ref)).all()
    ok = np.isfinite(q_ref)
    assert np.abs(np.angle(np.exp(1j * (q[ok] - q_ref[ok])))).max() < 1e-9
    det = np.stack([m.det_a(poses, q[:, p]) for p in range(8)], axis=1)
    both = np.isfinite(det_ref)
    # same sign of det A (the rows differ by a factor 2 each)
    assert (np.sign(det[both]) == np.sign(det_ref[both])).all()


def test_answers_at_poses_agree_with_the_reference(result):
    m = result.mechanism
    rng = np.random.default_rng(1)
    poses = rng.uniform(m.bounds[0], m.bounds[1], (400, 3))
    _, det_ref = reference_configurations(m, poses)
    valid = np.isfinite(det_ref) & (np.abs(det_ref) > 0)
    located = result.locate(poses)["points"]
    n_in = n_out = 0
    for i, answer in enumerate(located):
        if answer["workspace"] is True:
            assert valid[i].any()
            n_in += 1
        elif answer["workspace"] is False:
            assert not valid[i].any()
            n_out += 1
        for region in result.regions:
            if answer["regions"][str(region.id)] is True:
                # a configuration of the region's sign of det A
                assert (valid[i] & (np.sign(det_ref[i]) == region.sign)).any()
    assert n_in > 10 and n_out > 10


def test_regions_have_both_signs_and_periodic_phi(result):
    assert result.mechanism.periodic_axes == (2,)
    assert result.tree.periodic == (2,)
    signs = sorted(r.sign for r in result.regions)
    assert signs == [-1, 1]
    for region in result.regions:
        lo, hi = region.area
        assert 0 < lo <= hi
    # a pose and the same pose one turn on are one pose
    pose = np.array([[0.0, 0.0, 0.5]])
    turned = pose + np.array([[0.0, 0.0, 2 * np.pi]])
    assert (
        result.locate(pose)["points"][0]["regions"] == result.locate(turned)["points"][0]["regions"]
    )


def test_no_upper_bound_without_flows():
    """The 3-RRR's legs give no flows (no certificate that a region cannot hide
    in an uncertified node): those nodes stay open and no upper bound is claimed."""
    from pathlib import Path

    from moveability.analysis.flows import supports_flows

    example = Path(__file__).resolve().parents[2] / "examples" / "three-rrr.toml"
    mechanism = from_spec(load_spec(example))
    assert not supports_flows(mechanism)
    result = analyze(mechanism, precision=(0.8, 0.8, 0.4))
    assert result.open_nodes.any()
    assert result.count[0] >= 1 and result.count[1] is None


def test_leg_tapes_give_the_interpreted_bounds():
    """Each leg function's compiled tape (what the analysis runs over boxes) gives,
    bit for bit, the bounds of the same function evaluated on Intervals, on random
    boxes, wide and thin, around the whole turn."""
    from moveability.intervals import Interval
    from moveability.mechanisms import tape

    m = ThreeRRR.default()
    rng = np.random.default_rng(7)
    n = 400
    centre = np.column_stack(
        [rng.uniform(-6, 6, n), rng.uniform(-6, 6, n), rng.uniform(-np.pi, np.pi, n)]
    )
    half = rng.choice([0.0, 1e-9, 0.05, 0.7, 4.0], size=(n, 3))
    lo, hi = centre - half, centre + half
    q_mid = rng.uniform(-4, 4, n)
    q_half = rng.choice([0.0, 1e-6, 0.1, 2.0], size=n)
    q = Interval(q_mid - q_half, q_mid + q_half)
    box = np.arange(n)
    for leg in m.legs:
        for g in (leg.f, leg.df_dq, leg.d2f_dq2, *leg.df_dx):
            compiled = tape.run(g.tape, lo, hi, box, q)
            plain = g(*(Interval(lo[:, j], hi[:, j]) for j in range(3)), q)
            assert np.array_equal(compiled.lo, plain.lo)
            assert np.array_equal(compiled.hi, plain.hi)
            assert (compiled.lo <= compiled.hi).all()
