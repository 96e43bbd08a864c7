"""The paper's analysis, certified: regions R_j, N-connected regions W_Nj, feasibility.

:func:`analyze` subdivides the workspace box into a 2^k-tree whose leaves are
split until every posture sheet over them is certified (see
:mod:`moveability.analysis.sheets`) or the leaf is ``precision`` wide. The regions come
from :mod:`moveability.analysis.regions`; every answer is three-valued.
"""

from __future__ import annotations

import copy
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..compiled import kernel
from ..errors import InvalidParameterError, ResolutionError
from ..hypertree.keys import MAX_KEY_BITS
from ..hypertree.measurement import locate
from ..hypertree.status import BOUNDARY, IN, OUT
from ..hypertree.topology import refined_touching, touching
from ..hypertree.tree import HyperTree, to_coordinates
from ..intervals import Interval
from ..limits import INSIDE
from ..mechanisms import Mechanism, from_spec
from ..mechanisms.base import (
    FOLD_INNER,
    FOLD_OUTER,
    REACH_OUT,
    REACH_UNKNOWN,
    REGULAR,
    leg_reach,
)
from ..spec import describe_spec
from ..types import NO, UNKNOWN, YES, answer, word
from .flows import (
    Attachment,
    dead_or_certified,
    face_neighbours,
    flow_conditions,
    slot_spans,
    supports_flows,
)
from .joint_space import (
    JointSpaceCount,
    count_in_joint_space,
    joint_condition,
    witness_configurations,
)
from .open_parts import open_parts, open_text
from .regions import RegionGraph, region_graph
from .sheets import SheetTable, classify_sheets, stack_tables
from .valid_sets import covered_by_classes, valid_set_classes

__all__ = [
    "MAX_LEAVES",
    "RESOLVE_GROWTH",
    "RESOLVE_LEVELS",
    "RESOLVE_ROUND",
    "Analysis",
    "Region",
    "analysis_box",
    "analyze",
    "available_memory",
    "count_text",
    "leaf_budget",
    "resolve_analysis",
]

Progress = Callable[[int, int, int], object]
#: levels below the precision that :func:`analyze` may refine to settle the count
RESOLVE_LEVELS = 12
#: leaves the resolution may add, as a multiple of the leaves of the plain pass
#: (at least 32768); the plain pass's cells are the precision wide (see
#: analysis_box), so the multiple spans several levels below it
RESOLVE_GROWTH = 4.0
#: leaves split in one round of the resolution at most (those with open nodes first)
RESOLVE_ROUND = 1 << 13


@dataclass(frozen=True)
class Evidence:
    """What an analysis proves beyond its tree and sheet table, kept in a saved
    analysis so that loading it repeats no interval computation.

    Attributes
    ----------
    pairs, face_pairs : (m, 2) int
        Touching leaves (not OUT): by a shared vertex, by a shared face.
    contact : (m,) bool
        Per vertex pair: their common boundary holds a pose every leg reaches.
    flows : tuple of arrays
        The flows of the nodes that need a certificate: (nodes, bits, exists,
        faces), see :func:`moveability.analysis.flows.flow_conditions`.
    """

    pairs: NDArray[np.intp]
    face_pairs: NDArray[np.intp]
    contact: NDArray[np.bool_]
    flows: tuple[NDArray[Any], ...]


@dataclass(frozen=True)
class Region:
    """A resolved region R_j and its projection W_Nj.

    Attributes
    ----------
    id : int
        Deterministic for a mechanism and precision.
    sign : int
        Sign of det A in the region.
    area : (float, float)
        Inner and outer bounds of the area (volume) of W_Nj.
    equals_workspace : bool or None
        Whether W_Nj = W; None where the precision cannot decide.
    postures : tuple of str
        Postures met in the certified part of the region.
    certain : int
        The region's component of the certain graph (``Analysis.graph.certain``).
    possible : int
        Its component among the possible components of its sign
        (``Analysis.graph.possible[row]``, see :attr:`row`).
    """

    id: int
    sign: int
    area: tuple[float, float]
    equals_workspace: bool | None
    postures: tuple[str, ...]
    certain: int
    possible: int

    @property
    def row(self) -> int:
        """Row of the region's sign in the region graph: 0 for det A > 0, 1 for det A < 0."""
        return 0 if self.sign > 0 else 1


def check_precision(precision: float | Sequence[float], k: int) -> NDArray[np.float64]:
    """Per-axis precision from one number or one per pose axis."""
    allowed = f"a positive length, or {k} of them (one per pose axis)"
    try:
        value = np.asarray(precision, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError("precision", allowed, precision) from None
    if value.ndim == 0:
        value = np.full(k, float(value))
    if value.shape != (k,) or not (np.isfinite(value).all() and (value > 0).all()):
        raise InvalidParameterError("precision", allowed, precision)
    return value


def _as_given(eps: NDArray[np.float64]) -> float | tuple[float, ...]:
    """One number when every axis has the same precision, else a tuple."""
    return float(eps[0]) if (eps == eps[0]).all() else tuple(float(v) for v in eps)


def _depths(
    lo: NDArray[np.float64], hi: NDArray[np.float64], precision: NDArray[np.float64]
) -> tuple[int, ...]:
    widths = np.asarray(hi) - np.asarray(lo)
    depths = tuple(
        int(max(0, np.ceil(np.log2(w / e)))) for w, e in zip(widths, precision, strict=True)
    )
    if sum(depths) > MAX_KEY_BITS:
        raise ResolutionError(
            "precision",
            f"a precision coarser than about {(hi - lo).max() / 2.0 ** (62 / len(lo)):.3g}",
            _as_given(np.asarray(precision, dtype=np.float64)),
        )
    return depths


def analysis_box(
    mechanism: Mechanism, precision: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64], tuple[int, ...]]:
    """The box :func:`analyze` subdivides at ``precision`` (one width per pose
    axis), and the depth of each axis there.

    The tree halves every axis at each level down to the deepest axis' depth
    ``d``; where the mechanism's bounds hold its workspace, each axis that does
    not turn is widened to its precision times ``2**d`` (see
    :meth:`~moveability.mechanisms.base.Mechanism.pose_box`), so that the cells
    at the precision are the precision wide, as a grid of that spacing is, not
    down to half of it. The cells added hold no pose of W.

    Examples
    --------
    >>> import numpy as np
    >>> from moveability.mechanisms import FiveBar
    >>> lo, hi, depths = analysis_box(FiveBar(7, 8, 5, 8, 5), np.array([0.5, 0.25]))
    >>> depths, [float(v) for v in (hi - lo) / 2.0 ** np.array(depths)]
    ((7, 7), [0.5, 0.25])
    """
    lo, hi = mechanism.pose_box()
    depths = _depths(lo, hi, precision)  # refuses a precision the keys cannot hold
    level = max(depths)
    if level * len(depths) <= MAX_KEY_BITS:
        lo, hi = mechanism.pose_box(precision * 2.0**level)
        depths = _depths(lo, hi, precision)
    return lo, hi, depths


def analyze(
    mechanism: Mechanism | Mapping[str, Any] | str | os.PathLike[str],
    precision: float | Sequence[float] = 0.1,
    *,
    max_leaves: int | None = None,
    progress: Progress | None = None,
    generalized_aspects: bool = False,
    resolve: bool = True,
    resolve_levels: int = RESOLVE_LEVELS,
    resolve_growth: float = RESOLVE_GROWTH,
) -> Analysis:
    """Regions of feasible point-to-point motions of a mechanism.

    Parameters
    ----------
    mechanism : Mechanism, mapping or path
        A mechanism, or a spec (see :func:`moveability.mechanisms.registry.load_spec`).
    precision : float or sequence of float
        Undecided leaves are refined until at most this wide (pose units: lengths
        and radians); one number, or one per pose axis. The built-in mechanisms'
        cells at the precision are this wide (see :func:`analysis_box`).
    max_leaves : int, optional
        Fail with :class:`~moveability.ResolutionError` rather than hold more
        leaves; by default :func:`leaf_budget` (what the memory available holds).
    progress : callable, optional
        Called as ``progress(level, n_split, n_leaves)`` while the tree grows;
        if it has a ``phase`` method, that is called as each phase begins
        (see :func:`phase`).
    generalized_aspects : bool, optional
        Forbid serial singularities as well (det A != 0 and det B != 0): the
        regions are then the generalized aspects, in which the posture never
        changes.
    resolve : bool, optional
        After the pass at the precision, refine below it, one level a round,
        only the leaves that keep the count of regions or N-connectivity open
        (see :func:`resolve_analysis`); the default. For the five-bar, the
        biglide and the Delta the count of regions is also proved in the joint
        space (see :mod:`moveability.analysis.joint_space`), which often ends the refinement
        early. False keeps the plain pass. Mechanisms whose legs give no
        rates (see :func:`moveability.analysis.flows.supports_flows`) keep the plain
        pass.
    resolve_levels : int, optional
        Levels below the precision that the resolution may reach.
    resolve_growth : float, optional
        Leaves the resolution may add, as a multiple of the leaves of the plain
        pass (at least 32768), within ``max_leaves``; it splits at most
        ``RESOLVE_ROUND`` leaves a round. With ``resolve_levels``, a
        deterministic budget.

    Examples
    --------
    >>> from moveability import analyze
    >>> from moveability.mechanisms import FiveBar
    >>> result = analyze(FiveBar(7, 8, 5, 8, 5), precision=0.5)
    >>> len(result.regions), result.n_connected
    (2, False)
    """
    if not isinstance(mechanism, Mechanism):
        mechanism = from_spec(mechanism)
    eps = check_precision(precision, len(mechanism.pose_names))
    if max_leaves is None:
        max_leaves = leaf_budget(mechanism)
    lo, hi, depths = analysis_box(mechanism, eps)
    if isinstance(resolve_levels, bool) or not isinstance(resolve_levels, int | np.integer):
        raise InvalidParameterError("resolve_levels", "a whole number >= 0", resolve_levels)
    if resolve_levels < 0:
        raise InvalidParameterError("resolve_levels", "a whole number >= 0", resolve_levels)
    if not (np.isfinite(resolve_growth) and resolve_growth >= 0):
        raise InvalidParameterError("resolve_growth", "a number >= 0", resolve_growth)
    # the levels below the precision must fit in the keys too
    # two dyads, the Delta: the count is also proved in the joint space (see
    # joint_space; with constraints, one branch at a time: joint_branches)
    in_joints = not generalized_aspects and joint_condition(mechanism) is not None
    # without flows (legs given by constraints alone) no refinement can prove a
    # bound, but the joint space's count may, and its regions are listed then
    resolve = bool(resolve) and (supports_flows(mechanism) or in_joints)
    extra = min(int(resolve_levels), (MAX_KEY_BITS - sum(depths)) // len(depths)) if resolve else 0

    # the sheet tables of the cells that may end as leaves: the analysis reuses
    # them rather than classifying the final leaves again
    kept: list[tuple[NDArray[np.float64], NDArray[np.float64], SheetTable]] = []
    # legs whose fold certificates can be left out where a cell is split anyway
    lazy_folds = any(getattr(leg, "folds_optional", False) for leg in mechanism.legs)

    def classify(cell_lo: NDArray[np.float64], cell_hi: NDArray[np.float64]) -> NDArray[np.uint8]:
        # the build classifies one level a call, from level 0. Above the last
        # level the undecided cells are split, and the fold certificates decide
        # no status: they are left out there. A cell that stays there is IN (no
        # leg folds) or OUT (its fold groups are empty whatever its legs' codes)
        folds = not lazy_folds or len(kept) >= n_levels
        table = classify_sheets(mechanism, cell_lo, cell_hi, folds=folds)
        statuses = table.statuses()
        if kept:
            # a later level came: the undecided cells of the last one were split
            last_lo, last_hi, last = kept[-1]
            stay = np.flatnonzero(last.statuses() != BOUNDARY)
            kept[-1] = (last_lo[stay], last_hi[stay], last.take(stay))
        kept.append((cell_lo, cell_hi, table))
        return statuses

    n_levels = max(depths)

    # undecided cells follow the boundaries of the sets, of dimension k - 1: their
    # number grows about 2^(k - 1) times a level
    growth = 2.0 ** (len(depths) - 1)

    def watch(level: int, n_split: int, n_leaves: int) -> None:
        # a precision that cannot fit is refused early, not after filling memory
        remaining = n_levels - level - 1
        if remaining > 0:
            # the children of the cells split, then their growth each level after
            per_child = remaining if growth == 1 else (growth**remaining - 1) / (growth - 1)
            coming = n_split * 2.0 ** len(depths) * per_child
            if n_leaves + coming > 4 * max_leaves:
                raise ResolutionError("max_depth", "a tree that fits", n_split)
        if progress is not None:
            progress(level, n_split, n_leaves)

    phase(progress, "refining", levels=n_levels)
    # no merging: a parent is not certified by its children's certificates
    try:
        tree = HyperTree.build(
            lo,
            hi,
            classify,
            max_depth=[d + extra for d in depths],
            periodic=mechanism.periodic_axes,
            max_leaves=max_leaves,
            progress=watch,
            merge=False,
            stop_level=n_levels,
        )
    except ResolutionError:
        raise ResolutionError(
            "precision",
            f"a coarser precision: one whose tree fits in memory "
            f"(at most max_leaves={max_leaves} leaves)",
            precision,
        ) from None
    joint = None
    # with constraints the joint space's count costs more than the workspace's
    # often does: it is sought only where the workspace leaves the count open
    later = resolve and in_joints and not mechanism.restrictions.empty
    if resolve and in_joints and not later:
        phase(progress, "counting the regions in the joint space")
        joint = count_in_joint_space(mechanism)
    phase(progress, "joining the regions")
    result = Analysis(
        mechanism,
        _as_given(eps),
        tree,
        generalized_aspects=generalized_aspects,
        table=_leaf_table(mechanism, tree, kept),
        joint_count=joint,
    )
    budget = min(max_leaves, len(tree) + max(int(resolve_growth * len(tree)), 1 << 15))
    if extra:
        # the pass's analysis is no one else's: the rounds may shed it
        result = _resolve_rounds(result, budget, progress, owned=True)
    if later and result.count[0] != result.count[1]:
        phase(progress, "counting the regions in the joint space")
        joint = count_in_joint_space(mechanism)
        if joint is not None:
            result = _with_joint_count(result, joint)
            if extra:
                result = _resolve_rounds(result, budget, progress, owned=True)
    return result


def _with_joint_count(result: Analysis, joint: JointSpaceCount) -> Analysis:
    """The analysis ``result`` with the joint-space count ``joint``: the same tree,
    table and flows (taken from ``result``, each leaf its own)."""
    return Analysis(
        result.mechanism,
        result.precision,
        result.tree,
        generalized_aspects=result.generalized_aspects,
        table=result.table,
        flows_of=(result, np.arange(len(result.tree), dtype=np.intp)),
        joint_count=joint,
    )


#: the most leaves an analysis holds, whatever the memory
MAX_LEAVES = 1 << 23


def leaf_budget(mechanism: Mechanism, available: int | None = None) -> int:
    """The leaves an analysis of ``mechanism`` may hold: what three quarters of the
    memory ``available`` (bytes; by default what the system reports available)
    hold at ``(1 + P)`` KiB a leaf for P postures, within ``MAX_LEAVES`` (and
    at least 2^16). Measured peaks: about 1.9 KiB a leaf for the 3-RPR (one
    posture), 2.4 to 4 KiB for five-bars (four), 7.4 KiB for the Delta (eight).

    Examples
    --------
    >>> from moveability.mechanisms import FiveBar
    >>> leaf_budget(FiveBar(7, 8, 5, 8, 5), available=5 * 2**30)
    786432
    """
    if available is None:
        available = available_memory()
    if available is None:
        return MAX_LEAVES
    per_leaf = 1024 * (1 + int(mechanism.postures.shape[0]))
    return int(min(MAX_LEAVES, max(1 << 16, 0.75 * available // per_leaf)))


def available_memory() -> int | None:
    """Bytes of memory the system reports available (Linux: ``MemAvailable``);
    None where it says nothing."""
    try:
        with open("/proc/meminfo", encoding="ascii") as info:
            for line in info:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


def phase(progress: Progress | None, name: str, **info: int) -> None:
    """Tell a progress display that a phase of the analysis begins, if it has a
    ``phase(name, **info)`` method (a plain callable is only called per level).

    The phases are ``refining`` (``levels``: the levels of the precision),
    ``counting the regions in the joint space``, ``joining the regions``, and
    ``resolving`` (``round``, and ``levels``: the deepest level allowed).
    """
    announce = getattr(progress, "phase", None)
    if callable(announce):
        announce(name, **info)


def resolve_analysis(
    result: Analysis, *, max_leaves: int = MAX_LEAVES, progress: Progress | None = None
) -> Analysis:
    """Refine, below the precision, the leaves that keep the count of regions open.

    Each round splits the leaves of :meth:`Analysis.open_leaves` that are above
    the tree's maximal level (twice, with two pose axes, those where a region
    may hide), classifies
    only the new leaves and builds the analysis again, until nothing is open,
    the leaves reach the maximal level, or the tree would hold more than
    ``max_leaves`` leaves. The leaves split follow the open part; each round
    still rebuilds the graphs of the whole tree.
    """
    return _resolve_rounds(result, max_leaves, progress, owned=False)


def _resolve_rounds(
    result: Analysis, max_leaves: int, progress: Progress | None, *, owned: bool
) -> Analysis:
    """:func:`resolve_analysis`; ``owned`` says that ``result`` is no one else's: an
    analysis that a round refines is then shed (see :meth:`Analysis._shed`) as
    soon as the next one's table is built, which lowers the peak of memory (the
    analyses the rounds build are always shed)."""
    mechanism = result.mechanism
    rounds = 0
    while True:
        tree = result.tree
        below = tree.levels < tree.layout.n_levels
        hiding = result.hiding_leaves() & below
        mask = result.open_leaves() & below
        if int(mask.sum()) > RESOLVE_ROUND:
            # the leaves where a region may hide first, then the necks, coarsest first
            extra = np.flatnonzero(mask & ~hiding)
            extra = extra[np.argsort(tree.levels[extra], kind="stable")]
            room = max(RESOLVE_ROUND - int(hiding.sum()), 0)
            mask = hiding.copy()
            mask[extra[:room]] = True
        # what the budget leaves room for: the first leaves of the order above
        room = (max_leaves - len(tree)) // ((1 << tree.ndim) - 1)
        if int(mask.sum()) > room:
            chosen = np.concatenate(
                [np.flatnonzero(mask & hiding), np.flatnonzero(mask & ~hiding)]
            )[: max(room, 0)]
            mask = np.zeros(len(tree), dtype=bool)
            mask[chosen] = True
        n_split = int(mask.sum())
        if not n_split:
            return result
        rounds += 1
        phase(progress, "resolving", round=rounds, levels=int(tree.layout.n_levels))
        finer, children, old_index = _split_tree(mechanism, tree, mask)
        splits = [(old_index, children)]
        # with two pose axes a leaf where a region may hide is split twice: such
        # leaves tend to stay open for several levels, and each round costs the
        # whole tree. With three, twice makes 64 leaves of one: on the 3-RPR at
        # 1/64 the first round then spent the budget (6,390 leaves to 400,000)
        # where single splits decide two designs more in as much time
        # a child's parent is the leaf of the coarser tree whose key range holds its key
        child = np.flatnonzero(old_index < 0)
        parent = np.searchsorted(tree.keys, finer.keys[child], side="right") - 1
        again = np.zeros(len(finer), dtype=bool)
        again[child] = (mask & hiding)[parent]
        again &= (finer.levels < finer.layout.n_levels) & (tree.ndim <= 2)
        room = (max_leaves - len(finer)) // ((1 << tree.ndim) - 1)
        if 0 < int(again.sum()) <= room:
            # the table of the finer tree once, from the coarser one's and both
            # splits' children
            finer, children, second = _split_tree(mechanism, finer, again)
            splits.append((second, children))
            old_index = np.where(second >= 0, old_index[np.maximum(second, 0)], -1)
        table = _split_table(result.table, splits)
        if owned:
            result._shed()
        if progress is not None:
            progress(int(finer.levels.max()), n_split, len(finer))
        result = Analysis(
            mechanism,
            result.precision,
            finer,
            generalized_aspects=result.generalized_aspects,
            table=table,
            flows_of=(result, old_index),
            joint_count=result.joint_count,
        )
        owned = True


def _leaf_table(
    mechanism: Mechanism,
    tree: HyperTree,
    kept: list[tuple[NDArray[np.float64], NDArray[np.float64], SheetTable]],
) -> SheetTable:
    """The sheet table of the tree's leaves, from the tables of the cells classified
    while it was built (a cell is a leaf when its box is one). A leaf no table
    holds (none, unless the build changes) is classified here."""
    leaves = tree.leaves()
    n = len(tree)
    source = np.full(n, -1, dtype=np.intp)
    tables = [table for _, _, table in kept]
    offsets = np.cumsum([0] + [len(t.status) for t in tables])
    # the build classifies level c's cells in key order (children follow their
    # parents' order): they are the leaves of level c, in order, when the boxes
    # agree; located one by one otherwise
    by_level = np.argsort(tree.levels, kind="stable")
    starts = np.searchsorted(tree.levels[by_level], np.arange(len(kept) + 1))
    for c, (cell_lo, cell_hi, _) in enumerate(kept):
        if not len(cell_lo):
            continue
        at = by_level[starts[c] : starts[c + 1]]
        if at.size == len(cell_lo) and (
            np.array_equal(leaves.lo[at], cell_lo) and np.array_equal(leaves.hi[at], cell_hi)
        ):
            source[at] = offsets[c] + np.arange(at.size)
            continue
        _, leaf = locate(tree, 0.5 * (cell_lo + cell_hi))
        ok = leaf >= 0
        ok[ok] = (leaves.lo[leaf[ok]] == cell_lo[ok]).all(axis=1) & (
            leaves.hi[leaf[ok]] == cell_hi[ok]
        ).all(axis=1)
        source[leaf[ok]] = offsets[c] + np.flatnonzero(ok)
    missing = np.flatnonzero(source < 0)
    if missing.size:
        tables.append(classify_sheets(mechanism, leaves.lo[missing], leaves.hi[missing]))
        source[missing] = offsets[-1] + np.arange(missing.size)
    return stack_tables(tables).take(source)


class _Corners:
    """The lower (or ``upper``) corners of a tree's leaves, shape (n, k), computed
    for the rows indexed alone: each row as :meth:`HyperTree.leaves` computes it
    (the same expression on the same integers, so the same floats). A refined
    analysis needs those of its new nodes alone."""

    def __init__(self, tree: HyperTree, upper: bool) -> None:
        self._tree, self._upper = tree, upper
        self.shape = (len(tree), tree.ndim)

    def __getitem__(self, rows: Any) -> NDArray[np.float64]:
        tree = self._tree
        ints = tree.anchors[rows]
        if self._upper:
            ints = ints + tree.layout.cell_sizes(tree.levels[rows])
        return to_coordinates(tree.lo, tree.hi, tree.layout, ints)


class _Boxes:
    """The leaves' boxes, ``lo`` and ``hi`` (see :class:`_Corners`), computed for
    the leaves asked for alone."""

    def __init__(self, tree: HyperTree) -> None:
        self.lo = _Corners(tree, False)
        self.hi = _Corners(tree, True)


def _leaf_volumes(tree: HyperTree) -> NDArray[np.float64]:
    """:func:`~moveability.hypertree.measurement.leaf_volumes`, computed once per
    level: a leaf's widths, and so its volume, are those of its level (the same
    expression on the same numbers, so the same floats)."""
    levels = np.arange(int(tree.levels.max(initial=0)) + 1)
    widths = (tree.hi - tree.lo)[None, :] / np.exp2(tree.layout.axis_depths(levels))
    per_level: NDArray[np.float64] = np.prod(widths, axis=1)
    return np.asarray(per_level[tree.levels], dtype=np.float64)


def _touching(
    tree: HyperTree, refines: tuple[Analysis, NDArray[np.intp]] | None
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Pairs of touching leaves that are not OUT, by a shared vertex and by a shared
    face; for a refinement (the coarser analysis and each leaf's old index), from
    the coarser analysis's pairs."""
    if refines is None:
        return touching(tree, status=IN | BOUNDARY)
    old, old_index = refines
    return refined_touching(
        tree, old.tree, old._pairs, old._face_pairs, old_index, status=IN | BOUNDARY
    )


def _split(
    mechanism: Mechanism, tree: HyperTree, table: SheetTable, mask: NDArray[np.bool_]
) -> tuple[HyperTree, SheetTable, NDArray[np.intp]]:
    """Split the leaves of ``mask`` once: the finer tree, its sheet table (kept
    leaves keep their rows, children are classified) and each leaf's index in
    ``tree`` (-1 for children)."""
    finer, children, old_index = _split_tree(mechanism, tree, mask)
    return finer, _split_table(table, [(old_index, children)]), old_index


def _split_tree(
    mechanism: Mechanism, tree: HyperTree, mask: NDArray[np.bool_]
) -> tuple[HyperTree, SheetTable | None, NDArray[np.intp]]:
    """:func:`_split` without the finer tree's table: the finer tree, the sheet
    table of its children (in their order among its leaves) and each leaf's
    index in ``tree`` (-1 for children)."""
    children: list[SheetTable] = []

    def classify(
        lo: NDArray[np.float64], hi: NDArray[np.float64], found: list[SheetTable] = children
    ) -> NDArray[np.uint8]:
        found.append(classify_sheets(mechanism, lo, hi))
        return found[-1].statuses()

    # leaves at the maximal level stay as they are
    mask = mask & (tree.levels < tree.layout.n_levels)
    finer = tree.refine(mask, classify)
    # kept leaves stay in order among the new ones; children come in key order (a
    # child's key lies in its parent's range, apart from every kept leaf's)
    # both key lists are sorted: a binary search finds the kept leaves
    kept_keys = tree.keys[~mask]
    if kept_keys.size:
        at = np.minimum(np.searchsorted(kept_keys, finer.keys), kept_keys.size - 1)
        is_child = kept_keys[at] != finer.keys
    else:
        is_child = np.ones(len(finer), dtype=bool)
    old_index = np.full(len(finer), -1, dtype=np.intp)
    old_index[~is_child] = np.flatnonzero(~mask)
    # no children when no leaf could be split (all at the maximal level)
    return finer, (children[0] if children else None), old_index


def _split_table(
    table: SheetTable, splits: list[tuple[NDArray[np.intp], SheetTable | None]]
) -> SheetTable:
    """The sheet table of a tree split in turn by each of ``splits`` (each leaf's
    index in the tree before that split, -1 for a child, and the children's
    table, as :func:`_split_tree` gives them) from ``table``, the table of the
    first tree: the rows of the leaves kept from it and of the children of each
    split, gathered once."""
    # per leaf of the last tree: its row in `table` (-1 for a child), and, for a
    # child, its split and its row in that split's children
    row = np.arange(len(table.status), dtype=np.intp)
    split = np.full(row.size, -1, dtype=np.intp)
    child_row = np.full(row.size, -1, dtype=np.intp)
    for s, (old_index, _) in enumerate(splits):
        child = old_index < 0
        at = np.maximum(old_index, 0)
        rank = np.cumsum(child) - 1
        row = np.where(child, -1, row[at])
        split = np.where(child, s, split[at])
        child_row = np.where(child, rank, child_row[at])
    # one gather from the old rows (any row in the children's places), then the
    # children's rows written over theirs: no copy of the old table stacked
    out = table.take(np.maximum(row, 0))
    for s, (_, children) in enumerate(splits):
        at = np.flatnonzero(split == s)
        if children is None or not at.size:
            continue
        for f in fields(SheetTable):
            getattr(out, f.name)[at] = getattr(children, f.name)[child_row[at]]
    return out


def _reachable_contact(
    mechanism: Mechanism, leaves: Any, table: SheetTable, pairs: NDArray[np.intp]
) -> NDArray[np.bool_]:
    """Per pair of touching leaves that both hold a certified fold group: whether
    their common boundary holds a pose that every leg reaches (every leg regular
    there but at most one, which certainly holds reachable poses there).

    A leg regular over either leaf (a closed box) is regular over the common
    boundary, a part of it: only the other legs are asked, for their statuses
    alone where they can give them (:func:`~moveability.mechanisms.base.leg_reach`)."""
    out = np.zeros(pairs.shape[0], dtype=bool)
    # per leaf first: one gather of a flag per pair end, not of a row
    holds: NDArray[np.bool_] = np.asarray(table.group.any(axis=1), dtype=bool)
    both = holds[pairs[:, 0]] & holds[pairs[:, 1]]
    idx = np.flatnonzero(both)
    if not idx.size:
        return out
    a, b = pairs[idx, 0], pairs[idx, 1]
    lo = np.maximum(leaves.lo[a], leaves.lo[b])
    hi = np.minimum(leaves.hi[a], leaves.hi[b])
    # leaves touching across a periodic seam have no common box in coordinates
    real = (lo <= hi).all(axis=1)
    status = np.where(
        (table.leg_status[a] == REGULAR) | (table.leg_status[b] == REGULAR),
        REGULAR,
        REACH_UNKNOWN,
    ).astype(np.uint8)
    for i, leg in enumerate(mechanism.legs):
        ask = np.flatnonzero(real & (status[:, i] != REGULAR))
        if ask.size:
            status[ask, i] = leg_reach(leg, lo[ask], hi[ask], branches=False).status
    regular = status == REGULAR
    folds = (status == FOLD_OUTER) | (status == FOLD_INNER)
    out[idx] = real & (regular | folds).all(axis=1) & ((~regular).sum(axis=1) <= 1)
    return out


@kernel
def _walk_back(
    out: NDArray[np.bool_],
    starts: NDArray[np.intp],
    source: NDArray[np.int64],
    pred: NDArray[np.int64],
) -> None:  # pragma: no cover - compiled
    """Mark each start and its predecessors up to a leaf of a part (included)."""
    n = out.size
    for t in range(starts.size):
        i = starts[t]
        while not out[i]:
            out[i] = True
            if source[i] >= 0:
                break
            i = pred[i]
            if i < 0 or i >= n:
                break


@kernel
def _chain_search(
    pairs: NDArray[np.intp],
    group: NDArray[np.int64],
    seeds: NDArray[np.intp],
    source: NDArray[np.int64],
) -> tuple[
    NDArray[np.float64],
    NDArray[np.int64],
    NDArray[np.int64],
    NDArray[np.int64],
    NDArray[np.int64],
]:  # pragma: no cover - compiled
    """The breadth-first search of :func:`_necks`, from every seed at once, along
    the pairs whose two leaves are in one search group (``group``: -1 for a leaf
    searched by none; the leaves of a group are *through*). Groups are searched
    apart: no chain passes from one to another.

    Returns each leaf's hops from the nearest seed (inf where none reaches it),
    its predecessor on a shortest chain (-1 for a seed or an unreached leaf),
    its label (the part, ``source``, of the seed its chain starts from; -1 where
    unreached) and the two columns of the pairs searched whose leaves have
    two labels: where chains from two parts meet (those of two seeds first,
    then the others, each in the order of ``pairs``). A leaf's chain goes on
    through its neighbour one step nearer with the largest index, whose label
    it takes. Every seed is reached at once (0 hops, its own part): a pair of
    two seeds is no step of a chain, and is left out of the search."""
    n = group.size
    degree = np.zeros(n + 1, dtype=np.int64)
    # two passes over the pairs of two leaves of one group (a test of each pair
    # costs less than keeping them): each leaf's count of them, then the lists
    m = 0
    n_seed_meets = 0
    for t in range(pairs.shape[0]):
        i, j = pairs[t, 0], pairs[t, 1]
        if group[i] < 0 or group[i] != group[j]:
            continue
        if source[i] >= 0 and source[j] >= 0:
            if source[i] != source[j]:
                n_seed_meets += 1
        else:
            degree[i + 1] += 1
            degree[j + 1] += 1
            m += 1
    for i in range(n):
        degree[i + 1] += degree[i]
    fill = degree[:-1].copy()
    neighbour = np.empty(2 * m, dtype=np.int64)
    # the pairs of two seeds of two parts first (where parts touch), then the
    # pairs searched
    a = np.empty(n_seed_meets + m, dtype=np.int64)
    b = np.empty(n_seed_meets + m, dtype=np.int64)
    s = 0
    k = n_seed_meets
    for t in range(pairs.shape[0]):
        i, j = pairs[t, 0], pairs[t, 1]
        if group[i] < 0 or group[i] != group[j]:
            continue
        if source[i] >= 0 and source[j] >= 0:
            if source[i] != source[j]:
                a[s], b[s] = i, j
                s += 1
            continue
        a[k], b[k] = i, j
        k += 1
        neighbour[fill[i]] = j
        fill[i] += 1
        neighbour[fill[j]] = i
        fill[j] += 1
    hops = np.full(n, np.inf)
    pred = np.full(n, -1, dtype=np.int64)
    label = np.full(n, -1, dtype=np.int64)
    queue = np.empty(n, dtype=np.int64)
    tail = 0
    for t in range(seeds.size):
        i = seeds[t]
        if hops[i] == np.inf:
            hops[i] = 0.0
            label[i] = source[i]
            queue[tail] = i
            tail += 1
    head = 0
    while head < tail:
        v = queue[head]
        head += 1
        for u in range(degree[v], degree[v + 1]):
            w = neighbour[u]
            if hops[w] == np.inf:
                hops[w] = hops[v] + 1.0
                queue[tail] = w
                tail += 1
    # each leaf's predecessor: its neighbour one step nearer with the largest
    # index; labels in the order reached (a predecessor is reached first)
    for t in range(tail):
        w = queue[t]
        if hops[w] == 0.0:
            continue
        for u in range(degree[w], degree[w + 1]):
            v = neighbour[u]
            if hops[v] == hops[w] - 1.0 and v > pred[w]:
                pred[w] = v
        label[w] = label[pred[w]]
    # the pairs searched whose leaves have two labels: where chains meet
    k = n_seed_meets
    for t in range(n_seed_meets, n_seed_meets + m):
        la, lb = label[a[t]], label[b[t]]
        if la >= 0 and lb >= 0 and la != lb:
            a[k], b[k] = a[t], b[t]
            k += 1
    return hops, pred, label, a[:k], b[:k]


@kernel
def _grown(
    out: NDArray[np.bool_], pairs: NDArray[np.intp], group: NDArray[np.int64]
) -> NDArray[np.bool_]:  # pragma: no cover - compiled
    """``out`` and the leaves touching it (by ``pairs``) in its group (``group``,
    -1 for a leaf of none: see :func:`_chain_search`)."""
    grown = out.copy()
    for t in range(pairs.shape[0]):
        i, j = pairs[t, 0], pairs[t, 1]
        if group[i] < 0 or group[i] != group[j]:
            continue
        if out[i]:
            grown[j] = True
        if out[j]:
            grown[i] = True
    return grown


def _necks(
    pairs: NDArray[np.intp],
    gap: NDArray[np.bool_],
    source: NDArray[np.int64],
    slack: int,
    group: NDArray[np.int64] | None = None,
) -> NDArray[np.bool_]:
    """Gap leaves on the shortest chains of touching leaves between parts.

    ``source`` gives the part of the leaves that hold one (-1 elsewhere). One
    breadth-first search from every part at once, through gap leaves, labels
    each leaf with its nearest part; where leaves of two labels touch, a chain
    joins the two parts through them. For each pair of parts the chains within
    ``slack`` leaves of the shortest are kept, and their gap leaves returned.

    ``group``, when given, splits the search into independent ones: each leaf of
    ``gap`` or with a part is in one group (-1 for the others), the parts of two
    groups are distinct, and chains only pass between the leaves of one group.
    The result is the union of the searches of each group alone, each with the
    gap leaves and parts of its group (one pass over the pairs for them all).
    """
    n = gap.size
    out = np.zeros(n, dtype=bool)
    seeds = np.flatnonzero(source >= 0)
    if group is None:
        group = np.where(gap | (source >= 0), 0, -1).astype(np.int64)
    # each leaf labelled with its nearest part, along a shortest chain; the
    # touching leaves of two labels
    pairs = np.ascontiguousarray(pairs, dtype=np.int64).reshape(-1, 2)
    group = np.ascontiguousarray(group, dtype=np.int64)
    hops, pred, label, a, b = _chain_search(
        pairs,
        group,
        seeds,
        np.ascontiguousarray(source, dtype=np.int64),
    )
    if not a.size:
        return out
    length = hops[a] + hops[b]
    low, high = np.minimum(label[a], label[b]), np.maximum(label[a], label[b])
    # per two parts that chains join, the shortest chain's length
    _, pair_key = np.unique(low * (int(label.max()) + 1) + high, return_inverse=True)
    pair_key = pair_key.reshape(-1)
    shortest = np.full(int(pair_key.max()) + 1, np.inf)
    np.minimum.at(shortest, pair_key, length)
    near = length <= shortest[pair_key] + slack
    # walk back from both ends of each kept contact to its parts
    _walk_back(out, np.concatenate([a[near], b[near]]), source, pred)
    # and the gap leaves touching the chains (parts that touch have chains of
    # their own leaves alone): along the pairs searched alone (two leaves of one
    # group), as the chains and the gap leaves are all in their group
    return _grown(out, pairs, group) & gap


class _NeckSearches:
    """Searches of :func:`_necks` (each a gap mask and its parts over ``n`` leaves)
    gathered in batches of searches whose leaves (gap or part) are apart: each
    batch is one search by groups, whose result is the union of its searches'.
    A search joins the first batch none of whose leaves it holds."""

    def __init__(self, n: int) -> None:
        self._n = n
        #: per batch: (gap, source, group; a leaf of none has group -1), and the
        #: counts of its parts and of its groups
        self.batches: list[tuple[NDArray[np.bool_], NDArray[np.int64], NDArray[np.int64]]] = []
        self._counts: list[list[int]] = []

    def add(self, gap: NDArray[np.bool_], source: NDArray[np.int64], n_parts: int) -> None:
        """One search: its gap leaves and the part (0 to ``n_parts - 1``) of each
        leaf holding one, -1 elsewhere."""
        through = gap | (source >= 0)
        free = (b for b, batch in enumerate(self.batches) if not (through & (batch[2] >= 0)).any())
        b = next(free, None)
        if b is None:
            b = len(self.batches)
            self.batches.append(
                (
                    np.zeros(self._n, dtype=bool),
                    np.full(self._n, -1, dtype=np.int64),
                    np.full(self._n, -1, dtype=np.int64),
                )
            )
            self._counts.append([0, 0])
        b_gap, b_source, b_group = self.batches[b]
        counts = self._counts[b]
        b_gap |= gap
        held = source >= 0
        # the parts of each search numbered apart, and each search its own group
        b_source[held] = source[held] + counts[0]
        b_group[through] = counts[1]
        counts[0] += n_parts
        counts[1] += 1


def count_text(at_least: int, at_most: int | None, noun: str = "region") -> str:
    """A count of regions in words: definite only when proved.

    Examples
    --------
    >>> count_text(4, 4), count_text(2, 5), count_text(2, None)
    ('4 regions', 'at least 2, at most 5 regions', 'at least 2 regions (no upper bound proved)')
    """
    plural = f"{noun}s"
    if at_least == at_most:
        return f"{at_least} {noun if at_least == 1 else plural}"
    if at_most is None:
        return f"at least {at_least} {plural} (no upper bound proved)"
    return f"at least {at_least}, at most {at_most} {plural}"


class Analysis:
    """Result of :func:`analyze`: regions, workspace, point queries.

    The tree's leaves are IN where every sheet is decided, OUT where no valid
    configuration exists, BOUNDARY where undecided at the precision.
    """

    def __init__(
        self,
        mechanism: Mechanism,
        precision: float | Sequence[float],
        tree: HyperTree,
        generalized_aspects: bool = False,
        table: SheetTable | None = None,
        flows_of: tuple[Analysis, NDArray[np.intp]] | None = None,
        joint_count: JointSpaceCount | None = None,
        evidence: Evidence | None = None,
    ) -> None:
        self.mechanism = mechanism
        self.generalized_aspects = bool(generalized_aspects)
        #: bounds on the count proved in the joint space (two-dyad mechanisms, the Delta), if sought
        self.joint_count = joint_count
        #: per pose axis
        self.precisions = check_precision(precision, len(mechanism.pose_names))
        #: as given: one number, or one per pose axis
        self.precision = _as_given(self.precisions)
        self.tree = tree
        # the boxes of the leaves the passes below ask for (a refined analysis:
        # those of its new nodes), unless every leaf is classified here
        leaves: Any = tree.leaves() if table is None else _Boxes(tree)
        self.table: SheetTable = (
            classify_sheets(mechanism, leaves.lo, leaves.hi) if table is None else table
        )
        self.areas = _leaf_volumes(tree)
        live = np.flatnonzero(tree.status != OUT)
        if evidence is None:
            #: touching leaf pairs (not OUT), by a shared vertex and by a shared face
            self._pairs, self._face_pairs = _touching(tree, flows_of)
            contact = _reachable_contact(mechanism, leaves, self.table, self._pairs)
        else:
            self._pairs, self._face_pairs = evidence.pairs, evidence.face_pairs
            contact = evidence.contact
        pairs = self._pairs
        self._contact = contact
        self._n_live = live.size
        self.graph: RegionGraph = region_graph(
            self.table,
            pairs,
            mechanism.postures,
            cross_serial=not self.generalized_aspects,
            limits=mechanism.limits,
            reachable_contact=contact,
        )
        saved = None if evidence is None else evidence.flows
        #: the flows of the nodes (see :meth:`_flow_table`), built when first needed
        self._flows: tuple[Any, ...] | None = None
        #: (2, n, P): open nodes for det A > 0 (0) and < 0 (1), where a region might hide
        self.open_nodes = np.zeros((2, *self.table.status.shape), dtype=bool)
        #: see :meth:`_witness_nodes` and :attr:`undecided`, found when first asked
        self._witnessed: tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.bool_]] | None = (
            None
        )
        self._undecided: dict[str, Any] | None = None
        if not self._listed_are_all():
            self._attach(leaves, flows_of, saved)
        elif saved is not None:
            # the joint-space count proves the regions the graph lists to be all: no
            # region hides in an uncertified node, and no flow is needed for that;
            # a saved analysis's flows are kept for saving it again
            self._flow_table(leaves, None, saved)
        self._resolve()

    #: what a refined analysis takes from the analysis it refines (see
    #: :meth:`_shed`): its tree, pairs and flows, and the settings the rounds read
    _CARRIED = frozenset(
        {
            "mechanism", "generalized_aspects", "joint_count", "precisions", "precision",
            "tree", "_pairs", "_face_pairs", "_flows", "_complete_flows",
        }
    )  # fmt: skip

    def _shed(self) -> None:
        """Drop all but what a refined analysis takes from this one (``_CARRIED``),
        once the resolution has split its tree and built the finer table: the
        analysis is then only the source of the next one, and unusable else."""
        for name in list(vars(self)):
            if name not in self._CARRIED:
                delattr(self, name)

    def evidence(self) -> Evidence:
        """What the analysis proved beyond its tree and sheet table (see
        :class:`Evidence`), to be saved with them."""
        # every flow of every node: a loaded analysis then tries none
        flows = self._flows_now()
        if not self._complete_flows.all():
            self._complete(~self._complete_flows)
        return Evidence(self._pairs, self._face_pairs, self._contact, flows[:4])

    @property
    def cell_size(self) -> NDArray[np.float64]:
        """Per pose axis, the width of the smallest cells of the pass at the
        precision (the resolution may split finer): the tree halves every axis
        at each level, until the level at which the coarsest axis is at most the
        precision wide, or the axis' own deepest level. Where :func:`analysis_box`
        could widen the box, that is the precision itself."""
        lo, hi = self.tree.lo, self.tree.hi
        levels = max(_depths(lo, hi, self.precisions))
        depths = np.minimum(levels, np.asarray(self.tree.max_depth)).astype(np.float64)
        return np.asarray((hi - lo) / 2.0**depths, dtype=np.float64)

    @property
    def cell_text(self) -> str:
        """:attr:`cell_size` for titles and summaries, 4 significant digits."""
        return " x ".join(f"{v:.4g}" for v in self.cell_size)

    @property
    def precision_text(self) -> str:
        """The precision for titles and summaries (``0.1`` or ``0.1, 0.1, 0.02``)."""
        return ", ".join(f"{v:g}" for v in np.atleast_1d(self.precision))

    # ------------------------------------------------------------ regions
    def _listed_are_all(self) -> bool:
        """Whether :attr:`joint_count` proves that the regions the region graph
        lists (its possible components that hold a certified part, one region
        each) are all the regions: its upper bound is their number."""
        joint = self.joint_count
        if joint is None or joint.at_most is None:
            return False
        listed = sum(np.unique(self._certified_possible(row)[1]).size for row in (0, 1))
        return listed == joint.at_most

    def _certified_possible(self, row: int) -> tuple[NDArray[np.bool_], NDArray[np.int64]]:
        """The certified nodes of sign row ``row`` (a mask (n, P)) and the possible
        component of each: that of its first sub-node (a certified node lies within
        the limits: one piece)."""
        g, t = self.graph, self.table
        mask = (g.certain >= 0) & (t.sign == (1, -1)[row])
        return mask, g.possible[row][:, :: g.slots][mask]

    def _flow_table(
        self,
        leaves: Any,
        reuse: tuple[Analysis, NDArray[np.intp]] | None = None,
        saved: tuple[NDArray[Any], ...] | None = None,
    ) -> list[NDArray[np.bool_]]:
        """The nodes that need a certificate (alive and uncertified for some sign)
        with their flows along the pose axes (every flow where ``saved``, or
        where ``reuse`` held them), kept in ``_flows``; returns the nodes done
        (dead or certified) per sign row. See :meth:`_attach` for the arguments."""
        t = self.table
        cross = not self.generalized_aspects
        done = [dead_or_certified(t, s, cross) for s in (1, -1)]
        nodes = np.argwhere(~done[0] | ~done[1])
        n, n_post = t.status.shape
        m = nodes.shape[0]
        # per node: whether every flow was tried on it (a saved analysis holds
        # every flow of every node, see evidence; a mechanism without flows has
        # none to try)
        complete = np.full(m, saved is not None or not supports_flows(self.mechanism))
        if reuse is not None and reuse[0]._flows is None:
            reuse = None  # the refined analysis built none (see _listed_are_all)
        if saved is not None:
            saved_nodes, bits, exists, faces = saved
            if not np.array_equal(saved_nodes, nodes):
                raise InvalidParameterError(
                    "path", "a saved analysis whose flows match its sheets", "a mismatch"
                )
        elif reuse is None:
            bits, exists, faces = flow_conditions(
                self.mechanism, leaves.lo, leaves.hi, t, nodes, axes_only=True
            )
        else:
            old, old_index = reuse
            old_nodes, old_bits, old_exists, old_faces, old_n = old._flows_now()
            old_row = np.full((old_n, n_post), -1, dtype=np.int64)
            old_row[old_nodes[:, 0], old_nodes[:, 1]] = np.arange(old_nodes.shape[0])
            source = np.where(
                old_index[nodes[:, 0]] >= 0,
                old_row[np.maximum(old_index[nodes[:, 0]], 0), nodes[:, 1]],
                -1,
            )
            fresh = np.flatnonzero(source < 0)
            new_bits, new_exists, new_faces = flow_conditions(
                self.mechanism, leaves.lo, leaves.hi, t, nodes[fresh], axes_only=True
            )
            kept = source >= 0
            bits = np.zeros((2, m, old_bits.shape[2]), dtype=np.uint64)
            exists = np.zeros((m, old_exists.shape[1]), dtype=bool)
            faces = np.zeros((old_faces.shape[0], m), dtype=np.uint8)
            bits[:, kept], exists[kept], faces[:, kept] = (
                old_bits[:, source[kept]],
                old_exists[source[kept]],
                old_faces[:, source[kept]],
            )
            complete[kept] = old._complete_flows[source[kept]]
            bits[:, fresh], exists[fresh], faces[:, fresh] = new_bits, new_exists, new_faces
        self._spans = slot_spans(t, nodes, self.mechanism.limits)
        self._neighbours = face_neighbours(self.tree, self._face_pairs)
        self._flows = (nodes, bits, exists, faces, n)
        self._complete_flows: NDArray[np.bool_] = complete
        return done

    def _flows_now(self, leaves: Any = None) -> tuple[Any, ...]:
        """``_flows``, built first where they were not (see :meth:`_flow_table`);
        ``leaves`` the tree's leaves, if at hand."""
        if self._flows is None:
            self._flow_table(_Boxes(self.tree) if leaves is None else leaves)
        assert self._flows is not None  # built just above
        return self._flows

    def _attach(
        self,
        leaves: Any,
        reuse: tuple[Analysis, NDArray[np.intp]] | None = None,
        saved: tuple[NDArray[Any], ...] | None = None,
    ) -> None:
        """Nodes whose every valid configuration joins a certified sheet (see
        :mod:`moveability.analysis.flows`); the others, alive and uncertified, are *open*:
        a region might hide there. ``reuse`` carries the analysis this one
        refines, with the old index of each leaf (-1 for new ones); ``saved``
        the flows (nodes, bits, exists, faces) of a saved analysis of this
        tree; ``leaves`` are the tree's leaves.

        The flows along the pose axes are tried first, on every node; the other
        flows only on the nodes those leave open (see :meth:`_attached`)."""
        done = self._flow_table(leaves, reuse, saved)
        attached = self._attached(done, (0, 1), leaves=leaves)
        for row in (0, 1):
            self.open_nodes[row] = ~done[row] & ~attached[row]

    def _left_open(
        self, done: list[NDArray[np.bool_]], attached: list[NDArray[np.bool_]]
    ) -> NDArray[np.bool_]:
        """Per node of the flows: neither done nor attached for some sign row."""
        nodes = self._flows_now()[0]
        leaf, post = nodes[:, 0], nodes[:, 1]
        out = np.zeros(nodes.shape[0], dtype=bool)
        for d, a in zip(done, attached, strict=True):
            out |= ~d[leaf, post] & ~a[leaf, post]
        return out

    def _attached(
        self,
        done: list[NDArray[np.bool_]],
        rows: tuple[int, ...],
        leaves: Any = None,
    ) -> list[NDArray[np.bool_]]:
        """:func:`~moveability.analysis.flows.attached_nodes` for each sign row of
        ``rows`` (``done[i]`` for ``rows[i]``), with the flows of the nodes.

        Nodes may hold the flows along the pose axes alone: those left open are
        given the others (kept for later calls, :meth:`_complete`) and the
        attachment goes on with them. Attachment is monotone in the flows: a
        node attached with fewer flows is attached with more, and every node
        that all the flows attach attaches in the second pass (every node open
        after the first has them all), so the result is exactly that of all the
        flows."""
        nodes, bits, exists, faces, _ = self._flows_now(leaves)
        if not supports_flows(self.mechanism):
            # no flow: a node attaches only where none of its slots may hold a
            # configuration (as the attachment's runs would find)
            empty = nodes[~exists.any(axis=1)]
            out = []
            for d in done:
                alone = np.zeros_like(d)
                alone[empty[:, 0], empty[:, 1]] = True
                out.append(alone & ~d)
            return out
        runs = Attachment.both(done, nodes, exists, self._neighbours, self._spans)
        attached = [a.run(bits[row], faces) for a, row in zip(runs, rows, strict=True)]
        missing = self._left_open(done, attached) & ~self._complete_flows
        if not missing.any():
            return attached
        self._complete(missing, leaves)
        # the runs go on from the slots they attached, with the flows added
        return [a.run(bits[row], faces) for a, row in zip(runs, rows, strict=True)]

    def _complete(self, missing: NDArray[np.bool_], leaves: Any = None) -> None:
        """Every flow tried on the nodes of the flows where ``missing`` holds: their
        bits and exit faces replaced in place (kept for later calls)."""
        nodes, bits, _, faces, _ = self._flows_now()
        at = np.flatnonzero(missing)
        if leaves is None:
            leaves = _Boxes(self.tree)
        more_bits, _, more_faces = flow_conditions(
            self.mechanism, leaves.lo, leaves.hi, self.table, nodes[at]
        )
        bits[:, at], faces[:, at] = more_bits, more_faces
        self._complete_flows[at] = True

    def open_leaves(self, slack: int = 2) -> NDArray[np.bool_]:
        """Leaves that keep the count of regions open.

        Those holding an open node (a region might hide there); while
        N-connectivity is unknown, those of W where no region is known to hold
        every pose; and the *necks*: in a possible component that holds several
        certified parts, the leaves with uncertified nodes of that component on
        the shortest chains of touching leaves (within ``slack`` more leaves)
        between two certified parts whose nearest leaves touch. Refined, the
        parts join there, or the chains get longer until the component splits.
        """
        mask = self.hiding_leaves()
        if self.n_connected is None:
            mask |= self._w_open
        if self.complete:
            # every region is listed: no neck or hiding place can change the count
            return mask
        if self._witnesses_placed():
            # the regions are listed at the witnesses once each is certified (see
            # _witness_parts): no neck needs splitting for that
            return mask
        g, t = self.graph, self.table
        n, n_post = t.status.shape
        certified = (t.status == IN) | t.group
        sizes = np.bincount(g.certain[g.certain >= 0], minlength=g.certain_sign.size)
        # the searches of every possible component of several parts, those whose
        # leaves are apart run together (see _necks' groups)
        searches = _NeckSearches(n)
        for row in (0, 1):
            sign = (1, -1)[row]
            of_sign = np.flatnonzero(g.certain_sign == sign)
            owner = self._certain_to_possible[of_sign]
            per = np.bincount(owner, minlength=g.n_possible[row])
            labels = g.possible[row].reshape(n, n_post, g.slots)
            for u in np.flatnonzero(per >= 2):
                parts = of_sign[owner == u]
                gap = ((labels == u).any(axis=2) & ~certified).any(axis=1)
                # the part of each leaf holding one (the smallest where several: a
                # small part sharing the leaves of a large one keeps its own)
                # (of the parts it holds, the last by decreasing size, stable: its
                # index in `parts`); rank: a part's place in that order
                order = np.argsort(-sizes[parts], kind="stable")
                rank = np.full(g.certain_sign.size + 1, -1, dtype=np.int64)
                rank[parts[order]] = np.arange(parts.size)
                last = rank[g.certain].max(axis=1)
                source = np.where(last >= 0, order[np.maximum(last, 0)], -1).astype(np.int64)
                searches.add(gap, source, parts.size)
        for gap, source, group in searches.batches:
            mask |= _necks(self._pairs, gap, source, slack, group)
        return mask

    def hiding_leaves(self) -> NDArray[np.bool_]:
        """Leaves holding an open node, where a region might hide, and those holding
        a configuration of a region the joint-space count proves whose node is not
        certified (:meth:`unlisted_witnesses`); none once the listed regions are
        proved to be all (:attr:`complete`)."""
        if self.complete:
            return np.zeros(len(self.areas), dtype=bool)
        joint = self.joint_count
        if joint is not None and joint.decided:
            # the count is proved: no open node can change it, the regions it
            # proves are found at their witnesses
            return self.unlisted_witnesses()
        return np.asarray(self.open_nodes.any(axis=(0, 2)) | self.unlisted_witnesses(), dtype=bool)

    def unlisted_witnesses(self) -> NDArray[np.bool_]:
        """Leaves where a region proved by the joint-space count may still lack a
        certified part: each certified component of Q holds two regions, with a
        configuration of each at its witness joints (see
        :func:`~moveability.analysis.joint_space.witness_configurations`); the leaf
        of such a pose is returned while the node of its posture there is not
        certified. Refined there, the region gets a certified part and is listed
        (listed there once every witness is, see :meth:`_witness_parts`)."""
        out = np.zeros(len(self.areas), dtype=bool)
        leaf, _, certified = self._witness_nodes()
        out[leaf[~certified]] = True
        return out

    def _witnesses_placed(self) -> bool:
        """Whether the joint-space count is proved and a witness configuration of
        each region it proves lies in the tree (certified or not yet)."""
        joint = self.joint_count
        return bool(
            joint is not None
            and joint.decided
            and joint.witnesses.size
            and self._witness_nodes()[0].size == joint.at_least
        )

    def _witness_parts(self) -> list[int] | None:
        """The certified parts holding the witness configurations of a decided
        joint-space count (see :meth:`unlisted_witnesses`), one per region it
        proves, where every one is certified; else None.

        The witnesses lie in distinct regions (distinct components of the
        certified cells of Q, or two signs of det A), so their parts are in
        distinct regions, and being as many as the count they are all the
        regions."""
        if not self._witnesses_placed():
            return None
        leaf, posture, certified = self._witness_nodes()
        if not certified.all():
            return None
        parts = self.graph.certain[leaf, posture]
        if np.unique(parts).size != parts.size:
            return None  # two witnesses in one certified part: not what was proved
        return [int(c) for c in parts]

    def _witness_nodes(
        self,
    ) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.bool_]]:
        """The leaf and posture of each witness configuration placed in the tree,
        and whether that node is certified (found when first asked)."""
        if self._witnessed is None:
            self._witnessed = self._place_witnesses()
        return self._witnessed

    def _place_witnesses(
        self,
    ) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.bool_]]:
        none = np.zeros(0, dtype=np.intp)
        joint, m = self.joint_count, self.mechanism
        if joint is None or not joint.witnesses.size:
            return none, none, np.zeros(0, dtype=bool)
        poses, signs = witness_configurations(m, joint.witnesses)
        q = np.repeat(joint.witnesses, 2, axis=0)
        points = poses.reshape(q.shape[0], -1)
        found = np.isfinite(points).all(axis=1) & (signs.ravel() != 0) & joint.witnessed.ravel()
        q, points = q[found], points[found]
        if not points.size:
            return none, none, np.zeros(0, dtype=bool)
        _, leaf = locate(self.tree, points)
        with np.errstate(invalid="ignore"):
            angles = m.joint_angles(points, clip=True)
            gap = angles - q[:, None, :]
            for i, limit in enumerate(m.limits):
                if not limit.prismatic:
                    gap[:, :, i] = np.mod(gap[:, :, i] + np.pi, 2 * np.pi) - np.pi
            same = (np.abs(gap) <= 1e-7 * (1.0 + np.abs(q[:, None, :]))).all(axis=2)
        posture = np.argmax(same, axis=1)
        take = (leaf >= 0) & same.any(axis=1)
        leaf, posture = leaf[take], posture[take]
        g, t = self.graph, self.table
        certified = (g.certain[leaf, posture] >= 0) & (
            (t.status[leaf, posture] == IN) | t.group[leaf, posture]
        )
        return leaf, posture, np.asarray(certified, dtype=bool)

    def _resolve(self) -> None:
        g, t = self.graph, self.table
        n_post = t.status.shape[1]
        # certain component -> possible component of its sign
        self._certain_to_possible = np.full(g.certain_sign.size, -1, dtype=np.int64)
        for row in (0, 1):
            mask, possible = self._certified_possible(row)
            self._certain_to_possible[g.certain[mask]] = possible
        # each possible component holding certified parts is one region (distinct
        # possible components hold distinct regions); its largest certified part
        # represents it, the others may or may not belong to it
        sizes = np.bincount(g.certain[g.certain >= 0], minlength=g.certain_sign.size)
        regions: list[tuple[int, int, int]] = []  # (first node, certain, row * 2^40 + possible)
        self._unresolved: list[tuple[int, int]] = []
        self._extra_certain: list[int] = []
        # possible components holding an open node: a region may hide there
        self._open_possible: list[NDArray[np.bool_]] = []
        for row in (0, 1):
            labels = g.possible[row].reshape(len(self.areas), n_post, g.slots)[self.open_nodes[row]]
            flag = np.zeros(g.n_possible[row], dtype=bool)
            flag[labels[labels >= 0]] = True
            self._open_possible.append(flag)
        for row, s in enumerate((1, -1)):
            for u in range(g.n_possible[row]):
                inside = np.flatnonzero((g.certain_sign == s) & (self._certain_to_possible == u))
                if not inside.size:
                    if self._open_possible[row][u]:
                        self._unresolved.append((row, u))
                    continue
                c = int(inside[np.argmax(sizes[inside])])
                self._extra_certain.extend(int(x) for x in inside if x != c)
                first = int(np.flatnonzero(g.certain.ravel() == c)[0])
                regions.append((first, c, row * (1 << 40) + u))
        proved = self._witness_parts()
        #: whether the regions are listed at the joint-space count's witnesses
        self._by_witness = False
        if proved is not None and len(proved) > len(regions):
            self._by_witness = True
            # the joint-space count's regions, one at the certified part of each
            # witness: distinct regions, all of them
            regions = []
            for c in proved:
                row = int(g.certain_sign[c] < 0)
                first = int(np.flatnonzero(g.certain.ravel() == c)[0])
                regions.append((first, c, row * (1 << 40) + int(self._certain_to_possible[c])))
            self._extra_certain = sorted(set(range(g.certain_sign.size)) - set(proved))
        regions.sort()
        certified_leaf_in = t.status == IN
        w_certain = (t.exists & t.within).any(axis=1)  # whole leaf in W
        w_possible = (t.status != OUT).any(axis=1)
        self._w_certain, self._w_possible = w_certain, w_possible
        self.regions: list[Region] = []
        self._region_nodes: list[tuple[int, int, int]] = []  # (certain id, row, possible id)
        #: leaves that keep some W_Nj = W open
        self._w_open = np.zeros(len(self.areas), dtype=bool)
        self._spanning = self._spanning_nodes()
        # the listed regions are all: a possible component that holds one of them
        # holds no other region
        listed_all = self._bounds(len(regions))[1] == len(regions)
        codes = [code for _, _, code in regions]
        for rid, (_, c, code) in enumerate(regions):
            row, u = divmod(code, 1 << 40)
            in_c = g.certain == c
            inner = float(self.areas[(in_c & certified_leaf_in).any(axis=1)].sum())
            touch = (g.possible[row] == u).any(axis=1)
            outer = float(self.areas[touch].sum())
            covered = (in_c & ((t.status == IN) | t.group)).any(axis=1)
            if (w_certain & ~touch).any():
                equals: bool | None = False
            else:
                uncovered = w_possible & ~covered
                if uncovered.any():
                    sole = u if listed_all and codes.count(code) == 1 else None
                    uncovered &= ~self._held_by(c, row, uncovered, sole)
                equals = None if uncovered.any() else True
                self._w_open |= uncovered
            used = np.flatnonzero(in_c.any(axis=0))
            self.regions.append(
                Region(
                    id=rid,
                    sign=(1, -1)[row],
                    area=(inner, outer),
                    equals_workspace=equals,
                    postures=tuple(self.mechanism.posture_name(int(p)) for p in used),
                    certain=c,
                    possible=u,
                )
            )
            self._region_nodes.append((c, row, u))
        del n_post

    def _spanning_nodes(self) -> NDArray[np.bool_]:
        """(n, P): nodes whose posture has a valid configuration at every pose of W
        over the leaf: every leg reaches the leaf, and every configuration is
        within the limits (a range of a whole turn holds every angle; its stop
        only cuts the sheet in two pieces)."""
        t = self.table
        legs = t.leg_status
        reached = ~((legs == REACH_UNKNOWN) | (legs == REACH_OUT)).any(axis=1)
        valid = np.repeat(reached[:, None], t.status.shape[1], axis=1)
        for i, limit in enumerate(self.mechanism.limits):
            if limit.periodic or (not limit.prismatic and limit.hi - limit.lo >= 2 * np.pi):
                continue
            angles = Interval(t.angles_lo[:, :, i].ravel(), t.angles_hi[:, :, i].ravel())
            valid &= (limit.classify(angles) == INSIDE).reshape(valid.shape)
        return valid

    def _held_by(
        self, c: int, row: int, leaves: NDArray[np.bool_], sole: int | None = None
    ) -> NDArray[np.bool_]:
        """Of ``leaves``, those where every pose of W (but a set of measure zero)
        has a configuration in the region of certified part ``c`` (sign row ``row``).

        A node is *attached to c alone* when its flows (see
        :mod:`moveability.analysis.flows`) lead every valid configuration to certified
        sheets of ``c`` through nodes attached the same way. A leaf qualifies
        when one of its nodes is certified in ``c`` or attached to c alone, has
        det A of the region's sign throughout and every joint within its limits
        throughout: every pose of W over the leaf (every leg reaches it) then
        has that posture's configuration, in the region. It also qualifies
        when no node holds a valid configuration of the other sign, no
        identically singular posture holds a valid configuration and every node
        of the region's sign is certified in ``c``, attached to c alone or holds
        no valid configuration: the poses left out are those whose every valid
        configuration is singular, on the singular curves.

        A node is *good* for the region when every valid configuration it holds
        lies in the region, with det A of the region's sign throughout: certified
        in ``c`` or attached to c alone; or, where ``sole`` is the region's
        possible component and it holds no other region (the listed regions are
        proved to be all), every sub-node that may hold a valid configuration
        lies in that component. A leaf also qualifies when each class of
        postures with one valid set over it (see
        :mod:`moveability.analysis.valid_sets`) holds a good node or holds no
        valid configuration: every pose of W over it has a valid configuration
        of some posture, and the good node of that posture's class one at the
        same pose, in the region. This holds where joint limits cut W.
        """
        g, t = self.graph, self.table
        s = (1, -1)[row]
        cross = not self.generalized_aspects
        group = t.group if cross else np.zeros_like(t.group)
        in_c = (g.certain == c) & ((t.status == IN) | group)
        done = in_c | ~t.may_hold(s)
        (attached,) = self._attached([done], (row,))
        ok = (done | attached) & ~t.may_hold(-s) & ~(t.singular & (t.status != OUT))
        good = (in_c | attached) & (t.sign == s)
        if sole is not None:
            n, n_post = t.status.shape
            labels = g.possible[row].reshape(n, n_post, g.slots)
            own = ((labels == sole) | (labels < 0)).all(axis=2)
            good |= own & (t.sign == s) & (t.status != OUT) & ~t.singular
        spans = good & self._spanning
        held = ok.all(axis=1) | spans.any(axis=1)
        rest = leaves & ~held
        if rest.any():
            # postures of one valid set over the leaf: one good node covers them all
            sub = t.take(np.flatnonzero(rest))
            classes = valid_set_classes(self.mechanism, sub)
            held[rest] = covered_by_classes(classes, sub.status, good[rest])
        return np.asarray(leaves & held, dtype=bool)

    @property
    def count(self) -> tuple[int, int | None]:
        """Certified bounds ``(at_least, at_most)`` on the number of regions.

        ``at_least`` counts the possible components that hold a certified part
        (each holds a region of its own); ``at_most`` counts the certified parts,
        and is None (no bound) while a region may hide in an open node (see
        :mod:`moveability.analysis.flows`). Where :attr:`joint_count` holds bounds proved
        in the joint space (two-dyad mechanisms and the Delta, with the resolution on), the
        tighter of both are given. The count is known when they are equal.

        Examples
        --------
        >>> from moveability import analyze
        >>> from moveability.mechanisms import FiveBar
        >>> analyze(FiveBar(7, 8, 5, 8, 5), precision=0.1, resolve=False).count
        (2, None)
        >>> analyze(FiveBar(7, 8, 5, 8, 5), precision=0.1).count
        (2, 2)
        """
        return self._bounds(len(self.regions))

    def _bounds(self, n_listed: int) -> tuple[int, int | None]:
        """:attr:`count`, with ``n_listed`` regions listed."""
        hiding = any(flag.any() for flag in self._open_possible)
        at_least, at_most = n_listed, None if hiding else self.graph.certain_sign.size
        joint = self.joint_count
        if joint is not None:
            at_least = max(at_least, joint.at_least)
            if joint.at_most is not None:
                at_most = joint.at_most if at_most is None else min(at_most, joint.at_most)
        return at_least, at_most

    @property
    def complete(self) -> bool:
        """Whether the listed regions are proved to be all the regions: then no
        possible component without a listed region holds one, and every certified
        part lies in the listed region of its possible component."""
        return self.count[1] == len(self.regions)

    @property
    def n_regions(self) -> int | None:
        """The number of regions where it is proved, else None (see :attr:`count`)."""
        at_least, at_most = self.count
        return at_least if at_least == at_most else None

    def workspace_cells(self) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        """Leaves certainly in W, and leaves that W may meet besides.

        Returns
        -------
        certain, possible : ndarray of bool, shape (n_leaves,)
            ``certain``: a configuration of every pose of the leaf is valid;
            ``possible`` (which holds ``certain``): the leaf is not certified
            out of W. Masks over ``self.tree.leaves()``.

        Examples
        --------
        >>> from moveability import analyze
        >>> from moveability.mechanisms import FiveBar
        >>> result = analyze(FiveBar(), precision=0.5)
        >>> certain, possible = result.workspace_cells()
        >>> lo, hi = result.workspace["area"]
        >>> bool(abs(result.areas[certain].sum() - lo) < 1e-9), bool((possible >= certain).all())
        (True, True)
        """
        certain: NDArray[np.bool_] = np.array(self._w_certain, dtype=bool)
        possible: NDArray[np.bool_] = np.array(self._w_possible, dtype=bool)
        return certain, possible

    def region_cells(self, index: int) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        """Leaves certainly in a region, and leaves where it may extend besides.

        A leaf is *certain* when one of its posture sheets is IN and belongs to the
        region's certified component (their volumes sum to the region's inner
        bound); it is *possible* when, not certain, one of its sheets touches the
        region's possible component (certain and possible volumes sum to the outer
        bound).

        Parameters
        ----------
        index : int
            Position of the region in :attr:`regions`.

        Returns
        -------
        certain, possible : ndarray of bool, shape (n_leaves,)
            Disjoint masks over ``self.tree.leaves()``.

        Examples
        --------
        >>> from moveability import analyze
        >>> from moveability.mechanisms import FiveBar
        >>> result = analyze(FiveBar(7, 8, 5, 8, 5), precision=0.5)
        >>> certain, possible = result.region_cells(0)
        >>> bool(abs(result.areas[certain].sum() - result.regions[0].area[0]) < 1e-9)
        True
        """
        c, row, u = self._region_nodes[index]
        g, t = self.graph, self.table
        certain = ((g.certain == c) & (t.status == IN)).any(axis=1)
        possible = (g.possible[row] == u).any(axis=1) & ~certain
        return certain, possible

    @property
    def measure_name(self) -> str:
        """What the measures of sets of poses are: ``area`` (2 pose axes), ``volume`` (3)."""
        return {1: "length", 2: "area", 3: "volume"}.get(self.tree.ndim, "measure")

    @property
    def workspace(self) -> dict[str, tuple[float, float]]:
        """Bounds on the area (volume) of the workspace W, keyed by :attr:`measure_name`."""
        return {
            self.measure_name: (
                float(self.areas[self._w_certain].sum()),
                float(self.areas[self._w_possible].sum()),
            )
        }

    @property
    def undecided(self) -> dict[str, Any]:
        """What the precision left open.

        ``components``: possible components with no certified part where a
        region may still hide (they hold an open node), with the ``area`` of the
        leaves they touch; ``detached``: certified parts whose region is not
        known (they share a listed region's possible part and may or may not be
        in that region); ``boundary_area``: area of the leaves left undecided;
        ``open_area``: area of the leaves holding an open node (an uncertified
        node not proved to join a certified part). Once the listed regions are
        proved to be all (:attr:`complete`), no component, detached part or open
        node is left. With three pose axes the keys say ``volume`` for ``area``.

        ``open``: where the count or N-connectivity is still open (the leaves the
        resolution would refine next, :meth:`open_leaves`), as parts of touching
        leaves: their number, total measure and the largest ones with their
        bounding boxes (see :func:`~moveability.analysis.open_parts.open_parts`);
        no part once both are decided.
        """
        if self._undecided is None:
            self._undecided = self._find_undecided()
        return copy.deepcopy(self._undecided)

    def _find_undecided(self) -> dict[str, Any]:
        g = self.graph
        complete = self.complete
        unresolved = [] if complete else self._unresolved
        touch = np.zeros(self.areas.size, dtype=bool)
        for row, u in unresolved:
            touch |= (g.possible[row] == u).any(axis=1)
        undecided_leaves = self.tree.status == BOUNDARY
        measure = self.measure_name
        open_leaves = self.hiding_leaves()
        if complete and self.n_connected is not None:
            still = np.zeros(self.areas.size, dtype=bool)
        else:
            still = self.open_leaves()
        # the boxes of the open leaves alone (the others are not read)
        boxes, rows = _Boxes(self.tree), np.flatnonzero(still)
        lo, hi = np.zeros((2, still.size, self.tree.ndim))
        lo[rows], hi[rows] = boxes.lo[rows], boxes.hi[rows]
        where = open_parts(lo, hi, self.areas, self._pairs, still, measure)
        return {
            "components": len(unresolved),
            measure: float(self.areas[touch].sum()),
            "detached": 0 if complete and not self._by_witness else len(self._extra_certain),
            f"boundary_{measure}": float(self.areas[undecided_leaves].sum()),
            f"open_{measure}": float(self.areas[open_leaves].sum()),
            "open": where,
        }

    @property
    def n_connected(self) -> bool | None:
        """Whether W is N-connected: some W_Nj equals W."""
        if any(r.equals_workspace for r in self.regions):
            return True
        g = self.graph
        complete = self.complete
        # every possible component that may hold a region misses a leaf certainly in W
        occupied = [np.zeros(g.n_possible[row], dtype=bool) for row in (0, 1)]
        for _, row, u in self._region_nodes:
            occupied[row][u] = True
        for row in (0, 1):
            for u in range(g.n_possible[row]):
                if not (occupied[row][u] or (self._open_possible[row][u] and not complete)):
                    continue  # proved to hold no region
                touch = (g.possible[row] == u).any(axis=1)
                if not (self._w_certain & ~touch).any():
                    return None
        return False

    # ------------------------------------------------------------- points
    def as_poses(self, points: ArrayLike) -> NDArray[np.float64]:
        """The points as an ``(m, k)`` array of poses, checked and wrapped.

        Raises :class:`~moveability.errors.InvalidParameterError` naming
        ``points`` (not an array of ``k`` numbers per pose) or ``points[i]``
        (a coordinate that is not finite). Periodic coordinates are wrapped
        into the box.

        Examples
        --------
        >>> from moveability import analyze
        >>> from moveability.mechanisms import FiveBar
        >>> analyze(FiveBar(), precision=0.5).as_poses([1.0, 3.0]).tolist()
        [[1.0, 3.0]]
        """
        k = len(self.mechanism.pose_names)
        try:
            p = np.asarray(points, dtype=np.float64)
        except (TypeError, ValueError):
            raise InvalidParameterError(
                "points", f"an array of poses ({k} numbers each)", points
            ) from None
        if p.ndim == 1:
            p = p.reshape(1, -1)
        if p.ndim != 2 or p.shape[1] != k:
            raise InvalidParameterError("points", f"an array of shape (m, {k})", p.shape)
        bad = ~np.isfinite(p).all(axis=1)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise InvalidParameterError(f"points[{i}]", "finite coordinates", p[i].tolist())
        return self.mechanism.wrap_poses(p)

    def _point_answers(
        self, p: NDArray[np.float64]
    ) -> tuple[NDArray[np.int8], NDArray[np.int8], NDArray[np.intp]]:
        """Workspace answer and region answers (m, R) as codes (YES, NO, UNKNOWN), leaves."""
        m = p.shape[0]
        _, leaf = locate(self.tree, p)
        point_table = classify_sheets(self.mechanism, p, p)
        ws = np.full(m, UNKNOWN, dtype=np.int8)
        ws[(point_table.exists & point_table.within).any(axis=1)] = YES
        ws[(point_table.status == OUT).all(axis=1)] = NO
        answers = np.full((m, len(self.regions)), UNKNOWN, dtype=np.int8)
        inside_box = leaf >= 0
        lf = np.where(inside_box, leaf, 0)
        g, t = self.graph, self.table
        point_regular = (point_table.leg_status == REGULAR).all(axis=1)
        for j, (c, row, u) in enumerate(self._region_nodes):
            nodes_c = g.certain[lf] == c
            sure = (nodes_c & (t.status[lf] == IN)).any(axis=1)
            sure |= (nodes_c & t.group[lf]).any(axis=1) & point_regular
            touch = (g.possible[row][lf] == u).any(axis=1)
            # a pose outside the box is outside W (the box holds W); unless the pose
            # itself is certified out, say so only through `ws` below
            answers[:, j] = np.where(
                sure & inside_box, YES, np.where(~touch & inside_box, NO, UNKNOWN)
            )
        answers[ws == NO] = NO
        return ws, answers, np.where(inside_box, leaf, -1)

    def locate(self, points: ArrayLike) -> dict[str, Any]:
        """Workspace and region membership of each pose, as a JSON-ready dict.

        Each answer is ``True`` (the pose is in; a configuration of it lies in
        the region), ``False`` (it is not) or ``None`` (undecided at the
        precision).

        Examples
        --------
        >>> from moveability import analyze
        >>> from moveability.mechanisms import FiveBar
        >>> result = analyze(FiveBar(), precision=0.5)
        >>> result.locate([[3.5, 9.0]])["points"][0]["workspace"]
        True
        """
        p = self.as_poses(points)
        ws, answers, _ = self._point_answers(p)
        return {
            "regions": [r.id for r in self.regions],
            "points": [
                {
                    "pose": [float(v) for v in p[i]],
                    "workspace": answer(int(ws[i])),
                    "regions": {
                        str(r.id): answer(int(answers[i, j])) for j, r in enumerate(self.regions)
                    },
                }
                for i in range(p.shape[0])
            ],
        }

    def feasible(self, points: ArrayLike) -> dict[str, Any]:
        """Whether one region holds a configuration of every pose, with witnesses.

        Returns ``{"feasible": true|false|null, "region": id|null,
        "postures": [[t1, t2], ...]|null}``; the postures are joint angles of one
        valid configuration per pose in that region.
        """
        p = self.as_poses(points)
        ws, answers, leaf = self._point_answers(p)
        for j, region in enumerate(self.regions):
            if (answers[:, j] == YES).all():
                return {
                    "feasible": True,
                    "region": region.id,
                    "postures": self._witnesses(p, leaf, j),
                }
        if (ws == NO).any():
            return {"feasible": False, "region": None, "postures": None}
        if (leaf < 0).any():
            # a pose outside the box that the pose-level test could not place
            return {"feasible": None, "region": None, "postures": None}
        g = self.graph
        listed = {(row, u) for _, row, u in self._region_nodes}
        complete = self.complete
        for row in (0, 1):
            for u in range(g.n_possible[row]):
                if complete and (row, u) not in listed:
                    continue  # proved to hold no region
                if (g.possible[row][leaf] == u).any(axis=1).all():
                    return {"feasible": None, "region": None, "postures": None}
        return {"feasible": False, "region": None, "postures": None}

    def _witnesses(
        self, p: NDArray[np.float64], leaf: NDArray[np.intp], j: int
    ) -> list[list[float]]:
        c = self._region_nodes[j][0]
        g, t = self.graph, self.table
        # the poses are certified reachable: clip the rounding of the closed form
        joints = self.mechanism.joint_angles(p, clip=True)
        out = []
        for i in range(p.shape[0]):
            ok = (g.certain[leaf[i]] == c) & ((t.status[leaf[i]] == IN) | t.group[leaf[i]])
            ok &= np.isfinite(joints[i]).all(axis=1)
            posture = int(np.flatnonzero(ok)[0])
            q = [
                float(lim.wrap(v))
                for lim, v in zip(self.mechanism.limits, joints[i, posture], strict=True)
            ]
            out.append(q)
        return out

    # -------------------------------------------------------------- output
    def to_dict(self) -> dict[str, Any]:
        """The summary as a JSON-ready dict (the ``regions --json`` document)."""
        measure = self.measure_name
        return {
            "precision": (
                list(self.precision) if isinstance(self.precision, tuple) else self.precision
            ),
            "cell": [float(v) for v in self.cell_size],
            "pose": list(self.mechanism.pose_names),
            "workspace": {measure: list(self.workspace[measure])},
            "regions": [
                {
                    "id": r.id,
                    measure: list(r.area),
                    "equals_workspace": r.equals_workspace,
                    "sign": r.sign,
                    "postures": list(r.postures),
                }
                for r in self.regions
            ],
            "count": {"at_least": self.count[0], "at_most": self.count[1]},
            "n_connected": self.n_connected,
            "generalized_aspects": self.generalized_aspects,
            "undecided": self.undecided,
            "mechanism": self.mechanism.name,
            "leaves": len(self.tree),
            "notes": list(self.notes),
        }

    @property
    def notes(self) -> tuple[str, ...]:
        """Lines on what the design is exactly degenerate at, where that was found
        (a stroke that touches a parallel singularity only at its end, say): the
        reason an answer is what it is, rather than a bare null."""
        return () if self.joint_count is None else tuple(self.joint_count.notes)

    def summary(self) -> str:
        """A readable summary."""
        measure = self.measure_name
        w = self.workspace[measure]
        lines = [
            describe_spec(self.mechanism.to_spec()),
            f"precision {self.precision_text}: cells {self.cell_text}, {len(self.tree)} leaves",
            f"workspace {measure} in [{w[0]:.4f}, {w[1]:.4f}]",
            f"{count_text(*self.count)}:",
        ]
        for r in self.regions:
            lines.append(
                f"  region {r.id}: det A {'>' if r.sign > 0 else '<'} 0, {measure} in "
                f"[{r.area[0]:.4f}, {r.area[1]:.4f}], postures {', '.join(r.postures)}, "
                f"equals W: {word(r.equals_workspace)}"
            )
        u = self.undecided
        lines.append(
            f"undecided: {u['components']} component(s) without certified part, "
            f"{u['detached']} detached certified part(s), "
            f"{u[f'boundary_{measure}']:.4f} of {measure} in undecided leaves"
        )
        lines.append(f"workspace N-connected: {word(self.n_connected)}")
        still = open_text(u["open"], self.mechanism.pose_names, measure)
        if still:
            lines.append(still)
        lines.extend(self.notes)
        return "\n".join(lines)

