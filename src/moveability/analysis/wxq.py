"""The paper's construction: the configuration space as a 2^k-tree over W x Q.

A cell ``X x T`` of W x Q (k = pose axes + joint axes) is classified per leg:
the leg is *pinned* to a branch when that branch's joint angle over the whole
of X lies inside the cell's joint interval and every other branch lies outside
it; the cell then carries exactly one sheet of configurations, the graph of
that branch over X. A cell whose legs are all pinned and where det A keeps one
sign is IN for that sign; a cell holding no configuration (a leg unreachable,
or every branch outside its joint interval), or only configurations of the
other sign, is OUT; anything else is BOUNDARY. The joint axes span the limits,
so joint limits are faces of the box (an unlimited joint is a periodic axis).

The regions are the components of the IN and BOUNDARY cells of each sign
(vertex adjacency): a path of valid configurations of one sign only crosses
such cells, so every region lies in one component, and a component with an IN
cell holds at least one region. Its projection onto W bounds the region's
W_Nj: IN where an IN cell (a whole sheet over its X) covers it.

This construction cannot certify that two IN cells of one component belong to
one region where the sheet crosses a face of the joint grid (such cells stay
BOUNDARY at every depth); :func:`moveability.analyze` certifies connections
with posture sheets over W instead. The two are compared in the tests.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError, ResolutionError
from ..hypertree.keys import MAX_KEY_BITS
from ..hypertree.measurement import measure
from ..hypertree.projection import project
from ..hypertree.status import BOUNDARY, IN, OUT
from ..hypertree.topology import components
from ..hypertree.tree import HyperTree
from ..intervals import Interval
from ..limits import INSIDE, OUTSIDE, classify_angles
from ..mechanisms import Mechanism
from ..mechanisms.base import REACH_OUT, REGULAR
from ..types import Array
from .result import check_precision

__all__ = ["WxQAnalysis", "WxQRegion", "analyze_wxq"]


@dataclass(frozen=True)
class WxQRegion:
    """A component of the configuration-space tree holding certified cells."""

    sign: int
    #: bounds on the area of its projection onto W
    area: tuple[float, float]
    #: number of IN and of BOUNDARY cells
    cells: tuple[int, int]


def _classify(
    mechanism: Mechanism, lo: Array, hi: Array
) -> tuple[NDArray[np.uint8], NDArray[np.int8]]:
    """Decided status (IN decided / OUT / BOUNDARY) and sign of det A of each cell."""
    k = len(mechanism.pose_names)
    x_lo, x_hi = lo[:, :k], hi[:, :k]
    n = lo.shape[0]
    dead = np.zeros(n, dtype=bool)
    pinned = np.ones(n, dtype=bool)
    angles: list[Interval] = []
    for i, leg in enumerate(mechanism.legs):
        t_lo, t_hi = lo[:, k + i], hi[:, k + i]
        reach = leg.reach(x_lo, x_hi)
        regular = reach.status == REGULAR
        relation = [classify_angles(b, t_lo, t_hi) for b in reach.branches]
        hull_rel = classify_angles(reach.hull, t_lo, t_hi)
        none = np.all([r == OUTSIDE for r in relation], axis=0)
        dead |= (reach.status == REACH_OUT) | (regular & none) | (~regular & (hull_rel == OUTSIDE))
        # pinned: one branch inside the joint interval, the others outside
        which = np.full(n, -1)
        for b, r in enumerate(relation):
            others_out = np.all([rr == OUTSIDE for j, rr in enumerate(relation) if j != b], axis=0)
            which = np.where((r == INSIDE) & others_out, b, which)
        pinned &= regular & (which >= 0)
        chosen = np.clip(which, 0, None)
        enc_lo = np.choose(chosen, [b.lo for b in reach.branches])
        enc_hi = np.choose(chosen, [b.hi for b in reach.branches])
        # the joint interval itself also encloses the pinned angle
        angles.append(Interval(np.where(pinned, enc_lo, t_lo), np.where(pinned, enc_hi, t_hi)))
    with np.errstate(invalid="ignore"):
        det = mechanism.det_a_boxes(x_lo, x_hi, angles)
    sign = np.where(det.lo > 0, 1, np.where(det.hi < 0, -1, 0)).astype(np.int8)
    status = np.where(dead, OUT, np.where(pinned & (sign != 0), IN, BOUNDARY)).astype(np.uint8)
    sign[dead] = 0
    return status, sign


class WxQAnalysis:
    """Result of :func:`analyze_wxq`."""

    def __init__(self, mechanism: Mechanism, precision: float, tree: HyperTree) -> None:
        self.mechanism = mechanism
        self.precision = precision
        self.tree = tree
        leaves = tree.leaves()
        status, sign = _classify(mechanism, leaves.lo, leaves.hi)
        self.sign = sign
        k = len(mechanism.pose_names)
        self.regions: list[WxQRegion] = []
        for s in (1, -1):
            # cells of this sign: IN if certified, BOUNDARY if they may hold such configurations
            per_sign = np.where(
                status == OUT,
                OUT,
                np.where(
                    (status == IN) & (sign == s),
                    IN,
                    np.where((status == IN) | ((sign != 0) & (sign != s)), OUT, BOUNDARY),
                ),
            ).astype(np.uint8)
            signed = tree._replace(status=per_sign)
            labels, count = components(signed, status=IN | BOUNDARY, connectivity=tree.ndim)
            for c in range(count):
                cells = labels == c
                n_in = int((cells & (per_sign == IN)).sum())
                if not n_in:
                    continue
                shadow = project(signed.select(cells), list(range(k)))
                self.regions.append(
                    WxQRegion(sign=s, area=measure(shadow), cells=(n_in, int(cells.sum()) - n_in))
                )


def analyze_wxq(
    mechanism: Mechanism,
    precision: float = 0.2,
    *,
    max_leaves: int = 1 << 24,
    joint_coarsening: int = 3,
) -> WxQAnalysis:
    """Build the configuration space of ``mechanism`` in W x Q and find its regions.

    Pose axes are refined to ``precision``; joint axes to ``2 ** joint_coarsening``
    times the angle that moves the farthest pose by ``precision``.

    Examples
    --------
    >>> from moveability.mechanisms import FiveBar
    >>> result = analyze_wxq(FiveBar(7, 8, 5, 8, 5), precision=0.5)
    >>> sorted(r.sign for r in result.regions)
    [-1, 1]
    """
    eps = float(check_precision(precision, 1)[0])
    if not mechanism.restrictions.empty:
        raise InvalidParameterError(
            "mechanism", "one without passive limits, obstacles or collisions (use analyze)",
            mechanism.name,
        )
    w_lo, w_hi = mechanism.bounds
    q_lo = np.array([lim.lo for lim in mechanism.limits])
    q_hi = np.array([lim.lo + 2 * np.pi if lim.periodic else lim.hi for lim in mechanism.limits])
    reach = max(float(np.abs(np.concatenate([w_lo, w_hi])).max()), 1.0)
    lo = np.concatenate([w_lo, q_lo])
    hi = np.concatenate([w_hi, q_hi])
    widths = np.concatenate([w_hi - w_lo, (q_hi - q_lo) * reach])
    fine = [int(max(0, np.ceil(np.log2(w / eps)))) for w in widths]
    # joint cells a few times wider than the turn of a sheet over a pose cell, so
    # that sheets fit in them (a sheet crossing a joint cell's face pins no leg)
    depths = tuple(d if i < len(w_lo) else max(1, d - joint_coarsening) for i, d in enumerate(fine))
    if sum(depths) > MAX_KEY_BITS:
        raise ResolutionError("precision", "a coarser precision for the W x Q tree", precision)
    k = len(mechanism.pose_names)
    periodic = [k + i for i, lim in enumerate(mechanism.limits) if lim.periodic]

    def classify(cell_lo: Array, cell_hi: Array) -> NDArray[np.uint8]:
        status, _ = _classify(mechanism, cell_lo, cell_hi)
        return status

    tree = HyperTree.build(
        lo, hi, classify, max_depth=depths, periodic=periodic, max_leaves=max_leaves, merge=False
    )
    return WxQAnalysis(mechanism, eps, tree)
