"""Postures with one valid set over a leaf, against sampled poses.

The claim of :mod:`moveability.analysis.valid_sets`: two postures given one
label over a box have a valid configuration at exactly the same poses of it.
Checked at random poses of random boxes of random mechanisms, from the closed
forms (``joint_angles``) and the limits (``JointLimit.contains``) alone.
"""

from __future__ import annotations

import numpy as np
import pytest

from moveability.analysis.sheets import classify_sheets
from moveability.analysis.valid_sets import covered_by_classes, free_legs, valid_set_classes
from moveability.hypertree.status import OUT
from moveability.limits import JointLimit
from moveability.mechanisms import Delta, FiveBar, from_spec
from moveability.mechanisms.constraints import Constraints

PI = np.pi


def _limit(rng: np.random.Generator) -> JointLimit:
    kind = int(rng.integers(0, 4))
    if kind == 0:
        return JointLimit.unlimited()
    if kind == 1:
        return JointLimit(-PI, PI)
    a = float(rng.uniform(-PI, PI))
    return JointLimit(a, a + float(rng.uniform(0.2, 3.0)))


def _five_bar(rng: np.random.Generator) -> FiveBar:
    while True:
        L = rng.uniform(1.0, 9.0, 5)
        if rng.random() < 0.3:
            L[2] = L[1]
        if L[0] < L[1] + L[2] + L[3] + L[4] - 0.2:
            return FiveBar(*L, limits=(_limit(rng), _limit(rng)))


def _biglide(rng: np.random.Generator):
    limits = {}
    for name in ("rho1", "rho2"):
        lo = float(rng.uniform(-8.0, 4.0))
        limits[name] = [lo, lo + float(rng.uniform(0.5, 10.0))]
    return from_spec(
        {
            "mechanism": "biglide",
            "parameters": {"L1": float(rng.uniform(2, 7)), "L2": float(rng.uniform(2, 7))},
            "limits": limits,
        }
    )


def _delta(rng: np.random.Generator) -> Delta:
    lo = float(rng.uniform(-1.5, 0.5))
    width = float(rng.uniform(0.5, 2.5))
    return Delta(limits=(JointLimit(lo, lo + width),) * 3)


def _valid(m, points: np.ndarray) -> np.ndarray:
    """(m, P): whether each posture has a valid configuration at each point."""
    q = m.joint_angles(points)
    ok = np.isfinite(q).all(axis=2)
    for i, limit in enumerate(m.limits):
        ok &= np.where(np.isfinite(q[:, :, i]), limit.contains(np.nan_to_num(q[:, :, i])), False)
    return ok


def _boxes(m, rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    lo, hi = m.pose_box()
    width = (hi - lo) * rng.choice([0.02, 0.05, 0.15], size=(n, 1))
    start = lo + rng.random((n, lo.size)) * (hi - lo - width)
    return start, start + width


MAKERS = {"five-bar": _five_bar, "biglide": _biglide, "delta": _delta}


@pytest.mark.parametrize("kind", sorted(MAKERS))
@pytest.mark.parametrize("seed", range(4))
def test_postures_of_one_label_are_valid_at_the_same_poses(kind, seed):
    rng = np.random.default_rng(100 * seed + len(kind))
    split = 0
    for _ in range(4):
        m = MAKERS[kind](rng)
        box_lo, box_hi = _boxes(m, rng, 150)
        table = classify_sheets(m, box_lo, box_hi)
        labels = valid_set_classes(m, table)
        for b in range(box_lo.shape[0]):
            row = labels[b]
            if np.unique(row).size == row.size:
                continue  # every posture its own class: nothing claimed
            points = box_lo[b] + rng.random((60, box_lo.shape[1])) * (box_hi[b] - box_lo[b])
            valid = _valid(m, points)
            for p in range(row.size):
                same = np.flatnonzero(row == row[p])
                split += same.size > 1
                assert (valid[:, same] == valid[:, [p]]).all(), (m, box_lo[b], box_hi[b], p)
    assert split > 0  # the claim was tested somewhere


def test_a_free_joint_frees_its_leg_and_a_cut_limit_does_not():
    m = FiveBar(7, 8, 6, 8, 6, limits=(JointLimit.unlimited(), JointLimit(PI - 0.3, PI + 0.3)))
    rng = np.random.default_rng(3)
    box_lo, box_hi = _boxes(m, rng, 400)
    table = classify_sheets(m, box_lo, box_hi)
    free = free_legs(m, table)
    regular = table.leg_status[:, 0] == 1
    assert free[regular, 0].all()  # an unlimited joint never cuts
    # the limited joint is free only where every posture's enclosure lies within it
    inside = (table.angles_lo[:, :, 1] >= PI - 0.3) & (table.angles_hi[:, :, 1] <= PI + 0.3)
    assert not (free[:, 1] & ~inside.all(axis=1)).any()


def test_constraints_beyond_the_limits_keep_each_posture_alone():
    m = FiveBar(limits=(JointLimit.unlimited(), JointLimit(0.0, 1.0)))
    m = m.constrained(Constraints(collisions=True))
    table = classify_sheets(m, np.array([[3.0, 9.0]]), np.array([[3.1, 9.1]]))
    assert valid_set_classes(m, table).tolist() == [[0, 1, 2, 3]]


def test_a_class_is_covered_by_one_good_node_or_by_being_empty():
    labels = np.array([[0, 1, 0, 1]] * 4)
    out = np.uint8(OUT)
    status = np.array(
        [[4, 4, 4, 4], [4, out, 4, out], [4, 4, 4, 4], [out, out, out, out]], dtype=np.uint8
    )
    good = np.array([[1, 1, 0, 0], [1, 0, 0, 0], [1, 0, 0, 0], [0, 0, 0, 0]], dtype=bool)
    assert covered_by_classes(labels, status, good).tolist() == [True, True, False, True]
