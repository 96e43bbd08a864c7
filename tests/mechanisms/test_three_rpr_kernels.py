"""The 3-RPR's compiled enclosures (mechanisms/_rpr_kernels.py) against the
:class:`~moveability.intervals.Interval` path they replace.

The kernels repeat the Interval operations' steps box by box, so their bounds
must be the same floats, bit for bit (compared as integers: a zero's sign and
NaN included): det A (natural form intersected with the mean-value form), the
rows and their partials, the legs' lengths and joint gradients. The boxes are
small and large, with phi anywhere in a turn and across the periodic seam,
degenerate (lo == hi) in some or all axes, on signed zeros, and far away; their
numbers are not multiples of the kernels' chunk. The enclosures are also
checked to hold the exact values at points sampled inside the boxes.
"""

from __future__ import annotations

from fractions import Fraction
from math import isqrt

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from moveability import intervals as iv
from moveability.intervals import Interval
from moveability.limits import JointLimit
from moveability.mechanisms import ThreeRPR
from moveability.mechanisms import _rpr_kernels as kernels
from moveability.mechanisms.constraints import Constraints

DESIGNS = [
    ([[0, 0], [15.91, 0], [0, 10]], [[0, 0], [17.04, 0], [13.24, 16.10]], (10, 25)),
    ([[0, 0], [10, 0], [4, 8]], [[0, 0], [5, 0], [2, 4]], (4, 12)),
    ([[0, 0], [12, 1], [-2, 9]], [[1, -1], [6, 0], [3, 5]], (3, 14)),
    # far from the origin, and with coordinates of mixed magnitudes
    ([[1e6, -3e5], [1e6 + 7.5, -3e5], [1e6, -3e5 + 0.1]], [[-0.0, 0.0], [1e-3, 2.5], [7.0, -1e-9]],
     (0.5, 40)),
]  # fmt: skip


def _mechanism(design) -> ThreeRPR:
    base, platform, (lo, hi) = design
    stroke = JointLimit(float(lo), float(hi), prismatic=True)
    return ThreeRPR(base, platform, (stroke, stroke, stroke))


def _boxes(mechanism: ThreeRPR, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``n`` boxes of every kind, in random order."""
    rng = np.random.default_rng(seed)
    plo, phi = mechanism.pose_box()
    span = phi - plo
    kinds = rng.integers(0, 7, n)
    centre = plo + rng.random((n, 3)) * span
    # widths from a whole span down to a few ulps, per axis
    width = span * 10.0 ** rng.uniform(-12, 0, (n, 3))
    width[kinds == 0] = span  # the whole box
    width[kinds == 1] = 0.0  # points
    # degenerate in one axis
    one = np.flatnonzero(kinds == 2)
    width[one, rng.integers(0, 3, one.size)] = 0.0
    lo, hi = centre - width / 2, centre + width / 2
    # across the periodic seam: phi from below pi to beyond it
    seam = kinds == 3
    lo[seam, 2] = np.pi - rng.uniform(0, 0.3, seam.sum())
    hi[seam, 2] = np.pi + rng.uniform(0, 0.3, seam.sum())
    # phi spanning the turn, from -pi to pi (and the pose box's end beyond it)
    turn = kinds == 4
    lo[turn, 2], hi[turn, 2] = -np.pi, rng.choice([np.pi, phi[2]], turn.sum())
    # on signed zeros: a box starting at -0.0 or ending at 0.0
    zeros = np.flatnonzero(kinds == 5)
    axis = rng.integers(0, 3, zeros.size)
    lo[zeros, axis] = -0.0
    hi[zeros, axis] = np.maximum(hi[zeros, axis], 0.0)
    # far away (the lengths huge) and near the turn's quarter points
    far = kinds == 6
    lo[far, :2] *= 1e8
    hi[far, :2] = lo[far, :2] + width[far, :2]
    lo[far, 2] = rng.choice([-np.pi / 2, 0.0, np.pi / 2, np.pi], far.sum())
    hi[far, 2] = lo[far, 2] + width[far, 2]
    return lo, hi


def _bits(x) -> np.ndarray:
    return np.ascontiguousarray(np.asarray(x, dtype=np.float64)).view(np.int64)


def _assert_same(new: Interval, old: Interval) -> None:
    """The same floats, bit for bit."""
    assert new.lo.shape == old.lo.shape
    np.testing.assert_array_equal(_bits(new.lo), _bits(old.lo))
    np.testing.assert_array_equal(_bits(new.hi), _bits(old.hi))


def _angles(n: int) -> list[Interval]:
    # det A's rows depend on the pose alone: any enclosures of the lengths do
    return [Interval(np.full(n, 10.0), np.full(n, 11.0))] * 3


def _assert_all_same(mechanism: ThreeRPR, lo: np.ndarray, hi: np.ndarray) -> None:
    n = lo.shape[0]
    angles = _angles(n)
    with np.errstate(all="ignore"):
        _assert_same(
            mechanism.det_a_boxes(lo, hi, angles), mechanism._det_a_boxes_intervals(lo, hi, angles)
        )
        rows, partials = mechanism.rows_and_partials(lo, hi, angles)
        ref_rows, ref_partials = mechanism._rows_and_partials_intervals(lo, hi, angles)
        for row, ref in zip(rows, ref_rows, strict=True):
            for x, y in zip(row, ref, strict=True):
                _assert_same(x, y)
        for (along_x, along_q), (ref_x, ref_q) in zip(partials, ref_partials, strict=True):
            for entry, ref in zip(along_x, ref_x, strict=True):
                for x, y in zip(entry, ref, strict=True):
                    _assert_same(x, y)
            for x, y in zip(along_q, ref_q, strict=True):
                _assert_same(x, y)
        # the reaches and det A in one pass (the sheets' classification)
        reaches, det = mechanism.reaches_and_det(lo, hi)
        assert det is not None
        _assert_same(det, mechanism._det_a_boxes_intervals(lo, hi, angles))
        for leg, fused in zip(mechanism.rpr_legs, reaches, strict=True):
            length = leg._length_intervals(lo, hi)
            _assert_same(fused.hull, length)
            assert len(fused.branches) == 1
            _assert_same(fused.branches[0], length)
            np.testing.assert_array_equal(fused.status, np.where(length.lo > 0, 1, 4))
            assert not fused.fold_connected.any()
        for leg in mechanism.rpr_legs:
            reach = leg.reach(lo, hi)
            length = leg._length_intervals(lo, hi)
            _assert_same(reach.hull, length)
            np.testing.assert_array_equal(reach.status, np.where(length.lo > 0, 1, 4))
            # the lengths' own enclosures, and ones that straddle or touch zero
            for rho in (
                length,
                Interval(np.zeros(n), length.hi),
                Interval(-length.hi, -np.maximum(length.lo, 1e-300)),
                Interval(np.full(n, -0.0), np.full(n, -0.0)),
            ):
                new = leg.joint_gradient(lo, hi, 0, rho)
                old = leg._joint_gradient_intervals(lo, hi, 0, rho)
                for x, y in zip(new, old, strict=True):
                    _assert_same(x, y)


@pytest.mark.parametrize("design", range(len(DESIGNS)))
def test_kernels_give_the_interval_bounds_bit_for_bit(design):
    mechanism = _mechanism(DESIGNS[design])
    # 2999 boxes: eleven full chunks and a tail
    lo, hi = _boxes(mechanism, 2999, seed=design)
    _assert_all_same(mechanism, lo, hi)


def test_kernels_take_the_cosine_and_sine_given_or_compute_them():
    """With ``trig`` (4, n) given (``intervals.cos`` and ``sin`` of phi) or none
    (4, 0): the kernels compute the same bounds box by box."""
    mechanism = _mechanism(DESIGNS[2])
    lo, hi = _boxes(mechanism, 777, seed=5)
    c, s = iv.cos(Interval(lo[:, 2], hi[:, 2])), iv.sin(Interval(lo[:, 2], hi[:, 2]))
    trig = np.stack([c.lo, c.hi, s.lo, s.hi])
    legs = mechanism._leg_geometry
    for cos_sin in (trig, kernels.NO_TRIG):
        out = np.empty((2, 777))
        kernels.det_a_bounds(lo, hi, cos_sin, legs, out[0], out[1])
        rows = np.empty((2, 3 * kernels.ROW_ITEMS, 777))
        kernels.row_bounds(lo, hi, cos_sin, legs, rows[0], rows[1])
        length = np.empty((2, 777))
        kernels.reach_bounds(lo, hi, cos_sin, legs[1], length[0], length[1])
        grad = np.empty((2, 3, 777))
        kernels.joint_gradient_bounds(lo, hi, cos_sin, legs[2], length[0], length[1], *grad)
        if cos_sin is trig:
            first = (out, rows, length, grad)
        else:
            for new, old in zip((out, rows, length, grad), first, strict=True):
                np.testing.assert_array_equal(_bits(new), _bits(old))


@pytest.mark.parametrize("n", [0, 1, 255, 256, 257])
def test_kernels_at_the_chunk_edges(n):
    mechanism = _mechanism(DESIGNS[0])
    lo, hi = _boxes(mechanism, n, seed=n)
    _assert_all_same(mechanism, lo, hi)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.tuples(
            *[st.floats(-40.0, 40.0, allow_subnormal=True)] * 2,
            st.floats(-4.0, 4.0, allow_subnormal=True),
            *[st.floats(0.0, 50.0)] * 2,
            st.floats(0.0, 7.0),
        ),
        min_size=1,
        max_size=40,
    )
)
def test_kernels_on_arbitrary_boxes(boxes):
    mechanism = _mechanism(DESIGNS[0])
    data = np.array(boxes, dtype=np.float64)
    lo = data[:, :3]
    _assert_all_same(mechanism, lo, lo + data[:, 3:])


def test_kernels_take_wider_and_strided_arrays():
    """Boxes given as columns of wider arrays (the analysis's leaves hold the
    joints after the pose): the first three columns, as the Interval path reads them."""
    mechanism = _mechanism(DESIGNS[1])
    lo, hi = _boxes(mechanism, 700, seed=7)
    wide_lo = np.concatenate([lo, np.full((700, 3), 5.0)], axis=1)
    wide_hi = np.concatenate([hi, np.full((700, 3), 6.0)], axis=1)
    _assert_all_same(mechanism, wide_lo, wide_hi)
    _assert_all_same(mechanism, wide_lo[:, :3], wide_hi[:, :3])
    _assert_all_same(mechanism, lo[::-3], hi[::-3])


def test_constrained_mechanism_keeps_the_bounds():
    """A 3-RPR with restrictions (a passive limit) has the same det A and rows."""
    mechanism = _mechanism(DESIGNS[0])
    limited = mechanism.constrained(Constraints(passive={"B1": JointLimit(-2.0, 2.0)}))
    lo, hi = _boxes(mechanism, 500, seed=11)
    _assert_all_same(limited, lo, hi)
    angles = _angles(500)
    _assert_same(limited.det_a_boxes(lo, hi, angles), mechanism.det_a_boxes(lo, hi, angles))


# ------------------------------------------------------------- exact values
#: the fixed point of the reference: sin and cos to about 2^-290, the rest exact
_BITS = 320
_SLACK = Fraction(1, 1 << 250)


def _sin_cos(phi: float) -> tuple[Fraction, Fraction]:
    """The sine and cosine of the float ``phi`` (|phi| < 8) within 2^-290: their
    Taylor series in integers scaled by 2^320, each term truncated once."""
    one = 1 << _BITS
    scaled = Fraction(phi) * one
    assert scaled.denominator == 1  # the floats sampled here are multiples of 2^-320
    x = scaled.numerator
    x2 = x * x >> _BITS
    sine, term, k = x, x, 1
    while term:
        term = -(term * x2 // ((2 * k) * (2 * k + 1))) >> _BITS
        sine, k = sine + term, k + 1
    cosine, term, k = one, one, 1
    while term:
        term = -(term * x2 // ((2 * k - 1) * (2 * k))) >> _BITS
        cosine, k = cosine + term, k + 1
    return Fraction(sine, one), Fraction(cosine, one)


def _exact_rows(mechanism: ThreeRPR, pose: np.ndarray) -> list[list[Fraction]]:
    """Each leg's ``dx, dy, turn, -rby, rbx, -(rbx px + rby py)`` at a pose."""
    x, y = Fraction(pose[0]), Fraction(pose[1])
    sine, cosine = _sin_cos(float(pose[2]))
    out = []
    for (ax, ay), (bx, by) in zip(mechanism.base, mechanism.platform, strict=True):
        rbx = cosine * Fraction(bx) - sine * Fraction(by)
        rby = sine * Fraction(bx) + cosine * Fraction(by)
        px, py = x - Fraction(ax), y - Fraction(ay)
        out.append([px + rbx, py + rby, rbx * py - rby * px, -rby, rbx, -(rbx * px + rby * py)])
    return out


def _det(rows: list[list[Fraction]]) -> Fraction:
    (a, b, c), (d, e, f), (g, h, i) = (r[:3] for r in rows)
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)


def _holds(value: Fraction, lo: float, hi: float) -> bool:
    """``lo <= value <= hi`` up to the reference's error (an infinite bound holds all)."""
    return (lo == -np.inf or Fraction(lo) - _SLACK <= value) and (
        hi == np.inf or value <= Fraction(hi) + _SLACK
    )


@pytest.mark.parametrize("design", range(len(DESIGNS)))
def test_enclosures_hold_exact_values(design):
    """det A, the rows and their partials, the lengths and the joint gradients
    at points of each box (its corners and random points) lie in the box's
    enclosures: the values computed exactly (sin and cos within 2^-290)."""
    mechanism = _mechanism(DESIGNS[design])
    rng = np.random.default_rng(100 + design)
    n, k = 60, 12
    lo, hi = _boxes(mechanism, n, seed=200 + design)
    corners = np.array([[(c >> a) & 1 for a in range(3)] for c in range(8)], dtype=np.float64)
    t = np.concatenate([np.broadcast_to(corners, (n, 8, 3)), rng.random((n, k - 8, 3))], axis=1)
    # (clipped: lo + 1 * (hi - lo) may round beyond hi)
    points = np.clip(lo[:, None, :] + t * (hi - lo)[:, None, :], lo[:, None, :], hi[:, None, :])
    angles = _angles(n)
    det = mechanism.det_a_boxes(lo, hi, angles)
    rows, partials = mechanism.rows_and_partials(lo, hi, angles)
    lengths = [leg.reach(lo, hi).hull for leg in mechanism.rpr_legs]
    gradients = [
        leg.joint_gradient(lo, hi, 0, lengths[i]) for i, leg in enumerate(mechanism.rpr_legs)
    ]
    checked = 0
    for b in range(n):
        for pose in points[b]:
            exact = _exact_rows(mechanism, pose)
            assert _holds(_det(exact), det.lo[b], det.hi[b])
            for i in range(3):
                along_x = partials[i][0]
                boxes = [*rows[i], along_x[0][2], along_x[1][2], along_x[2][2]]
                for value, box in zip(exact[i], boxes, strict=True):
                    assert _holds(value, box.lo[b], box.hi[b])
                # the length: lo^2 <= dx^2 + dy^2 <= hi^2 (lo >= 0)
                square = exact[i][0] ** 2 + exact[i][1] ** 2
                assert Fraction(lengths[i].lo[b]) ** 2 <= square <= Fraction(lengths[i].hi[b]) ** 2
                if square == 0:
                    continue
                # the gradient row / rho: rho between two fractions within 2^-300
                scale = 1 << 300
                root = isqrt(int(square * scale * scale))
                for rho in (Fraction(root, scale), Fraction(root + 1, scale)):
                    for e in range(3):
                        g = gradients[i][e]
                        assert _holds(exact[i][e] / rho, g.lo[b], g.hi[b])
            checked += 1
    assert checked == n * k
