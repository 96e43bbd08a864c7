"""Key layout: encoding, child offsets and axis arithmetic against plain integers."""

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from moveability.errors import ResolutionError
from moveability.hypertree.keys import KeyLayout

depths = st.lists(st.integers(0, 5), min_size=1, max_size=5)


@settings(deadline=None, max_examples=60)
@given(depths, st.integers(0, 2**32))
def test_encode_decode_round_trip(max_depth, seed):
    layout = KeyLayout(tuple(max_depth))
    rng = np.random.default_rng(seed)
    anchors = np.stack([rng.integers(0, 1 << d, 50) for d in max_depth], axis=1)
    np.testing.assert_array_equal(layout.decode(layout.encode(anchors)), anchors)


@settings(deadline=None, max_examples=40)
@given(depths.filter(lambda d: sum(d) <= 16))
def test_cells_are_contiguous_key_ranges(max_depth):
    """Every cell of every level covers exactly the keys of its finest cells (every
    finest cell is listed: at most 2^16 of them)."""
    layout = KeyLayout(tuple(max_depth))
    fine = np.array(list(itertools.product(*[range(1 << d) for d in max_depth])))
    fine_keys = layout.encode(fine)
    assert sorted(fine_keys.tolist()) == list(range(layout.span(0)))
    for level in range(layout.n_levels + 1):
        depth = layout.axis_depths(np.array([level]))[0]
        coarse = fine >> (np.array(max_depth) - depth)  # cell index at this level
        cell_key = layout.encode(coarse << (np.array(max_depth) - depth))
        offset = fine_keys - cell_key
        assert (offset < layout.span(level)).all()
        assert ((cell_key % layout.span(level)) == 0).all()


@settings(deadline=None, max_examples=40)
@given(depths)
def test_children_tile_their_parent(max_depth):
    layout = KeyLayout(tuple(max_depth))
    for level in range(layout.n_levels):
        key_off, anchor_off = layout.child_offsets(level)
        assert key_off.size == 1 << len(layout.split_axes[level])
        np.testing.assert_array_equal(layout.encode(anchor_off), key_off)
        np.testing.assert_array_equal(np.diff(key_off), layout.span(level + 1))


@settings(deadline=None, max_examples=60)
@given(depths, st.integers(0, 2**32), st.booleans(), st.booleans())
def test_shift_matches_integer_arithmetic(max_depth, seed, up, periodic):
    layout = KeyLayout(tuple(max_depth))
    rng = np.random.default_rng(seed)
    axis = int(rng.integers(0, len(max_depth)))
    size = 1 << max_depth[axis]
    anchors = np.stack([rng.integers(0, 1 << d, 40) for d in max_depth], axis=1)
    step = 1 << int(rng.integers(0, max_depth[axis] + 1))
    keys, inside = layout.shift(layout.encode(anchors), axis, step, 1 if up else -1, periodic)
    moved = anchors[:, axis] + (step if up else -step)
    expected_inside = (moved >= 0) & (moved < size)
    if periodic:
        assert inside.all()
    else:
        np.testing.assert_array_equal(inside, expected_inside)
    expected = anchors.copy()
    expected[:, axis] = moved % size
    ok = inside if not periodic else np.ones_like(inside)
    np.testing.assert_array_equal(layout.decode(keys)[ok], expected[ok])


def test_too_many_bits_is_a_resolution_error():
    with pytest.raises(ResolutionError, match="max_depth"):
        KeyLayout((16, 16, 16, 16))
