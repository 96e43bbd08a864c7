"""Components from the compiled kernel against the numpy adjacency and scipy."""

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from moveability import BOUNDARY, IN, OUT, HyperTree, adjacency, components


def _by_graph(tree, status, connectivity):
    """Components from the numpy adjacency pairs, by scipy's graph labelling."""
    chosen = np.isin(tree.status, [s for s in (IN, OUT, BOUNDARY) if s & status])
    pairs = adjacency(tree, status=status, connectivity=connectivity)
    n = len(tree)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, raw = connected_components(graph, directed=False)
    labels = np.where(chosen, raw, -1)
    return labels, len(np.unique(raw[chosen]))


def _same_partition(a, b):
    taken = a >= 0
    np.testing.assert_array_equal(taken, b >= 0)
    pairs = np.unique(np.stack([a[taken], b[taken]], axis=1), axis=0)
    assert len(np.unique(pairs[:, 0])) == len(pairs) == len(np.unique(pairs[:, 1]))


def _random_tree(rng, shape, periodic):
    values = rng.choice([IN, OUT, BOUNDARY], size=shape, p=[0.45, 0.4, 0.15])
    # blocks of equal statuses give leaves at mixed levels
    coarse = rng.choice([IN, OUT], size=tuple(max(s // 4, 1) for s in shape))
    block = np.kron(coarse, np.ones(tuple(min(s, 4) for s in shape), dtype=int))
    values = np.where(rng.random(shape) < 0.5, block, values)
    return HyperTree.from_array(values.astype(np.uint8), periodic=periodic)


@pytest.mark.parametrize(
    ("shape", "periodic"),
    [((16, 32), ()), ((16, 8), (0,)), ((8, 8, 8), (1,)), ((4, 8, 4, 8), (0, 3)), ((2, 4), (0, 1))],
)
@pytest.mark.parametrize("status", [IN, IN | BOUNDARY, OUT])
def test_kernel_matches_graph_labelling(shape, periodic, status):
    rng = np.random.default_rng(sum(shape) + len(periodic) + int(status))
    for _ in range(3):
        tree = _random_tree(rng, shape, periodic)
        assert len(np.unique(tree.levels)) > 1
        for c in range(1, len(shape) + 1):
            labels, count = components(tree, status=status, connectivity=c)
            ref, ref_count = _by_graph(tree, status, c)
            assert count == ref_count
            _same_partition(labels, ref)


def test_labels_are_numbered_by_first_leaf():
    rng = np.random.default_rng(3)
    tree = _random_tree(rng, (16, 16), ())
    labels, count = components(tree, status=IN | BOUNDARY)
    firsts = [int(np.flatnonzero(labels == i)[0]) for i in range(count)]
    assert firsts == sorted(firsts)
    assert set(labels[labels >= 0].tolist()) == set(range(count))


def test_empty_selection_has_no_component():
    tree = HyperTree.from_array(np.zeros((4, 4), dtype=bool))
    labels, count = components(tree)
    assert count == 0
    assert (labels == -1).all()


@pytest.mark.parametrize("seed", range(6))
def test_edge_components_match_scipy(seed):
    """The compiled union-find labels the components scipy finds, numbered by first node,
    with edges through nodes that are not taken."""
    from moveability.hypertree.topology import edge_components

    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 400))
    m = int(rng.integers(0, 2 * n))
    edges = rng.integers(0, n, size=(m, 2))
    taken = rng.random(n) < 0.7
    labels, count = edge_components(n, edges, taken)
    graph = coo_matrix((np.ones(m), (edges[:, 0], edges[:, 1])), shape=(n, n))
    _, raw = connected_components(graph, directed=False)
    assert (labels[~taken] == -1).all()
    assert count == len(np.unique(raw[taken]))
    # the same partition of the taken nodes, numbered in the order of first nodes
    nodes = np.flatnonzero(taken)
    _, first = np.unique(raw[nodes], return_index=True)
    order = np.argsort(first)
    expected = np.empty(first.size, dtype=np.int64)
    expected[order] = np.arange(first.size)
    _, inverse = np.unique(raw[nodes], return_inverse=True)
    np.testing.assert_array_equal(labels[nodes], expected[inverse])


@pytest.mark.parametrize("seed", range(4))
def test_pairs_merged_as_remapped_are_those_remapped_then_merged(seed):
    """A coarser tree's pairs between kept leaves, merged with the pairs found as
    they are remapped, are those remapped first and then merged: kept leaves in
    order (the merge) or not (the sort it falls back to)."""
    from moveability.hypertree._kernels import _with_known, _with_remapped, remap_pairs

    rng = np.random.default_rng([seed, 47])
    n_old, n = 30, 40
    kept = np.sort(rng.choice(n, size=24, replace=False))
    new_of_old = np.full(n_old, -1, dtype=np.int64)
    new_of_old[np.sort(rng.choice(n_old, size=24, replace=False))] = kept
    if seed % 2:
        # kept leaves out of order: the pairs remapped are not sorted
        at = np.flatnonzero(new_of_old >= 0)
        new_of_old[at[[0, -1]]] = new_of_old[at[[-1, 0]]]
    old = np.array([(i, j) for i in range(n_old) for j in range(i + 1, n_old)], dtype=np.int64)
    old = old[rng.random(len(old)) < 0.3]
    fresh = np.setdiff1d(np.arange(n), kept)
    a = rng.choice(fresh, 50)
    b = rng.integers(0, n, 50)
    keep = a != b
    found = np.unique(np.sort(np.stack([a[keep], b[keep]], axis=1), axis=1), axis=0)
    found = found[rng.permutation(len(found))]
    a, b = np.ascontiguousarray(found[:, 0]), np.ascontiguousarray(found[:, 1])
    known = remap_pairs(old, new_of_old, np.zeros(n, dtype=bool))
    want = _with_known(a, b, n, known)
    np.testing.assert_array_equal(_with_remapped(a, b, n, old, new_of_old), want)
    assert len(want) > len(found) > 0
