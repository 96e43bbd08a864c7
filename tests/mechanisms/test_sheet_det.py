"""det A along the sheets (moveability.mechanisms.sheet_det) for user-defined legs.

Differential tests: over random boxes of user-defined mechanisms with sliders, every
posture's enclosure holds det A at every configuration of poses sampled in the
box (and at the box's corners), it lies inside the natural enclosure, and it
decides the sign of det A on boxes where the natural one does not. The second
derivatives the specs give agree with finite differences of the rows of A.
"""

from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path

import numpy as np
import pytest

from moveability import load_spec
from moveability.mechanisms.base import REGULAR, interval_det
from moveability.mechanisms.custom import CustomMechanism
from moveability.mechanisms.sheet_det import det_along_sheets, gives_second_derivatives

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

#: a 3-RPR written with its constraints (prismatic legs, phi periodic)
RPR_CUSTOM = """
mechanism = "custom"
pose = ["x", "y", "phi"]
periodic = ["phi"]
joints = ["r1", "r2", "r3"]
[parameters]
b2 = 5.0
u = 2.0
v = 4.0
[[legs]]
joint = "r1"
kind = "prismatic"
constraint = "x**2 + y**2 - r1**2"
[[legs]]
joint = "r2"
kind = "prismatic"
constraint = "(x + cos(phi)*b2 - 10)**2 + (y + sin(phi)*b2)**2 - r2**2"
[[legs]]
joint = "r3"
kind = "prismatic"
constraint = "(x + cos(phi)*u - sin(phi)*v - 4)**2 + (y + sin(phi)*u + cos(phi)*v - 8)**2 - r3**2"
[limits]
r1 = [4.0, 12.0]
r2 = [4.0, 12.0]
r3 = [4.0, 12.0]
[bounds]
x = [-8.0, 16.0]
y = [-8.0, 16.0]
phi = ["-pi", "pi"]
"""


#: a biglide written with its constraints (rails y = 0 and y = 2)
BIGLIDE_CUSTOM = {
    "mechanism": "custom",
    "pose": ["x", "y"],
    "joints": ["r1", "r2"],
    "parameters": {"a": 5.0, "b": 4.0},
    "legs": [
        {"joint": "r1", "kind": "prismatic", "constraint": "(x - r1)**2 + y**2 - a**2"},
        {"joint": "r2", "kind": "prismatic", "constraint": "(x - r2)**2 + (y - 2)**2 - b**2"},
    ],
    "limits": {"r1": [-10.0, 10.0], "r2": [-10.0, 10.0]},
    "bounds": {"x": [-10.0, 10.0], "y": [-6.0, 6.0]},
}


def _mechanisms():
    return {
        "biglide": CustomMechanism(load_spec(BIGLIDE_CUSTOM)),
        "3-RPR": CustomMechanism(load_spec(tomllib.loads(RPR_CUSTOM))),
    }


MECHANISMS = _mechanisms()


def _boxes(m, n, width, rng):
    lo, hi = m.bounds
    span = hi - lo
    centre = lo + rng.random((n, lo.size)) * span
    half = 0.5 * width * span * rng.random((n, lo.size))
    return np.maximum(centre - half, lo), np.minimum(centre + half, hi)


@pytest.mark.parametrize("name", sorted(MECHANISMS))
@pytest.mark.parametrize("width", [0.002, 0.01, 0.05])
def test_enclosures_hold_det_a_on_the_sheets(name, width):
    m = MECHANISMS[name]
    assert gives_second_derivatives(m)
    rng = np.random.default_rng(7)
    lo, hi = _boxes(m, 400, width, rng)
    reach = [leg.reach(lo, hi) for leg in m.legs]
    regular = np.logical_and.reduce([r.status == REGULAR for r in reach])
    branch_angles = [list(r.branches) for r in reach]
    dets = m.det_a_postures(lo, hi, branch_angles)
    narrowed = 0
    checked = 0
    for p, branches in enumerate(m.postures):
        angles = [branch_angles[i][int(b)] for i, b in enumerate(branches)]
        rows = [leg.a_row_boxes(lo, hi, a) for leg, a in zip(m.legs, angles, strict=True)]
        natural = interval_det(rows)
        d = dets[p]
        # never wider than the natural enclosure, and the same as det_a_boxes
        assert np.all(d.lo >= natural.lo) and np.all(d.hi <= natural.hi)
        one = m.det_a_boxes(lo, hi, angles, posture=p)
        assert np.array_equal(one.lo, d.lo) and np.array_equal(one.hi, d.hi)
        narrowed += int(np.sum(((d.lo > 0) | (d.hi < 0)) & (natural.lo <= 0) & (natural.hi >= 0)))
        for b in np.flatnonzero(regular):
            # poses in the box: its corners and random ones
            k = lo.shape[1]
            corners = np.array(
                [[hi[b, j] if (c >> j) & 1 else lo[b, j] for j in range(k)] for c in range(1 << k)]
            )
            inside = lo[b] + rng.random((12, k)) * (hi[b] - lo[b])
            points = np.vstack([corners, inside])
            q = m.joint_angles(points)[:, p, :]
            ok = np.isfinite(q).all(axis=1)
            for i in range(len(m.legs)):
                # the configurations of this posture: each leg's root in its enclosure
                ok &= (q[:, i] >= angles[i].lo[b] - 1e-9) & (q[:, i] <= angles[i].hi[b] + 1e-9)
            if not ok.any():
                continue
            values = m.det_a(points[ok], q[ok])
            slack = 1e-9 * (1.0 + np.abs(values).max())
            assert np.all(values >= d.lo[b] - slack) and np.all(values <= d.hi[b] + slack), (
                name, p, lo[b], hi[b], values, d.lo[b], d.hi[b]
            )
            checked += int(ok.sum())
    assert checked > 100
    if width >= 0.01:
        # the form decides boxes the natural enclosure leaves open (at the
        # narrowest boxes the natural enclosure is about as tight already)
        assert narrowed > 0


@pytest.mark.parametrize("name", sorted(MECHANISMS))
def test_second_derivatives_agree_with_finite_differences(name):
    m = MECHANISMS[name]
    rng = np.random.default_rng(11)
    lo, hi = m.bounds
    points = lo + rng.random((300, lo.size)) * (hi - lo)
    q = m.joint_angles(points)
    for i, leg in enumerate(m.legs):
        d2f_dxdx, d2f_dqdx = leg.second_derivatives
        for b in range(q.shape[1]):
            ok = np.isfinite(q[:, b, i])
            x, t = points[ok], q[ok, b, i]
            if not x.shape[0]:
                continue
            step = 1e-6
            row = leg.a_row(x, t)
            for axis in range(lo.size):
                moved = x.copy()
                moved[:, axis] += step
                numeric = (leg.a_row(moved, t) - row) / step
                for entry in range(lo.size):
                    exact = leg._call(d2f_dxdx[entry][axis], x, t)
                    assert np.allclose(exact, numeric[:, entry], rtol=1e-4, atol=1e-4)
            numeric = (leg.a_row(x, t + step) - row) / step
            for entry in range(lo.size):
                exact = leg._call(d2f_dqdx[entry], x, t)
                assert np.allclose(exact, numeric[:, entry], rtol=1e-4, atol=1e-4)


@pytest.mark.parametrize("name", ["five-bar-custom.toml", "delta-custom.toml"])
def test_revolute_legs_keep_the_natural_enclosure(name):
    """User-defined legs with revolute joints are given no second derivatives (see
    custom._second_derivative_bodies): det A stays the natural enclosure."""
    m = CustomMechanism(load_spec(EXAMPLES / name))
    assert not gives_second_derivatives(m)
    rng = np.random.default_rng(5)
    lo, hi = _boxes(m, 200, 0.02, rng)
    reach = [leg.reach(lo, hi) for leg in m.legs]
    branch_angles = [list(r.branches) for r in reach]
    for p, d in enumerate(m.det_a_postures(lo, hi, branch_angles)):
        angles = [branch_angles[i][int(b)] for i, b in enumerate(m.postures[p])]
        rows = [leg.a_row_boxes(lo, hi, a) for leg, a in zip(m.legs, angles, strict=True)]
        natural = interval_det(rows)
        assert np.array_equal(d.lo, natural.lo, equal_nan=True)
        assert np.array_equal(d.hi, natural.hi, equal_nan=True)


def test_a_leg_without_second_derivatives_keeps_the_natural_enclosure():
    m = MECHANISMS["biglide"]
    lo, hi = np.array([[2.1, 1.0]]), np.array([[2.2, 1.1]])
    reach = [leg.reach(lo, hi) for leg in m.legs]
    angles = [reach[0].branches[0], reach[1].branches[1]]
    rows = [leg.a_row_boxes(lo, hi, a) for leg, a in zip(m.legs, angles, strict=True)]
    plain = CustomMechanism.__new__(CustomMechanism)
    plain.__dict__.update(m.__dict__)
    plain.legs = (m.legs[0], dataclasses.replace(m.legs[1], d2f_dxdx=None, d2f_dqdx=None))
    assert not gives_second_derivatives(plain)
    natural = interval_det(rows)
    kept = det_along_sheets(plain, lo, hi, angles, rows)
    assert np.array_equal(kept.lo, natural.lo) and np.array_equal(kept.hi, natural.hi)
    narrowed = det_along_sheets(m, lo, hi, angles, rows)
    assert narrowed.lo[0] > 0 > natural.lo[0]


def test_rows_at_points_when_a_derivative_is_a_constant():
    """A leg whose constraint does not depend on one pose axis (the 3-RPR's first
    leg, its platform point at the origin: dF/dphi = 0): its row of A at poses,
    det A and the planner's checks take the constant as a column."""
    m = MECHANISMS["3-RPR"]
    points = np.array([[6.0, 4.0, 2.0], [6.5, 4.2, 2.1]])
    q = m.joint_angles(points)
    row = m.legs[0].a_row(points, q[:, 0, 0])
    assert row.shape == (2, 3) and np.array_equal(row[:, 2], [0.0, 0.0])
    assert np.allclose(row[:, :2], 2 * points[:, :2])
    det = m.det_a(points, q[:, 0, :])
    assert det.shape == (2,) and np.isfinite(det).all()
