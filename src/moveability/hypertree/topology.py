"""Adjacency and connected components of the leaves of a tree.

Two leaves are adjacent with connectivity ``c`` when their closed boxes meet
in a face of dimension at least ``k - c``: ``c = 1`` is a shared face,
``c = k`` a shared vertex (the "orthogonal hops" of ``skimage.measure.label``).

Adjacent pairs are found by probing: from every leaf, in every direction
``d`` of ``{-1, 0, 1}^k`` with at most ``c`` non-zero entries, the finest cell
just outside the leaf is located by one binary search over the sorted keys.
When two leaves touch, the smaller one's probe across the contact lands in the
larger one (cells of a higher level are no larger on any axis), so probing
from every leaf finds every adjacent pair, with ``2k`` probes per leaf for
face adjacency.
"""

from __future__ import annotations

import itertools

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError
from ._kernels import label_leaves
from .status import IN, status_mask
from .tree import HyperTree

__all__ = ["adjacency", "components", "directions"]


def directions(ndim: int, connectivity: int) -> NDArray[np.int8]:
    """Probe directions: vectors of ``{-1, 0, 1}^ndim`` with 1 to ``connectivity`` non-zeros.

    Examples
    --------
    >>> directions(2, 1).tolist()
    [[-1, 0], [0, -1], [0, 1], [1, 0]]
    >>> len(directions(3, 3))
    26
    """
    out = [
        d
        for d in itertools.product((-1, 0, 1), repeat=ndim)
        if 1 <= sum(x != 0 for x in d) <= connectivity
    ]
    return np.array(out, dtype=np.int8).reshape(-1, ndim)


def _check_connectivity(tree: HyperTree, connectivity: int) -> int:
    if isinstance(connectivity, bool) or not isinstance(connectivity, int | np.integer):
        raise InvalidParameterError("connectivity", f"an int in [1, {tree.ndim}]", connectivity)
    if not 1 <= int(connectivity) <= tree.ndim:
        raise InvalidParameterError("connectivity", f"an int in [1, {tree.ndim}]", connectivity)
    return int(connectivity)


def _probe_pairs(
    tree: HyperTree, sources: NDArray[np.intp], connectivity: int
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """All (source, leaf) pairs found by probing from ``sources`` (with repeats)."""
    layout = tree.layout
    keys0 = tree.keys[sources]
    sizes = layout.cell_sizes(tree.levels[sources])
    periodic = set(tree.periodic)
    src_parts, dst_parts = [], []
    for d in directions(tree.ndim, connectivity):
        keys = keys0
        inside = np.ones(keys.size, dtype=bool)
        for axis in np.flatnonzero(d):
            if d[axis] > 0:
                keys, ok = layout.shift(keys, int(axis), sizes[:, axis], +1, axis in periodic)
            else:
                keys, ok = layout.shift(keys, int(axis), 1, -1, axis in periodic)
            inside &= ok
        hit = np.searchsorted(tree.keys, keys[inside], side="right") - 1
        src_parts.append(sources[inside])
        dst_parts.append(hit)
    if not src_parts:
        empty = np.zeros(0, dtype=np.intp)
        return empty, empty
    return np.concatenate(src_parts), np.concatenate(dst_parts)


def adjacency(
    tree: HyperTree, *, status: int | None = None, connectivity: int = 1
) -> NDArray[np.intp]:
    """Pairs of adjacent leaves, as an (m, 2) array of leaf indices ``i < j``.

    Parameters
    ----------
    tree : HyperTree
    status : int, optional
        Keep only pairs of leaves whose status is in ``status`` (e.g.
        ``IN | BOUNDARY``); all leaves by default.
    connectivity : int, optional
        1 for a shared face up to ``k`` for a shared vertex.

    Notes
    -----
    ``O(n D log n)`` for ``n`` leaves and ``D`` probe directions
    (``2k`` for face adjacency).

    Examples
    --------
    >>> import numpy as np
    >>> from moveability import HyperTree, adjacency
    >>> tree = HyperTree.from_array(np.ones((2, 2), dtype=bool), merge=False)
    >>> adjacency(tree).tolist()
    [[0, 1], [0, 2], [1, 3], [2, 3]]
    >>> len(adjacency(tree, connectivity=2))
    6
    """
    c = _check_connectivity(tree, connectivity)
    chosen = (
        np.ones(len(tree), dtype=bool) if status is None else (status_mask(status)[tree.status])
    )
    src, dst = _probe_pairs(tree, np.flatnonzero(chosen), c)
    keep = chosen[dst] & (src != dst)
    lo = np.minimum(src, dst)[keep].astype(np.int64)
    hi = np.maximum(src, dst)[keep].astype(np.int64)
    # one integer per pair, so that duplicates go in a 1-D sort
    n = max(len(tree), 1)
    packed = np.sort(lo * n + hi)
    if packed.size:
        packed = packed[np.r_[True, packed[1:] != packed[:-1]]]
    return np.stack([packed // n, packed % n], axis=1).astype(np.intp)


def components(
    tree: HyperTree, *, status: int = IN, connectivity: int = 1
) -> tuple[NDArray[np.int64], int]:
    """Connected components of the leaves whose status is in ``status``.

    Parameters
    ----------
    tree : HyperTree
    status : int, optional
        Statuses taken, e.g. ``IN`` or ``IN | BOUNDARY``.
    connectivity : int, optional
        1 for a shared face up to ``k`` for a shared vertex; periodic axes are
        crossed.

    Returns
    -------
    labels : ndarray of int64
        One label per leaf, ``-1`` for leaves not taken. Labels are numbered
        in the order of their first leaf (by key), so they are deterministic.
    count : int
        Number of components.

    Notes
    -----
    ``O(n D log n)`` for ``n`` leaves and ``D`` probe directions, in a compiled
    kernel that merges components with a union-find as it probes (no edge
    list is stored). :func:`adjacency` probes the same way with numpy.

    Examples
    --------
    >>> import numpy as np
    >>> from moveability import HyperTree, components
    >>> grid = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 0], [0, 0, 0, 1]], dtype=bool)
    >>> components(HyperTree.from_array(grid))[1]
    3
    >>> components(HyperTree.from_array(grid), connectivity=2)[1]
    2
    >>> components(HyperTree.from_array(grid, periodic=[0, 1]), connectivity=2)[1]
    1
    """
    c = _check_connectivity(tree, connectivity)
    chosen = status_mask(status)[tree.status]
    return label_leaves(
        tree.keys, tree.levels, chosen, tree.layout, tree.periodic, directions(tree.ndim, c)
    )
