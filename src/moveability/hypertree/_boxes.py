"""Compiled boxes of cells: both corners of each cell in one pass.

:func:`~moveability.hypertree.tree.to_coordinates` maps finest-grid positions to
coordinates with whole-array numpy passes (a float copy of the positions, a
product, a sum, the top positions set to ``hi``); the tree's builds and its
leaves need both corners of every cell, ``anchor`` and ``anchor + size``. This
loop computes them with the same operations on the same floats (each position
converted exactly, times the step, plus ``lo``: two roundings, no fused
multiply-add), without the intermediate arrays.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..compiled import kernel


@kernel
def cell_boxes(
    anchors: NDArray[np.int64],
    levels: NDArray[np.uint8],
    depths: NDArray[np.int64],
    lo: NDArray[np.float64],
    hi: NDArray[np.float64],
    step: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:  # pragma: no cover - compiled
    """The lower and upper corners (n, k) of the cells at ``anchors`` (n, k) of
    ``levels`` (n,), or all of one level when ``levels`` holds one: along axis
    ``a`` a cell of level ``l`` spans ``2 ** (depths[a] - min(l, depths[a]))``
    finest units; position ``i`` maps to ``i * step[a] + lo[a]``, or to ``hi[a]``
    at the top ``2 ** depths[a]`` and beyond."""
    n, k = anchors.shape
    out_lo = np.empty((n, k))
    out_hi = np.empty((n, k))
    one = levels.size == 1
    for r in range(n):
        level = np.int64(levels[0] if one else levels[r])
        for a in range(k):
            depth = depths[a]
            top = np.int64(1) << depth
            start = anchors[r, a]
            end = start + (np.int64(1) << (depth - min(level, depth)))
            x = float(start) * step[a]
            out_lo[r, a] = hi[a] if start >= top else x + lo[a]
            y = float(end) * step[a]
            out_hi[r, a] = hi[a] if end >= top else y + lo[a]
    return out_lo, out_hi
