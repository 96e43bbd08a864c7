"""Certified shortcuts and corner cutting: soundness against the closed form, and the
laws of the greedy search and of the corner cutting."""

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from moveability import load_spec
from moveability.analysis.smoothing import (
    certify_segments,
    cut_corners,
    path_length,
    shortcut,
    smooth_path,
)
from moveability.errors import InvalidParameterError
from moveability.limits import JointLimit
from moveability.mechanisms import FiveBar, ThreeRPR, from_spec

PAPER = FiveBar()  # the paper's design: L0=7, L1=L3=8, L2=L4=5, 0 <= theta <= pi


def _valid_along(m, a, b, posture, sign, n=400):
    """Closed-form check of a segment at n + 1 points: reachable in the posture,
    within the limits, det A of the sign."""
    s = np.linspace(0.0, 1.0, n + 1)[:, None]
    poses = a + s * (b - a)
    q = m.joint_angles(poses)[:, posture]
    if not np.isfinite(q).all():
        return False
    within = all(lim.contains(q[:, i]).all() for i, lim in enumerate(m.limits))
    return within and bool((np.sign(m.det_a(poses, q)) == sign).all())


def test_segments_in_a_certified_area_are_proved_and_others_are_not():
    # (2, 3) -> (5, 3) keeps posture +- (index 1) regular, det A < 0; (2, 3) -> (2, 20)
    # leaves the workspace
    ok = certify_segments(
        PAPER, [[2.0, 3.0], [2.0, 3.0]], [[5.0, 3.0], [2.0, 20.0]], 1, -1, resolution=0.01
    )
    assert ok.tolist() == [True, False]
    assert _valid_along(PAPER, np.array([2.0, 3.0]), np.array([5.0, 3.0]), 1, -1)
    # the same segment with the other sign is refused
    assert not certify_segments(PAPER, [[2.0, 3.0]], [[5.0, 3.0]], 1, 1, 0.01)[0]


def test_a_point_and_a_reversed_segment():
    a, b = np.array([[2.0, 3.0]]), np.array([[5.0, 3.0]])
    assert certify_segments(PAPER, a, a, 1, -1, 0.01)[0]  # a degenerate segment
    assert certify_segments(PAPER, b, a, 1, -1, 0.01)[0]


@pytest.mark.parametrize(
    ("spec", "spread"),
    [
        ("examples/five-bar-paper.toml", 1.0),
        ("examples/five-bar-full-turn.toml", 1.0),
        ("examples/biglide.toml", 1.0),
        ("examples/three-rpr.toml", (2.0, 2.0, 0.2)),
    ],
)
def test_proved_segments_are_valid_at_every_sample(spec, spread):
    # soundness, differentially: whatever is proved agrees with the closed form along
    # the segment; and some random segments are proved
    m = from_spec(load_spec(spec))
    rng = np.random.default_rng(7)
    lo, hi = m.bounds
    k = len(lo)
    a = rng.uniform(lo, hi, (400, k))
    b = a + rng.normal(0.0, 1.0, (400, k)) * np.asarray(spread)
    proved = 0
    for posture in range(m.postures.shape[0]):
        for sign in (1, -1):
            ok = certify_segments(m, a, b, posture, sign, np.asarray(spread) / 50)
            for i in np.flatnonzero(ok):
                assert _valid_along(m, a[i], b[i], posture, sign)
            proved += int(ok.sum())
    assert proved >= 20


def test_periodic_angles_may_be_unwrapped():
    stroke = JointLimit(3.0, 14.0, prismatic=True)
    m = ThreeRPR([[0, 0], [12, 1], [-2, 9]], [[1, -1], [6, 0], [3, 5]], (stroke,) * 3)
    a = np.array([[4.3, 1.3, 2.99]])
    b = np.array([[4.3, 1.3, 3.19]])  # past pi: the same as -3.09
    turn = np.array([[0.0, 0.0, 2.0 * np.pi]])
    for sign in (1, -1):
        here = certify_segments(m, a, b, 0, sign, (0.05, 0.05, 0.01))
        there = certify_segments(m, a - turn, b - turn, 0, sign, (0.05, 0.05, 0.01))
        assert here.tolist() == there.tolist()
    # the segment is proved with the sign of det A found at its ends
    q = m.joint_angles(a)[:, 0]
    sign = int(np.sign(m.det_a(a, q))[0])
    assert certify_segments(m, a, b, 0, sign, (0.05, 0.05, 0.01))[0]


def test_postures_one_per_segment():
    a = np.array([[2.0, 3.0], [2.0, 3.0]])
    b = np.array([[5.0, 3.0], [5.0, 3.0]])
    assert certify_segments(PAPER, a, b, [1, 0], -1, 0.01).tolist() == [True, False]


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"posture": 4}, "posture"),
        ({"posture": [0, 1, 2]}, "posture"),
        ({"sign": 0}, "sign"),
        ({"resolution": -1.0}, "resolution"),
        ({"resolution": [0.1, 0.1, 0.1]}, "resolution"),
        ({"ends": [[1.0, 2.0, 3.0]]}, "ends"),
    ],
)
def test_bad_arguments_are_named(kwargs, name):
    args = {
        "starts": [[2.0, 3.0]],
        "ends": [[5.0, 3.0]],
        "posture": 1,
        "sign": -1,
        "resolution": 0.01,
        **kwargs,
    }
    with pytest.raises(InvalidParameterError, match=name):
        certify_segments(PAPER, **args)


# ---------------------------------------------------------------- the greedy search
@settings(max_examples=60, deadline=None)
@given(st.integers(1, 300), st.lists(st.integers(1, 299), max_size=8))
def test_shortcut_keeps_ends_and_only_allowed_jumps(n, walls):
    walls = sorted({w for w in walls if w < n})

    def test(i, js):
        # a shortcut may not jump over a wall (a wall w separates w - 1 and w)
        return np.array([not any(i < w <= j for w in walls) for j in js], dtype=bool)

    kept = shortcut(test, n)
    assert kept[0] == 0 and kept[-1] == n - 1
    assert all(b > a for a, b in itertools.pairwise(kept))
    for a, b in itertools.pairwise(kept):
        assert b == a + 1 or test(a, np.array([b]))[0]
    # with walls only, the greedy search is optimal: one jump per wall, at most
    assert len(kept) <= 2 * len(walls) + 2


def test_shortcut_extremes():
    assert shortcut(lambda i, js: np.ones(js.size, dtype=bool), 50) == [0, 49]
    assert shortcut(lambda i, js: np.zeros(js.size, dtype=bool), 6) == [0, 1, 2, 3, 4, 5]
    assert shortcut(lambda i, js: np.ones(js.size, dtype=bool), 1) == [0]
    with pytest.raises(InvalidParameterError, match="n"):
        shortcut(lambda i, js: js > 0, 0)


# ---------------------------------------------------------------- corner cutting
@settings(max_examples=40, deadline=None)
@given(
    st.lists(
        st.tuples(st.floats(-10, 10), st.floats(-10, 10)), min_size=2, max_size=12, unique=True
    ),
    st.integers(0, 4),
    st.integers(0, 2**12 - 1),
)
def test_cutting_corners_shortens_and_keeps_what_is_fixed(points, rounds, mask):
    v = np.array(points)
    movable = np.array([(mask >> i) & 1 for i in range(v.shape[0])], dtype=bool)
    allowed = np.random.default_rng(mask).random(64) < 0.7

    def test(a, b, at):
        return allowed[at % 64]

    out, origin = cut_corners(test, v, movable, rounds=rounds)
    assert path_length(out) <= path_length(v) + 1e-9
    np.testing.assert_array_equal(out[0], v[0])
    np.testing.assert_array_equal(out[-1], v[-1])
    # the ends and the fixed corners are still there, in order
    keep = [i for i in range(v.shape[0]) if not movable[i] or i in (0, v.shape[0] - 1)]
    assert set(keep) <= set(origin.tolist())
    kept = origin[origin >= 0]
    assert (np.diff(kept) > 0).all()
    np.testing.assert_array_equal(out[origin >= 0], v[kept])


def test_cutting_a_square_corner_tends_to_a_curve():
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    yes = lambda a, b, at: np.ones(len(a), dtype=bool)  # noqa: E731
    out, origin = cut_corners(yes, square, [True, True, True], rounds=4)
    assert out.shape[0] == 2**4 + 2 and origin.tolist()[::17] == [0, 2]
    assert 1.5 < path_length(out) < 2.0
    refused, _ = cut_corners(lambda a, b, at: np.zeros(len(a), bool), square, [True] * 3)
    np.testing.assert_array_equal(refused, square)
    # only short cuts allowed: the cut shrinks to a quarter, then a sixteenth
    short = lambda a, b, at: np.linalg.norm(b - a, axis=1) < 0.1  # noqa: E731
    out, _ = cut_corners(short, square, [True] * 3, rounds=1)
    np.testing.assert_allclose(out[1:3], [[1.0 - 1 / 16, 0.0], [1.0, 1 / 16]])
    with pytest.raises(InvalidParameterError, match="cut"):
        cut_corners(yes, square, [True] * 3, cut=0.75)
    with pytest.raises(InvalidParameterError, match="movable"):
        cut_corners(yes, square, [True] * 2)


# ---------------------------------------------------------------- whole motions
def test_smooth_path_keeps_fixed_poses_and_posture_changes():
    # a zigzag in posture +- (1), a posture change to ++ (0) in place, then back
    zig = np.array([[2.0, 3.0], [3.0, 4.0], [4.0, 3.0], [5.0, 4.0], [5.0, 4.0], [5.0, 3.5]])
    post = np.array([1, 1, 1, 1, 0, 0])
    fixed = np.array([True, False, True, False, False, True])
    p, q, origin = smooth_path(PAPER, zig, post, fixed, -1, 0.01, rounds=0)
    # kept: the fixed ones and both sides of the change; 1 is cut out
    assert origin.tolist() == [0, 2, 3, 4, 5]
    assert q.tolist() == [1, 1, 1, 0, 0]
    np.testing.assert_array_equal(p, zig[origin])
    with pytest.raises(InvalidParameterError, match="postures, fixed"):
        smooth_path(PAPER, zig, post[:3], fixed, -1, 0.01)


def test_a_second_pass_keeps_the_fixed_configurations():
    # a zigzag in posture +- (1) through a fixed middle pose
    x = np.linspace(1.0, 6.0, 21)
    zig = np.stack([x, 3.0 + 0.4 * (np.arange(21) % 2)], axis=1)
    fixed = np.zeros(21, dtype=bool)
    fixed[10] = True
    post = np.ones(21, dtype=int)
    one, _, o1 = smooth_path(PAPER, zig, post, fixed, -1, 0.0125, passes=1)
    two, q, o2 = smooth_path(PAPER, zig, post, fixed, -1, 0.0125, passes=2, spacing=0.1)
    for p, origin in ((one, o1), (two, o2)):
        assert {0, 10, 20} <= set(origin.tolist())
        np.testing.assert_array_equal(p[origin >= 0], zig[origin[origin >= 0]])
        assert path_length(p) < 0.8 * path_length(zig)
    assert path_length(two) <= path_length(one) + 1e-9
    assert (q == 1).all()
    with pytest.raises(InvalidParameterError, match="spacing"):
        smooth_path(PAPER, zig, post, fixed, -1, 0.0125, passes=2, spacing=0.0)


def test_path_length():
    assert path_length([[0.0, 0.0], [3.0, 4.0]]) == 5.0
    assert path_length([1.0, 3.0, 2.0]) == 3.0
    assert path_length([[1.0, 1.0]]) == 0.0
