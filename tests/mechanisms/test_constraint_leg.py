"""Soundness of ConstraintLeg's certificates, against roots found at sampled poses.

The leg is the five-bar's first leg, ``F = |P - C(t)|^2 - b^2``: at a pose the
roots are known in closed form (``RRLeg.angles``). For random boxes and poses
sampled inside each box: REACH_OUT boxes have no root, REGULAR boxes have the
two roots inside their enclosures with the branch's sign of dF/dq, fold boxes
have their roots in ``hull``, and fold-connected boxes' fold paths end where
the roots meet.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from moveability import intervals as iv
from moveability.intervals import Interval
from moveability.mechanisms.base import FOLD_INNER, FOLD_OUTER, REACH_OUT, REGULAR
from moveability.mechanisms.constraint_leg import ConstraintLeg
from moveability.mechanisms.expressions import cos, sin
from moveability.mechanisms.rr_leg import RRLeg

A, B = 8.0, 5.0


def five_bar_leg(a: float = A, b: float = B) -> ConstraintLeg:
    return ConstraintLeg(
        "t1",
        f=lambda x, y, t: (x - a * cos(t)) ** 2 + (y - a * sin(t)) ** 2 - b * b,
        df_dq=lambda x, y, t: 2 * a * (x * sin(t) - y * cos(t)),
        d2f_dq2=lambda x, y, t: 2 * a * (x * cos(t) + y * sin(t)),
        df_dx=(lambda x, y, t: 2 * (x - a * cos(t)), lambda x, y, t: 2 * (y - a * sin(t))),
    )


def actuator_leg() -> ConstraintLeg:
    """A linear actuator from the origin: F = x^2 + y^2 - q^2, stroke [5, 10]."""
    return ConstraintLeg(
        "d",
        f=lambda x, y, q: x * x + y * y - q**2,
        df_dq=lambda x, y, q: -2 * q,
        d2f_dq2=lambda x, y, q: -2 + 0 * q,
        df_dx=(lambda x, y, q: 2 * x + 0 * q, lambda x, y, q: 2 * y + 0 * q),
        prismatic=True,
        stroke=(5.0, 10.0),
    )


def _square_boxes(rng, radius, theta, exponents):
    """Square boxes centred at the polar points (radius, theta), their half-widths
    10^u with u uniform in ``exponents``."""
    centre = np.stack([radius * np.cos(theta), radius * np.sin(theta)], axis=1)
    half = 10.0 ** rng.uniform(*exponents, (radius.size, 1)) * np.ones((1, 2))
    return centre - half, centre + half


def _in(enclosure_lo, enclosure_hi, q, tol=1e-9):
    """Whether angle q lies in [lo, hi] modulo 2 pi."""
    k = np.floor((q - enclosure_lo) / (2 * np.pi))
    q = q - 2 * np.pi * k
    return (q >= enclosure_lo - tol) & (q <= enclosure_hi + tol)


@pytest.mark.parametrize(("a", "b"), [(8.0, 5.0), (5.0, 8.0), (6.0, 6.0)])
def test_reach_is_sound(a, b):
    rng = np.random.default_rng(1)
    leg, ref = five_bar_leg(a, b), RRLeg((0.0, 0.0), a, b, "t1")
    n, per = 1500, 10
    centre = rng.uniform(-(a + b) - 1, a + b + 1, (n, 2))
    half = rng.uniform(0.01, 0.6, (n, 2))
    lo, hi = centre - half, centre + half
    reach = leg.reach(lo, hi)
    u = rng.uniform(0, 1, (n, per, 2))
    u[:, 0] = 0.0  # the corners too
    u[:, 1] = 1.0
    points = lo[:, None, :] + u * (hi - lo)[:, None, :]
    q = ref.angles(points.reshape(-1, 2)).reshape(n, per, 2)
    reachable = np.isfinite(q).all(axis=2)
    assert not reachable[reach.status == REACH_OUT].any()
    regular = reach.status == REGULAR
    assert reachable[regular].all()
    for branch in (0, 1):
        lo_b = reach.branches[branch].lo[:, None]
        hi_b = reach.branches[branch].hi[:, None]
        # the closed form's roots, matched to the branch by the sign of dF/dq
        d = leg.serial_term(points.reshape(-1, 2), q[:, :, branch].reshape(-1)).reshape(n, per)
        sign = np.sign(d)
        ok = _in(lo_b, hi_b, q[:, :, branch])
        want = 1.0 if branch == 0 else -1.0
        assert ok[regular].all()
        assert (sign[regular] == want).all()
    fold = (reach.status == FOLD_OUTER) | (reach.status == FOLD_INNER)
    for branch in (0, 1):
        qq = q[:, :, branch]
        inside = _in(reach.hull.lo[:, None], reach.hull.hi[:, None], qq)
        assert inside[fold & reachable.any(axis=1)][reachable[fold & reachable.any(axis=1)]].all()
    # the statuses are not vacuous
    assert regular.sum() > 250 and (reach.status == REACH_OUT).sum() > 100 and fold.sum() > 25
    assert reach.fold_connected.sum() > 15
    assert not reach.fold_connected[~fold].any()


@pytest.mark.parametrize(
    ("a", "b", "margin"), [(8.0, 5.0, 0.01), (5.0, 8.0, 0.01), (6.0, 6.0, 0.1)]
)
def test_reach_decides_boxes_clear_of_the_folds(a, b, margin):
    """Boxes farther than ``margin`` from both folds (the circles of radii
    ``|a - b|`` and ``a + b`` about the base) are decided: REACH_OUT beyond them,
    REGULAR between them. A box just beyond the reach keeps a run where ``F``'s
    enclosures over wide monotone pieces hold 0; ``F`` at the run's ends shows
    it holds no root."""
    rng = np.random.default_rng(2)
    n = 8000
    half = rng.uniform(0.001, 0.1, (n, 1)) * np.ones((1, 2))
    r = rng.uniform(0.0, a + b + 2.0, n)
    theta = rng.uniform(-np.pi, np.pi, n)
    centre = np.stack([r * np.cos(theta), r * np.sin(theta)], axis=1)
    lo, hi = centre - half, centre + half
    status = five_bar_leg(a, b).reach(lo, hi).status
    near = np.hypot(np.clip(0.0, lo[:, 0], hi[:, 0]), np.clip(0.0, lo[:, 1], hi[:, 1]))
    far = np.hypot(np.maximum(-lo[:, 0], hi[:, 0]), np.maximum(-lo[:, 1], hi[:, 1]))
    out = (near > a + b + margin) | (far < abs(a - b) - margin)
    inside = (near > abs(a - b) + margin) & (far < a + b - margin)
    assert out.sum() > 500 and inside.sum() > 2000
    assert (status[out] == REACH_OUT).all()
    assert (status[inside] == REGULAR).all()


@pytest.mark.parametrize(("a", "b"), [(8.0, 5.0), (5.0, 8.0), (6.0, 6.0), (8.0, 7.99)])
def test_fold_boxes_hold_a_corner_on_each_side_of_the_reach(a, b):
    """A fold certificate says one corner of the box is reachable and another is
    beyond the reach (over a monotone piece the latter is tested at the piece's
    ends): both are checked against the closed form, on boxes about the two
    folds, of every size down to a ten-thousandth."""
    rng = np.random.default_rng(4)
    leg, ref = five_bar_leg(a, b), RRLeg((0.0, 0.0), a, b, "t1")
    n = 3000
    theta = rng.uniform(-np.pi, np.pi, n)
    radius = np.where(rng.uniform(size=n) < 0.5, a + b, abs(a - b)) + rng.uniform(-0.1, 0.1, n)
    lo, hi = _square_boxes(rng, radius, theta, (-4, -0.5))
    status = leg.reach(lo, hi).status
    fold = np.flatnonzero((status == FOLD_OUTER) | (status == FOLD_INNER))
    assert fold.size > 300
    corners = np.stack(
        [np.where([(c >> j) & 1 for j in range(2)], hi[fold], lo[fold]) for c in range(4)], axis=1
    )
    reached = np.isfinite(ref.angles(corners.reshape(-1, 2))).all(axis=1).reshape(-1, 4)
    assert reached.any(axis=1).all()
    assert (~reached).any(axis=1).all()


@pytest.mark.parametrize(("a", "b"), [(8.0, 5.0), (5.0, 8.0), (6.0, 6.0), (8.0, 7.99)])
def test_fold_hulls_hold_every_root_and_are_tight(a, b):
    """The hull of a box with one run holds the roots of every pose of the box
    (sampled: corners, edges and inside) and is moved in from its run's wide
    end pieces: its width is within a small multiple of the roots' spread.
    Boxes about both folds, many across the cut of the circle at pi, of every
    size down to a ten-thousandth."""
    rng = np.random.default_rng(9)
    leg, ref = five_bar_leg(a, b), RRLeg((0.0, 0.0), a, b, "t1")
    n = 4000
    # directions about pi too: the hull of a run across the circle's cut
    theta = np.where(rng.uniform(size=n) < 0.4, np.pi + rng.normal(0.0, 0.05, n),
                     rng.uniform(-np.pi, np.pi, n))  # fmt: skip
    radius = np.where(rng.uniform(size=n) < 0.5, a + b, abs(a - b)) + rng.uniform(-0.05, 0.05, n)
    lo, hi = _square_boxes(rng, radius, theta, (-4, -1))
    reach = leg.reach(lo, hi)
    one = np.flatnonzero(np.isfinite(reach.hull.lo) & np.isfinite(reach.hull.hi))
    assert one.size > 1000
    per = 40
    u = rng.uniform(0.0, 1.0, (one.size, per, 2))
    u[:, :4] = [[0, 0], [0, 1], [1, 0], [1, 1]]  # the corners
    u[:, 4:8, 0] = np.round(u[:, 4:8, 0])  # and the edges
    points = lo[one, None, :] + u * (hi - lo)[one, None, :]
    q = ref.angles(points.reshape(-1, 2)).reshape(one.size, per, 2)
    h_lo, h_hi = reach.hull.lo[one, None], reach.hull.hi[one, None]
    for branch in (0, 1):
        qq = q[:, :, branch]
        found = np.isfinite(qq)
        assert _in(h_lo, h_hi, qq, tol=0.0)[found].all()
    # tight: beyond the extreme sampled roots the hull reaches a small part of
    # one of the isolation's first pieces (a run's end piece, monotone, is
    # bisected): without that, most hulls reach past them by half a piece or more
    excess = []
    for i in np.flatnonzero(np.isfinite(q).any(axis=(1, 2))):
        roots = q[i][np.isfinite(q[i])]
        roots = h_lo[i, 0] + np.mod(roots - h_lo[i, 0], 2 * np.pi)  # in the hull's turn
        excess.append(max(roots.min() - h_lo[i, 0], h_hi[i, 0] - roots.max()))
    excess = np.array(excess) / (2 * np.pi / leg.pieces)
    assert excess.size > 800
    assert np.median(excess) < 0.1
    if abs(a - b) > 1.0:  # the folds clear of the base: tight everywhere
        assert np.quantile(excess, 0.99) < 0.01


def test_contraction_ends_within_its_tolerance_of_the_roots_spread():
    """The branch enclosures of regular boxes hold every root, and each bound is
    within ``rtol`` (2^-10) of the enclosure's width of the extreme root: for this
    leg ``F`` at a joint value is exact over a box (each coordinate appears once),
    so the certifiable bounds are the roots' extremes, here sampled densely on
    the box's boundary (where they lie: the roots have no critical point inside
    a regular box)."""
    rng = np.random.default_rng(6)
    leg, ref = five_bar_leg(), RRLeg((0.0, 0.0), A, B, "t1")
    n = 300
    radius = rng.uniform(4.0, 12.0, n)
    theta = rng.uniform(-np.pi, np.pi, n)
    centre = np.stack([radius * np.cos(theta), radius * np.sin(theta)], axis=1)
    half = 10.0 ** rng.uniform(-3, -1, (n, 1)) * np.ones((1, 2))
    lo, hi = centre - half, centre + half
    reach = leg.reach(lo, hi)
    regular = np.flatnonzero(reach.status == REGULAR)
    assert regular.size > 250
    t = np.linspace(0.0, 1.0, 801)
    for i in regular:
        x0, y0 = lo[i]
        x1, y1 = hi[i]
        edge = np.concatenate([
            np.stack([x0 + t * (x1 - x0), np.full_like(t, y0)], 1),
            np.stack([x0 + t * (x1 - x0), np.full_like(t, y1)], 1),
            np.stack([np.full_like(t, x0), y0 + t * (y1 - y0)], 1),
            np.stack([np.full_like(t, x1), y0 + t * (y1 - y0)], 1),
        ])  # fmt: skip
        roots = ref.angles(edge)
        for b in range(2):
            enclosure = reach.branches[b][i]
            lo_b, hi_b = float(enclosure.lo), float(enclosure.hi)
            # the roots unwrapped next to the enclosure
            turns = np.round((0.5 * (lo_b + hi_b) - roots[:, b]) / (2 * np.pi))
            q = roots[:, b] + 2 * np.pi * turns
            width = hi_b - lo_b
            assert lo_b <= q.min() + 1e-12 and q.max() <= hi_b + 1e-12
            slack = 2.0**-10 * width + 1e-9 * (q.max() - q.min()) + 1e-12
            assert q.min() - lo_b <= slack
            assert hi_b - q.max() <= slack


def test_fold_connected_boxes_hold_both_sides_and_a_fold_path():
    rng = np.random.default_rng(2)
    leg, ref = five_bar_leg(), RRLeg((0.0, 0.0), A, B, "t1")
    theta = rng.uniform(-np.pi, np.pi, 400)
    radius = np.where(rng.uniform(size=400) < 0.5, A + B, A - B) + rng.uniform(-0.2, 0.2, 400)
    centre = np.stack([radius * np.cos(theta), radius * np.sin(theta)], axis=1)
    half = rng.uniform(0.05, 0.4, (400, 1))
    lo, hi = centre - half, centre + half
    reach = leg.reach(lo, hi)
    boxes = np.flatnonzero(reach.fold_connected)
    assert boxes.size > 100
    for i in boxes:
        grid = np.stack(
            np.meshgrid(*[np.linspace(lo[i, j], hi[i, j], 15) for j in range(2)]), -1
        ).reshape(-1, 2)
        ok = np.isfinite(ref.angles(grid)).all(axis=1)
        assert ok.any() and not ok.all()
        for pose in grid[ok][[0, -1]]:
            path = leg.fold_path(lo[i], hi[i], pose)
            assert np.allclose(path[0], pose)
            assert ((path >= lo[i] - 1e-12) & (path <= hi[i] + 1e-12)).all()
            # along the path every pose is reachable; at its end the roots meet
            t = np.linspace(0, 1, 50)[:, None]
            for a, b in itertools.pairwise(path):
                q = ref.angles(a + t * (b - a), clip=True)
                assert np.isfinite(q).all()
            gap = np.abs(np.angle(np.exp(1j * (q[-1, 0] - q[-1, 1]))))
            assert gap < 1e-3


def test_angles_match_closed_form_and_points_are_labelled_by_serial_sign():
    rng = np.random.default_rng(3)
    leg, ref = five_bar_leg(), RRLeg((0.0, 0.0), A, B, "t1")
    p = rng.uniform(-14, 14, (2000, 2))
    q, q_ref = leg.angles(p), ref.angles(p)
    assert (np.isfinite(q) == np.isfinite(q_ref)).all()
    ok = np.isfinite(q_ref)
    assert np.abs(np.angle(np.exp(1j * (q[ok] - q_ref[ok])))).max() < 1e-9
    # the five-bar's branch 0 (theta + alpha) is where dF/dq > 0
    both = ok.all(axis=1)
    assert (leg.serial_term(p[both], q[both, 0]) > 0).all()
    assert np.abs(leg.constraint(p[both], q[both, 0])).max() < 1e-9


def test_point_boxes_near_the_fold_and_clip():
    leg = five_bar_leg()
    inside = np.array([[A + B - 1e-9, 0.0], [0.0, A - B + 1e-9]])
    q = leg.angles(inside)
    assert np.isfinite(q).all()
    beyond = np.array([[A + B + 1e-13, 0.0]])
    assert np.isnan(leg.angles(beyond)).all()
    assert np.isfinite(leg.angles(beyond, clip=True)).all()


def test_prismatic_leg_with_one_root_in_its_stroke():
    leg = actuator_leg()
    lo = np.array([[6.0, 0.0], [20.0, 0.0]])
    hi = np.array([[6.5, 0.5], [21.0, 1.0]])
    reach = leg.reach(lo, hi)
    assert reach.status.tolist() == [REGULAR, REACH_OUT]
    q = np.hypot(6.2, 0.3)
    assert reach.branches[1].contains(q)[0]
    # no root of positive dF/dq (q < 0) in the widened stroke: enclosed beyond it
    assert reach.branches[0].lo[0] > 12.5
    assert np.allclose(leg.angles(np.array([[6.2, 0.3]]))[0, 1], q)


def test_prismatic_hulls_hold_the_root():
    """A prismatic leg's cells of one run (F = x^2 + y^2 - q^2, stroke [5, 10],
    searched over [3.75, 11.25]): the hull holds the root q = |P| of every
    sampled pose, also where the run meets the end of the search range."""
    leg = actuator_leg()
    rng = np.random.default_rng(12)
    n = 3000
    theta = rng.uniform(-np.pi, np.pi, n)
    radius = rng.choice([3.75, 11.25, 7.0], n) + rng.normal(0.0, 0.3, n)
    lo, hi = _square_boxes(rng, radius, theta, (-4, -0.5))
    reach = leg.reach(lo, hi)
    one = np.flatnonzero(np.isfinite(reach.hull.lo) & np.isfinite(reach.hull.hi))
    assert one.size > 100
    u = rng.uniform(0.0, 1.0, (one.size, 30, 2))
    u[:, :4] = [[0, 0], [0, 1], [1, 0], [1, 1]]
    root = np.hypot(*np.moveaxis(lo[one, None, :] + u * (hi - lo)[one, None, :], -1, 0))
    inside = (root >= 3.75) & (root <= 11.25)
    held = (root >= reach.hull.lo[one, None]) & (root <= reach.hull.hi[one, None])
    assert held[inside].all()


@settings(deadline=None, max_examples=60)
@given(
    st.floats(-12, 12),
    st.floats(-12, 12),
    st.floats(0.001, 1.0),
    st.floats(0.001, 1.0),
)
@example(0.0, 1.1125369292536007e-308, 1.0, 1.0)  # a corner next to the base
def test_reach_property(cx, cy, wx, wy):
    leg, ref = five_bar_leg(), RRLeg((0.0, 0.0), A, B, "t1")
    lo, hi = np.array([[cx, cy]]), np.array([[cx + wx, cy + wy]])
    reach = leg.reach(lo, hi)
    corners = np.array([[cx, cy], [cx + wx, cy], [cx, cy + wy], [cx + wx, cy + wy]])
    q = ref.angles(np.vstack([corners, 0.5 * (lo + hi)]))
    if reach.status[0] == REACH_OUT:
        assert np.isnan(q).all()
    if reach.status[0] == REGULAR:
        for b in (0, 1):
            assert _in(reach.branches[b].lo[0], reach.branches[b].hi[0], q[:, b]).all()


def test_guarded_expressions_never_certify_across_a_pole():
    # F = tan(q) - x has a root on each branch of tan; the pieces across the poles
    # must not be certified monotone (tan jumps there)
    from moveability.mechanisms.expressions import tan

    leg = ConstraintLeg(
        "q",
        f=lambda x, q: tan(q) - x,
        df_dq=lambda x, q: 1 + tan(q) ** 2,
        d2f_dq2=lambda x, q: 2 * tan(q) * (1 + tan(q) ** 2),
        df_dx=(lambda x, q: -1 + 0 * q,),
    )
    reach = leg.reach(np.array([[0.2]]), np.array([[0.3]]))
    # two roots, both with dF/dq > 0: not a regular leg
    assert reach.status[0] != REGULAR
    assert iv.tan(Interval(1.5, 1.6)).hi == np.inf


@pytest.mark.parametrize(
    "source", ["five-bar-custom.toml", "delta-custom.toml", "three-rrr.toml"]
)
def test_run_ends_from_the_isolation_are_those_evaluated(source):
    """``F`` at the runs' starts and ends (``_run_ends``), taken from the compiled
    isolation's end tests where it made them, equals ``F`` evaluated there bit for
    bit (one turn on at the end of a run across the circle's cut), and most of
    them come from the isolation."""
    from pathlib import Path

    from moveability import load_spec
    from moveability.mechanisms import expressions as ex
    from moveability.mechanisms import from_spec

    examples = Path(__file__).resolve().parents[2] / "examples"
    mechanism = from_spec(load_spec(examples / source))
    rng = np.random.default_rng(21)
    low, high = (np.asarray(b, dtype=float) for b in mechanism.bounds)
    span = high - low
    width = span * rng.choice([0.0, 1 / 400, 1 / 60, 1 / 8], (3000, 1))
    lo = low + (span - width) * rng.random((3000, low.size))
    hi = lo + width
    wrapped = reused = total = 0
    for leg in mechanism.legs:
        runs = leg._runs(leg._root_pieces(lo, hi), lo.shape[0])
        f_start, f_end = leg._run_ends(lo, hi, runs)
        start = leg._box_eval(leg.f, lo, hi, runs.box, ex.points(runs.start))
        end = leg._box_eval(leg.f, lo, hi, runs.box, runs.end)
        for got, want in ((f_start, start), (f_end, end)):
            assert np.array_equal(got.lo, want.lo, equal_nan=True)
            assert np.array_equal(got.hi, want.hi, equal_nan=True)
        wrapped += int((runs.end.hi > np.pi).sum())
        # the runs whose first piece the isolation tested
        pieces = runs.pieces
        keys = zip(pieces.box.tolist(), pieces.lo.tolist(), strict=True)
        where = {key: i for i, key in enumerate(keys)}
        first = [where[key] for key in zip(runs.box.tolist(), runs.start.tolist(), strict=True)]
        reused += int(pieces.tested[first].sum())
        total += runs.box.size
    assert wrapped > 0  # runs across the cut among them
    assert reused > total // 4


@pytest.mark.parametrize("name", ["five-bar-custom.toml", "three-rrr.toml", "delta-custom.toml"])
def test_reach_over_no_box(name):
    """No box: empty statuses, branches, hull and fold certificates, for every leg
    (the isolation is not run)."""
    from moveability import load_spec
    from moveability.mechanisms import from_spec

    m = from_spec(load_spec(Path(__file__).resolve().parents[2] / "examples" / name))
    k = len(m.pose_names)
    for leg in m.legs:
        for options in ({}, {"folds": False}, {"branches": False}):
            reach = leg.reach(np.zeros((0, k)), np.zeros((0, k)), **options)
            assert reach.status.shape == (0,) and reach.fold_connected.shape == (0,)
            assert reach.hull.lo.shape == (0,)
            assert all(b.lo.shape == (0,) and b.hi.shape == (0,) for b in reach.branches)
