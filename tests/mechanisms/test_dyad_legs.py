"""User-defined legs recognised as dyads: a circle (sphere) of fixed radius about a
knee the joint moves. The joint-space count then applies to them as to their
built-in twins, and must give the same bounds on the same tree of Q.
"""

from __future__ import annotations

import numpy as np
import pytest

from custom_specs import custom_delta_spec, five_bar_spec
from moveability import analyze
from moveability.analysis.joint_space import count_in_joint_space, joint_condition
from moveability.intervals import Interval
from moveability.limits import JointLimit
from moveability.mechanisms import Delta, FiveBar
from moveability.mechanisms.custom import CustomMechanism
from moveability.mechanisms.dyad_leg import DyadLeg


def _random_five_bars(n, seed):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        lengths = tuple(float(v) for v in np.round(rng.uniform(1.0, 8.0, 5), 1))
        lo = float(np.round(rng.uniform(-np.pi, 0.5), 2))
        limits = (lo, lo + float(np.round(rng.uniform(1.0, 4.0), 2)))
        out.append((lengths, limits))
    return out


@pytest.mark.parametrize("lengths, limits", _random_five_bars(12, 5))
def test_a_user_defined_five_bar_counts_as_its_twin(lengths, limits):
    custom = CustomMechanism(five_bar_spec(lengths, limits))
    twin = FiveBar(*lengths, limits=(JointLimit(*limits), JointLimit(*limits)))
    assert all(isinstance(leg, DyadLeg) for leg in custom.legs)
    a, b = count_in_joint_space(custom), count_in_joint_space(twin)
    assert (a.at_least, a.at_most, a.leaves) == (b.at_least, b.at_most, b.leaves)
    np.testing.assert_array_equal(a.witnesses, b.witnesses)


def test_the_knees_agree_with_the_built_in_legs():
    custom = CustomMechanism(five_bar_spec((7.0, 8.0, 5.0, 8.0, 5.0), (0.0, "pi")))
    twin = FiveBar(7.0, 8.0, 5.0, 8.0, 5.0)
    angles = Interval(np.array([-0.3, 0.4, 2.0]), np.array([-0.2, 0.45, 2.5]))
    for mine, theirs in zip(custom.legs, twin.legs, strict=True):
        assert mine.distal == theirs.distal
        for got, want in zip(mine.knee_boxes(angles), theirs.knee_boxes(angles), strict=True):
            for g, w in zip(got, want, strict=True):
                # both enclose the same functions: they overlap, and agree at points
                assert (g.lo <= w.hi + 1e-12).all() and (w.lo <= g.hi + 1e-12).all()
        from mpmath import iv

        point = iv.mpf(0.7)
        (x, y), (dx, dy) = mine.knee_exact(point, iv)
        (wx, wy), (wdx, wdy) = theirs.knee_exact(point, iv)
        for u, v in ((x, wx), (y, wy), (dx, wdx), (dy, wdy)):
            assert abs(float(u.mid) - float(v.mid)) < 1e-12


def test_a_user_defined_five_bar_is_decided_and_listed():
    spec = five_bar_spec((6.0, 7.0, 4.0, 6.0, 5.5), (0.0, "pi"))
    custom, twin = CustomMechanism(spec), FiveBar(6.0, 7.0, 4.0, 6.0, 5.5)
    got, want = analyze(custom, 0.2), analyze(twin, 0.2)
    assert got.count == want.count and got.count[0] == got.count[1]
    assert len(got.regions) == got.count[0]


def test_scaled_constraints_are_dyads_and_others_are_not():
    base = five_bar_spec()
    scaled = dict(base, legs=[dict(base["legs"][0]), dict(base["legs"][1])])
    scaled["legs"][0]["constraint"] = "3*((x - L1*cos(t1))**2 + (y - L1*sin(t1))**2) - 3*L2**2"
    m = CustomMechanism(scaled)
    assert isinstance(m.legs[0], DyadLeg) and m.legs[0].distal == pytest.approx(5.0)
    # an ellipse, a radius that the joint changes: not dyads
    for constraint in (
        "(x - L1*cos(t1))**2 + 2*(y - L1*sin(t1))**2 - L2**2",
        "(x - L1*cos(t1))**2 + (y - L1*sin(t1))**2 - (L2 + t1)**2",
        "(x - L1*cos(t1))*(y - L1*sin(t1)) - L2**2",
    ):
        other = dict(base, legs=[dict(base["legs"][0], constraint=constraint), base["legs"][1]])
        m = CustomMechanism(other)
        assert not isinstance(m.legs[0], DyadLeg)
        assert joint_condition(m) is None


def test_a_box_that_cuts_the_workspace_gives_no_joint_space_count():
    spec = five_bar_spec()
    # the legs reach x up to L0 + L3 + L4 = 20: a box to 10 cuts their workspace
    spec["bounds"] = {"x": [-14.0, 10.0], "y": [-14.0, 14.0]}
    m = CustomMechanism(spec)
    assert all(isinstance(leg, DyadLeg) for leg in m.legs)
    assert joint_condition(m) is None
    assert analyze(m, 0.5).joint_count is None


@pytest.mark.parametrize(
    "design, limits",
    [
        ((10.0, 4.0, 8.0, 15.0), [(-np.pi / 2, np.pi / 3), (-np.pi / 3, np.pi / 2), (-1.0, 2.0)]),
        ((10.0, 4.0, 8.0, 10.0), [(-np.pi / 2, np.pi / 2)] * 3),
    ],
)
def test_a_user_defined_delta_counts_as_its_twin(design, limits):
    twin = Delta(*design, limits=tuple(JointLimit(*lim) for lim in limits))
    custom = CustomMechanism(custom_delta_spec(design, limits, twin.bounds))
    assert type(joint_condition(custom)).__name__ == "SphereCentres"
    a, b = count_in_joint_space(custom), count_in_joint_space(twin)
    assert (a.at_least, a.at_most, a.leaves) == (b.at_least, b.at_most, b.leaves)
