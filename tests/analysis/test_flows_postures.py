""":func:`moveability.analysis.flows.flow_conditions` takes the nodes of every posture
in one pass (each leg's methods called once per branch, on that branch's rows):
its flows, slots and exit faces are, bit for bit, those of the nodes of each
posture passed alone, whatever the order of the nodes and whatever mix of them
(postures of regular leaves only next to postures of folding ones), for the
five-bar, the biglide, the Delta, the 3-RPR (one posture) and a five-bar with a
passive limit (constraints: one pass per posture)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from moveability import analyze, load_spec
from moveability.analysis.flows import flow_conditions
from moveability.limits import JointLimit
from moveability.mechanisms.base import FOLD_INNER, FOLD_OUTER, REACH_OUT, REGULAR
from moveability.mechanisms.constraints import Constraints
from moveability.mechanisms.registry import from_spec

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
#: (spec, precision, passive limits); coarse: a few hundred nodes per posture
CASES = [
    ("five-bar-paper.toml", 0.3, None),
    ("biglide.toml", 0.3, None),
    ("delta.toml", 0.1, None),
    ("three-rpr.toml", [1.0, 1.0, 0.3], None),
    ("five-bar-paper.toml", 0.5, {"C": (-2.0, 2.0)}),
]
#: nodes kept of an analysis (a random sample of them beyond)
MAX_NODES = 3000


@pytest.fixture(
    scope="module",
    params=CASES,
    ids=[f"{spec.removesuffix('.toml')}{'-passive' if extra else ''}" for spec, _, extra in CASES],
)
def analysed(request: Any) -> tuple[Any, ...]:
    spec, precision, passive = request.param
    if passive is None:
        mechanism: Any = load_spec(EXAMPLES / spec)
    else:
        limits = {name: JointLimit(*span) for name, span in passive.items()}
        mechanism = from_spec(EXAMPLES / spec).constrained(Constraints(passive=limits))
    result = analyze(mechanism, precision=precision, resolve=False)
    leaves = result.tree.leaves()
    nodes = result._flows[0]
    if nodes.shape[0] > MAX_NODES:
        rng = np.random.default_rng(7)
        nodes = nodes[np.sort(rng.choice(nodes.shape[0], MAX_NODES, replace=False))]
    return result.mechanism, leaves.lo, leaves.hi, result.table, nodes


def each_posture_alone(
    mechanism: Any, lo: Any, hi: Any, table: Any, nodes: Any, axes_only: bool
) -> tuple[Any, Any, Any]:
    """The flows of the nodes, those of each posture computed apart."""
    parts = []
    for p in np.unique(nodes[:, 1]):
        at = np.flatnonzero(nodes[:, 1] == p)
        parts.append((at, flow_conditions(mechanism, lo, hi, table, nodes[at], axes_only)))
    m = nodes.shape[0]
    bits0, exists0, faces0 = parts[0][1]
    bits = np.zeros((2, m, bits0.shape[2]), dtype=bits0.dtype)
    exists = np.zeros((m, exists0.shape[1]), dtype=exists0.dtype)
    faces = np.zeros((faces0.shape[0], m), dtype=faces0.dtype)
    for at, (b, e, f) in parts:
        bits[:, at], exists[at], faces[:, at] = b, e, f
    return bits, exists, faces


def assert_same(got: tuple[Any, ...], want: tuple[Any, ...]) -> None:
    for g, w in zip(got, want, strict=True):
        assert g.dtype == w.dtype and g.shape == w.shape
        assert np.array_equal(g, w)


@pytest.mark.parametrize("axes_only", [True, False])
def test_one_pass_is_each_posture_alone(analysed: tuple[Any, ...], axes_only: bool) -> None:
    mechanism, lo, hi, table, nodes = analysed
    got = flow_conditions(mechanism, lo, hi, table, nodes, axes_only)
    want = each_posture_alone(mechanism, lo, hi, table, nodes, axes_only)
    assert_same(got, want)
    # some flow is found, some slot exists: the comparison is not of empty results
    assert got[1].any() and (got[0] != 0).any()
    if not axes_only:
        # the flows beyond the axes are tried: some node has one
        n_axes = 2 * lo.shape[1]
        assert (got[0] >> np.uint64(n_axes) != 0).any()
    # in any order of the nodes, each node's own
    order = np.random.default_rng(3).permutation(nodes.shape[0])
    shuffled = flow_conditions(mechanism, lo, hi, table, nodes[order], axes_only)
    assert_same(shuffled, (got[0][:, order], got[1][order], got[2][:, order]))


def test_postures_decide_apart(analysed: tuple[Any, ...]) -> None:
    """A posture given its regular leaves alone, one given only leaves where some leg
    is not regular, the others all theirs: what a posture decides from its rows
    together (a leg that may fold, a leaf's own direction that moves) stays its own."""
    mechanism, lo, hi, table, nodes = analysed
    postures = np.unique(nodes[:, 1])
    if postures.size < 2:
        pytest.skip("one posture")
    status = table.leg_status[nodes[:, 0]]
    regular = (status == REGULAR).all(axis=1)
    folds = ((status == FOLD_OUTER) | (status == FOLD_INNER)).any(axis=1)
    first, second = postures[0], postures[1]
    keep = np.ones(nodes.shape[0], dtype=bool)
    keep[nodes[:, 1] == first] = regular[nodes[:, 1] == first]
    keep[nodes[:, 1] == second] = ~regular[nodes[:, 1] == second]
    mixed = nodes[keep]
    # and, in the first, leaves where a leg cannot reach (never nodes of the
    # analysis, which are alive): a posture with no fold keeps its rates there
    out = (table.leg_status == REACH_OUT).any(axis=1) & ~(
        (table.leg_status != REGULAR) & (table.leg_status != REACH_OUT)
    ).any(axis=1)
    unreached = np.flatnonzero(out)[:50]
    mixed = np.concatenate([mixed, np.stack([unreached, np.full(unreached.size, first)], axis=1)])
    # the mix is as meant: both postures there, folds in the second, none in the first
    assert (mixed[:, 1] == first).any()
    assert folds[keep & (nodes[:, 1] == second)].any()
    assert not folds[keep & (nodes[:, 1] == first)].any()
    for axes_only in (True, False):
        got = flow_conditions(mechanism, lo, hi, table, mixed, axes_only)
        assert_same(got, each_posture_alone(mechanism, lo, hi, table, mixed, axes_only))
