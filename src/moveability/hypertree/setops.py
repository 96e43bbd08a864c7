"""Boolean operations on trees: union, intersection, difference, complement.

Two trees over the same box and periodicity are combined on their common
refinement: every leaf of the result lies inside exactly one leaf of each
operand. Statuses combine by three-valued (Kleene) logic, so a BOUNDARY leaf
stays undecided unless the other operand decides the result (``OUT & x`` is
``OUT``, ``IN | x`` is ``IN``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import IncompatibleTreesError, ResolutionError
from .keys import KeyLayout
from .status import AND_TABLE, NOT_TABLE, OR_TABLE
from .subdivision import merge_siblings
from .tree import DEFAULT_MAX_LEAVES, HyperTree

__all__ = ["complement", "difference", "equals", "intersection", "overlay", "union"]


def _check_compatible(a: HyperTree, b: HyperTree) -> None:
    if not isinstance(b, HyperTree):
        raise IncompatibleTreesError("other", "a HyperTree", type(b).__name__)
    if a.ndim != b.ndim:
        raise IncompatibleTreesError("other", f"a tree of {a.ndim} axes", b.ndim)
    if not (np.array_equal(a.lo, b.lo) and np.array_equal(a.hi, b.hi)):
        raise IncompatibleTreesError(
            "other",
            f"a tree over the box lo={a.lo.tolist()}, hi={a.hi.tolist()}",
            f"lo={b.lo.tolist()}, hi={b.hi.tolist()}",
        )
    if a.periodic != b.periodic:
        raise IncompatibleTreesError("other", f"periodic axes {a.periodic}", b.periodic)


def relayout(tree: HyperTree, max_depth: tuple[int, ...]) -> HyperTree:
    """The same set in a layout whose depths are at least the tree's on every axis.

    A leaf that the new layout cannot represent at its level is cut into the
    new layout's cells of that level.
    """
    if max_depth == tree.max_depth:
        return tree
    old, new = tree.layout, KeyLayout(max_depth)
    old_md = np.asarray(old.max_depth)
    new_md = np.asarray(new.max_depth)
    anchors = tree.anchors << (new_md - old_md)[None, :]
    levels = tree.levels.astype(np.int64)
    # extra bits of depth on each axis at the leaf's own level
    extra = new.axis_depths(levels) - old.axis_depths(levels)
    n_parts = np.left_shift(1, extra.sum(axis=1))
    total = int(n_parts.sum())
    if total > DEFAULT_MAX_LEAVES:
        raise ResolutionError(
            "other",
            f"trees whose common refinement has at most {DEFAULT_MAX_LEAVES} cells "
            f"(per-axis depths {tree.max_depth} in the layout {max_depth} need {total})",
            tree,
        )
    owner = np.repeat(np.arange(len(tree)), n_parts)
    # enumerate the sub-cells of each leaf: mixed-radix digits over the axes
    rank = np.arange(owner.size) - np.repeat(np.cumsum(n_parts) - n_parts, n_parts)
    sizes = new.cell_sizes(levels)[owner]
    sub = anchors[owner].copy()
    for axis in range(tree.ndim):
        e = extra[owner, axis]
        digit = rank & ((1 << e) - 1)
        rank = rank >> e
        sub[:, axis] += digit * sizes[:, axis]
    keys = new.encode(sub)
    order = np.argsort(keys, kind="stable")
    return HyperTree(
        tree.lo,
        tree.hi,
        new.max_depth,
        keys[order],
        tree.levels[owner][order],
        tree.status[owner][order],
        tree.periodic,
    )


def overlay(
    a: HyperTree, b: HyperTree
) -> tuple[
    NDArray[np.uint64],
    NDArray[np.uint8],
    NDArray[np.intp],
    NDArray[np.intp],
    KeyLayout,
    HyperTree,
    HyperTree,
]:
    """Common refinement of two trees.

    Returns ``(keys, levels, index_a, index_b, layout, a2, b2)``: the leaves of the
    refinement sorted by key, the leaf of ``a2`` and of ``b2`` holding each, the
    shared layout, and the operands in that layout.
    """
    _check_compatible(a, b)
    depth = tuple(max(x, y) for x, y in zip(a.max_depth, b.max_depth, strict=True))
    a2, b2 = relayout(a, depth), relayout(b, depth)
    ib = np.searchsorted(b2.keys, a2.keys, side="right") - 1
    from_a = b2.levels[ib] <= a2.levels  # a's leaf is inside b's (or equal)
    ia = np.searchsorted(a2.keys, b2.keys, side="right") - 1
    from_b = a2.levels[ia] < b2.levels  # b's leaf is strictly inside a's
    keys = np.concatenate([a2.keys[from_a], b2.keys[from_b]])
    levels = np.concatenate([a2.levels[from_a], b2.levels[from_b]])
    index_a = np.concatenate([np.flatnonzero(from_a), ia[from_b]])
    index_b = np.concatenate([ib[from_a], np.flatnonzero(from_b)])
    order = np.argsort(keys, kind="stable")
    return keys[order], levels[order], index_a[order], index_b[order], a2.layout, a2, b2


def _combine(a: HyperTree, b: HyperTree, table: NDArray[np.uint8]) -> HyperTree:
    keys, levels, ia, ib, layout, a2, b2 = overlay(a, b)
    status = table[a2.status[ia], b2.status[ib]]
    keys, levels, status = merge_siblings(layout, keys, levels, status)
    return HyperTree(a.lo, a.hi, layout.max_depth, keys, levels, status, a.periodic)


def union(a: HyperTree, b: HyperTree) -> HyperTree:
    """The set of points in ``a`` or in ``b`` (also ``a | b``).

    Examples
    --------
    >>> import numpy as np
    >>> from moveability import HyperTree, union
    >>> a = HyperTree.from_array(np.array([True, False, False, False]))
    >>> b = HyperTree.from_array(np.array([False, True, False, False]))
    >>> union(a, b).status.tolist()
    [1, 2]
    """
    return _combine(a, b, OR_TABLE)


def intersection(a: HyperTree, b: HyperTree) -> HyperTree:
    """The set of points in both ``a`` and ``b`` (also ``a & b``).

    Examples
    --------
    >>> import numpy as np
    >>> from moveability import HyperTree, intersection
    >>> a = HyperTree.from_array(np.array([True, True, False, False]))
    >>> b = HyperTree.from_array(np.array([False, True, True, False]))
    >>> intersection(a, b).status.tolist()
    [2, 1, 2]
    """
    return _combine(a, b, AND_TABLE)


def complement(a: HyperTree) -> HyperTree:
    """The points of the box not in ``a`` (also ``~a``); BOUNDARY stays BOUNDARY.

    Examples
    --------
    >>> import numpy as np
    >>> from moveability import HyperTree, complement
    >>> complement(HyperTree.from_array(np.array([True, False]))).status.tolist()
    [2, 1]
    """
    return a._replace(status=NOT_TABLE[a.status])


def difference(a: HyperTree, b: HyperTree) -> HyperTree:
    """The points of ``a`` not in ``b`` (also ``a - b``).

    Examples
    --------
    >>> import numpy as np
    >>> from moveability import HyperTree, difference
    >>> a = HyperTree.from_array(np.array([True, True]))
    >>> b = HyperTree.from_array(np.array([False, True]))
    >>> difference(a, b).status.tolist()
    [1, 2]
    """
    return intersection(a, complement(b))


def equals(a: HyperTree, b: HyperTree) -> bool:
    """Whether two trees give every point of the box the same status.

    Trees with different leaves may be equal: a BOUNDARY leaf and its
    subdivision into BOUNDARY leaves say the same thing of every point.

    Examples
    --------
    >>> import numpy as np
    >>> from moveability import HyperTree, equals
    >>> a = HyperTree.from_array(np.array([True, True]), merge=False)
    >>> b = HyperTree.from_array(np.array([True, True]))
    >>> len(a), len(b), equals(a, b)
    (2, 1, True)
    """
    try:
        _, _, ia, ib, _, a2, b2 = overlay(a, b)
    except IncompatibleTreesError:
        return False
    return bool(np.array_equal(a2.status[ia], b2.status[ib]))
