"""The compiled corners of cells (hypertree._boxes.cell_boxes through
tree.cell_corners) against to_coordinates, which the tree's builds and leaves
used before: the same floats, bit for bit, on random layouts, boxes (small and
huge spans, a periodic one), levels and anchors (the top position included)."""

from __future__ import annotations

import numpy as np
import pytest

from moveability.hypertree.keys import KeyLayout
from moveability.hypertree.tree import cell_corners, to_coordinates


def _bits(x: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(x).view(np.int64)


@pytest.mark.parametrize("seed", range(4))
def test_cell_corners_are_to_coordinates_bit_for_bit(seed):
    rng = np.random.default_rng(seed)
    for _ in range(60):
        k = int(rng.integers(1, 5))
        depths = tuple(int(d) for d in rng.integers(0, 14, k))
        layout = KeyLayout(depths)
        lo = rng.normal(size=k) * 10.0 ** rng.integers(-3, 6, k)
        hi = lo + np.abs(rng.normal(size=k)) * 10.0 ** rng.integers(-3, 6, k) + 1e-9
        if rng.random() < 0.3:
            lo[0], hi[0] = -np.pi, np.pi
        n = 500
        levels = rng.integers(0, layout.n_levels + 1, n).astype(np.uint8)
        sizes = layout.cell_sizes(levels)
        res = np.left_shift(1, np.array(depths, dtype=np.int64))
        anchors = rng.integers(0, 1 << 20, (n, k)) % res // sizes * sizes
        a, b = cell_corners(lo, hi, layout, anchors, levels)
        np.testing.assert_array_equal(_bits(a), _bits(to_coordinates(lo, hi, layout, anchors)))
        np.testing.assert_array_equal(
            _bits(b), _bits(to_coordinates(lo, hi, layout, anchors + sizes))
        )
        # the last cell ends at hi exactly
        assert (
            b[anchors + sizes == res] == np.broadcast_to(hi, b.shape)[anchors + sizes == res]
        ).all()
        # one level for all the cells
        one = np.full(1, levels[0], dtype=np.uint8)
        a, b = cell_corners(lo, hi, layout, anchors, one)
        ends = anchors + layout.cell_sizes(one)
        np.testing.assert_array_equal(_bits(a), _bits(to_coordinates(lo, hi, layout, anchors)))
        np.testing.assert_array_equal(_bits(b), _bits(to_coordinates(lo, hi, layout, ends)))


def test_cell_corners_of_no_cells():
    layout = KeyLayout((3, 2))
    a, b = cell_corners(
        np.zeros(2), np.ones(2), layout, np.zeros((0, 2), dtype=np.int64), np.zeros(0, np.uint8)
    )
    assert a.shape == b.shape == (0, 2)
