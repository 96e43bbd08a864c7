"""The five-bar's det A enclosure on a known posture (:func:`branch_det`): it
holds det A at sampled configurations of the posture, near the folds too,
and it is narrower than the rows stacked where a leg folds."""

from __future__ import annotations

import numpy as np
import pytest

from moveability import from_spec
from posture_boxes import posture_enclosures


def _five_bar(lengths):
    return from_spec(
        {
            "mechanism": "five-bar",
            "parameters": dict(zip(("L0", "L1", "L2", "L3", "L4"), lengths, strict=True)),
            "limits": {"theta1": "unlimited", "theta2": "unlimited"},
        }
    )


@pytest.mark.parametrize(
    "lengths",
    [
        (9.0, 8.0, 5.0, 5.0, 8.0),
        (6.0, 5.0, 5.0, 5.0, 5.0),
        (7.0, 8.0, 5.0, 8.0, 5.0),
        (3.0, 2.0, 6.0, 4.5, 3.5),
    ],
)
def test_det_enclosure_holds_near_the_folds(lengths):
    mechanism = _five_bar(lengths)
    rng = np.random.default_rng(2)
    L0, L1, L2, L3, L4 = lengths
    # poses on and near each leg's fold circles, and anywhere
    angle = rng.uniform(-np.pi, np.pi, 3000)
    radius = rng.choice([L1 + L2, abs(L1 - L2)], 3000) + rng.normal(0, 1e-3, 3000)
    on_first = np.stack([radius * np.cos(angle), radius * np.sin(angle)], -1)
    radius = rng.choice([L3 + L4, abs(L3 - L4)], 3000) + rng.normal(0, 1e-3, 3000)
    on_second = np.stack([L0 + radius * np.cos(angle), radius * np.sin(angle)], -1)
    anywhere = rng.uniform([-L1 - L2, -L1 - L2], [L0 + L3 + L4, L1 + L2], (3000, 2))
    centres = np.concatenate([on_first, on_second, anywhere])
    half = 10.0 ** rng.uniform(-5, -1, size=centres.shape)
    lo, hi = centres - half, centres + half
    held = narrower = 0
    for posture, branches in enumerate(mechanism.postures):
        angles, _ = posture_enclosures(mechanism, lo, hi, posture)
        sharp = mechanism.det_a_boxes(lo, hi, angles, posture=posture)
        natural = mechanism.det_a_boxes(lo, hi, angles)
        assert (sharp.lo >= natural.lo).all() and (sharp.hi <= natural.hi).all()
        narrower += int((sharp.hi - sharp.lo < 0.5 * (natural.hi - natural.lo)).sum())
        poses = lo[:, None, :] + rng.random((lo.shape[0], 8, 2)) * (hi - lo)[:, None, :]
        flat = poses.reshape(-1, 2)
        t1 = mechanism.legs[0].angles(flat)[:, branches[0]]
        t2 = mechanism.legs[1].angles(flat)[:, branches[1]]
        det = mechanism.det_a(flat, np.stack([t1, t2], -1)).reshape(-1, 8)
        known = np.isfinite(det)
        inside = (sharp.lo[:, None] <= det) & (det <= sharp.hi[:, None])
        assert inside[known].all()
        held += int(known.sum())
    assert held > 10_000
    assert narrower > 100  # where a leg folds
