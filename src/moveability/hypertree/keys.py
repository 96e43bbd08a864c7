"""Morton-style keys of the cells of a 2^k-tree with per-axis depths.

A tree over ``k`` axes with maximal depths ``max_depth[i]`` splits, on the way
from level ``L - 1`` to level ``L``, every axis whose maximal depth is at least
``L``. A cell of level ``L`` therefore has depth ``min(L, max_depth[i])`` on
axis ``i``. Its *anchor* is its lower corner in units of the finest cells of
each axis. The *key* interleaves the anchor bits level by level (most
significant first), so that

* every cell is one contiguous range of keys, ``[key, key + span(level))``;
* sorting leaves by key sorts them in depth-first (Z) order, and the leaf
  holding a point is found by one binary search;
* moving a key along one axis is integer arithmetic on that axis' bits
  (the "dilated integer" trick), with carries confined to the axis.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..errors import ResolutionError
from . import _bits

__all__ = ["MAX_KEY_BITS", "KeyLayout"]

#: Bits available for a key: the sum of the maximal depths may not exceed it.
MAX_KEY_BITS = 62

_U64 = np.uint64


@dataclass(frozen=True)
class KeyLayout:
    """Bit layout of the keys for given per-axis maximal depths.

    Parameters
    ----------
    max_depth : tuple of int
        Maximal depth of each axis.

    Examples
    --------
    >>> layout = KeyLayout((2, 1))
    >>> layout.n_levels, layout.total_bits
    (2, 3)
    >>> [int(k) for k in layout.encode(np.array([[3, 1], [1, 0]]))]
    [7, 1]
    >>> layout.decode(np.array([7, 1], dtype=np.uint64)).tolist()
    [[3, 1], [1, 0]]
    """

    max_depth: tuple[int, ...]
    n_levels: int = field(init=False)
    total_bits: int = field(init=False)
    #: prefix[L] = number of key bits fixed by a cell of level L.
    prefix: tuple[int, ...] = field(init=False)
    #: split_axes[L] = axes split on the way from level L to L + 1.
    split_axes: tuple[tuple[int, ...], ...] = field(init=False)
    #: positions[i][j] = key bit (from the least significant) of anchor bit j of
    #: axis i, where j counts from the least significant anchor bit.
    positions: tuple[tuple[int, ...], ...] = field(init=False)
    masks: tuple[int, ...] = field(init=False)

    def __post_init__(self) -> None:
        md = tuple(int(d) for d in self.max_depth)
        total = sum(md)
        if total > MAX_KEY_BITS:
            raise ResolutionError(
                "max_depth",
                f"per-axis depths summing to at most {MAX_KEY_BITS} bits",
                md,
            )
        n_levels = max(md, default=0)
        split_axes = tuple(
            tuple(i for i, d in enumerate(md) if d > level) for level in range(n_levels)
        )
        prefix = [0]
        for axes in split_axes:
            prefix.append(prefix[-1] + len(axes))
        positions: list[list[int]] = [[0] * d for d in md]
        for level, axes in enumerate(split_axes):
            for rank, axis in enumerate(axes):
                from_msb = prefix[level] + rank
                # anchor bit (from lsb) introduced at this level
                j = md[axis] - 1 - level
                positions[axis][j] = total - 1 - from_msb
        masks = tuple(sum(1 << p for p in pos) for pos in positions)
        object.__setattr__(self, "max_depth", md)
        object.__setattr__(self, "n_levels", n_levels)
        object.__setattr__(self, "total_bits", total)
        object.__setattr__(self, "prefix", tuple(prefix))
        object.__setattr__(self, "split_axes", split_axes)
        object.__setattr__(self, "positions", tuple(tuple(p) for p in positions))
        object.__setattr__(self, "masks", masks)

    @property
    def ndim(self) -> int:
        return len(self.max_depth)

    # ------------------------------------------------------------------ sizes
    def span(self, level: int) -> int:
        """Number of finest keys covered by a cell of ``level``."""
        return 1 << (self.total_bits - self.prefix[level])

    def spans(self, levels: NDArray[np.integer]) -> NDArray[np.uint64]:
        """:meth:`span` for an array of levels."""
        shifts = self.total_bits - np.asarray(self.prefix, dtype=np.int64)[levels]
        return np.left_shift(_U64(1), shifts.astype(_U64))

    def axis_depths(self, levels: NDArray[np.integer]) -> NDArray[np.int64]:
        """Depth ``min(level, max_depth[i])`` of each cell on each axis, shape (n, k)."""
        by_level = self._per_level(levels, 0)
        if by_level is not None:
            return by_level
        lv = np.asarray(levels, dtype=np.int64)[:, None]
        return np.minimum(lv, np.asarray(self.max_depth, dtype=np.int64)[None, :])

    def cell_sizes(self, levels: NDArray[np.integer]) -> NDArray[np.int64]:
        """Size of each cell in finest units of each axis, shape (n, k)."""
        by_level = self._per_level(levels, 1)
        if by_level is not None:
            return by_level
        md = np.asarray(self.max_depth, dtype=np.int64)[None, :]
        return np.left_shift(np.int64(1), md - self.axis_depths(levels))

    def _per_level(self, levels: NDArray[np.integer], which: int) -> NDArray[np.int64] | None:
        """:meth:`axis_depths` (``which`` 0) or :meth:`cell_sizes` (1) of the
        ``levels`` (n,) of the tree, 0 to ``n_levels``, as rows of a table of one
        row per level (one gather, not four passes over (n, k) arrays); None for
        other levels (computed as the formula says)."""
        lv = np.asarray(levels)
        if lv.ndim != 1 or lv.dtype.kind not in "ui":
            return None
        if lv.size and (int(lv.min()) < 0 or int(lv.max()) > self.n_levels):
            return None
        tables = self.__dict__.get("_level_tables")
        if tables is None:
            md = np.asarray(self.max_depth, dtype=np.int64)[None, :]
            depths = np.minimum(np.arange(self.n_levels + 1, dtype=np.int64)[:, None], md)
            tables = (depths, np.left_shift(np.int64(1), md - depths))
            # a frozen dataclass: the cache is set past its __setattr__ (not a field)
            object.__setattr__(self, "_level_tables", tables)
        return np.take(tables[which], lv, axis=0)

    # -------------------------------------------------------- encode / decode
    @property
    def position_table(self) -> NDArray[np.int64]:
        """``positions`` as a (k, max depth) array (unused entries are 0)."""
        width = max(max(self.max_depth, default=0), 1)
        table = np.zeros((self.ndim, width), dtype=np.int64)
        for axis, pos in enumerate(self.positions):
            table[axis, : len(pos)] = pos
        return table

    def encode(self, anchors: NDArray[np.integer]) -> NDArray[np.uint64]:
        """Keys of anchors given in finest units, shape (n, k) -> (n,)."""
        a = np.ascontiguousarray(anchors, dtype=np.int64).reshape(-1, self.ndim)
        return _bits.encode(a, self.position_table, np.asarray(self.max_depth, dtype=np.int64))

    def decode(self, keys: NDArray[np.uint64]) -> NDArray[np.int64]:
        """Anchors in finest units of the keys, shape (n,) -> (n, k)."""
        kk = np.ascontiguousarray(keys, dtype=_U64).ravel()
        return _bits.decode(kk, self.position_table, np.asarray(self.max_depth, dtype=np.int64))

    # ------------------------------------------------------------ children
    def child_offsets(self, level: int) -> tuple[NDArray[np.uint64], NDArray[np.int64]]:
        """Key offsets and anchor offsets of the children of a cell of ``level``.

        Returns ``(key_offsets, anchor_offsets)`` of shapes (c,) and (c, k), in
        key order, where ``c = 2 ** len(split_axes[level])``.
        """
        axes = self.split_axes[level]
        m = len(axes)
        c = np.arange(1 << m, dtype=np.int64)
        key_off = c.astype(_U64) * _U64(self.span(level + 1))
        anchor_off = np.zeros((1 << m, self.ndim), dtype=np.int64)
        for rank, axis in enumerate(axes):
            bit = (c >> (m - 1 - rank)) & 1
            anchor_off[:, axis] = bit << (self.max_depth[axis] - 1 - level)
        return key_off, anchor_off

    # ------------------------------------------------------ axis arithmetic
    def shift(
        self,
        keys: NDArray[np.uint64],
        axis: int,
        steps: NDArray[np.integer] | int,
        sign: int,
        periodic: bool,
    ) -> tuple[NDArray[np.uint64], NDArray[np.bool_]]:
        """Move keys by ``sign * steps`` finest units along ``axis``.

        ``steps`` must be powers of two no larger than the axis length. Returns
        the moved keys and a mask of those still inside the box (all True on a
        periodic axis, where coordinates wrap around).
        """
        kk = np.asarray(keys, dtype=_U64)
        depth = self.max_depth[axis]
        st = np.broadcast_to(np.asarray(steps, dtype=np.int64), kk.shape)
        if depth == 0:
            # a single cell along this axis: any move leaves the box or wraps onto itself
            return kk.copy(), np.full(kk.shape, periodic)
        mask = _U64(self.masks[axis])
        # dilate the step: its single bit goes to the axis' key position;
        # a step of the whole axis length wraps onto the same coordinate
        whole = st >= (1 << depth)
        bit_index = np.where(whole, 0, np.log2(np.maximum(st, 1)).astype(np.int64))
        pos = np.asarray(self.positions[axis], dtype=np.int64)[bit_index]
        dil = np.where(whole, _U64(0), np.left_shift(_U64(1), pos.astype(_U64)))
        x = kk & mask
        rest = kk & ~mask
        if sign > 0:
            moved = ((x | ~mask) + dil) & mask
            inside = moved > x
        else:
            moved = (x - dil) & mask
            inside = moved < x
        if periodic:
            inside = np.ones(kk.shape, dtype=bool)
        return rest | moved, inside
