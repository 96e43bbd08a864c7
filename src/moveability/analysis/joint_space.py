"""The count of regions proved in the joint space of a mechanism of two dyads.

In the five-bar and the biglide each leg ends with a distal link from a *knee*
``C_i(q_i)`` (the elbow, or the slider) to the platform point P. Given the
joints q, P lies on both circles ``|P - C_i| = b_i``; with ``d = |C_1 - C_2|``:

* det A, the cross product of ``P - C_1`` and ``P - C_2``, vanishes exactly
  where P, C_1 and C_2 are collinear, that is ``d = b_1 + b_2`` or
  ``d = |b_1 - b_2|``;
* for ``|b_1 - b_2| < d < b_1 + b_2`` there are two poses, mirror images
  across the line C_1 C_2, one for each sign of det A, and they vary
  continuously with q.

So ``(X, q) -> (q, sign det A)`` maps the configurations within the limits with
det A != 0 homeomorphically onto ``D x {+1, -1}``, where
``D = {q in Q : |b_1 - b_2| < d(q) < b_1 + b_2}`` and Q is the box of joint
ranges (a free joint's axis glued into a circle). The regions R_j are the
components of D, twice. :func:`count_in_joint_space` bounds that number on a
quadtree of Q:

* a cell is IN when ``d^2`` is certainly inside the open interval over the
  closed cell, OUT when certainly outside;
* ``at_least``: possible components (IN or undecided cells, touching at a
  face or corner) that hold an IN cell; each holds a component of D;
* ``at_most``: components of the IN cells, once every undecided cell is
  *attached*: every point of D in it reaches an IN cell within D (see
  :mod:`moveability.analysis.flows`). A cell is attached along a direction in which
  ``d^2`` moves away from each bound it may meet in the cell, when every cell
  across the faces the direction leaves through is IN, OUT or attached
  before it; or, where ``d^2`` is convex (concave) over the cell and meets
  only the lower (upper) bound, through any face: the set beyond the bound is
  then convex, and a ray from it through any point of D stays in D up to the
  cell's boundary.

Only the cells that keep the count open are refined, one level a round: the
loose cells, and the undecided cells of possible components that hold several
certified ones; until the bounds meet or a budget is spent.

The Delta robot has the same structure in a 3-D joint space: given q, the
platform's centre lies on three spheres of radius ``lb`` about centres
``c_i(q_i)``; there are two poses, one for each sign of det A, exactly where the
centres are not collinear and their circumradius is below ``lb`` (see
:class:`moveability.mechanisms.delta.Circumradius`, a function ``F`` with ``D =
{F > 0}``, which its ``joint_condition`` gives). The same octree count applies,
with one bound and the flows along the directions of three axes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .. import intervals as iv
from ..hypertree.status import BOUNDARY, IN, OUT
from ..hypertree.topology import adjacency, components
from ..hypertree.tree import HyperTree
from ..intervals import Interval
from ..mechanisms.base import Mechanism
from ..types import Array
from .flows import attached_nodes, face_neighbours, flow_directions
from .joint_branches import BranchCondition, takes_branches
from .stop_traces import StopBlock, block_labels, block_members, find_blocks

__all__ = [
    "JointSpaceCount",
    "count_in_joint_space",
    "has_dyads",
    "joint_condition",
    "witness_configurations",
]

#: depth of the first, uniform pass over each joint axis (two joints, three)
START_DEPTH = 6
START_DEPTH_3D = 4
#: deepest level of the refinement on each joint axis (two joints, three: the
#: keys hold 62 bits)
MAX_DEPTH = 26
MAX_DEPTH_3D = 20
#: leaves the tree of Q may hold (two joints, three)
MAX_LEAVES = 1 << 16
MAX_LEAVES_3D = 1 << 19
#: levels above a leaf at which a convex block is sought, and the most leaves tried
_BLOCK_LEVELS = 4
_BLOCK_LEAVES = 256
#: finest units a block's box is widened by against rounding
_WIDEN = 1e-6


@dataclass(frozen=True)
class JointSpaceCount:
    """Bounds on the number of regions R_j, proved in the joint space.

    Attributes
    ----------
    at_least, at_most : int, int or None
        The bounds (``at_most`` None where no upper bound is proved).
    leaves : int
        Leaves of the quadtree of Q when the refinement stopped.
    open_measure : float
        Measure of Q (rad^2, or joint units) in the undecided leaves of the
        possible components whose count is still open.
    """

    at_least: int
    at_most: int | None
    leaves: int
    open_measure: float
    #: (m, n_joints): a point of Q inside each component of the certified cells (the
    #: centre of its largest cell); each is the joints of two configurations, one
    #: of each sign of det A, of two distinct regions (see :func:`witness_configurations`)
    witnesses: NDArray[np.float64] = field(
        default_factory=lambda: np.zeros((0, 0), dtype=np.float64), compare=False
    )
    #: lines on what the design is exactly degenerate at, where the count found it
    notes: tuple[str, ...] = ()
    #: (m, 2) bool: which of the two configurations of each witness (see
    #: :func:`witness_configurations`) lies in a region of its own; by default
    #: both, but with constraints (see :mod:`moveability.analysis.joint_branches`)
    #: each witness stands for one branch alone
    witness_poses: NDArray[np.bool_] | None = field(default=None, compare=False)

    @property
    def witnessed(self) -> NDArray[np.bool_]:
        """(m, 2) bool: :attr:`witness_poses`, both where not given."""
        if self.witness_poses is not None:
            return self.witness_poses
        return np.ones((self.witnesses.shape[0], 2), dtype=bool)

    @property
    def decided(self) -> bool:
        """Whether the bounds meet."""
        return self.at_least == self.at_most


def has_dyads(mechanism: Mechanism) -> bool:
    """Whether the mechanism is two dyads meeting at a planar platform point (the
    five-bar, the biglide, user-defined legs of the form
    :class:`~moveability.mechanisms.dyad_leg.DyadLeg`): legs that give
    :meth:`knee_boxes` and a ``distal`` link, over two pose axes that are not
    periodic, in a box of poses that holds all they reach.

    Examples
    --------
    >>> from moveability.mechanisms import FiveBar
    >>> has_dyads(FiveBar())
    True
    """
    legs = mechanism.legs
    return (
        len(mechanism.pose_names) == 2
        and not mechanism.periodic_axes
        and len(legs) == 2
        and all(hasattr(leg, "knee_boxes") and hasattr(leg, "distal") for leg in legs)
        and _reach_within_bounds(mechanism)
    )


def _reach_within_bounds(mechanism: Mechanism) -> bool:
    """Whether every pose the legs reach lies in the mechanism's box of poses:
    the count in Q holds every configuration, so a box that cuts the workspace
    (a user-defined one may) would make it count regions it does not hold."""
    if mechanism.bounds_hold_workspace:
        return True
    lo_box, hi_box = (np.asarray(b, dtype=np.float64) for b in mechanism.bounds)
    lo_q, hi_q, _ = _joint_box(mechanism)
    reach_lo = np.full(lo_box.size, -np.inf)
    reach_hi = np.full(lo_box.size, np.inf)
    for i, leg in enumerate(mechanism.legs):
        (knee, _, _) = leg.knee_boxes(Interval(lo_q[i : i + 1], hi_q[i : i + 1]))  # type: ignore[attr-defined]
        b = float(leg.distal)  # type: ignore[attr-defined]
        for j, c in enumerate(knee):
            reach_lo[j] = max(reach_lo[j], float(c.lo[0]) - b)
            reach_hi[j] = min(reach_hi[j], float(c.hi[0]) + b)
    return bool((reach_lo >= lo_box).all() and (reach_hi <= hi_box).all())


def joint_condition(mechanism: Mechanism) -> Any:
    """The function of the joints whose components count the regions, with its
    bounds (``lower``, ``upper``), ``terms`` and ``classify``: the distance of
    the knees of two dyads (:func:`has_dyads`), or a mechanism's own
    ``joint_condition`` (the Delta); None for the others, or with constraints
    beyond the paper's that cannot be taken one branch at a time (see
    :func:`~moveability.analysis.joint_branches.takes_branches`).

    Examples
    --------
    >>> from moveability.mechanisms import Delta, FiveBar
    >>> [type(joint_condition(m)).__name__ for m in (FiveBar(), Delta())]
    ['_Distance', 'Circumradius']
    """
    if not mechanism.restrictions.empty:
        return _Distance(mechanism) if takes_branches(mechanism) and has_dyads(mechanism) else None
    if has_dyads(mechanism):
        return _Distance(mechanism)
    own = getattr(mechanism, "joint_condition", None)
    condition = own() if callable(own) else None
    return condition if condition is not None and _reach_within_bounds(mechanism) else None


def _joint_box(mechanism: Mechanism) -> tuple[Array, Array, tuple[int, ...]]:
    lo = np.array([lim.lo for lim in mechanism.limits], dtype=np.float64)
    hi = np.array(
        [lim.lo + 2 * np.pi if lim.periodic else lim.hi for lim in mechanism.limits],
        dtype=np.float64,
    )
    periodic = tuple(i for i, lim in enumerate(mechanism.limits) if lim.periodic)
    return lo, hi, periodic


class _Distance:
    """``d^2 = |C_1(q_1) - C_2(q_2)|^2`` over boxes of Q, with its bounds."""

    def __init__(self, mechanism: Mechanism) -> None:
        self.legs = mechanism.legs
        b1, b2 = (Interval(float(leg.distal)) for leg in self.legs)  # type: ignore[attr-defined]
        self.lower = iv.square(b1 - b2)
        self.upper = iv.square(b1 + b2)

    def terms(
        self, lo: Array, hi: Array, hessian: bool = True
    ) -> tuple[Interval, list[Interval], list[Interval]]:
        """``d^2`` (natural and mean-value forms intersected), its gradient and its
        Hessian ``[h11, h12, h22]`` over the boxes (an empty list without
        ``hessian``)."""
        q = [Interval(lo[:, i], hi[:, i]) for i in range(2)]
        (p1, v1, a1), (p2, v2, a2) = (
            leg.knee_boxes(q[i])  # type: ignore[attr-defined]
            for i, leg in enumerate(self.legs)
        )
        dx, dy = p1[0] - p2[0], p1[1] - p2[1]
        natural = iv.square(dx) + iv.square(dy)
        grad = [
            (dx * v1[0] + dy * v1[1]) * 2.0,
            -((dx * v2[0] + dy * v2[1]) * 2.0),
        ]
        mid = 0.5 * (lo + hi)
        m1, m2 = (
            leg.knee_boxes(Interval(mid[:, i]))[0]  # type: ignore[attr-defined]
            for i, leg in enumerate(self.legs)
        )
        mean = iv.square(m1[0] - m2[0]) + iv.square(m1[1] - m2[1])
        for i in range(2):
            mean = mean + grad[i] * (q[i] - mid[:, i])
        value = Interval(np.maximum(natural.lo, mean.lo), np.minimum(natural.hi, mean.hi))
        if not hessian:
            return value, grad, []
        second = [
            (v1[0] * v1[0] + v1[1] * v1[1] + dx * a1[0] + dy * a1[1]) * 2.0,
            -((v1[0] * v2[0] + v1[1] * v2[1]) * 2.0),
            (v2[0] * v2[0] + v2[1] * v2[1] - dx * a2[0] - dy * a2[1]) * 2.0,
        ]
        return value, grad, second

    def poses(self, joints: Array) -> NDArray[np.float64]:
        """(m, 2, 2): the platform points of the joints (m, 2), where the circles of
        the distal links about the knees meet (NaN where they do not)."""
        (k1, _, _), (k2, _, _) = (
            leg.knee_boxes(Interval(joints[:, i]))  # type: ignore[attr-defined]
            for i, leg in enumerate(self.legs)
        )
        c1 = np.stack([k1[0].lo, k1[1].lo], axis=1)
        c2 = np.stack([k2[0].lo, k2[1].lo], axis=1)
        b1, b2 = (float(leg.distal) for leg in self.legs)  # type: ignore[attr-defined]
        d = c2 - c1
        dist2 = np.sum(d * d, axis=1)
        # knees at one place (a joint vector off D): NaN, no pose
        with np.errstate(invalid="ignore", divide="ignore"):
            along = (b1 * b1 - b2 * b2 + dist2) / (2.0 * dist2)
            height = np.sqrt(b1 * b1 / dist2 - along * along)
            foot = c1 + along[:, None] * d
            normal = np.stack([-d[:, 1], d[:, 0]], axis=1) * height[:, None]
        return np.stack([foot + normal, foot - normal], axis=1)

    def classify(self, lo: Array, hi: Array) -> NDArray[np.uint8]:
        value, _, _ = self.terms(lo, hi, hessian=False)
        inside = (value.lo > self.lower.hi) & (value.hi < self.upper.lo)
        outside = (value.hi < self.lower.lo) | (value.lo > self.upper.hi)
        return np.where(inside, IN, np.where(outside, OUT, BOUNDARY)).astype(np.uint8)


#: the flows of the cells of Q met in one count: (anchor, level) -> (which hold,
#: their exit faces)
_FlowCache = dict[bytes, tuple[NDArray[np.bool_], NDArray[np.uint8]]]


def _flows(
    distance: Any, lo: Array, hi: Array, branch: BranchCondition | None
) -> tuple[NDArray[np.bool_], NDArray[np.uint8], bool]:
    """The flows of the boxes ``lo``, ``hi`` of Q: (m, F) where each holds, (F, m)
    the faces each leaves through, and whether the last constant one is the
    convex (concave) test; with a ``branch``, its constraints kept too and two
    flows along the level curves of d^2 after the constant ones."""
    k = lo.shape[1]
    with np.errstate(invalid="ignore", over="ignore"):
        value, grad, second = distance.terms(lo, hi)
        high = value.hi >= distance.upper.lo  # may meet the upper bound
        low = value.lo <= distance.lower.hi  # may meet the lower bound
        vectors, exits = flow_directions(k)
        # the convex (concave) test of two joints, from the Hessian, when given
        hessian = k == 2 and len(second) == 3
        n_const = vectors.shape[0] + int(hessian)
        # with a branch, two more: along the level curves of d^2
        n_flows = n_const + (2 if branch is not None else 0)
        ok = np.zeros((lo.shape[0], n_flows), dtype=bool)
        faces = np.zeros((n_flows, lo.shape[0]), dtype=np.uint8)
        for f, (v, fl) in enumerate(zip(vectors, exits, strict=True)):
            rate = grad[0] * float(v[0])
            for axis in range(1, k):
                rate = rate + grad[axis] * float(v[axis])
            ok[:, f] = (~high | (rate.hi <= 0)) & (~low | (rate.lo >= 0))
            faces[f] = sum(1 << j for j in fl)
        # the constraints allow every flow where they all hold (and no box is asked)
        inside = np.ones(lo.shape[0], dtype=bool)
        if branch is not None and lo.shape[0]:
            kept, inside, level, level_faces = branch.flows(lo, hi, vectors, value, grad)
            ok[:, : vectors.shape[0]] &= kept
            ok[:, n_const:], faces[n_const:] = level, level_faces
        if hessian:
            h11, h12, h22 = second
            det = h11 * h22 - h12 * h12
            convex = (h11.lo > 0) & (det.lo > 0)
            concave = (h11.hi < 0) & (det.lo > 0)
            ok[:, n_const - 1] = (convex & ~high) | (concave & ~low)
            ok[:, n_const - 1] &= inside
            faces[n_const - 1] = 0b1111
    return ok, faces, hessian


def _cached_flows(
    tree: HyperTree,
    leaves: Any,
    rows: NDArray[np.intp],
    distance: Any,
    branch: BranchCondition | None,
    cache: _FlowCache,
) -> tuple[NDArray[np.bool_], NDArray[np.uint8], bool]:
    """:func:`_flows` of the leaves ``rows``, each cell's computed once over the
    rounds of one count (a cell's flows depend on its box alone); ``cache`` maps
    a cell's anchor and level to its row of flows."""
    keys = [
        bytes(row)
        for row in np.column_stack([tree.anchors[rows], tree.levels[rows]]).astype(np.int64)
    ]
    new = np.array([key not in cache for key in keys], dtype=bool)
    fresh = np.flatnonzero(new)
    ok, faces, hessian = _flows(distance, leaves.lo[rows[fresh]], leaves.hi[rows[fresh]], branch)
    for j, i in enumerate(fresh):
        cache[keys[i]] = (ok[j], faces[:, j])
    if not rows.size:
        return ok, faces, hessian
    all_ok = np.stack([cache[key][0] for key in keys])
    all_faces = np.stack([cache[key][1] for key in keys], axis=1)
    return all_ok, all_faces, hessian


def _attached(
    tree: HyperTree,
    leaves: Any,
    distance: Any,
    settled: NDArray[np.bool_],
    branch: BranchCondition | None = None,
    cache: _FlowCache | None = None,
) -> NDArray[np.bool_]:
    """The undecided leaves whose every point of D reaches an IN leaf within D
    (``leaves`` are the tree's leaves), ``settled`` leaves taken as decided (those
    of stop blocks: their points of D lie in certified pieces); with a
    ``branch``, of its D_s, the flows keeping its constraints too. The flows of
    each cell are kept in ``cache`` over the rounds, where given."""
    status = tree.status
    rows = np.flatnonzero((status == BOUNDARY) & ~settled)
    ok, faces, hessian = _cached_flows(
        tree, leaves, rows, distance, branch, {} if cache is None else cache
    )
    n_flows = ok.shape[1]
    weights = np.left_shift(np.uint64(1), np.arange(n_flows, dtype=np.uint64))
    bits = (ok.astype(np.uint64) * weights).sum(axis=1, dtype=np.uint64)[:, None]
    nodes = np.stack([rows, np.zeros_like(rows)], axis=1)
    neighbours = face_neighbours(tree)
    done = (status != BOUNDARY) | settled
    attached = np.zeros(len(tree), dtype=bool)
    while True:
        found = attached_nodes(
            (done | attached)[:, None],
            nodes,
            bits,
            np.ones((rows.size, 1), dtype=bool),
            faces,
            neighbours,
        )[:, 0]
        attached |= found
        if not hessian:
            return attached
        blocks = _convex_blocks(tree, distance, neighbours, done | attached, branch)
        if not blocks.any():
            return attached
        attached |= blocks


def _convex_blocks(
    tree: HyperTree,
    distance: _Distance,
    neighbours: Any,
    done: NDArray[np.bool_],
    branch: BranchCondition | None = None,
) -> NDArray[np.bool_]:
    """Leaves not done that lie in a box B of a coarser level over which ``d^2`` is
    convex (concave) and meets only the lower (upper) bound, when every leaf
    across B's boundary is done: every point of D in B then reaches that boundary
    within D, along the ray from the point of B where ``d^2`` is least (greatest).
    Several leaves around a point of D's complement (equal distal links: the
    knees meet) depend on each other; B holds them all."""
    loose = np.flatnonzero(~done & (tree.status == BOUNDARY))
    out = np.zeros(len(tree), dtype=bool)
    if not loose.size or loose.size > _BLOCK_LEAVES:
        return out
    anchors = tree.anchors
    ends = anchors + tree.layout.cell_sizes(tree.levels)
    pairs = np.concatenate(neighbours.pairs)
    extent = np.left_shift(np.int64(1), np.asarray(tree.max_depth, dtype=np.int64))
    scale = (tree.hi - tree.lo) / extent
    # the blocks 1 .. _BLOCK_LEVELS levels above each loose leaf, tested at once
    ups = np.arange(1, _BLOCK_LEVELS + 1)
    leaf = np.repeat(loose, ups.size)
    levels = np.maximum(tree.levels[leaf].astype(np.int64) - np.tile(ups, loose.size), 0)
    size = tree.layout.cell_sizes(levels)
    b_lo = (anchors[leaf] // size) * size
    b_hi = b_lo + size
    # a little wider than B: convexity over more than B holds over B
    lo = np.nextafter(tree.lo + b_lo * scale, -np.inf) - _WIDEN * scale
    hi = np.nextafter(tree.lo + b_hi * scale, np.inf) + _WIDEN * scale
    with np.errstate(invalid="ignore", over="ignore"):
        value, _, (h11, h12, h22) = distance.terms(lo, hi)
        det = h11 * h22 - h12 * h12
    convex = (h11.lo > 0) & (det.lo > 0) & (value.hi < distance.upper.lo)
    concave = (h11.hi < 0) & (det.lo > 0) & (value.lo > distance.lower.hi)
    # a box that meets a face of Q that is not glued (a stop) attaches nothing
    stops = np.ones(tree.ndim, dtype=bool)
    stops[list(tree.periodic)] = False
    on_stop = ((b_lo == 0) | (b_hi == extent))[:, stops].any(axis=1)
    usable = (convex | concave) & ~on_stop
    if branch is not None and usable.any():
        # the ray argument knows d^2 alone: the constraints must hold over all B
        usable[usable] = branch.inside(lo[usable], hi[usable])
    for j in np.flatnonzero(usable):
        if out[leaf[j]]:
            continue
        inside = ((anchors >= b_lo[j]) & (ends <= b_hi[j])).all(axis=1)
        # the leaves across B's boundary: neighbours of leaves in B, outside B
        cross = inside[pairs[:, 0]] & ~inside[pairs[:, 1]]
        if done[pairs[cross, 1]].all():
            out |= inside & ~done
    return out


def _witnesses(
    leaves: Any,
    volumes: Array,
    labels: NDArray[np.int64],
    n: int,
    blocks: list[StopBlock],
    distance: Any,
) -> NDArray[np.float64]:
    """(n, k): a joint vector of D in each of the ``n`` certain components
    (``labels`` over the leaves, then the pieces of the stop ``blocks``, -1 for
    nodes of none): the centre of its largest IN cell, or where it has none, a
    point of D of its first piece (:meth:`StopBlock.points`)."""
    n_leaves = volumes.size
    out = np.full((n, leaves.lo.shape[1]), np.nan)
    cells = labels[:n_leaves]
    inside = np.flatnonzero(cells >= 0)
    # the largest cell of each label: sort by label, then by decreasing volume
    order = inside[np.lexsort((-volumes[inside], cells[inside]))]
    first = order[np.r_[True, cells[order][1:] != cells[order][:-1]]] if order.size else order
    out[cells[first]] = 0.5 * (leaves.lo[first] + leaves.hi[first])
    pieces = labels[n_leaves:]
    bare = np.ones(n, dtype=bool)
    bare[cells[inside]] = False
    if not bare.any():
        return out
    points = np.concatenate([block.points(distance.classify) for block in blocks])
    for p in np.flatnonzero(pieces >= 0)[::-1]:
        if bare[pieces[p]]:
            out[pieces[p]] = points[p]
    return out


#: an open part of Q narrower than this share of each joint's range is taken for a
#: point where the design is degenerate (the refinement reaches 2^-26 of a range)
_POINT_SHARE = 1e-6


def _degenerate_notes(
    mechanism: Mechanism, lo: Array, hi: Array, spans: Array
) -> tuple[str, ...]:
    """A line where the count stays open only about one point of Q (the leaves of
    ``lo``, ``hi`` within ``_POINT_SHARE`` of each range ``spans``): the design
    is exactly degenerate there (a joint stop at a parallel singularity, a
    tangency), or within that distance of it; none otherwise."""
    if not lo.shape[0]:
        return ()
    box_lo, box_hi = lo.min(axis=0), hi.max(axis=0)
    if not ((box_hi - box_lo) <= _POINT_SHARE * spans).all():
        return ()
    centre = 0.5 * (box_lo + box_hi)
    where = ", ".join(
        f"{name} = {v:.9g}" for name, v in zip(mechanism.joint_names, centre, strict=True)
    )
    width = float((box_hi - box_lo).max())
    return (
        f"degenerate design: the count stays open only within {width:.1g} of {where}, "
        "where the boundary of the non-singular joint set meets a joint stop or itself "
        "(a stop at a parallel singularity, or a tangency); no precision decides it",
    )


def _trace_notes(
    mechanism: Mechanism, degenerate: list[tuple[int, float, float]], decided: bool
) -> tuple[str, ...]:
    """A line where the count stays open and a stop trace failed on a degenerate
    point (see :func:`~moveability.analysis.stop_traces.trace_runs`); none
    otherwise."""
    if decided or not degenerate:
        return ()
    axis, stop, t = degenerate[0]
    names = mechanism.joint_names
    return (
        f"degenerate design: the boundary of the non-singular joint set touches the "
        f"stop {names[axis]} = {stop:.9g} at {names[1 - axis]} = {t:.9g}, exactly or "
        "within one float (undecided there at 424 bits); no precision decides it",
    )


def witness_configurations(
    mechanism: Mechanism, joints: Array
) -> tuple[NDArray[np.float64], NDArray[np.int8]]:
    """The configurations of the joints ``joints`` (m, n_joints) with det A != 0: for
    the joints of a certified cell of Q (:attr:`JointSpaceCount.witnesses`), one
    of each sign of det A, each in a region of its own.

    Returns
    -------
    poses : (m, 2, k) array
        The two poses of each joint vector (NaN where none is found).
    signs : (m, 2) int8
        The sign of det A at each (0 where it could not be told).

    Examples
    --------
    >>> import numpy as np
    >>> from moveability.mechanisms import FiveBar
    >>> m = FiveBar(7, 8, 5, 8, 5)
    >>> poses, signs = witness_configurations(m, np.array([[1.0, 2.0]]))
    >>> q = np.repeat([[1.0, 2.0]], 2, axis=0)
    >>> bool(np.abs(m.constraints(poses[0], q)).max() < 1e-9), sorted(signs[0].tolist())
    (True, [-1, 1])
    """
    condition = joint_condition(mechanism)
    joints = np.asarray(joints, dtype=np.float64).reshape(-1, len(mechanism.limits))
    poses = (
        np.full((joints.shape[0], 2, len(mechanism.pose_names)), np.nan)
        if condition is None
        else condition.poses(joints)
    )
    q = np.repeat(joints, 2, axis=0)
    with np.errstate(invalid="ignore"):
        det = mechanism.det_a(poses.reshape(q.shape[0], -1), q).reshape(-1, 2)
    signs = np.where(np.isfinite(det), np.sign(det), 0).astype(np.int8)
    return poses, signs


def count_in_joint_space(
    mechanism: Mechanism,
    *,
    max_depth: int | None = None,
    max_leaves: int | None = None,
    closed_form: bool = True,
    stop_traces: bool = True,
) -> JointSpaceCount | None:
    """Certified bounds on the number of regions of a two-dyad mechanism or a Delta.

    Returns None for other mechanisms (see :func:`joint_condition`). The tree
    of Q starts uniform at depth ``START_DEPTH`` (``START_DEPTH_3D`` for three
    joints) and is refined where the count stays open, one level a round, to
    ``max_depth`` per axis (by default ``MAX_DEPTH``, or ``MAX_DEPTH_3D``) or
    ``max_leaves`` leaves (by default ``MAX_LEAVES``, or ``MAX_LEAVES_3D``): a
    deterministic budget. Where the mechanism decides D in closed form (the
    biglide's ``exact_region_count``) that count is given, unless
    ``closed_form`` is False. With two joints, boxes on a stop where D's
    boundary nears it tangentially are decided by D's trace on the stop
    (:mod:`moveability.analysis.stop_traces`), unless ``stop_traces`` is False.

    Notes
    -----
    Each round costs the leaves of the tree (labelling and attachment); the
    leaves split are those of the open possible components alone, and their
    number follows the boundary of D there.

    Examples
    --------
    >>> import numpy as np
    >>> from moveability.limits import JointLimit
    >>> from moveability.mechanisms import FiveBar
    >>> paper = FiveBar(7, 8, 5, 8, 5, (JointLimit(0, np.pi), JointLimit(0, np.pi)))
    >>> found = count_in_joint_space(paper)
    >>> found.at_least, found.at_most
    (2, 2)
    """
    distance = joint_condition(mechanism)
    if distance is None:
        return None
    if not mechanism.restrictions.empty:
        return _count_branches(mechanism, distance, max_depth, max_leaves)
    exact = mechanism.exact_region_count() if closed_form else None
    if exact is not None:
        # D decided in closed form (the biglide's bands)
        n, witnesses, notes = exact
        return JointSpaceCount(2 * n, 2 * n, 0, 0.0, witnesses, notes)
    found = _count(mechanism, distance, max_depth, max_leaves, stop_traces)
    if stop_traces and not found.decided and len(mechanism.limits) == 2:
        # the traces' boxes are never split: where they leave the count open, the
        # plain refinement may still close it (both bounds are proved)
        plain = _count(mechanism, distance, max_depth, max_leaves, False)
        if plain.decided:
            return plain
        tops = [c.at_most for c in (found, plain) if c.at_most is not None]
        return JointSpaceCount(
            at_least=max(found.at_least, plain.at_least),
            at_most=min(tops) if tops else None,
            leaves=found.leaves,
            open_measure=found.open_measure,
            witnesses=found.witnesses,
            notes=found.notes,
        )
    return found


def _count_branches(
    mechanism: Mechanism, distance: Any, max_depth: int | None, max_leaves: int | None
) -> JointSpaceCount:
    """:func:`count_in_joint_space` with constraints: the components of D_+ and of
    D_- (see :mod:`moveability.analysis.joint_branches`), each witness standing
    for its own branch."""
    branches = [BranchCondition(mechanism, distance, s) for s in (1, -1)]
    found = [_count(mechanism, distance, max_depth, max_leaves, False, b) for b in branches]
    tops = [c.at_most for c in found]
    k = len(mechanism.limits)
    witnesses = np.concatenate([c.witnesses.reshape(-1, k) for c in found])
    first = found[0].witnesses.reshape(-1, k).shape[0]
    poses = np.zeros((witnesses.shape[0], 2), dtype=bool)
    poses[:first, 0] = True
    poses[first:, 1] = True
    return JointSpaceCount(
        at_least=sum(c.at_least for c in found),
        at_most=None if None in tops else sum(t for t in tops if t is not None),
        leaves=sum(c.leaves for c in found),
        open_measure=sum(c.open_measure for c in found),
        witnesses=witnesses,
        witness_poses=poses,
    )


def _count(
    mechanism: Mechanism,
    distance: Any,
    max_depth: int | None,
    max_leaves: int | None,
    stop_traces: bool,
    branch: BranchCondition | None = None,
) -> JointSpaceCount:
    """:func:`count_in_joint_space` on the tree of Q, with or without stop traces;
    with a ``branch``, the components of its D_s (counted once, not twice)."""
    condition = distance if branch is None else branch
    copies = 2 if branch is None else 1
    # the flows of each cell, found once over the rounds
    cache: _FlowCache = {}
    lo, hi, periodic = _joint_box(mechanism)
    k = lo.size
    if max_leaves is None:
        max_leaves = MAX_LEAVES if k == 2 else MAX_LEAVES_3D
    if max_depth is None:
        max_depth = MAX_DEPTH if k == 2 else MAX_DEPTH_3D
    tree = HyperTree.build(
        lo,
        hi,
        condition.classify,
        max_depth=max_depth,
        periodic=periodic,
        merge=False,
        stop_level=START_DEPTH if k == 2 else START_DEPTH_3D,
        max_leaves=max_leaves,
    )
    # boxes on a stop decided by D's trace there (two joints), and those that failed
    blocks: list[StopBlock] = []
    failed: set[tuple[int, int, int]] = set()
    degenerate: list[tuple[int, float, float]] = []
    while True:
        leaves = tree.leaves()
        member = block_members(tree, blocks)
        settled = member >= 0
        undecided = (tree.status == BOUNDARY) & ~settled
        loose = undecided & ~_attached(tree, leaves, distance, settled, branch, cache)
        # closed cells touching at a corner: the IN ones share a point of D (open)
        if blocks:
            pairs = adjacency(tree, status=IN | BOUNDARY, connectivity=k)
            possible, n_possible, certain, n_certain = block_labels(
                tree, leaves, blocks, member, pairs
            )
        else:
            possible, n_possible = components(tree, status=IN | BOUNDARY, connectivity=k)
            certain, n_certain = components(tree, status=IN, connectivity=k)
        # certain components per possible component, and possible ones left loose
        inside = np.flatnonzero(certain >= 0)
        owner = np.full(n_certain, -1, dtype=np.int64)
        owner[certain[inside]] = possible[inside]
        per = np.bincount(owner, minlength=n_possible)
        has_loose = np.zeros(n_possible, dtype=bool)
        of_leaf = possible[: len(tree)]
        has_loose[of_leaf[loose]] = True
        at_least = int((per > 0).sum())
        at_most = None if loose.any() else n_certain
        open_parts = has_loose | (per >= 2)
        mask = undecided & (of_leaf >= 0)
        mask[mask] = open_parts[of_leaf[mask]]
        volumes = np.prod(leaves.hi - leaves.lo, axis=1)
        open_measure = float(volumes[mask].sum())
        # refined: the loose cells, and every undecided cell of a component that
        # holds several certified ones (they join there, or it splits); the other
        # undecided cells are attached already
        several = np.zeros(mask.size, dtype=bool)
        several[mask] = (per >= 2)[of_leaf[mask]]
        mask &= several | loose
        if at_least != at_most and k == 2 and stop_traces:
            # where D meets a stop, its trace there may decide what no cell does
            new = find_blocks(tree, distance, np.flatnonzero(mask), blocks, failed, degenerate)
            if new:
                blocks.extend(new)
                continue
        still = mask.copy()
        mask &= tree.levels < tree.layout.n_levels
        room = (max_leaves - len(tree)) // ((1 << k) - 1)
        if at_least == at_most or not mask.any() or int(mask.sum()) > room:
            return JointSpaceCount(
                at_least=copies * at_least,
                at_most=None if at_most is None else copies * at_most,
                leaves=len(tree),
                open_measure=open_measure,
                witnesses=_witnesses(leaves, volumes, certain, n_certain, blocks, distance),
                notes=_degenerate_notes(mechanism, leaves.lo[still], leaves.hi[still], hi - lo)
                or _trace_notes(mechanism, degenerate, at_least == at_most),
            )
        tree = tree.refine(mask, condition.classify)
