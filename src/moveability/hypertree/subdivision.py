"""Top-down subdivision and bottom-up merging of 2^k-tree leaves.

Both work level by level on whole arrays of cells: the frontier of a level is
classified at once, its undecided cells are split together, and sibling
groups are merged together.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from ..errors import ResolutionError
from .keys import KeyLayout
from .status import BOUNDARY

__all__ = ["merge_siblings", "split_leaves", "subdivide"]

Decide = Callable[[NDArray[np.uint64], NDArray[np.int64], int], NDArray[np.uint8]]
Progress = Callable[[int, int, int], object]


def subdivide(
    layout: KeyLayout,
    decide: Decide,
    *,
    max_leaves: int,
    progress: Progress | None = None,
    stop_level: int | None = None,
) -> tuple[NDArray[np.uint64], NDArray[np.uint8], NDArray[np.uint8]]:
    """Subdivide the root cell until every leaf is decided or at maximal depth.

    Parameters
    ----------
    layout : KeyLayout
        Key layout of the tree.
    decide : callable
        ``decide(keys, anchors, level)`` returns one status per cell of the
        frontier; ``BOUNDARY`` cells are split while ``level`` is below the
        maximal level.
    max_leaves : int
        Raise :class:`ResolutionError` rather than hold more cells than this.
    progress : callable, optional
        Called as ``progress(level, n_frontier, n_leaves)`` after each level.
    stop_level : int, optional
        Split no cell of this level or deeper (default: the maximal level); the
        levels beyond are left to :func:`split_leaves`.

    Returns
    -------
    keys, levels, status : ndarray
        The leaves, sorted by key.
    """
    k = layout.ndim
    keys = np.zeros(1, dtype=np.uint64)
    anchors = np.zeros((1, k), dtype=np.int64)
    out_keys: list[NDArray[np.uint64]] = []
    out_levels: list[NDArray[np.uint8]] = []
    out_status: list[NDArray[np.uint8]] = []
    n_leaves = 0
    level = 0
    while keys.size:
        status = np.asarray(decide(keys, anchors, level), dtype=np.uint8)
        split = status == BOUNDARY
        if level >= (layout.n_levels if stop_level is None else min(stop_level, layout.n_levels)):
            split[:] = False
        leaf = ~split
        out_keys.append(keys[leaf])
        out_levels.append(np.full(int(leaf.sum()), level, dtype=np.uint8))
        out_status.append(status[leaf])
        n_leaves += int(leaf.sum())
        n_split = int(split.sum())
        if progress is not None:
            progress(level, n_split, n_leaves)
        if not n_split:
            break
        key_off, anchor_off = layout.child_offsets(level)
        n_next = n_split * key_off.size
        if n_leaves + n_next > max_leaves:
            raise ResolutionError(
                "max_depth",
                f"a depth whose tree holds at most max_leaves={max_leaves} cells "
                f"(level {level + 1} alone needs {n_next})",
                layout.max_depth,
            )
        keys = (keys[split][:, None] + key_off[None, :]).ravel()
        anchors = (anchors[split][:, None, :] + anchor_off[None, :, :]).reshape(-1, k)
        level += 1
    all_keys = np.concatenate(out_keys)
    order = np.argsort(all_keys, kind="stable")
    return all_keys[order], np.concatenate(out_levels)[order], np.concatenate(out_status)[order]


def merge_siblings(
    layout: KeyLayout,
    keys: NDArray[np.uint64],
    levels: NDArray[np.uint8],
    status: NDArray[np.uint8],
) -> tuple[NDArray[np.uint64], NDArray[np.uint8], NDArray[np.uint8]]:
    """Replace every complete group of IN (or OUT) siblings by their parent.

    Leaves must be sorted by key and partition the box. BOUNDARY leaves are
    never merged: their depth is the resolution reached so far.
    """
    keys = np.asarray(keys, dtype=np.uint64)
    levels = np.asarray(levels, dtype=np.uint8)
    status = np.asarray(status, dtype=np.uint8)
    for level in range(layout.n_levels, 0, -1):
        n = keys.size
        n_children = 1 << len(layout.split_axes[level - 1])
        parent_mask = np.uint64(layout.span(level - 1) - 1)
        first = np.flatnonzero(
            (levels == level) & ((keys & parent_mask) == 0) & (status != BOUNDARY)
        )
        first = first[first + n_children <= n]
        if not first.size:
            continue
        group = first[:, None] + np.arange(n_children)[None, :]
        same = (levels[group] == level).all(axis=1) & (status[group] == status[first][:, None]).all(
            axis=1
        )
        first = first[same]
        if not first.size:
            continue
        keep = np.ones(n, dtype=bool)
        keep[(first[:, None] + np.arange(1, n_children)[None, :]).ravel()] = False
        levels = levels.copy()
        levels[first] = level - 1
        keys, levels, status = keys[keep], levels[keep], status[keep]
    return keys, levels, status


def split_leaves(
    layout: KeyLayout,
    keys: NDArray[np.uint64],
    levels: NDArray[np.uint8],
    anchors: NDArray[np.int64],
) -> tuple[NDArray[np.uint64], NDArray[np.uint8], NDArray[np.int64]]:
    """The children of cells (keys, levels, anchors), sorted by key.

    Cells must be above the maximal level. Returns the children's keys, levels
    and anchors.
    """
    out_keys, out_levels, out_anchors = [], [], []
    for level in np.unique(levels):
        at = np.flatnonzero(levels == level)
        key_off, anchor_off = layout.child_offsets(int(level))
        out_keys.append((keys[at][:, None] + key_off[None, :]).ravel())
        out_anchors.append(
            (anchors[at][:, None, :] + anchor_off[None, :, :]).reshape(-1, layout.ndim)
        )
        out_levels.append(np.full(at.size * key_off.size, int(level) + 1, dtype=np.uint8))
    if not out_keys:
        return (
            np.zeros(0, dtype=np.uint64),
            np.zeros(0, dtype=np.uint8),
            np.zeros((0, layout.ndim), dtype=np.int64),
        )
    all_keys = np.concatenate(out_keys)
    order = np.argsort(all_keys, kind="stable")
    return all_keys[order], np.concatenate(out_levels)[order], np.concatenate(out_anchors)[order]
