"""Soundness of the sheet certificates against sampled points (closed-form postures)."""

import numpy as np
import pytest

from moveability.analysis.sheets import classify_sheets
from moveability.hypertree.status import IN, OUT
from moveability.limits import JointLimit
from moveability.mechanisms import FiveBar
from moveability.mechanisms.base import FOLD_INNER, FOLD_OUTER, REACH_OUT, REGULAR

DESIGNS = [
    ((7, 8, 5, 8, 5), (0.0, np.pi), (0.0, np.pi)),
    ((7, 8, 5, 8, 5), (-np.pi, np.pi), None),
    ((6, 5, 7, 5, 7), (-np.pi / 2, np.pi), (0.0, 1.5 * np.pi)),
    ((3, 4, 4, 5, 3), None, (-2.0, 2.5)),
]


def _mechanism(lengths, lim1, lim2):
    limits = tuple(
        JointLimit.unlimited() if lim is None else JointLimit(*lim) for lim in (lim1, lim2)
    )
    return FiveBar(*lengths, limits=limits)


def _random_boxes(rng, mechanism, n, size):
    lo_b, hi_b = mechanism.bounds
    width = rng.uniform(0.02, size, (n, 2))
    lo = rng.uniform(lo_b, hi_b - width, (n, 2))
    return lo, lo + width


@pytest.mark.parametrize("design", DESIGNS)
def test_certificates_hold_at_sampled_points(design):
    m = _mechanism(*design)
    rng = np.random.default_rng(7)
    lo, hi = _random_boxes(rng, m, 3000, 1.5)
    table = classify_sheets(m, lo, hi)
    samples = 12
    t = rng.random((lo.shape[0], samples, 2))
    pts = lo[:, None, :] + t * (hi - lo)[:, None, :]
    # the corners too
    corners = np.stack([lo, hi, np.c_[lo[:, 0], hi[:, 1]], np.c_[hi[:, 0], lo[:, 1]]], axis=1)
    pts = np.concatenate([pts, corners], axis=1)
    flat = pts.reshape(-1, 2)
    q = m.joint_angles(flat).reshape(lo.shape[0], pts.shape[1], 4, 2)
    det = m.det_a(np.repeat(flat, 4, axis=0), q.reshape(-1, 2)).reshape(q.shape[:3])
    exists = np.isfinite(q).all(axis=-1)
    within = np.ones(q.shape[:3], dtype=bool)
    for i, lim in enumerate(m.limits):
        within &= lim.contains(np.where(np.isfinite(q[..., i]), q[..., i], 0.0))
    valid = exists & within
    checked = 0
    for p in range(4):
        sheet_in = table.status[:, p] == IN
        # IN: a valid configuration of this posture at every sample, of the recorded sign
        assert exists[sheet_in, :, p].all()
        assert within[sheet_in, :, p].all()
        sign = table.sign[sheet_in, p][:, None]
        assert (np.sign(det[sheet_in, :, p]) == sign).all()
        # OUT: no valid configuration of this posture anywhere in the box
        sheet_out = table.status[:, p] == OUT
        assert not valid[sheet_out, :, p].any()
        # a certified sign holds wherever the posture exists
        signed = table.sign[:, p] != 0
        s = table.sign[signed, p][:, None]
        e = exists[signed, :, p]
        assert (np.sign(det[signed, :, p])[e] == np.broadcast_to(s, e.shape)[e]).all()
        checked += int(sheet_in.sum() + sheet_out.sum())
    assert checked > 1000
    # leg reach codes
    for i, leg in enumerate(m.legs):
        angles = leg.angles(flat).reshape(lo.shape[0], pts.shape[1], 2)
        reach = np.isfinite(angles).all(axis=-1)
        assert reach[table.leg_status[:, i] == REGULAR].all()
        assert not reach[table.leg_status[:, i] == REACH_OUT].any()
        folds = (table.leg_status[:, i] == FOLD_OUTER) | (table.leg_status[:, i] == FOLD_INNER)
        # a certified fold has reachable and unreachable poses (checked on a fine grid)
        for b in np.flatnonzero(folds)[:40]:
            g = np.stack(
                np.meshgrid(
                    np.linspace(lo[b, 0], hi[b, 0], 60), np.linspace(lo[b, 1], hi[b, 1], 60)
                ),
                -1,
            ).reshape(-1, 2)
            r = np.isfinite(leg.angles(g)).all(axis=1)
            assert r.any() and (~r).any()


def test_regular_branches_stay_in_their_enclosures():
    m = _mechanism(*DESIGNS[2])
    rng = np.random.default_rng(11)
    lo, hi = _random_boxes(rng, m, 2000, 0.8)
    for leg in m.legs:
        reach = leg.reach(lo, hi)
        regular = np.flatnonzero(reach.status == REGULAR)
        assert regular.size > 100
        for _ in range(8):
            pts = lo[regular] + rng.random((regular.size, 2)) * (hi - lo)[regular]
            ang = leg.angles(pts)
            for b, enc in enumerate(reach.branches):
                a = ang[:, b]
                # the enclosure is unwrapped: some turn of the angle lies in it
                turns = np.round((enc.mid[regular] - a) / (2 * np.pi))
                a = a + 2 * np.pi * turns
                assert (enc.lo[regular] <= a).all() and (a <= enc.hi[regular]).all()
        folding = np.flatnonzero((reach.status == FOLD_OUTER) | (reach.status == FOLD_INNER))
        for _ in range(8):
            pts = lo[folding] + rng.random((folding.size, 2)) * (hi - lo)[folding]
            ang = leg.angles(pts)
            for b in range(2):
                ok = np.isfinite(ang[:, b])
                a = ang[ok, b]
                mid = reach.hull.mid[folding][ok]
                a = a + 2 * np.pi * np.round((mid - a) / (2 * np.pi))
                assert (reach.hull.lo[folding][ok] <= a).all()
                assert (a <= reach.hull.hi[folding][ok]).all()


@pytest.mark.parametrize(
    ("spec", "precision"),
    [
        ("examples/five-bar-paper.toml", 0.2),
        ("examples/five-bar-unlimited.toml", 0.3),
        ("examples/biglide.toml", 0.1),
        ("examples/three-rpr.toml", (1.6, 1.6, 0.2)),
    ],
)
def test_the_analysis_keeps_the_build_tables_of_its_leaves(spec, precision):
    """Each leaf is classified once, while the tree is built: the table the analysis
    holds is the one a fresh classification of its leaves gives, field by field."""
    from dataclasses import fields

    from moveability import analyze, from_spec

    result = analyze(from_spec(spec), precision=precision, resolve=False)
    leaves = result.tree.leaves()
    fresh = classify_sheets(result.mechanism, leaves.lo, leaves.hi)
    for field in fields(fresh):
        kept, again = getattr(result.table, field.name), getattr(fresh, field.name)
        assert kept.shape == again.shape, field.name
        np.testing.assert_array_equal(kept, again, err_msg=field.name)
