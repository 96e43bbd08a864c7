"""Joint enclosures of one posture over boxes of poses, as the analysis' sheets
take them: each leg's branch enclosure where it is regular over the box, the
hull of both branches elsewhere (shared by tests that build constraint margins
or det A enclosures by hand)."""

from __future__ import annotations

import numpy as np

from moveability.intervals import Interval
from moveability.mechanisms.base import REGULAR


def posture_enclosures(mechanism, lo, hi, posture):
    """``(angles, regular)``: one Interval per leg, and (n, legs) where each leg
    is regular."""
    angles, regular = [], []
    for leg, branch in zip(mechanism.legs, mechanism.postures[posture], strict=True):
        reach = leg.reach(lo, hi)
        ok = reach.status == REGULAR
        angles.append(
            Interval(
                np.where(ok, reach.branches[branch].lo, reach.hull.lo),
                np.where(ok, reach.branches[branch].hi, reach.hull.hi),
            )
        )
        regular.append(ok)
    return angles, np.stack(regular, axis=1)
