"""Projection of a tree onto some of its axes."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError
from .keys import KeyLayout
from .setops import union
from .status import BOUNDARY, IN, OUT
from .subdivision import subdivide
from .tree import HyperTree

__all__ = ["project"]


def _check_axes(tree: HyperTree, axes: Sequence[int]) -> tuple[int, ...]:
    try:
        values = tuple(int(a) for a in axes)
    except (TypeError, ValueError):
        raise InvalidParameterError("axes", "a sequence of axis numbers", axes) from None
    if not values or len(set(values)) != len(values):
        raise InvalidParameterError("axes", "a non-empty sequence of distinct axes", axes)
    if any(not 0 <= a < tree.ndim for a in values):
        raise InvalidParameterError("axes", f"axis numbers in [0, {tree.ndim - 1}]", axes)
    return values


def _maximal(
    layout: KeyLayout, keys: NDArray[np.uint64], levels: NDArray[np.uint8]
) -> tuple[NDArray[np.uint64], NDArray[np.uint8]]:
    """The cells of a set of cells that no other cell of the set contains, sorted.

    Cells of one layout are nested or disjoint, so after sorting by key (larger
    cells first on ties), a cell is contained in an earlier one exactly when an
    earlier cell's key range reaches past its key.
    """
    if not keys.size:
        return keys, levels
    order = np.lexsort((levels, keys))
    keys, levels = keys[order], levels[order]
    ends = keys + layout.spans(levels)
    reach = np.empty_like(ends)
    reach[0] = 0
    np.maximum.accumulate(ends[:-1], out=reach[1:])
    keep = reach <= keys
    return keys[keep], levels[keep]


def _cover(
    layout: KeyLayout, cells: NDArray[np.uint64], cell_levels: NDArray[np.uint8]
) -> tuple[NDArray[np.uint64], NDArray[np.uint8], NDArray[np.uint8]]:
    """Leaves of the coarsest tree in which disjoint ``cells`` are IN leaves, the rest OUT."""
    n = cells.size

    def decide(keys: NDArray[np.uint64], _: NDArray[np.int64], level: int) -> NDArray[np.uint8]:
        if not n:
            return np.full(keys.size, OUT, dtype=np.uint8)
        first = np.searchsorted(cells, keys, side="left")
        last = np.searchsorted(cells, keys + np.uint64(layout.span(level)), side="left")
        at = np.minimum(first, n - 1)
        exact = (last > first) & (cells[at] == keys) & (cell_levels[at] == level)
        return np.where(last == first, OUT, np.where(exact, IN, BOUNDARY)).astype(np.uint8)

    return subdivide(layout, decide, max_leaves=np.iinfo(np.int64).max)


def project(tree: HyperTree, axes: Sequence[int]) -> HyperTree:
    """Projection of the set onto the listed axes, as a tree of ``len(axes)`` axes.

    A projected cell is IN where the projections of IN leaves cover it, OUT
    where no IN or BOUNDARY leaf projects onto it, BOUNDARY otherwise. So the
    IN part is inside the true projection and the IN and BOUNDARY parts hold it.

    Parameters
    ----------
    tree : HyperTree
    axes : sequence of int
        Axes kept, in the order of the new tree's axes.

    Notes
    -----
    ``O(n log n)`` for ``n`` leaves: the projected leaves are sorted once, the
    cells covered by others dropped, and the rest completed into a tree.

    Examples
    --------
    >>> import numpy as np
    >>> from moveability import HyperTree, project
    >>> grid = np.zeros((4, 4), dtype=bool)
    >>> grid[1, 2] = True
    >>> project(HyperTree.from_array(grid), [1]).status.tolist()
    [2, 1, 2]
    """
    kept = _check_axes(tree, axes)
    layout = KeyLayout(tuple(tree.max_depth[a] for a in kept))
    anchors = tree.anchors[:, list(kept)]
    keys = layout.encode(anchors)
    levels = np.minimum(tree.levels, layout.n_levels).astype(np.uint8)
    periodic = tuple(i for i, a in enumerate(kept) if a in tree.periodic)
    lo, hi = tree.lo[list(kept)], tree.hi[list(kept)]

    def tree_of(mask: NDArray[np.bool_], covered: int) -> HyperTree:
        cells, cell_levels = _maximal(layout, keys[mask], levels[mask])
        k, lv, st = _cover(layout, cells, cell_levels)
        st = np.where(st == IN, np.uint8(covered), st).astype(np.uint8)
        return HyperTree(lo, hi, layout.max_depth, k, lv, st, periodic)

    inner = tree_of(tree.status == IN, IN)
    outer = tree_of(tree.status != OUT, BOUNDARY)
    return union(inner, outer)
