"""Reach statuses without the branch enclosures, and the contacts that use them.

``ConstraintLeg.reach(branches=False)`` skips the contraction of the roots: its
statuses and fold certificates must be those of the full reach. The analysis
asks a leg so on the common boundary of two touching leaves that both hold a
fold group (``_reachable_contact``), and only for the legs regular over neither
leaf: a leg regular over a leaf (a closed box) is regular over any part of it.
Its answers must hold every contact that the full reach of every leg on the
common boundary finds, and add none that a leg's statuses there deny.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from moveability import analyze, load_spec
from moveability.analysis.result import _reachable_contact
from moveability.mechanisms import from_spec
from moveability.mechanisms.base import FOLD_INNER, FOLD_OUTER, REGULAR
from moveability.mechanisms.constraint_leg import ConstraintLeg

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _boxes(mechanism, n, seed):
    """Random boxes over the mechanism's bounds, from a two-hundredth to a fifth
    of them; a third of them flat along one axis (a face between two cells)."""
    rng = np.random.default_rng(seed)
    lo, hi = (np.asarray(v, dtype=float) for v in mechanism.bounds)
    span = hi - lo
    width = span * rng.uniform(1 / 200, 1 / 5, (n, 1))
    start = lo + (span - width) * rng.random((n, lo.size))
    end = start + width
    flat = np.flatnonzero(rng.random(n) < 1 / 3)
    axis = rng.integers(0, lo.size, flat.size)
    end[flat, axis] = start[flat, axis]
    return start, end


@pytest.mark.parametrize(
    "name", ["five-bar-custom.toml", "delta-custom.toml", "three-rrr.toml", "prismatic"]
)
def test_status_only_reach_gives_the_full_statuses(name):
    if name == "prismatic":
        pytest.importorskip("sympy")
        from moveability.mechanisms.custom import CustomMechanism

        mechanism = CustomMechanism(PRISMATIC)
    else:
        mechanism = from_spec(load_spec(EXAMPLES / name))
    legs = [leg for leg in mechanism.legs if isinstance(leg, ConstraintLeg)]
    assert legs
    lo, hi = _boxes(mechanism, 1500, 5)
    seen = set()
    for leg in legs:
        full = leg.reach(lo, hi)
        bare = leg.reach(lo, hi, branches=False)
        assert np.array_equal(full.status, bare.status)
        assert np.array_equal(full.fold_connected, bare.fold_connected)
        for enclosure in (*bare.branches, bare.hull):
            assert np.isneginf(enclosure.lo).all() and np.isposinf(enclosure.hi).all()
        seen.update(np.unique(full.status).tolist())
    # regular boxes (the contraction was skipped there), and folds but on the
    # prismatic legs (their strokes stay off r = 0)
    assert REGULAR in seen
    assert (FOLD_OUTER in seen or FOLD_INNER in seen) == (name != "prismatic")


#: a prismatic leg given by its constraint (a 2-D point on a circle of variable radius)
PRISMATIC = {
    "mechanism": "custom",
    "pose": ["x", "y"],
    "joints": ["r1", "r2"],
    "legs": [
        {"joint": "r1", "constraint": "x**2 + y**2 - r1**2"},
        {"joint": "r2", "constraint": "(x - 4)**2 + y**2 - r2**2"},
    ],
    "limits": {"r1": [1.0, 4.0], "r2": [1.0, 4.0]},
    "bounds": {"x": [-5.0, 9.0], "y": [-5.0, 5.0]},
}


def _contact_with_every_leg_asked(mechanism, leaves, table, pairs):
    """The contacts as each leg's full reach over the common boundary finds them."""
    holds = table.group.any(axis=1)
    idx = np.flatnonzero(holds[pairs[:, 0]] & holds[pairs[:, 1]])
    out = np.zeros(pairs.shape[0], dtype=bool)
    a, b = pairs[idx, 0], pairs[idx, 1]
    lo = np.maximum(leaves.lo[a], leaves.lo[b])
    hi = np.minimum(leaves.hi[a], leaves.hi[b])
    real = (lo <= hi).all(axis=1)
    status = np.stack([leg.reach(lo, hi).status for leg in mechanism.legs], axis=1)
    regular = status == REGULAR
    folds = (status == FOLD_OUTER) | (status == FOLD_INNER)
    out[idx] = real & (regular | folds).all(axis=1) & ((~regular).sum(axis=1) <= 1)
    return out, idx, status


@pytest.mark.parametrize(
    ("name", "precision"), [("five-bar-custom.toml", 0.1), ("three-rrr.toml", 0.3)]
)
def test_contacts_hold_those_of_every_leg_asked(name, precision):
    result = analyze(load_spec(EXAMPLES / name), precision)
    mechanism, table, pairs = result.mechanism, result.table, result._pairs
    leaves = result.tree.leaves()
    asked = []
    reach = ConstraintLeg.reach

    def counted(self, lo, hi, **options):
        asked.append(lo.shape[0])
        return reach(self, lo, hi, **options)

    with pytest.MonkeyPatch.context() as m:
        m.setattr(ConstraintLeg, "reach", counted)
        found = _reachable_contact(mechanism, leaves, table, pairs)
    every, idx, status = _contact_with_every_leg_asked(mechanism, leaves, table, pairs)
    # the legs regular over a leaf are not asked on the common boundary
    assert 0 < sum(asked) < idx.size * len(mechanism.legs)
    assert every.any()  # contacts to find
    assert not (every & ~found).any()
    # a contact found beyond them: each leg the full reach did not prove regular
    # there is regular over one of the two leaves, or folds there with a certificate
    a, b = pairs[idx, 0], pairs[idx, 1]
    from_leaves = (table.leg_status[a] == REGULAR) | (table.leg_status[b] == REGULAR)
    folds = (status == FOLD_OUTER) | (status == FOLD_INNER)
    more = found[idx] & ~every[idx]
    assert ((status[more] == REGULAR) | from_leaves[more] | folds[more]).all()
    # the 3-RRR's isolation leaves some faces of leaves regular undecided: the
    # leaves prove contacts the faces' own statuses do not
    assert more.any() == (name == "three-rrr.toml")
