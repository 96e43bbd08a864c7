"""What the resolution carries from one round to the next, against the same
computed afresh: the sheet table of a tree split twice, and the search for necks
of several possible components at once."""

from pathlib import Path

import numpy as np
import pytest

import moveability.analysis.result as result_module
from moveability import analyze
from moveability.analysis.result import (
    RESOLVE_GROWTH,
    Analysis,
    _split,
    _split_table,
    _split_tree,
    leaf_budget,
    resolve_analysis,
)
from moveability.analysis.sheets import classify_sheets
from moveability.hypertree.status import BOUNDARY
from moveability.mechanisms import FiveBar, from_spec, load_spec


def tables_equal(a, b):
    from dataclasses import fields

    for f in fields(a):
        np.testing.assert_array_equal(getattr(a, f.name), getattr(b, f.name), err_msg=f.name)


@pytest.fixture(scope="module")
def plain():
    # the pass at the precision of a resolved analysis, before its rounds (its
    # leaves may be split below the precision)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(result_module, "_resolve_rounds", lambda result, *_, **__: result)
        plain = analyze(FiveBar(7, 8, 5, 8, 5), precision=0.5)
    assert (plain.tree.levels < plain.tree.layout.n_levels).all()
    return plain


@pytest.mark.parametrize("seed", range(3))
def test_table_of_two_splits_is_that_of_its_leaves(plain, seed):
    rng = np.random.default_rng(seed)
    mech, tree = plain.mechanism, plain.tree
    mask = (tree.status == BOUNDARY) & (rng.random(len(tree)) < 0.5)
    finer, children, first = _split_tree(mech, tree, mask)
    assert (first < 0).sum() == (1 << tree.ndim) * mask.sum()
    again = (first < 0) & (rng.random(len(finer)) < 0.5)
    finest, more, second = _split_tree(mech, finer, again)
    table = _split_table(plain.table, [(first, children), (second, more)])
    # the same as the tables of each split in turn, and as the leaves classified
    _, step, _ = _split(mech, tree, plain.table, mask)
    _, steps, _ = _split(mech, finer, step, again)
    tables_equal(table, steps)
    leaves = finest.leaves()
    tables_equal(table, classify_sheets(mech, leaves.lo, leaves.hi))


def test_refined_analysis_equals_the_fresh_one(plain):
    # a round of the resolution (its table, pairs and flows carried from the
    # coarser analysis) against the analysis of the same tree from nothing
    mech, tree = plain.mechanism, plain.tree
    mask = (tree.status == BOUNDARY) & (np.random.default_rng(5).random(len(tree)) < 0.5)
    finer, children, old_index = _split_tree(mech, tree, mask)
    table = _split_table(plain.table, [(old_index, children)])
    carried = Analysis(mech, plain.precision, finer, table=table, flows_of=(plain, old_index))
    fresh = Analysis(mech, plain.precision, finer)
    tables_equal(carried.table, fresh.table)
    np.testing.assert_array_equal(carried._pairs, fresh._pairs)
    np.testing.assert_array_equal(carried.open_nodes, fresh.open_nodes)
    np.testing.assert_array_equal(carried.open_leaves(), fresh.open_leaves())
    assert carried.count == fresh.count
    assert [r.area for r in carried.regions] == [r.area for r in fresh.regions]


def test_resolution_sheds_only_its_own_analyses():
    # the 3-RPR at a coarse precision: a few rounds. resolve_analysis leaves the
    # analysis it is given whole (the rounds shed only those they build), and
    # its result is that of analyze (which lets the rounds shed its pass)
    spec = Path(__file__).parents[2] / "examples" / "three-rpr.toml"
    mech = from_spec(load_spec(spec))
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(result_module, "_resolve_rounds", lambda result, *_, **__: result)
        first = analyze(mech, 3.0)
    before = set(vars(first))
    shed: list[int] = []
    original = Analysis._shed
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(Analysis, "_shed", lambda self: shed.append(1) or original(self))
        n = len(first.tree)
        budget = min(leaf_budget(mech), n + max(int(RESOLVE_GROWTH * n), 1 << 15))
        resolved = resolve_analysis(first, max_leaves=budget)
        assert len(shed) >= 1  # rounds ran, and shed the analyses they built
        again = analyze(mech, 3.0)
    assert set(vars(first)) == before
    assert len(resolved.tree) > len(first.tree)
    np.testing.assert_array_equal(resolved.tree.keys, again.tree.keys)
    assert resolved.count == again.count
    assert [r.area for r in resolved.regions] == [r.area for r in again.regions]
    # a shed analysis keeps what a refinement takes from it alone
    first._shed()
    assert set(vars(first)) <= Analysis._CARRIED
