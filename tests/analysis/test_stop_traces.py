"""Stop traces: boxes of Q on a joint stop, decided by D's trace on the stop.

References: quadratics and cubics whose roots are known in closed form; and
five-bars whose stop is tangent to the boundary of D, built in closed form.
For those, the side of the tangency that the floats fall on is found from the
closed form of the distance's extremum along the stop (50 digits), and the
count is checked against the same design with the stop moved 1e-3 further to
that side, where nothing is near-degenerate and the joint-space count without
traces decides it.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from mpmath import mp, mpf

import moveability.analysis.joint_space as js
from moveability.analysis.joint_space import count_in_joint_space, joint_condition
from moveability.analysis.stop_traces import trace_runs
from moveability.limits import JointLimit
from moveability.mechanisms import FiveBar
from region_references import joint_space_count


def _quadratic(r: float, delta: str):
    return lambda ctx, t: ((t - r) ** 2 - ctx.mpf(delta), 2 * (t - r))


@pytest.mark.parametrize("delta", ["-1e-3", "-1e-14", "-1e-40", "1e-40", "1e-14", "1e-3"])
def test_runs_of_a_quadratic(delta):
    rng = np.random.default_rng(int(abs(float(delta)) ** 0.01 * 1e6) + (delta[0] == "-"))
    for _ in range(20):
        r = float(rng.uniform(-2, 2))
        lo, hi = sorted(rng.uniform(-3, 3, 2).tolist())
        runs = trace_runs(_quadratic(r, delta), lo, hi)
        with mp.workdps(60):
            d = mpf(delta)
            roots = [mpf(r) - mp.sqrt(d), mpf(r) + mp.sqrt(d)] if d > 0 else []
            inside = [x for x in roots if lo < x < hi]
            if runs is None:
                # undecided only where the dip is narrower than the floats can cut
                assert inside and roots[1] - roots[0] < 1e-15
                continue
            # the runs: pieces of [lo, hi] between the roots inside it where q > 0
            cuts = [mpf(lo), *inside, mpf(hi)]
            want = [
                (a, b)
                for a, b in itertools.pairwise(cuts)
                if ((a + b) / 2 - r) ** 2 > d
            ]
            assert runs.shape[0] == len(want)
            for row, (a, b) in zip(runs, want, strict=True):
                # the outer range holds the run; the point inside lies in it
                assert row[0] <= a and b <= row[1]
                assert (mpf(row[2]) - r) ** 2 > d
                assert bool(row[3]) == (a == lo) and bool(row[4]) == (b == hi)


def test_runs_of_a_cubic_and_undecided_zeros():
    # (t - 0.5)(t - 1)(t - 2) on [0, 3]: positive on (0.5, 1) and (2, 3]
    f = lambda ctx, t: (  # noqa: E731
        (t - 0.5) * (t - 1) * (t - 2),
        3 * t**2 - 7 * t + 3.5,
    )
    runs = trace_runs(f, 0.0, 3.0)
    assert runs is not None and runs.shape[0] == 2
    assert runs[0, 0] <= 0.5 and 1.0 <= runs[0, 1] <= 2.0 and runs[1, 0] <= 2.0
    assert runs[1, 1] == 3.0 and runs[1, 4] == 1.0 and runs[0, 3] == 0.0
    # a zero proved exactly at an end (0.5 - 0.5 is 0): not in the runs
    runs = trace_runs(f, 0.5, 3.0)
    assert runs is not None and runs.shape[0] == 2 and runs[0, 3] == 0.0
    assert runs[0, 0] == 0.5 and 0.5 < runs[0, 2] < 1.0
    # a double root at no float: undecided, never a guess
    third = lambda ctx, t: ((3 * t - 1) ** 2, 6 * (3 * t - 1))  # noqa: E731
    assert trace_runs(third, 0.0, 1.0) is None
    # a double root on a breakpoint: the two sides are two runs
    runs = trace_runs(_quadratic(1.5, "0"), 0.0, 3.0)
    assert runs is not None and runs[:, :2].tolist() == [[0.0, 1.5], [1.5, 3.0]]


def _tangent_stop(rng: np.random.Generator, shift: float):
    """A five-bar whose theta1 stop c makes the distance of the knees along it reach
    a bound of D exactly (in closed form), c moved by ``shift``; and the
    signed margin of D at that extremum, at the floats of the design."""
    while True:
        l0, l1, l2, l3, l4 = (float(v) for v in np.round(rng.uniform(2.0, 8.0, 5), 1))
        upper = bool(rng.random() < 0.5)
        # the extremum of d along theta1 = c is |C1(c) - B2| + l3 (max) or
        # | |C1(c) - B2| - l3 | (min), B2 = (l0, 0)
        target = (l2 + l4 - l3) if upper else (l3 + abs(l2 - l4))
        cos_c = (l1 * l1 + l0 * l0 - target * target) / (2 * l0 * l1)
        if target <= 0 or not -0.95 < cos_c < 0.95:
            continue
        c = math.acos(cos_c) * (1 if rng.random() < 0.5 else -1) + shift
        low_side = bool(rng.random() < 0.5)
        span = float(rng.uniform(0.8, 2.5))
        t1 = (c, c + span) if low_side else (c - span, c)
        a = float(rng.uniform(-math.pi, math.pi))
        t2 = (a, a + float(rng.uniform(1.5, 5.0)))
        m = FiveBar(l0, l1, l2, l3, l4, (JointLimit(*t1), JointLimit(*t2)))
        with mp.workdps(50):
            c_m = mpf(c)
            r = mp.sqrt(mpf(l1) ** 2 + mpf(l0) ** 2 - 2 * mpf(l0) * mpf(l1) * mp.cos(c_m))
            if upper:
                margin = (mpf(l2) + mpf(l4)) ** 2 - (r + mpf(l3)) ** 2
            else:
                margin = (r - mpf(l3)) ** 2 - (mpf(l2) - mpf(l4)) ** 2
            # the extremum lies inside theta2's range (else no tangency in Q)
            b2 = (mpf(l0), mpf(0))
            c1 = (mpf(l1) * mp.cos(c_m), mpf(l1) * mp.sin(c_m))
            toward = mp.atan2(c1[1] - b2[1], c1[0] - b2[0])
            # the farthest point of C2's circle from C1 (max), or the nearest (min)
            t_star = toward + mp.pi if upper else toward
            t_star = float(t_star)
        lo2 = t2[0]
        t_star = lo2 + (t_star - lo2) % (2 * math.pi)
        if not lo2 + 0.05 < t_star < t2[1] - 0.05:
            continue
        return m, float(margin), low_side, c


def _moved(m: FiveBar, low_side: bool, step: float) -> FiveBar:
    t1, t2 = m.limits
    lim = JointLimit(t1.lo + step, t1.hi) if low_side else JointLimit(t1.lo, t1.hi + step)
    return FiveBar(*m.lengths, (lim, t2))


@pytest.mark.parametrize("shift", [0.0, 1e-15, -1e-15, 1e-12, -1e-12, 1e-9])
def test_tangent_stops_against_the_design_moved_off_the_tangency(shift):
    rng = np.random.default_rng(int(abs(shift) * 1e15) % 1000 + (shift < 0) * 7 + 3)
    compared = decided = 0
    for _ in range(6):
        m, margin, low_side, _ = _tangent_stop(rng, shift)
        found = count_in_joint_space(m)
        decided += found.decided
        # move the stop 1e-3 to the side the floats fall on: the margin at the
        # extremum grows in magnitude, keeping its sign (the stop's derivative of
        # the margin decides the direction)
        step = 1e-3
        with mp.workdps(50):
            probe = _tangent_margin(m, low_side, step)
        direction = 1.0 if (probe - margin) * margin > 0 else -1.0
        far = _moved(m, low_side, direction * step)
        truth = count_in_joint_space(far, stop_traces=False)
        if not truth.decided:
            continue
        compared += 1
        assert found.at_least <= truth.at_least
        assert found.at_most is None or truth.at_most <= found.at_most
    assert decided >= 5, decided
    assert compared >= 4, compared


def _tangent_margin(m: FiveBar, low_side: bool, step: float) -> float:
    """The margin at the extremum along the stop moved by ``step`` (see
    :func:`_tangent_stop`), for the bound the design is tangent to."""
    l0, l1, l2, l3, l4 = (mpf(v) for v in m.lengths)
    t1 = m.limits[0]
    c = mpf(t1.lo if low_side else t1.hi) + step
    r = mp.sqrt(l1**2 + l0**2 - 2 * l0 * l1 * mp.cos(c))
    hi_gap = (l2 + l4) ** 2 - (r + l3) ** 2
    lo_gap = (r - l3) ** 2 - (l2 - l4) ** 2
    return float(hi_gap if abs(hi_gap) < abs(lo_gap) else lo_gap)


def test_a_stop_that_only_touches_d_is_said_degenerate_or_decided():
    # knees exactly the distal links' sum apart at theta1 = 0 = theta2: a stop
    # of each joint through that point; decided or open, never wrong
    m = FiveBar(2.0, 1.0, 1.0, 1.0, 1.0, (JointLimit(0.0, 1.5), JointLimit(0.0, 1.5)))
    assert joint_condition(m) is not None
    found = count_in_joint_space(m)
    plain = count_in_joint_space(m, stop_traces=False)
    assert found.at_least >= plain.at_least
    if plain.at_most is not None and found.at_most is not None:
        assert found.at_most <= plain.at_most


@pytest.mark.parametrize(
    "m",
    [
        FiveBar(5.2, 5.587, 1.26, 5.06, 1.26, (
            JointLimit(5.309109137899916, 11.309109137899917),
            JointLimit(-1.7901937514267752, -1.7701937514267752),
        )),
        FiveBar(4.92, 1.45, 3.54, 1.45, 3.54, (
            JointLimit(3.100793040404903, 3.120793040404903),
            JointLimit(-1.183562865822816, 1.816437134177184),
        )),
    ],
)  # fmt: skip
def test_pieces_of_blocks_on_two_stops_join_where_they_share_a_point(m):
    """Narrow windows: blocks on two stops meet near a corner of Q. A point of D
    that one block's trace certifies (an end of its run) lies in the other's
    closed box, and so in one of its pieces: the two join, and the traces alone
    decide what the plain count decides."""
    plain = count_in_joint_space(m, stop_traces=False)
    assert plain.decided
    traced = js._count(m, joint_condition(m), None, None, True)
    assert (traced.at_least, traced.at_most) == (plain.at_least, plain.at_most)


@pytest.mark.parametrize(
    "lengths, theta1, theta2, upper, count",
    [
        # theta1's lower stop: the hole d < L2 - L4 stays 4.4e-16 (in d^2) off it
        ((1.3, 6.0, 4.6, 4.8, 3.8), (-1.152976021597577, 1.8354377097000063),
         (-3.493129765509691, -0.8884375392349664), False, 4),
        # theta1's upper stop: 1.3e-14 inside d < L2 + L4, a channel along it
        ((7.1, 3.5, 4.5, 3.0, 4.0), (-3.758039976546116, -0.8604284956229948),
         (-1.5877925377533861, 1.5135518559151502), True, 2),
    ],
)  # fmt: skip
def test_channels_along_a_stop_narrower_than_a_float_are_counted(
    lengths, theta1, theta2, upper, count
):
    """Two designs of benchmarks/bench_counts.py whose stop runs a hair inside D at
    its tangency: a grid of Q splits D there (a 1200 x 1200 grid counts one
    component more), the traces join it. The margin at the tangency, from the
    closed form of the knees' distance along the stop at 50 digits, says the
    stop lies in D; the design with that stop moved 1e-2 further into D (no
    near-degeneracy left) has the same count, without traces and on the grid."""
    m = FiveBar(*lengths, (JointLimit(*theta1), JointLimit(*theta2)))
    low_side = not upper
    with mp.workdps(50):
        margin = _tangent_margin(m, low_side, 0.0)
    assert 0 < margin < 1e-13
    found = count_in_joint_space(m)
    assert found.decided and found.at_least == count
    with mp.workdps(50):
        step = 1e-2 if _tangent_margin(m, low_side, 1e-2) > margin else -1e-2
    moved = _moved(m, low_side, step)
    far = count_in_joint_space(moved, stop_traces=False)
    assert far.decided and far.at_least == count
    assert joint_space_count(moved, 1200) == count
