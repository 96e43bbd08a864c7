"""The generalized octree: :class:`HyperTree`, a k-dimensional 2^k-tree.

A tree is stored as a *linear* tree: the leaves only, as three parallel numpy
arrays sorted by their Morton-style key (see :mod:`moveability.hypertree.keys`):

``keys`` (uint64)
    the key of the lower corner of each leaf;
``levels`` (uint8)
    the subdivision level of each leaf (0 is the root box);
``status`` (uint8)
    :data:`~moveability.IN`, :data:`~moveability.OUT` or
    :data:`~moveability.BOUNDARY`.

Trees are immutable; every operation returns a new tree.
"""

from __future__ import annotations

import os
import zipfile
from collections.abc import Callable, Iterable, Sequence
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError, ResolutionError
from . import _boxes
from .keys import KeyLayout
from .status import BOUNDARY, IN, OUT, is_valid_status
from .subdivision import Progress, merge_siblings, split_leaves, subdivide

__all__ = ["MAX_DIMENSION", "HyperTree", "Leaves", "load"]

#: Largest number of axes of a tree (W x Q of a 6-dof manipulator).
MAX_DIMENSION = 12
#: Default bound on the number of cells a construction may hold.
DEFAULT_MAX_LEAVES = 1 << 25
_FORMAT = "moveability.HyperTree"
_FORMAT_VERSION = 1

Classifier = Callable[[NDArray[np.float64], NDArray[np.float64]], ArrayLike]


class Leaves(NamedTuple):
    """The leaves of a tree as arrays: boxes ``[lo, hi]``, status and level."""

    lo: NDArray[np.float64]
    hi: NDArray[np.float64]
    status: NDArray[np.uint8]
    level: NDArray[np.uint8]


# ---------------------------------------------------------------- validation
def _as_box(lo: ArrayLike, hi: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    try:
        lo_a = np.atleast_1d(np.asarray(lo, dtype=np.float64))
        hi_a = np.atleast_1d(np.asarray(hi, dtype=np.float64))
    except (TypeError, ValueError):
        raise InvalidParameterError("lo/hi", "sequences of numbers", (lo, hi)) from None
    if lo_a.ndim != 1 or hi_a.ndim != 1 or lo_a.shape != hi_a.shape:
        raise InvalidParameterError(
            "lo/hi", "two 1-D sequences of the same length", (lo_a.shape, hi_a.shape)
        )
    if not 1 <= lo_a.size <= MAX_DIMENSION:
        raise InvalidParameterError("lo", f"between 1 and {MAX_DIMENSION} coordinates", lo_a.size)
    if not (np.isfinite(lo_a).all() and np.isfinite(hi_a).all()):
        raise InvalidParameterError("lo/hi", "finite numbers", (lo_a.tolist(), hi_a.tolist()))
    if not (lo_a < hi_a).all():
        bad = int(np.flatnonzero(lo_a >= hi_a)[0])
        raise InvalidParameterError(
            f"hi[{bad}]", f"a value greater than lo[{bad}]={lo_a[bad]!r}", float(hi_a[bad])
        )
    lo_a.setflags(write=False)
    hi_a.setflags(write=False)
    return lo_a, hi_a


def _as_max_depth(max_depth: int | Sequence[int], k: int) -> tuple[int, ...]:
    values = np.atleast_1d(np.asarray(max_depth))
    if values.dtype.kind not in "iu" or values.ndim != 1:
        raise InvalidParameterError("max_depth", "an int or one int per axis", max_depth)
    if values.size == 1:
        values = np.repeat(values, k)
    if values.size != k:
        raise InvalidParameterError("max_depth", f"an int or {k} ints (one per axis)", max_depth)
    if (values < 0).any():
        raise InvalidParameterError("max_depth", "non-negative depths", max_depth)
    if int(values.sum()) > 62:
        raise ResolutionError(
            "max_depth", "depths summing to at most 62 over the axes", tuple(values.tolist())
        )
    return tuple(int(v) for v in values)


def _as_periodic(periodic: Iterable[int], k: int) -> tuple[int, ...]:
    try:
        axes = sorted({int(a) for a in periodic})
    except (TypeError, ValueError):
        raise InvalidParameterError("periodic", "a sequence of axis numbers", periodic) from None
    if any(not 0 <= a < k for a in axes):
        raise InvalidParameterError("periodic", f"axis numbers in [0, {k - 1}]", periodic)
    return tuple(axes)


def _readonly(a: NDArray[Any]) -> NDArray[Any]:
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


class HyperTree:
    """An immutable k-dimensional 2^k-tree over an axis-aligned box.

    Use :meth:`build` (adaptive subdivision by a classifier) or
    :meth:`from_array` (from a grid of statuses) rather than the constructor.

    Parameters
    ----------
    lo, hi : array_like
        Corners of the box, ``k`` coordinates each.
    max_depth : tuple of int
        Maximal depth of each axis.
    keys, levels, status : array_like
        The leaves, sorted by key (see :mod:`moveability.hypertree.keys`).
    periodic : sequence of int
        Axes whose two ends are glued.

    Examples
    --------
    >>> import numpy as np
    >>> from moveability import HyperTree, IN, OUT, BOUNDARY, measure
    >>> def disk(lo, hi):
    ...     near = np.sqrt((np.clip(0.0, lo, hi) ** 2).sum(axis=1))
    ...     far = np.sqrt((np.maximum(abs(lo), abs(hi)) ** 2).sum(axis=1))
    ...     return np.where(far <= 1, IN, np.where(near > 1, OUT, BOUNDARY))
    >>> tree = HyperTree.build([-1, -1], [1, 1], disk, max_depth=6)
    >>> inner, outer = measure(tree)
    >>> bool(inner < np.pi < outer)
    True
    """

    __slots__ = ("_anchors", "_hi", "_keys", "_layout", "_levels", "_lo", "_periodic", "_status")

    def __init__(
        self,
        lo: ArrayLike,
        hi: ArrayLike,
        max_depth: int | Sequence[int],
        keys: ArrayLike,
        levels: ArrayLike,
        status: ArrayLike,
        periodic: Iterable[int] = (),
    ) -> None:
        self._lo, self._hi = _as_box(lo, hi)
        k = self._lo.size
        self._layout = KeyLayout(_as_max_depth(max_depth, k))
        self._periodic = _as_periodic(periodic, k)
        keys_a = np.asarray(keys, dtype=np.uint64).ravel()
        levels_a = np.asarray(levels, dtype=np.uint8).ravel()
        status_a = np.asarray(status, dtype=np.uint8).ravel()
        if not keys_a.size == levels_a.size == status_a.size:
            raise InvalidParameterError(
                "keys/levels/status",
                "arrays of one length",
                (keys_a.size, levels_a.size, status_a.size),
            )
        if not is_valid_status(status_a).all():
            raise InvalidParameterError("status", "values IN, OUT or BOUNDARY", status_a)
        self._keys = _readonly(keys_a)
        self._levels = _readonly(levels_a)
        self._status = _readonly(status_a)
        self._anchors: NDArray[np.int64] | None = None

    # ------------------------------------------------------------ construction
    @classmethod
    def build(
        cls,
        lo: ArrayLike,
        hi: ArrayLike,
        classify: Classifier,
        *,
        max_depth: int | Sequence[int],
        periodic: Iterable[int] = (),
        max_leaves: int = DEFAULT_MAX_LEAVES,
        merge: bool = True,
        progress: Progress | None = None,
        stop_level: int | None = None,
    ) -> HyperTree:
        """Build a tree by adaptive subdivision of the box ``[lo, hi]``.

        Parameters
        ----------
        lo, hi : array_like
            Corners of the box, ``k`` coordinates each, ``1 <= k <= 12``.
        classify : callable
            ``classify(cell_lo, cell_hi)`` receives two (n, k) float arrays, the
            closed boxes of ``n`` cells, and returns ``n`` statuses: ``IN`` if the
            whole box is in the set, ``OUT`` if no point of it is, ``BOUNDARY``
            otherwise (or when it cannot tell).
        max_depth : int or sequence of int
            Maximal depth, for all axes or one per axis. Axis ``i`` is cut into
            at most ``2 ** max_depth[i]`` cells.
        periodic : sequence of int, optional
            Axes whose two ends are glued (an unlimited revolute joint).
        max_leaves : int, optional
            Fail with :class:`~moveability.ResolutionError` rather than hold more
            cells than this.
        merge : bool, optional
            Merge complete groups of IN (or OUT) siblings into their parent.
        progress : callable, optional
            Called as ``progress(level, n_split, n_leaves)`` after each level.
        stop_level : int, optional
            Split no cell of this level or deeper; the levels beyond
            (up to ``max_depth``) are reached by :meth:`refine` only.

        Returns
        -------
        HyperTree

        Notes
        -----
        The work is proportional to the number of cells classified, which
        follows the boundary of the set: only BOUNDARY cells are split.

        Examples
        --------
        >>> import numpy as np
        >>> from moveability import HyperTree, IN, OUT, BOUNDARY
        >>> def right_half(lo, hi):
        ...     return np.where(lo[:, 0] >= 0, IN, np.where(hi[:, 0] <= 0, OUT, BOUNDARY))
        >>> tree = HyperTree.build([-1, -1], [1, 1], right_half, max_depth=4)
        >>> len(tree), tree.status.tolist()
        (4, [2, 2, 1, 1])
        """
        lo_a, hi_a = _as_box(lo, hi)
        k = lo_a.size
        layout = KeyLayout(_as_max_depth(max_depth, k))
        periodic_t = _as_periodic(periodic, k)
        if not callable(classify):
            raise InvalidParameterError("classify", "a callable", classify)
        if int(max_leaves) < 1:
            raise InvalidParameterError("max_leaves", "a positive int", max_leaves)

        def decide(
            keys: NDArray[np.uint64], anchors: NDArray[np.int64], level: int
        ) -> NDArray[np.uint8]:
            cell_lo, cell_hi = cell_corners(
                lo_a, hi_a, layout, anchors, np.full(1, level, dtype=np.uint8)
            )
            result = np.asarray(classify(cell_lo, cell_hi))
            if result.shape != (keys.size,) or result.dtype.kind not in "iub":
                raise InvalidParameterError(
                    "classify",
                    f"a function returning {keys.size} integer statuses",
                    f"an array of shape {result.shape} and dtype {result.dtype}",
                )
            result = result.astype(np.int64)
            if not is_valid_status(result).all():
                bad = result[~is_valid_status(result)]
                raise InvalidParameterError(
                    "classify", "statuses IN (1), OUT (2) or BOUNDARY (4)", np.unique(bad)
                )
            return result.astype(np.uint8)

        keys, levels, status = subdivide(
            layout, decide, max_leaves=int(max_leaves), progress=progress, stop_level=stop_level
        )
        if merge:
            keys, levels, status = merge_siblings(layout, keys, levels, status)
        return cls(lo_a, hi_a, layout.max_depth, keys, levels, status, periodic_t)

    def refine(self, mask: ArrayLike, classify: Classifier) -> HyperTree:
        """A tree whose selected leaves are split once, their children classified.

        Leaves already at the maximal level stay as they are. ``classify``
        receives the children's boxes in key order (the order they take among
        the leaves of the new tree). Nothing is merged.

        Examples
        --------
        >>> import numpy as np
        >>> from moveability import HyperTree, IN, BOUNDARY
        >>> tree = HyperTree.build([0, 0], [1, 1], lambda lo, hi: np.full(len(lo), BOUNDARY),
        ...                        max_depth=3, stop_level=1)
        >>> finer = tree.refine([True, False, False, False], lambda lo, hi: np.full(len(lo), IN))
        >>> len(tree), len(finer), finer.levels.tolist()
        (4, 7, [2, 2, 2, 2, 1, 1, 1])
        """
        m = np.asarray(mask, dtype=bool)
        if m.shape != (len(self),):
            raise InvalidParameterError("mask", f"{len(self)} booleans", m.shape)
        split = m & (self._levels < self._layout.n_levels)
        if not split.any():
            return self
        keys, levels, anchors = split_leaves(
            self._layout, self._keys[split], self._levels[split], self.anchors[split]
        )
        cell_lo, cell_hi = cell_corners(self._lo, self._hi, self._layout, anchors, levels)
        status = np.asarray(classify(cell_lo, cell_hi))
        if status.shape != (keys.size,) or not is_valid_status(status.astype(np.int64)).all():
            raise InvalidParameterError(
                "classify", f"a function returning {keys.size} statuses", status.shape
            )
        all_keys = np.concatenate([self._keys[~split], keys])
        order = np.argsort(all_keys, kind="stable")
        return HyperTree(
            self._lo,
            self._hi,
            self.max_depth,
            all_keys[order],
            np.concatenate([self._levels[~split], levels])[order],
            np.concatenate([self._status[~split], status.astype(np.uint8)])[order],
            self._periodic,
        )

    @classmethod
    def from_array(
        cls,
        values: ArrayLike,
        lo: ArrayLike | None = None,
        hi: ArrayLike | None = None,
        *,
        periodic: Iterable[int] = (),
        merge: bool = True,
    ) -> HyperTree:
        """A tree whose finest cells are the cells of a k-dimensional grid.

        Parameters
        ----------
        values : array_like
            Boolean grid (True is IN) or grid of statuses; every side a power of two.
        lo, hi : array_like, optional
            Box of the grid; by default ``0`` and the shape (one unit per cell).
        periodic : sequence of int, optional
            Axes whose two ends are glued.
        merge : bool, optional
            Merge complete groups of IN (or OUT) siblings into their parent.

        Examples
        --------
        >>> import numpy as np
        >>> from moveability import HyperTree
        >>> grid = np.zeros((4, 4), dtype=bool)
        >>> grid[:2, :2] = True
        >>> tree = HyperTree.from_array(grid)
        >>> len(tree), tree.levels.tolist()
        (4, [1, 1, 1, 1])
        """
        v = np.asarray(values)
        if v.dtype == bool:
            v = np.where(v, int(IN), int(OUT))
        if v.ndim < 1 or v.ndim > MAX_DIMENSION or v.size == 0:
            raise InvalidParameterError(
                "values", f"a non-empty array of 1 to {MAX_DIMENSION} dimensions", v.shape
            )
        sides = np.asarray(v.shape)
        depths = np.log2(sides).astype(np.int64)
        if not (1 << depths == sides).all():
            raise InvalidParameterError("values", "sides that are powers of two", v.shape)
        if v.dtype.kind not in "iu" or not is_valid_status(v.astype(np.int64)).all():
            raise InvalidParameterError(
                "values", "booleans or statuses IN, OUT, BOUNDARY", np.unique(v)
            )
        lo_v = np.zeros(v.ndim) if lo is None else lo
        hi_v = sides.astype(np.float64) if hi is None else hi
        layout = KeyLayout(_as_max_depth(tuple(depths.tolist()), v.ndim))
        anchors = np.indices(v.shape).reshape(v.ndim, -1).T
        keys = layout.encode(anchors)
        order = np.argsort(keys, kind="stable")
        keys = keys[order]
        status = v.reshape(-1)[order].astype(np.uint8)
        levels = np.full(keys.size, layout.n_levels, dtype=np.uint8)
        if merge:
            keys, levels, status = merge_siblings(layout, keys, levels, status)
        return cls(lo_v, hi_v, layout.max_depth, keys, levels, status, periodic)

    # ---------------------------------------------------------------- access
    @property
    def ndim(self) -> int:
        """Number of axes ``k``."""
        return int(self._lo.size)

    @property
    def lo(self) -> NDArray[np.float64]:
        """Lower corner of the box."""
        return self._lo

    @property
    def hi(self) -> NDArray[np.float64]:
        """Upper corner of the box."""
        return self._hi

    @property
    def max_depth(self) -> tuple[int, ...]:
        """Maximal depth of each axis."""
        return self._layout.max_depth

    @property
    def periodic(self) -> tuple[int, ...]:
        """Axes whose ends are glued, sorted."""
        return self._periodic

    @property
    def layout(self) -> KeyLayout:
        """Bit layout of the keys."""
        return self._layout

    @property
    def keys(self) -> NDArray[np.uint64]:
        """Key of each leaf (sorted)."""
        return self._keys

    @property
    def levels(self) -> NDArray[np.uint8]:
        """Level of each leaf."""
        return self._levels

    @property
    def status(self) -> NDArray[np.uint8]:
        """Status of each leaf."""
        return self._status

    @property
    def anchors(self) -> NDArray[np.int64]:
        """Lower corner of each leaf in finest units of each axis, shape (n, k)."""
        if self._anchors is None:
            self._anchors = _readonly(self._layout.decode(self._keys))
        return self._anchors

    def __len__(self) -> int:
        return int(self._keys.size)

    def leaves(self) -> Leaves:
        """Boxes, statuses and levels of the leaves, in key order.

        Examples
        --------
        >>> import numpy as np
        >>> from moveability import HyperTree
        >>> tree = HyperTree.from_array(np.array([True, False]), [0.0], [1.0])
        >>> leaves = tree.leaves()
        >>> leaves.lo.tolist(), leaves.hi.tolist(), leaves.status.tolist()
        ([[0.0], [0.5]], [[0.5], [1.0]], [1, 2])
        """
        lo, hi = cell_corners(self._lo, self._hi, self._layout, self.anchors, self._levels)
        return Leaves(lo, hi, self._status, self._levels)

    def cell_widths(self) -> NDArray[np.float64]:
        """Width of each leaf along each axis, shape (n, k)."""
        depths = self._layout.axis_depths(self._levels)
        return (self._hi - self._lo)[None, :] / np.exp2(depths)

    def counts(self) -> dict[str, int]:
        """Number of leaves of each status."""
        return {
            name: int(np.count_nonzero(self._status == value))
            for name, value in (("IN", IN), ("OUT", OUT), ("BOUNDARY", BOUNDARY))
        }

    def select(self, mask: ArrayLike) -> HyperTree:
        """A tree with the same leaves, those not chosen set OUT.

        Parameters
        ----------
        mask : array_like
            Boolean mask over the leaves, or leaf indices.

        Examples
        --------
        >>> import numpy as np
        >>> from moveability import HyperTree
        >>> tree = HyperTree.from_array(np.array([True, True]), merge=False)
        >>> tree.select([False, True]).status.tolist()
        [2, 1]
        """
        m = np.asarray(mask)
        if m.dtype == bool:
            if m.shape != self._keys.shape:
                raise InvalidParameterError("mask", f"{len(self)} booleans", m.shape)
            chosen = m
        else:
            if m.dtype.kind not in "iu" or m.ndim != 1:
                raise InvalidParameterError("mask", "booleans or leaf indices", m)
            if m.size and (m.min() < -len(self) or m.max() >= len(self)):
                raise InvalidParameterError("mask", f"indices below {len(self)}", m)
            chosen = np.zeros(len(self), dtype=bool)
            chosen[m] = True
        status = np.where(chosen, self._status, np.uint8(OUT)).astype(np.uint8)
        return self._replace(status=status)

    def _replace(self, **arrays: Any) -> HyperTree:
        new = HyperTree(
            self._lo,
            self._hi,
            self.max_depth,
            arrays.get("keys", self._keys),
            arrays.get("levels", self._levels),
            arrays.get("status", self._status),
            self._periodic,
        )
        if "keys" not in arrays:
            new._anchors = self._anchors
        return new

    # ------------------------------------------------------------- operators
    def __or__(self, other: HyperTree) -> HyperTree:
        from .setops import union

        return union(self, other)

    def __and__(self, other: HyperTree) -> HyperTree:
        from .setops import intersection

        return intersection(self, other)

    def __sub__(self, other: HyperTree) -> HyperTree:
        from .setops import difference

        return difference(self, other)

    def __invert__(self) -> HyperTree:
        from .setops import complement

        return complement(self)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, HyperTree):
            return NotImplemented
        from .setops import equals

        return equals(self, other)

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        c = self.counts()
        return (
            f"HyperTree(ndim={self.ndim}, leaves={len(self)}, IN={c['IN']}, "
            f"BOUNDARY={c['BOUNDARY']}, OUT={c['OUT']}, max_depth={self.max_depth}, "
            f"periodic={self.periodic})"
        )

    # ------------------------------------------------------------ persistence
    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the tree to a ``.npz`` file (see :func:`load`)."""
        np.savez_compressed(
            path,
            format=np.array(_FORMAT),
            version=np.array(_FORMAT_VERSION),
            lo=self._lo,
            hi=self._hi,
            max_depth=np.asarray(self.max_depth, dtype=np.int64),
            periodic=np.asarray(self._periodic, dtype=np.int64),
            keys=self._keys,
            levels=self._levels,
            status=self._status,
        )

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> HyperTree:
        """Read a tree written by :meth:`save`."""
        return load(path)


def load(path: str | os.PathLike[str]) -> HyperTree:
    """Read a tree written by :meth:`HyperTree.save`.

    Examples
    --------
    >>> import numpy as np, tempfile, os
    >>> from moveability import HyperTree, load
    >>> tree = HyperTree.from_array(np.eye(4, dtype=bool))
    >>> path = os.path.join(tempfile.mkdtemp(), "tree.npz")
    >>> tree.save(path)
    >>> bool(load(path) == tree)
    True
    """
    fields = read_archive(path, "a .npz file written by HyperTree.save")
    needed = ("format", "version", "lo", "hi", "max_depth", "periodic", "keys", "levels", "status")
    missing = [name for name in needed if name not in fields]
    if missing or str(fields["format"]) != _FORMAT:
        raise InvalidParameterError(
            "path",
            "a .npz file written by HyperTree.save",
            f"{os.fspath(path)} (missing {missing})",
        )
    if int(fields["version"]) != _FORMAT_VERSION:
        raise InvalidParameterError(
            "path", f"format version {_FORMAT_VERSION}", int(fields["version"])
        )
    tree = HyperTree(
        fields["lo"],
        fields["hi"],
        tuple(int(v) for v in fields["max_depth"]),
        fields["keys"],
        fields["levels"],
        fields["status"],
        tuple(int(v) for v in fields["periodic"]),
    )
    _check_partition(tree, os.fspath(path))
    return tree


def read_archive(path: str | os.PathLike[str], what: str) -> dict[str, Any]:
    """The arrays of a ``.npz`` archive; bad or missing files raise an error naming ``path``."""
    try:
        # open the file here: np.load leaves it open when the archive is corrupt
        with open(path, "rb") as handle:
            data = np.load(handle, allow_pickle=False)
            if not hasattr(data, "files"):  # a .npy array, not an archive
                raise ValueError("not an .npz archive")
            with data:
                return {name: data[name] for name in data.files}
    except FileNotFoundError:
        raise InvalidParameterError("path", "an existing .npz file", os.fspath(path)) from None
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
        raise InvalidParameterError("path", what, f"{os.fspath(path)} ({exc})") from None


def _check_partition(tree: HyperTree, where: str) -> None:
    """Raise unless the leaves are sorted, aligned and tile the box exactly."""
    layout = tree.layout
    keys, levels = tree.keys, tree.levels
    if keys.size == 0 or (levels > layout.n_levels).any():
        raise InvalidParameterError("path", "leaves tiling the box", where)
    spans = layout.spans(levels)
    ends = keys + spans
    ok = (
        keys[0] == 0
        and bool((keys[1:] == ends[:-1]).all())
        and int(ends[-1]) == layout.span(0)
        and bool(((keys & (spans - np.uint64(1))) == 0).all())
    )
    if not ok:
        raise InvalidParameterError("path", "leaves tiling the box", where)


def to_coordinates(
    lo: NDArray[np.float64],
    hi: NDArray[np.float64],
    layout: KeyLayout,
    ints: NDArray[np.int64],
) -> NDArray[np.float64]:
    """Coordinates of finest-grid positions; the top position maps exactly to ``hi``.

    Every cell face is computed from the same integer by the same expression,
    so adjacent cells share their faces exactly.
    """
    inv_res = np.exp2(-np.asarray(layout.max_depth, dtype=np.float64))
    # (hi - lo) * inv_res is exact (a power-of-two scaling), so each coordinate
    # is one rounding of the exact value
    x = np.array(ints, dtype=np.float64)
    x *= (hi - lo) * inv_res
    x += lo
    top = ints >= np.left_shift(1, np.asarray(layout.max_depth, dtype=np.int64))
    if top.any():
        x[top] = np.broadcast_to(hi, x.shape)[top]
    return x


def cell_corners(
    lo: NDArray[np.float64],
    hi: NDArray[np.float64],
    layout: KeyLayout,
    anchors: NDArray[np.int64],
    levels: NDArray[np.integer],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Both corners of cells, shape (n, k) each: :func:`to_coordinates` of their
    anchors and of their anchors plus their sizes (``levels``: one per cell, or
    one for all), the same floats, in one compiled pass.

    Examples
    --------
    >>> import numpy as np
    >>> layout = KeyLayout((2, 1))
    >>> lo, hi = np.array([0.0, -1.0]), np.array([1.0, 1.0])
    >>> a, b = cell_corners(lo, hi, layout, np.array([[1, 0], [2, 1]]), np.array([2, 1]))
    >>> a.tolist(), b.tolist()
    ([[0.25, -1.0], [0.5, 0.0]], [[0.5, 0.0], [1.0, 1.0]])
    """
    depths = np.asarray(layout.max_depth, dtype=np.int64)
    inv_res = np.exp2(-np.asarray(layout.max_depth, dtype=np.float64))
    # as to_coordinates scales: (hi - lo) * inv_res, exact
    step = np.ascontiguousarray((hi - lo) * inv_res, dtype=np.float64)
    return _boxes.cell_boxes(
        np.ascontiguousarray(anchors, dtype=np.int64).reshape(-1, layout.ndim),
        np.ascontiguousarray(levels, dtype=np.uint8).reshape(-1),
        depths,
        np.ascontiguousarray(lo, dtype=np.float64),
        np.ascontiguousarray(hi, dtype=np.float64),
        step,
    )
