"""Regions from certified sheets: certain connections and possible ones.

Nodes are (leaf, posture) pairs of a tree over the workspace. Two graphs are
built on them, for each sign of det A:

* the *certain* graph joins IN sheets of the same posture in touching leaves
  (the sheets are graphs of one continuous function over closed leaves, so
  they share the configurations over the common face, edge or corner), and
  the postures of a certified fold group; its components are each inside one
  region R_j;
* the *possible* graph joins every node that may hold a valid configuration
  of that sign to the same posture in touching leaves, and to the postures of
  its own leaf that differ only on legs that may fold there. A continuous
  path of valid configurations only ever moves along these edges, so every
  region lies inside one of its components.

A possible component holding exactly one certain component is a *resolved*
region: the certain part is in it, and nothing outside the possible part is.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..compiled import kernel
from ..hypertree._kernels import edge_labels, relabel_roots_into, union_sets
from ..hypertree.status import IN
from ..limits import JointLimit
from .sheets import SheetTable

__all__ = ["RegionGraph", "region_graph", "split_legs"]

#: slack when comparing rounded angle pieces (more overlap only adds edges)
_TOL = 1e-9


@dataclass(frozen=True)
class RegionGraph:
    """Components of the certain and possible graphs.

    Attributes
    ----------
    certain : (n, P) int64
        Certain component of each node, -1 where the node is not certified.
    possible : (2, n, P * slots) int64
        Possible component of each sub-node (column ``posture * slots + piece``)
        for det A > 0 (row 0) and < 0 (row 1), -1 where the sub-node cannot hold
        a valid configuration of that sign. A node's sub-nodes hold its
        configurations by the piece of each limited joint's range they lie in
        (one piece, slot 0, for a node within the limits).
    certain_sign : (n_certain,) int8
        Sign of det A in each certain component.
    n_possible : tuple of int
        Number of possible components of each sign.
    certain_edges : (m, 2) int64
        The certain graph's edges, for planning motions along it.
    """

    certain: NDArray[np.int64]
    possible: NDArray[np.int64]
    certain_sign: NDArray[np.int8]
    n_possible: tuple[int, int]
    #: (m, 2) node pairs of the certain graph (node = leaf * P + posture)
    certain_edges: NDArray[np.int64]
    #: sub-nodes per node in ``possible`` (one per piece of the joint ranges)
    slots: int

    @cached_property
    def certain_matrix(self) -> Any:
        """The certain graph as a sparse adjacency matrix over the nodes
        (``leaf * P + posture``, a ``scipy.sparse.csr_matrix``), built once, for
        walks along it (planning)."""
        from scipy.sparse import coo_matrix

        n = self.certain.size
        e = self.certain_edges
        return coo_matrix(
            (np.ones(e.shape[0], dtype=np.int8), (e[:, 0], e[:, 1])), shape=(n, n)
        ).tocsr()


@kernel
def _certain_edges(
    pairs: NDArray[np.int64],
    sign: NDArray[np.int8],
    regular_in: NDArray[np.bool_],
    certified: NDArray[np.bool_],
    group: NDArray[np.bool_],
    contact: NDArray[np.bool_],
    use_contact: bool,
    pq: NDArray[np.int64],
    same_leaf: NDArray[np.bool_],
) -> NDArray[np.int64]:  # pragma: no cover - compiled
    """The certain graph's edges (node = leaf * P + posture), (m, 2): per posture,
    the touching pairs whose sheets have one sign and are a regular IN sheet
    and a certified one (or two fold group members with a reachable contact);
    then, per pair of postures, the leaves where both are members of one fold
    group of one sign. One pass, into an array as long as they may be (its
    pages beyond the edges written are never touched)."""
    n, n_post = sign.shape
    out = np.empty((pairs.shape[0] * n_post + pq.shape[0] * n, 2), dtype=np.int64)
    k = 0
    for p in range(n_post):
        for t in range(pairs.shape[0]):
            i, j = pairs[t, 0], pairs[t, 1]
            if sign[i, p] != sign[j, p]:
                continue
            ok = (regular_in[i, p] and certified[j, p]) or (certified[i, p] and regular_in[j, p])
            if not ok and use_contact:
                ok = group[i, p] and group[j, p] and contact[t]
            if ok:
                out[k, 0] = i * n_post + p
                out[k, 1] = j * n_post + p
                k += 1
    for g in range(pq.shape[0]):
        p, q = pq[g, 0], pq[g, 1]
        for i in range(n):
            if group[i, p] and group[i, q] and same_leaf[g, i] and sign[i, p] == sign[i, q]:
                out[k, 0] = i * n_post + p
                out[k, 1] = i * n_post + q
                k += 1
    return out[:k]


@kernel
def _sub_nodes_meet(
    bounds: NDArray[np.float64],
    piece_of: NDArray[np.int64],
    i: int,
    p: int,
    ci: int,
    j: int,
    q: int,
    cj: int,
    tol: float,
) -> bool:  # pragma: no cover - compiled
    """Whether the pieces of sub-node (i, p, ci) and (j, q, cj) overlap on every leg
    (``bounds``: (n, P, legs, pieces, 2): each leg's pieces; ``piece_of`` (slots,
    legs): the piece of each leg in a slot)."""
    for leg in range(bounds.shape[2]):
        a, b = piece_of[ci, leg], piece_of[cj, leg]
        if not (bounds[i, p, leg, a, 0] <= bounds[j, q, leg, b, 1] + tol):
            return False
        if not (bounds[j, q, leg, b, 0] <= bounds[i, p, leg, a, 1] + tol):
            return False
    return True


@kernel
def _join_sub_nodes(
    parent0: NDArray[np.int64],
    parent1: NDArray[np.int64],
    join0: bool,
    join1: bool,
    has: NDArray[np.bool_],
    bounds: NDArray[np.float64],
    piece_of: NDArray[np.int64],
    i: int,
    p: int,
    j: int,
    q: int,
    tol: float,
) -> None:  # pragma: no cover - compiled
    """Joins the sub-nodes of node (i, p) and node (j, q) that exist (``has``) and
    whose pieces overlap, in the union-find ``parent0`` if ``join0`` and in
    ``parent1`` if ``join1`` (for :func:`_possible_labels_both`)."""
    n_post, slots = has.shape[1], has.shape[2]
    for ci in range(slots):
        if not has[i, p, ci]:
            continue
        for cj in range(slots):
            if has[j, q, cj] and _sub_nodes_meet(bounds, piece_of, i, p, ci, j, q, cj, tol):
                u = (i * n_post + p) * slots + ci
                v = (j * n_post + q) * slots + cj
                if join0:
                    union_sets(parent0, u, v)
                if join1:
                    union_sets(parent1, u, v)


@kernel
def _seed_certain(
    parent0: NDArray[np.int64],
    parent1: NDArray[np.int64],
    alive: NDArray[np.bool_],
    has: NDArray[np.bool_],
    certain: NDArray[np.int64],
    sign: NDArray[np.int8],
) -> NDArray[np.bool_]:  # pragma: no cover - compiled
    """For :func:`_possible_labels_both`: the first sub-node of each node of a
    certain component joined, in the union-find of its sign, with the first
    seeded sub-node of that component; returns the seeded nodes (n, P)."""
    n, n_post, slots = has.shape
    seeded = np.zeros((n, n_post), dtype=np.bool_)
    first = np.full(certain.max() + 1 if certain.size else 0, -1, dtype=np.int64)
    for i in range(n):
        for p in range(n_post):
            c = certain[i, p]
            if c < 0 or not has[i, p, 0]:
                continue
            one_slot = True
            for ci in range(1, slots):
                if has[i, p, ci]:
                    one_slot = False
            row = 0 if sign[i, p] > 0 else 1
            if not one_slot or sign[i, p] == 0 or not alive[row, i, p] or alive[1 - row, i, p]:
                continue
            seeded[i, p] = True
            u = (i * n_post + p) * slots
            if first[c] < 0:
                first[c] = u
            elif row == 0:
                union_sets(parent0, first[c], u)
            else:
                union_sets(parent1, first[c], u)
    return seeded


@kernel
def _possible_labels_both(
    pairs: NDArray[np.int64],
    alive: NDArray[np.bool_],
    has: NDArray[np.bool_],
    bounds: NDArray[np.float64],
    piece_of: NDArray[np.int64],
    pq: NDArray[np.int64],
    same_leaf: NDArray[np.bool_],
    taken: NDArray[np.bool_],
    tol: float,
    certain: NDArray[np.int64],
    sign: NDArray[np.int8],
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:  # pragma: no cover - compiled
    """Components of the possible graphs of both signs, joined on the fly (no edge
    list) from one pass over the pairs.

    Sub-node ``(leaf * P + posture) * slots + slot``. Touching leaves (the rows of
    ``pairs``) join the same posture's sub-nodes that exist and may hold a
    configuration (``alive``) where their pieces overlap; within a leaf, the
    postures of each pair ``pq`` join where ``same_leaf`` says they differ only
    on folding legs. Labels on the ``taken`` sub-nodes, numbered by first
    sub-node (as :func:`~moveability.hypertree.topology.edge_components`).
    ``alive`` (2, n, P) and ``taken`` (2, sub-nodes) per sign; the sub-nodes that exist,
    ``has`` (n, P, slots), and their pieces' bounds, ``bounds`` (n, P, legs,
    pieces, 2: each leg's pieces, node by node), with ``piece_of`` (slots, legs) the
    piece of each leg in a slot; whether two pieces overlap is found once for
    both signs.

    The certain graph's components (``certain`` (n, P), -1 off it; ``sign`` (n,
    P) of det A) are joined first: each holds configurations that are connected,
    so the possible graph of their sign joins them too. A node of one (one
    sub-node, the first, that exists, alive for its sign alone) is *seeded*,
    and a pair of seeded nodes of one certain component is not looked at again.
    This changes no component where the pieces of a certain edge overlap, as
    they do (an edge of the certain graph joins configurations); it spares the
    pairs inside the certified parts of the regions. ``certain`` all -1 seeds
    nothing.
    Returns the labels (2, sub-nodes) and their counts (2,); each sign's
    components are those of its own graph (a union-find's partition does not
    depend on the order of its unions, and the labels are numbered by first
    sub-node)."""
    n, n_post = alive.shape[1], alive.shape[2]
    slots = has.shape[2]
    parent0 = np.arange(n * n_post * slots)
    parent1 = np.arange(n * n_post * slots)
    seeded = _seed_certain(parent0, parent1, alive, has, certain, sign)
    # the node pairs to join: (pair, posture) of touching leaves, then (posture
    # pair, leaf) within a leaf; one loop whose body calls a helper only for the
    # nodes that join (a call with many arrays per pair costs more than the pair)
    within = np.argwhere(same_leaf)
    n_touching = pairs.shape[0] * n_post
    for t in range(n_touching + within.shape[0]):
        if t < n_touching:
            row = t // n_post
            p = t - row * n_post
            i, j, q = pairs[row, 0], pairs[row, 1], p
        else:
            k, i = within[t - n_touching, 0], within[t - n_touching, 1]
            p, q, j = pq[k, 0], pq[k, 1], i
        if seeded[i, p] and seeded[j, q] and certain[i, p] == certain[j, q]:
            continue  # one certain component, already joined
        both0 = alive[0, i, p] and alive[0, j, q]
        both1 = alive[1, i, p] and alive[1, j, q]
        if both0 or both1:
            _join_sub_nodes(parent0, parent1, both0, both1, has, bounds, piece_of, i, p, j, q, tol)
    labels = np.empty((2, parent0.size), dtype=np.int64)
    counts = np.zeros(2, dtype=np.int64)
    # each sign's scratch an array done with: the other row, then parent0
    counts[0] = relabel_roots_into(parent0, taken[0], labels[0], labels[1])
    counts[1] = relabel_roots_into(parent1, taken[1], labels[1], parent0)
    return labels, counts


def _posture_pairs(postures: NDArray[np.int64]) -> list[tuple[int, int, NDArray[np.bool_]]]:
    """Pairs of postures with the legs on which they differ."""
    out = []
    for p in range(postures.shape[0]):
        for q in range(p + 1, postures.shape[0]):
            out.append((p, q, postures[p] != postures[q]))
    return out


def joint_pieces(
    lo: NDArray[np.float64], hi: NDArray[np.float64], limit: JointLimit
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    """Values in ``[limit.lo, limit.hi]`` of unwrapped angle enclosures, as two pieces.

    Returns ``(lo, hi, ok)`` of shape (2, ...): piece 0 starts where the
    enclosure enters the range, piece 1 is its next turn from ``limit.lo``.
    """
    if limit.periodic:
        full = np.ones((2, *lo.shape), dtype=bool)
        full[1] = False
        return np.full((2, *lo.shape), -np.inf), np.full((2, *lo.shape), np.inf), full
    if limit.prismatic:
        # a stroke never wraps: one piece
        one = np.zeros((2, *lo.shape), dtype=bool)
        one[0] = (lo <= limit.hi + _TOL) & (hi >= limit.lo - _TOL)
        return (
            np.stack([np.maximum(lo, limit.lo), np.full(lo.shape, limit.lo)]),
            np.stack([np.minimum(hi, limit.hi), np.full(lo.shape, limit.lo)]),
            one,
        )
    two_pi = 2 * np.pi
    with np.errstate(invalid="ignore", over="ignore"):
        k = np.floor((lo - limit.lo) / two_pi)
        k = np.where(np.isfinite(k), k, 0.0)
        a_lo = lo - two_pi * k
        a_hi = hi - two_pi * k
        wide = ~np.isfinite(lo) | ~np.isfinite(hi) | (hi - lo >= two_pi - _TOL)
        ok0 = wide | (a_lo <= limit.hi + _TOL)
        ok1 = ~wide & (a_hi - two_pi >= limit.lo - _TOL)
        lo0 = np.where(wide, limit.lo, np.maximum(a_lo, limit.lo))
        hi0 = np.where(wide, limit.hi, np.minimum(a_hi, limit.hi))
        lo1 = np.full(lo.shape, limit.lo)
        hi1 = np.where(ok1, a_hi - two_pi, limit.lo)
    return np.stack([lo0, lo1]), np.stack([hi0, hi1]), np.stack([ok0, ok1])


#: the kinds of joint of :func:`_piece_bounds`
_FREE, _STROKE, _REVOLUTE = 0, 1, 2


@kernel
def _piece_bounds(
    lo: NDArray[np.float64],
    hi: NDArray[np.float64],
    kinds: NDArray[np.int64],
    stop_lo: NDArray[np.float64],
    stop_hi: NDArray[np.float64],
    piece_of: NDArray[np.int64],
    bounds: NDArray[np.float64],
    has: NDArray[np.bool_],
) -> None:  # pragma: no cover - compiled
    """Each leg's two pieces of the (n, P, legs) enclosures, as :func:`joint_pieces`
    gives them for a free joint, a stroke or a limited revolute joint (``kinds``:
    ``_FREE``, ``_STROKE``, ``_REVOLUTE``; stops ``[stop_lo, stop_hi]``), into
    ``bounds`` (n, P, legs, pieces, 2: two pieces where some leg is a limited
    revolute joint, else the first alone; a free joint's or a stroke's second
    piece, where there is one, is never read); the sub-nodes whose piece of
    some leg is missing (``piece_of`` (slots, legs): the piece of each leg in a
    slot) cleared in ``has`` (n, P, slots). One pass, the same floats as
    joint_pieces' numpy operations (a NaN bound stays NaN, as in
    ``np.maximum``, and fails every comparison)."""
    n, n_post, n_legs = bounds.shape[0], bounds.shape[1], bounds.shape[2]
    slots = has.shape[2]
    pieces = bounds.shape[3]
    two_pi = 2 * np.pi
    for i in range(n):
        for p in range(n_post):
            for leg in range(n_legs):
                a = lo[i, p, leg]
                b = hi[i, p, leg]
                s_lo, s_hi = stop_lo[leg], stop_hi[leg]
                if kinds[leg] == _FREE:
                    for k in range(pieces):
                        bounds[i, p, leg, k, 0] = -np.inf
                        bounds[i, p, leg, k, 1] = np.inf
                    continue
                if kinds[leg] == _STROKE:
                    ok = a <= s_hi + _TOL and b >= s_lo - _TOL
                    bounds[i, p, leg, 0, 0] = s_lo if a < s_lo else a
                    bounds[i, p, leg, 0, 1] = s_hi if b > s_hi else b
                    if pieces > 1:
                        bounds[i, p, leg, 1, 0] = s_lo
                        bounds[i, p, leg, 1, 1] = s_lo
                    if not ok:
                        for c in range(slots):
                            has[i, p, c] = False
                    continue
                # a limited revolute joint: the turn where the enclosure enters
                # [s_lo, s_hi], and its next turn from s_lo
                k_turn = np.floor((a - s_lo) / two_pi)
                if not np.isfinite(k_turn):
                    k_turn = 0.0
                a_lo = a - two_pi * k_turn
                a_hi = b - two_pi * k_turn
                wide = not np.isfinite(a) or not np.isfinite(b) or b - a >= two_pi - _TOL
                ok0 = wide or a_lo <= s_hi + _TOL
                ok1 = not wide and a_hi - two_pi >= s_lo - _TOL
                if wide:
                    bounds[i, p, leg, 0, 0], bounds[i, p, leg, 0, 1] = s_lo, s_hi
                else:
                    bounds[i, p, leg, 0, 0] = s_lo if a_lo < s_lo else a_lo
                    bounds[i, p, leg, 0, 1] = s_hi if a_hi > s_hi else a_hi
                bounds[i, p, leg, 1, 0] = s_lo
                bounds[i, p, leg, 1, 1] = a_hi - two_pi if ok1 else s_lo
                for c in range(slots):
                    if not (ok1 if piece_of[c, leg] == 1 else ok0):
                        has[i, p, c] = False


def _sub_node_bounds(
    angles_lo: NDArray[np.float64],
    angles_hi: NDArray[np.float64],
    limits: tuple[JointLimit, ...],
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.bool_]]:
    """The pieces of the sub-nodes of the (n, P, legs) enclosures, node by node:
    ``bounds`` (n, P, legs, pieces, 2), each leg's pieces (:func:`joint_pieces`:
    two where a leg's range has two pieces, see :func:`split_legs`, else the
    first alone, as no slot reads another), ``piece_of`` (slots, legs), the
    piece of each leg in a slot, and ``has`` (n, P, slots), the sub-nodes whose
    every leg's piece exists. One compiled pass (:func:`_piece_bounds`)."""
    n, n_post, n_legs = angles_lo.shape
    split = split_legs(limits)
    slots = 1 << len(split)
    piece_of = np.zeros((slots, n_legs), dtype=np.int64)
    for i in split:
        piece_of[:, i] = (np.arange(slots) >> split.index(i)) & 1
    bounds = np.empty((n, n_post, n_legs, 2 if split else 1, 2))
    has = np.ones((n, n_post, slots), dtype=bool)
    kinds = np.array(
        [_FREE if lim.periodic else _STROKE if lim.prismatic else _REVOLUTE for lim in limits],
        dtype=np.int64,
    )
    _piece_bounds(
        np.ascontiguousarray(angles_lo, dtype=np.float64),
        np.ascontiguousarray(angles_hi, dtype=np.float64),
        kinds,
        np.array([float(lim.lo) for lim in limits]),
        np.array([float(lim.hi) for lim in limits]),
        piece_of,
        bounds,
        has,
    )
    return bounds, piece_of, has


def split_legs(limits: tuple[JointLimit, ...]) -> list[int]:
    """Legs whose joint range has two pieces: the limited revolute joints.

    Bit ``j`` of a sub-node's slot is the piece of leg ``split_legs(limits)[j]``;
    prismatic and free joints have one piece.
    """
    return [i for i, lim in enumerate(limits) if not (lim.periodic or lim.prismatic)]


def region_graph(
    table: SheetTable,
    pairs: NDArray[np.intp],
    postures: NDArray[np.int64],
    cross_serial: bool = True,
    limits: tuple[JointLimit, ...] | None = None,
    reachable_contact: NDArray[np.bool_] | None = None,
    seed_certain: bool = True,
) -> RegionGraph:
    """Build both graphs from a sheet table and the touching leaf pairs.

    With ``cross_serial=False`` no path may meet a serial singularity (det B = 0)
    either: postures never change, and the components are the generalized
    aspects (det A and det B of constant sign). ``reachable_contact`` says, per
    pair, that the two leaves' common boundary holds a pose every leg reaches:
    two certified fold groups of one posture then share a configuration there.
    With ``seed_certain`` (the default) the possible graphs start from the
    certain graph's components (see :func:`_possible_labels_both`): the same
    components, found sooner.
    """
    n, n_post = table.status.shape
    if limits is None:
        limits = tuple(JointLimit.unlimited() for _ in range(table.angles_lo.shape[2]))
    group = table.group if cross_serial else np.zeros_like(table.group)
    certified = (table.status == IN) | group
    # legs whose branches may meet in a leaf; none may be crossed without serial ones
    folding = table.folding if cross_serial else np.zeros_like(table.folding)

    # ---------------------------------------------------------------- certain
    post_pairs = _posture_pairs(postures)
    pq = np.array([(p, q) for p, q, _ in post_pairs], dtype=np.int64).reshape(-1, 2)
    # per posture pair, the leaves where the two differ only on folding legs
    same_leaf = (
        np.stack([(~differ[None, :] | folding).all(axis=1) for _, _, differ in post_pairs])
        if post_pairs
        else np.zeros((0, n), dtype=bool)
    )
    # the (m, 2) pairs as they are: no copy of their columns
    pairs = np.ascontiguousarray(pairs, dtype=np.int64).reshape(-1, 2)
    contact = (
        np.zeros(0, dtype=bool)
        if reachable_contact is None
        else np.ascontiguousarray(reachable_contact, dtype=bool)
    )
    args = (
        pairs, np.ascontiguousarray(table.sign), np.ascontiguousarray(table.status == IN),
        np.ascontiguousarray(certified), np.ascontiguousarray(group), contact,
        reachable_contact is not None, pq, same_leaf,
    )  # fmt: skip
    certain_edges = _certain_edges(*args)
    certain, n_certain = edge_labels(
        n * n_post, certain_edges[:, 0], certain_edges[:, 1], certified.ravel()
    )
    certain_sign = np.zeros(n_certain, dtype=np.int8)
    labelled = certain >= 0
    certain_sign[certain[labelled]] = table.sign.ravel()[labelled]

    # --------------------------------------------------------------- possible
    # A limited joint's enclosure may hold values on both sides of a stop (near hi
    # and, one turn on, near lo): a path never passes from one to the other. Each
    # node is split by the piece of [lo, hi] each leg's value lies in, and pieces
    # are joined only where they overlap.
    # per node, each leg's pieces (once, whatever the slots), and the sub-nodes
    bounds, piece_of, has = _sub_node_bounds(table.angles_lo, table.angles_hi, limits)
    slots = has.shape[2]
    # both signs from one pass over the pairs
    alive = np.stack([table.may_hold(s) for s in (1, -1)])
    taken = (alive[:, :, :, None] & has[None]).reshape(2, -1)
    seeds = certain.reshape(n, n_post) if seed_certain else np.full((n, n_post), -1)
    possible, counts = _possible_labels_both(
        pairs, alive, has, bounds, piece_of, pq, same_leaf, taken, _TOL, seeds,
        np.ascontiguousarray(table.sign),
    )  # fmt: skip
    return RegionGraph(
        certain=certain.reshape(n, n_post),
        possible=possible.reshape(2, n, n_post * slots),
        slots=slots,
        certain_sign=certain_sign,
        certain_edges=certain_edges,
        n_possible=(int(counts[0]), int(counts[1])),
    )
