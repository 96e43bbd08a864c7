"""The box the analysis subdivides: its cells at the precision are the precision
wide where the mechanism's bounds hold W, the cells it adds hold no pose of W,
and a box the user gave is kept."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from moveability import analyze, load_spec
from moveability.analysis.result import _depths, analysis_box
from moveability.hypertree.status import OUT
from moveability.limits import JointLimit
from moveability.mechanisms import Biglide, FiveBar, ThreeRRR, from_spec
from moveability.mechanisms.base import fitted_span
from region_references import five_bar, random_biglides

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

finite = st.floats(-1e6, 1e6, allow_nan=False)


@settings(max_examples=400, deadline=None)
@given(finite, st.floats(1e-9, 1e6), st.floats(1e-6, 1e3))
def test_fitted_span_holds_the_span_within_the_width(lo, span, eps):
    hi = lo + span
    if not hi > lo:
        return
    depth = _depths(np.array([lo]), np.array([hi]), np.array([eps]))[0]
    width = eps * 2.0**depth
    new_lo, new_hi = fitted_span(lo, hi, width)
    assert new_lo == lo and new_hi >= hi
    # at most the width in floats: the depth at eps stays, the cells are at most eps
    assert new_hi - new_lo <= width
    assert _depths(np.array([new_lo]), np.array([new_hi]), np.array([eps]))[0] == depth
    assert (new_hi - new_lo) / 2.0**depth <= eps


def test_fitted_span_keeps_a_span_as_wide_as_the_width():
    assert fitted_span(0.0, 8.0, 8.0) == (0.0, 8.0)
    assert fitted_span(0.0, 8.0, 4.0) == (0.0, 8.0)
    assert fitted_span(1.0, 1.0, 4.0) == (1.0, 1.0)
    assert fitted_span(0.0, 1.0, float("inf")) == (0.0, 1.0)


@pytest.mark.parametrize(
    "mechanism, precision",
    [
        (FiveBar(7, 8, 5, 8, 5), [0.035, 0.035]),
        (FiveBar(7, 8, 5, 8, 5), [0.1, 0.02]),
        (Biglide(5.0, 5.0), [0.05, 0.05]),
        (from_spec(load_spec(EXAMPLES / "delta.toml")), [0.1, 0.1, 0.05]),
    ],
)
def test_cells_at_the_precision_are_the_precision_wide(mechanism, precision):
    eps = np.asarray(precision, dtype=np.float64)
    lo, hi, depths = analysis_box(mechanism, eps)
    bounds_lo, bounds_hi = mechanism.pose_box()
    assert (lo <= bounds_lo).all() and (hi >= bounds_hi).all()
    # one depth for every axis: the tree halves them all at each level
    assert len(set(depths)) == 1
    np.testing.assert_allclose((hi - lo) / 2.0 ** np.array(depths), eps, rtol=1e-12)
    result = analyze(mechanism, precision=precision, resolve=False)
    np.testing.assert_allclose(result.cell_size, eps, rtol=1e-12)


def test_a_periodic_axis_keeps_one_turn():
    m = from_spec(load_spec(EXAMPLES / "three-rpr.toml"))
    eps = np.array([0.5, 0.5, 0.1])
    lo, hi, depths = analysis_box(m, eps)
    box_lo, box_hi = m.pose_box()
    assert lo[2] == box_lo[2] and hi[2] == box_hi[2]
    # the other axes take the deepest axis' depth (the turn is halved with them)
    assert depths[0] == depths[1] >= depths[2]
    np.testing.assert_allclose((hi[:2] - lo[:2]) / 2.0 ** depths[0], eps[:2], rtol=1e-12)


def test_the_cells_added_hold_no_pose_of_w():
    m = FiveBar(7, 8, 5, 8, 5, limits=(JointLimit(0, np.pi), JointLimit(0, np.pi)))
    result = analyze(m, precision=0.05, resolve=False)
    leaves = result.tree.leaves()
    blo, bhi = m.bounds
    beyond = (leaves.lo >= bhi).any(axis=1) | (leaves.hi <= blo).any(axis=1)
    assert beyond.any()
    assert (leaves.status[beyond] == OUT).all()


def test_a_box_the_user_gave_is_kept():
    custom = from_spec(load_spec(EXAMPLES / "five-bar-custom.toml"))
    assert not custom.bounds_hold_workspace
    lo, hi, _ = analysis_box(custom, np.array([0.05, 0.05]))
    box_lo, box_hi = custom.pose_box()
    assert (lo == box_lo).all() and (hi == box_hi).all()
    rrr = from_spec(load_spec(EXAMPLES / "three-rrr.toml"))
    assert rrr.bounds_hold_workspace  # its box is derived from the design
    given_box = ThreeRRR(rrr.base, rrr.platform, rrr.proximal, rrr.distal,
                         bounds=((-2.0, -1.0), (2.0, 3.0)))  # fmt: skip
    assert not given_box.bounds_hold_workspace
    lo, hi, _ = analysis_box(given_box, np.array([0.3, 0.3, 0.3]))
    assert (lo[:2] == [-2.0, -1.0]).all() and (hi[:2] == [2.0, 3.0]).all()


def test_widening_changes_no_definite_answer():
    """The paper's five-bar on its bounds and on the widened box: bounds overlap,
    counts and N-connectivity agree, and no pose is answered both ways."""
    m = FiveBar(7, 8, 5, 8, 5, limits=(JointLimit(0, np.pi), JointLimit(0, np.pi)))
    kept = FiveBar(7, 8, 5, 8, 5, limits=m.limits)
    kept.bounds_hold_workspace = False
    a, b = analyze(m, precision=0.05), analyze(kept, precision=0.05)
    assert a.count == b.count == (2, 2)
    assert a.n_connected is b.n_connected is False
    rng = np.random.default_rng(3)
    _no_contradiction(a, b, rng.uniform(m.bounds[0], m.bounds[1], (3000, 2)))


def _no_contradiction(a, b, poses):
    """Two certified analyses of one mechanism: counts' bounds meet, decided
    N-connectivity agrees, and no pose's answer is definite both ways."""
    (lo_a, hi_a), (lo_b, hi_b) = a.count, b.count
    assert max(lo_a, lo_b) <= min(x for x in (hi_a, hi_b, 10**9) if x is not None)
    if a.n_connected is not None and b.n_connected is not None:
        assert a.n_connected is b.n_connected
    (wa,), (wb,) = a.workspace.values(), b.workspace.values()
    assert wa[0] <= wb[1] and wb[0] <= wa[1]
    for pa, pb in zip(a.locate(poses)["points"], b.locate(poses)["points"], strict=True):
        assert None in (pa["workspace"], pb["workspace"]) or pa["workspace"] == pb["workspace"]


def _random_designs():
    """8 five-bars (lengths in [1, 8], every other with equal legs, a joint in
    three free) and 4 biglides (a third with equal legs)."""
    rng = np.random.default_rng(13)
    designs = []
    while len(designs) < 8:
        lengths = [float(v) for v in np.round(rng.uniform(1.0, 8.0, 5), 2)]
        if len(designs) % 2:
            lengths[3], lengths[4] = lengths[1], lengths[2]
        limits = []
        for _ in range(2):
            start = float(rng.uniform(-np.pi, np.pi))
            free = rng.random() < 1 / 3
            limits.append(None if free else (start, start + float(rng.uniform(0.5, 2 * np.pi))))
        try:
            designs.append(five_bar(tuple(lengths), *limits))
        except ValueError:
            continue
    return designs + random_biglides(4, 17)


@pytest.mark.parametrize("index", range(12))
def test_widened_and_kept_boxes_never_contradict(index):
    """Random five-bars (equal links, free and cut joints) and biglides, each on the
    widened box and on its bounds, at 0.1: no answer of one contradicts the other."""
    import copy

    m = _random_designs()[index]
    kept = copy.copy(m)
    kept.bounds_hold_workspace = False
    a, b = analyze(m, precision=0.1), analyze(kept, precision=0.1)
    assert (a.cell_size >= b.cell_size).all()
    rng = np.random.default_rng(index)
    poses = rng.uniform(m.bounds[0], m.bounds[1], (1500, 2))
    _no_contradiction(a, b, poses)
