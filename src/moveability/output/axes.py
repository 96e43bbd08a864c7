"""What every figure shares: pyplot imported when first drawn, the palette, panels
of axes, boxes filled as one collection and the pose box framed and labelled."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, cast

import numpy as np

from ..extras import require
from ..types import Array

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from ..mechanisms.base import Mechanism

__all__ = ["PALETTE", "UNDECIDED", "draw_cells", "figure_of", "frame_axes", "panels", "pyplot"]

#: Okabe-Ito colours
PALETTE = ("#0072B2", "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#D55E00", "#F0E442", "#000000")
UNDECIDED = "#BBBBBB"


def pyplot() -> Any:
    """matplotlib's pyplot, imported when a figure is first drawn (the Agg backend
    unless one was chosen); a missing ``plot`` extra is one line."""
    matplotlib = require("matplotlib", "plot", "figures")

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt


def figure_of(ax: Axes) -> Figure:
    """The figure that holds ``ax``."""
    return cast("Figure", ax.figure)


def panels(n: int, max_cols: int, size: float) -> list[Axes]:
    """A grid of ``n`` panels (at most ``max_cols`` per row), as a flat list of axes."""
    cols = min(n, max_cols)
    rows = int(np.ceil(n / cols))
    _, grid = pyplot().subplots(rows, cols, figsize=(size * cols, size * rows), squeeze=False)
    return list(grid.ravel())


def draw_cells(
    ax: Axes, lo: Array, hi: Array, color: Any, label: str | None = None, alpha: float = 1.0
) -> Any:
    """Fill the boxes ``[lo, hi]`` (first two axes) as one collection; returns it."""
    from matplotlib.collections import PolyCollection

    verts = np.stack([lo, np.c_[hi[:, 0], lo[:, 1]], hi, np.c_[lo[:, 0], hi[:, 1]]], axis=1)
    coll = PolyCollection(
        list(verts), facecolors=color, edgecolors="none", alpha=alpha, label=label
    )
    ax.add_collection(coll)
    return coll


def frame_axes(ax: Axes, mechanism: Mechanism, title: str) -> None:
    """Limits of the pose box, equal aspect, labelled pose axes and a title."""
    lo, hi = mechanism.bounds
    names = mechanism.pose_names
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    ax.set_xlabel(f"{names[0]} (length units)")
    ax.set_ylabel(f"{names[1]} (length units)")
    ax.set_title(title)
