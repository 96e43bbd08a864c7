"""Compiled bit interleaving for :class:`moveability.hypertree.keys.KeyLayout`.

A profile of :func:`moveability.project` at 17 million leaves spent half its
time decoding keys bit by bit with whole-array numpy passes (one per key bit);
these loops do the same per key, in one pass over memory.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..compiled import kernel


@kernel
def encode(
    anchors: NDArray[np.int64], positions: NDArray[np.int64], depths: NDArray[np.int64]
) -> NDArray[np.uint64]:  # pragma: no cover - compiled
    """Keys of anchors: anchor bit ``j`` of axis ``i`` goes to key bit ``positions[i, j]``."""
    n, k = anchors.shape
    out = np.zeros(n, dtype=np.uint64)
    one = np.uint64(1)
    for r in range(n):
        key = np.uint64(0)
        for axis in range(k):
            a = np.uint64(anchors[r, axis])
            for j in range(depths[axis]):
                key |= ((a >> np.uint64(j)) & one) << np.uint64(positions[axis, j])
        out[r] = key
    return out


@kernel
def decode(
    keys: NDArray[np.uint64], positions: NDArray[np.int64], depths: NDArray[np.int64]
) -> NDArray[np.int64]:  # pragma: no cover - compiled
    """Anchors of keys (the inverse of :func:`encode`)."""
    n = keys.size
    k = depths.size
    out = np.zeros((n, k), dtype=np.int64)
    one = np.uint64(1)
    for r in range(n):
        key = keys[r]
        for axis in range(k):
            a = np.uint64(0)
            for j in range(depths[axis]):
                a |= ((key >> np.uint64(positions[axis, j])) & one) << np.uint64(j)
            out[r, axis] = np.int64(a)
    return out
