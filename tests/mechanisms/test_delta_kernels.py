"""The Delta's compiled enclosures (mechanisms/_delta_kernels.py) against the
:class:`~moveability.intervals.Interval` code they replace, kept as the
reference (``Delta._det_a_boxes_intervals``).

The kernels repeat the Interval operations' steps box by box, so their bounds
must be the same floats, bit for bit (``np.array_equal``, NaN at the same
places): det A without a posture (the stacked rows and the centres' form) and
with each posture (the mean-value form along the sheet where every leg is
regular). The boxes are of every kind: the whole workspace box, points, thin
(one or two axes of no width), wide and narrow, about a leg's fold surfaces
(``|g| = 1``) and about its axis (``t = 0``, where the direction is singular),
across the cut of arctan2 (the in-plane ``s < 0`` with ``z`` straddling 0), on
signed zeros, far out of reach and huge (overflowing squares). The angle
enclosures are the legs' own (as the sheets take them: a branch's where the
leg is regular, else the hull), random, points, wider than a turn, infinite
and NaN. The designs include the example's, a rod as long as the arm, a
platform wider than the base and a short rod. (test_delta_hostile.py checks
that the enclosures hold det A at sampled configurations.)
"""

from __future__ import annotations

import numpy as np
import pytest

from moveability.intervals import Interval
from moveability.mechanisms.base import REGULAR
from moveability.mechanisms.delta import Delta

DESIGNS = {
    "example": Delta(0.2, 0.05, 0.35, 0.8),
    "default": Delta(10.0, 4.0, 8.0, 15.0),
    # la = lb: la^2 - lb^2 = 0, g's minimum in t on the axis
    "arm-as-rod": Delta(10.0, 4.0, 12.0, 12.0),
    # r > R (the offset positive) and a rod shorter than the arm
    "wide-platform": Delta(3.0, 5.0, 9.0, 7.0),
}


def _same(a: Interval, b: Interval) -> None:
    """The two enclosures are the same floats (NaN at the same places)."""
    assert np.array_equal(a.lo, b.lo, equal_nan=True)
    assert np.array_equal(a.hi, b.hi, equal_nan=True)


def _g(m: Delta, leg: int, p: np.ndarray) -> np.ndarray:
    """``g`` of a leg at poses (floats)."""
    s, d, z = m.delta_legs[leg]._plane(p)
    la, lb = m.arm, m.rod
    with np.errstate(all="ignore"):
        return (s * s + z * z + d * d + la * la - lb * lb) / (2 * la * np.hypot(s, z))


def _boxes(m: Delta, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``n`` boxes of every kind, in random order."""
    rng = np.random.default_rng(seed)
    blo, bhi = m.bounds
    span = bhi - blo
    kinds = rng.integers(0, 12, n)
    centre = blo + rng.random((n, 3)) * span
    width = span * 10.0 ** rng.uniform(-12, 0, (n, 3))
    # mostly narrow boxes: most are regular for every leg, as in a deep tree
    narrow = kinds >= 9
    width[narrow] = span * 10.0 ** rng.uniform(-4, -2, (int(narrow.sum()), 1))
    width[kinds == 0] = span  # the whole box
    width[kinds == 1] = 0.0  # points
    thin = np.flatnonzero(kinds == 2)
    width[thin, rng.integers(0, 3, thin.size)] = 0.0
    width[thin[::2], rng.integers(0, 3, thin[::2].size)] = 0.0
    # about a leg's fold surface: bisect g - 1 (or g + 1) on a segment from the
    # box's centre outwards
    for j in np.flatnonzero(kinds == 3):
        leg = int(rng.integers(0, 3))
        a, b = centre[j].copy(), centre[j] + rng.normal(size=3) * span
        ga, gb = abs(_g(m, leg, a[None])[0]), abs(_g(m, leg, b[None])[0])
        if (ga < 1) != (gb < 1):
            for _ in range(60):
                c = 0.5 * (a + b)
                if (abs(_g(m, leg, c[None])[0]) < 1) == (ga < 1):
                    a = c
                else:
                    b = c
            centre[j] = a
        width[j] *= 1e-3
    # about a leg's axis: s = 0 and z = 0
    for j in np.flatnonzero(kinds == 4):
        leg = m.delta_legs[int(rng.integers(0, 3))]
        ux, uy = leg.unit
        radial = m.base_radius - m.platform_radius
        along = rng.uniform(-1, 1) * span[0]
        centre[j] = [radial * ux - along * uy, radial * uy + along * ux, 0.0]
        width[j] *= 1e-2
    lo, hi = centre - width / 2, centre + width / 2
    # across the cut of arctan2: s < 0, z straddling 0
    for j in np.flatnonzero(kinds == 5):
        leg = m.delta_legs[int(rng.integers(0, 3))]
        ux, uy = leg.unit
        radial = m.base_radius - m.platform_radius - rng.uniform(0.1, 1.0) * span[0]
        c = np.array([radial * ux, radial * uy, 0.0])
        lo[j], hi[j] = c - width[j] / 2, c + width[j] / 2
        lo[j, 2], hi[j, 2] = -rng.uniform(0, 1), rng.choice([0.0, rng.uniform(0, 1)])
    # on signed zeros
    zeros = np.flatnonzero(kinds == 6)
    axis = rng.integers(0, 3, zeros.size)
    lo[zeros, axis] = -0.0
    hi[zeros, axis] = np.maximum(hi[zeros, axis], 0.0)
    # far out of reach, and huge
    far = kinds == 7
    lo[far] = centre[far] * 1e3
    hi[far] = lo[far] + width[far]
    huge = np.flatnonzero(kinds == 8)
    lo[huge] = -(10.0 ** rng.uniform(150, 308, (huge.size, 3)))
    hi[huge] = 10.0 ** rng.uniform(150, 308, (huge.size, 3))
    return lo, hi


def _angles(m: Delta, lo: np.ndarray, hi: np.ndarray, posture: int, seed: int) -> list[Interval]:
    """Angle enclosures of every kind for the legs of ``posture``: as the sheets
    take them (a branch's where the leg is regular, else the hull), random,
    points, wider than a turn, infinite and NaN."""
    rng = np.random.default_rng(seed)
    n = lo.shape[0]
    out = []
    for i, leg in enumerate(m.delta_legs):
        reach = leg.reach(lo, hi)
        branch = reach.branches[int(m.postures[posture][i])]
        regular = reach.status == REGULAR
        a_lo = np.where(regular, branch.lo, reach.hull.lo)
        a_hi = np.where(regular, branch.hi, reach.hull.hi)
        kinds = rng.integers(0, 12, n)  # mostly the legs' own
        t = rng.uniform(-4, 4, n)
        width = 10.0 ** rng.uniform(-12, 0.5, n)
        pick = kinds == 0
        a_lo[pick], a_hi[pick] = t[pick] - width[pick] / 2, t[pick] + width[pick] / 2
        pick = kinds == 1
        a_lo[pick], a_hi[pick] = t[pick], t[pick]
        pick = kinds == 2
        a_lo[pick], a_hi[pick] = t[pick] - 4, t[pick] + 4
        odd = np.flatnonzero(kinds == 3)
        a_lo[odd] = rng.choice([-np.inf, np.nan, 0.0, -0.0], odd.size)
        a_hi[odd] = rng.choice([np.inf, np.nan, np.pi, 0.0], odd.size)
        out.append(Interval(a_lo, a_hi))
    return out


@pytest.mark.parametrize("name", sorted(DESIGNS))
def test_det_a_boxes_bit_for_bit(name: str) -> None:
    m = DESIGNS[name]
    lo, hi = _boxes(m, 700, seed=len(name))
    regular_boxes = 0
    for posture in range(m.postures.shape[0]):
        angles = _angles(m, lo, hi, posture, seed=posture)
        _same(m.det_a_boxes(lo, hi, angles), m._det_a_boxes_intervals(lo, hi, angles))
        got = m.det_a_boxes(lo, hi, angles, posture=posture)
        want = m._det_a_boxes_intervals(lo, hi, angles, posture=posture)
        _same(got, want)
        plain = m._det_a_boxes_intervals(lo, hi, angles)
        regular_boxes += int(((got.lo != plain.lo) | (got.hi != plain.hi)).sum())
    # the mean-value form narrowed many enclosures: its path ran and counted
    assert regular_boxes > 100


def test_det_a_boxes_of_few_boxes_and_other_shapes() -> None:
    m = DESIGNS["example"]
    lo, hi = _boxes(m, 40, seed=3)
    angles = _angles(m, lo, hi, 5, seed=4)
    for k in (0, 1, 2, 17):
        sub = [Interval(a.lo[:k], a.hi[:k]) for a in angles]
        _same(
            m.det_a_boxes(lo[:k], hi[:k], sub, posture=5),
            m._det_a_boxes_intervals(lo[:k], hi[:k], sub, posture=5),
        )
    # one enclosure for every box (broadcast views), and boxes in Fortran order
    n = lo.shape[0]
    one = [Interval(np.broadcast_to(0.3, (n,)), np.broadcast_to(0.4, (n,)))] * 3
    _same(
        m.det_a_boxes(np.asfortranarray(lo), np.asfortranarray(hi), one, posture=2),
        m._det_a_boxes_intervals(lo, hi, one, posture=2),
    )


# ------------------------------------------------------------------ the legs
# mechanisms/_delta_leg_kernels.py against DeltaLeg's Interval code
# (``_reach_intervals``, ``_joint_gradient_intervals``, ``_fold_flow_intervals``)


def _leg_boxes(m: Delta, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The boxes of :func:`_boxes`, and more about the legs' folds (wider: they
    hold both sides), with NaN and infinite coordinates."""
    lo, hi = _boxes(m, 700, seed)
    rng = np.random.default_rng(seed + 100)
    # boxes about the fold surfaces, of widths that certify folds and connect them
    flo, fhi = _boxes(m, 400, seed + 1)
    mid = 0.5 * (flo + fhi)
    span = m.bounds[1] - m.bounds[0]
    half = span * 10.0 ** rng.uniform(-5, -1.5, (400, 1)) / 2
    lo, hi = np.concatenate([lo, mid - half]), np.concatenate([hi, mid + half])
    odd = rng.choice(lo.shape[0], 20, replace=False)
    axis = rng.integers(0, 3, 20)
    lo[odd, axis] = rng.choice([np.nan, -np.inf, 0.0], 20)
    hi[odd, axis] = rng.choice([np.nan, np.inf, 1.0], 20)
    return lo, hi


def _same_reach(got: object, want: object) -> None:
    assert np.array_equal(got.status, want.status)  # type: ignore[attr-defined]
    assert np.array_equal(got.fold_connected, want.fold_connected)  # type: ignore[attr-defined]
    for a, b in zip(got.branches, want.branches, strict=True):  # type: ignore[attr-defined]
        _same(a, b)
    _same(got.hull, want.hull)  # type: ignore[attr-defined]


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # the references' infinities
@pytest.mark.parametrize("name", sorted(DESIGNS))
def test_leg_reach_bit_for_bit(name: str) -> None:
    from moveability.mechanisms.base import FOLD_INNER, FOLD_OUTER, REACH_OUT, REACH_UNKNOWN

    m = DESIGNS[name]
    lo, hi = _leg_boxes(m, seed=len(name))
    seen = np.zeros(5, dtype=int)
    for leg in m.delta_legs:
        got, want = leg.reach(lo, hi), leg._reach_intervals(lo, hi)
        _same_reach(got, want)
        for k, code in enumerate((REGULAR, FOLD_OUTER, FOLD_INNER, REACH_OUT, REACH_UNKNOWN)):
            seen[k] += int((want.status == code).sum())
        folds = (want.status == FOLD_OUTER) | (want.status == FOLD_INNER)
        connected = int((want.fold_connected & folds).sum())
        assert connected > 10
    # every path of the kernels ran: regular, folds of both kinds (a rod no longer
    # than the arm has no inner fold, g > -1), out of reach, unknown
    assert seen[0] > 100 and seen[1] > 10 and seen[3] > 10 and seen[4] > 10
    assert seen[2] > 10 or m.rod <= m.arm


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # the references' infinities
def test_leg_reach_of_few_boxes_and_other_shapes() -> None:
    m = DESIGNS["default"]
    lo, hi = _leg_boxes(m, seed=5)
    leg = m.delta_legs[1]
    for k in (0, 1, 2, 17):
        _same_reach(leg.reach(lo[:k], hi[:k]), leg._reach_intervals(lo[:k], hi[:k]))
    _same_reach(
        leg.reach(np.asfortranarray(lo), np.asfortranarray(hi)), leg._reach_intervals(lo, hi)
    )


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # the references' infinities
@pytest.mark.parametrize("name", sorted(DESIGNS))
def test_joint_gradient_bit_for_bit(name: str) -> None:
    m = DESIGNS[name]
    lo, hi = _leg_boxes(m, seed=len(name) + 7)
    mid = 0.5 * lo + 0.5 * hi
    finite = 0
    for posture in (0, 3, 6):
        angles = _angles(m, lo, hi, posture, seed=posture)
        for i, leg in enumerate(m.delta_legs):
            b = int(m.postures[posture][i])
            got = leg.joint_gradient(lo, hi, b, angles[i])
            want = leg._joint_gradient_intervals(lo, hi, b, angles[i])
            for g, w in zip(got, want, strict=True):
                _same(g, w)
                finite += int((np.isfinite(w.lo) & np.isfinite(w.hi)).sum())
            # at the centres, with the centres of the enclosures (as flows take them)
            centre = Interval(angles[i].mid)
            got = leg.joint_gradient(mid, mid, b, centre)
            want = leg._joint_gradient_intervals(mid, mid, b, centre)
            for g, w in zip(got, want, strict=True):
                _same(g, w)
    assert finite > 1000
    # one enclosure for every box (a broadcast view)
    leg = m.delta_legs[2]
    one = Interval(np.broadcast_to(0.3, (lo.shape[0],)), np.broadcast_to(0.4, (lo.shape[0],)))
    for g, w in zip(
        leg.joint_gradient(lo, hi, 0, one),
        leg._joint_gradient_intervals(lo, hi, 0, one),
        strict=True,
    ):
        _same(g, w)


def _velocities(n: int, seed: int) -> list[list[Interval]]:
    """Velocities of every kind: the axes' unit vectors (one interval for every
    box), random enclosures, points, wide, infinite and NaN."""
    rng = np.random.default_rng(seed)
    out = [[Interval(np.array(float(a == j))) for j in range(3)] for a in range(3)]
    out.append([Interval(np.array(-1.0)), Interval(np.array(0.5)), Interval(np.array(0.25))])
    for _ in range(3):
        v = []
        for _axis in range(3):
            c = rng.normal(size=n)
            w = 10.0 ** rng.uniform(-12, 0.5, n)
            w[rng.random(n) < 0.2] = 0.0
            v_lo, v_hi = c - w / 2, c + w / 2
            odd = rng.random(n) < 0.03
            v_lo[odd] = rng.choice([-np.inf, np.nan, 0.0, -0.0], int(odd.sum()))
            v_hi[odd] = rng.choice([np.inf, np.nan, 0.0, 1.0], int(odd.sum()))
            v.append(Interval(v_lo, v_hi))
        out.append(v)
    return out


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # the references' infinities
@pytest.mark.parametrize("name", sorted(DESIGNS))
def test_fold_flow_bit_for_bit(name: str) -> None:
    m = DESIGNS[name]
    lo, hi = _leg_boxes(m, seed=len(name) + 11)
    n = lo.shape[0]
    kept = 0
    for leg in m.delta_legs:
        status = leg._reach_intervals(lo, hi).status
        for branch in (0, 1):
            cache: dict[str, object] = {}
            reference: dict[str, object] = {}
            for velocity in _velocities(n, seed=branch):
                keeps, rate = leg.fold_flow(lo, hi, status, branch, velocity, cache=cache)
                want_keeps, want_rate = leg._fold_flow_intervals(
                    lo, hi, status, branch, velocity, cache=reference
                )
                _same_fold_flow(keeps, rate, want_keeps, want_rate, status)
                kept += int(keeps.sum())
            # without a cache, and of one box of each kind
            velocity = [Interval(np.array(1.0)), Interval(np.array(0.0)), Interval(-0.5, 0.25)]
            for k in range(5):
                at = np.flatnonzero(status == status[k * 17])[:1]
                keeps, rate = leg.fold_flow(lo[at], hi[at], status[at], branch, velocity)
                want_keeps, want_rate = leg._fold_flow_intervals(
                    lo[at], hi[at], status[at], branch, velocity
                )
                _same_fold_flow(keeps, rate, want_keeps, want_rate, status[at])
    assert kept > 0


def _same_fold_flow(
    keeps: np.ndarray,
    rate: Interval,
    want_keeps: np.ndarray,
    want_rate: Interval,
    status: np.ndarray,
) -> None:
    """The compiled fold flow is the reference's where the leg may fold; elsewhere
    it keeps nothing (as the reference) and its rate is the whole line."""
    from moveability.mechanisms.base import FOLD_INNER, FOLD_OUTER

    folds = (status == FOLD_OUTER) | (status == FOLD_INNER)
    assert np.array_equal(keeps, want_keeps)
    assert not keeps[~folds].any()
    _same(
        Interval(rate.lo[folds], rate.hi[folds]), Interval(want_rate.lo[folds], want_rate.hi[folds])
    )
    assert (rate.lo[~folds] == -np.inf).all() and (rate.hi[~folds] == np.inf).all()


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # the references' infinities
@pytest.mark.parametrize("sheets", [True, False])
@pytest.mark.parametrize("name", sorted(DESIGNS))
def test_det_a_postures_bit_for_bit(
    name: str, sheets: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``det_a_postures``: every posture's enclosure from one pass for all the
    postures (``det_a_all`` and ``mean_value_all``; the one-posture kernels must
    not run), and the reference's, bit for bit, posture by posture: with each
    leg's enclosure on each branch as the sheets take them (the branch's where
    the leg is regular, else the hull), and with enclosures of every kind
    (``sheets`` False: random, points, wider than a turn, infinite, NaN)."""
    from moveability.mechanisms import _delta_kernels

    def forbidden(*args: object) -> None:
        raise AssertionError("a one-posture kernel ran")

    m = DESIGNS[name]
    lo, hi = _leg_boxes(m, seed=len(name) + 3)
    n = lo.shape[0]
    reaches = [leg.reach(lo, hi) for leg in m.delta_legs]
    rng = np.random.default_rng(len(name))
    branch_angles = []
    for r in reaches:
        regular = r.status == REGULAR
        pair = []
        for b in range(2):
            a_lo = np.where(regular, r.branches[b].lo, r.hull.lo)
            a_hi = np.where(regular, r.branches[b].hi, r.hull.hi)
            if not sheets:
                odd = rng.random(n) < 0.3
                t = rng.uniform(-4, 4, n)
                width = np.where(rng.random(n) < 0.2, 0.0, 10.0 ** rng.uniform(-12, 0.8, n))
                a_lo, a_hi = np.where(odd, t, a_lo), np.where(odd, t + width, a_hi)
                bad = np.flatnonzero(rng.random(n) < 0.02)
                a_lo[bad] = rng.choice([-np.inf, np.nan, -0.0], bad.size)
                a_hi[bad] = rng.choice([np.inf, np.nan, 0.0], bad.size)
            pair.append(Interval(a_lo, a_hi))
        branch_angles.append(pair)
    monkeypatch.setattr(_delta_kernels, "det_a_prepare", forbidden)
    monkeypatch.setattr(_delta_kernels, "mean_value_bounds", forbidden)
    got = m.det_a_postures(lo, hi, branch_angles)
    monkeypatch.undo()
    narrowed = 0
    for posture, branches in enumerate(m.postures):
        angles = [branch_angles[i][int(b)] for i, b in enumerate(branches)]
        _same(got[posture], m._det_a_boxes_intervals(lo, hi, angles, posture=posture))
        _same(got[posture], m.det_a_boxes(lo, hi, angles, posture=posture))
        plain = m._det_a_boxes_intervals(lo, hi, angles)
        narrowed += int(((got[posture].lo != plain.lo) | (got[posture].hi != plain.hi)).sum())
    assert narrowed > 100  # the mean-value form ran and narrowed
