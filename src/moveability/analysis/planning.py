"""Planning a motion through given poses inside one region R_j.

The motion follows a shortest chain of the certain graph (see
:mod:`moveability.analysis.regions`) between certified sheets holding the poses. Within
a leaf whose sheet is certified the pose moves along straight segments (the
leaf is convex, and every configuration of the sheet over it is valid). Within
a leaf where a leg folds, it moves through the mechanism's hub and fold point
of the leaf, and the posture changes at the fold point, where the branches
meet. Joint angles come from the closed-form inverse kinematics of the current
posture; segments are subdivided until consecutive configurations are at most
``step`` apart in pose and in every joint.

That chain of cells zigzags. By default it is then shortened and smoothed
(:mod:`moveability.analysis.smoothing`): each stretch of one posture is cut
short by straight shortcuts and its corners are rounded, every new segment
proved valid over boxes covering it; the poses asked and the posture changes
stay where the chain put them.
"""

from __future__ import annotations

import itertools
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.sparse.csgraph import breadth_first_order

from ..errors import InvalidParameterError, PlanningError
from ..hypertree.measurement import locate
from ..hypertree.status import IN
from ..mechanisms.base import REGULAR
from ..types import Array
from .sheets import classify_sheets
from .smoothing import path_length, smooth_path

if TYPE_CHECKING:
    from ..hypertree.tree import Leaves
    from .result import Analysis

__all__ = ["PlanningError", "default_poses", "plan_motion"]

#: proofs of shortcuts bisect their boxes down to the analysis precision over this
_REFINE = 8.0
#: passes of shortening and smoothing
_PASSES = 2


def _start_nodes(analysis: Analysis, point: Array, leaf: int, component: int) -> list[int]:
    """Certified nodes of ``component`` over ``leaf`` holding a configuration of ``point``."""
    t, g = analysis.table, analysis.graph
    n_post = t.status.shape[1]
    # the sheet certificates at the pose itself (a degenerate box)
    point_table = classify_sheets(analysis.mechanism, point[None, :], point[None, :])
    regular_here = bool((point_table.leg_status[0] == REGULAR).all())
    nodes = []
    for p in range(n_post):
        if g.certain[leaf, p] != component:
            continue
        if t.status[leaf, p] == IN or (t.group[leaf, p] and regular_here):
            nodes.append(leaf * n_post + p)
    # prefer regular sheets
    nodes.sort(key=lambda node: t.status[node // n_post, node % n_post] != IN)
    return nodes


def _route(analysis: Analysis, start: int, goal: int) -> list[int]:
    _order, pred = breadth_first_order(
        analysis.graph.certain_matrix, start, directed=False, return_predecessors=True
    )
    if pred[goal] < 0 and goal != start:
        raise PlanningError("the certified part of the region does not join the poses")
    path = [goal]
    while path[-1] != start:
        path.append(int(pred[path[-1]]))
    return path[::-1]


def _touching(
    analysis: Analysis, leaves: Leaves, lo_u: Array, hi_u: Array, leaf: int, offset: Array
) -> Array:
    """The shift of ``leaf`` (by whole turns of the periodic axes, near ``offset``) that
    makes it touch the box ``[lo_u, hi_u]``: paths cross the seam of a periodic axis."""
    shift = offset.copy()
    for axis in analysis.mechanism.periodic_axes:
        for turns in (0.0, -1.0, 1.0):
            c = offset[axis] + turns * 2.0 * np.pi
            lo_v, hi_v = leaves.lo[leaf, axis] + c, leaves.hi[leaf, axis] + c
            gap = max(lo_v - hi_u[axis], lo_u[axis] - hi_v)
            if gap <= 1e-9:
                shift[axis] = c
                break
    return shift


def _reachable_pose(analysis: Analysis, lo: Array, hi: Array) -> Array:
    """A pose of the common boundary ``[lo, hi]`` of two fold leaves that every leg
    reaches: its middle, else the first corner that is (their contact is certified
    to hold reachable poses: a fold certificate's reachable corner)."""
    k = lo.size
    corners = np.where((np.arange(1 << k)[:, None] >> np.arange(k)) & 1, hi, lo)
    candidates = np.vstack([0.5 * (lo + hi)[None, :], corners])
    q = analysis.mechanism.joint_angles(candidates, clip=False)
    reached = np.isfinite(q.reshape(candidates.shape[0], -1)).all(axis=1)
    if not reached.any():
        raise PlanningError("no reachable pose found where two fold leaves touch")
    return np.asarray(candidates[int(np.argmax(reached))])


class _Fold:
    """How a motion crosses a leaf where one leg's branches meet (a certified fold).

    Either the leaf's reachable part is star-shaped about a hub (``hub`` and
    ``point`` from the mechanism's ``fold_waypoints``), or it is a union of
    segments along one axis anchored on a reachable face (the leg's
    ``fold_anchor`` and ``fold_path``).
    """

    def __init__(self, analysis: Analysis, leaves: Leaves, leaf: int, offset: Array) -> None:
        t = analysis.table
        self.lo, self.hi, self.offset = leaves.lo[leaf], leaves.hi[leaf], offset
        legs = tuple(int(i) for i in np.flatnonzero(t.folding[leaf]))
        self.leg: Any = None
        if len(legs) == 1 and hasattr(analysis.mechanism.legs[legs[0]], "fold_path"):
            self.leg = analysis.mechanism.legs[legs[0]]
            return
        statuses = tuple(int(t.leg_status[leaf, i]) for i in legs)
        self.hub, self.point = analysis.mechanism.fold_waypoints(legs, self.lo, self.hi, statuses)

    def through(self, a: Array, b: Array) -> list[Array]:
        """Poses between ``a`` and ``b`` (both reachable, in the leaf) to go through."""
        if self.leg is None:
            return [self.hub + self.offset]
        off = self.offset
        return [
            self.leg.fold_anchor(self.lo, self.hi, a - off) + off,
            self.leg.fold_anchor(self.lo, self.hi, b - off) + off,
        ]

    def change(self, at: Array, pu: int, pv: int) -> tuple[list[tuple[Array, int]], Array]:
        """Waypoints changing posture from ``pu`` to ``pv``, and the pose reached."""
        if self.leg is None:
            hub, point = self.hub + self.offset, self.point + self.offset
            return [(hub, pu), (point, pu), (point, pv), (hub, pv)], hub
        # the path's poses are reachable and joined by reachable segments; its last
        # one is a fold pose: there and back, the posture changed at the fold
        path = self.leg.fold_path(self.lo, self.hi, at - self.offset) + self.offset
        there = [(pose, pu) for pose in path[1:]]
        back = [(pose, pv) for pose in path[-2::-1]]
        return [*there, (path[-1], pv), *back], at


def _waypoints(
    analysis: Analysis,
    leaves: Leaves,
    nodes: list[int],
    begin: Array,
    end: Array,
    offset: Array,
) -> tuple[list[tuple[Array, int]], Array]:
    """Poses and postures between which the pose moves in straight segments.

    Consecutive waypoints lie in one closed leaf: a leaf whose sheet is certified
    is convex, and the reachable part of a fold leaf is crossed as :class:`_Fold`
    says. Poses are unwrapped: a path crossing the seam of a periodic angle goes
    on past it, the leaves being shifted by whole turns (``offset`` for the first
    leaf; the offset of the last one is returned with the waypoints).
    """
    t = analysis.table
    n_post = t.status.shape[1]

    def fold(leaf: int) -> _Fold | None:
        return _Fold(analysis, leaves, leaf, offset) if t.folding[leaf].any() else None

    current = begin + offset
    out: list[tuple[Array, int]] = [(current, nodes[0] % n_post)]
    for u, v in itertools.pairwise(nodes):
        lu, pu = divmod(u, n_post)
        lv, pv = divmod(v, n_post)
        here = fold(lu)
        if lu == lv:
            # a posture change inside a certified fold group, at a fold pose
            assert here is not None
            steps, current = here.change(current, pu, pv)
            out += steps
            continue
        # through the middle of the face (edge, corner) the two leaves share
        lo_u, hi_u = leaves.lo[lu] + offset, leaves.hi[lu] + offset
        shift = _touching(analysis, leaves, lo_u, hi_u, lv, offset)
        lo_v, hi_v = leaves.lo[lv] + shift, leaves.hi[lv] + shift
        face_lo, face_hi = np.maximum(lo_u, lo_v), np.minimum(hi_u, hi_v)
        if here is not None and t.folding[lv].any():
            # between two fold leaves the middle may be beyond the reach
            shared = _reachable_pose(analysis, face_lo, face_hi)
        else:
            shared = 0.5 * (face_lo + face_hi)
        if here is not None:
            out += [(pose, pu) for pose in here.through(current, shared)]
        out.append((shared, pu))
        current, offset = shared, shift
    last_leaf, last_posture = divmod(nodes[-1], n_post)
    here = fold(last_leaf)
    if here is not None:
        out += [(pose, last_posture) for pose in here.through(current, end + offset)]
    out.append((end + offset, last_posture))
    return out, offset


def _joints(analysis: Analysis, poses: Array, postures: NDArray[np.intp]) -> Array:
    """Joint angles of each pose in its posture."""
    # the poses of a plan are certified reachable: forgive the rounding at folds
    q = analysis.mechanism.joint_angles(poses, clip=True)
    return q[np.arange(poses.shape[0]), np.asarray(postures, dtype=np.intp)]


def _joint_moves(analysis: Analysis, dq: Array) -> Array:
    """How far each joint moves for joint differences ``dq``: a revolute joint by the
    shorter way round, a prismatic one by the difference."""
    turn = np.abs(np.angle(np.exp(1j * dq)))
    prismatic = np.array([lim.prismatic for lim in analysis.mechanism.limits], dtype=bool)
    return np.where(prismatic, np.abs(dq), turn)


def _walk(
    analysis: Analysis, vertices: Array, postures: NDArray[np.intp], step: float
) -> tuple[Array, NDArray[np.intp], NDArray[np.intp]]:
    """The motion along straight segments between ``vertices`` (each segment in the
    posture of its end), consecutive configurations within ``step`` in pose and in
    every joint; with the index in it of each vertex.

    Each segment is cut evenly to the step in pose, then pieces where a joint moves
    more are halved until none does; all segments at once, since the inverse
    kinematics of some legs costs most per call.
    """
    a, b = vertices[:-1], vertices[1:]
    if not a.shape[0]:
        return vertices, postures, np.zeros(1, dtype=np.intp)
    counts = np.maximum(1, np.ceil(np.linalg.norm(b - a, axis=1) / step)).astype(np.intp)
    seg = np.repeat(np.arange(a.shape[0]), counts + 1)
    s = np.concatenate([np.linspace(0.0, 1.0, c + 1) for c in counts])
    for _ in range(60):
        poses = a[seg] + s[:, None] * (b - a)[seg]
        q = _joints(analysis, poses, postures[1:][seg])
        jump = _joint_moves(analysis, np.diff(q, axis=0)).max(axis=1)
        bad = np.flatnonzero((jump > step) & (seg[1:] == seg[:-1]))
        if not bad.size:
            break
        seg = np.concatenate([seg, seg[bad]])
        s = np.concatenate([s, 0.5 * (s[bad] + s[bad + 1])])
        order = np.lexsort((s, seg))
        seg, s = seg[order], s[order]
    else:
        raise PlanningError("could not subdivide a segment to the requested step")
    # a segment's start is the previous one's end, or the first vertex
    later = s > 0.0
    out = np.concatenate([vertices[:1], poses[later]])
    post = np.concatenate([postures[:1], postures[1:][seg[later]]]).astype(np.intp)
    per_segment = np.bincount(seg[later], minlength=a.shape[0])
    at = np.concatenate([[0], np.cumsum(per_segment)]).astype(np.intp)
    return out, post, at


def _chain(
    analysis: Analysis, p: Array, component: int
) -> tuple[Array, NDArray[np.intp], NDArray[np.intp]]:
    """Corners of the motion along the certain graph through the poses ``p``: poses,
    postures, and the index of the corner where each pose is reached."""
    n_post = analysis.table.status.shape[1]
    leaves = analysis.tree.leaves()
    _, leaf = locate(analysis.tree, p)
    current = _start_nodes(analysis, p[0], int(leaf[0]), component)[0]
    corners: list[tuple[Array, int]] = [(p[0], current % n_post)]
    reached = [0]
    offset = np.zeros(p.shape[1])
    for i in range(1, p.shape[0]):
        goals = _start_nodes(analysis, p[i], int(leaf[i]), component)
        route = _route(analysis, current, goals[0])
        waypoints, offset = _waypoints(analysis, leaves, route, p[i - 1], p[i], offset)
        corners += waypoints[1:]
        reached.append(len(corners) - 1)
        current = route[-1]
    poses = np.stack([c[0] for c in corners])
    postures = np.array([c[1] for c in corners], dtype=np.intp)
    return poses, postures, np.array(reached, dtype=np.intp)


def _lengths(analysis: Analysis, poses: Array, joints: Array) -> tuple[float, float]:
    """Euclidean length of a motion in pose coordinates and in joint coordinates."""
    dq = _joint_moves(analysis, np.diff(joints, axis=0))
    return path_length(poses), float(np.linalg.norm(dq, axis=1).sum())


def plan_motion(
    analysis: Analysis, points: ArrayLike, step: float | None = None, smooth: bool = True
) -> dict[str, Any]:
    """A continuous motion through ``points`` in order, inside one region.

    The motion first follows a chain of cells of the certain graph (it
    zigzags from cell to cell). With ``smooth``, every stretch of it that
    keeps one posture is then shortened by straight shortcuts and its corners
    are cut, each new segment proved valid by interval arithmetic over boxes
    covering it (see :mod:`moveability.analysis.smoothing`); posture changes
    and the poses asked stay where they were.

    Parameters
    ----------
    analysis : Analysis
        The analysis of the mechanism.
    points : array_like, shape (m, k)
        The poses to pass through, in order.
    step : float, optional
        Consecutive configurations are at most ``step`` apart in pose and in
        each joint (default: the smallest precision of the analysis).
    smooth : bool, default True
        Shorten and smooth the motion; False gives the chain of cells as it is.

    Returns
    -------
    dict
        ``{"feasible": True, "region": id, "path": [{"pose", "joints",
        "posture"}, ...], "waypoints": [index, ...], "length": {"pose":
        {"before", "after"}, "joints": {"before", "after"}}}``. Every
        configuration satisfies the constraints, keeps the region's sign of
        det A and respects the limits. ``waypoints`` holds the index in
        ``path`` where each pose asked is reached (the first is 0, the last
        ``len(path) - 1``). ``length`` gives the Euclidean length of the
        motion in pose coordinates and in joint coordinates, before and after
        smoothing (equal without it). Periodic pose angles are continuous
        along the path: a pose may be reached one or more whole turns away
        from the value asked.

    Raises
    ------
    PlanningError
        When no region is known to hold every pose (exit 3 in the CLI).
    InvalidParameterError
        When ``step`` is not a positive length.

    Notes
    -----
    Shortcutting is greedy: from each kept configuration, the farthest later
    one of the same stretch that a proved shortcut reaches, found by doubling
    and then narrowing down (a few batches of proofs per kept configuration,
    the stretches sharing each batch). Three rounds of corner cutting follow;
    then a second pass of both over the result. Each proof bisects the boxes
    covering a segment down to an eighth of the analysis precision along each
    axis, so a shortcut that only a finer look would prove is not taken. The
    cost is a few dozen calls of
    :func:`~moveability.analysis.sheets.classify_sheets`, on batches of boxes.

    Examples
    --------
    >>> from moveability import analyze
    >>> from moveability.mechanisms import FiveBar
    >>> result = analyze(FiveBar(), precision=0.2)
    >>> motion = plan_motion(result, [[1.0, 3.0], [5.0, 3.0]])
    >>> motion["feasible"], motion["path"][0]["pose"], motion["waypoints"][0]
    (True, [1.0, 3.0], 0)
    >>> motion["length"]["pose"]["after"] <= motion["length"]["pose"]["before"]
    True
    """
    points = analysis.as_poses(points)
    step = _check_step(analysis, step)
    answer = analysis.feasible(points)
    if not answer["feasible"]:
        raise PlanningError(_apart_message(analysis, points, answer["feasible"]))
    region = analysis.regions[answer["region"]]
    p = np.asarray(points, dtype=np.float64).reshape(-1, len(analysis.mechanism.pose_names))
    corners, corner_postures, reached = _chain(analysis, p, region.certain)
    poses, postures, at = _walk(analysis, corners, corner_postures, step)
    joints = _present(analysis, _joints(analysis, poses, postures))
    waypoints = at[reached]
    before = _lengths(analysis, poses, joints)
    if smooth:
        fixed = np.zeros(poses.shape[0], dtype=bool)
        fixed[waypoints] = True
        corners, corner_postures, origin = smooth_path(
            analysis.mechanism,
            poses,
            postures,
            fixed,
            region.sign,
            resolution=analysis.precisions / _REFINE,
            passes=_PASSES,
            spacing=step,
        )
        poses, postures, at = _walk(analysis, corners, corner_postures, step)
        where = {int(o): int(a) for o, a in zip(origin, at, strict=True) if o >= 0}
        waypoints = np.array([where[int(w)] for w in waypoints], dtype=np.intp)
        joints = _present(analysis, _joints(analysis, poses, postures))
    after = _lengths(analysis, poses, joints)
    _check(analysis, poses, joints, region.sign)
    return {
        "feasible": True,
        "region": region.id,
        "path": [
            {
                "pose": [float(v) for v in poses[k]],
                "joints": [float(v) for v in joints[k]],
                "posture": analysis.mechanism.posture_name(int(postures[k])),
            }
            for k in range(poses.shape[0])
        ],
        "waypoints": [int(w) for w in waypoints],
        "length": {
            "pose": {"before": before[0], "after": after[0]},
            "joints": {"before": before[1], "after": after[1]},
        },
    }


def _check_step(analysis: Analysis, step: float | None) -> float:
    if step is None:
        return float(analysis.precisions.min())
    try:
        value = float(step)
    except (TypeError, ValueError):
        raise InvalidParameterError("step", "a positive length", step) from None
    if not (np.isfinite(value) and value > 0):
        raise InvalidParameterError("step", "a positive length", step)
    return value


def _present(analysis: Analysis, joints: Array) -> Array:
    """Joint values as the joints read them: in their range, or continuous if unlimited."""
    out = joints.copy()
    for i, lim in enumerate(analysis.mechanism.limits):
        if lim.periodic:
            out[:, i] = np.unwrap(joints[:, i])
        else:
            out[:, i] = lim.wrap(joints[:, i])
    return out


def _check(analysis: Analysis, poses: Array, joints: Array, sign: int) -> None:
    """Every configuration solves the constraints, has det A of ``sign`` and is within
    the limits: a failure is a bug, reported as such."""
    m = analysis.mechanism
    with np.errstate(invalid="ignore"):  # NaN where a pose would be unreachable
        residual = float(np.abs(m.constraints(poses, joints)).max())
        det = m.det_a(poses, joints)
        within = all(bool(lim.contains(joints[:, i]).all()) for i, lim in enumerate(m.limits))
        # passive limits, obstacles, collisions: certified at each configuration
        within &= bool(m.constraints_hold(poses, joints).all())
    if not (residual <= 1e-9 and (np.sign(det) == sign).all() and within):
        signs = sorted({"nan" if np.isnan(d) else f"{int(np.sign(d)):+d}" for d in det})
        raise PlanningError(
            f"internal check failed (residual {residual:.3g}, det A signs {signs}, "
            f"within limits {within})"
        )


def _apart_message(analysis: Analysis, points: Array, feasible: bool | None) -> str:
    p = np.asarray(points, dtype=np.float64).reshape(-1, len(analysis.mechanism.pose_names))
    located = analysis.locate(p)["points"]
    outside = [i for i, a in enumerate(located) if a["workspace"] is False]
    if outside:
        return f"pose(s) {outside} lie outside the workspace"
    if feasible is False:
        for i in range(len(located)):
            for j in range(i + 1, len(located)):
                if analysis.feasible(p[[i, j]])["feasible"] is False:
                    return f"poses {i} and {j} lie in no common region"
        return "the poses lie in no common region"
    return "the precision cannot tell whether one region holds every pose; try a finer precision"


def default_poses(analysis: Analysis) -> Array:
    """Two far-apart poses certainly in the largest region (to show a motion when
    none is asked).

    Examples
    --------
    >>> from moveability import analyze
    >>> from moveability.mechanisms import FiveBar
    >>> default_poses(analyze(FiveBar(), precision=0.5)).shape
    (2, 2)
    """
    index = max(range(len(analysis.regions)), key=lambda j: analysis.regions[j].area[0])
    leaves = analysis.tree.leaves()
    sure = np.flatnonzero(analysis.region_cells(index)[0])
    centres = 0.5 * (leaves.lo[sure] + leaves.hi[sure])
    a = centres[np.argmin(centres[:, 0])]
    b = centres[np.argmax(centres[:, 0])]
    return np.stack([a, b])
