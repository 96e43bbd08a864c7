"""The deductions across pairs of links (:meth:`ConstraintMargins.void` and the
narrowed ways to keep a pair apart), checked against sampled configurations
near the contacts where three links touch, a leg folds or det A vanishes.

Boxes are centred at configurations of five-bars whose links nearly touch;
configurations are sampled in each box on one posture and one sign of det A,
and tested pointwise (:func:`constraint_references.constrained`, no library
code): a void box holds none that keeps the links apart, and a motion said to
keep the constraints keeps sampled configurations apart until det A changes
sign or the pose leaves the box.
"""

from __future__ import annotations

import numpy as np
import pytest

from constraint_references import _cross2, constrained
from moveability import from_spec
from moveability.intervals import Interval
from moveability.limits import INSIDE
from posture_boxes import posture_enclosures

DESIGNS = [
    # Caro et al.'s five-bar and its mirror, and one with equal links
    (9.0, 8.0, 5.0, 5.0, 8.0),
    (9.0, 5.0, 8.0, 8.0, 5.0),
    (6.0, 5.0, 5.0, 5.0, 5.0),
]
#: contacts of the first design found by the analysis: three links touching,
#: two links along the base, a fold where det A vanishes with D on AC
CONTACTS = [(10.75, -2.437), (10.875, -4.091), (11.70, -5.665)]


def _mechanism(lengths):
    return from_spec(
        {
            "mechanism": "five-bar",
            "parameters": dict(zip(("L0", "L1", "L2", "L3", "L4"), lengths, strict=True)),
            "limits": {"theta1": "unlimited", "theta2": "unlimited"},
            "collisions": {"links": True},
        }
    )


def _points(lengths, pose, t1, t2):
    L0, L1, _, L3, _ = lengths
    n = pose.shape[0]
    return {
        "A": np.zeros((n, 2)),
        "B": np.tile([L0, 0.0], (n, 1)),
        "C": np.stack([L1 * np.cos(t1), L1 * np.sin(t1)], -1),
        "D": np.stack([L0 + L3 * np.cos(t2), L3 * np.sin(t2)], -1),
        "P": pose,
    }


def _near_contacts(lengths, rng, n):
    """Poses where two links that share no joint nearly touch."""
    L0, L1, L2, L3, L4 = lengths
    t = rng.uniform(-np.pi, np.pi, size=(200_000, 2))
    C = np.stack([L1 * np.cos(t[:, 0]), L1 * np.sin(t[:, 0])], -1)
    D = np.stack([L0 + L3 * np.cos(t[:, 1]), L3 * np.sin(t[:, 1])], -1)
    cd = D - C
    d = np.hypot(*cd.T)
    ok = (d > abs(L2 - L4)) & (d < L2 + L4)
    a = (L2**2 - L4**2 + d**2) / (2 * d)
    h = np.sqrt(np.maximum(L2**2 - a**2, 0.0))
    e = cd / d[:, None]
    sign = rng.choice([-1.0, 1.0], size=d.size)
    P = C + a[:, None] * e + (sign * h)[:, None] * np.stack([-e[:, 1], e[:, 0]], -1)
    pts = {"A": np.zeros_like(C), "B": np.tile([L0, 0.0], (d.size, 1)), "C": C, "D": D, "P": P}

    def gap(p, q, r, s):
        # a cheap proxy for the distance between segments pq and rs: end to segment
        def to_segment(o, c, e_):
            u = e_ - c
            w = np.clip(((o - c) * u).sum(-1) / (u * u).sum(-1), 0, 1)
            return np.hypot(*(c + w[:, None] * u - o).T)

        return np.minimum.reduce(
            [to_segment(p, r, s), to_segment(q, r, s), to_segment(r, p, q), to_segment(s, p, q)]
        )

    near = np.minimum.reduce(
        [gap(pts["A"], C, pts["B"], D), gap(pts["A"], C, D, P), gap(C, P, pts["B"], D)]
    )
    chosen = np.flatnonzero(ok & (near < 0.05))
    return P[rng.choice(chosen, size=min(n, chosen.size), replace=False)]


def _boxes(lengths, rng, n):
    centres = _near_contacts(lengths, rng, n)
    if lengths == DESIGNS[0]:
        extra = np.array(CONTACTS + [(x, -y) for x, y in CONTACTS])
        centres = np.concatenate([np.repeat(extra, 12, axis=0), centres])
    half = 10.0 ** rng.uniform(-4, -1.3, size=centres.shape)
    return centres - half, centres + half


def _samples(mechanism, lengths, lo, hi, posture, rng, m):
    """Configurations of a posture at poses sampled in one box: points, det A."""
    pose = lo + rng.random((m, 2)) * (hi - lo)
    branches = mechanism.postures[posture]
    t1 = mechanism.legs[0].angles(pose)[:, branches[0]]
    t2 = mechanism.legs[1].angles(pose)[:, branches[1]]
    keep = np.isfinite(t1) & np.isfinite(t2)
    pts = _points(lengths, pose[keep], t1[keep], t2[keep])
    det = _cross2(pts["P"] - pts["C"], pts["P"] - pts["D"])
    return pts, det


def _apart(pts):
    mode = {**pts, "valid": np.ones(pts["P"].shape[0], dtype=bool)}
    return constrained(mode, collisions=True)


@pytest.mark.parametrize("lengths", DESIGNS, ids=["caro", "mirrored", "equal"])
def test_void_boxes_hold_no_configuration_apart(lengths):
    mechanism = _mechanism(lengths)
    rng = np.random.default_rng(3)
    lo, hi = _boxes(lengths, rng, 600)
    claimed = 0
    for posture in range(len(mechanism.postures)):
        angles, regular = posture_enclosures(mechanism, lo, hi, posture)
        margins = mechanism.constraint_margins(lo, hi, angles, posture, regular)
        for sign in (1, -1):
            for box in np.flatnonzero(margins.void(sign)):
                claimed += 1
                pts, det = _samples(mechanism, lengths, lo[box], hi[box], posture, rng, 400)
                apart = _apart(pts)
                assert not (apart & (np.sign(det) == sign)).any(), (posture, sign, lo[box])
    # the deductions are exercised
    assert claimed > 20


@pytest.mark.parametrize("lengths", DESIGNS[:2], ids=["caro", "mirrored"])
def test_kept_motions_keep_the_links_apart(lengths):
    """Translations of the pose where both legs are regular: where ``kept`` says
    the motion keeps the constraints of one sign of det A, sampled
    configurations of that sign that start apart stay apart."""
    mechanism = _mechanism(lengths)
    rng = np.random.default_rng(8)
    lo, hi = _boxes(lengths, rng, 600)
    checked = 0
    for posture in range(len(mechanism.postures)):
        angles, regular = posture_enclosures(mechanism, lo, hi, posture)
        both = regular.all(axis=1)
        b_lo, b_hi = lo[both], hi[both]
        angles = [Interval(a.lo[both], a.hi[both]) for a in angles]
        margins = mechanism.constraint_margins(b_lo, b_hi, angles, posture, regular[both])
        active = margins.codes != INSIDE
        for _ in range(4):
            direction = rng.normal(size=2)
            direction /= np.hypot(*direction)
            velocity = [Interval(np.full(b_lo.shape[0], v)) for v in direction]
            gradients = [
                leg.joint_gradient(b_lo, b_hi, int(b), a)
                for leg, b, a in zip(
                    mechanism.legs, mechanism.postures[posture], angles, strict=True
                )
            ]
            rates = [g[0] * velocity[0] + g[1] * velocity[1] for g in gradients]
            moving = mechanism.linkage_velocities(b_lo, b_hi, angles, velocity, rates)
            for sign in (1, -1):
                kept = margins.kept(moving, sign) & active
                for box in np.flatnonzero(kept)[:40]:
                    pts, det = _samples(mechanism, lengths, b_lo[box], b_hi[box], posture, rng, 30)
                    start = _apart(pts) & (np.sign(det) == sign)
                    for pose in pts["P"][start]:
                        room = np.where(direction > 0, b_hi[box] - pose, b_lo[box] - pose)
                        limit = np.min(np.abs(room / np.where(direction == 0, np.inf, direction)))
                        path = pose + np.linspace(0, limit, 60)[:, None] * direction
                        q, d = _path(mechanism, lengths, path, posture)
                        same = np.cumprod(np.sign(d) == sign).astype(bool)
                        assert _apart(q)[same].all(), (posture, sign, pose, direction)
                        checked += 1
    assert checked > 50


def _path(mechanism, lengths, path, posture):
    branches = mechanism.postures[posture]
    t1 = mechanism.legs[0].angles(path)[:, branches[0]]
    t2 = mechanism.legs[1].angles(path)[:, branches[1]]
    pts = _points(lengths, path, t1, t2)
    return pts, _cross2(pts["P"] - pts["C"], pts["P"] - pts["D"])
