"""Figures of an analysis with three pose axes (x, y, phi), or (x, y, z) for a
translational mechanism such as the Delta: slices and a 3-D view.

With three pose axes the regions are solids. :func:`plot_slices` cuts them at
chosen values of the third axis (an orientation, or a height) and draws the
(x, y) slices;
:func:`plot_regions_3d` draws the outer surface of each region's certified
part, found by :func:`moveability.hypertree.topology.boundary_faces`. Colours and legends follow
:mod:`moveability.output.plot`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from ..hypertree.status import BOUNDARY, OUT
from ..hypertree.topology import boundary_faces
from ..types import Array
from .axes import (
    PALETTE,
    UNDECIDED,
    draw_cells,
    figure_of,
    frame_axes,
    opaque_legend,
    panels,
    precision_text,
    pyplot,
    significant,
)

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from ..analysis.result import Analysis

__all__ = ["DEFAULT_PHIS", "MAX_FACES", "plot_regions_3d", "plot_slices"]

#: angles of the slices drawn by default (radians): -135, -45, 45 and 135 degrees
DEFAULT_PHIS = tuple(float(v) for v in np.radians([-135.0, -45.0, 45.0, 135.0]))
#: most faces drawn by :func:`plot_regions_3d` over all regions
MAX_FACES = 20000


def _check_3d(result: Analysis, name: str) -> None:
    if result.tree.ndim != 3:
        raise InvalidParameterError(
            "figure", "an analysis with 3 pose axes", f"{name} of {result.tree.ndim} pose axes"
        )


def _sign(sign: int) -> str:
    return ">" if sign > 0 else "<"


def _region_label(result: Analysis, index: int) -> str:
    region = result.regions[index]
    return (
        f"region {region.id}: det A {_sign(region.sign)} 0, {result.measure_name} in "
        f"[{region.area[0]:.3g}, {region.area[1]:.3g}]"
    )


def _angle_text(mechanism: Any, axis: int, value: float) -> str:
    """A slice's title: a periodic angle in degrees, a length (the Delta's height)
    with three significant digits, as the other titles give numbers."""
    name = mechanism.pose_names[axis]
    if axis in mechanism.periodic_axes:
        return f"{name} = {np.degrees(value):.4g}\N{DEGREE SIGN}"
    return f"{name} = {significant(value)}"


# ------------------------------------------------------------------- slices
def _wrap(result: Analysis, value: float) -> float:
    axis = 2
    if axis in result.mechanism.periodic_axes:
        pose = np.zeros((1, 3))
        pose[0, axis] = value
        return float(result.mechanism.wrap_poses(pose)[0, axis])
    return float(value)


def _default_cuts(result: Analysis) -> Array:
    """Four values of the third axis: the default angles when it is periodic, else
    the heights that cut the volume of the leaves that may hold W at 1/8, 3/8, 5/8
    and 7/8 (a workspace in two parts, above and below, gets slices in both)."""
    if 2 in result.mechanism.periodic_axes:
        return np.asarray(DEFAULT_PHIS, dtype=np.float64)
    leaves = result.tree.leaves()
    maybe_w = leaves.status != OUT
    if not maybe_w.any():
        maybe_w = np.ones_like(maybe_w)
    lo, hi = leaves.lo[maybe_w], leaves.hi[maybe_w]
    volume = np.prod(hi - lo, axis=1)
    centre = 0.5 * (lo[:, 2] + hi[:, 2])
    order = np.argsort(centre, kind="stable")
    cumulative = np.cumsum(volume[order]) / volume.sum()
    quantiles = (np.arange(4) + 0.5) / 4.0
    return np.asarray(np.interp(quantiles, cumulative, centre[order]), dtype=np.float64)


def _in_slice(lo: Array, hi: Array, value: float, top: float) -> NDArray[np.bool_]:
    """Leaves whose third-axis range holds ``value`` (half-open, except at the top)."""
    return (lo[:, 2] <= value) & ((value < hi[:, 2]) | ((hi[:, 2] == top) & (value == top)))


def _outline(ax: Axes, result: Analysis, value: float) -> Any:
    """Outline of W (certain or undecided) in a slice, from a raster twice the finest grid."""
    from ..hypertree.measurement import locate

    tree = result.tree
    # the leaves' finest depth on each axis (the tree may allow deeper ones), at
    # most 2048 points a side
    finest = tree.layout.axis_depths(tree.levels).max(axis=0, initial=0)
    n = [min(2 << int(d), 2048) for d in finest[:2]]
    xs = tree.lo[0] + (np.arange(n[0]) + 0.5) * (tree.hi[0] - tree.lo[0]) / n[0]
    ys = tree.lo[1] + (np.arange(n[1]) + 0.5) * (tree.hi[1] - tree.lo[1]) / n[1]
    gx, gy = np.meshgrid(xs, ys)
    pts = np.stack([gx.ravel(), gy.ravel(), np.full(gx.size, value)], axis=1)
    _, leaf = locate(tree, pts)
    maybe_w = (result.table.status != OUT).any(axis=1)
    inside = np.where(leaf >= 0, maybe_w[np.maximum(leaf, 0)], False).reshape(gx.shape)
    if inside.any() and not inside.all():
        return ax.contour(
            gx, gy, inside.astype(float), levels=[0.5], colors=["black"], linewidths=0.8
        )
    return None


def plot_slices(
    result: Analysis, phis: ArrayLike | None = None, axes: Sequence[Axes] | None = None
) -> Figure:
    """The (x, y) slices of the regions at chosen values of the third axis (orientations
    phi, or heights z), one panel each.

    Each panel draws the leaves whose third-axis range holds the angle: a
    region's certified part solid, where it may extend light, undecided leaves
    of no region grey, and the outline of W (certain or undecided) in black.

    Parameters
    ----------
    result : Analysis
        An analysis with three pose axes (x, y, phi).
    phis : array_like, optional
        Values of the third axis at the slices: angles in radians (periodic angles
        are wrapped), or heights in length units for a translational mechanism
        (by default four heights spread over the volume of W's leaves);
        :data:`DEFAULT_PHIS` by default.
    axes : sequence of Axes, optional
        One per angle; new panels by default.

    Returns
    -------
    Figure

    Examples
    --------
    >>> from moveability import analyze
    >>> result = analyze("examples/three-rpr.toml", precision=(2, 2, 0.4))
    >>> fig = plot_slices(result, phis=[0.0, 0.5])
    >>> [ax.get_title() for ax in fig.axes]
    ['phi = 0\N{DEGREE SIGN}', 'phi = 28.65\N{DEGREE SIGN}']
    """
    _check_3d(result, "slices")
    values = np.atleast_1d(
        np.asarray(_default_cuts(result) if phis is None else phis, dtype=np.float64)
    )
    if values.ndim != 1 or values.size == 0 or not np.isfinite(values).all():
        what = "angles (radians)" if 2 in result.mechanism.periodic_axes else "values"
        raise InvalidParameterError("phis", f"one or more finite {what}", phis)
    if axes is None:
        axes = panels(values.size, 2, 6.0)
    if len(axes) < values.size:
        raise InvalidParameterError("axes", f"at least {values.size} axes", len(axes))
    fig = figure_of(axes[0])
    leaves = result.tree.leaves()
    lo, hi = leaves.lo, leaves.hi
    top = float(result.tree.hi[2])
    masks = [result.region_cells(j) for j in range(len(result.regions))]
    coloured = np.zeros(lo.shape[0], dtype=bool)
    for certain, possible in masks:
        coloured |= certain | possible
    undecided = (leaves.status == BOUNDARY) & ~coloured
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    m = result.mechanism
    for ax, asked in zip(axes, values, strict=False):
        value = _wrap(result, float(asked))
        cut = _in_slice(lo, hi, value, top)
        grey = cut & undecided
        coll = draw_cells(ax, lo[grey, :2], hi[grey, :2], UNDECIDED)
        coll.set_gid("undecided")
        for j, (certain, possible) in enumerate(masks):
            color = PALETTE[j % len(PALETTE)]
            rid = result.regions[j].id
            light = cut & possible
            coll = draw_cells(ax, lo[light, :2], hi[light, :2], color, alpha=0.3)
            coll.set_gid(f"region {rid} possible")
            solid = cut & certain
            coll = draw_cells(ax, lo[solid, :2], hi[solid, :2], color)
            coll.set_gid(f"region {rid} certain")
        _outline(ax, result, value)
        frame_axes(ax, m, _angle_text(m, 2, value))
    for ax in axes[values.size :]:
        ax.set_axis_off()
    handles: list[Any] = [
        Patch(color=PALETTE[j % len(PALETTE)], label=_region_label(result, j) + " (certified)")
        for j in range(len(result.regions))
    ]
    handles += [
        Patch(color=PALETTE[0], alpha=0.3, label="light: where a region may extend"),
        Patch(color=UNDECIDED, label="undecided, in no region"),
        Line2D([], [], color="black", lw=0.8, label="outline of W (certain or undecided)"),
    ]
    # below the panels: saved with bbox_inches="tight"
    opaque_legend(fig, handles, loc="upper center", ncol=2, fontsize=8, bbox_to_anchor=(0.5, 0.02))
    fig.suptitle(
        f"Slices of the N-connected regions (precision {precision_text(result)}); "
        f"{result.measure_name}s of the whole regions"
    )
    return fig


# --------------------------------------------------------------- 3-D view
def _quads(lo: Array, hi: Array, axis: NDArray[np.intp]) -> Array:
    """The four corners (m, 4, 3) of axis-aligned faces of a 3-D box grid."""
    u = np.array([1, 0, 0])[axis]  # first in-plane axis: 1 when the normal is x, else 0
    v = np.array([2, 2, 1])[axis]
    rows = np.arange(lo.shape[0])
    quads = np.repeat(lo[:, None, :], 4, axis=1)
    quads[rows, 1, u] = hi[rows, u]
    quads[rows, 2, u] = hi[rows, u]
    quads[rows, 2, v] = hi[rows, v]
    quads[rows, 3, v] = hi[rows, v]
    return quads


def plot_regions_3d(result: Analysis, ax: Axes | None = None, max_faces: int = MAX_FACES) -> Figure:
    """A 3-D view of the certified part of each region: the outer surface of its leaves.

    Parameters
    ----------
    result : Analysis
        An analysis with three pose axes.
    ax : Axes, optional
        3-D axes (``projection="3d"``); new ones by default.
    max_faces : int
        At most this many faces are drawn over all regions: above it, each
        region keeps its largest faces in proportion, and the title says so.

    Returns
    -------
    Figure

    Examples
    --------
    >>> from moveability import analyze
    >>> result = analyze("examples/three-rpr.toml", precision=(2, 2, 0.4))
    >>> fig = plot_regions_3d(result)
    >>> fig.axes[0].get_zlabel()
    'phi (rad)'
    """
    _check_3d(result, "regions-3d")
    if isinstance(max_faces, bool) or not isinstance(max_faces, int) or max_faces < 1:
        raise InvalidParameterError("max_faces", "a positive int", max_faces)
    from matplotlib.patches import Patch
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    # 3-D axes: their z methods are not in the Axes annotations
    view: Any = ax
    if view is None:
        view = pyplot().figure(figsize=(8, 7)).add_subplot(projection="3d")
    fig = figure_of(view)
    faces = []
    for j in range(len(result.regions)):
        lo, hi, axis, _ = boundary_faces(result.tree, result.region_cells(j)[0])
        faces.append(_quads(lo, hi, axis))
    total = sum(f.shape[0] for f in faces)
    handles = []
    shown = 0
    for j, quads in enumerate(faces):
        if total > max_faces:
            keep = max_faces * quads.shape[0] // total
            size = np.linalg.norm(quads[:, 2] - quads[:, 0], axis=1)
            quads = quads[np.sort(np.argsort(-size, kind="stable")[:keep])]
        shown += quads.shape[0]
        color = PALETTE[j % len(PALETTE)]
        coll = Poly3DCollection(
            list(quads), facecolors=color, edgecolors="#333333", linewidths=0.1, alpha=0.35
        )
        coll.set_gid(f"region {result.regions[j].id}")
        view.add_collection3d(coll)
        handles.append(Patch(color=color, alpha=0.6, label=_region_label(result, j)))
    m = result.mechanism
    lo_box, hi_box = m.bounds
    view.set_xlim(lo_box[0], hi_box[0])
    view.set_ylim(lo_box[1], hi_box[1])
    view.set_zlim(lo_box[2], hi_box[2])
    names = m.pose_names
    view.set_xlabel(f"{names[0]} (length units)")
    view.set_ylabel(f"{names[1]} (length units)")
    unit = "rad" if 2 in m.periodic_axes else "length units"
    view.set_zlabel(f"{names[2]} ({unit})")
    opaque_legend(view, handles, loc="upper left", fontsize=7)
    title = f"Certified part of each region (precision {precision_text(result)})"
    if shown < total:
        title += f"\nlargest {shown} of {total} faces shown"
    view.set_title(title)
    return fig
