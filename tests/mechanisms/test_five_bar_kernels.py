"""The five-bar's compiled enclosures (mechanisms/_rr_kernels.py) against the
:class:`~moveability.intervals.Interval` code they replace, kept as the
reference (``FiveBar._det_a_boxes_intervals``, ``RRLeg._reach_intervals``,
``_knee_boxes_intervals``, ``_fold_flow_intervals``).

The kernels repeat the Interval operations' steps box by box, so their bounds
must be the same floats, bit for bit (``np.array_equal``, NaN at the same
places): det A with and without a posture (the branch forms intersected), the
elbows over angle enclosures, the legs' reach (codes, branches, hull, whether
the folds connect) and fold flows. The boxes are of every kind: wide and
whole, points, thin, around the legs' fold circles and their bases, across the
cut of arctan2 behind a base, out of reach, on signed zeros; the angle
enclosures are the legs' own (infinite where the reach is unknown), random,
wider than a turn, infinite and NaN. The designs include the paper's, equal
links (the inner fold circle shrunk to the base), a leg that just reaches the
other base, and unequal legs. The enclosures are also checked to hold det A at
points sampled in the boxes.
"""

from __future__ import annotations

import numpy as np
import pytest

from moveability.intervals import Interval
from moveability.limits import JointLimit
from moveability.mechanisms import FiveBar
from moveability.mechanisms.base import REGULAR

HALF_TURN = (JointLimit(0.0, np.pi), JointLimit(0.0, np.pi))
DESIGNS = {
    "paper": FiveBar(7, 8, 5, 8, 5, HALF_TURN),
    # equal links: the inner fold circle is the base itself
    "equal-links": FiveBar(5, 6, 6, 6, 6, HALF_TURN),
    # the leg at A just reaches the base B, and the one at B just reaches A
    "just-reaches": FiveBar(
        13, 8, 5, 8, 5, (JointLimit(-np.pi / 2, np.pi / 2), JointLimit(0.0, np.pi))
    ),
    # unequal legs; limits at the singular angles 0 and pi
    "unequal": FiveBar(4, 3, 9, 7, 2.5, (JointLimit(0.0, np.pi), JointLimit(-np.pi, 0.0))),
}


def _same(a: Interval, b: Interval) -> None:
    """The two enclosures are the same floats (NaN at the same places)."""
    assert np.array_equal(a.lo, b.lo, equal_nan=True)
    assert np.array_equal(a.hi, b.hi, equal_nan=True)


def _boxes(m: FiveBar, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``n`` boxes of every kind, in random order."""
    rng = np.random.default_rng(seed)
    blo, bhi = m.bounds
    span = bhi - blo
    kinds = rng.integers(0, 9, n)
    centre = blo + rng.random((n, 2)) * span
    width = span * 10.0 ** rng.uniform(-12, 0, (n, 2))
    width[kinds == 0] = span  # the whole box
    width[kinds == 1] = 0.0  # points
    thin = np.flatnonzero(kinds == 2)
    width[thin, rng.integers(0, 2, thin.size)] = 0.0
    # about a leg's fold circles (outer, inner) or its base
    legs = m.rr_legs
    for kind, outer in ((3, True), (4, False)):
        at = np.flatnonzero(kinds == kind)
        for j in at:
            leg = legs[rng.integers(0, 2)]
            radius = leg.proximal + leg.distal if outer else abs(leg.proximal - leg.distal)
            t = rng.uniform(-np.pi, np.pi)
            centre[j] = np.asarray(leg.base) + radius * np.array([np.cos(t), np.sin(t)])
        width[at] *= 1e-3
    base = np.flatnonzero(kinds == 5)
    for j in base:
        centre[j] = legs[rng.integers(0, 2)].base
    lo, hi = centre - width / 2, centre + width / 2
    # behind a base, across the cut of arctan2 (y straddling the base's)
    cut = np.flatnonzero(kinds == 6)
    for j in cut:
        leg = legs[rng.integers(0, 2)]
        lo[j, 0] = leg.base[0] - rng.uniform(0.5, 3)
        hi[j, 0] = rng.choice([leg.base[0] - 0.1, leg.base[0]])
        lo[j, 1], hi[j, 1] = -rng.uniform(0, 1), rng.choice([0.0, rng.uniform(0, 1)])
    # on signed zeros
    zeros = np.flatnonzero(kinds == 7)
    axis = rng.integers(0, 2, zeros.size)
    lo[zeros, axis] = -0.0
    hi[zeros, axis] = np.maximum(hi[zeros, axis], 0.0)
    # out of reach, far away
    far = kinds == 8
    lo[far] = centre[far] * 1e3
    hi[far] = lo[far] + width[far]
    return lo, hi


def _angles(reach, n: int, rng: np.random.Generator) -> list[Interval]:
    """Angle enclosures of every kind: a branch's, the hull (infinite where the
    reach is unknown), random, wider than a turn, points, infinite and NaN."""
    kinds = rng.integers(0, 7, n)
    t = rng.uniform(-4, 4, n)
    width = 10.0 ** rng.uniform(-12, 0.5, n)
    lo, hi = t - width / 2, t + width / 2
    for k, source in enumerate((reach.branches[0], reach.branches[1], reach.hull)):
        lo[kinds == k], hi[kinds == k] = source.lo[kinds == k], source.hi[kinds == k]
    lo[kinds == 3], hi[kinds == 3] = t[kinds == 3], t[kinds == 3]
    lo[kinds == 4], hi[kinds == 4] = t[kinds == 4] - 4, t[kinds == 4] + 4
    odd = np.flatnonzero(kinds == 5)
    lo[odd] = rng.choice([-np.inf, np.nan, 0.0], odd.size)
    hi[odd] = rng.choice([np.inf, np.nan, np.pi], odd.size)
    return [Interval(lo, hi)]


@pytest.mark.parametrize("name", sorted(DESIGNS))
def test_reach_and_knees_bit_for_bit(name: str) -> None:
    m = DESIGNS[name]
    lo, hi = _boxes(m, 1501, seed=len(name))
    rng = np.random.default_rng(7)
    kinds = set()
    for leg in m.rr_legs:
        got, want = leg.reach(lo, hi), leg._reach_intervals(lo, hi)
        assert np.array_equal(got.status, want.status)
        assert np.array_equal(got.fold_connected, want.fold_connected)
        for a, b in zip([*got.branches, got.hull], [*want.branches, want.hull], strict=True):
            _same(a, b)
        kinds |= set(np.unique(want.status).tolist())
        (angles,) = _angles(want, lo.shape[0], rng)
        for a, b in zip(leg.knee_boxes(angles), leg._knee_boxes_intervals(angles), strict=True):
            _same(a[0], b[0])
            _same(a[1], b[1])
        # a single box and an enclosure of another shape (a number)
        number = Interval(np.float64(0.25), np.float64(0.5))
        _same(leg.knee_boxes(number)[0][0], leg._knee_boxes_intervals(number)[0][0])
        _same(leg.reach(lo[:1], hi[:1]).hull, leg._reach_intervals(lo[:1], hi[:1]).hull)
    # the boxes met every reach code: regular, both folds, out of reach, unknown
    assert len(kinds) >= 4


@pytest.mark.parametrize("name", sorted(DESIGNS))
def test_det_a_bit_for_bit(name: str) -> None:
    m = DESIGNS[name]
    lo, hi = _boxes(m, 1501, seed=10 + len(name))
    rng = np.random.default_rng(11)
    reaches = [leg._reach_intervals(lo, hi) for leg in m.rr_legs]
    angles = [_angles(r, lo.shape[0], rng)[0] for r in reaches]
    for posture in (None, 0, 1, 2, 3):
        got = m.det_a_boxes(lo, hi, angles, posture)
        want = m._det_a_boxes_intervals(lo, hi, angles, posture)
        _same(got, want)
    # the branch forms narrowed some enclosures
    natural = m._det_a_boxes_intervals(lo, hi, angles)
    assert (want.hi - want.lo < natural.hi - natural.lo).any()
    # the legs' own enclosures, as the analysis gives them; one box
    for p, branches in enumerate(m.postures):
        own = [r.branches[int(b)] for r, b in zip(reaches, branches, strict=True)]
        _same(m.det_a_boxes(lo, hi, own, p), m._det_a_boxes_intervals(lo, hi, own, p))
        first = [a[:1] for a in own]
        _same(
            m.det_a_boxes(lo[:1], hi[:1], first, p),
            m._det_a_boxes_intervals(lo[:1], hi[:1], first, p),
        )


@pytest.mark.parametrize("name", sorted(DESIGNS))
def test_det_a_postures_bit_for_bit(name: str) -> None:
    """Every posture at once: each one's bounds as the Interval reference gives them
    with that posture's enclosures (random ones per leg and branch, of every kind)."""
    m = DESIGNS[name]
    lo, hi = _boxes(m, 1501, seed=30 + len(name))
    rng = np.random.default_rng(31)
    reaches = [leg._reach_intervals(lo, hi) for leg in m.rr_legs]
    branch_angles = [[_angles(r, lo.shape[0], rng)[0] for _ in range(2)] for r in reaches]
    every = m.det_a_postures(lo, hi, branch_angles)
    assert len(every) == 4
    for p, branches in enumerate(m.postures):
        own = [branch_angles[i][int(b)] for i, b in enumerate(branches)]
        _same(every[p], m._det_a_boxes_intervals(lo, hi, own, p))
    # the legs' own branches; one box; a leg without one branch's enclosure (the
    # one-call-per-posture path reports it)
    own = [list(r.branches) for r in reaches]
    for p, det in enumerate(m.det_a_postures(lo[:1], hi[:1], [[a[:1] for a in b] for b in own])):
        first = [own[i][int(b)][:1] for i, b in enumerate(m.postures[p])]
        _same(det, m._det_a_boxes_intervals(lo[:1], hi[:1], first, p))
    with pytest.raises(ValueError, match="branch_angles"):
        m.det_a_postures(lo, hi, [own[0], [own[1][0], None]])


@pytest.mark.parametrize("name", sorted(DESIGNS))
def test_fold_flow_bit_for_bit(name: str) -> None:
    m = DESIGNS[name]
    lo, hi = _boxes(m, 1001, seed=20 + len(name))
    rng = np.random.default_rng(21)
    n = lo.shape[0]
    a, b = rng.normal(size=(2, 2, n)) * 10.0 ** rng.uniform(-3, 2, (2, 1, n))
    velocities = [
        [Interval(np.minimum(a[k], b[k]), np.maximum(a[k], b[k])) for k in range(2)],
        [Interval(a[0]), Interval(b[1])],  # points
        [Interval(np.float64(1.0)), Interval(np.float64(-0.5))],  # one for every box
        [Interval(np.zeros(n)), Interval(np.full(n, -np.inf), np.full(n, np.inf))],
    ]
    for leg in m.rr_legs:
        status = leg._reach_intervals(lo, hi).status
        for branch in (0, 1):
            cache, ref_cache = {}, {}
            for velocity in velocities:
                keeps, rate = leg.fold_flow(lo, hi, status, branch, velocity, cache=cache)
                want_keeps, want = leg._fold_flow_intervals(
                    lo, hi, status, branch, velocity, cache=ref_cache
                )
                assert np.array_equal(keeps, want_keeps)
                _same(rate, want)
            assert "fold_compiled" in cache


@pytest.mark.parametrize("name", sorted(DESIGNS))
def test_det_a_holds_the_exact_values(name: str) -> None:
    m = DESIGNS[name]
    rng = np.random.default_rng(30)
    blo, bhi = m.bounds
    centre = blo + rng.random((400, 2)) * (bhi - blo)
    width = (bhi - blo) * 10.0 ** rng.uniform(-6, -1, (400, 1))
    lo, hi = centre - width / 2, centre + width / 2
    reaches = [leg.reach(lo, hi) for leg in m.rr_legs]
    regular = (reaches[0].status == REGULAR) & (reaches[1].status == REGULAR)
    assert regular.sum() > 50
    points = lo + rng.random((400, 2)) * (hi - lo)
    q = m.joint_angles(points)  # (points, postures, legs)
    for p, branches in enumerate(m.postures):
        angles = [r.branches[int(b)] for r, b in zip(reaches, branches, strict=True)]
        det = m.det_a_boxes(lo, hi, angles, p)
        exact = m.det_a(points, q[:, p])
        ok = regular & np.isfinite(exact)
        assert ((det.lo[ok] <= exact[ok]) & (exact[ok] <= det.hi[ok])).all()
