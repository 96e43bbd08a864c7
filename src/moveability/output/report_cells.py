"""The cells an HTML report embeds, so that the page answers clicks by itself.

For each cell the page needs what :meth:`~moveability.analysis.result.Analysis.locate`
and :meth:`~moveability.analysis.result.Analysis.feasible` read from a leaf:
whether the leaf is certainly in W or may meet it, and per region whether the
leaf is certainly in it or may meet it. While the listed regions are not proved
to be all, the possible components that might hold another region are kept
too, as feasibility reads them. A pose is answered from the cell holding it,
found as :func:`moveability.hypertree.measurement.locate` finds it (cells are
half-open; a pose on a shared face belongs to the upper cell).

To draw a motion the page also needs, per region, the postures of the
region's certified sheets over each cell: a sheet certified regular (the cell
is then certainly in the region), or a member of a certified fold group, where
a leg's branches meet and the posture may change. A fold cell comes with the
hub and fold point of :meth:`~moveability.mechanisms.base.Mechanism.fold_waypoints`
(mechanisms whose legs give none keep only the regular sheets: their motions
in the page keep one posture).

Sibling cells whose answers agree are merged: the answers do not change (fold
cells are never merged: each has its own hub). A tree with more than
``max_cells`` cells after that is coarsened: the deepest siblings are merged
whatever their answers, keeping what all of them certify (certainly in W, or
in a region with a posture: all of them; may meet: any of them; no fold
group). The page's answers are then never more definite than the analysis's.

The page receives the cells as the levels of the linear tree in key order (the
tree's shape follows from them), one class index per cell (a class is one
combination of answers) and the hub and fold point of each fold cell, all
compressed with zlib.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..hypertree.keys import KeyLayout
from ..hypertree.measurement import leaf_volumes, locate
from ..hypertree.status import BOUNDARY, IN, OUT
from ..hypertree.tree import HyperTree
from ..types import NO, UNKNOWN, YES, answer

if TYPE_CHECKING:
    from ..analysis.result import Analysis

__all__ = ["MAX_CELLS", "PageCells", "page_cells"]

#: cells a page holds at most before the tree is coarsened
MAX_CELLS = 400_000


@dataclass(frozen=True)
class Layout:
    """Where each answer sits in the bits of a class."""

    n_regions: int
    n_postures: int
    n_legs: int
    n_extra: int

    @property
    def per_region(self) -> int:
        """Touch, then one bit per posture certified regular, one per fold group member."""
        return 1 + 2 * self.n_postures

    def region(self, j: int) -> int:
        return 2 + j * self.per_region

    @property
    def folding(self) -> int:
        """First bit of the legs folding in the cell."""
        return 2 + self.n_regions * self.per_region

    @property
    def extra(self) -> int:
        return self.folding + self.n_legs

    @property
    def width(self) -> int:
        return self.extra + self.n_extra

    def group_bits(self) -> NDArray[np.bool_]:
        """Mask of the bits of fold group members."""
        mask = np.zeros(self.width, dtype=bool)
        for j in range(self.n_regions):
            start = self.region(j) + 1 + self.n_postures
            mask[start : start + self.n_postures] = True
        return mask


@dataclass(frozen=True)
class PageCells:
    """The cells of a page and what each certifies.

    Attributes
    ----------
    tree : HyperTree
        The cells (status IN where certainly in W, OUT where not in W, BOUNDARY
        elsewhere), over the analysis's box and key layout.
    classes : ndarray of bool, shape (n_classes, n_bits)
        Per class (see :class:`Layout`): ``[w_certain, w_possible]``; per region
        ``touch``, one bit per posture certified regular in the region, one per
        posture of a certified fold group in the region; one bit per leg
        folding in the cell; one bit per further possible component.
    cell_class : ndarray of int, shape (n_cells,)
    fold_cells : ndarray of int
        The cells holding a fold group member, in order.
    folds : ndarray of float, shape (n_fold_cells, 2, k)
        Hub and fold point of each of them.
    layout : Layout
    leaves : int
        Leaves of the analysis.
    coarse : bool
        Whether cells whose answers differ were merged.
    coarsened : float
        Share of the measure of the box where the page's answers are less
        definite than the analysis's cells (0 when only agreeing cells merged).
    """

    tree: HyperTree
    classes: NDArray[np.bool_]
    cell_class: NDArray[np.intp]
    fold_cells: NDArray[np.intp]
    folds: NDArray[np.float64]
    layout: Layout
    leaves: int
    coarse: bool = False
    coarsened: float = 0.0

    # ------------------------------------------------------------ answers
    def region_bits(self, index: NDArray[np.intp]) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        """Per cell of ``index`` and region: (certainly in, may meet), shape (m, R) each."""
        return _region_bits(self.classes[self.cell_class[index]], self.layout)

    def answers(self, points: ArrayLike) -> tuple[NDArray[np.int8], NDArray[np.int8]]:
        """What the page answers at poses already wrapped: workspace (m,) and
        regions (m, R) as codes (YES, NO, UNKNOWN)."""
        p = np.atleast_2d(np.asarray(points, dtype=np.float64))
        _, cell = locate(self.tree, p)
        inside = cell >= 0
        c = np.where(inside, cell, 0)
        bits = self.classes[self.cell_class[c]]
        ws = np.where(bits[:, 0], YES, np.where(bits[:, 1], UNKNOWN, NO)).astype(np.int8)
        sure, touch = self.region_bits(c)
        regions = np.where(sure, YES, np.where(touch, UNKNOWN, NO)).astype(np.int8)
        ws[~inside] = UNKNOWN
        regions[~inside] = UNKNOWN
        return ws, regions

    def feasible(self, points: ArrayLike) -> bool | None:
        """The page's feasibility of poses already wrapped: yes when one region
        certainly holds every pose; unknown when a pose is outside the box or a
        possible component meets every pose's cell; no otherwise."""
        p = np.atleast_2d(np.asarray(points, dtype=np.float64))
        _, regions = self.answers(p)
        if (regions == YES).all(axis=0).any():
            return True
        _, cell = locate(self.tree, p)
        if (cell < 0).any():
            return None
        _, touch = self.region_bits(cell)
        extra = self.classes[self.cell_class[cell]][:, self.layout.extra :]
        if touch.all(axis=0).any() or extra.all(axis=0).any():
            return None
        return False

    def locate(self, points: ArrayLike) -> list[dict[str, Any]]:
        """Per pose already wrapped, the page's answers: ``workspace`` and
        ``regions`` (one per region) as True, False or None."""
        ws, regions = self.answers(points)
        return [
            {"workspace": answer(int(ws[i])), "regions": [answer(int(v)) for v in regions[i]]}
            for i in range(ws.size)
        ]

    # ---------------------------------------------------------- encoding
    def payload(self) -> tuple[dict[str, Any], bytes]:
        """The cells as the page reads them: a JSON-ready description, and the
        compressed arrays (levels as uint8; class indices as uint8 or uint16;
        hubs and fold points as uint16 fractions of their cell, all little-endian)."""
        n_classes = self.classes.shape[0]
        if n_classes > 65536:
            raise ValueError(f"too many classes of cells for a page: {n_classes}")
        index_type = np.dtype("<u1" if n_classes <= 256 else "<u2")
        raw = (
            self.tree.levels.astype(np.uint8).tobytes()
            + self.cell_class.astype(index_type).tobytes()
            + _relative(self.tree, self.fold_cells, self.folds).tobytes()
        )
        lay = self.layout
        p = lay.n_postures
        classes = []
        for row in self.classes:
            regions = []
            for j in range(lay.n_regions):
                bits = row[lay.region(j) : lay.region(j) + lay.per_region]
                regions.append(
                    [
                        int(bits[0]),
                        [int(q) for q in np.flatnonzero(bits[1 : 1 + p])],
                        [int(q) for q in np.flatnonzero(bits[1 + p :])],
                    ]
                )
            classes.append(
                [
                    int(row[0]),
                    int(row[1]),
                    regions,
                    [int(e) for e in np.flatnonzero(row[lay.extra :])],
                    [int(i) for i in np.flatnonzero(row[lay.folding : lay.extra])],
                ]
            )
        meta = {
            "n_cells": len(self.tree),
            "n_folds": int(self.folds.shape[0]),
            "index_bytes": int(index_type.itemsize),
            "max_depth": list(self.tree.max_depth),
            "lo": [float(v) for v in self.tree.lo],
            "hi": [float(v) for v in self.tree.hi],
            "periodic": list(self.tree.periodic),
            # sums of the cells' anchors per axis: the page checks the tree it rebuilds
            "anchor_sums": [int(v) for v in self.tree.anchors.sum(axis=0)],
            # class: [w_certain, w_possible, per region [touch, regular postures,
            # fold group postures], further components, folding legs]
            "classes": classes,
            "leaves": self.leaves,
            "coarse": self.coarse,
            "coarsened": self.coarsened,
        }
        return meta, zlib.compress(raw, 9)


def _relative(
    tree: HyperTree, cells: NDArray[np.intp], folds: NDArray[np.float64]
) -> NDArray[np.uint16]:
    """Hubs and fold points as fractions of their cell, in 1/65535 (for drawing)."""
    if not cells.size:
        return np.zeros(0, dtype="<u2")
    leaves = tree.leaves()
    lo, hi = leaves.lo[cells][:, None, :], leaves.hi[cells][:, None, :]
    share = np.clip((folds - lo) / (hi - lo), 0.0, 1.0)
    return np.asarray(np.round(share * 65535), dtype="<u2")


def _region_bits(
    bits: NDArray[np.bool_], lay: Layout
) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    p = lay.n_postures
    per = bits[:, 2 : lay.folding].reshape(-1, lay.n_regions, lay.per_region)
    sure = np.asarray(per[:, :, 1 : 1 + p].any(axis=2), dtype=bool)
    return sure, np.asarray(per[:, :, 0], dtype=bool)


def _fold_points(result: Analysis, leaf: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Hub and fold point of a leaf holding a certified fold group."""
    t = result.table
    leaves_lo, leaves_hi = _leaf_box(result, leaf)
    legs = tuple(int(i) for i in np.flatnonzero(t.folding[leaf]))
    statuses = tuple(int(t.leg_status[leaf, i]) for i in legs)
    hub, point = result.mechanism.fold_waypoints(legs, leaves_lo, leaves_hi, statuses)
    return np.asarray(hub, dtype=np.float64), np.asarray(point, dtype=np.float64)


def _leaf_box(result: Analysis, leaf: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    tree = result.tree
    layout = tree.layout
    anchor = tree.anchors[leaf : leaf + 1]
    size = layout.cell_sizes(tree.levels[leaf : leaf + 1])
    from ..hypertree.tree import to_coordinates

    lo = to_coordinates(tree.lo, tree.hi, layout, anchor)[0]
    hi = to_coordinates(tree.lo, tree.hi, layout, anchor + size)[0]
    return lo, hi


def _leaf_bits(
    result: Analysis,
) -> tuple[NDArray[np.bool_], Layout, dict[int, NDArray[np.float64]]]:
    """The answers of each leaf of the analysis as bits (see :class:`Layout`), and
    the hub and fold point of each leaf whose fold groups the page can cross."""
    g, t = result.graph, result.table
    n_post = t.status.shape[1]
    n_legs = len(result.mechanism.legs)
    w_certain, w_possible = result.workspace_cells()
    columns = [w_certain[:, None], w_possible[:, None]]
    # fold groups the page can cross: those whose leaf gives a hub and a fold point
    group = np.asarray(t.group, dtype=bool) & (not result.generalized_aspects)
    fold_leaves = np.flatnonzero(group.any(axis=1))
    crossable = np.zeros(t.status.shape[0], dtype=bool)
    folds: dict[int, NDArray[np.float64]] = {}
    for leaf in fold_leaves:
        try:
            folds[int(leaf)] = np.stack(_fold_points(result, int(leaf)))
        except (NotImplementedError, ValueError):
            continue
        crossable[leaf] = True
    group &= crossable[:, None]
    for j, region in enumerate(result.regions):
        certain, possible = result.region_cells(j)
        in_c = g.certain == region.certain
        columns += [(certain | possible)[:, None], in_c & (t.status == IN), in_c & group]
    has_group = np.asarray(group.any(axis=1), dtype=bool)
    columns.append(np.asarray(t.folding, dtype=bool) & has_group[:, None])
    extra = []
    if not result.complete:
        # feasibility reads every possible component while a region may be missing
        listed = {(r.row, r.possible) for r in result.regions}
        for row in (0, 1):
            labels = g.possible[row]
            for u in range(int(g.n_possible[row])):
                if (row, u) not in listed:
                    extra.append((labels == u).any(axis=1)[:, None])
    bits = np.concatenate(columns + extra, axis=1).astype(bool)
    return bits, Layout(len(result.regions), n_post, n_legs, len(extra)), folds


def _class_ids(bits: NDArray[np.bool_]) -> tuple[NDArray[np.bool_], NDArray[np.intp]]:
    packed = np.packbits(bits, axis=1)
    rows, inverse = np.unique(packed, axis=0, return_inverse=True)
    classes = np.unpackbits(rows, axis=1, count=bits.shape[1]).astype(bool)
    return classes, inverse.ravel().astype(np.intp)


def _sibling_groups(
    keys: NDArray[np.uint64], levels: NDArray[np.uint8], layout: KeyLayout, level: int
) -> tuple[NDArray[np.intp], int]:
    """First cells of the complete groups of siblings at ``level`` (every child of
    one parent is a cell), and the group size."""
    size = 1 << len(layout.split_axes[level - 1])
    at = np.flatnonzero(levels == level)
    if at.size < size:
        return np.zeros(0, dtype=np.intp), size
    shift = np.uint64(layout.total_bits - layout.prefix[level - 1])
    parent = keys[at] >> shift
    # the children of a parent are consecutive in key order, the first at its key
    first = at[: at.size - size + 1]
    same = parent[: at.size - size + 1] == parent[size - 1 :]
    contiguous = at[size - 1 :] - first == size - 1
    starts = first[same & contiguous]
    starts = starts[(keys[starts] & np.uint64((1 << int(shift)) - 1)) == 0]
    return starts.astype(np.intp), size


def _merge(
    keys: NDArray[np.uint64],
    levels: NDArray[np.uint8],
    bits: NDArray[np.bool_],
    layout: KeyLayout,
    level: int,
    groups: NDArray[np.bool_],
    rule: tuple[NDArray[np.bool_], NDArray[np.bool_]] | None,
) -> tuple[NDArray[np.uint64], NDArray[np.uint8], NDArray[np.bool_]]:
    """Merge the complete sibling groups at ``level``: without ``rule``, those whose
    bits agree and hold no fold group (the bits ``groups``); with ``rule = (keep_all, clear)`` every
    group, a bit set where all members have it (``keep_all``), cleared
    (``clear``), or set where any member has it (the others)."""
    starts, size = _sibling_groups(keys, levels, layout, level)
    if not starts.size:
        return keys, levels, bits
    members = starts[:, None] + np.arange(size)[None, :]
    group_bits = bits[members]  # (groups, size, bits)
    if rule is None:
        agree = (group_bits == group_bits[:, :1]).all(axis=(1, 2))
        agree &= ~group_bits[:, 0, groups].any(axis=1)
        starts, members, group_bits = starts[agree], members[agree], group_bits[agree]
        merged = group_bits[:, 0]
    else:
        keep_all, clear = rule
        merged = np.where(keep_all, group_bits.all(axis=1), group_bits.any(axis=1))
        merged[:, clear] = False
    if not starts.size:
        return keys, levels, bits
    keep = np.ones(keys.size, dtype=bool)
    keep[members[:, 1:].ravel()] = False
    levels = levels.copy()
    levels[starts] = level - 1
    bits = bits.copy()
    bits[starts] = merged
    return keys[keep], levels[keep], bits[keep]


def page_cells(result: Analysis, max_cells: int = MAX_CELLS) -> PageCells:
    """The cells of an analysis as a report page embeds them.

    Parameters
    ----------
    result : Analysis
    max_cells : int
        Coarsen the tree (see the module notes) until it holds at most this many
        cells, or is the root.

    Examples
    --------
    >>> from moveability import analyze
    >>> from moveability.mechanisms import FiveBar
    >>> result = analyze(FiveBar(7, 8, 5, 8, 5), precision=0.5)
    >>> cells = page_cells(result)
    >>> len(cells.tree) < len(result.tree), cells.coarse
    (True, False)
    >>> poses = [[3.5, 9.0], [3.5, 9.5]]
    >>> cells.feasible(poses) == result.feasible(poses)["feasible"]
    True
    """
    tree = result.tree
    layout = tree.layout
    leaf_bits, lay, fold_points = _leaf_bits(result)
    group_mask = lay.group_bits()
    # what all members must certify: in W, in a region with a posture
    keep_all = np.zeros(lay.width, dtype=bool)
    keep_all[0] = True
    for j in range(lay.n_regions):
        keep_all[lay.region(j) + 1 : lay.region(j) + 1 + lay.n_postures] = True
    clear = group_mask.copy()
    clear[lay.folding : lay.extra] = True
    keys, levels, bits = tree.keys, tree.levels, leaf_bits

    def merge_agreeing(
        keys: NDArray[np.uint64], levels: NDArray[np.uint8], bits: NDArray[np.bool_], top: int
    ) -> tuple[NDArray[np.uint64], NDArray[np.uint8], NDArray[np.bool_]]:
        for level in range(top, 0, -1):
            keys, levels, bits = _merge(keys, levels, bits, layout, level, group_mask, None)
        return keys, levels, bits

    top = int(levels.max()) if levels.size else 0
    keys, levels, bits = merge_agreeing(keys, levels, bits, top)
    coarse = False
    while keys.size > max_cells and int(levels.max()) > 0:
        top = int(levels.max())
        keys, levels, bits = _merge(keys, levels, bits, layout, top, group_mask, (keep_all, clear))
        keys, levels, bits = merge_agreeing(keys, levels, bits, top - 1)
        coarse = True
    status = np.where(bits[:, 0], IN, np.where(bits[:, 1], BOUNDARY, OUT)).astype(np.uint8)
    cells = HyperTree(tree.lo, tree.hi, tree.max_depth, keys, levels, status, tree.periodic)
    # fold cells were never merged: each is a leaf of the analysis
    fold_cells = np.flatnonzero(bits[:, group_mask].any(axis=1))
    leaf = np.searchsorted(tree.keys, keys[fold_cells])
    folds = np.zeros((fold_cells.size, 2, tree.ndim))
    for i, index in enumerate(leaf):
        folds[i] = fold_points[int(index)]
    classes, cell_class = _class_ids(bits)
    out = PageCells(cells, classes, cell_class, fold_cells, folds, lay, len(tree))
    if not coarse:
        return out
    share = _coarsened_share(result, out, leaf_bits)
    return PageCells(cells, classes, cell_class, fold_cells, folds, lay, len(tree), True, share)


def _coarsened_share(result: Analysis, cells: PageCells, leaf_bits: NDArray[np.bool_]) -> float:
    """Share of the box's measure where a leaf's answer is more definite than the
    page's answer at the leaf's centre."""
    tree = result.tree
    leaves = tree.leaves()
    _, cell = locate(cells.tree, 0.5 * (leaves.lo + leaves.hi))
    sure, touch = cells.region_bits(cell)
    leaf_sure, leaf_touch = _region_bits(leaf_bits, cells.layout)
    lost = ((leaf_sure & ~sure) | (~leaf_touch & touch)).any(axis=1)
    volumes = leaf_volumes(tree)
    return float(volumes[lost].sum() / volumes.sum())
