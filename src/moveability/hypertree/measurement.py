"""Measures and point queries on trees: :func:`measure` and :func:`locate`."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from .status import BOUNDARY, IN, OUT
from .tree import HyperTree, to_coordinates

__all__ = ["leaf_volumes", "locate", "measure"]


def leaf_volumes(tree: HyperTree) -> NDArray[np.float64]:
    """Volume (length, area, ...) of each leaf."""
    return np.prod(tree.cell_widths(), axis=1)


def measure(tree: HyperTree) -> tuple[float, float]:
    """Bounds on the volume of the set: ``(inner, outer)``.

    ``inner`` is the volume of the IN leaves, ``outer`` that of the IN and
    BOUNDARY leaves; the set's volume lies between them.

    Examples
    --------
    >>> import numpy as np
    >>> from moveability import HyperTree, measure, IN, OUT, BOUNDARY
    >>> grid = np.array([[IN, BOUNDARY], [OUT, OUT]])
    >>> measure(HyperTree.from_array(grid, [0, 0], [2, 2]))
    (1.0, 2.0)
    """
    volumes = leaf_volumes(tree)
    inner = float(volumes[tree.status == IN].sum())
    outer = inner + float(volumes[tree.status == BOUNDARY].sum())
    return inner, outer


def locate(tree: HyperTree, points: ArrayLike) -> tuple[NDArray[np.uint8], NDArray[np.intp]]:
    """Status at each point and the index of the leaf holding it.

    A point on a face shared by two leaves belongs to the upper one (cells are
    half-open, except at the top of the box). Points outside the box get
    ``OUT`` and leaf index ``-1``.

    Parameters
    ----------
    tree : HyperTree
    points : array_like
        Shape (m, k), or (k,) for one point.

    Returns
    -------
    status : ndarray of uint8, shape (m,)
    index : ndarray of intp, shape (m,)

    Examples
    --------
    >>> import numpy as np
    >>> from moveability import HyperTree, locate
    >>> tree = HyperTree.from_array(np.array([True, False]), [0.0], [1.0])
    >>> status, index = locate(tree, [[0.25], [0.75], [2.0]])
    >>> status.tolist(), index.tolist()
    ([1, 2, 2], [0, 1, -1])
    """
    try:
        p = np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError("points", "an array of numbers", points) from None
    if p.ndim == 1:
        p = p[None, :]
    if p.ndim != 2 or p.shape[1] != tree.ndim:
        raise InvalidParameterError("points", f"an array of shape (m, {tree.ndim})", p.shape)
    if not np.isfinite(p).all():
        bad = int(np.flatnonzero(~np.isfinite(p).all(axis=1))[0])
        raise InvalidParameterError(f"points[{bad}]", "finite coordinates", p[bad].tolist())
    layout = tree.layout
    lo, hi = tree.lo, tree.hi
    inside = ((p >= lo) & (p <= hi)).all(axis=1)
    res = np.left_shift(1, np.asarray(layout.max_depth, dtype=np.int64))
    q = p[inside]
    guess = np.floor((q - lo) / (hi - lo) * res).astype(np.int64)
    guess = np.clip(guess, 0, res - 1)
    # correct rounding against the exact cell faces used everywhere else
    below = to_coordinates(lo, hi, layout, guess) > q
    guess = np.where(below, guess - 1, guess)
    above = (to_coordinates(lo, hi, layout, guess + 1) <= q) & (guess + 1 < res)
    guess = np.clip(np.where(above, guess + 1, guess), 0, res - 1)
    keys = layout.encode(guess)
    index = np.full(p.shape[0], -1, dtype=np.intp)
    index[inside] = np.searchsorted(tree.keys, keys, side="right") - 1
    status = np.full(p.shape[0], int(OUT), dtype=np.uint8)
    status[inside] = tree.status[index[inside]]
    return status, index
