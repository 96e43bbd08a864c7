"""Boxes of Q against a joint stop, decided by the trace of D on the stop.

Where the boundary of D (see :mod:`moveability.analysis.joint_space`) is tangent
to a joint stop, as when a five-bar's stop meets a parallel singularity
tangentially, the cells of Q about the point of tangency stay undecided at
every depth: D passes there through a channel, or is cut, narrower than any
cell. This module decides such places on the stop itself.

Take a box B of the tree of Q (two joints) with a face on exactly one stop
``q_a = c`` (a joint that is not periodic), and call t the other joint. When
over the closed box B

* only one bound of ``d^2`` may be met (the lower, or the upper), and
* ``d^2`` moves certainly into D (up from the lower bound, down from the
  upper) as ``q_a`` moves toward the stop (``d(d^2)/dq_a`` of a certain sign),

each segment of B across the stop (t fixed) meets D in one interval that
starts on the stop, or not at all: from a point of D, moving toward the stop
keeps ``d^2`` between its bounds. So ``D ∩ B`` is the union of those
intervals over the *trace* ``S = {t : (c, t) in D}``, and it has one
component per run of S, which touches the stop along its run. Such a
component is a certified part of D (a *piece*), and it meets a cell beside B
only where their shared boundary lies over its run.

S is a set of one variable, decided in interval arithmetic at 106 bits, then
212 and 424 (mpmath's ``iv``, with outward rounding): the sign of
``phi(t) = d^2(c, t) - lower`` (or ``upper - d^2(c, t)``) is certified at
breakpoints, and between consecutive ones phi has certainly no zero (a
centred form) or is monotone (its derivative; weakly will do, as phi is
analytic and its zeros isolated), so it changes sign there at most once;
a breakpoint where phi's enclosure is exactly zero (at an angle of 0, say)
is a zero proved. The runs of S are then the runs of breakpoints
where phi > 0. A box where this fails at 424 bits stays undecided: the
design is exactly degenerate there, or within about 1e-120 of it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..hypertree._kernels import edge_components
from ..hypertree.status import BOUNDARY, IN
from ..hypertree.tree import HyperTree, cell_corners
from ..types import Array

__all__ = ["StopBlock", "block_labels", "block_members", "find_blocks", "trace_runs"]

#: working precisions of a trace, in bits
PRECISIONS = (106, 212, 424)
#: most breakpoints in one trace
MAX_BREAKPOINTS = 400
#: most boxes traced in one round
MAX_TRACES = 32

#: phi and its derivative over an interval of t, in an interval context
TraceFunction = Callable[[Any, Any], tuple[Any, Any]]


@dataclass(frozen=True)
class StopBlock:
    """A box of Q on one stop, decided by the runs of D's trace there.

    Attributes
    ----------
    anchor, size : (2,) int64 arrays
        The box in the tree's finest units.
    lo, hi : (2,) float arrays
        The box in joint coordinates.
    axis : int
        The stopped joint (the other one is t).
    value : float
        The stop.
    runs : (m, 5) float array
        One row per run of the trace: an outer range ``[lo, hi]`` of t that holds
        the run and no other, a t of the run (``(value, t)`` lies in D), and
        whether the run holds the box's lower and upper end of t (1.0 or 0.0).
    """

    anchor: NDArray[np.int64]
    size: NDArray[np.int64]
    lo: NDArray[np.float64]
    hi: NDArray[np.float64]
    axis: int
    value: float
    runs: NDArray[np.float64]

    def points(self, classify: Callable[[Array, Array], Array]) -> NDArray[np.float64]:
        """(m, 2): a joint vector of D in each piece: off the stop, the centre of
        the largest of boxes halving toward the stop that ``classify`` finds IN,
        about the run's middle breakpoint (on the stop itself where none is)."""
        m = self.runs.shape[0]
        out = np.empty((m, 2))
        out[:, self.axis] = self.value
        out[:, 1 - self.axis] = self.runs[:, 2]
        a, t = self.axis, 1 - self.axis
        inward = 1.0 if self.value == self.lo[a] else -1.0
        width = float(self.hi[a] - self.lo[a])
        steps = 0.5 ** np.arange(1, 40)
        for p in range(m):
            lo = np.empty((steps.size, 2))
            hi = np.empty((steps.size, 2))
            ends = self.value + inward * width * steps
            lo[:, a], hi[:, a] = np.minimum(self.value, ends), np.maximum(self.value, ends)
            half = 0.5 * width * steps
            lo[:, t] = np.maximum(self.runs[p, 2] - half, self.lo[t])
            hi[:, t] = np.minimum(self.runs[p, 2] + half, self.hi[t])
            found = np.flatnonzero(np.asarray(classify(lo, hi)) == IN)
            if found.size:
                out[p] = 0.5 * (lo[found[0]] + hi[found[0]])
        return out


def trace_runs(
    phi: TraceFunction, t_lo: float, t_hi: float, where: list[float] | None = None
) -> NDArray[np.float64] | None:
    """The runs of ``{t in [t_lo, t_hi] : phi(t) > 0}`` (see the module notes),
    as rows ``(outer lo, outer hi, t inside, holds t_lo, holds t_hi)``; None
    where undecided at every precision. Then ``where``, when given, receives
    the t where the last precision stopped, if phi's sign was undecided there
    or within one float of it (phi is zero there, or within about 1e-120 of
    zero: a degenerate design), and nothing if the breakpoints ran out.

    Examples
    --------
    >>> # (t - 1)^2 - 1e-30 on [0, 3]: positive but on a gap of 2e-15 about t = 1
    >>> f = lambda ctx, t: ((t - 1) ** 2 - ctx.mpf("1e-30"), 2 * (t - 1))
    >>> runs = trace_runs(f, 0.0, 3.0)
    >>> runs.shape[0], float(runs[0, 0]), float(runs[1, 1]), bool(runs[0, 1] <= 1 <= runs[1, 0])
    (2, 0.0, 3.0, True)
    >>> # a double root at 1/3, which no float holds: undecided
    >>> trace_runs(lambda ctx, t: ((3 * t - 1) ** 2, 6 * (3 * t - 1)), 0.0, 1.0) is None
    True
    """
    from mpmath import iv

    saved = iv.prec
    stuck: list[float] = []
    try:
        for bits in PRECISIONS:
            iv.prec = bits
            stuck = []
            found = _runs_at(iv, phi, float(t_lo), float(t_hi), stuck)
            if found is not None:
                return found
    finally:
        iv.prec = saved
    if where is not None:
        where.extend(stuck)
    return None


def _sign(ctx: Any, phi: TraceFunction, t: float) -> int | None:
    """The sign of phi(t): 1, -1, or 0 where its enclosure is exactly zero (a
    zero proved, as at an angle of 0); None where undecided."""
    value, _ = phi(ctx, ctx.mpf(t))
    if value.a > 0:
        return 1
    if value.b < 0:
        return -1
    return 0 if value.a == 0 and value.b == 0 else None


def _settled(ctx: Any, phi: TraceFunction, u: float, v: float, same: bool) -> bool:
    """Whether phi has no zero on [u, v] (``same``: its ends share a sign), or at
    most one (monotone): then it is positive on (u, v) exactly where the ends'
    signs say so, a zero at an end included."""
    box, mid = ctx.mpf([u, v]), ctx.mpf(0.5 * (u + v))
    _, slope = phi(ctx, box)
    # monotone, if only weakly: phi is analytic (a polynomial in the joint, or in
    # its sine and cosine) and not zero throughout, so its zeros are isolated
    if slope.a >= 0 or slope.b <= 0:
        return True
    if not same:
        return False
    centre, _ = phi(ctx, mid)
    centred = centre + slope * (box - mid)
    return bool(centred.a > 0 or centred.b < 0)


def _runs_at(
    ctx: Any, phi: TraceFunction, t_lo: float, t_hi: float, stuck: list[float]
) -> NDArray[np.float64] | None:
    s_lo, s_hi = _sign(ctx, phi, t_lo), _sign(ctx, phi, t_hi)
    if s_lo is None or s_hi is None:
        stuck.append(t_lo if s_lo is None else t_hi)
        return None
    points, signs = [t_lo], [s_lo]
    # left to right: the pieces still to settle, by their right ends
    stack = [(t_hi, s_hi)]
    while stack:
        v, s_v = stack[-1]
        u, s_u = points[-1], signs[-1]
        if _settled(ctx, phi, u, v, s_u == s_v):
            points.append(v)
            signs.append(s_v)
            stack.pop()
            continue
        if len(points) + len(stack) > MAX_BREAKPOINTS:
            return None
        m = 0.5 * (u + v)
        s_m = _sign(ctx, phi, m) if u < m < v else None
        if s_m is None:
            stuck.append(m)
            return None
        stack.append((m, s_m))
    runs = []
    n = len(points)
    i = 0
    while i < n:
        if signs[i] <= 0:
            i += 1
            continue
        j = i
        while j + 1 < n and signs[j + 1] > 0:
            j += 1
        runs.append(
            (
                points[i - 1] if i else t_lo,
                points[j + 1] if j + 1 < n else t_hi,
                points[(i + j) // 2],
                float(i == 0),
                float(j == n - 1),
            )
        )
        i = j + 1
    return np.array(runs, dtype=np.float64).reshape(-1, 5)


def _trace_function(distance: Any, axis: int, value: float, lower: bool) -> TraceFunction:
    """phi on the stop ``q_axis = value`` (see the module notes), from the legs'
    ``knee_exact``."""
    legs = distance.legs
    b1, b2 = (float(leg.distal) for leg in legs)
    t_axis = 1 - axis

    def phi(ctx: Any, t: Any) -> tuple[Any, Any]:
        q = [t, t]
        q[axis] = ctx.mpf(value)
        (p1, v1), (p2, v2) = (leg.knee_exact(q[i], ctx) for i, leg in enumerate(legs))
        dx, dy = p1[0] - p2[0], p1[1] - p2[1]
        d2 = dx**2 + dy**2
        if t_axis == 0:
            slope = 2 * (dx * v1[0] + dy * v1[1])
        else:
            slope = -2 * (dx * v2[0] + dy * v2[1])
        if lower:
            return d2 - (ctx.mpf(b1) - ctx.mpf(b2)) ** 2, slope
        return (ctx.mpf(b1) + ctx.mpf(b2)) ** 2 - d2, -slope

    return phi


def block_members(tree: HyperTree, blocks: list[StopBlock]) -> NDArray[np.int64]:
    """The block holding each leaf (-1: none)."""
    member = np.full(len(tree), -1, dtype=np.int64)
    if not blocks:
        return member
    anchors = tree.anchors
    ends = anchors + tree.layout.cell_sizes(tree.levels)
    for b, block in enumerate(blocks):
        inside = ((anchors >= block.anchor) & (ends <= block.anchor + block.size)).all(axis=1)
        member[inside] = b
    return member


def find_blocks(
    tree: HyperTree,
    distance: Any,
    candidates: NDArray[np.intp],
    blocks: list[StopBlock],
    failed: set[tuple[int, int, int]],
    degenerate: list[tuple[int, float, float]] | None = None,
) -> list[StopBlock]:
    """New blocks about the leaves ``candidates`` (undecided, outside ``blocks``):
    for each, the coarsest box above it that meets the conditions of the module
    notes, traced; boxes whose trace failed are added to ``failed`` (keys
    ``(level, anchor_0, anchor_1)``) and not traced again, and where a trace
    failed on a degenerate point (see :func:`trace_runs`), ``degenerate``
    receives ``(stopped joint, stop, t)``."""
    if tree.ndim != 2 or not candidates.size:
        return []
    extent = np.left_shift(np.int64(1), np.asarray(tree.max_depth, dtype=np.int64))
    stops = np.ones(2, dtype=bool)
    stops[list(tree.periodic)] = False
    if not stops.any():
        return []
    anchors = tree.anchors[candidates]
    levels = tree.levels[candidates].astype(np.int64)
    ups = np.arange(int(levels.max()) + 1)
    leaf = np.repeat(np.arange(candidates.size), ups.size)
    level = levels[leaf] - np.tile(ups, candidates.size)
    keep = level >= 0
    leaf, level = leaf[keep], level[keep]
    size = tree.layout.cell_sizes(level)
    b_lo = (anchors[leaf] // size) * size
    b_hi = b_lo + size
    lo, hi = cell_corners(tree.lo, tree.hi, tree.layout, b_lo, level)
    # on the faces of Q, the limits themselves
    lo = np.where(b_lo == 0, tree.lo, lo)
    hi = np.where(b_hi == extent, tree.hi, hi)
    with np.errstate(invalid="ignore", over="ignore"):
        value, grad, _ = distance.terms(lo, hi, hessian=False)
    meets_low = value.lo <= distance.lower.hi
    meets_high = value.hi >= distance.upper.lo
    # a periodic t keeps the box off its seam (no pair of leaves across it)
    seam = np.zeros(2, dtype=bool)
    seam[list(tree.periodic)] = True
    on_seam = seam & ((b_lo == 0) | (b_hi == extent))
    # the stop each box hangs from: (axis, 0 lower / 1 upper), -1 for none;
    # d^2 rises toward the stop (lower bound) or falls toward it (upper bound)
    axis = np.full(level.size, -1, dtype=np.int64)
    side = np.zeros(level.size, dtype=np.int64)
    lower = np.zeros(level.size, dtype=bool)
    for a in np.flatnonzero(stops):
        normal = grad[a]
        for s, face in ((0, b_lo[:, a] == 0), (1, b_hi[:, a] == extent[a])):
            rises = normal.hi < 0 if s == 0 else normal.lo > 0
            falls = normal.lo > 0 if s == 0 else normal.hi < 0
            low = meets_low & ~meets_high & rises
            high = meets_high & ~meets_low & falls
            fits = face & (low | high) & ~on_seam[:, 1 - a] & (axis < 0)
            axis[fits], side[fits], lower[fits] = a, s, low[fits]
    ok = axis >= 0
    # the coarsest box of each candidate
    chosen: dict[tuple[int, int, int], int] = {}
    seen: set[int] = set()
    for j in np.flatnonzero(ok)[::-1]:
        key = (int(level[j]), int(b_lo[j, 0]), int(b_lo[j, 1]))
        if key not in failed and int(leaf[j]) not in seen:
            seen.add(int(leaf[j]))
            chosen.setdefault(key, int(j))
    order = sorted(chosen, key=lambda kk: kk[0])
    taken = [(b.anchor, b.anchor + b.size) for b in blocks]
    found: list[StopBlock] = []
    for key in order[:MAX_TRACES]:
        j = chosen[key]
        a_lo, a_hi = b_lo[j], b_hi[j]
        if any((a_lo < t_hi).all() and (t_lo < a_hi).all() for t_lo, t_hi in taken):
            continue
        stopped = int(axis[j])
        t = 1 - stopped
        stop = float(tree.hi[stopped] if side[j] else tree.lo[stopped])
        phi = _trace_function(distance, stopped, stop, bool(lower[j]))
        where: list[float] = []
        runs = trace_runs(phi, float(lo[j, t]), float(hi[j, t]), where)
        if runs is None:
            failed.add(key)
            if degenerate is not None and where:
                degenerate.append((stopped, stop, where[0]))
            continue
        box = (a_lo.copy(), (a_hi - a_lo).copy(), lo[j].copy(), hi[j].copy())
        found.append(StopBlock(*box, stopped, stop, runs))
        taken.append((a_lo, a_hi))
    return found


def block_labels(
    tree: HyperTree,
    leaves: Any,
    blocks: list[StopBlock],
    member: NDArray[np.int64],
    pairs: NDArray[np.intp],
) -> tuple[NDArray[np.int64], int, NDArray[np.int64], int]:
    """Possible and certain components over the leaves and the blocks' pieces
    (nodes ``len(tree) + i`` in block order).

    ``pairs`` are the adjacent IN or BOUNDARY leaves (vertex adjacency). The
    undecided leaves of a block are left out: its pieces hold their points of
    D. An IN leaf of a block lies over its trace, so in one piece, and is joined
    to it. A piece is joined to a leaf beside the block that shares a boundary
    with one of its leaves over the piece's outer range of t (possibly), and
    certainly to an IN one whose shared boundary meets that range alone (that
    boundary lies in D, so over the trace). Pieces that hold one end point of
    their traces (blocks end to end on one stop, or meeting at a corner of Q on
    two stops) are joined certainly; pieces of other blocks that touch,
    possibly.

    Returns
    -------
    possible, n_possible, certain, n_certain :
        Labels over the nodes (-1 off the graph) and their counts.
    """
    n = len(tree)
    status = tree.status
    offsets = np.cumsum([0] + [b.runs.shape[0] for b in blocks])
    n_nodes = n + int(offsets[-1])
    inside = status == IN
    maybe = np.ones(n_nodes, dtype=bool)
    maybe[:n] = inside | ((status == BOUNDARY) & (member < 0))
    sure = np.ones(n_nodes, dtype=bool)
    sure[:n] = inside
    a, b = pairs[:, 0], pairs[:, 1]
    possible_edges = [pairs]
    certain_edges = [pairs]
    for k, block in enumerate(blocks):
        t = 1 - block.axis
        runs = block.runs
        pieces = n + offsets[k] + np.arange(runs.shape[0])
        # the IN leaves of the block, each in the piece over its range of t
        own = np.flatnonzero((member == k) & inside)
        over = (leaves.lo[own, t][:, None] <= runs[None, :, 1]) & (
            leaves.hi[own, t][:, None] >= runs[None, :, 0]
        )
        # (none: joined to every piece, possibly, rather than left apart)
        over[over.sum(axis=1) == 0] = True
        rows, cols = np.nonzero(over)
        possible_edges.append(np.stack([own[rows], pieces[cols]], axis=1))
        held = over.sum(axis=1) == 1
        rows, cols = np.nonzero(over[held])
        certain_edges.append(np.stack([own[held][rows], pieces[cols]], axis=1))
        for this, other in ((a, b), (b, a)):
            cross = (member[this] == k) & (member[other] != k)
            if not cross.any():
                continue
            i, j = this[cross], other[cross]
            meets = _meets(leaves, i, j, block)
            lone = meets.sum(axis=1) == 1
            beside = member[j]
            for p in range(runs.shape[0]):
                free = meets[:, p] & (beside < 0)
                possible_edges.append(np.stack([j[free], np.full(int(free.sum()), pieces[p])], 1))
                sure_hit = free & lone & sure[j]
                certain_edges.append(
                    np.stack([j[sure_hit], np.full(int(sure_hit.sum()), pieces[p])], 1)
                )
            # a leaf of another block: its pieces over the shared boundary, possibly
            for k2 in np.unique(beside[beside >= 0]):
                row = beside == k2
                theirs = _meets(leaves, j[row], i[row], blocks[k2])
                for p, q in np.argwhere(meets[row].T.astype(np.int64) @ theirs.astype(np.int64)):
                    possible_edges.append(
                        np.array([[pieces[p], n + offsets[k2] + q]], dtype=np.int64)
                    )
    # pieces that hold one end point of their box's trace (a point of D on the
    # stop), as blocks end to end on one stop or at a corner of Q on two do
    by_point: dict[tuple[float, float], list[int]] = {}
    for k, block in enumerate(blocks):
        t = 1 - block.axis
        for p, run in enumerate(block.runs):
            for end, held in ((block.lo[t], run[3]), (block.hi[t], run[4])):
                if held > 0:
                    point = [0.0, 0.0]
                    point[block.axis], point[t] = block.value, float(end)
                    by_point.setdefault((point[0], point[1]), []).append(n + offsets[k] + p)
    # such a point lies in D: in any other block whose closed box holds it, it
    # hangs from that block's stop over one run, and joins that run's piece too
    for (x, y), nodes in by_point.items():
        for k, block in enumerate(blocks):
            t = 1 - block.axis
            if not (block.lo[0] <= x <= block.hi[0] and block.lo[1] <= y <= block.hi[1]):
                continue
            at = (x, y)[t]
            (over,) = np.nonzero((block.runs[:, 0] <= at) & (at <= block.runs[:, 1]))
            if over.size == 1:
                nodes.append(n + offsets[k] + int(over[0]))
        joined = np.array([(nodes[0], other) for other in set(nodes[1:])], dtype=np.int64)
        possible_edges.append(joined.reshape(-1, 2))
        certain_edges.append(joined.reshape(-1, 2))
    possible, n_possible = _labels(n_nodes, possible_edges, maybe)
    certain, n_certain = _labels(n_nodes, certain_edges, sure)
    return possible, n_possible, certain, n_certain


def _meets(
    leaves: Any, i: NDArray[np.intp], j: NDArray[np.intp], block: StopBlock
) -> NDArray[np.bool_]:
    """(m, pieces): whether the boundary shared by leaf ``i`` (of ``block``) and
    leaf ``j`` meets each piece's outer range of t."""
    t = 1 - block.axis
    s_lo = np.maximum(leaves.lo[i, t], leaves.lo[j, t])
    s_hi = np.minimum(leaves.hi[i, t], leaves.hi[j, t])
    runs = block.runs
    return np.asarray(
        (s_lo[:, None] <= runs[None, :, 1]) & (s_hi[:, None] >= runs[None, :, 0]), dtype=bool
    )


def _labels(
    n: int, edges: list[NDArray[Any]], taken: NDArray[np.bool_]
) -> tuple[NDArray[np.int64], int]:
    e = np.concatenate([np.asarray(x, dtype=np.int64).reshape(-1, 2) for x in edges])
    e = e[taken[e[:, 0]] & taken[e[:, 1]]]
    return edge_components(n, e, taken)
