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

__all__ = [
    "EXCLUDED",
    "FONT",
    "PALETTE",
    "UNDECIDED",
    "draw_cells",
    "figure_of",
    "frame_axes",
    "mix_colors",
    "opaque_legend",
    "panels",
    "precision_text",
    "pyplot",
    "significant",
    "style_axes",
]

#: Okabe-Ito colours
PALETTE = ("#0072B2", "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#D55E00", "#F0E442", "#000000")
UNDECIDED = "#BBBBBB"
#: configurations that a constraint beyond the paper excludes (a passive joint
#: limit, an obstacle, a link collision): a pale rose, apart from the palette and grey
EXCLUDED = "#F2C9C0"
#: font sizes (points) shared by the figures of :mod:`moveability.output.plot`
FONT = {"suptitle": 11.0, "title": 9.5, "label": 9.0, "tick": 8.0, "legend": 8.0}


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


def panels(n: int, max_cols: int, size: float, aspect: float | None = None) -> list[Axes]:
    """A grid of ``n`` panels (at most ``max_cols`` per row), as a flat list of axes.

    Panels are ``size`` inches wide and as high by default. Given ``aspect`` (the
    height over the width of what a panel shows), they are that much high plus
    room for a title, and the figure uses matplotlib's constrained layout, so
    that labels of one panel never run over the next.
    """
    cols = min(n, max_cols)
    rows = int(np.ceil(n / cols))
    if aspect is None:
        _, grid = pyplot().subplots(rows, cols, figsize=(size * cols, size * rows), squeeze=False)
    else:
        height = size * min(max(aspect, 0.2), 2.0) + 0.9
        _, grid = pyplot().subplots(
            rows, cols, figsize=(size * cols, height * rows), squeeze=False, layout="constrained"
        )
    return list(grid.ravel())


def style_axes(ax: Axes) -> None:
    """The font sizes of :data:`FONT` on an axes' title, labels and ticks."""
    ax.tick_params(labelsize=FONT["tick"])
    ax.xaxis.label.set_fontsize(FONT["label"])
    ax.yaxis.label.set_fontsize(FONT["label"])
    ax.title.set_fontsize(FONT["title"])


def opaque_legend(where: Any, handles: list[Any], **kwargs: Any) -> Any:
    """A legend on an axes or a figure with an opaque frame: a see-through frame
    over certified cells would make them look undecided."""
    kwargs.setdefault("fontsize", FONT["legend"])
    kwargs.setdefault("title_fontsize", FONT["legend"])
    legend = where.legend(handles=handles, framealpha=1.0, **kwargs)
    legend.get_frame().set_edgecolor("#888888")
    return legend


def mix_colors(colors: list[Any]) -> tuple[float, float, float]:
    """The mean of some colours in RGB: the colour of a place several sets share."""
    from matplotlib.colors import to_rgb

    rgb = np.mean([to_rgb(c) for c in colors], axis=0)
    return float(rgb[0]), float(rgb[1]), float(rgb[2])


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
    draw_obstacles(ax, mechanism)


def draw_obstacles(ax: Axes, mechanism: Mechanism) -> None:
    """The mechanism's obstacles (``[[obstacles]]``), hatched, over the data."""
    from matplotlib.patches import Circle

    for obstacle in mechanism.restrictions.obstacles:
        ax.add_patch(
            Circle(
                obstacle.center, obstacle.radius, facecolor="#dddddd", edgecolor="black",
                hatch="///", linewidth=1.0, zorder=5,
            )
        )  # fmt: skip
        ax.annotate("obstacle", obstacle.center, ha="center", va="center", fontsize=7, zorder=6)


def significant(value: float, digits: int = 3, direction: int = 0) -> str:
    """``value`` with at most ``digits`` significant digits, in fixed notation.

    ``direction`` -1 rounds down, +1 up (the ends of an enclosure, rounded outwards).

    Examples
    --------
    >>> [significant(v) for v in (0.0349066, 156.748, 2.90506, -3.0, 1234.5)]
    ['0.0349', '157', '2.91', '-3', '1230']
    >>> significant(42.531, direction=-1), significant(43.250, direction=1)
    ('42.5', '43.3')
    """
    v = float(value)
    if not np.isfinite(v):
        return str(v)
    if v == 0.0:
        return "0"
    decimals = digits - 1 - int(np.floor(np.log10(abs(v))))
    scale = 10.0**decimals
    if direction < 0:
        r = np.floor(v * scale) / scale
    elif direction > 0:
        r = np.ceil(v * scale) / scale
    else:
        r = np.round(v * scale) / scale
    if r == 0.0:
        return "0"
    text = f"{r:.{max(decimals, 0)}f}"
    return text.rstrip("0").rstrip(".") if "." in text else text


def precision_text(result: Any) -> str:
    """An analysis' precision for a title, as it was given (one value, or one per
    axis), three significant digits each."""
    values = np.atleast_1d(result.precision)
    return ", ".join(significant(v) for v in values)
