"""Property tests of HyperTree on random trees in 1 to 6 dimensions.

Trees are random unions of axis-aligned boxes and balls in [0, 1]^k, classified
exactly for boxes and conservatively for balls, or random status grids. Set
algebra is checked as equalities of trees, and pointwise against three-valued
(Kleene) logic and the true sets; components, projections and measures are
checked against oracles computed on the finest grid of each tree.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from moveability import (
    BOUNDARY,
    IN,
    OUT,
    HyperTree,
    complement,
    components,
    difference,
    equals,
    intersection,
    leaf_volumes,
    load,
    locate,
    measure,
    project,
    union,
)

K_MAX = 6
BUILD_BITS = 14  # total depth bits of a built tree
ARRAY_BITS = 10  # total depth bits of a tree made from a grid
RASTER_CELLS = 1 << 12  # largest finest grid used as an oracle
BALL_MARGIN = 1e-9  # points this close to a sphere are not judged against the truth

IN_, OUT_, BND = int(IN), int(OUT), int(BOUNDARY)
ALL_STATUS = (IN_, OUT_, BND)

FEW = settings(deadline=None, max_examples=60, suppress_health_check=[HealthCheck.too_slow])
SOME = settings(deadline=None, max_examples=120, suppress_health_check=[HealthCheck.too_slow])


# ------------------------------------------------------------------ sets
@dataclass(frozen=True)
class Box:
    a: np.ndarray
    b: np.ndarray

    def classify(self, lo, hi):
        inside = (lo >= self.a).all(axis=1) & (hi <= self.b).all(axis=1)
        disjoint = ((hi < self.a) | (lo > self.b)).any(axis=1)
        return inside, disjoint

    def contains(self, p):
        return ((p >= self.a) & (p <= self.b)).all(axis=1), np.ones(len(p), dtype=bool)


@dataclass(frozen=True)
class Ball:
    c: np.ndarray
    r: float

    def classify(self, lo, hi):
        near = np.sqrt(((np.clip(self.c, lo, hi) - self.c) ** 2).sum(axis=1))
        far = np.sqrt((np.maximum(np.abs(lo - self.c), np.abs(hi - self.c)) ** 2).sum(axis=1))
        return far <= self.r, near > self.r

    def contains(self, p):
        d = np.sqrt(((p - self.c) ** 2).sum(axis=1))
        return d <= self.r, np.abs(d - self.r) > BALL_MARGIN


def union_classifier(shapes):
    """Kleene union of the shapes' classifications: IN if one says IN, OUT if all say OUT."""

    def classify(lo, hi):
        any_in = np.zeros(len(lo), dtype=bool)
        all_out = np.ones(len(lo), dtype=bool)
        for s in shapes:
            inside, disjoint = s.classify(lo, hi)
            any_in |= inside
            all_out &= disjoint
        return np.where(any_in, IN_, np.where(all_out, OUT_, BND))

    return classify


def truth(shapes, p):
    """Membership of points in the union of shapes, and where it can be trusted."""
    member = np.zeros(len(p), dtype=bool)
    sure = np.ones(len(p), dtype=bool)
    for s in shapes:
        m, ok = s.contains(p)
        member |= m
        sure &= ok
    return member, sure


@dataclass
class Case:
    tree: HyperTree
    shapes: list | None  # None for a tree made from a grid


# ------------------------------------------------------------ strategies
coordinate = st.one_of(
    st.sampled_from([0.0, 1.0]),  # shapes reaching the sides of the box (and across them)
    st.integers(0, 16).map(lambda i: i / 16),
    st.floats(0.0, 1.0, allow_nan=False, allow_infinity=False),
)


@st.composite
def shapes_of(draw, k):
    out = []
    for _ in range(draw(st.integers(0, 4))):
        if draw(st.booleans()):
            x = np.array([draw(coordinate) for _ in range(k)])
            y = np.array([draw(coordinate) for _ in range(k)])
            out.append(Box(np.minimum(x, y), np.maximum(x, y)))
        else:
            c = np.array([draw(coordinate) for _ in range(k)])
            out.append(Ball(c, draw(st.floats(0.05, 1.0))))
    return out


@st.composite
def per_axis_depths(draw, cap, bits):
    """One depth per axis, at most ``cap[i]`` on axis ``i`` and ``bits`` in all."""
    md = [0] * len(cap)
    for axis in draw(st.permutations(range(len(cap)))):
        md[axis] = draw(st.integers(0, min(cap[axis], bits - sum(md))))
    return tuple(md)


@st.composite
def max_depths(draw, cap, bits=BUILD_BITS):
    """An int (same depth on every axis) or one depth per axis, within ``cap``."""
    if draw(st.booleans()):
        return draw(st.integers(0, min(min(cap), bits // len(cap))))
    return draw(per_axis_depths(cap, bits))


def depth_tuple(md, k):
    return (md,) * k if isinstance(md, int) else tuple(md)


@st.composite
def grid_trees(draw, k, periodic, cap):
    md = draw(per_axis_depths(cap, ARRAY_BITS))
    coarse = tuple(draw(st.integers(0, d)) for d in md)
    seed = draw(st.integers(0, 2**32 - 1))
    weights = np.array(draw(st.sampled_from([(1, 1, 1), (6, 3, 1), (1, 8, 1), (1, 1, 0)])), float)
    rng = np.random.default_rng(seed)
    size = tuple(1 << c for c in coarse)
    grid = rng.choice(np.array(ALL_STATUS), size=size, p=weights / weights.sum())
    for axis, (c, d) in enumerate(zip(coarse, md, strict=True)):
        grid = np.repeat(grid, 1 << (d - c), axis=axis)  # blocks, so that merging happens
    tree = HyperTree.from_array(
        grid.astype(np.uint8), np.zeros(k), np.ones(k), periodic=periodic, merge=draw(st.booleans())
    )
    return Case(tree, None)


@st.composite
def built_trees(draw, k, periodic, cap):
    shapes = draw(shapes_of(k))
    md = draw(max_depths(cap))
    tree = HyperTree.build(
        np.zeros(k),
        np.ones(k),
        union_classifier(shapes),
        max_depth=md,
        periodic=periodic,
        merge=draw(st.booleans()),
    )
    return Case(tree, shapes)


def trees_of(k, periodic, cap):
    return st.one_of(built_trees(k, periodic, cap), grid_trees(k, periodic, cap))


@st.composite
def spaces(draw, k_max=K_MAX):
    """Dimension, periodic axes and a per-axis depth cap (bounding common refinements)."""
    k = draw(st.integers(1, k_max))
    periodic = ()
    if draw(st.integers(0, 3)):
        periodic = tuple(sorted(draw(st.sets(st.integers(0, k - 1), max_size=k))))
    if draw(st.booleans()):
        cap = (BUILD_BITS // k,) * k
    else:
        cap = draw(per_axis_depths((BUILD_BITS,) * k, BUILD_BITS))
    return k, periodic, cap


@st.composite
def groups(draw, n, k_max=K_MAX):
    """``n`` trees over the same box [0, 1]^k with the same periodic axes."""
    k, periodic, cap = draw(spaces(k_max))
    return [draw(trees_of(k, periodic, cap)) for _ in range(n)]


@st.composite
def one_tree(draw, k_max=K_MAX):
    return draw(trees_of(*draw(spaces(k_max))))


@st.composite
def component_trees(draw, k_max=5):
    """Grids dense in components, whose count periodicity often changes."""
    k = draw(st.integers(1, k_max))
    periodic = tuple(sorted(draw(st.sets(st.integers(0, k - 1), max_size=k))))
    md = [1] * k
    for axis in draw(st.permutations(range(k))):
        md[axis] += draw(st.integers(0, min(4, ARRAY_BITS - sum(md))))
    rng = np.random.default_rng(draw(seeds))
    p_in = draw(st.floats(0.3, 0.7))
    p_bnd = draw(st.sampled_from([0.0, 0.1]))
    probs = [p_in, 1 - p_in - p_bnd, p_bnd]
    if draw(st.booleans()):
        # noise on a grid a little coarser than the finest one
        coarse = [max(1, d - draw(st.integers(0, 1))) for d in md]
        grid = rng.choice(np.array(ALL_STATUS), size=tuple(1 << c for c in coarse), p=probs)
        for axis, (c, d) in enumerate(zip(coarse, md, strict=True)):
            grid = np.repeat(grid, 1 << (d - c), axis=axis)
    else:
        # dyadic blocks of many sizes painted over each other: large leaves meet small ones
        grid = np.full(tuple(1 << d for d in md), OUT_)
        for _ in range(draw(st.integers(1, 24))):
            block = []
            for d in md:
                size = 1 << int(rng.integers(0, d + 1))
                start = int(rng.integers(0, (1 << d) // size)) * size
                block.append(slice(start, start + size))
            grid[tuple(block)] = rng.choice(np.array(ALL_STATUS), p=probs)
    tree = HyperTree.from_array(
        grid.astype(np.uint8), np.zeros(k), np.ones(k), periodic=periodic, merge=draw(st.booleans())
    )
    return Case(tree, None)


def sample_points(seed, k, n=64):
    """Random points, points on the faces of a dyadic grid, and the box corners."""
    rng = np.random.default_rng(seed)
    random = rng.random((n, k))
    faces = rng.integers(0, 9, size=(16, k)) / 8
    corners = np.array([np.zeros(k), np.ones(k)])
    return np.concatenate([random, faces, corners])


seeds = st.integers(0, 2**32 - 1)


# -------------------------------------------------------------- helpers
def kleene_or(x, y):
    return np.where((x == IN_) | (y == IN_), IN_, np.where((x == OUT_) & (y == OUT_), OUT_, BND))


def kleene_and(x, y):
    return np.where((x == OUT_) | (y == OUT_), OUT_, np.where((x == IN_) & (y == IN_), IN_, BND))


def kleene_not(x):
    return np.where(x == IN_, OUT_, np.where(x == OUT_, IN_, BND))


def status_at(tree, points):
    return locate(tree, points)[0].astype(np.int64)


def close(x, y):
    return x == pytest.approx(y, rel=1e-9, abs=1e-12)


def le(x, y):
    return x <= y + 1e-9 * max(1.0, abs(y))


def assert_valid(tree):
    """Leaves sorted by key, aligned and tiling the box; statuses valid."""
    layout = tree.layout
    keys = tree.keys.astype(object)
    spans = [layout.span(int(level)) for level in tree.levels]
    assert len(tree) >= 1
    assert keys[0] == 0
    for i in range(len(tree) - 1):
        assert keys[i] + spans[i] == keys[i + 1]
    assert keys[-1] + spans[-1] == layout.span(0)
    assert all(int(key) % span == 0 for key, span in zip(keys, spans, strict=True))
    assert np.isin(tree.status, ALL_STATUS).all()
    assert close(float(leaf_volumes(tree).sum()), float(np.prod(tree.hi - tree.lo)))


def finest_shape(tree):
    return tuple(1 << d for d in tree.max_depth)


def raster(tree):
    """Status of every finest cell of the tree, as a grid (the oracle of this file)."""
    shape = finest_shape(tree)
    idx = np.indices(shape).reshape(tree.ndim, -1).T
    res = np.array(shape, dtype=np.float64)
    centres = tree.lo + (tree.hi - tree.lo) * (idx + 0.5) / res
    return status_at(tree, centres).reshape(shape)


def grid_components(taken, periodic, connectivity):
    """Connected components of the True cells of a grid, axes in ``periodic`` wrapped."""
    shape = taken.shape
    k = taken.ndim
    n = taken.size
    flat = np.flatnonzero(taken.ravel())
    if not flat.size:
        return 0, np.full(shape, -1)
    coords = np.array(np.unravel_index(flat, shape)).T
    src, dst = [flat], [flat]
    for d in itertools.product((-1, 0, 1), repeat=k):
        if not 1 <= sum(x != 0 for x in d) <= connectivity:
            continue
        nb = coords + np.array(d)
        ok = np.ones(len(nb), dtype=bool)
        for axis in range(k):
            if axis in periodic:
                nb[:, axis] %= shape[axis]
            else:
                ok &= (nb[:, axis] >= 0) & (nb[:, axis] < shape[axis])
        target = np.ravel_multi_index(nb[ok].T, shape)
        keep = taken.ravel()[target]
        src.append(flat[ok][keep])
        dst.append(target[keep])
    s, t = np.concatenate(src), np.concatenate(dst)
    graph = coo_matrix((np.ones(len(s), dtype=np.int8), (s, t)), shape=(n, n)).tocsr()
    _, raw = connected_components(graph, directed=False)
    labels = np.full(n, -1)
    labels[flat] = raw[flat]
    count = len(np.unique(raw[flat]))
    return count, labels.reshape(shape)


# --------------------------------------------------------- set algebra
@SOME
@given(groups(2))
def test_de_morgan(cases):
    a, b = (c.tree for c in cases)
    assert ~(a | b) == (~a & ~b)
    assert ~(a & b) == (~a | ~b)
    assert complement(union(a, b)) == intersection(complement(a), complement(b))


@SOME
@given(one_tree())
def test_idempotence_and_double_complement(case):
    a = case.tree
    assert (a | a) == a
    assert (a & a) == a
    assert ~~a == a
    assert np.array_equal((~~a).status, a.status)
    assert equals(a, a)


@SOME
@given(groups(2))
def test_commutativity(cases):
    a, b = (c.tree for c in cases)
    assert (a | b) == (b | a)
    assert (a & b) == (b & a)
    # the result is a single well-formed tree, whatever the operand order
    for t in (a | b, a & b, a - b):
        assert_valid(t)


@FEW
@given(groups(3, k_max=4))
def test_associativity_and_distributivity(cases):
    a, b, c = (x.tree for x in cases)
    assert ((a | b) | c) == (a | (b | c))
    assert ((a & b) & c) == (a & (b & c))
    assert (a & (b | c)) == ((a & b) | (a & c))
    assert (a | (b & c)) == ((a | b) & (a | c))


@SOME
@given(groups(2))
def test_union_contains_operand(cases):
    a, b = (c.tree for c in cases)
    u = a | b
    assert (u & a) == a
    assert (u | a) == u
    assert ((a & b) | a) == a
    ia, oa = measure(a)
    iu, ou = measure(u)
    ii, oi = measure(a & b)
    assert le(ia, iu) and le(oa, ou)
    assert le(ii, ia) and le(oi, oa)
    assert le(ia, oa) and le(iu, ou)


@SOME
@given(groups(2))
def test_difference_is_and_not(cases):
    a, b = (c.tree for c in cases)
    assert (a - b) == (a & ~b)
    assert difference(a, b) == intersection(a, complement(b))
    assert (a - a) == (a & ~a)


@SOME
@given(groups(2))
def test_equality_is_semantic(cases):
    a, b = (c.tree for c in cases)
    if sum(max(x, y) for x, y in zip(a.max_depth, b.max_depth, strict=True)) > 14:
        return
    same = bool(np.array_equal(raster_on(a, b), raster_on(b, a)))
    assert (a == b) is same
    assert (a == b) == (b == a)
    assert (a != b) is (not same)


def raster_on(tree, other):
    """Statuses of ``tree`` on the finest grid of the common layout with ``other``."""
    shape = tuple(1 << max(x, y) for x, y in zip(tree.max_depth, other.max_depth, strict=True))
    idx = np.indices(shape).reshape(tree.ndim, -1).T
    centres = tree.lo + (tree.hi - tree.lo) * (idx + 0.5) / np.array(shape, dtype=np.float64)
    return status_at(tree, centres)


@SOME
@given(one_tree())
def test_unmerged_equals_merged(case):
    a = case.tree
    reordered = HyperTree(a.lo, a.hi, a.max_depth, a.keys, a.levels, a.status, a.periodic)
    assert reordered == a
    if np.prod(finest_shape(a)) > RASTER_CELLS:
        return
    grid = raster(a).astype(np.uint8)
    for merge in (False, True):
        t = HyperTree.from_array(grid, a.lo, a.hi, periodic=a.periodic, merge=merge)
        assert t == a
        assert len(t) <= grid.size
    assert len(HyperTree.from_array(grid, a.lo, a.hi, merge=False)) == grid.size


# ------------------------------------------------------------ pointwise
@SOME
@given(groups(2), seeds)
def test_kleene_soundness_at_points(cases, seed):
    a, b = (c.tree for c in cases)
    p = sample_points(seed, a.ndim)
    sa, sb = status_at(a, p), status_at(b, p)
    so, sn, sx, sd = (status_at(t, p) for t in (a | b, a & b, ~a, a - b))
    # implications that any sound combination must satisfy
    assert (so[(sa == IN_) | (sb == IN_)] == IN_).all()
    assert (so[(sa == OUT_) & (sb == OUT_)] == OUT_).all()
    assert (sn[(sa == OUT_) | (sb == OUT_)] == OUT_).all()
    assert (sn[(sa == IN_) & (sb == IN_)] == IN_).all()
    assert (sx[sa == IN_] == OUT_).all()
    assert (sx[sa == OUT_] == IN_).all()
    assert (sd[(sa == OUT_) | (sb == IN_)] == OUT_).all()
    assert (sd[(sa == IN_) & (sb == OUT_)] == IN_).all()
    # and, operands being combined on their common refinement, exact Kleene logic
    assert np.array_equal(so, kleene_or(sa, sb))
    assert np.array_equal(sn, kleene_and(sa, sb))
    assert np.array_equal(sx, kleene_not(sa))
    assert np.array_equal(sd, kleene_and(sa, kleene_not(sb)))


@SOME
@given(groups(2), seeds)
def test_trees_are_sound_against_the_true_sets(cases, seed):
    built = [c for c in cases if c.shapes is not None]
    p = sample_points(seed, cases[0].tree.ndim)
    for case in built:
        member, sure = truth(case.shapes, p)
        s = status_at(case.tree, p)
        assert member[sure & (s == IN_)].all()
        assert not member[sure & (s == OUT_)].any()
    if len(built) == 2:
        (ma, ka), (mb, kb) = (truth(c.shapes, p) for c in built)
        sure = ka & kb
        a, b = built[0].tree, built[1].tree
        for tree, member in (
            (a | b, ma | mb),
            (a & b, ma & mb),
            (a - b, ma & ~mb),
            (~a, ~ma),
        ):
            s = status_at(tree, p)
            assert member[sure & (s == IN_)].all()
            assert not member[sure & (s == OUT_)].any()


@FEW
@given(spaces(), st.data())
def test_deeper_build_refines_shallower(space, data):
    k, periodic, _ = space
    shapes = data.draw(shapes_of(k))
    d1 = data.draw(st.integers(0, BUILD_BITS // k - 1))
    d2 = data.draw(st.integers(d1 + 1, BUILD_BITS // k))
    classify = union_classifier(shapes)
    box = (np.zeros(k), np.ones(k))
    shallow = HyperTree.build(*box, classify, max_depth=d1, periodic=periodic)
    deep = HyperTree.build(*box, classify, max_depth=d2, periodic=periodic)
    p = sample_points(data.draw(seeds), k)
    ss, sd = status_at(shallow, p), status_at(deep, p)
    assert (sd[ss == IN_] == IN_).all()
    assert (sd[ss == OUT_] == OUT_).all()
    assert measure(shallow - deep)[0] == 0.0
    assert measure(deep - shallow)[0] == 0.0
    i1, o1 = measure(shallow)
    i2, o2 = measure(deep)
    assert le(i1, i2) and le(i2, o2) and le(o2, o1)
    # combining trees of different depths keeps the deeper layout
    assert (shallow | deep).max_depth == deep.max_depth
    assert (shallow & deep) == (deep & shallow)


@FEW
@given(spaces(), st.data())
def test_operands_of_different_per_axis_depths(space, data):
    k, periodic, _ = space
    shapes = data.draw(shapes_of(k))
    md_a = depth_tuple(data.draw(max_depths((BUILD_BITS,) * k)), k)
    # b's depths are drawn independently but for a bound on the common layout (18 bits):
    # relayout cuts a leaf into 2 ** (extra bits) cells, e.g. (14, 0) with (0, 14) gives
    # 2 ** 28 cells, which no longer fits in memory
    extra, md_b = 4, [0] * k
    for axis in data.draw(st.permutations(range(k))):
        top = min(BUILD_BITS - sum(md_b), md_a[axis] + extra)
        md_b[axis] = data.draw(st.integers(0, top))
        extra -= max(0, md_b[axis] - md_a[axis])
    md_b = tuple(md_b)
    classify = union_classifier(shapes)
    box = (np.zeros(k), np.ones(k))
    a = HyperTree.build(*box, classify, max_depth=md_a, periodic=periodic)
    b = HyperTree.build(*box, classify, max_depth=md_b, periodic=periodic)
    for t in (a | b, a & b, a - b):
        assert t.max_depth == tuple(max(x, y) for x, y in zip(md_a, md_b, strict=True))
        assert t.periodic == periodic
        assert_valid(t)
    # two sound approximations of one set: they never disagree on IN versus OUT
    p = sample_points(data.draw(seeds), k)
    sa, sb = status_at(a, p), status_at(b, p)
    assert not ((sa == IN_) & (sb == OUT_)).any()
    assert not ((sa == OUT_) & (sb == IN_)).any()
    assert measure(a - b)[0] == 0.0
    assert measure(b - a)[0] == 0.0
    # so [inner(a | b), outer(a & b)] is a bracket at least as tight as each one's
    ia, oa = measure(a)
    ib, ob = measure(b)
    inner, outer = measure(a | b)[0], measure(a & b)[1]
    assert le(max(ia, ib), inner) and le(outer, min(oa, ob))
    assert le(inner, outer)
    assert close(inner, ia + ib - measure(a & b)[0])


# --------------------------------------------------------------- measure
@SOME
@given(one_tree(), seeds)
def test_measure_additive_over_a_selection(case, seed):
    a = case.tree
    rng = np.random.default_rng(seed)
    m = rng.random(len(a)) < 0.5
    x, y = a.select(m), a.select(~m)
    ia, oa = measure(a)
    ix, ox = measure(x)
    iy, oy = measure(y)
    assert close(ix + iy, ia)
    assert close(ox + oy, oa)
    assert (x | y) == a
    assert measure(x & y) == (0.0, 0.0)
    # select by indices is the same as select by mask
    assert x == a.select(np.flatnonzero(m))


@SOME
@given(groups(2))
def test_measure_additive_over_a_crisp_split(cases):
    a, b0 = (c.tree for c in cases)
    b = b0.select(b0.status == IN_)  # no BOUNDARY leaf left
    assert not (b.status == BND).any()
    ia, oa = measure(a)
    i1, o1 = measure(a & ~b)
    i2, o2 = measure(a & b)
    assert close(i1 + i2, ia)
    assert close(o1 + o2, oa)


@SOME
@given(one_tree())
def test_measure_of_complement_and_raster(case):
    a = case.tree
    vol = float(np.prod(a.hi - a.lo))
    inner, outer = measure(a)
    ci, co = measure(~a)
    assert 0.0 <= inner <= outer <= vol * (1 + 1e-12)
    assert close(ci, vol - outer)
    assert close(co, vol - inner)
    if np.prod(finest_shape(a)) <= RASTER_CELLS:
        r = raster(a)
        cell = vol / r.size
        assert close(inner, np.count_nonzero(r == IN_) * cell)
        assert close(outer, np.count_nonzero(r != OUT_) * cell)


# ------------------------------------------------------------ projection
@st.composite
def axes_of(draw, k):
    n = draw(st.integers(1, k))
    return tuple(draw(st.permutations(range(k)))[:n])


@SOME
@given(groups(2), st.data())
def test_projection_monotone(cases, data):
    a, b = (c.tree for c in cases)
    axes = data.draw(axes_of(a.ndim))
    pa, pab = project(a, axes), project(a & b, axes)
    assert pa.ndim == len(axes)
    assert pa.max_depth == tuple(a.max_depth[i] for i in axes)
    ia, oa = measure(pa)
    iab, oab = measure(pab)
    assert le(iab, ia) and le(oab, oa)
    p = sample_points(data.draw(seeds), len(axes))
    sa, sab = status_at(pa, p), status_at(pab, p)
    assert (sa[sab == IN_] == IN_).all()
    assert (sab[sa == OUT_] == OUT_).all()
    # the union projects onto the union of the projections
    assert project(a | b, axes) == (project(a, axes) | project(b, axes))


@SOME
@given(one_tree(), st.data())
def test_projection_matches_the_finest_grid(case, data):
    a = case.tree
    if np.prod(finest_shape(a)) > RASTER_CELLS:
        return
    axes = data.draw(axes_of(a.ndim))
    p = project(a, axes)
    assert_valid(p)
    assert p.periodic == tuple(i for i, ax in enumerate(axes) if ax in a.periodic)
    r = raster(a)
    dropped = tuple(i for i in range(a.ndim) if i not in axes)
    kept_order = np.transpose(r, list(axes) + list(dropped))
    flat = kept_order.reshape((*(r.shape[i] for i in axes), -1))
    expected = np.where(
        (flat == IN_).any(axis=-1), IN_, np.where((flat == OUT_).all(axis=-1), OUT_, BND)
    )
    assert np.array_equal(raster(p), expected)
    # projecting onto every axis in order gives the same set
    assert project(a, range(a.ndim)) == a


@SOME
@given(one_tree(), seeds)
def test_projection_is_sound_for_built_trees(case, seed):
    a = case.tree
    if case.shapes is None or a.ndim < 2:
        return
    axes = (0,)
    p = project(a, axes)
    pts = sample_points(seed, a.ndim)
    s_full = status_at(a, pts)
    s_proj = status_at(p, pts[:, list(axes)])
    # a point IN the tree projects IN; a projected point OUT has no IN/BOUNDARY point above it
    assert (s_proj[s_full == IN_] == IN_).all()
    assert (s_full[s_proj == OUT_] == OUT_).all()


# ------------------------------------------------------------ components
statuses_taken = st.sampled_from(
    [IN_, OUT_, BND, IN_ | BND, OUT_ | BND, IN_ | OUT_ | BND, int(IN | BOUNDARY)]
)


@SOME
@given(st.one_of(one_tree(k_max=5), component_trees()), statuses_taken, st.data())
def test_components_match_the_finest_grid(case, status, data):
    a = case.tree
    cells = int(np.prod(finest_shape(a)))
    if cells > RASTER_CELLS:
        return
    max_c = a.ndim if cells * 3**a.ndim <= 1 << 20 else 1
    connectivity = data.draw(st.integers(1, max_c))
    labels, count = components(a, status=status, connectivity=connectivity)
    r = raster(a)
    taken = (r & status) != 0
    expected, grid_labels = grid_components(taken, a.periodic, connectivity)
    assert count == expected
    chosen = (a.status & status) != 0
    assert ((labels >= 0) == chosen).all()
    assert set(np.unique(labels[chosen]).tolist()) == set(range(count))
    # the two labellings are the same partition of the finest cells
    shape = finest_shape(a)
    idx = np.indices(shape).reshape(a.ndim, -1).T
    centres = a.lo + (a.hi - a.lo) * (idx + 0.5) / np.array(shape, dtype=np.float64)
    leaf = locate(a, centres)[1].reshape(shape)
    pairs = {(int(labels[i]), int(g)) for i, g in zip(leaf[taken], grid_labels[taken], strict=True)}
    assert len(pairs) == count
    # labels are numbered in the order of their first leaf
    if count:
        _, first = np.unique(labels[chosen], return_index=True)
        assert (np.diff(first) > 0).all()


@SOME
@given(st.one_of(one_tree(), component_trees()))
def test_components_of_complement_and_merge_invariance(case):
    a = case.tree
    n_in = components(a, status=IN)[1]
    assert components(~a, status=OUT)[1] == n_in
    assert components(~a, status=IN)[1] == components(a, status=OUT)[1]
    # splitting every leaf into finest cells does not change the components
    if np.prod(finest_shape(a)) <= RASTER_CELLS:
        unmerged = HyperTree.from_array(raster(a), a.lo, a.hi, periodic=a.periodic, merge=False)
        assert len(unmerged) == np.prod(finest_shape(a))
        assert components(unmerged, status=IN)[1] == n_in
    # more connectivity can only join components
    counts = [components(a, status=IN, connectivity=c)[1] for c in range(1, a.ndim + 1)]
    assert counts == sorted(counts, reverse=True)


# ----------------------------------------------------------- persistence
@settings(
    deadline=None,
    max_examples=40,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(case=one_tree())
def test_save_load_roundtrip(tmp_path, case):
    a = case.tree
    path = tmp_path / "tree.npz"
    a.save(path)
    b = load(path)
    assert b == a
    assert np.array_equal(b.keys, a.keys) and b.keys.dtype == a.keys.dtype
    assert np.array_equal(b.levels, a.levels) and b.levels.dtype == a.levels.dtype
    assert np.array_equal(b.status, a.status) and b.status.dtype == a.status.dtype
    assert np.array_equal(b.lo, a.lo) and np.array_equal(b.hi, a.hi)
    assert b.max_depth == a.max_depth
    assert b.periodic == a.periodic
    assert HyperTree.load(path) == a
    # a loaded tree combines with the original
    assert (b | a) == a and (b & ~a) == (a & ~a)


@pytest.mark.parametrize("k", [1, 2, 3, 4])
@pytest.mark.parametrize("wrap", [False, True])
@pytest.mark.parametrize("merge", [False, True])
def test_components_where_a_large_leaf_meets_a_smaller_one(k, wrap, merge):
    """A level-1 leaf U and a level-2 leaf L touching U's face away from U's lower corner.

    Only a probe from L, across its upper face, finds the contact (the probe from
    U across its lower face lands elsewhere); with ``wrap`` the contact is across
    the periodic end of the axis.
    """
    for axis in range(k):
        grid = np.full((8,) * k, OUT_)
        upper = [slice(0, 4)] * k
        small = [slice(2, 4)] * k
        if wrap:
            upper[axis], small[axis] = slice(0, 4), slice(6, 8)
        else:
            upper[axis], small[axis] = slice(4, 8), slice(2, 4)
        grid[tuple(upper)] = IN_
        grid[tuple(small)] = IN_
        periodic = (axis,) if wrap else ()
        tree = HyperTree.from_array(grid, periodic=periodic, merge=merge)
        if merge:
            assert len(tree) < grid.size
        expected, _ = grid_components(grid == IN_, periodic, 1)
        assert expected == 1
        for c in range(1, k + 1):
            assert components(tree, connectivity=c)[1] == expected
        # and with the statuses reversed, OUT taken
        assert components(~tree, status=OUT, connectivity=1)[1] == expected
