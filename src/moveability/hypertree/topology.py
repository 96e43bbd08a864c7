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
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from ..types import Array
from ._kernels import (
    adjacent_and_face_pairs,
    adjacent_pairs,
    edge_components,
    label_leaves,
    remap_pairs,
)
from .status import IN, status_mask
from .tree import HyperTree, to_coordinates

__all__ = [
    "adjacency",
    "boundary_faces",
    "components",
    "directions",
    "edge_components",
    "refined_adjacency",
    "refined_touching",
    "touching",
]


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
    ``O(n D log n)`` for ``n`` leaves and ``D`` probe directions (``2k`` for
    face adjacency), in a compiled kernel; each pair is written once, by its
    finer leaf, so no list of repeated pairs is sorted.

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
    pairs = adjacent_pairs(
        tree.keys, tree.levels, chosen, tree.layout, tree.periodic, directions(tree.ndim, c)
    )
    return pairs.astype(np.intp, copy=False)


def _refinement(
    tree: HyperTree, old_tree: HyperTree, old_index: NDArray[np.intp], status: int | None
) -> tuple[NDArray[np.bool_], NDArray[np.bool_], NDArray[np.int64]] | None:
    """For a tree refined from ``old_tree`` (``old_index`` as in
    :func:`refined_adjacency`): the leaves with the ``status``, the kept leaves
    and each old leaf's new index (-1 where it was split); None when a split
    leaf did not have the ``status`` (its neighbours are then not all known)."""
    chosen = (
        np.ones(len(tree), dtype=bool) if status is None else (status_mask(status)[tree.status])
    )
    old_chosen = (
        np.ones(len(old_tree), dtype=bool)
        if status is None
        else (status_mask(status)[old_tree.status])
    )
    old_index = np.asarray(old_index, dtype=np.int64)
    if old_index.shape != (len(tree),) or old_index.max(initial=-1) >= len(old_tree):
        raise InvalidParameterError(
            "old_index", f"one index below {len(old_tree)} (or -1) per leaf", old_index.shape
        )
    kept = old_index >= 0
    new_of_old = np.full(len(old_tree), -1, dtype=np.int64)
    new_of_old[old_index[kept]] = np.flatnonzero(kept)
    if ((new_of_old < 0) & ~old_chosen).any():
        return None
    return chosen, kept, new_of_old


def refined_adjacency(
    tree: HyperTree,
    old_tree: HyperTree,
    old_pairs: NDArray[np.intp],
    old_index: NDArray[np.intp],
    *,
    status: int | None = None,
    connectivity: int = 1,
) -> NDArray[np.intp]:
    """:func:`adjacency` of a tree refined from ``old_tree``, whose pairs are known.

    ``old_pairs`` are ``old_tree``'s pairs for the same ``status`` and
    ``connectivity``; ``old_index`` gives each leaf of ``tree`` its index in
    ``old_tree``, -1 for a new leaf (a child of a split one); kept leaves keep
    their statuses. Kept leaves keep their pairs with each other; only the new
    leaves and the kept leaves that touched a split one probe. When a split
    leaf did not have the ``status`` (its neighbours are then not all known),
    the plain :func:`adjacency` is computed.

    Examples
    --------
    >>> import numpy as np
    >>> from moveability import BOUNDARY, HyperTree, adjacency
    >>> def undecided(lo, hi):
    ...     return np.full(len(lo), BOUNDARY, dtype=np.uint8)
    >>> coarse = HyperTree.build([0, 0], [1, 1], undecided, max_depth=3, stop_level=1)
    >>> fine = coarse.refine([True, False, False, False], undecided)
    >>> index = np.array([-1, -1, -1, -1, 1, 2, 3])  # the children of leaf 0 come first
    >>> pairs = refined_adjacency(fine, coarse, adjacency(coarse), index)
    >>> bool(np.array_equal(pairs, adjacency(fine)))
    True
    """
    c = _check_connectivity(tree, connectivity)
    refined = _refinement(tree, old_tree, old_index, status)
    if refined is None:
        return adjacency(tree, status=status, connectivity=c)
    chosen, kept, new_of_old = refined
    sources = ~kept
    known = remap_pairs(np.asarray(old_pairs, dtype=np.int64).reshape(-1, 2), new_of_old, sources)
    return adjacent_pairs(
        tree.keys,
        tree.levels,
        chosen,
        tree.layout,
        tree.periodic,
        directions(tree.ndim, c),
        sources=sources,
        fresh=~kept,
        known=known,
    ).astype(np.intp, copy=False)


def touching(
    tree: HyperTree, *, status: int | None = None
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """:func:`adjacency` by a shared vertex and by a shared face, from one search.

    The pairs by a face are those that the vertex search finds along an axis
    (each pair is found from its finer leaf in both): ``(adjacency(tree,
    status=status, connectivity=tree.ndim), adjacency(tree, status=status,
    connectivity=1))``.

    Examples
    --------
    >>> import numpy as np
    >>> from moveability import HyperTree
    >>> tree = HyperTree.from_array(np.ones((2, 2), dtype=bool), merge=False)
    >>> vertex, face = touching(tree)
    >>> len(vertex), face.tolist()
    (6, [[0, 1], [0, 2], [1, 3], [2, 3]])
    """
    chosen = (
        np.ones(len(tree), dtype=bool) if status is None else (status_mask(status)[tree.status])
    )
    pairs, faces = adjacent_and_face_pairs(
        tree.keys, tree.levels, chosen, tree.layout, tree.periodic, directions(tree.ndim, tree.ndim)
    )
    return pairs.astype(np.intp, copy=False), faces.astype(np.intp, copy=False)


def refined_touching(
    tree: HyperTree,
    old_tree: HyperTree,
    old_pairs: NDArray[np.intp],
    old_face_pairs: NDArray[np.intp],
    old_index: NDArray[np.intp],
    *,
    status: int | None = None,
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """:func:`touching` of a tree refined from ``old_tree``, whose pairs are known.

    ``old_pairs`` and ``old_face_pairs`` are ``touching(old_tree, status=status)``;
    ``old_index`` as in :func:`refined_adjacency`: kept leaves keep their pairs
    of both kinds with each other, and only the new leaves and the kept leaves
    that touched a split one probe (once, for both kinds).

    Examples
    --------
    >>> import numpy as np
    >>> from moveability import BOUNDARY, HyperTree
    >>> def undecided(lo, hi):
    ...     return np.full(len(lo), BOUNDARY, dtype=np.uint8)
    >>> coarse = HyperTree.build([0, 0], [1, 1], undecided, max_depth=3, stop_level=1)
    >>> fine = coarse.refine([True, False, False, False], undecided)
    >>> index = np.array([-1, -1, -1, -1, 1, 2, 3])  # the children of leaf 0 come first
    >>> vertex, face = refined_touching(fine, coarse, *touching(coarse), index)
    >>> all(np.array_equal(a, b) for a, b in zip((vertex, face), touching(fine)))
    True
    """
    refined = _refinement(tree, old_tree, old_index, status)
    if refined is None:
        return touching(tree, status=status)
    chosen, kept, new_of_old = refined
    # the kept leaves that touched a split one probe: those by a face among them
    pairs, faces = adjacent_and_face_pairs(
        tree.keys,
        tree.levels,
        chosen,
        tree.layout,
        tree.periodic,
        directions(tree.ndim, tree.ndim),
        refined=(~kept, (np.asarray(old_pairs), np.asarray(old_face_pairs)), new_of_old),
    )
    return pairs.astype(np.intp, copy=False), faces.astype(np.intp, copy=False)


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


def boundary_faces(
    tree: HyperTree, chosen: ArrayLike
) -> tuple[Array, Array, NDArray[np.intp], NDArray[np.int8]]:
    """Faces of the outer surface of the union of the chosen leaves.

    Each face is a piece of a chosen leaf's face where the leaf meets an
    unchosen leaf (across periodic axes too) or the border of the box; faces
    between two chosen leaves are left out. Where a large chosen leaf meets
    several smaller leaves, only the pieces against unchosen ones are kept,
    so the faces tile the surface exactly.

    Parameters
    ----------
    tree : HyperTree
    chosen : array_like of bool
        Mask over the leaves.

    Returns
    -------
    lo, hi : ndarray of float64, shape (m, k)
        Corners of the faces; ``lo[:, axis] == hi[:, axis]`` on the normal axis.
    axis : ndarray of intp, shape (m,)
        Normal axis of each face.
    side : ndarray of int8, shape (m,)
        +1 where the chosen leaf lies below the face along ``axis``, -1 above.

    Notes
    -----
    ``O(n k log n)`` for ``n`` leaves: one face-adjacency probe of the tree
    (:func:`moveability.hypertree.topology.adjacency`), then numpy on the pairs.

    Examples
    --------
    >>> import numpy as np
    >>> from moveability import HyperTree
    >>> tree = HyperTree.from_array(np.ones((2, 2, 2), dtype=bool), merge=False)
    >>> lo, hi, axis, side = boundary_faces(tree, [True, True] + [False] * 6)
    >>> len(axis)  # two unit cubes side by side: 10 outer faces
    10
    """
    mask = np.asarray(chosen, dtype=bool).ravel()
    if mask.size != len(tree):
        raise InvalidParameterError("chosen", f"a mask of {len(tree)} leaves", mask.size)
    k = tree.ndim
    anchors = tree.anchors
    ends = anchors + tree.layout.cell_sizes(tree.levels)
    res = np.left_shift(np.int64(1), np.asarray(tree.max_depth, dtype=np.int64))
    pairs = adjacency(tree, connectivity=1)
    pairs = pairs[mask[pairs[:, 0]] != mask[pairs[:, 1]]]
    s = np.where(mask[pairs[:, 0]], pairs[:, 0], pairs[:, 1])
    o = np.where(mask[pairs[:, 0]], pairs[:, 1], pairs[:, 0])
    lo_parts: list[NDArray[np.int64]] = []
    hi_parts: list[NDArray[np.int64]] = []
    axis_parts: list[NDArray[np.intp]] = []
    side_parts: list[NDArray[np.int8]] = []
    overlap_lo = np.maximum(anchors[s], anchors[o])
    overlap_hi = np.minimum(ends[s], ends[o])
    inner = np.flatnonzero(mask)
    for a in range(k):
        wrap = a in tree.periodic
        others = np.ones(s.size, dtype=bool)
        for b in range(k):
            if b != a:
                others &= overlap_hi[:, b] > overlap_lo[:, b]
        top_s = ends[s, a] % res[a] if wrap else ends[s, a]
        top_o = ends[o, a] % res[a] if wrap else ends[o, a]
        for side, touch, plane in (
            (1, top_s == anchors[o, a], ends[s, a]),
            (-1, top_o == anchors[s, a], anchors[s, a]),
        ):
            sel = touch & others
            f_lo, f_hi = overlap_lo[sel].copy(), overlap_hi[sel].copy()
            f_lo[:, a] = f_hi[:, a] = plane[sel]
            lo_parts.append(f_lo)
            hi_parts.append(f_hi)
            axis_parts.append(np.full(f_lo.shape[0], a, dtype=np.intp))
            side_parts.append(np.full(f_lo.shape[0], side, dtype=np.int8))
        if wrap:
            continue
        # the border of the box
        for side, at, plane in (
            (1, ends[inner, a] == res[a], ends[inner, a]),
            (-1, anchors[inner, a] == 0, anchors[inner, a]),
        ):
            f_lo, f_hi = anchors[inner][at].copy(), ends[inner][at].copy()
            f_lo[:, a] = f_hi[:, a] = plane[at]
            lo_parts.append(f_lo)
            hi_parts.append(f_hi)
            axis_parts.append(np.full(f_lo.shape[0], a, dtype=np.intp))
            side_parts.append(np.full(f_lo.shape[0], side, dtype=np.int8))
    ints_lo = np.concatenate(lo_parts) if lo_parts else np.zeros((0, k), dtype=np.int64)
    ints_hi = np.concatenate(hi_parts) if hi_parts else np.zeros((0, k), dtype=np.int64)
    return (
        to_coordinates(tree.lo, tree.hi, tree.layout, ints_lo),
        to_coordinates(tree.lo, tree.hi, tree.layout, ints_hi),
        np.concatenate(axis_parts) if axis_parts else np.zeros(0, dtype=np.intp),
        np.concatenate(side_parts) if side_parts else np.zeros(0, dtype=np.int8),
    )
