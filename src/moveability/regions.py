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

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from .sheets import SheetTable
from .status import IN, OUT

__all__ = ["RegionGraph", "region_graph"]


@dataclass(frozen=True)
class RegionGraph:
    """Components of the certain and possible graphs.

    Attributes
    ----------
    certain : (n, P) int64
        Certain component of each node, -1 where the node is not certified.
    possible : (2, n, P) int64
        Possible component of each node for det A > 0 (row 0) and < 0 (row 1),
        -1 where the node cannot hold a valid configuration of that sign.
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


def _components(
    n_nodes: int, edges: NDArray[np.int64], taken: NDArray[np.bool_]
) -> tuple[NDArray[np.int64], int]:
    """Components of the taken nodes, numbered by first node; -1 elsewhere."""
    if edges.size:
        graph = coo_matrix(
            (np.ones(edges.shape[0], dtype=np.int8), (edges[:, 0], edges[:, 1])),
            shape=(n_nodes, n_nodes),
        ).tocsr()
    else:
        graph = coo_matrix((n_nodes, n_nodes), dtype=np.int8).tocsr()
    _, raw = connected_components(graph, directed=False)
    labels = np.full(n_nodes, -1, dtype=np.int64)
    nodes = np.flatnonzero(taken)
    if not nodes.size:
        return labels, 0
    uniq, first = np.unique(raw[nodes], return_index=True)
    order = np.argsort(first, kind="stable")
    rank = np.empty(uniq.size, dtype=np.int64)
    rank[order] = np.arange(uniq.size)
    labels[nodes] = rank[np.searchsorted(uniq, raw[nodes])]
    return labels, int(uniq.size)


def _posture_pairs(postures: NDArray[np.int64]) -> list[tuple[int, int, NDArray[np.bool_]]]:
    """Pairs of postures with the legs on which they differ."""
    out = []
    for p in range(postures.shape[0]):
        for q in range(p + 1, postures.shape[0]):
            out.append((p, q, postures[p] != postures[q]))
    return out


def region_graph(
    table: SheetTable,
    pairs: NDArray[np.intp],
    postures: NDArray[np.int64],
    cross_serial: bool = True,
) -> RegionGraph:
    """Build both graphs from a sheet table and the touching leaf pairs.

    With ``cross_serial=False`` no path may meet a serial singularity (det B = 0)
    either: postures never change, and the components are the generalized
    aspects (det A and det B of constant sign).
    """
    n, n_post = table.status.shape
    node = np.arange(n * n_post, dtype=np.int64).reshape(n, n_post)
    a, b = pairs[:, 0], pairs[:, 1]
    group = table.group if cross_serial else np.zeros_like(table.group)
    certified = (table.status == IN) | group
    # legs whose branches may meet in a leaf; none may be crossed without serial ones
    folding = table.folding if cross_serial else np.zeros_like(table.folding)

    # ---------------------------------------------------------------- certain
    edges = []
    for p in range(n_post):
        sa, sb = table.sign[a, p], table.sign[b, p]
        # two regular IN sheets, or a regular IN sheet and a fold group member
        ok = (sa == sb) & (
            ((table.status[a, p] == IN) & certified[b, p])
            | (certified[a, p] & (table.status[b, p] == IN))
        )
        edges.append(np.stack([node[a[ok], p], node[b[ok], p]], axis=1))
    for p, q, differ in _posture_pairs(postures):
        # members of one fold group: they differ only on legs folding in the leaf
        same_group = (~differ[None, :] | folding).all(axis=1)
        ok = group[:, p] & group[:, q] & same_group
        ok &= table.sign[:, p] == table.sign[:, q]
        idx = np.flatnonzero(ok)
        edges.append(np.stack([node[idx, p], node[idx, q]], axis=1))
    certain_edges = np.concatenate(edges)
    certain, n_certain = _components(n * n_post, certain_edges, certified.ravel())
    certain_sign = np.zeros(n_certain, dtype=np.int8)
    labelled = certain >= 0
    certain_sign[certain[labelled]] = table.sign.ravel()[labelled]

    # --------------------------------------------------------------- possible
    possible = np.full((2, n * n_post), -1, dtype=np.int64)
    counts = []
    for row, s in enumerate((1, -1)):
        alive = (table.status != OUT) & ((table.sign == s) | (table.sign == 0))
        edges = []
        for p in range(n_post):
            ok = alive[a, p] & alive[b, p]
            edges.append(np.stack([node[a[ok], p], node[b[ok], p]], axis=1))
        may_fold = folding  # legs not certified regular nor unreachable
        for p, q, differ in _posture_pairs(postures):
            same_leaf = (~differ[None, :] | may_fold).all(axis=1)
            ok = alive[:, p] & alive[:, q] & same_leaf
            idx = np.flatnonzero(ok)
            edges.append(np.stack([node[idx, p], node[idx, q]], axis=1))
        labels, count = _components(n * n_post, np.concatenate(edges), alive.ravel())
        possible[row] = labels
        counts.append(count)
    return RegionGraph(
        certain=certain.reshape(n, n_post),
        possible=possible.reshape(2, n, n_post),
        certain_sign=certain_sign,
        certain_edges=certain_edges,
        n_possible=(counts[0], counts[1]),
    )
