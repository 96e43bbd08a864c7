"""The search for necks (the leaves the resolution splits between parts) against
scipy's breadth-first distances on random graphs."""

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import shortest_path

from moveability.analysis.result import _chain_search, _grown, _necks, _NeckSearches


def random_case(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sorted pairs i < j over n leaves, a gap mask and the parts (-1 elsewhere)."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 60))
    m = int(rng.integers(0, 3 * n))
    a, b = rng.integers(0, n, m), rng.integers(0, n, m)
    keep = a != b
    pairs = np.unique(np.stack([np.minimum(a, b), np.maximum(a, b)], axis=1)[keep], axis=0)
    pairs = pairs.reshape(-1, 2).astype(np.int64)
    source = np.where(rng.random(n) < 0.15, rng.integers(0, 4, n), -1).astype(np.int64)
    gap = (rng.random(n) < 0.6) & (source < 0)
    return pairs, gap, source


@pytest.mark.parametrize("seed", range(60))
def test_chain_search_against_scipy_distances(seed):
    pairs, gap, source = random_case(seed)
    n = gap.size
    through = gap | (source >= 0)
    seeds = np.flatnonzero(source >= 0)
    group = np.where(through, 0, -1).astype(np.int64)
    hops, pred, label, a, b = _chain_search(pairs, group, seeds, source)

    # reference: distances from a node joined to every seed, along the pairs of
    # two leaves that are `through`
    use = through[pairs[:, 0]] & through[pairs[:, 1]]
    rows = np.concatenate([pairs[use, 0], np.full(seeds.size, n)])
    cols = np.concatenate([pairs[use, 1], seeds])
    graph = coo_matrix((np.ones(rows.size), (rows, cols)), shape=(n + 1, n + 1)).tocsr()
    dist = shortest_path(graph, directed=False, unweighted=True, indices=n)[:n] - 1.0
    np.testing.assert_array_equal(hops, dist)

    touching = {(int(i), int(j)) for i, j in pairs[use]}
    for w in range(n):
        if source[w] >= 0:
            assert hops[w] == 0 and pred[w] == -1 and label[w] == source[w]
        elif np.isfinite(hops[w]):
            # one step nearer a part, along a searched pair, with its label: of
            # such neighbours, the one of largest index
            v = int(pred[w])
            nearer = [
                u for u in range(n) if (min(u, w), max(u, w)) in touching and hops[u] == hops[w] - 1
            ]
            assert v == max(nearer)
            assert label[w] == label[v]
        else:
            assert pred[w] == -1 and label[w] == -1

    # the meeting pairs: the searched pairs whose leaves have two labels, those of
    # two seeds first, then the others, each in order
    meeting = [
        (i, j) for i, j in pairs[use] if label[i] >= 0 and label[j] >= 0 and label[i] != label[j]
    ]
    expected = [(i, j) for i, j in meeting if source[i] >= 0 and source[j] >= 0] + [
        (i, j) for i, j in meeting if not (source[i] >= 0 and source[j] >= 0)
    ]
    assert [(int(i), int(j)) for i, j in zip(a, b, strict=True)] == [
        (int(i), int(j)) for i, j in expected
    ]


@pytest.mark.parametrize("seed", range(30))
def test_necks_hold_a_shortest_chain_between_each_two_parts(seed):
    pairs, gap, source = random_case(seed)
    out = _necks(pairs, gap, source, 1)
    assert not (out & ~gap).any()
    through = gap | (source >= 0)
    hops, pred, label, a, b = _chain_search(
        pairs, np.where(through, 0, -1).astype(np.int64), np.flatnonzero(source >= 0), source
    )
    if not a.size:
        assert not out.any()
        return
    # per two parts, the gap leaves of one shortest chain (both ends walked back)
    best: dict[tuple[int, int], tuple[float, int, int]] = {}
    for i, j in zip(a, b, strict=True):
        key = (min(label[i], label[j]), max(label[i], label[j]))
        length = hops[i] + hops[j]
        if key not in best or length < best[key][0]:
            best[key] = (length, int(i), int(j))
    for _, i, j in best.values():
        for w in (i, j):
            while w >= 0:
                assert out[w] or not gap[w]
                w = int(pred[w])



def batched(searches: _NeckSearches, pairs: np.ndarray, n: int) -> np.ndarray:
    """The necks of every batch of ``searches``, one search a batch, joined."""
    got = np.zeros(n, dtype=bool)
    for b_gap, b_source, b_group in searches.batches:
        got |= _necks(pairs, b_gap, b_source, 1, b_group)
    return got

@pytest.mark.parametrize("seed", range(30))
def test_necks_by_groups_are_the_union_of_each_groups_necks(seed):
    # a graph's leaves dealt to a few searches, each with its own gap leaves and
    # parts: one search by groups gives the union of the searches run alone
    pairs, gap, source = random_case(seed)
    rng = np.random.default_rng(1000 + seed)
    n = gap.size
    which = rng.integers(-1, 3, n)  # the search of each leaf (-1: none)
    searches = _NeckSearches(n)
    expected = np.zeros(n, dtype=bool)
    for g in range(3):
        mine = which == g
        g_gap = gap & mine
        g_source = np.where(mine, source, -1).astype(np.int64)
        expected |= _necks(pairs, g_gap, g_source, 1)
        searches.add(g_gap, g_source, 4)
    assert len(searches.batches) == 1  # apart: one batch
    np.testing.assert_array_equal(batched(searches, pairs, n), expected)


@pytest.mark.parametrize("seed", range(10))
def test_neck_searches_that_share_leaves_run_apart(seed):
    pairs, gap, source = random_case(seed)
    n = gap.size
    searches = _NeckSearches(n)
    expected = np.zeros(n, dtype=bool)
    # the same leaves twice, then a third of the leaves: three batches, two
    for g_gap in (gap, gap, gap & (np.arange(n) % 3 == 0)):
        expected |= _necks(pairs, g_gap, source, 1)
        searches.add(g_gap, source, 4)
    assert len(searches.batches) == 3
    np.testing.assert_array_equal(batched(searches, pairs, n), expected)


@pytest.mark.parametrize("seed", range(10))
def test_grown_along_the_pairs_of_one_group(seed):
    pairs, gap, _ = random_case(seed)
    rng = np.random.default_rng(2000 + seed)
    n = gap.size
    group = rng.integers(-1, 2, n).astype(np.int64)
    out = rng.random(n) < 0.2
    expected = out.copy()
    for i, j in pairs:
        if group[i] >= 0 and group[i] == group[j]:
            expected[i] |= out[j]
            expected[j] |= out[i]
    np.testing.assert_array_equal(_grown(out, pairs, group), expected)
