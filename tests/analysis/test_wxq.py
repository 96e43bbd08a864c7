"""The paper's W x Q construction against the certified sheet construction."""

import numpy as np
import pytest

from moveability import analyze
from moveability.analysis.wxq import analyze_wxq
from moveability.limits import JointLimit
from moveability.mechanisms import FiveBar

DESIGNS = [
    ((7.0, 8.0, 5.0, 8.0, 5.0), (0.0, np.pi)),
    ((7.0, 8.0, 5.0, 8.0, 5.0), None),
    ((6.0, 5.0, 7.0, 5.0, 7.0), (-np.pi / 2, np.pi)),
]


@pytest.mark.parametrize(("lengths", "limit"), DESIGNS)
def test_both_constructions_find_the_same_regions(lengths, limit):
    joint = JointLimit.unlimited() if limit is None else JointLimit(*limit)
    m = FiveBar(*lengths, limits=(joint, joint))
    sheets = analyze(m, precision=0.1)
    wxq = analyze_wxq(m, precision=0.25)
    assert sorted(r.sign for r in wxq.regions) == sorted(r.sign for r in sheets.regions)
    for s in (1, -1):
        a = [r.area for r in sheets.regions if r.sign == s]
        b = [r.area for r in wxq.regions if r.sign == s]
        # one region of each sign here: the bounds of its W_Nj must overlap
        assert len(a) == len(b) == 1
        assert max(a[0][0], b[0][0]) <= min(a[0][1], b[0][1])
        # each certified cell of W x Q holds a whole sheet over its pose box
        assert b[0][0] > 0


def test_wxq_cells_respect_their_certificates():
    joint = JointLimit(0.0, np.pi)
    m = FiveBar(limits=(joint, joint))
    result = analyze_wxq(m, precision=0.5)
    leaves = result.tree.leaves()
    certified = np.flatnonzero(leaves.status == 1)
    assert certified.size > 100
    rng = np.random.default_rng(1)
    for i in certified[:: max(1, certified.size // 200)]:
        pts = leaves.lo[i, :2] + rng.random((20, 2)) * (leaves.hi[i, :2] - leaves.lo[i, :2])
        q = m.joint_angles(pts)  # (20, 4, 2), angles of any turn
        lo, hi = leaves.lo[i, 2:], leaves.hi[i, 2:]
        q = lo + np.mod(q - lo, 2 * np.pi)
        inside = (q <= hi).all(axis=-1)
        # exactly one posture of every pose of the box lies in the cell, of the cell's sign
        assert (inside.sum(axis=1) == 1).all()
        p = np.argmax(inside, axis=1)
        det = m.det_a(pts, q[np.arange(20), p])
        assert (np.sign(det) == result.sign[i]).all()
