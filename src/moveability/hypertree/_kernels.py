"""Compiled kernels (numba) for the hot loops of the tree engine.

The profile of :func:`moveability.components` on a 4-D tree of 1.5 million
leaves showed most of the time in whole-array passes per probe direction
(shift, binary search, graph assembly). This kernel does the same probing leaf
by leaf with a galloping search from the previous hit, and merges the
components on the fly with a union-find, so no edge list is ever stored.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..compiled import kernel
from .keys import KeyLayout

__all__ = [
    "adjacent_and_face_pairs",
    "adjacent_pairs",
    "edge_components",
    "label_leaves",
    "mark_sources",
    "remap_pairs",
]


@kernel
def _find(parent: NDArray[np.int64], i: int) -> int:  # pragma: no cover - compiled
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@kernel
def union_sets(parent: NDArray[np.int64], i: int, j: int) -> None:  # pragma: no cover - compiled
    """Join the sets of ``i`` and ``j``; the smaller root stays the root."""
    a = _find(parent, i)
    b = _find(parent, j)
    if a != b:
        if a < b:
            parent[b] = a
        else:
            parent[a] = b


@kernel
def relabel_roots(
    parent: NDArray[np.int64], taken: NDArray[np.bool_]
) -> tuple[NDArray[np.int64], int]:  # pragma: no cover - compiled
    """Labels of the taken elements' sets, numbered by first element (-1 elsewhere)."""
    labels = np.empty(parent.size, dtype=np.int64)
    count = relabel_roots_into(parent, taken, labels, np.empty(parent.size, dtype=np.int64))
    return labels, count


@kernel
def relabel_roots_into(
    parent: NDArray[np.int64],
    taken: NDArray[np.bool_],
    out: NDArray[np.int64],
    scratch: NDArray[np.int64],
) -> int:  # pragma: no cover - compiled
    """:func:`relabel_roots` into ``out``, with ``scratch`` (as long, overwritten)
    for the roots' labels: returns the count. (A caller done with an array of its
    own lends it as the scratch: no fresh memory for a large union-find.)"""
    for i in range(scratch.size):
        scratch[i] = -1
    count = 0
    for i in range(parent.size):
        if not taken[i]:
            out[i] = -1
            continue
        r = _find(parent, i)
        if scratch[r] < 0:
            scratch[r] = count
            count += 1
        out[i] = scratch[r]
    return count


@kernel
def _gallop(keys: NDArray[np.uint64], target: np.uint64, start: int) -> int:  # pragma: no cover
    """Index of the last key <= target, searching outwards from ``start``."""
    n = keys.size
    if keys[start] <= target:
        lo = start
        step = 1
        hi = start + 1
        while hi < n and keys[hi] <= target:
            lo = hi
            step *= 2
            hi = lo + step
        if hi > n:
            hi = n
        # keys[lo] <= target, and keys[hi] > target or hi == n
    else:
        hi = start
        step = 1
        lo = start - 1
        while lo > 0 and keys[lo] > target:
            hi = lo
            step *= 2
            lo = hi - step
        if lo < 0:
            lo = 0
        # keys[hi] > target; keys[lo] <= target (keys[0] == 0 <= target)
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if keys[mid] <= target:
            lo = mid
        else:
            hi = mid
    return lo


@kernel
def _neighbour_key(
    key: np.uint64,
    level: np.int64,
    direction: NDArray[np.int8],
    max_depth: NDArray[np.int64],
    masks: NDArray[np.uint64],
    positions: NDArray[np.int64],
    periodic: NDArray[np.bool_],
) -> tuple[np.uint64, bool]:  # pragma: no cover - compiled
    """The key of the point just beyond a leaf in one probe direction (its upper
    side by the leaf's size, its lower side by one unit), and whether that point
    is in the box (across periodic axes it always is)."""
    one = np.uint64(1)
    for axis in range(max_depth.size):
        step = direction[axis]
        if step == 0:
            continue
        depth = max_depth[axis]
        cell_depth = level if level < depth else depth
        if (cell_depth == 0 and step > 0) or depth == 0:
            # the cell spans the whole axis: it meets only itself across it
            if not periodic[axis]:
                return key, False
            continue
        mask = masks[axis]
        x = key & mask
        if step > 0:
            dil = one << np.uint64(positions[axis, depth - cell_depth])
            moved = ((x | ~mask) + dil) & mask
            wrapped = moved < x
        else:
            dil = one << np.uint64(positions[axis, 0])
            moved = (x - dil) & mask
            wrapped = moved > x
        if wrapped and not periodic[axis]:
            return key, False
        key = (key & ~mask) | moved
    return key, True


@kernel
def _label(
    keys: NDArray[np.uint64],
    levels: NDArray[np.uint8],
    chosen: NDArray[np.bool_],
    max_depth: NDArray[np.int64],
    masks: NDArray[np.uint64],
    positions: NDArray[np.int64],
    periodic: NDArray[np.bool_],
    directions: NDArray[np.int8],
) -> tuple[NDArray[np.int64], int]:  # pragma: no cover - compiled
    n = keys.size
    n_dir = directions.shape[0]
    parent = np.arange(n)
    last = np.zeros(n_dir, dtype=np.int64)
    for i in range(n):
        if not chosen[i]:
            continue
        level = np.int64(levels[i])
        for d in range(n_dir):
            key, inside = _neighbour_key(
                keys[i], level, directions[d], max_depth, masks, positions, periodic
            )
            if not inside:
                continue
            j = _gallop(keys, key, last[d])
            last[d] = j
            if chosen[j]:
                union_sets(parent, i, j)
    return relabel_roots(parent, chosen)


@kernel
def _pairs(
    keys: NDArray[np.uint64],
    levels: NDArray[np.uint8],
    chosen: NDArray[np.bool_],
    max_depth: NDArray[np.int64],
    masks: NDArray[np.uint64],
    positions: NDArray[np.int64],
    periodic: NDArray[np.bool_],
    directions: NDArray[np.int8],
    sources: NDArray[np.bool_],
    fresh: NDArray[np.bool_],
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.bool_]]:  # pragma: no cover
    """Adjacent pairs of chosen leaves, each written once, by its finer leaf.

    A leaf's probe in the direction of an adjacent leaf at least as large lands
    in it (the two are dyadic cells: the finer one's extent along the other
    axes lies within the larger one's), so every pair is found from its finer
    leaf; a pair of leaves of one level, found from both, is kept from the
    lower index. Only the ``sources`` probe, and a pair of two leaves that are
    not ``fresh`` is left out (a refined tree's pairs between kept leaves are
    known). One pass: the pairs go to arrays that grow by doubling. The third
    array flags the pairs found by a probe along an axis (one non-zero entry):
    those of face adjacency."""
    n = keys.size
    n_dir = directions.shape[0]
    last = np.zeros(n_dir, dtype=np.int64)
    found = np.empty(n_dir, dtype=np.int64)
    found_face = np.zeros(n_dir, dtype=np.bool_)
    axial = np.zeros(n_dir, dtype=np.bool_)
    for d in range(n_dir):
        nonzero = 0
        for axis in range(directions.shape[1]):
            if directions[d, axis] != 0:
                nonzero += 1
        axial[d] = nonzero == 1
    n_src = 0
    for i in range(n):
        if chosen[i] and sources[i]:
            n_src += 1
    # each pair is written once: about half the probe directions per leaf
    cap = max(16, n_src * (n_dir // 2 + 1))
    out_a = np.empty(cap, dtype=np.int64)
    out_b = np.empty(cap, dtype=np.int64)
    out_f = np.empty(cap, dtype=np.bool_)
    total = 0
    for i in range(n):
        if not chosen[i] or not sources[i]:
            continue
        level = np.int64(levels[i])
        m = 0
        for d in range(n_dir):
            key, inside = _neighbour_key(
                keys[i], level, directions[d], max_depth, masks, positions, periodic
            )
            if not inside:
                continue
            j = _gallop(keys, key, last[d])
            last[d] = j
            if j == i or not chosen[j] or not (fresh[i] or fresh[j]):
                continue
            other = np.int64(levels[j])
            if other > level or (other == level and j < i):
                continue  # written from j
            seen = False
            for t in range(m):
                if found[t] == j:
                    seen = True
                    found_face[t] |= axial[d]
                    break
            if not seen:
                found[m] = j
                found_face[m] = axial[d]
                m += 1
        if total + m > cap:
            cap = max(2 * cap, total + m)
            grown_a = np.empty(cap, dtype=np.int64)
            grown_b = np.empty(cap, dtype=np.int64)
            grown_f = np.empty(cap, dtype=np.bool_)
            grown_a[:total] = out_a[:total]
            grown_b[:total] = out_b[:total]
            grown_f[:total] = out_f[:total]
            out_a, out_b, out_f = grown_a, grown_b, grown_f
        for t in range(m):
            out_a[total + t] = i
            out_b[total + t] = found[t]
            out_f[total + t] = found_face[t]
        total += m
    return out_a[:total], out_b[:total], out_f[:total]


def adjacent_pairs(
    keys: NDArray[np.uint64],
    levels: NDArray[np.uint8],
    chosen: NDArray[np.bool_],
    layout: KeyLayout,
    periodic: tuple[int, ...],
    directions: NDArray[np.int8],
    sources: NDArray[np.bool_] | None = None,
    fresh: NDArray[np.bool_] | None = None,
    known: NDArray[np.int64] | None = None,
) -> NDArray[np.int64]:
    """Adjacent pairs of chosen leaves, ``(m, 2)`` leaf indices ``i < j`` in sorted order.

    For a refined tree, ``known`` gives the pairs between kept leaves, ``fresh``
    the new leaves, and ``sources`` the leaves that must probe: the new ones
    and every kept leaf that touched a split one (see :func:`_pairs`)."""
    args = _layout_arrays(layout, periodic)
    n = keys.size
    every = np.ones(n, dtype=np.bool_)
    src = every if sources is None else sources
    new = every if fresh is None else fresh
    a, b, _ = _pairs(keys, levels, chosen, *args, directions, src, new)
    return _with_known(a, b, n, known)


def adjacent_and_face_pairs(
    keys: NDArray[np.uint64],
    levels: NDArray[np.uint8],
    chosen: NDArray[np.bool_],
    layout: KeyLayout,
    periodic: tuple[int, ...],
    directions: NDArray[np.int8],
    refined: tuple[
        NDArray[np.bool_], tuple[NDArray[np.int64], NDArray[np.int64]], NDArray[np.int64]
    ]
    | None = None,
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """:func:`adjacent_pairs` with ``directions`` and the pairs of those found by
    its directions along an axis (face adjacency), from one search.

    For a refined tree, ``refined`` is ``(fresh, old, new_of_old)``: the new
    leaves, the coarser tree's pairs of both kinds, and each old leaf's new
    index (-1 where split). Then the new leaves and the kept ones that touched
    a split one probe, and the old pairs between kept leaves are merged with
    those found as they are remapped."""
    n = keys.size
    if refined is None:
        sources = fresh = np.ones(n, dtype=np.bool_)
    else:
        fresh, old, new_of_old = refined
        old_all = np.ascontiguousarray(old[0], dtype=np.int64).reshape(-1, 2)
        old_faces = np.ascontiguousarray(old[1], dtype=np.int64).reshape(-1, 2)
        new_of_old = np.ascontiguousarray(new_of_old, dtype=np.int64)
        sources = fresh.copy()
        mark_sources(old_all, new_of_old, sources)
    a, b, face = _pairs(
        keys, levels, chosen, *_layout_arrays(layout, periodic), directions, sources, fresh
    )
    if refined is None:
        return _sorted_pairs(a, b, n), _sorted_pairs(a[face], b[face], n)
    return (
        _with_remapped(a, b, n, old_all, new_of_old),
        _with_remapped(a[face], b[face], n, old_faces, new_of_old),
    )


def _with_known(
    a: NDArray[np.int64], b: NDArray[np.int64], n: int, known: NDArray[np.int64] | None
) -> NDArray[np.int64]:
    """The pairs found, and those ``known``, in sorted order."""
    if known is None or not known.size:
        return _sorted_pairs(a, b, n)
    known = np.ascontiguousarray(known, dtype=np.int64)
    if not _in_order(known):
        return _sorted_pairs(np.concatenate([a, known[:, 0]]), np.concatenate([b, known[:, 1]]), n)
    # the known pairs are sorted (a refined tree keeps its kept leaves' order, so
    # an adjacency's pairs stay sorted) and none is found again (each found pair
    # has a fresh leaf): a merge
    return _merged_pairs(_sorted_pairs(a, b, n), known)


@kernel
def _in_order(pairs: NDArray[np.int64]) -> bool:  # pragma: no cover - compiled
    """Whether pairs ``i < j`` are in strictly increasing order."""
    for t in range(pairs.shape[0]):
        if pairs[t, 0] >= pairs[t, 1]:
            return False
        if t and (
            pairs[t, 0] < pairs[t - 1, 0]
            or (pairs[t, 0] == pairs[t - 1, 0] and pairs[t, 1] <= pairs[t - 1, 1])
        ):
            return False
    return True


@kernel
def _sorted_pairs(
    a: NDArray[np.int64], b: NDArray[np.int64], n: int
) -> NDArray[np.int64]:  # pragma: no cover - compiled
    """The pairs ``(min, max)`` in sorted order: counted by their first leaf, then each
    leaf's few partners sorted in place (insertion sort)."""
    m = a.size
    start = np.zeros(n + 1, dtype=np.int64)
    for t in range(m):
        start[min(a[t], b[t]) + 1] += 1
    for i in range(n):
        start[i + 1] += start[i]
    out = np.empty((m, 2), dtype=np.int64)
    fill = start[:-1].copy()
    for t in range(m):
        lo = min(a[t], b[t])
        out[fill[lo], 0] = lo
        out[fill[lo], 1] = max(a[t], b[t])
        fill[lo] += 1
    for i in range(n):
        for u in range(start[i] + 1, start[i + 1]):
            value = out[u, 1]
            v = u - 1
            while v >= start[i] and out[v, 1] > value:
                out[v + 1, 1] = out[v, 1]
                v -= 1
            out[v + 1, 1] = value
    return out


@kernel
def _merged_pairs(
    first: NDArray[np.int64], second: NDArray[np.int64]
) -> NDArray[np.int64]:  # pragma: no cover - compiled
    """Two lists of pairs, each in sorted order and with no pair in both, merged
    into one in sorted order."""
    m1, m2 = first.shape[0], second.shape[0]
    out = np.empty((m1 + m2, 2), dtype=np.int64)
    s = t = 0
    for u in range(m1 + m2):
        take_first = t >= m2 or (
            s < m1
            and (
                first[s, 0] < second[t, 0]
                or (first[s, 0] == second[t, 0] and first[s, 1] < second[t, 1])
            )
        )
        if take_first:
            out[u, 0] = first[s, 0]
            out[u, 1] = first[s, 1]
            s += 1
        else:
            out[u, 0] = second[t, 0]
            out[u, 1] = second[t, 1]
            t += 1
    return out


@kernel
def remap_pairs(
    pairs: NDArray[np.int64], new_of_old: NDArray[np.int64], sources: NDArray[np.bool_]
) -> NDArray[np.int64]:  # pragma: no cover - compiled
    """A coarser tree's pairs in a refined tree: the pairs of two kept leaves, by their
    new indices (``new_of_old``, -1 for a split leaf), in the order given; the kept
    leaf of a pair with a split one is marked in ``sources`` (it must probe)."""
    m = pairs.shape[0]
    out = np.empty((m, 2), dtype=np.int64)
    k = 0
    for t in range(m):
        i = new_of_old[pairs[t, 0]]
        j = new_of_old[pairs[t, 1]]
        if i >= 0 and j >= 0:
            out[k, 0] = i
            out[k, 1] = j
            k += 1
        elif i >= 0:
            sources[i] = True
        elif j >= 0:
            sources[j] = True
    return out[:k]


@kernel
def mark_sources(
    pairs: NDArray[np.int64], new_of_old: NDArray[np.int64], sources: NDArray[np.bool_]
) -> None:  # pragma: no cover - compiled
    """The kept leaf of each of a coarser tree's pairs with a split leaf marked in
    ``sources`` (as :func:`remap_pairs` does), without the pairs remapped."""
    for t in range(pairs.shape[0]):
        i = new_of_old[pairs[t, 0]]
        j = new_of_old[pairs[t, 1]]
        if i >= 0 and j < 0:
            sources[i] = True
        elif j >= 0 and i < 0:
            sources[j] = True


@kernel
def _remapped_merged(
    found: NDArray[np.int64], old: NDArray[np.int64], new_of_old: NDArray[np.int64]
) -> tuple[NDArray[np.int64], bool]:  # pragma: no cover - compiled
    """:func:`_merged_pairs` of the pairs ``found`` (in sorted order) and the coarser
    tree's pairs ``old`` between kept leaves, by their new indices
    (:func:`remap_pairs`), in one pass with no list of the latter; False (and
    no pairs) when those are not ``i < j`` in strictly increasing order."""
    m1, m2 = found.shape[0], old.shape[0]
    # at most every pair of both: the pages past those written are never touched
    out = np.empty((m1 + m2, 2), dtype=np.int64)
    s = u = 0
    last_i = last_j = -1
    for t in range(m2):
        i = new_of_old[old[t, 0]]
        j = new_of_old[old[t, 1]]
        if i < 0 or j < 0:
            continue
        if i >= j or i < last_i or (i == last_i and j <= last_j):
            return out[:0], False
        last_i, last_j = i, j
        # the found pairs before it (a pair in both lists comes second, as in a merge)
        while s < m1 and (found[s, 0] < i or (found[s, 0] == i and found[s, 1] < j)):
            out[u, 0] = found[s, 0]
            out[u, 1] = found[s, 1]
            s += 1
            u += 1
        out[u, 0] = i
        out[u, 1] = j
        u += 1
    while s < m1:
        out[u, 0] = found[s, 0]
        out[u, 1] = found[s, 1]
        s += 1
        u += 1
    return out[:u], True


def _with_remapped(
    a: NDArray[np.int64],
    b: NDArray[np.int64],
    n: int,
    old: NDArray[np.int64],
    new_of_old: NDArray[np.int64],
) -> NDArray[np.int64]:
    """:func:`_with_known` of the pairs found and a coarser tree's pairs ``old``
    between kept leaves (:func:`remap_pairs`), merged as they are remapped."""
    merged, ok = _remapped_merged(_sorted_pairs(a, b, n), old, new_of_old)
    if ok:
        return merged
    known = remap_pairs(old, new_of_old, np.zeros(new_of_old.size, dtype=np.bool_))
    return _with_known(a, b, n, known)


def _layout_arrays(
    layout: KeyLayout, periodic: tuple[int, ...]
) -> tuple[NDArray[np.int64], NDArray[np.uint64], NDArray[np.int64], NDArray[np.bool_]]:
    periodic_mask = np.zeros(layout.ndim, dtype=bool)
    periodic_mask[list(periodic)] = True
    return (
        np.asarray(layout.max_depth, dtype=np.int64),
        np.array(layout.masks, dtype=np.uint64),
        layout.position_table,
        periodic_mask,
    )


def label_leaves(
    keys: NDArray[np.uint64],
    levels: NDArray[np.uint8],
    chosen: NDArray[np.bool_],
    layout: KeyLayout,
    periodic: tuple[int, ...],
    directions: NDArray[np.int8],
) -> tuple[NDArray[np.int64], int]:
    """Component labels of the chosen leaves (numbered by first leaf), and their count."""
    labels, count = _label(keys, levels, chosen, *_layout_arrays(layout, periodic), directions)
    return labels, int(count)


@kernel
def edge_labels(
    n: int, a: NDArray[np.int64], b: NDArray[np.int64], taken: NDArray[np.bool_]
) -> tuple[NDArray[np.int64], int]:  # pragma: no cover - compiled
    parent = np.arange(n)
    for t in range(a.size):
        union_sets(parent, a[t], b[t])
    return relabel_roots(parent, taken)


def edge_components(
    n: int, edges: NDArray[np.int64], taken: NDArray[np.bool_]
) -> tuple[NDArray[np.int64], int]:
    """Components of a graph of ``n`` nodes given by its ``(m, 2)`` edges (through any
    node), labelled on the taken nodes in the order of their first node, -1 elsewhere;
    and their count."""
    e = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    labels, count = edge_labels(
        int(n),
        np.ascontiguousarray(e[:, 0]),
        np.ascontiguousarray(e[:, 1]),
        np.ascontiguousarray(taken, dtype=np.bool_),
    )
    return labels, int(count)
