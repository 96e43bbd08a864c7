"""The five-bar analysis against an independent method in the joint space.

For a five-bar, det A vanishes exactly where the circles of radius L2 about C
and L4 about D are tangent, so the parallel-singularity-free configurations
are, for each assembly mode (sign of det A), a copy of
``D = {q in Q : |L2 - L4| < |C(q) - D(q)| < L2 + L4}``. The regions R_j are
therefore (component of D, sign) pairs. The reference labels D on a fine grid
of Q (scipy.ndimage, with wrap-around on unlimited joints) and decides the
region of a configuration by the label of its joint cell; the tree never sees
this construction.
"""

import numpy as np
import pytest
from scipy import ndimage

from moveability import analyze, load_analysis, save_analysis
from moveability.limits import JointLimit
from moveability.mechanisms import FiveBar

PAPER = (7.0, 8.0, 5.0, 8.0, 5.0)
CASES = [
    (PAPER, (0.0, np.pi), (0.0, np.pi)),
    (PAPER, (-np.pi, np.pi), (-np.pi, np.pi)),
    (PAPER, None, None),
    ((6.0, 5.0, 7.0, 5.0, 7.0), (-np.pi / 2, np.pi), (0.0, 1.5 * np.pi)),
    ((3.0, 4.0, 4.0, 5.0, 3.0), None, (-2.0, 2.5)),
    ((5.0, 6.0, 4.0, 5.0, 4.5), (0.3, 2.8), (-0.5, 2.0)),
    # L3 = L4: the base B is reached with every angle of joint 2; regions joined only
    # through that point are not certified (answers there stay unknown)
    ((5.0, 6.0, 4.0, 5.0, 5.0), (0.3, 2.8), (-0.5, 2.0)),
]
N_GRID = 800


def _mechanism(lengths, lim1, lim2):
    limits = tuple(
        JointLimit.unlimited() if lim is None else JointLimit(*lim) for lim in (lim1, lim2)
    )
    return FiveBar(*lengths, limits=limits)


class JointSpaceReference:
    """Regions of a five-bar from a labelled grid of its joint space."""

    def __init__(self, m):
        self.m = m
        L0, L1, L2, L3, L4 = m.lengths
        self.lo = np.array([lim.lo for lim in m.limits])
        self.hi = np.array([lim.lo + 2 * np.pi if lim.periodic else lim.hi for lim in m.limits])
        t = [np.linspace(self.lo[i], self.hi[i], N_GRID + 1) for i in range(2)]
        centres = [0.5 * (a[1:] + a[:-1]) for a in t]
        t1, t2 = np.meshgrid(*centres, indexing="ij")
        cd = np.hypot(L1 * np.cos(t1) - L0 - L3 * np.cos(t2), L1 * np.sin(t1) - L3 * np.sin(t2))
        self.inside = (cd > abs(L2 - L4)) & (cd < L2 + L4)
        labels, count = ndimage.label(self.inside)
        # glue the ends of unlimited joints
        parent = np.arange(count + 1)

        def find(x):
            while parent[x] != x:
                x = parent[x]
            return x

        for axis, lim in enumerate(m.limits):
            if not lim.periodic:
                continue
            a = np.take(labels, 0, axis=axis)
            b = np.take(labels, -1, axis=axis)
            for u, v in zip(a[(a > 0) & (b > 0)], b[(a > 0) & (b > 0)], strict=True):
                ru, rv = find(u), find(v)
                if ru != rv:
                    parent[max(ru, rv)] = min(ru, rv)
        roots = np.array([find(x) for x in range(count + 1)])
        kept = np.unique(roots[1:]) if count else np.zeros(0, dtype=int)
        rank = np.full(count + 1, -1)
        rank[kept] = np.arange(kept.size)
        self.labels = np.where(labels > 0, rank[roots[labels]], -1)  # -1 outside D
        self.cd = cd
        self.n_components = int(self.labels.max()) + 1

    def configurations(self, points):
        """(label, sign, robust) of each posture of each point; label -1 if not valid."""
        m = self.m
        L2, L4 = m.lengths[2], m.lengths[4]
        q = m.joint_angles(points)  # (n, 4, 2)
        n = points.shape[0]
        label = np.full((n, 4), -1)
        robust = np.ones((n, 4), dtype=bool)
        flat_pts = np.repeat(points, 4, axis=0)
        det = m.det_a(flat_pts, q.reshape(-1, 2)).reshape(n, 4)
        sign = np.sign(np.nan_to_num(det)).astype(int)
        finite = np.isfinite(q).all(axis=-1)
        ok = finite.copy()
        idx = np.zeros((n, 4, 2), dtype=int)
        for i, lim in enumerate(m.limits):
            a = np.where(finite, q[..., i], 0.0)
            w = lim.wrap(a)
            inside = lim.contains(a)
            ok &= inside
            span = self.hi[i] - self.lo[i]
            f = (w - self.lo[i]) / span * N_GRID
            idx[..., i] = np.clip(np.floor(f).astype(int), 0, N_GRID - 1)
            # near a joint limit the grid cannot tell
            if not lim.periodic:
                near = (np.abs(w - lim.lo) < 0.02) | (np.abs(w - lim.hi) < 0.02)
                robust &= ~(finite & near)
        lab = self.labels[idx[..., 0], idx[..., 1]]
        cd = self.cd[idx[..., 0], idx[..., 1]]
        robust &= ~(finite & ((np.abs(cd - (L2 + L4)) < 0.05) | (np.abs(cd - abs(L2 - L4)) < 0.05)))
        robust &= ~(finite & (np.abs(np.nan_to_num(det)) < 0.05))
        label = np.where(ok, lab, -1)
        return label, sign, robust

    def regions_at(self, points):
        """Set of (label, sign) regions holding a configuration of each point."""
        label, sign, robust = self.configurations(points)
        out = [
            {(int(label[i, p]), int(sign[i, p])) for p in range(4) if label[i, p] >= 0}
            for i in range(points.shape[0])
        ]
        return out, robust.all(axis=1)


@pytest.fixture(scope="module", params=range(len(CASES)))
def case(request):
    m = _mechanism(*CASES[request.param])
    return m, JointSpaceReference(m), analyze(m, precision=0.1)


def _match(result, ref, points):
    """Reference region of each tree region, from points certainly in it."""
    answers = result.locate(points)["points"]
    regions, robust = ref.regions_at(points)
    mapping = {}
    for r in result.regions:
        seen = set()
        for a, rs, ok in zip(answers, regions, robust, strict=True):
            if ok and a["regions"][str(r.id)] is True:
                signed = {x for x in rs if x[1] == r.sign}
                seen.add(frozenset(signed))
        # every point certainly in region r has a configuration of one reference region
        common = frozenset.intersection(*seen) if seen else frozenset()
        assert len(common) >= 1, (r, seen)
        mapping[r.id] = common
    return mapping


def test_region_count_matches_joint_space_components(case):
    _, ref, result = case
    assert len(result.regions) == 2 * ref.n_components
    # possible components without a certified part may remain, but they are small
    assert result.undecided["area"] <= 0.02 * result.workspace["area"][1]


def test_membership_agrees_with_the_joint_space(case):
    m, ref, result = case
    rng = np.random.default_rng(5)
    lo, hi = m.bounds
    pts = rng.uniform(lo, hi, (4000, 2))
    mapping = _match(result, ref, pts)
    # distinct tree regions are distinct reference regions
    chosen = [next(iter(v)) for v in mapping.values() if len(v) == 1]
    assert len(set(chosen)) == len(chosen)
    answers = result.locate(pts)["points"]
    regions, robust = ref.regions_at(pts)
    n_definite = 0
    for a, rs, ok in zip(answers, regions, robust, strict=True):
        if not ok:
            continue
        if a["workspace"] is False:
            assert not rs
        for r in result.regions:
            ans = a["regions"][str(r.id)]
            targets = mapping[r.id]
            if ans is True:
                assert rs & targets, (a, rs, targets)
                n_definite += 1
            elif ans is False:
                assert not (rs & targets), (a, rs, targets)
                n_definite += 1
    assert n_definite > 0.8 * len(result.regions) * robust.sum()


def test_far_points_get_definite_answers(case):
    """A pose whose neighbourhood of radius 2 * precision has one reference answer
    gets a definite answer."""
    m, ref, result = case
    if m.lengths[3] == m.lengths[4] or m.lengths[1] == m.lengths[2]:
        pytest.skip("a leg with equal links: connections through its base are not certified")
    eps = result.precision
    rng = np.random.default_rng(9)
    lo, hi = m.bounds
    centres = rng.uniform(lo, hi, (1500, 2))
    angles = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    ring = np.concatenate(
        [np.stack([r * np.cos(angles), r * np.sin(angles)], axis=1) for r in (eps, 2 * eps)]
    )
    mapping = _match(result, ref, rng.uniform(lo, hi, (3000, 2)))
    answers = result.locate(centres)["points"]
    checked = 0
    for c, a in zip(centres, answers, strict=True):
        around = c + np.concatenate([[[0.0, 0.0]], ring])
        regions, robust = ref.regions_at(around)
        if not robust.all():
            continue
        for r in result.regions:
            inside = [bool(rs & mapping[r.id]) for rs in regions]
            if all(inside) or not any(inside):
                assert a["regions"][str(r.id)] is not None, (c, r)
                checked += 1
    assert checked > 500


def test_areas_bracket_a_grid_estimate_and_tighten(case):
    m, ref, result = case
    lo, hi = m.bounds
    n = 500
    xs = lo[0] + (np.arange(n) + 0.5) * (hi[0] - lo[0]) / n
    ys = lo[1] + (np.arange(n) + 0.5) * (hi[1] - lo[1]) / n
    grid = np.stack(np.meshgrid(xs, ys), -1).reshape(-1, 2)
    cell = (hi[0] - lo[0]) * (hi[1] - lo[1]) / n**2
    regions, _ = ref.regions_at(grid)
    mapping = _match(result, ref, grid[::7])
    w_estimate = cell * sum(1 for rs in regions if rs)
    # a grid estimate errs by about the boundary length times the spacing
    slack = 0.02 * w_estimate
    w_in, w_out = result.workspace["area"]
    assert w_in - slack <= w_estimate <= w_out + slack
    for r in result.regions:
        estimate = cell * sum(1 for rs in regions if rs & mapping[r.id])
        assert r.area[0] - slack <= estimate <= r.area[1] + slack
    coarse = analyze(m, precision=0.3, resolve=False)
    fine = analyze(m, precision=0.05, resolve=False)
    widths = [x.workspace["area"][1] - x.workspace["area"][0] for x in (coarse, result, fine)]
    assert widths[0] > widths[1] > widths[2]


def test_regions_do_not_change_with_precision(case):
    m, _, result = case
    summaries = []
    for eps in (0.2, 0.1, 0.05):
        r = analyze(m, precision=eps, resolve=False)
        summaries.append(
            sorted((x.sign, round(0.5 * (x.area[0] + x.area[1]), 0)) for x in r.regions)
        )
    counts = {len(s) for s in summaries}
    assert counts == {len(result.regions)}
    signs = {tuple(x[0] for x in s) for s in summaries}
    assert len(signs) == 1


def test_paper_cases():
    joint = JointLimit(0.0, np.pi)
    result = analyze(FiveBar(*PAPER, limits=(joint, joint)), precision=0.05)
    assert len(result.regions) == 2
    assert result.n_connected is False
    assert all(r.equals_workspace is False for r in result.regions)
    full = JointLimit(-np.pi, np.pi)
    result = analyze(FiveBar(*PAPER, limits=(full, full)), precision=0.05)
    assert len(result.regions) == 2
    # near the top corner of W every posture has det A > 0, near the bottom one < 0
    top, bottom = [3.5, 12.4], [3.5, -12.4]
    assert result.feasible([top, bottom])["feasible"] is False
    assert result.n_connected is False


def test_feasible_witnesses_are_valid_configurations():
    m = _mechanism(*CASES[0])
    result = analyze(m, precision=0.1)
    rng = np.random.default_rng(2)
    lo, hi = m.bounds
    found = 0
    candidates = rng.uniform(lo, hi, (3000, 2))
    inside = [a["workspace"] is True for a in result.locate(candidates)["points"]]
    candidates = candidates[np.array(inside)]
    for _ in range(40):
        pts = candidates[rng.choice(len(candidates), 3)]
        answer = result.feasible(pts)
        if answer["feasible"]:
            q = np.array(answer["postures"])
            assert np.abs(m.constraints(pts, q)).max() < 1e-9
            for i, lim in enumerate(m.limits):
                assert lim.contains(q[:, i]).all()
            region = result.regions[answer["region"]]
            assert (np.sign(m.det_a(pts, q)) == region.sign).all()
            found += 1
        else:
            assert answer["postures"] is None
    assert found > 10


def test_save_and_load_give_the_same_answers(tmp_path):
    m = _mechanism(*CASES[3])
    result = analyze(m, precision=0.2)
    path = tmp_path / "analysis.npz"
    save_analysis(result, path)
    again = load_analysis(path)
    assert again.to_dict() == result.to_dict()
    pts = np.random.default_rng(0).uniform(*m.bounds, (50, 2))
    assert again.locate(pts) == result.locate(pts)


def test_leaf_table_from_the_build_by_level_or_by_location(monkeypatch):
    """The sheet table of the leaves is gathered from the build's tables level by
    level; when a level's cells are not its leaves in key order, they are located
    one by one: the same table either way."""
    from dataclasses import fields

    import moveability.analysis.result as result_module

    captured = []
    original = result_module._leaf_table

    def capture(mechanism, tree, kept):
        captured.append((mechanism, tree, list(kept)))
        return original(mechanism, tree, kept)

    monkeypatch.setattr(result_module, "_leaf_table", capture)
    analyze(FiveBar(*PAPER), precision=0.2, resolve=False)
    mechanism, tree, kept = captured[0]
    fast = original(mechanism, tree, kept)
    rng = np.random.default_rng(7)
    shuffled = []
    for cell_lo, cell_hi, table in kept:
        order = rng.permutation(len(cell_lo))
        shuffled.append((cell_lo[order], cell_hi[order], table.take(order)))
    located = original(mechanism, tree, shuffled)
    assert any(len(c) > 1 for c, _, _ in kept)
    for f in fields(fast):
        np.testing.assert_array_equal(getattr(fast, f.name), getattr(located, f.name), f.name)


def test_leaf_volumes_by_level_are_those_of_each_leaf():
    """The leaves' volumes computed once per level are, bit for bit, those computed
    leaf by leaf, on a tree of leaves of many levels and unequal axes."""
    from moveability import BOUNDARY, IN, OUT, HyperTree
    from moveability.analysis.result import _leaf_volumes
    from moveability.hypertree.measurement import leaf_volumes

    rng = np.random.default_rng(5)

    def mixed(lo, hi):
        return rng.choice(np.array([IN, OUT, BOUNDARY], dtype=np.uint8), size=len(lo))

    tree = HyperTree.build(
        [-1.3, 0.1, 0.0], [2.9, 0.7, 6.283185307179586], mixed, max_depth=[5, 3, 6], merge=False
    )
    assert len(np.unique(tree.levels)) > 2
    np.testing.assert_array_equal(_leaf_volumes(tree), leaf_volumes(tree))


def test_sub_node_bounds_are_the_joint_pieces():
    """The pieces of the region graph's sub-nodes, written node by node (a stroke's
    in a compiled pass), are those of joint_pieces, for free, prismatic and
    limited revolute joints: each leg's piece of each slot."""
    from moveability.analysis.regions import _sub_node_bounds, joint_pieces, split_legs

    rng = np.random.default_rng(8)
    lo = rng.uniform(-10, 30, (200, 2, 4))
    hi = lo + rng.uniform(0, 8, lo.shape)
    lo[0, 0], hi[1, 1] = np.nan, np.inf
    limits = (
        JointLimit.unlimited(),
        JointLimit(lo=10.0, hi=25.0, periodic=False, prismatic=True),
        JointLimit(lo=-1.0, hi=2.5, periodic=False, prismatic=False),
        JointLimit(lo=12.0, hi=20.0, periodic=False, prismatic=True),
    )
    bounds, piece_of, has = _sub_node_bounds(lo, hi, limits)
    split = split_legs(limits)
    assert split == [2] and bounds.shape == (200, 2, 4, 2, 2)
    assert piece_of.tolist() == [[0, 0, 0, 0], [0, 0, 1, 0]]
    want_has = np.ones(has.shape, dtype=bool)
    for i, limit in enumerate(limits):
        want_lo, want_hi, want_ok = joint_pieces(lo[:, :, i], hi[:, :, i], limit)
        for c in range(2):
            k = c if i == 2 else 0
            np.testing.assert_array_equal(bounds[:, :, i, piece_of[c, i], 0], want_lo[k])
            np.testing.assert_array_equal(bounds[:, :, i, piece_of[c, i], 1], want_hi[k])
            want_has[:, :, c] &= want_ok[k]
    np.testing.assert_array_equal(has, want_has)
    assert has.any() and not has.all()


def test_sub_node_bounds_keep_one_piece_where_no_range_has_two():
    """Without a limited revolute joint, no slot reads a second piece: each leg's
    first alone is kept, the same as where a leg has two pieces."""
    from moveability.analysis.regions import _sub_node_bounds, joint_pieces

    rng = np.random.default_rng(9)
    lo = rng.uniform(-4, 16, (100, 1, 3))
    hi = lo + rng.uniform(0, 8, lo.shape)
    ends = [(4.0, 14.0), (5.0, 12.0), (0.0, 9.0)]
    strokes = tuple(JointLimit(lo=a, hi=b, periodic=False, prismatic=True) for a, b in ends)
    bounds, piece_of, has = _sub_node_bounds(lo, hi, strokes)
    assert bounds.shape == (100, 1, 3, 1, 2) and not piece_of.any()
    # with a limited revolute leg beside them: two pieces, the strokes' first the same
    revolute = JointLimit(lo=-1.0, hi=2.5, periodic=False, prismatic=False)
    wide_lo = np.concatenate([lo, lo[:, :, :1]], axis=2)
    wide_hi = np.concatenate([hi, hi[:, :, :1]], axis=2)
    two, _, _ = _sub_node_bounds(wide_lo, wide_hi, (*strokes, revolute))
    assert two.shape == (100, 1, 4, 2, 2)
    np.testing.assert_array_equal(bounds[:, :, :, 0], two[:, :, :3, 0])
    want = np.ones(has.shape[:2], dtype=bool)
    for i, limit in enumerate(strokes):
        want &= joint_pieces(lo[:, :, i], hi[:, :, i], limit)[2][0]
    np.testing.assert_array_equal(has[:, :, 0], want)
    assert has.any() and not has.all()


@pytest.mark.parametrize("seed", range(3))
def test_possible_labels_of_both_signs_are_those_found_apart(seed):
    """The possible graph's components of both signs from one pass over the pairs
    are those of each sign's edges listed one by one and joined apart (two
    postures, two slots, a posture pair)."""
    from moveability.analysis.regions import _possible_labels_both

    rng = np.random.default_rng([seed, 43])
    n, n_post, slots, n_legs = 60, 2, 2, 2
    pairs = np.unique(np.sort(rng.integers(0, n, (150, 2)), axis=1), axis=0)
    pairs = pairs[pairs[:, 0] < pairs[:, 1]].astype(np.int64)
    alive = rng.random((2, n, n_post)) < 0.7
    has = rng.random((n_post, slots, n)) < 0.8
    lo = rng.uniform(0, 1, (n_legs, 2, n, n_post))
    hi = lo + rng.uniform(0, 0.6, lo.shape)
    combo = np.array([[0, 0], [1, 0]], dtype=np.int64)
    pq = np.array([[0, 1]], dtype=np.int64)
    same_leaf = rng.random((1, n)) < 0.5
    taken = (alive[:, :, :, None] & has.transpose(2, 0, 1)[None]).reshape(2, -1)
    # node by node: each leg's two pieces, (n, P, legs, 2, 2), and each slot's piece
    bounds = np.ascontiguousarray(np.stack([lo, hi], axis=-1).transpose(2, 3, 0, 1, 4))
    labels, counts = _possible_labels_both(
        pairs, alive, np.ascontiguousarray(has.transpose(2, 0, 1)), bounds, combo, pq,
        same_leaf, taken, 1e-9, np.full((n, n_post), -1), np.zeros((n, n_post), np.int8),
    )  # fmt: skip

    def sub(i, p, c):
        return (i * n_post + p) * slots + c

    def root(parent, u):
        while parent[u] != u:
            u = parent[u]
        return u

    def meet(i, p, ci, j, q, cj):
        return all(
            lo[leg, combo[ci, leg], i, p] <= hi[leg, combo[cj, leg], j, q] + 1e-9
            and lo[leg, combo[cj, leg], j, q] <= hi[leg, combo[ci, leg], i, p] + 1e-9
            for leg in range(n_legs)
        )

    for s in range(2):
        # the sign's edges one by one: touching leaves in one posture, then the
        # posture pair within a leaf where same_leaf says so
        ends = [(i, p, j, p) for i, j in pairs for p in range(n_post)]
        ends += [(i, 0, i, 1) for i in range(n) if same_leaf[0, i]]
        parent = list(range(n * n_post * slots))
        for i, p, j, q in ends:
            if not (alive[s, i, p] and alive[s, j, q]):
                continue
            for ci in range(slots):
                for cj in range(slots):
                    if has[p, ci, i] and has[q, cj, j] and meet(i, p, ci, j, q, cj):
                        parent[root(parent, sub(i, p, ci))] = root(parent, sub(j, q, cj))
        # labels numbered by first taken sub-node
        want = np.full(len(parent), -1, dtype=np.int64)
        first: dict[int, int] = {}
        for u in np.flatnonzero(taken[s]):
            want[u] = first.setdefault(root(parent, u), len(first))
        count = len(first)
        np.testing.assert_array_equal(labels[s], want)
        assert counts[s] == count
        # neither everything nor nothing joined
        assert 1 < count < int(taken[s].sum())


@pytest.mark.parametrize(
    ("spec", "precision", "generalized", "resolve"),
    [
        ("five-bar-paper.toml", 0.1, False, True),
        ("five-bar-paper.toml", 0.1, True, True),
        ("five-bar-full-turn.toml", 0.15, False, True),
        ("five-bar-unlimited.toml", 0.15, False, True),
        ("five-bar-custom-passive.toml", 0.15, False, True),
        ("biglide.toml", 0.1, False, True),
        ("three-rpr.toml", 0.6, False, False),
        ("delta.toml", 0.3, False, True),
    ],
)
def test_possible_graph_seeded_with_the_certain_one_is_the_same(
    spec, precision, generalized, resolve
):
    """The possible graphs joined from the certain graph's components first (and
    the pairs inside one component skipped) have the components of the graphs
    joined pair by pair: every certain edge's pieces overlap."""
    from pathlib import Path

    from moveability.analysis.regions import region_graph

    path = Path(__file__).resolve().parents[2] / "examples" / spec
    r = analyze(
        str(path), precision=precision, generalized_aspects=generalized, resolve=resolve
    )
    args = (r.table, r._pairs, r.mechanism.postures)
    kwargs = {
        "cross_serial": not generalized,
        "limits": r.mechanism.limits,
        "reachable_contact": r._contact,
    }
    seeded = region_graph(*args, **kwargs)
    plain = region_graph(*args, **kwargs, seed_certain=False)
    np.testing.assert_array_equal(seeded.possible, plain.possible)
    assert seeded.n_possible == plain.n_possible
    np.testing.assert_array_equal(seeded.certain, plain.certain)
    # the seeds were used: some certain component holds more than one node
    assert (np.bincount(seeded.certain[seeded.certain >= 0]) > 1).any()
