"""The map of a sweep over two varied names: number of regions, N-connected designs marked.

matplotlib is imported inside :func:`plot_sweep_map` only.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError
from ..extras import require
from .designs import varied_unit
from .table import RESULT_COLUMNS, read_table

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["map_axes", "map_grid", "plot_sweep_map"]

#: codes of the cells of a map that hold no number of regions
UNKNOWN, FAILED, MISSING = -1, -2, -3

# Okabe-Ito colours for 1, 2, 3, ... regions (0 regions: white)
_COUNT_COLOURS = ("#56B4E9", "#0072B2", "#009E73", "#E69F00", "#CC79A7", "#D55E00", "#F0E442")
_UNKNOWN_COLOUR = "#BBBBBB"
_FAILED_COLOUR = "#000000"

Table = tuple[Sequence[str], Sequence[Mapping[str, Any]]]


def _varied(columns: Sequence[str]) -> list[str]:
    return list(columns[: len(columns) - len(RESULT_COLUMNS)])


def map_axes(columns: Sequence[str], rows: Sequence[Mapping[str, Any]]) -> tuple[str, str]:
    """The two varied names that take more than one value in the table.

    Raises
    ------
    moveability.errors.InvalidParameterError
        Named ``--figure`` unless exactly two varied names take several values.

    Examples
    --------
    >>> cols = ["L1", "L2", "theta1.max", *RESULT_COLUMNS]
    >>> rows = [{"L1": 8.0, "L2": a, "theta1.max": b} for a in (4.0, 5.0) for b in (1.0, 2.0)]
    >>> map_axes(cols, rows)
    ('L2', 'theta1.max')
    """
    several = [name for name in _varied(columns) if len({row[name] for row in rows}) > 1]
    if len(several) != 2:
        raise InvalidParameterError(
            "--figure",
            "a sweep in which exactly two varied names take several values",
            ", ".join(several) or "none",
        )
    return several[0], several[1]


def map_grid(
    columns: Sequence[str], rows: Sequence[Mapping[str, Any]], x: str, y: str
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64], NDArray[np.bool_]]:
    """The map's data: x values, y values, codes (ny, nx) and N-connected mask (ny, nx).

    A code is the number of regions, or :data:`UNKNOWN` (regions not resolved
    at the precision), :data:`FAILED` (the design's error) or :data:`MISSING`
    (no row yet).

    Examples
    --------
    >>> cols = ["L2", "theta1.max", *RESULT_COLUMNS]
    >>> rows = [{"L2": 4.0, "theta1.max": 1.0, "regions": 2, "n_connected": True},
    ...         {"L2": 5.0, "theta1.max": 1.0, "regions": None, "error": "failed"}]
    >>> xs, ys, codes, connected = map_grid(cols, rows, "L2", "theta1.max")
    >>> codes.tolist(), connected.tolist()
    ([[2, -2]], [[True, False]])
    """
    varied = _varied(columns)
    for name, axis in ((x, "x"), (y, "y")):
        if name not in varied:
            raise InvalidParameterError(axis, "a varied name: " + ", ".join(varied), name)
    if x == y:
        raise InvalidParameterError("y", "a varied name other than x", y)
    for other in varied:
        if other not in (x, y) and len({row[other] for row in rows}) > 1:
            raise InvalidParameterError(
                "--figure", f"a sweep where only {x} and {y} take several values", other
            )
    xs = np.array(sorted({float(row[x]) for row in rows}), dtype=np.float64)
    ys = np.array(sorted({float(row[y]) for row in rows}), dtype=np.float64)
    codes = np.full((ys.size, xs.size), MISSING, dtype=np.int64)
    connected = np.zeros((ys.size, xs.size), dtype=bool)
    for row in rows:
        i = int(np.searchsorted(ys, float(row[y])))
        j = int(np.searchsorted(xs, float(row[x])))
        if row.get("error"):
            codes[i, j] = FAILED
        elif row.get("regions") is None:
            codes[i, j] = UNKNOWN
        else:
            codes[i, j] = int(row["regions"])
        connected[i, j] = row.get("n_connected") is True
    return xs, ys, codes, connected


def _edges(values: NDArray[np.float64]) -> NDArray[np.float64]:
    """Cell edges around sorted centres: midpoints inside, half steps outside."""
    if values.size == 1:
        half = 0.5 * max(abs(float(values[0])) * 0.1, 1e-3)
        return np.array([values[0] - half, values[0] + half])
    mid = 0.5 * (values[1:] + values[:-1])
    return np.concatenate([[2 * values[0] - mid[0]], mid, [2 * values[-1] - mid[-1]]])


def _label(name: str) -> str:
    unit = varied_unit(name)
    return f"{name} ({'length units of the spec' if unit == 'length' else unit})"


def plot_sweep_map(
    table: str | os.PathLike[str] | Table,
    x: str | None = None,
    y: str | None = None,
    ax: Axes | None = None,
) -> Figure:
    """Map the number of regions over two varied names; N-connected designs are starred.

    Parameters
    ----------
    table : path or (columns, rows)
        A sweep table (CSV or Parquet), or what :func:`~moveability.sweep.read_table` returns.
    x, y : str, optional
        The varied names along the axes; by default the two that take several values.
    ax : matplotlib Axes, optional
        Where to draw; a new figure otherwise.

    Returns
    -------
    matplotlib.figure.Figure

    Notes
    -----
    Each design is a cell coloured by its number of regions; cells whose
    regions are unknown at the precision are grey, failed designs are black
    with a white cross, designs not yet computed are left white. A star marks
    the designs whose workspace is certified N-connected.

    Examples
    --------
    >>> cols = ["L2", "theta1.max", *RESULT_COLUMNS]
    >>> rows = [{"L2": a, "theta1.max": b, "regions": 2, "n_connected": a > 4}
    ...         for a in (4.0, 5.0) for b in (1.0, 2.0)]
    >>> fig = plot_sweep_map((cols, rows))
    >>> fig.axes[0].get_xlabel()
    'L2 (length units of the spec)'
    """
    columns: Sequence[str]
    rows: Sequence[Mapping[str, Any]]
    if isinstance(table, str | os.PathLike):
        columns, rows = read_table(table, name="table")
    else:
        columns, rows = table
    if x is None or y is None:
        x, y = map_axes(columns, rows)
    xs, ys, codes, connected = map_grid(columns, rows, x, y)

    matplotlib = require("matplotlib", "plot", "the sweep figure")

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    if ax is None:
        fig, ax = plt.subplots(figsize=(7.5, 5.0))
    else:
        fig = ax.figure  # type: ignore[assignment]

    counts = sorted(int(c) for c in np.unique(codes) if c >= 0)
    categories: list[tuple[int, str, str]] = []  # (code, colour, label)
    for k in counts:
        colour = "#FFFFFF" if k == 0 else _COUNT_COLOURS[(k - 1) % len(_COUNT_COLOURS)]
        categories.append((k, colour, f"{k} region{'s' if k != 1 else ''}"))
    if (codes == UNKNOWN).any():
        categories.append((UNKNOWN, _UNKNOWN_COLOUR, "regions unknown at this precision"))
    if (codes == FAILED).any():
        categories.append((FAILED, _FAILED_COLOUR, "design failed (see error column)"))
    if (codes == MISSING).any():
        categories.append((MISSING, "#FFFFFF", "not computed"))
    index = np.zeros(codes.shape, dtype=np.int64)
    for i, (code, _, _) in enumerate(categories):
        index[codes == code] = i
    cmap = ListedColormap([colour for _, colour, _ in categories] or ["#FFFFFF"])
    ax.pcolormesh(
        _edges(xs),
        _edges(ys),
        index,
        cmap=cmap,
        vmin=-0.5,
        vmax=max(len(categories), 1) - 0.5,
        edgecolors="#FFFFFF",
        linewidth=0.5,
    )
    gx, gy = np.meshgrid(xs, ys)
    failed = codes == FAILED
    if failed.any():
        ax.scatter(gx[failed], gy[failed], marker="x", color="#FFFFFF", s=30, zorder=3)
    if connected.any():
        ax.scatter(
            gx[connected],
            gy[connected],
            marker="*",
            color="#000000",
            edgecolors="#FFFFFF",
            linewidths=0.5,
            s=90,
            zorder=3,
        )
    ax.set_xlabel(_label(x))
    ax.set_ylabel(_label(y))
    ax.set_title(f"Number of N-connected regions over {x} and {y}")
    handles: list[Any] = [
        Patch(facecolor=colour, edgecolor="#777777", label=label) for _, colour, label in categories
    ]
    handles.append(
        Line2D(
            [], [], marker="*", linestyle="", color="#000000", markersize=10, label="W N-connected"
        )
    )
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.02, 1.0), frameon=False)
    fig.tight_layout()
    return fig
