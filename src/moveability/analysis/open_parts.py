"""Where an analysis is still open: the connected parts of its open leaves.

When the refinement stops (its budget or its deepest level reached) with the
count or N-connectivity undecided, a designer needs to know *where* the
answer is missing, not only how much: a tiny part about one pose points at a
design that is degenerate there (a stop exactly at a singular configuration, a
stroke that just meets a leg's reach), a large one at a precision too coarse.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..hypertree._kernels import edge_components

__all__ = ["MAX_PARTS", "open_parts", "open_text"]

#: parts described one by one (the largest first); the others are only counted
MAX_PARTS = 8


def open_parts(
    lo: NDArray[np.float64],
    hi: NDArray[np.float64],
    measures: NDArray[np.float64],
    pairs: NDArray[np.intp],
    mask: NDArray[np.bool_],
    measure: str = "area",
    limit: int = MAX_PARTS,
) -> dict[str, Any]:
    """The open leaves (``mask``) grouped into parts of touching leaves.

    Parameters
    ----------
    lo, hi : (n, k) arrays
        The leaves' boxes.
    measures : (n,) array
        The leaves' areas (volumes).
    pairs : (m, 2) int array
        Touching leaves (by a face, an edge or a vertex).
    mask : (n,) bool
        The open leaves.
    measure : str
        The key of the measure in the parts (``area``, ``volume``).
    limit : int
        Parts described, the largest first.

    Returns
    -------
    dict
        ``{"parts": n_parts, measure: total, "largest": [{measure: m, "box":
        [lo, hi]}, ...]}``: the number of parts, their total measure, and the
        largest ``limit`` parts with their bounding boxes.

    Examples
    --------
    >>> import numpy as np
    >>> lo = np.array([[0.0, 0.0], [1.0, 0.0], [3.0, 3.0]])
    >>> hi = lo + 1.0
    >>> parts = open_parts(lo, hi, np.ones(3), np.array([[0, 1]]), np.ones(3, bool))
    >>> parts["parts"], parts["area"], parts["largest"][0]
    (2, 3.0, {'area': 2.0, 'box': [[0.0, 0.0], [2.0, 1.0]]})
    """
    index = np.flatnonzero(mask)
    total = float(measures[index].sum())
    if not index.size:
        return {"parts": 0, measure: total, "largest": []}
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    both = mask[pairs[:, 0]] & mask[pairs[:, 1]]
    every, n_parts = edge_components(mask.size, pairs[both], mask)
    labels = every[index]
    sizes = np.bincount(labels, weights=measures[index], minlength=n_parts)
    order = np.argsort(-sizes, kind="stable")[:limit]
    largest = []
    for part in order:
        rows = index[labels == part]
        box = [lo[rows].min(axis=0).tolist(), hi[rows].max(axis=0).tolist()]
        largest.append({measure: float(sizes[part]), "box": box})
    return {"parts": int(n_parts), measure: total, "largest": largest}


def open_text(parts: dict[str, Any], pose: tuple[str, ...] | list[str], measure: str) -> str:
    """One line for people: how much is still open and where the largest part
    lies (empty when nothing is open).

    Examples
    --------
    >>> parts = {"parts": 2, "area": 0.5, "largest": [
    ...     {"area": 0.4, "box": [[1.0, 2.0], [1.5, 2.25]]}]}
    >>> open_text(parts, ("x", "y"), "area")
    'still open: 0.5 of area in 2 part(s); the largest (0.4) in x [1, 1.5], y [2, 2.25]'
    """
    if not parts.get("parts"):
        return ""
    text = f"still open: {parts[measure]:.6g} of {measure} in {parts['parts']} part(s)"
    if parts["largest"]:
        first = parts["largest"][0]
        lo, hi = first["box"]
        where = ", ".join(
            f"{name} [{a:.6g}, {b:.6g}]" for name, a, b in zip(pose, lo, hi, strict=True)
        )
        text += f"; the largest ({first[measure]:.6g}) in {where}"
    return text
