"""The compiled attachment of :func:`moveability.analysis.flows.attached_nodes` and the
face sides of :func:`~moveability.analysis.flows.face_neighbours`, against plain
Python references on random small trees (merged cells of several sizes, a
periodic axis or not)."""

from __future__ import annotations

import numpy as np
import pytest

from moveability import HyperTree
from moveability.analysis.flows import _SPAN_TOL, attached_nodes, face_neighbours
from moveability.hypertree.status import BOUNDARY, IN, OUT
from moveability.hypertree.topology import adjacency


def random_tree(rng: np.random.Generator, periodic: tuple[int, ...]) -> HyperTree:
    statuses = np.array([IN, BOUNDARY, OUT], dtype=np.uint8)
    values = rng.choice(statuses, size=(8, 8), p=[0.5, 0.3, 0.2])
    values[:4, :4] = IN  # a merged block: leaves of several sizes
    return HyperTree.from_array(values, periodic=periodic)


def reference_sides(tree: HyperTree) -> list[list[tuple[int, int]]]:
    """Per direction (+x, -x, +y, -y): the pairs (a, b) of face-adjacent leaves
    (not OUT) with b across a's face, from the leaves' cells on the finest grid;
    the adjacency's pairs as given, then reversed, each in its order."""
    pairs = adjacency(tree, status=IN | BOUNDARY, connectivity=1)
    sizes = tree.layout.cell_sizes(tree.levels)
    extent = 1 << np.asarray(tree.max_depth)
    out: list[list[tuple[int, int]]] = [[] for _ in range(4)]
    for a, b in pairs.tolist() + pairs[:, ::-1].tolist():
        for axis in range(2):
            end_a = tree.anchors[a, axis] + sizes[a, axis]
            end_b = tree.anchors[b, axis] + sizes[b, axis]
            if axis in tree.periodic:
                end_a, end_b = end_a % extent[axis], end_b % extent[axis]
            if end_a == tree.anchors[b, axis]:
                out[2 * axis].append((a, b))
            if tree.anchors[a, axis] == end_b:
                out[2 * axis + 1].append((a, b))
    return out


def reference_attached(done, nodes, bits, exists, faces, neighbours, spans):
    """The least fixed point, by sweeps until nothing changes."""
    m, slots = exists.shape
    row = {(int(a), int(p)): r for r, (a, p) in enumerate(nodes.tolist())}
    attached = ~exists | done[nodes[:, 0], nodes[:, 1]][:, None]
    first = attached.copy()

    def meet(ra: int, ca: int, rb: int, cb: int) -> bool:
        sa, sb = spans[ra, ca], spans[rb, cb]
        return bool(((sa[:, 0] <= sb[:, 1] + _SPAN_TOL) & (sb[:, 0] <= sa[:, 1] + _SPAN_TOL)).all())

    def clear(r: int, c: int, f: int) -> bool:
        leaf, p = nodes[r]
        if neighbours.open[leaf, f]:
            return False
        for a, b in neighbours.pairs[f].tolist():
            if a != leaf or done[b, p]:
                continue
            if (b, p) not in row:
                return False
            rb = row[b, p]
            for cb in range(slots):
                if not first[rb, cb] and meet(r, c, rb, cb) and not attached[rb, cb]:
                    return False
        return True

    changed = True
    while changed:
        changed = False
        for r in range(m):
            for c in range(slots):
                if attached[r, c]:
                    continue
                for d in range(faces.shape[0]):
                    if not (int(bits[r, c]) >> d) & 1:
                        continue
                    if all(clear(r, c, f) for f in range(4) if (int(faces[d, r]) >> f) & 1):
                        attached[r, c] = changed = True
                        break
    state = done.copy()
    state[nodes[:, 0], nodes[:, 1]] |= attached.all(axis=1)
    return state & ~done


@pytest.mark.parametrize("seed", range(6))
def test_face_sides_and_attachment_match_references(seed: int) -> None:
    rng = np.random.default_rng(seed)
    tree = random_tree(rng, (1,) if seed % 2 else ())
    neighbours = face_neighbours(tree)
    assert [list(map(tuple, p.tolist())) for p in neighbours.pairs] == reference_sides(tree)
    n, n_post, slots, n_flows = len(tree), 2, 2, 5
    done = rng.random((n, n_post)) < 0.3
    done[tree.status == OUT] = True
    nodes = np.argwhere(~done)
    nodes = nodes[rng.random(nodes.shape[0]) < 0.9]  # some never listed: they block
    m = nodes.shape[0]
    bits = rng.integers(0, 1 << n_flows, size=(m, slots)).astype(np.uint64)
    exists = rng.random((m, slots)) < 0.8
    faces = rng.integers(0, 16, size=(n_flows, m)).astype(np.uint8)
    faces[0] = 0  # a flow that leaves through no face attaches at once
    spans = np.sort(rng.random((m, slots, 1, 2)), axis=-1)
    for s in (spans, None):
        got = attached_nodes(done, nodes, bits, exists, faces, neighbours, s)
        full = np.broadcast_to(np.array([0.0, 1.0]), (m, slots, 1, 2)) if s is None else s
        want = reference_attached(done, nodes, bits, exists, faces, neighbours, full)
        assert np.array_equal(got, want)
        assert want.any() and (~want & ~done).any()  # neither trivial


# ------------------------------------------------------------- axis flows first
@pytest.mark.parametrize(
    ("spec", "precision"),
    [
        ("five-bar-paper.toml", 0.1),
        ("five-bar-full-turn.toml", 0.1),
        ("three-rpr.toml", [1.0, 1.0, 0.2]),
    ],
)
def test_axis_flows_first_attach_exactly_what_every_flow_attaches(spec, precision):
    """The analysis tries the flows along the pose axes on every node and the others
    only on the nodes left open: its open nodes, and those of a region attached
    alone (``_held_by``), are those that every flow on every node gives."""
    from pathlib import Path

    from moveability import analyze, load_spec
    from moveability.analysis.flows import dead_or_certified, flow_conditions

    examples = Path(__file__).resolve().parents[2] / "examples"
    result = analyze(load_spec(examples / spec), precision=precision, resolve=False)
    table, leaves = result.table, result.tree.leaves()
    nodes = result._flows[0]
    # the second pass ran, on some nodes and not all
    complete = result._complete_flows
    assert 0 < int(complete.sum()) < complete.size
    bits, exists, faces = flow_conditions(result.mechanism, leaves.lo, leaves.hi, table, nodes)
    axes, _, _ = flow_conditions(
        result.mechanism, leaves.lo, leaves.hi, table, nodes, axes_only=True
    )
    # the axis flows are the first bits of every flow's
    n_axes = 2 * leaves.lo.shape[1]
    first = np.uint64((1 << n_axes) - 1)
    assert np.array_equal(axes, bits & first)
    assert not (axes & ~first).any()
    gained = 0
    for row, s in enumerate((1, -1)):
        done = dead_or_certified(table, s)
        every = attached_nodes(
            done, nodes, bits[row], exists, faces, result._neighbours, result._spans
        )
        assert np.array_equal(result.open_nodes[row], ~done & ~every)
        alone = attached_nodes(
            done, nodes, axes[row], exists, faces, result._neighbours, result._spans
        )
        assert not (alone & ~every).any()
        gained += int((every & ~alone).sum())
    # axis flows alone leave more open: the second pass is not idle
    assert gained > 0
    # the nodes completed keep their flows: equal to every flow's
    at = np.flatnonzero(complete)
    assert np.array_equal(result._flows[1][:, at], bits[:, at])
    # a saved analysis holds every flow of every node
    evidence = result.evidence()
    assert result._complete_flows.all()
    assert np.array_equal(evidence.flows[1], bits)


@pytest.mark.parametrize("n_flags", [1, 7, 8, 9, 26, 63, 64])
def test_flow_bits_against_sums_of_powers_of_two(n_flags):
    """The flows' flags packed as _node_flows packs them (one bit a flow, ORed)."""
    from moveability.analysis.flows import _bit

    rng = np.random.default_rng(n_flags)
    flags = rng.random((2, 50, 3, n_flags)) < 0.5
    weights = np.left_shift(np.uint64(1), np.arange(n_flags, dtype=np.uint64))
    expected = (flags.astype(np.uint64) * weights).sum(axis=-1, dtype=np.uint64)
    packed = np.zeros(flags.shape[:-1], dtype=np.uint64)
    for f in range(n_flags):
        packed |= _bit(flags[..., f], f)
    assert packed.dtype == np.uint64 and np.array_equal(packed, expected)


@pytest.mark.parametrize("seed", range(4))
def test_attachments_of_both_signs_are_those_found_apart(seed: int) -> None:
    """What the slots wait on, found for two signs from one pass over the face
    pairs (Attachment.both), is what each attachment finds alone, and so are
    the nodes attached."""
    from moveability.analysis.flows import Attachment

    rng = np.random.default_rng([seed, 41])
    tree = random_tree(rng, (0,) if seed % 2 else ())
    neighbours = face_neighbours(tree)
    n, n_post, slots, n_flows = len(tree), 2, 2, 5
    done = [rng.random((n, n_post)) < 0.3 for _ in range(2)]
    for d in done:
        d[tree.status == OUT] = True
    nodes = np.argwhere(~done[0] | ~done[1])
    nodes = nodes[rng.random(nodes.shape[0]) < 0.9]
    m = nodes.shape[0]
    exists = rng.random((m, slots)) < 0.8
    spans = np.sort(rng.random((m, slots, 1, 2)), axis=-1)
    bits = rng.integers(0, 1 << n_flows, size=(2, m, slots)).astype(np.uint64)
    faces = rng.integers(0, 16, size=(n_flows, m)).astype(np.uint8)
    faces[0] = 0
    together = Attachment.both(done, nodes, exists, neighbours, spans)
    for s, d in enumerate(done):
        alone = Attachment(d, nodes, exists, neighbours, spans)
        per_face, never, ptr, row, slot, face = together[s]._waiting
        want = alone._waiting
        np.testing.assert_array_equal(per_face, want[0])
        np.testing.assert_array_equal(never, want[1])
        # the pointers index the triples of both signs: each slot's run of them
        np.testing.assert_array_equal(ptr - ptr[0], want[2])
        for got, expected in zip((row, slot, face), want[3:], strict=True):
            np.testing.assert_array_equal(got[ptr[0] : ptr[-1]], expected)
        got_nodes = together[s].run(bits[s], faces)
        assert np.array_equal(got_nodes, alone.run(bits[s], faces))
        reference = reference_attached(d, nodes, bits[s], exists, faces, neighbours, spans)
        assert np.array_equal(got_nodes, reference)
    assert per_face.any() and ptr[-1] > ptr[0]  # something waits


@pytest.mark.parametrize(
    ("spec", "precision"),
    [("five-bar-custom.toml", 0.2), ("three-rrr.toml", [1.0, 1.0, 0.4])],
)
def test_without_flows_the_attachment_is_that_of_no_flow_bits(spec, precision):
    """A mechanism whose legs give no flows skips the attachment's runs: its open
    nodes are those the runs give with no flow bit (a node attaches only where
    none of its slots may hold a configuration)."""
    from pathlib import Path

    from moveability import analyze, load_spec
    from moveability.analysis.flows import dead_or_certified, supports_flows

    examples = Path(__file__).resolve().parents[2] / "examples"
    result = analyze(load_spec(examples / spec), precision=precision, resolve=False)
    assert not supports_flows(result.mechanism)
    nodes, bits, exists, faces, _ = result._flows
    assert not bits.any()
    for row, s in enumerate((1, -1)):
        done = dead_or_certified(result.table, s)
        runs = attached_nodes(
            done, nodes, bits[row], exists, faces, result._neighbours, result._spans
        )
        assert np.array_equal(result.open_nodes[row], ~done & ~runs)


@pytest.mark.parametrize(
    "spec, precision",
    [("five-bar-paper.toml", 0.05), ("five-bar-full-turn.toml", 0.1), ("biglide.toml", 0.05)],
)
def test_a_count_proved_in_the_joint_space_builds_no_flows(spec, precision, monkeypatch):
    """Where the joint-space count proves the listed regions to be all, the
    analysis builds no flows (no region can hide): every answer is that of the
    analysis that attaches the nodes all the same, and saving builds the flows."""
    from pathlib import Path

    from moveability import analyze, load_spec
    from moveability.analysis.result import Analysis

    examples = Path(__file__).resolve().parents[2] / "examples"
    spec_data = load_spec(examples / spec)
    lazy = analyze(spec_data, precision=precision)
    assert lazy.joint_count is not None and lazy.complete
    assert lazy._flows is None and not lazy.open_nodes.any()
    monkeypatch.setattr(Analysis, "_listed_are_all", lambda self: False)
    eager = analyze(spec_data, precision=precision)
    assert eager._flows is not None
    assert lazy.to_dict() == eager.to_dict()
    rng = np.random.default_rng(5)
    lo, hi = lazy.tree.lo, lazy.tree.hi
    poses = rng.uniform(lo, hi, (2000, lo.size))
    assert lazy.locate(poses) == eager.locate(poses)
    pairs = poses[:40].reshape(20, 2, lo.size)
    assert [lazy.feasible(p)["feasible"] for p in pairs] == [
        eager.feasible(p)["feasible"] for p in pairs
    ]
    # the saved evidence holds every flow of every node, as the eager one's
    lazy_flows, eager_flows = lazy.evidence().flows, eager.evidence().flows
    for a, b in zip(lazy_flows, eager_flows, strict=True):
        assert np.array_equal(a, b)
