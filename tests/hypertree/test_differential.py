"""Differential tests: the tree engine against brute-force references.

Every reference below works on plain grids or on all pairs of leaf boxes, with
no use of the keys, the probing or the merging of the package:

* components of grid-derived trees against :func:`scipy.ndimage.label`, and on
  periodic axes against a brute-force graph over the grid cells;
* adjacency against a test of every pair of closed leaf boxes;
* locate against a search of every leaf box (half-open cells);
* projection against ``np.any`` over the dropped axes of the grid.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from moveability import BOUNDARY, IN, OUT, HyperTree, adjacency, components, locate, project

STATUSES = np.array([int(IN), int(OUT), int(BOUNDARY)])
HYPOTHESIS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])

# ----------------------------------------------------------------- references


def random_grid(rng, shape, density, kind):
    """A boolean grid: i.i.d. cells ("noise") or coarse blocks with 10% flipped ("blocky")."""
    if kind == "noise":
        return rng.random(shape) < density
    factors = [min(4, s) for s in shape]
    coarse = rng.random([s // f for s, f in zip(shape, factors, strict=True)]) < density
    grid = coarse
    for axis, f in enumerate(factors):
        grid = np.repeat(grid, f, axis=axis)
    return grid ^ (rng.random(shape) < 0.1)


def random_status_grid(rng, shape, p=(0.4, 0.4, 0.2), blocky=True):
    """A grid of IN/OUT/BOUNDARY values, with coarse blocks for mixed levels."""
    values = rng.choice(STATUSES, size=shape, p=list(p))
    if blocky:
        factors = [min(2, s) for s in shape]
        coarse = rng.choice(
            STATUSES[:2], size=[s // f for s, f in zip(shape, factors, strict=True)]
        )
        for axis, f in enumerate(factors):
            coarse = np.repeat(coarse, f, axis=axis)
        values = np.where(rng.random(shape) < 0.75, coarse, values)
    return values.astype(np.int64)


def grid_classifier(grid):
    """Exact classifier of the set of True cells of ``grid`` over the box [0, shape]."""

    def classify(lo, hi):
        a = np.rint(lo).astype(np.int64)
        b = np.rint(hi).astype(np.int64)
        assert np.array_equal(a, lo) and np.array_equal(b, hi)
        out = np.empty(lo.shape[0], dtype=np.int64)
        for i in range(lo.shape[0]):
            block = grid[tuple(slice(x, y) for x, y in zip(a[i], b[i], strict=True))]
            assert block.size > 0
            out[i] = IN if block.all() else (BOUNDARY if block.any() else OUT)
        return out

    return classify


def random_classifier(rng, p_split, split_root=True):
    """A classifier drawing statuses at random: BOUNDARY cells are split, up to max depth.

    With ``split_root`` the root box is always split, so the tree has several leaves.
    """
    calls = []

    def classify(lo, hi):
        n = lo.shape[0]
        split = rng.random(n) < p_split
        if split_root and not calls:
            split[:] = True
        calls.append(n)
        decided = np.where(rng.random(n) < 0.5, int(IN), int(OUT))
        return np.where(split, int(BOUNDARY), decided).astype(np.int64)

    return classify


def depths_of(shape):
    depths = [int(s).bit_length() - 1 for s in shape]
    assert [1 << d for d in depths] == list(shape)
    return depths


def tree_from_grid_adaptive(grid, periodic=(), merge=True):
    shape = grid.shape
    return HyperTree.build(
        np.zeros(grid.ndim),
        np.asarray(shape, dtype=float),
        grid_classifier(grid),
        max_depth=depths_of(shape),
        periodic=periodic,
        merge=merge,
    )


def leaf_cells(tree, shape):
    """Grid of the leaf holding each cell of a grid over the tree's box [0, shape].

    Computed from the leaf boxes only; also checks that they tile the grid exactly.
    """
    leaves = tree.leaves()
    lo = np.rint(leaves.lo).astype(np.int64)
    hi = np.rint(leaves.hi).astype(np.int64)
    assert np.array_equal(lo, leaves.lo) and np.array_equal(hi, leaves.hi)
    owner = np.full(shape, -1, dtype=np.int64)
    count = np.zeros(shape, dtype=np.int64)
    for i in range(len(tree)):
        box = tuple(slice(a, b) for a, b in zip(lo[i], hi[i], strict=True))
        owner[box] = i
        count[box] += 1
    assert (count == 1).all(), "the leaves do not tile the box"
    return owner


def grid_neighbour_offsets(k, connectivity):
    return [
        d
        for d in itertools.product((-1, 0, 1), repeat=k)
        if 1 <= sum(x != 0 for x in d) <= connectivity
    ]


def brute_labels(mask, connectivity, periodic=()):
    """Components of the True cells of ``mask``: a graph over the cells, -1 elsewhere.

    Neighbours differ by an offset of ``{-1, 0, 1}^k`` with 1 to ``connectivity``
    non-zeros; indices wrap on the periodic axes and must stay inside on the others.
    """
    shape = mask.shape
    k = mask.ndim
    n = mask.size
    flat = mask.ravel()
    index = np.indices(shape).reshape(k, -1)
    rows, cols = [], []
    for d in grid_neighbour_offsets(k, connectivity):
        other = index + np.asarray(d)[:, None]
        ok = np.ones(n, dtype=bool)
        for axis in range(k):
            if axis in periodic:
                other[axis] %= shape[axis]
            else:
                ok &= (other[axis] >= 0) & (other[axis] < shape[axis])
        src = np.flatnonzero(ok)
        dst = np.ravel_multi_index(tuple(other[:, ok]), shape)
        both = flat[src] & flat[dst]
        rows.append(src[both])
        cols.append(dst[both])
    r = np.concatenate(rows)
    c = np.concatenate(cols)
    graph = coo_matrix((np.ones(r.size, dtype=np.int8), (r, c)), shape=(n, n))
    _, raw = connected_components(graph, directed=False)
    labels = np.where(flat, raw, -1).reshape(shape)
    return labels, int(np.unique(raw[flat]).size)


def ndimage_labels(mask, connectivity):
    labels, count = ndimage.label(
        mask, structure=ndimage.generate_binary_structure(mask.ndim, connectivity)
    )
    return labels.astype(np.int64) - 1, int(count)


def assert_same_partition(a, b):
    """Two labellings (-1 for cells not taken) are equal up to a renaming of labels."""
    taken = a >= 0
    np.testing.assert_array_equal(taken, b >= 0)
    pairs = np.unique(np.stack([a[taken], b[taken]]), axis=1)
    n_a = np.unique(a[taken]).size
    n_b = np.unique(b[taken]).size
    assert pairs.shape[1] == n_a == n_b, (pairs.shape[1], n_a, n_b)


def tree_components_on_grid(tree, shape, status=IN, connectivity=1):
    labels, count = components(tree, status=status, connectivity=connectivity)
    assert labels.shape == (len(tree),)
    taken = np.isin(tree.status, [s for s in STATUSES if s & int(status)])
    assert np.array_equal(labels >= 0, taken)
    if count:
        # labels are 0 .. count - 1, numbered in the order of their first leaf
        first = labels[taken][np.sort(np.unique(labels[taken], return_index=True)[1])]
        np.testing.assert_array_equal(first, np.arange(count))
    return labels[leaf_cells(tree, shape)], count


def brute_adjacency(tree, connectivity, status=None):
    """Adjacent pairs ``i < j`` from a test of every pair of closed leaf boxes."""
    leaves = tree.leaves()
    n = len(tree)
    k = tree.ndim
    n_touch = np.zeros((n, n), dtype=np.int64)
    meets = np.ones((n, n), dtype=bool)
    for axis in range(k):
        a_lo = leaves.lo[:, None, axis]
        a_hi = leaves.hi[:, None, axis]
        b_lo = leaves.lo[None, :, axis]
        b_hi = leaves.hi[None, :, axis]
        overlap = np.minimum(a_hi, b_hi) > np.maximum(a_lo, b_lo)
        touch = (a_hi == b_lo) | (b_hi == a_lo)
        if axis in tree.periodic:
            top, bottom = tree.hi[axis], tree.lo[axis]
            touch |= ((a_hi == top) & (b_lo == bottom)) | ((b_hi == top) & (a_lo == bottom))
        # an interval overlapping the other also meets it wherever it touches it
        # (e.g. a leaf spanning a whole periodic axis): the contact is the overlap
        touch &= ~overlap
        meets &= overlap | touch
        n_touch += touch
    ok = meets & (n_touch >= 1) & (n_touch <= connectivity)
    if status is not None:
        chosen = (leaves.status & int(status)) != 0
        ok &= chosen[:, None] & chosen[None, :]
    i, j = np.nonzero(np.triu(ok, 1))
    return np.stack([i, j], axis=1)


def brute_locate(tree, points):
    """Status and leaf index of each point by testing every leaf box (half-open cells)."""
    leaves = tree.leaves()
    p = points[:, None, :]
    lo = leaves.lo[None]
    hi = leaves.hi[None]
    top = (leaves.hi == tree.hi)[None]
    hit = ((lo <= p) & ((p < hi) | (top & (p == hi)))).all(axis=2)
    in_box = ((points >= tree.lo) & (points <= tree.hi)).all(axis=1)
    np.testing.assert_array_equal(hit.sum(axis=1), in_box.astype(np.int64))
    index = np.where(in_box, hit.argmax(axis=1), -1)
    status = np.where(in_box, leaves.status[np.maximum(index, 0)], int(OUT))
    return status, index


def project_grid(values, kept):
    """Projection of a status grid onto the axes ``kept`` (in that order)."""
    dropped = tuple(a for a in range(values.ndim) if a not in kept)
    any_in = np.any(values == IN, axis=dropped)
    any_b = np.any(values == BOUNDARY, axis=dropped)
    out = np.where(any_in, int(IN), np.where(any_b, int(BOUNDARY), int(OUT)))
    remaining = [a for a in range(values.ndim) if a in kept]
    return np.transpose(out, [remaining.index(a) for a in kept])


def rasterize(tree, shape):
    """Status of each cell of a grid over the tree's box [0, shape]."""
    return tree.status[leaf_cells(tree, shape)].astype(np.int64)


# ------------------------------------------------------ 0. the references agree


@pytest.mark.parametrize("shape", [(8, 16), (4, 8, 4), (4, 4, 8, 4), (1, 8), (2, 1, 4)])
@pytest.mark.parametrize("density", [0.3, 0.5, 0.7])
def test_brute_labeller_equals_ndimage_without_periodic_axes(shape, density):
    rng = np.random.default_rng([len(shape), *shape, int(density * 10)])
    for _ in range(3):
        grid = random_grid(rng, shape, density, "noise")
        for c in range(1, len(shape) + 1):
            ref, ref_count = ndimage_labels(grid, c)
            labels, count = brute_labels(grid, c)
            assert count == ref_count
            assert_same_partition(labels, ref)


def test_brute_labeller_wraps_on_periodic_axes():
    grid = np.zeros((4, 8), dtype=bool)
    grid[0, 0] = grid[3, 0] = grid[1, 7] = grid[1, 0] = True
    assert brute_labels(grid, 1)[1] == 3  # {(0,0), (1,0)}, {(3,0)}, {(1,7)}
    assert brute_labels(grid, 1, periodic=(0,))[1] == 2  # (3,0) joins (0,0) across the wrap
    assert brute_labels(grid, 1, periodic=(1,))[1] == 2  # (1,7) joins (1,0) across the wrap
    assert brute_labels(grid, 1, periodic=(0, 1))[1] == 1
    diag = np.zeros((4, 4), dtype=bool)
    diag[0, 0] = diag[3, 3] = True
    assert brute_labels(diag, 2, periodic=(0, 1))[1] == 1
    assert brute_labels(diag, 2, periodic=(0,))[1] == 2
    assert brute_labels(diag, 1, periodic=(0, 1))[1] == 2


def test_brute_adjacency_on_a_small_periodic_example():
    grid = np.ones((2, 4), dtype=bool)
    tree = HyperTree.from_array(grid, merge=False, periodic=(1,))
    leaves = tree.leaves()
    pairs = {tuple(p) for p in brute_adjacency(tree, 1)}
    # each cell has 2 + 1 face neighbours on a 2 x 4 grid wrapping along axis 1
    assert len(pairs) == 8 * 3 // 2
    a = int(np.flatnonzero((leaves.lo == [0, 0]).all(axis=1))[0])
    b = int(np.flatnonzero((leaves.lo == [0, 3]).all(axis=1))[0])
    assert (min(a, b), max(a, b)) in pairs
    # a leaf spanning the whole periodic axis meets only its neighbours along axis 0
    whole = HyperTree.from_array(grid, periodic=(1,))
    assert len(whole) == 1
    assert brute_adjacency(whole, 2).shape == (0, 2)


# ------------------------------------------------- 1. components vs ndimage.label

GRID_SHAPES = [(8, 16), (16, 8), (4, 8, 4), (8, 4, 2), (4, 4, 8, 4), (2, 4, 4, 4)]


@pytest.mark.parametrize("shape", GRID_SHAPES)
@pytest.mark.parametrize("density", [0.3, 0.5, 0.7])
@pytest.mark.parametrize("kind", ["noise", "blocky"])
@pytest.mark.parametrize("merge", [True, False])
def test_components_of_grid_tree_match_ndimage(shape, density, kind, merge):
    rng = np.random.default_rng([len(shape), *shape, int(density * 10), len(kind)])
    n_cells = int(np.prod(shape))
    mixed = 0
    for _ in range(3):
        grid = random_grid(rng, shape, density, kind)
        tree = HyperTree.from_array(grid, merge=merge)
        np.testing.assert_array_equal(rasterize(tree, shape), np.where(grid, IN, OUT))
        if merge:
            mixed += len(np.unique(tree.levels)) > 1
        else:
            assert len(tree) == n_cells
        for c in range(1, len(shape) + 1):
            ref, ref_count = ndimage_labels(grid, c)
            labels, count = tree_components_on_grid(tree, shape, connectivity=c)
            assert count == ref_count
            assert_same_partition(labels, ref)
            # the complement too: components of the OUT leaves
            ref, ref_count = ndimage_labels(~grid, c)
            labels, count = tree_components_on_grid(tree, shape, status=OUT, connectivity=c)
            assert count == ref_count
            assert_same_partition(labels, ref)
    if merge and kind == "blocky":
        assert mixed > 0, "no tree with leaves at mixed levels"


@pytest.mark.parametrize("shape", [(8, 8), (4, 4, 8), (4, 2, 4, 4)])
@pytest.mark.parametrize("status", [IN | BOUNDARY, BOUNDARY, OUT | BOUNDARY])
def test_components_of_status_grid_tree_match_ndimage(shape, status):
    rng = np.random.default_rng([len(shape), *shape, int(status)])
    levels_seen = set()
    for _ in range(3):
        values = random_status_grid(rng, shape)
        tree = HyperTree.from_array(values)
        levels_seen.update(np.unique(tree.levels).tolist())
        mask = (values & int(status)) != 0
        for c in range(1, len(shape) + 1):
            ref, ref_count = ndimage_labels(mask, c)
            labels, count = tree_components_on_grid(tree, shape, status=status, connectivity=c)
            assert count == ref_count
            assert_same_partition(labels, ref)
    assert len(levels_seen) > 1


# ------------------------------------------- 2. adaptive trees vs ndimage.label


@pytest.mark.parametrize("shape", GRID_SHAPES)
@pytest.mark.parametrize("density", [0.3, 0.5, 0.7])
@pytest.mark.parametrize("merge", [True, False])
def test_components_of_adaptive_tree_match_ndimage(shape, density, merge):
    rng = np.random.default_rng([len(shape), *shape, int(density * 10), 7])
    levels_seen = set()
    for kind in ("blocky", "blocky", "noise"):
        grid = random_grid(rng, shape, density, kind)
        tree = tree_from_grid_adaptive(grid, merge=merge)
        np.testing.assert_array_equal(rasterize(tree, shape), np.where(grid, IN, OUT))
        assert not (tree.status == BOUNDARY).any()
        levels_seen.update(np.unique(tree.levels).tolist())
        for c in range(1, len(shape) + 1):
            ref, ref_count = ndimage_labels(grid, c)
            labels, count = tree_components_on_grid(tree, shape, connectivity=c)
            assert count == ref_count
            assert_same_partition(labels, ref)
    assert len(levels_seen) > 1


def test_adaptive_tree_with_few_large_leaves():
    # two big blocks joined only by a corner of small cells: labels hinge on mixed levels
    grid = np.zeros((16, 16), dtype=bool)
    grid[:8, :8] = True
    grid[8, 8] = True
    grid[9:, 9:] = True
    tree = tree_from_grid_adaptive(grid)
    assert tree.levels.min() == 1 and tree.levels.max() == 4
    for c, expected in ((1, 3), (2, 1)):
        ref, ref_count = ndimage_labels(grid, c)
        assert ref_count == expected
        labels, count = tree_components_on_grid(tree, grid.shape, connectivity=c)
        assert count == expected
        assert_same_partition(labels, ref)


# ------------------------------------------------------------ 3. periodic axes

PERIODIC_SHAPES = [
    (8, 16),
    (1, 8),
    (2, 8),
    (8, 2),
    (2, 2),
    (1, 4, 4),
    (2, 2, 8),
    (4, 8, 4),
    (4, 1, 2, 4),
    (2, 2, 2, 2),
    (4, 4, 8, 4),
]


@pytest.mark.parametrize("shape", PERIODIC_SHAPES)
@pytest.mark.parametrize("merge", [True, False])
def test_components_with_periodic_axes_match_brute_force(shape, merge):
    rng = np.random.default_rng([len(shape), *shape, int(merge), 3])
    k = len(shape)
    subsets = [s for r in range(1, k + 1) for s in itertools.combinations(range(k), r)]
    wrapped = 0
    for trial in range(8):
        periodic = subsets[rng.integers(len(subsets))] if trial % 3 else tuple(range(k))
        density = rng.uniform(0.3, 0.7)
        grid = random_grid(rng, shape, density, "blocky" if trial % 2 else "noise")
        if trial == 0 and max(shape) > 2:
            # two slabs at the ends of the longest axis, cut off from each other in
            # the box by an empty slab, joined across the wrap
            axis = int(np.argmax(shape))
            moved = np.moveaxis(grid, axis, 0)
            moved[0] = moved[-1] = True
            moved[shape[axis] // 2] = False
        for build in (False, True):
            if build:
                tree = tree_from_grid_adaptive(grid, periodic=periodic, merge=merge)
            else:
                tree = HyperTree.from_array(grid, periodic=periodic, merge=merge)
            assert tree.periodic == tuple(sorted(periodic))
            for c in range(1, k + 1):
                ref, ref_count = brute_labels(grid, c, periodic)
                labels, count = tree_components_on_grid(tree, shape, connectivity=c)
                assert count == ref_count, (periodic, c)
                assert_same_partition(labels, ref)
                wrapped += ref_count != ndimage_labels(grid, c)[1]
    if max(shape) > 2:
        assert wrapped > 0, "no case where the wrap-around changed the components"
    else:
        # on axes of 1 or 2 cells, the neighbours across the wrap are neighbours already
        assert wrapped == 0


@pytest.mark.parametrize("k", [2, 3, 4])
@pytest.mark.parametrize("merge", [True, False])
def test_ring_closes_only_across_the_wrap(k, merge):
    # two arcs of a ring along axis 0, joined only across the wrap of axis 0
    shape = (8,) + (4,) * (k - 1)
    rest = (0,) * (k - 2)
    straight = np.zeros(shape, dtype=bool)
    straight[[0, 1, 2, 5, 6, 7], 0, *rest] = True
    # the same, with the second arc moved by one cell along axis 1: the two arcs
    # then meet across the wrap only by an edge (connectivity 2)
    bent = np.zeros(shape, dtype=bool)
    bent[[0, 1, 2], 0, *rest] = True
    bent[[5, 6, 7], 1, *rest] = True
    for grid, periodic, expected in (
        (straight, (), [2] * k),
        (straight, (0,), [1] * k),
        (straight, tuple(range(1, k)), [2] * k),
        (bent, (), [2] * k),
        (bent, (0,), [2] + [1] * (k - 1)),
        (bent, tuple(range(k)), [2] + [1] * (k - 1)),
    ):
        tree = HyperTree.from_array(grid, periodic=periodic, merge=merge)
        for c in range(1, k + 1):
            ref, ref_count = brute_labels(grid, c, periodic)
            labels, count = tree_components_on_grid(tree, shape, connectivity=c)
            assert ref_count == expected[c - 1], (periodic, c)
            assert count == ref_count, (periodic, c)
            assert_same_partition(labels, ref)


# ---------------------------------------------------------------- 4. adjacency


def random_adaptive_tree(
    rng, max_depth, periodic=(), merge=False, p_split=0.6, split_root=True, lo=None, hi=None
):
    """A tree built by a random classifier, by default over the box [0, 2 ** max_depth]."""
    k = len(max_depth)
    lo = np.zeros(k) if lo is None else lo
    hi = np.exp2(np.asarray(max_depth, dtype=float)) if hi is None else hi
    return HyperTree.build(
        lo,
        hi,
        random_classifier(rng, p_split, split_root),
        max_depth=list(max_depth),
        periodic=periodic,
        merge=merge,
    )


ADJ_DEPTHS = [(3, 3), (4, 2), (0, 3), (1, 3), (2, 2, 2), (3, 1, 2), (1, 0, 3), (2, 2, 1, 2)]


@pytest.mark.parametrize("max_depth", ADJ_DEPTHS)
@pytest.mark.parametrize("merge", [False, True])
def test_adjacency_matches_brute_force(max_depth, merge):
    rng = np.random.default_rng([len(max_depth), *max_depth, int(merge), 11])
    k = len(max_depth)
    subsets = [s for r in range(k + 1) for s in itertools.combinations(range(k), r)]
    levels_seen = set()
    for trial in range(8):
        periodic = subsets[trial % len(subsets)] if trial < len(subsets) else ()
        tree = random_adaptive_tree(rng, max_depth, periodic, merge, rng.uniform(0.4, 0.8))
        levels_seen.update(np.unique(tree.levels).tolist())
        for c in range(1, k + 1):
            pairs = adjacency(tree, connectivity=c)
            assert pairs.ndim == 2 and pairs.shape[1] == 2
            assert (pairs[:, 0] < pairs[:, 1]).all()
            np.testing.assert_array_equal(pairs, np.unique(pairs, axis=0))
            ref = brute_adjacency(tree, c)
            np.testing.assert_array_equal(pairs, ref, err_msg=f"periodic={periodic}, c={c}")
            for status in (IN, OUT | BOUNDARY):
                np.testing.assert_array_equal(
                    adjacency(tree, status=status, connectivity=c),
                    brute_adjacency(tree, c, status),
                )
    assert len(levels_seen) > 1


@pytest.mark.parametrize("max_depth", [(4, 4), (5, 3), (3, 3, 3), (2, 4, 1), (2, 2, 2, 2)])
def test_refined_adjacency_matches_a_fresh_one(max_depth):
    """Pairs of a refined tree from the coarser tree's pairs: equal to the adjacency
    computed afresh, whatever the statuses, periodic axes and connectivity, and
    after several rounds of refinement (as the resolution of an analysis does);
    the known pairs merged when sorted, sorted again when not."""
    from moveability.hypertree.topology import refined_adjacency

    rng = np.random.default_rng([len(max_depth), *max_depth, 23])
    k = len(max_depth)
    for trial in range(6):
        periodic = tuple(a for a in range(k) if rng.random() < 0.4)
        # built to a level above the deepest, so that leaves can be split
        stop = int(rng.integers(1, max(max_depth)))
        tree = HyperTree.build(
            np.zeros(k),
            np.exp2(np.asarray(max_depth, dtype=float)),
            random_classifier(rng, 0.6, True),
            max_depth=list(max_depth),
            periodic=periodic,
            merge=False,
            stop_level=stop,
        )
        c = int(rng.integers(1, k + 1))
        status = [None, IN | BOUNDARY, IN][trial % 3]
        pairs = adjacency(tree, status=status, connectivity=c)
        for _ in range(3):
            can = tree.levels < tree.layout.n_levels
            if status is not None and trial % 2:
                # split only leaves with the status: the refined pairs are then reused
                can &= np.isin(tree.status, [s for s in (IN, OUT, BOUNDARY) if s & status])
            mask = can & (rng.random(len(tree)) < 0.3)
            finer = tree.refine(mask, random_classifier(rng, 0.6, True))
            is_child = ~np.isin(finer.keys, tree.keys[~mask])
            old_index = np.full(len(finer), -1)
            old_index[~is_child] = np.flatnonzero(~mask)
            got = refined_adjacency(
                finer, tree, pairs, old_index, status=status, connectivity=c
            )
            # the known pairs in another order: sorted again, not merged
            shuffled = refined_adjacency(
                finer, tree, pairs[rng.permutation(len(pairs))], old_index,
                status=status, connectivity=c,
            )  # fmt: skip
            pairs = adjacency(finer, status=status, connectivity=c)
            np.testing.assert_array_equal(got, pairs, err_msg=f"{periodic}, c={c}")
            np.testing.assert_array_equal(shuffled, pairs, err_msg=f"{periodic}, c={c}")
            tree = finer


@pytest.mark.parametrize("shape", [(4, 8), (2, 4, 4), (2, 2, 2, 4), (1, 2, 4)])
def test_adjacency_of_grid_tree_matches_grid_offsets(shape):
    # unmerged grid trees: leaves are grid cells, neighbours are grid offsets
    rng = np.random.default_rng([len(shape), *shape])
    k = len(shape)
    for periodic in ((), (0,), (k - 1,), tuple(range(k))):
        grid = rng.random(shape) < 0.5
        tree = HyperTree.from_array(grid, merge=False, periodic=periodic)
        owner = leaf_cells(tree, shape)
        for c in range(1, k + 1):
            expected = set()
            for cell in np.ndindex(*shape):
                for d in grid_neighbour_offsets(k, c):
                    other = []
                    for axis, (x, dx) in enumerate(zip(cell, d, strict=True)):
                        y = x + dx
                        if axis in periodic:
                            y %= shape[axis]
                        elif not 0 <= y < shape[axis]:
                            break
                        other.append(y)
                    else:
                        i, j = owner[cell], owner[tuple(other)]
                        if i != j:
                            expected.add((min(i, j), max(i, j)))
            got = {tuple(p) for p in adjacency(tree, connectivity=c).tolist()}
            assert got == expected, (periodic, c)


# ------------------------------------------------------------------- 5. locate


def locate_points(rng, tree, n_random=300):
    leaves = tree.leaves()
    k = tree.ndim
    width = tree.hi - tree.lo
    parts = [rng.uniform(tree.lo - 0.25 * width, tree.hi + 0.25 * width, size=(n_random, k))]
    # points on faces, edges and corners of random leaves (each coordinate from a leaf)
    idx = rng.integers(len(tree), size=(n_random, k))
    which = rng.integers(3, size=(n_random, k))
    axis = np.arange(k)[None, :]
    lo = leaves.lo[idx, axis]
    hi = leaves.hi[idx, axis]
    parts.append(np.where(which == 0, lo, np.where(which == 1, hi, 0.5 * (lo + hi))))
    # the corners of the box, and points just inside and just outside its faces
    corners = np.array(list(itertools.product((0, 1), repeat=k)), dtype=bool)
    parts.append(np.where(corners, tree.hi, tree.lo))
    near = parts[1][: n_random // 3].copy()
    ax = rng.integers(k, size=near.shape[0])
    rows = np.arange(near.shape[0])
    side = rng.integers(4, size=near.shape[0])
    bound = np.where(side % 2 == 0, tree.lo[ax], tree.hi[ax])
    toward = np.where(side < 2, -np.inf, np.inf)
    near[rows, ax] = np.nextafter(bound, toward)
    parts.append(near)
    # just below / above the faces of leaves
    faces = parts[1][n_random // 3 :].copy()
    faces = np.nextafter(faces, np.where(rng.random(faces.shape) < 0.5, -np.inf, np.inf))
    parts.append(faces)
    return np.concatenate(parts)


BOXES = [
    ((0.0, 0.0), (8.0, 8.0)),
    ((-1.3, 0.2), (2.7, 5.1)),
    ((-3.0, -0.1, 1e-3), (0.7, 0.1, 3.3)),
    ((0.1, -7.0, 2.0, -0.5), (0.3, 9.0, 2.9, 0.5)),
]


@pytest.mark.parametrize(("lo", "hi"), BOXES)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_locate_matches_brute_force(lo, hi, seed):
    rng = np.random.default_rng([seed, len(lo)])
    k = len(lo)
    max_depth = [int(x) for x in rng.integers(1, 5 if k <= 2 else 3, size=k)]
    for periodic in ((), tuple(range(k))):
        tree = HyperTree.build(
            lo, hi, random_classifier(rng, 0.6), max_depth=max_depth, periodic=periodic
        )
        assert len(tree) > 1
        points = locate_points(rng, tree)
        status, index = locate(tree, points)
        ref_status, ref_index = brute_locate(tree, points)
        assert (ref_index == -1).any() and (ref_index >= 0).any()
        np.testing.assert_array_equal(index, ref_index)
        np.testing.assert_array_equal(status, ref_status)
        # one point at a time gives the same answers
        for p in points[:: max(1, len(points) // 25)]:
            s1, i1 = locate(tree, p)
            r_s, r_i = brute_locate(tree, p[None, :])
            assert (int(s1[0]), int(i1[0])) == (int(r_s[0]), int(r_i[0]))


@pytest.mark.parametrize("shape", [(8, 16), (4, 2, 8), (2, 4, 2, 4)])
def test_locate_cell_centres_and_lower_corners_of_grid(shape):
    rng = np.random.default_rng([len(shape), *shape])
    grid = random_grid(rng, shape, 0.5, "blocky")
    tree = HyperTree.from_array(grid)
    owner = leaf_cells(tree, shape)
    cells = np.indices(shape).reshape(len(shape), -1).T.astype(float)
    for offset in (0.5, 0.0):  # the centre, then the lower corner (on shared faces)
        status, index = locate(tree, cells + offset)
        np.testing.assert_array_equal(index, owner.ravel())
        np.testing.assert_array_equal(status, np.where(grid, IN, OUT).ravel())
    # the upper corner of each cell belongs to the next cell, but the top of the box
    # to the last one
    status, index = locate(tree, cells + 1.0)
    upper = np.minimum(cells.astype(np.int64) + 1, np.asarray(shape) - 1)
    np.testing.assert_array_equal(index, owner[tuple(upper.T)])


# ------------------------------------------------------------------ 6. project


@pytest.mark.parametrize("shape", [(4, 8, 2), (8, 4, 4), (2, 4, 4, 8), (4, 2, 2, 4)])
@pytest.mark.parametrize("merge", [True, False])
def test_project_boolean_grid_is_any_over_dropped_axes(shape, merge):
    rng = np.random.default_rng([len(shape), *shape, int(merge)])
    k = len(shape)
    subsets = [
        p for r in range(1, k) for s in itertools.combinations(range(k), r) for p in [s, s[::-1]]
    ]
    non_trivial = 0
    for trial, kept in enumerate(subsets):
        density = 0.05 + 0.05 * (trial % 4)  # sparse, so that np.any is not all True
        grid = random_grid(rng, shape, density, "blocky" if trial % 2 else "noise")
        tree = HyperTree.from_array(grid, merge=merge)
        proj = project(tree, kept)
        assert proj.ndim == len(kept)
        assert proj.max_depth == tuple(depths_of(shape)[a] for a in kept)
        assert not (proj.status == BOUNDARY).any()
        expected = project_grid(np.where(grid, IN, OUT), kept)
        np.testing.assert_array_equal(
            rasterize(proj, expected.shape), expected, err_msg=f"kept={kept}"
        )
        non_trivial += 0 < (expected == IN).sum() < expected.size
    assert non_trivial > len(subsets) // 2


@pytest.mark.parametrize("shape", [(4, 8, 2), (8, 4, 4), (2, 4, 4, 8), (4, 2, 2, 4)])
def test_project_status_grid(shape):
    rng = np.random.default_rng([len(shape), *shape, 5])
    k = len(shape)
    subsets = [p for r in range(1, k) for p in itertools.permutations(range(k), r)]
    kinds = set()
    for trial, kept in enumerate(subsets):
        p_in = (0.02, 0.05, 0.1)[trial % 3]
        values = random_status_grid(rng, shape, p=(p_in, 0.9 - p_in, 0.1), blocky=False)
        tree = HyperTree.from_array(values, periodic=[a for a in range(k) if trial % 2])
        proj = project(tree, kept)
        expected = project_grid(values, kept)
        np.testing.assert_array_equal(
            rasterize(proj, expected.shape), expected, err_msg=f"kept={kept}"
        )
        assert proj.periodic == (tuple(range(len(kept))) if trial % 2 else ())
        kinds.update(np.unique(expected).tolist())
    assert kinds == {int(IN), int(OUT), int(BOUNDARY)}


@pytest.mark.parametrize("max_depth", [(3, 2, 2), (2, 3, 1, 2), (1, 3, 3)])
def test_project_adaptive_tree(max_depth):
    # mixed levels: rasterize to the finest grid, project the grid, compare
    rng = np.random.default_rng([len(max_depth), *max_depth])
    k = len(max_depth)
    shape = tuple(1 << d for d in max_depth)
    kinds = set()
    for kept in itertools.permutations(range(k), k - 1):
        tree = random_adaptive_tree(rng, max_depth, merge=True, p_split=0.7)
        assert len(np.unique(tree.levels)) > 1
        values = rasterize(tree, shape)
        proj = project(tree, kept)
        expected = project_grid(values, kept)
        np.testing.assert_array_equal(rasterize(proj, expected.shape), expected)
        kinds.update(np.unique(expected).tolist())
    assert kinds == {int(IN), int(OUT), int(BOUNDARY)}


# ------------------------------------------- deep trees (high bits of the keys)


def point_refined_tree(rng, lo, hi, max_depth, periodic=(), merge=False, n_points=2):
    """A tree refined down to ``max_depth`` around a few random points only.

    Cells holding a point are BOUNDARY (and split); the others are IN or OUT at
    random, mostly OUT above level 6, so that projections are not all IN. The
    keys use up to 62 bits while the tree has a few hundred leaves.
    """
    lo = np.asarray(lo, dtype=float)
    hi = np.asarray(hi, dtype=float)
    targets = rng.uniform(lo, hi, size=(n_points, lo.size))
    deepest = int(np.argmax(max_depth))  # split at every level: its width gives the level

    def classify(cell_lo, cell_hi):
        t = targets[None, :, :]
        hit = ((cell_lo[:, None, :] <= t) & (t <= cell_hi[:, None, :])).all(axis=2).any(axis=1)
        ratio = (hi - lo)[deepest] / (cell_hi - cell_lo)[:, deepest]
        level = np.rint(np.log2(ratio))
        p_in = np.where(level < 6, 0.1, 0.5)
        decided = np.where(rng.random(hit.size) < p_in, int(IN), int(OUT))
        return np.where(hit, int(BOUNDARY), decided).astype(np.int64)

    tree = HyperTree.build(
        lo, hi, classify, max_depth=list(max_depth), periodic=periodic, merge=merge
    )
    return tree, targets


def brute_components(tree, status, connectivity):
    """Components of the leaves of ``status`` over the brute-force adjacency graph."""
    taken = (tree.status & int(status)) != 0
    pairs = brute_adjacency(tree, connectivity, status)
    n = len(tree)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, raw = connected_components(graph, directed=False)
    return np.where(taken, raw, -1), int(np.unique(raw[taken]).size)


def brute_project_at(tree, kept, points):
    """Status of the projection at ``points``: IN if an IN leaf's half-open box
    projects onto the point, else BOUNDARY if a BOUNDARY leaf's does, else OUT."""
    leaves = tree.leaves()
    kept = list(kept)
    lo = leaves.lo[:, kept][None]
    hi = leaves.hi[:, kept][None]
    top = (leaves.hi[:, kept] == tree.hi[kept])[None]
    p = points[:, None, :]
    over = ((lo <= p) & ((p < hi) | (top & (p == hi)))).all(axis=2)
    any_in = (over & (leaves.status == IN)[None]).any(axis=1)
    any_b = (over & (leaves.status == BOUNDARY)[None]).any(axis=1)
    return np.where(any_in, int(IN), np.where(any_b, int(BOUNDARY), int(OUT)))


DEEP = [
    ((-1.3, 0.2), (2.7, 5.1), (31, 31)),
    ((0.0, -2.0), (1.0, 2.0), (40, 22)),
    ((-1.0, -1.0, -1.0), (1.0, 2.0, 3.0), (20, 21, 21)),
    ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (30, 0, 32)),
    ((-2.0, 0.5, 0.0, -1.0), (2.0, 1.5, 8.0, 1.0), (15, 16, 15, 16)),
]


@pytest.mark.parametrize(("lo", "hi", "max_depth"), DEEP)
def test_deep_tree_adjacency_components_locate_project(lo, hi, max_depth):
    rng = np.random.default_rng([len(lo), *max_depth])
    k = len(lo)
    for periodic, merge in (((), False), (tuple(range(k)), True), ((0,), False)):
        tree, targets = point_refined_tree(rng, lo, hi, max_depth, periodic, merge)
        assert sum(tree.max_depth) == sum(max_depth) >= 40
        assert int(tree.levels.max()) == max(max_depth) and tree.levels.min() <= 1
        assert 20 < len(tree) < 1000
        # adjacency and components
        for c in range(1, k + 1):
            np.testing.assert_array_equal(adjacency(tree, connectivity=c), brute_adjacency(tree, c))
            for status in (IN, IN | BOUNDARY):
                labels, count = components(tree, status=status, connectivity=c)
                ref, ref_count = brute_components(tree, status, c)
                assert count == ref_count
                assert_same_partition(labels, ref)
        # locate: random points, points near the refined ones, faces of leaves
        scale = (tree.hi - tree.lo) * np.exp2(-rng.integers(0, max(max_depth), size=(200, k)))
        near = targets[rng.integers(len(targets), size=200)] + rng.normal(size=(200, k)) * scale
        points = np.concatenate([locate_points(rng, tree, n_random=150), near])
        status, index = locate(tree, points)
        ref_status, ref_index = brute_locate(tree, points)
        np.testing.assert_array_equal(index, ref_index)
        np.testing.assert_array_equal(status, ref_status)
        # projection, checked point by point
        inside = points[ref_index >= 0]
        for kept in ([0], [k - 1], list(range(k - 1, 0, -1)), list(range(k))[::-1]):
            proj = project(tree, kept)
            got, _ = locate(proj, inside[:, kept])
            np.testing.assert_array_equal(got, brute_project_at(tree, kept, inside[:, kept]))


# --------------------------------------------------------- hypothesis variants


@st.composite
def grid_cases(draw):
    k = draw(st.integers(1, 4))
    depths = draw(st.lists(st.integers(0, 4), min_size=k, max_size=k).filter(lambda d: sum(d) <= 8))
    shape = tuple(1 << d for d in depths)
    seed = draw(st.integers(0, 2**32 - 1))
    density = draw(st.floats(0.2, 0.8))
    kind = draw(st.sampled_from(["noise", "blocky"]))
    grid = random_grid(np.random.default_rng(seed), shape, density, kind)
    periodic = tuple(sorted(draw(st.sets(st.integers(0, k - 1)))))
    connectivity = draw(st.integers(1, k))
    return grid, periodic, connectivity


@HYPOTHESIS
@given(case=grid_cases(), merge=st.booleans(), adaptive=st.booleans())
def test_hypothesis_components_match_brute_force(case, merge, adaptive):
    grid, periodic, c = case
    if adaptive:
        tree = tree_from_grid_adaptive(grid, periodic=periodic, merge=merge)
    else:
        tree = HyperTree.from_array(grid, periodic=periodic, merge=merge)
    ref, ref_count = brute_labels(grid, c, periodic)
    labels, count = tree_components_on_grid(tree, grid.shape, connectivity=c)
    assert count == ref_count
    assert_same_partition(labels, ref)
    if not periodic:
        nd, nd_count = ndimage_labels(grid, c)
        assert nd_count == count
        assert_same_partition(labels, nd)


@st.composite
def tree_cases(draw, random_box=False):
    k = draw(st.integers(1, 4))
    depths = draw(st.lists(st.integers(0, 3), min_size=k, max_size=k).filter(lambda d: sum(d) <= 7))
    periodic = tuple(sorted(draw(st.sets(st.integers(0, k - 1)))))
    seed = draw(st.integers(0, 2**32 - 1))
    p_split = draw(st.floats(0.3, 0.9))
    merge = draw(st.booleans())
    split_root = draw(st.booleans())
    lo = hi = None
    if random_box:
        coordinate = st.floats(-100, 100, allow_subnormal=False)
        lo = np.array(draw(st.lists(coordinate, min_size=k, max_size=k)))
        width = np.array(draw(st.lists(st.floats(1e-3, 100), min_size=k, max_size=k)))
        hi = lo + width
    rng = np.random.default_rng(seed)
    tree = random_adaptive_tree(rng, depths, periodic, merge, p_split, split_root, lo, hi)
    return tree, rng


@HYPOTHESIS
@given(case=tree_cases(random_box=True), data=st.data())
def test_hypothesis_adjacency_and_components_match_brute_force(case, data):
    tree, _ = case
    c = data.draw(st.integers(1, tree.ndim))
    status = data.draw(st.sampled_from([None, IN, OUT, BOUNDARY, IN | BOUNDARY]))
    np.testing.assert_array_equal(
        adjacency(tree, status=status, connectivity=c), brute_adjacency(tree, c, status)
    )
    status = IN | OUT | BOUNDARY if status is None else status
    labels, count = components(tree, status=status, connectivity=c)
    ref, ref_count = brute_components(tree, status, c)
    assert count == ref_count
    assert_same_partition(labels, ref)


@HYPOTHESIS
@given(case=tree_cases(random_box=True))
def test_hypothesis_locate_matches_brute_force(case):
    tree, rng = case
    points = locate_points(rng, tree, n_random=60)
    status, index = locate(tree, points)
    ref_status, ref_index = brute_locate(tree, points)
    np.testing.assert_array_equal(index, ref_index)
    np.testing.assert_array_equal(status, ref_status)


@HYPOTHESIS
@given(case=tree_cases(), data=st.data())
def test_hypothesis_project_matches_brute_force(case, data):
    tree, _ = case
    k = tree.ndim
    kept = data.draw(
        st.permutations(range(k)).flatmap(
            lambda p: st.sampled_from([tuple(p[:r]) for r in range(1, k + 1)])
        )
    )
    shape = tuple(1 << d for d in tree.max_depth)
    values = rasterize(tree, shape)
    proj = project(tree, kept)
    expected = project_grid(values, kept)
    np.testing.assert_array_equal(rasterize(proj, expected.shape), expected)


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    k=st.integers(1, 4),
    data=st.data(),
    seed=st.integers(0, 2**32 - 1),
    merge=st.booleans(),
)
def test_hypothesis_deep_trees_match_brute_force(k, data, seed, merge):
    # up to 62 key bits; at most 40 per axis so that float faces stay distinct
    depth = st.integers(0, min(40, 62 // k))
    depths = data.draw(st.lists(depth, min_size=k, max_size=k).filter(lambda d: max(d) > 0))
    periodic = tuple(sorted(data.draw(st.sets(st.integers(0, k - 1)))))
    rng = np.random.default_rng(seed)
    lo = rng.uniform(-5, 5, size=k)
    hi = lo + rng.uniform(0.1, 5, size=k)
    tree, targets = point_refined_tree(rng, lo, hi, depths, periodic, merge, n_points=1)
    c = data.draw(st.integers(1, k))
    np.testing.assert_array_equal(adjacency(tree, connectivity=c), brute_adjacency(tree, c))
    labels, count = components(tree, status=IN | BOUNDARY, connectivity=c)
    ref, ref_count = brute_components(tree, IN | BOUNDARY, c)
    assert count == ref_count
    assert_same_partition(labels, ref)
    scale = (hi - lo) * np.exp2(-rng.integers(0, max(depths) + 1, size=(100, k)))
    points = np.concatenate(
        [locate_points(rng, tree, n_random=60), targets + rng.normal(size=(100, k)) * scale]
    )
    status, index = locate(tree, points)
    ref_status, ref_index = brute_locate(tree, points)
    np.testing.assert_array_equal(index, ref_index)
    np.testing.assert_array_equal(status, ref_status)
    kept = data.draw(st.permutations(range(k)))[: data.draw(st.integers(1, k))]
    inside = points[ref_index >= 0][:, kept]
    got, _ = locate(project(tree, kept), inside)
    np.testing.assert_array_equal(got, brute_project_at(tree, kept, inside))


@pytest.mark.parametrize("max_depth", [(4, 4), (3, 3, 3), (2, 4, 1), (0, 3, 2), (2, 2, 2, 2)])
def test_touching_matches_two_adjacencies(max_depth):
    """The vertex and face pairs from one search equal the two adjacencies computed
    apart, on a tree and on its refinements (pairs reused, as the resolution of an
    analysis does), whatever the statuses and periodic axes (axes of depth 0 too)."""
    from moveability.hypertree.topology import refined_touching, touching

    rng = np.random.default_rng([len(max_depth), *max_depth, 29])
    k = len(max_depth)
    fewer = False
    for trial in range(4):
        periodic = tuple(a for a in range(k) if rng.random() < 0.5)
        stop = int(rng.integers(1, max(max_depth)))
        tree = HyperTree.build(
            np.zeros(k),
            np.exp2(np.asarray(max_depth, dtype=float)),
            random_classifier(rng, 0.6, True),
            max_depth=list(max_depth),
            periodic=periodic,
            merge=False,
            stop_level=stop,
        )
        status = [None, IN | BOUNDARY][trial % 2]

        def apart(t: HyperTree, status: int | None = status) -> tuple[np.ndarray, np.ndarray]:
            return (
                adjacency(t, status=status, connectivity=k),
                adjacency(t, status=status, connectivity=1),
            )

        vertex, face = touching(tree, status=status)
        for got, want in zip((vertex, face), apart(tree), strict=True):
            np.testing.assert_array_equal(got, want, err_msg=f"{periodic}")
        fewer |= len(face) < len(vertex)
        for _ in range(3):
            mask = (tree.levels < tree.layout.n_levels) & (rng.random(len(tree)) < 0.3)
            finer = tree.refine(mask, random_classifier(rng, 0.6, True))
            is_child = ~np.isin(finer.keys, tree.keys[~mask])
            old_index = np.full(len(finer), -1)
            old_index[~is_child] = np.flatnonzero(~mask)
            vertex, face = refined_touching(finer, tree, vertex, face, old_index, status=status)
            for got, want in zip((vertex, face), apart(finer), strict=True):
                np.testing.assert_array_equal(got, want, err_msg=f"{periodic}")
            fewer |= len(face) < len(vertex)
            tree = finer
    # some leaves touch by a corner alone: the face pairs were picked out
    assert fewer
