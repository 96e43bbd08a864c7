"""The search for necks (the leaves the resolution splits between parts) against
scipy's breadth-first distances on random graphs."""

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import shortest_path

from moveability.analysis.result import _chain_search, _necks


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
    hops, pred, label, a, b, searched = _chain_search(pairs, through, seeds, source)

    # reference: distances from a node joined to every seed, along the pairs of
    # two leaves that are `through`
    use = through[pairs[:, 0]] & through[pairs[:, 1]]
    rows = np.concatenate([pairs[use, 0], np.full(seeds.size, n)])
    cols = np.concatenate([pairs[use, 1], seeds])
    graph = coo_matrix((np.ones(rows.size), (rows, cols)), shape=(n + 1, n + 1)).tocsr()
    # the pairs searched, returned for the growth of the necks: those `through`
    np.testing.assert_array_equal(searched, pairs[use])
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
    hops, pred, label, a, b, _ = _chain_search(
        pairs, through, np.flatnonzero(source >= 0), source
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
