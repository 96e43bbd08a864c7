"""Compiled kernels (numba) for the hot loops of the tree engine.

The profile of :func:`moveability.components` on a 4-D tree of 1.5 million
leaves showed most of the time in whole-array passes per probe direction
(shift, binary search, graph assembly). This kernel does the same probing leaf
by leaf with a galloping search from the previous hit, and merges the
components on the fly with a union-find, so no edge list is ever stored.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from .keys import KeyLayout

__all__ = ["label_leaves"]


@njit(cache=True, nogil=True)
def _find(parent: NDArray[np.int64], i: int) -> int:  # pragma: no cover - compiled
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@njit(cache=True, nogil=True)
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


@njit(cache=True, nogil=True)
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
    k = max_depth.size
    n_dir = directions.shape[0]
    parent = np.arange(n)
    last = np.zeros(n_dir, dtype=np.int64)
    one = np.uint64(1)
    for i in range(n):
        if not chosen[i]:
            continue
        level = np.int64(levels[i])
        for d in range(n_dir):
            key = keys[i]
            inside = True
            for axis in range(k):
                step = directions[d, axis]
                if step == 0:
                    continue
                depth = max_depth[axis]
                cell_depth = level if level < depth else depth
                if (cell_depth == 0 and step > 0) or depth == 0:
                    # the cell spans the whole axis: it meets only itself across it
                    if not periodic[axis]:
                        inside = False
                        break
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
                    inside = False
                    break
                key = (key & ~mask) | moved
            if not inside:
                continue
            j = _gallop(keys, key, last[d])
            last[d] = j
            if chosen[j]:
                a = _find(parent, i)
                b = _find(parent, j)
                if a != b:
                    if a < b:
                        parent[b] = a
                    else:
                        parent[a] = b
    labels = np.full(n, -1, dtype=np.int64)
    root_label = np.full(n, -1, dtype=np.int64)
    count = 0
    for i in range(n):
        if not chosen[i]:
            continue
        r = _find(parent, i)
        if root_label[r] < 0:
            root_label[r] = count
            count += 1
        labels[i] = root_label[r]
    return labels, count


def label_leaves(
    keys: NDArray[np.uint64],
    levels: NDArray[np.uint8],
    chosen: NDArray[np.bool_],
    layout: KeyLayout,
    periodic: tuple[int, ...],
    directions: NDArray[np.int8],
) -> tuple[NDArray[np.int64], int]:
    """Component labels of the chosen leaves (numbered by first leaf), and their count."""
    k = layout.ndim
    positions = layout.position_table
    masks = np.array(layout.masks, dtype=np.uint64)
    periodic_mask = np.zeros(k, dtype=bool)
    periodic_mask[list(periodic)] = True
    labels, count = _label(
        keys,
        levels,
        chosen,
        np.asarray(layout.max_depth, dtype=np.int64),
        masks,
        positions,
        periodic_mask,
        directions,
    )
    return labels, int(count)
