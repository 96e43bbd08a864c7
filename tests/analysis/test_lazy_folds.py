"""Fold certificates left out where a subdivision splits the cell anyway.

``classify_sheets(folds=False)`` lets a leg given by its constraint (the
user-defined ones, and the 3-RRR's) skip its fold certificates: the tree
statuses must not change (they decide which cells are split), the fold groups
may only shrink, and a leg's reach code may only go from a fold code to
REACH_UNKNOWN. The analysis asks so above the last level; its answers must be
those of an analysis that certifies every fold.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from moveability import analyze, load_spec
from moveability.analysis.sheets import classify_sheets
from moveability.mechanisms import from_spec
from moveability.mechanisms.base import FOLD_INNER, FOLD_OUTER, REACH_UNKNOWN
from moveability.mechanisms.constraint_leg import ConstraintLeg

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
SPECS = [
    "five-bar-custom.toml",
    "five-bar-custom-passive.toml",
    "delta-custom.toml",
    "three-rrr.toml",
]


def _boxes(mechanism, n, seed):
    """Random boxes over the mechanism's bounds, from a fortieth to a third of them."""
    rng = np.random.default_rng(seed)
    lo, hi = (np.asarray(v, dtype=float) for v in mechanism.bounds)
    span = hi - lo
    width = span * rng.uniform(1 / 40, 1 / 3, (n, 1))
    start = lo + (span - width) * rng.random((n, lo.size))
    return start, start + width


@pytest.mark.parametrize("name", SPECS)
def test_statuses_do_not_depend_on_the_fold_certificates(name):
    mechanism = from_spec(load_spec(EXAMPLES / name))
    assert any(isinstance(leg, ConstraintLeg) for leg in mechanism.legs)
    lo, hi = _boxes(mechanism, 600, 3)
    full = classify_sheets(mechanism, lo, hi)
    lazy = classify_sheets(mechanism, lo, hi, folds=False)
    assert np.array_equal(full.statuses(), lazy.statuses())
    for name_ in ("status", "sign", "exists", "within", "det_lo", "det_hi"):
        assert np.array_equal(getattr(full, name_), getattr(lazy, name_), equal_nan=True), name_
    assert not (lazy.group & ~full.group).any()
    changed = full.leg_status != lazy.leg_status
    assert np.isin(full.leg_status[changed], [FOLD_OUTER, FOLD_INNER]).all()
    assert (lazy.leg_status[changed] == REACH_UNKNOWN).all()
    # the designs do fold inside some of these boxes, so the check is not empty
    assert changed.any()


@pytest.mark.parametrize(("name", "precision"), [
    ("five-bar-custom.toml", 0.1),
    ("five-bar-custom-passive.toml", 0.1),
    ("delta-custom.toml", 0.15),
    ("three-rrr.toml", 0.5),
])  # fmt: skip
def test_analysis_answers_as_with_every_fold_certified(name, precision, monkeypatch):
    spec = load_spec(EXAMPLES / name)
    lazy = analyze(spec, precision)
    monkeypatch.setattr(ConstraintLeg, "folds_optional", False)
    full = analyze(spec, precision)
    assert lazy.to_dict() == full.to_dict()
    assert np.array_equal(lazy.tree.keys, full.tree.keys)
    assert np.array_equal(lazy.table.statuses(), full.table.statuses())
    assert np.array_equal(lazy.table.group, full.table.group)
    rng = np.random.default_rng(8)
    lo, hi = np.asarray(lazy.tree.lo), np.asarray(lazy.tree.hi)
    poses = lo + (hi - lo) * rng.random((1500, lo.size))
    assert lazy.locate(poses) == full.locate(poses)
    # the leaves of the last level are classified with their certificates in both
    last = lazy.tree.levels == lazy.tree.levels.max()
    assert np.array_equal(lazy.table.leg_status[last], full.table.leg_status[last])
