"""Figures of an analysis: workspace, postures, regions, joint space, planned motion.

Every ``plot_*`` function draws on the axes it is given (or new ones) and
returns the figure; matplotlib is imported here only. Colours follow the
Okabe-Ito palette, which stays distinct with colour-blind vision; lengths are
in the units of the mechanism's spec, angles in radians. Where several sets
share a place (two regions over one joint vector, or over one pose) the place
takes the mean of their colours, and the legend names each mixture drawn.
Legends are opaque and stand beside or below the data; numbers in titles keep
three significant digits.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..hypertree.measurement import locate
from ..hypertree.status import IN, OUT
from ..intervals import Interval
from ..types import Array
from .axes import (
    EXCLUDED,
    FONT,
    PALETTE,
    UNDECIDED,
    draw_cells,
    figure_of,
    frame_axes,
    mix_colors,
    opaque_legend,
    panels,
    precision_text,
    pyplot,
    significant,
    style_axes,
)

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from ..analysis.result import Analysis
    from ..mechanisms.base import Mechanism

__all__ = [
    "FIGURES",
    "FIGURES_3D",
    "MAX_POSTURE_CHANGES",
    "PALETTE",
    "WORKSPACE_PAD",
    "animate_path",
    "figure",
    "figures_for",
    "joint_space_raster",
    "plot_joint_space",
    "plot_path",
    "plot_postures",
    "plot_regions",
    "plot_workspace",
]

#: figures of mechanisms with two pose axes
FIGURES = ("workspace", "postures", "regions", "joint-space", "path")
#: figures of mechanisms with three pose axes (see :mod:`moveability.output.plot3d`)
FIGURES_3D = ("slices", "regions-3d")
#: posture changes of a motion that :func:`plot_path` gives a panel each (the
#: title says when a motion has more)
MAX_POSTURE_CHANGES = 10
#: a pale fill for the region a motion stays in
_REGION_FILL = "#E3EBF3"
#: markers of the poses a motion was asked to pass through
_ASKED: dict[str, Any] = {"marker": "*", "color": "#F0E442", "mec": "black", "ms": 12}


# ------------------------------------------------------------------ helpers
def _axes(ax: Axes | None, figsize: tuple[float, float]) -> tuple[Figure, Axes]:
    if ax is not None:
        return figure_of(ax), ax
    fig, new = pyplot().subplots(figsize=figsize, layout="constrained")
    return fig, new


def _enclosure_text(bounds: tuple[float, float]) -> str:
    """``[lo, hi]`` rounded outwards to three significant digits."""
    return f"[{significant(bounds[0], direction=-1)}, {significant(bounds[1], direction=1)}]"


def _unit(mechanism: Mechanism, joint: int) -> str:
    """``rad`` for a revolute joint, ``length units`` for a prismatic one."""
    return "length units" if mechanism.limits[joint].prismatic else "rad"


def _joint_text(mechanism: Mechanism, joints: Array) -> str:
    """Joint values with their units, three significant digits each."""
    units = {_unit(mechanism, i) for i in range(len(joints))}
    values = ", ".join(significant(v) for v in joints)
    if len(units) == 1:
        return f"q = ({values}) {units.pop()}"
    shown = (f"{significant(v)} {_unit(mechanism, i)}" for i, v in enumerate(joints))
    return "q = (" + ", ".join(shown) + ")"


def _light(color: Any, weight: float = 0.35) -> tuple[float, float, float]:
    """A pale, opaque version of a colour (``weight`` of it on white)."""
    from matplotlib.colors import to_rgb

    rgb = weight * np.asarray(to_rgb(color)) + (1.0 - weight)
    return float(rgb[0]), float(rgb[1]), float(rgb[2])


def _sign_text(sign: int) -> str:
    return f"det A {'>' if sign > 0 else '<'} 0"


def _box_aspect(lo: Array, hi: Array) -> float:
    return float((hi[1] - lo[1]) / (hi[0] - lo[0]))


def _pose_axes(ax: Axes, mechanism: Mechanism, title: str, box: tuple[Array, Array]) -> None:
    """Limits of a box, equal aspect, labelled pose axes, a title, the shared fonts."""
    frame_axes(ax, mechanism, title)
    ax.set_xlim(box[0][0], box[1][0])
    ax.set_ylim(box[0][1], box[1][1])
    style_axes(ax)


def _outer_labels(axes: Sequence[Axes], n: int, cols: int) -> None:
    """Axis labels on the left column and the bottom panel of each column only."""
    rows = int(np.ceil(n / cols))
    for k, ax in enumerate(axes[:n]):
        row, col = divmod(k, cols)
        if col:
            ax.set_ylabel("")
        if row < rows - 1 and k + cols < n:
            ax.set_xlabel("")


# ---------------------------------------------------------------- workspace
def plot_workspace(result: Analysis, ax: Axes | None = None) -> Figure:
    """The workspace W (certain and undecided cells) with the singularity loci.

    Parallel singularities (det A = 0) are drawn per posture, serial ones (a
    leg's branches meeting) per leg. The legend stands beside the axes (below
    them when the pose box is wide).
    """
    m = result.mechanism
    lo, hi = m.bounds
    wide = _box_aspect(lo, hi) < 0.6
    figsize = (7.5, 7.5 * _box_aspect(lo, hi) + 2.6) if wide else (9.0, 7.0)
    fig, ax = _axes(ax, figsize)
    leaves = result.tree.leaves()
    t = result.table
    certain = (t.exists & t.within).any(axis=1)
    possible = (t.status != OUT).any(axis=1)
    draw_cells(ax, leaves.lo[certain], leaves.hi[certain], "#DDEEFF", label="W (certain)")
    undecided = possible & ~certain
    draw_cells(
        ax,
        leaves.lo[undecided],
        leaves.hi[undecided],
        UNDECIDED,
        label="W (undecided at this precision)",
    )
    gx, gy, pts = _grid(m)
    q = m.joint_angles(pts)
    handles: list[Any] = []
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    for p in range(q.shape[1]):
        qp = q[:, p, :]
        ok = np.isfinite(qp).all(axis=1)
        for i, lim in enumerate(m.limits):
            ok &= lim.contains(np.where(np.isfinite(qp[:, i]), qp[:, i], 0.0))
        det = np.full(pts.shape[0], np.nan)
        det[ok] = m.det_a(pts[ok], qp[ok])
        color = PALETTE[p % len(PALETTE)]
        if np.isfinite(det).any() and np.nanmin(det) < 0 < np.nanmax(det):
            ax.contour(gx, gy, det.reshape(gx.shape), levels=[0.0], colors=[color], linewidths=1.2)
        handles.append(Line2D([], [], color=color, label=f"det A = 0, posture {m.posture_name(p)}"))
    for i, leg in enumerate(m.legs):
        reach = np.isfinite(leg.angles(pts)).all(axis=1).astype(float)
        if reach.min() < 0.5 < reach.max():
            ax.contour(
                gx,
                gy,
                reach.reshape(gx.shape),
                levels=[0.5],
                colors=["black"],
                linestyles=[("--", ":")[i % 2]],
                linewidths=1.0,
            )
        handles.append(
            Line2D(
                [],
                [],
                color="black",
                linestyle=("--", ":")[i % 2],
                label=f"serial singularity, leg {i + 1} ({leg.joint})",
            )
        )
    handles = [
        Patch(color="#DDEEFF", label="W (certain)"),
        Patch(color=UNDECIDED, label="W undecided at this precision"),
        *handles,
    ]
    title = f"Workspace W and singularity loci (precision {precision_text(result)})"
    _pose_axes(ax, m, title, (lo, hi))
    if wide:
        opaque_legend(ax, handles, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=2)
    else:
        opaque_legend(ax, handles, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    return fig


def _grid(mechanism: Mechanism, n: int = 400) -> tuple[Array, Array, Array]:
    lo, hi = mechanism.bounds
    xs = np.linspace(lo[0], hi[0], n)
    ys = np.linspace(lo[1], hi[1], n)
    gx, gy = np.meshgrid(xs, ys)
    return gx, gy, np.stack([gx.ravel(), gy.ravel()], axis=1)


# ----------------------------------------------------------------- postures
def _leg_points(mechanism: Mechanism, pose: Array, joints: Array) -> list[Array]:
    """Each leg as a polyline (its ``links``: fixed or sliding joint, ..., platform
    point); legs that give no links (user-defined ones) are left out."""
    out = []
    for i, leg in enumerate(mechanism.legs):
        links = getattr(leg, "links", None)
        if links is not None and np.isfinite(joints[i]):
            out.append(np.asarray(links(np.asarray(pose, dtype=np.float64), float(joints[i]))))
    return out


def _rails(mechanism: Mechanism, pose: Array) -> list[Array]:
    """The stroke of each prismatic leg: where its sliding joint goes from one end
    of its limits to the other (a segment (2, 2))."""
    out = []
    for i, leg in enumerate(mechanism.legs):
        lim = mechanism.limits[i]
        links = getattr(leg, "links", None)
        if lim.prismatic and links is not None:
            p = np.asarray(pose, dtype=np.float64)
            out.append(np.stack([links(p, lim.lo)[0], links(p, lim.hi)[0]]))
    return out


def _draw_rails(ax: Axes, mechanism: Mechanism, pose: Array) -> list[Any]:
    artists = []
    for rail in _rails(mechanism, pose):
        (line,) = ax.plot(
            rail[:, 0],
            rail[:, 1],
            "-",
            color="#999999",
            lw=5,
            alpha=1.0,
            solid_capstyle="butt",
            zorder=1,
        )
        artists.append(line)
    return artists


def _draw_mechanism(
    ax: Axes,
    mechanism: Mechanism,
    pose: Array,
    joints: Array,
    color: Any,
    alpha: float = 1.0,
    label: str | None = None,
) -> list[Any]:
    """The links of a mechanism (each leg's ``links``), its actuated joints as black
    squares and the platform point as a black dot; returns the artists."""
    artists = []
    for k, pts in enumerate(_leg_points(mechanism, pose, joints)):
        (line,) = ax.plot(
            pts[:, 0],
            pts[:, 1],
            "-o",
            color=color,
            alpha=alpha,
            lw=2,
            ms=4,
            label=label if k == 0 else None,
            zorder=4,
        )
        (base,) = ax.plot([pts[0, 0]], [pts[0, 1]], "s", color="black", ms=6, zorder=5)
        artists += [line, base]
    (point,) = ax.plot([pose[0]], [pose[1]], "o", color="black", ms=5, zorder=6)
    artists.append(point)
    return artists


def _fit_box(points: Array, pad: float = 0.06) -> tuple[Array, Array]:
    """A box holding the points (n, 2), widened by ``pad`` of its size."""
    lo = np.nanmin(points, axis=0)
    hi = np.nanmax(points, axis=0)
    span = np.maximum(hi - lo, 1e-9)
    margin = pad * max(float(span.max()), 1e-9)
    return lo - margin, hi + margin


def _mechanism_box(
    mechanism: Mechanism, poses: Array, joints: Array, pad: float = 0.06
) -> tuple[Array, Array]:
    """A box holding the whole mechanism in the given configurations: the fixed
    joints, the strokes of sliding ones, every link and the platform points (the
    pose box for legs that give no links)."""
    if not all(hasattr(leg, "links") for leg in mechanism.legs):
        lo, hi = mechanism.bounds
        return np.asarray(lo[:2], dtype=np.float64), np.asarray(hi[:2], dtype=np.float64)
    pts = [np.asarray(poses, dtype=np.float64)[:, :2]]
    for pose, q in zip(poses, joints, strict=True):
        pts += _leg_points(mechanism, pose, q)
    if len(poses):
        pts += _rails(mechanism, poses[0])
    return _fit_box(np.concatenate(pts), pad)


def plot_postures(
    mechanism: Mechanism, pose: ArrayLike, axes: Sequence[Axes] | None = None
) -> Figure:
    """The mechanism at one pose in each of its postures.

    Postures beyond a joint limit are drawn faint and say so; singular ones
    (|det A| or a leg's serial term nearly zero) are marked. Every panel shows
    the whole mechanism in all its postures at the same scale.
    """
    p = np.asarray(pose, dtype=np.float64).reshape(1, -1)
    q = mechanism.joint_angles(p)[0]
    n = q.shape[0]
    reachable = np.isfinite(q).all(axis=1)
    if reachable.any():
        box = _mechanism_box(mechanism, np.repeat(p, int(reachable.sum()), axis=0), q[reachable])
    else:
        box = mechanism.bounds
    cols = min(n, 4)
    if axes is None:
        axes = panels(n, 4, 3.4, aspect=_box_aspect(*box))
    fig = figure_of(axes[0])
    scale = float(np.abs(np.concatenate(mechanism.bounds)).max())
    for k in range(n):
        ax = axes[k]
        name = mechanism.posture_name(k)
        if not reachable[k]:
            ax.set_title(f"posture {name}: unreachable", fontsize=FONT["title"])
            ax.set_axis_off()
            continue
        within = all(lim.contains(q[k, i]) for i, lim in enumerate(mechanism.limits))
        det = float(mechanism.det_a(p, q[k][None, :])[0])
        serial = [
            float(leg.serial_term(p, q[k][None, i])[0]) for i, leg in enumerate(mechanism.legs)
        ]
        singular = abs(det) < 1e-3 * scale**2 or min(abs(s) for s in serial) < 1e-3 * scale**2
        color = PALETTE[k % len(PALETTE)]
        _draw_rails(ax, mechanism, p[0])
        _draw_mechanism(ax, mechanism, p[0], q[k], color, alpha=1.0 if within else 0.3)
        state = [] if within else ["beyond a joint limit"]
        if singular:
            state.append("singular")
        title = f"posture {name}: {_joint_text(mechanism, q[k])}\ndet A = {significant(det)}"
        if state:
            title += " [" + ", ".join(state) + "]"
        _pose_axes(ax, mechanism, title, box)
    _outer_labels(axes, n, cols)
    for ax in axes[n:]:
        ax.set_axis_off()
    fig.suptitle(
        f"Postures at pose ({', '.join(significant(v) for v in p[0])})", fontsize=FONT["suptitle"]
    )
    return fig


# ------------------------------------------------------------------ regions
def _mixture_label(names: list[str]) -> str:
    if len(names) == 1:
        return names[0]
    return ", ".join(names[:-1]) + " and " + names[-1]


#: margin around the workspace in the regions figure, a fraction of its larger side
WORKSPACE_PAD = 0.03


def _workspace_box(result: Analysis, pad: float = WORKSPACE_PAD) -> tuple[Array, Array]:
    """The box of the cells of W certified or undecided (not out for every
    posture), widened by ``pad`` of its larger side; the pose box when W is empty."""
    possible = (result.table.status != OUT).any(axis=1)
    if not possible.any():
        lo, hi = result.mechanism.bounds
        return np.asarray(lo[:2], dtype=np.float64), np.asarray(hi[:2], dtype=np.float64)
    leaves = result.tree.leaves()
    return _fit_box(np.concatenate([leaves.lo[possible], leaves.hi[possible]])[:, :2], pad)


def plot_regions(result: Analysis, axes: Sequence[Axes] | None = None) -> Figure:
    """Each N-connected region W_Nj (one panel each) and an overlay.

    Solid: certified part of W_Nj; pale: where W_Nj may extend (undecided band).
    The overlay draws the certified parts; where several regions hold a pose
    it takes the mean of their colours, and the legend names each mixture.
    Every panel frames the workspace (its certified and undecided cells, with a
    margin of :data:`WORKSPACE_PAD`) at equal scales.
    """
    m = result.mechanism
    regions = result.regions
    n = len(regions) + 1
    lo, hi = _workspace_box(result)
    cols = min(n, 3)
    if axes is None:
        axes = panels(n, 3, 4.2, aspect=_box_aspect(lo, hi))
        # room for the figure's title and the legend below the panels (two entries
        # a region): the panels frame W tightly and leave none to spare
        rows = int(np.ceil(2 * len(regions) / min(4, max(2, len(regions)))))
        figure_of(axes[0]).set_figheight(figure_of(axes[0]).get_figheight() + 0.3 + 0.15 * rows)
    fig = figure_of(axes[0])
    leaves = result.tree.leaves()
    overlay = axes[len(regions)]
    from matplotlib.patches import Patch

    handles: list[Any] = []
    held = np.zeros((len(leaves.lo), len(regions)), dtype=bool)
    for j, region in enumerate(regions):
        color = PALETTE[j % len(PALETTE)]
        sure, maybe = result.region_cells(j)
        held[:, j] = sure
        ax = axes[j]
        draw_cells(ax, leaves.lo[maybe], leaves.hi[maybe], _light(color))
        draw_cells(ax, leaves.lo[sure], leaves.hi[sure], color)
        title = (
            f"W_N{region.id} ({_sign_text(region.sign)})\n"
            f"{result.measure_name} in {_enclosure_text(region.area)}"
        )
        _pose_axes(ax, m, title, (lo, hi))
        handles += [
            Patch(color=color, label=f"W_N{region.id}: certified"),
            Patch(color=_light(color), label=f"W_N{region.id}: undecided band"),
        ]
    # the overlay: one colour per set of regions holding the leaf
    combos, which = np.unique(held, axis=0, return_inverse=True)
    which = np.asarray(which).reshape(-1)
    mixtures = []
    for c, combo in enumerate(combos):
        members = np.flatnonzero(combo)
        if not members.size:
            continue
        mixed = mix_colors([PALETTE[j % len(PALETTE)] for j in members])
        cells = which == c
        draw_cells(overlay, leaves.lo[cells], leaves.hi[cells], mixed)
        if members.size > 1:
            names = [f"W_N{regions[j].id}" for j in members]
            mixtures.append(Patch(color=mixed, label=f"{_mixture_label(names)} (overlay)"))
    _pose_axes(overlay, m, "All N-connected regions\n(certified parts)", (lo, hi))
    _outer_labels(axes, n, cols)
    for ax in axes[n:]:
        ax.set_axis_off()
    handles += mixtures
    opaque_legend(fig, handles, loc="outside lower center", ncol=min(4, max(2, len(handles) // 2)))
    fig.suptitle(
        f"N-connected regions (precision {precision_text(result)})", fontsize=FONT["suptitle"]
    )
    return fig


# -------------------------------------------------------------- joint space
def _dyads(mechanism: Mechanism) -> bool:
    from ..analysis.joint_space import has_dyads

    return has_dyads(mechanism)


def _knees(mechanism: Mechanism, joints: Array) -> list[Array]:
    """The knee of each leg (elbow or slider, where the distal link starts), (m, 2)."""
    out = []
    for i, leg in enumerate(mechanism.legs):
        knee = leg.knee_boxes(Interval(joints[:, i]))[0]  # type: ignore[attr-defined]
        out.append(np.stack([knee[0].mid, knee[1].mid], axis=-1))
    return out


def _assemblies(mechanism: Mechanism, joints: Array) -> Array:
    """The poses of two dyads at joint vectors: P on both circles ``|P - C_i| = b_i``.

    Returns shape (m, 2, 2): the two mirror poses across the line of the knees,
    NaN where the circles do not cross (or touch: det A = 0 there).
    """
    c1, c2 = _knees(mechanism, joints)
    b1, b2 = (float(leg.distal) for leg in mechanism.legs)  # type: ignore[attr-defined]
    v = c2 - c1
    d = np.hypot(v[:, 0], v[:, 1])
    ok = (d > abs(b1 - b2)) & (d < b1 + b2)
    with np.errstate(divide="ignore", invalid="ignore"):
        a = (b1 * b1 - b2 * b2 + d * d) / (2.0 * d)
        h = np.sqrt(np.maximum(b1 * b1 - a * a, 0.0))
        e = v / d[:, None]
    normal = np.stack([-e[:, 1], e[:, 0]], axis=1)
    foot = c1 + a[:, None] * e
    poses = np.stack([foot + h[:, None] * normal, foot - h[:, None] * normal], axis=1)
    poses[~ok] = np.nan
    return poses


def _region_of_component(result: Analysis) -> NDArray[np.int64]:
    """Position in ``result.regions`` of each certain component (-1: none listed)."""
    out = np.full(result.graph.certain_sign.size, -1, dtype=np.int64)
    for j, region in enumerate(result.regions):
        out[region.certain] = j
    return out


def _node_regions(
    result: Analysis, leaf: NDArray[np.intp], candidates: NDArray[np.bool_]
) -> NDArray[np.int64]:
    """The region of configurations given by their leaf and candidate postures
    (m, P): the region of a certified node (leaf, p) among the candidates, or -1."""
    t, g = result.table, result.graph
    inside = leaf >= 0
    lf = np.where(inside, leaf, 0)
    certified = ((t.status[lf] == IN) | t.group[lf]) & candidates & inside[:, None]
    component = np.where(certified, g.certain[lf], -1)
    region = _region_of_component(result)
    labels = np.where(component >= 0, region[np.maximum(component, 0)], -1)
    # a leg at a fold matches two postures of one configuration: the same region
    return np.asarray(labels.max(axis=1), dtype=np.int64)


def _configuration_regions(result: Analysis, poses: Array, joints: Array) -> NDArray[np.int64]:
    """The region (position in ``result.regions``) certified to hold each
    configuration (pose, joints), or -1.

    The configuration lies on the sheet of the posture whose joint values at the
    pose are its joints (modulo 2 pi for revolute joints); the node of that
    sheet over the pose's leaf, when certified, belongs to one certain component.
    """
    m = result.mechanism
    out = np.full(poses.shape[0], -1, dtype=np.int64)
    ok = np.isfinite(poses).all(axis=1) & np.isfinite(joints).all(axis=1)
    if not ok.any():
        return out
    x = m.wrap_poses(poses[ok])
    q = joints[ok]
    _, leaf = locate(result.tree, x)
    angles = m.joint_angles(x, clip=True)
    diff = angles - q[:, None, :]
    for i, lim in enumerate(m.limits):
        if not lim.prismatic:
            diff[..., i] = np.mod(diff[..., i] + np.pi, 2.0 * np.pi) - np.pi
    scale = max(1.0, float(np.abs(np.concatenate(m.bounds)).max()))
    with np.errstate(invalid="ignore"):
        match = np.asarray((np.abs(diff) <= 1e-6 * scale).all(axis=2), dtype=bool)
    out[ok] = _node_regions(result, leaf, match)
    return out


def _joint_box(mechanism: Mechanism) -> tuple[Array, Array]:
    lims = mechanism.limits
    lo = np.array([lim.lo for lim in lims], dtype=np.float64)
    hi = np.array([lim.lo + 2 * np.pi if lim.periodic else lim.hi for lim in lims])
    return lo, hi


def _raster_layers(
    mechanism: Mechanism, poses: Array, joints: Array, labels: NDArray[np.int64], n_regions: int
) -> NDArray[np.int64]:
    """The layer of :func:`joint_space_raster` of each configuration (pose, joints):
    its region when certified in one (``labels`` >= 0), else ``n_regions + 1``
    where a constraint beyond the paper excludes it (checked at the configuration
    itself), else ``n_regions`` (undecided)."""
    layers = np.where(labels >= 0, labels, n_regions)
    if mechanism.restrictions.empty or not len(labels):
        return layers
    with np.errstate(invalid="ignore", divide="ignore"):
        excluded = ~mechanism.constraints_hold(poses, joints)
    return np.where((labels < 0) & excluded, n_regions + 1, layers)


def joint_space_raster(
    result: Analysis, resolution: int = 300
) -> tuple[Array, Array, NDArray[np.bool_]]:
    """The traces of the regions in the joint space Q, on a grid of joint vectors.

    For the five-bar and the biglide (two dyads), each joint vector ``q`` at the
    centre of a cell has up to two configurations, the two poses where the
    distal links meet (one with det A > 0, one with det A < 0). Each is placed
    in the region whose certified sheet holds it: the sheet of its posture over
    the leaf of its pose (:func:`moveability.hypertree.measurement.locate`).
    Other two-joint mechanisms, which give no forward kinematics, are sampled
    on a grid of poses over the leaves not out of W instead, each
    configuration marking the cell of its joints.

    Parameters
    ----------
    result : Analysis
        An analysis of a mechanism with two joints.
    resolution : int
        Cells per joint axis, over the joint limits (one turn for a free joint).

    Returns
    -------
    q1, q2 : ndarray, shape (resolution,)
        Joint values at the centres of the cells along each axis.
    holds : ndarray of bool, shape (resolution, resolution, R + 2)
        ``holds[b, a, j]``: a configuration over ``(q1[a], q2[b])`` is certified in
        ``result.regions[j]``; ``holds[b, a, R]``: one is not certified in any
        listed region (undecided at the precision); ``holds[b, a, R + 1]``: one
        is excluded by a constraint beyond the paper (a passive joint limit, an
        obstacle, a link collision: ``[passive_limits]``, ``[[obstacles]]``,
        ``[collisions]``), by the mechanism's pointwise check
        (:meth:`~moveability.mechanisms.base.Mechanism.constraints_hold`) of
        that very configuration. A configuration certified in a region is
        counted there only.

    Examples
    --------
    >>> from moveability import analyze
    >>> from moveability.mechanisms import FiveBar
    >>> result = analyze(FiveBar(), precision=0.5)
    >>> q1, q2, holds = joint_space_raster(result, resolution=40)
    >>> holds.shape == (40, 40, len(result.regions) + 2)
    True
    """
    from ..errors import InvalidParameterError

    m = result.mechanism
    if len(m.legs) != 2:
        raise InvalidParameterError("result", "an analysis of a mechanism with two joints", m.name)
    n = int(resolution)
    if n < 2:
        raise InvalidParameterError("resolution", "a whole number >= 2", resolution)
    lo, hi = _joint_box(m)
    samples = 2 * n
    if not _dyads(m):
        # sampled configurations leave gaps in cells finer than their spacing
        n = max(2, n // 3)
    centres = [lo[i] + (np.arange(n) + 0.5) * (hi[i] - lo[i]) / n for i in range(2)]
    n_regions = len(result.regions)
    holds = np.zeros((n, n, n_regions + 2), dtype=bool)
    if _dyads(m):
        g1, g2 = np.meshgrid(centres[0], centres[1])
        joints = np.stack([g1.ravel(), g2.ravel()], axis=1)
        flat = holds.reshape(n * n, n_regions + 2)
        poses = _assemblies(m, joints)
        for s in range(2):
            x = poses[:, s]
            rows = np.flatnonzero(np.isfinite(x).all(axis=1))
            labels = _configuration_regions(result, x, joints)[rows]
            flat[rows, _raster_layers(m, x[rows], joints[rows], labels, n_regions)] = True
        return centres[0], centres[1], holds
    # no forward kinematics: configurations of a grid of poses mark their cells
    box_lo, box_hi = result.tree.lo, result.tree.hi
    axes = [np.linspace(box_lo[i], box_hi[i], samples) for i in range(box_lo.size)]
    x = np.stack([a.ravel() for a in np.meshgrid(*axes)], axis=1)
    status, leaf = locate(result.tree, x)
    keep = status != OUT
    x, leaf = x[keep], leaf[keep]
    q = m.joint_angles(x, clip=True)
    n_post = q.shape[1]
    for p in range(n_post):
        qp = q[:, p, :]
        valid = np.isfinite(qp).all(axis=1)
        for i, lim in enumerate(m.limits):
            valid &= lim.contains(np.where(np.isfinite(qp[:, i]), qp[:, i], 0.0))
        with np.errstate(invalid="ignore"):
            valid &= m.det_a(x, qp) != 0
        if not valid.any():
            continue
        candidates = np.zeros((int(valid.sum()), n_post), dtype=bool)
        candidates[:, p] = True
        labels = _node_regions(result, leaf[valid], candidates)
        cell = []
        for i, lim in enumerate(m.limits):
            v = lim.wrap(qp[valid, i])
            cell.append(np.clip(((v - lo[i]) / (hi[i] - lo[i]) * n).astype(np.int64), 0, n - 1))
        holds[cell[1], cell[0], _raster_layers(m, x[valid], qp[valid], labels, n_regions)] = True
    return centres[0], centres[1], holds


def _angle_ticks(axis: Any, lo: float, hi: float) -> None:
    """Ticks at multiples of pi/4 (pi/2 on a range over 1.5 pi), labelled with pi."""
    from fractions import Fraction

    from matplotlib.ticker import FixedLocator, FuncFormatter

    step = np.pi / 2 if hi - lo > 1.5 * np.pi else np.pi / 4
    ticks = np.arange(np.ceil(lo / step - 1e-9), np.floor(hi / step + 1e-9) + 1) * step

    def text(value: float, _pos: int) -> str:
        f = Fraction(round(value / np.pi * 4), 4)
        if f == 0:
            return "0"
        num = "" if abs(f.numerator) == 1 else str(abs(f.numerator))
        sign = "-" if f < 0 else ""
        den = "" if f.denominator == 1 else f"/{f.denominator}"
        return f"{sign}{num}\N{GREEK SMALL LETTER PI}{den}"

    axis.set_major_locator(FixedLocator(ticks.tolist()))
    axis.set_major_formatter(FuncFormatter(text))


def _singular_texts(mechanism: Mechanism) -> tuple[str, str]:
    """What det A = 0 means in Q for two dyads: the knees as far apart as the distal
    links reach, or as near as their difference."""
    from ..mechanisms import FiveBar
    from ..mechanisms.biglide import Biglide

    if isinstance(mechanism, FiveBar):
        return "|CD| = L2 + L4", "|CD| = |L2 - L4|"
    if isinstance(mechanism, Biglide):
        return "|rho2 - rho1| = L1 + L2", "|rho2 - rho1| = |L1 - L2|"
    return "|C1C2| = b1 + b2", "|C1C2| = |b1 - b2|"


def _exclusion_text(mechanism: Mechanism) -> str:
    """What excludes configurations beyond the paper's hypotheses: ``a passive joint
    limit``, ``an obstacle``, ``a link collision``, or some of them."""
    r = mechanism.restrictions
    causes = [
        text
        for present, text in (
            (bool(r.passive), "a passive joint limit"),
            (bool(r.obstacles), "an obstacle"),
            (r.collisions, "a link collision"),
        )
        if present
    ]
    if len(causes) > 1:
        return ", ".join(causes[:-1]) + " or " + causes[-1]
    return causes[0] if causes else "a constraint"


def _trace_label(
    result: Analysis, members: NDArray[np.intp], undecided: bool, excluded: bool = False
) -> str:
    names = [f"R{result.regions[j].id} ({_sign_text(result.regions[j].sign)})" for j in members]
    cause = _exclusion_text(result.mechanism)
    if not names:
        if undecided and excluded:
            return f"undecided and excluded by {cause}, one configuration each"
        return f"excluded by {cause}" if excluded else "undecided at this precision"
    text = _mixture_label(names)
    others = (["an undecided one"] if undecided else []) + (
        [f"one excluded by {cause}"] if excluded else []
    )
    if others:
        return f"{text} and {' and '.join(others)}"
    if len(names) > 1:
        return f"{text}, one configuration each"
    return text


def plot_joint_space(result: Analysis, ax: Axes | None = None, resolution: int = 300) -> Figure:
    """The joint space Q: the traces of the regions R_j, singular curves, limits.

    Each cell of a grid of Q (``resolution`` per axis, see
    :func:`joint_space_raster`) takes the colour of the regions its
    configurations lie in; where two configurations over one joint vector lie
    in two regions (two assembly modes), the cell takes the mean of their
    colours, grey stands for a configuration undecided at the precision and
    pale rose for one that a constraint beyond the paper (a passive joint limit,
    an obstacle, a link collision) excludes, checked at the configuration itself.
    The legend names every mixture drawn. For two dyads the parallel
    singularities (the knees as far apart as the distal links reach, or as near
    as their difference) are drawn on top, and the joint limits as dash-dotted
    lines.
    """
    m = result.mechanism
    fig, ax = _axes(ax, (9.5, 6.0))
    q1, _, holds = joint_space_raster(result, resolution)
    n_regions = len(result.regions)
    n = q1.size
    lo, hi = _joint_box(m)
    colors = [*(PALETTE[j % len(PALETTE)] for j in range(n_regions)), UNDECIDED, EXCLUDED]
    image = np.zeros((n, n, 4))
    combos, which = np.unique(holds.reshape(n * n, n_regions + 2), axis=0, return_inverse=True)
    which = np.asarray(which).reshape(n, n)
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    entries: list[tuple[tuple[int, int, int], Any]] = []
    for c, combo in enumerate(combos):
        members = np.flatnonzero(combo)
        if not members.size:
            continue
        color = mix_colors([colors[j] for j in members])
        image[which == c] = (*color, 1.0)
        regions_in = members[members < n_regions]
        undecided, excluded = bool(combo[n_regions]), bool(combo[n_regions + 1])
        label = _trace_label(result, regions_in, undecided, excluded)
        # mixtures of two regions first, then each region alone, undecided and
        # excluded last
        order = (-regions_in.size, int(excluded) + 2 * int(not regions_in.size), int(undecided))
        entries.append((order, Patch(color=color, label=label)))
    handles: list[Any] = [h for _, h in sorted(entries, key=lambda e: e[0])]
    ax.imshow(
        image,
        origin="lower",
        extent=(lo[0], hi[0], lo[1], hi[1]),
        interpolation="nearest",
        aspect="auto",
        zorder=1,
    )
    if _dyads(m):
        # parallel singularities: P, C1 and C2 aligned
        k = max(400, n)
        g1, g2 = np.meshgrid(np.linspace(lo[0], hi[0], k), np.linspace(lo[1], hi[1], k))
        c1, c2 = _knees(m, np.stack([g1.ravel(), g2.ravel()], axis=1))
        d = np.hypot(*(c1 - c2).T).reshape(g1.shape)
        b1, b2 = (float(leg.distal) for leg in m.legs)  # type: ignore[attr-defined]
        styles: tuple[Any, Any] = ("-", "--")
        for level, style, text in zip(
            (b1 + b2, abs(b1 - b2)), styles, _singular_texts(m), strict=True
        ):
            if d.min() < level < d.max():
                ax.contour(
                    g1,
                    g2,
                    d,
                    levels=[level],
                    colors=["black"],
                    linestyles=[style],
                    linewidths=1.2,
                    zorder=3,
                )
                handles.append(
                    Line2D([], [], color="black", linestyle=style, label=f"det A = 0: {text}")
                )
    limited = [i for i, lim in enumerate(m.limits) if not lim.periodic]
    margin = 0.04 * (hi - lo)
    view_lo = np.array([lo[i] - (margin[i] if i in limited else 0.0) for i in range(2)])
    view_hi = np.array([hi[i] + (margin[i] if i in limited else 0.0) for i in range(2)])
    stops: dict[str, Any] = {"color": "#333333", "linestyle": "-.", "lw": 1.0, "zorder": 3}
    for i in limited:
        draw = ax.axvline if i == 0 else ax.axhline
        for value in (lo[i], hi[i]):
            draw(value, **stops)
    if limited:
        handles.append(Line2D([], [], label="joint limits", **stops))
    ax.set_xlim(view_lo[0], view_hi[0])
    ax.set_ylim(view_lo[1], view_hi[1])
    if _unit(m, 0) == _unit(m, 1):
        ax.set_aspect("equal")
    for i, axis in enumerate((ax.xaxis, ax.yaxis)):
        if not m.limits[i].prismatic:
            _angle_ticks(axis, view_lo[i], view_hi[i])
    ax.set_xlabel(f"{m.joint_names[0]} ({_unit(m, 0)})")
    ax.set_ylabel(f"{m.joint_names[1]} ({_unit(m, 1)})")
    how = "" if _dyads(m) else " (configurations sampled on a grid of poses)"
    ax.set_title(
        f"Joint space Q: traces of the regions{how}\n(precision {precision_text(result)}, "
        f"{n} x {n} joint vectors)"
    )
    style_axes(ax)
    opaque_legend(
        ax,
        handles,
        loc="upper left",
        bbox_to_anchor=(1.02, 1.0),
        title="configurations over q lie in",
    )
    return fig


# ---------------------------------------------------------------------- path
def _posture_changes(path: Sequence[Mapping[str, Any]]) -> list[int]:
    return [k for k in range(1, len(path)) if path[k]["posture"] != path[k - 1]["posture"]]


def _waypoints(motion: Mapping[str, Any]) -> list[int]:
    """Indices into the path where each asked pose is reached (the first and the
    last configuration when the motion does not say)."""
    n = len(motion["path"])
    given = motion.get("waypoints")
    if given is None:
        return [0, n - 1] if n > 1 else [0]
    return [min(max(int(k), 0), n - 1) for k in given]


def _frames(motion: Mapping[str, Any], count: int) -> list[int]:
    """The steps of a motion shown: the first and the last, every posture change
    (the first :data:`MAX_POSTURE_CHANGES`), the asked poses while there is room
    within ``count``, then steps far from those already shown."""
    n = len(motion["path"])
    picks = {0, n - 1}
    picks.update(_posture_changes(motion["path"])[:MAX_POSTURE_CHANGES])
    total = min(n, max(count, len(picks)))
    for k in _waypoints(motion):
        if len(picks) >= total:
            break
        picks.add(k)
    while len(picks) < total:
        shown = np.array(sorted(picks))
        gap = np.abs(np.arange(n)[:, None] - shown[None, :]).min(axis=1)
        picks.add(int(np.argmax(gap)))
    return sorted(picks)


def _posture_index(mechanism: Mechanism, name: str) -> int:
    return next(i for i in range(len(mechanism.postures)) if mechanism.posture_name(i) == name)


def _motion_arrays(motion: Mapping[str, Any]) -> tuple[Array, Array]:
    path = motion["path"]
    poses = np.array([c["pose"] for c in path], dtype=np.float64)
    joints = np.array([c["joints"] for c in path], dtype=np.float64)
    return poses, joints


def _backdrop(
    result: Analysis, region: int, box: tuple[Array, Array], pixels: int = 500
) -> tuple[Array, tuple[float, float, float, float]]:
    """The certified part of a region over a box, as an RGBA image and its extent:
    a backdrop that many panels, or frames, draw at the cost of one image."""
    from matplotlib.colors import to_rgb

    j = next(i for i, r in enumerate(result.regions) if r.id == region)
    lo, hi = box
    aspect = _box_aspect(lo, hi)
    nx = pixels if aspect <= 1 else max(2, int(pixels / aspect))
    ny = max(2, int(nx * aspect))
    xs = lo[0] + (np.arange(nx) + 0.5) * (hi[0] - lo[0]) / nx
    ys = lo[1] + (np.arange(ny) + 0.5) * (hi[1] - lo[1]) / ny
    gx, gy = np.meshgrid(xs, ys)
    points = np.stack([gx.ravel(), gy.ravel()], axis=1)
    _, leaf = locate(result.tree, result.mechanism.wrap_poses(points))
    sure, _ = result.region_cells(j)
    inside = np.zeros(points.shape[0], dtype=bool)
    inside[leaf >= 0] = sure[leaf[leaf >= 0]]
    image = np.zeros((ny * nx, 4))
    image[inside] = (*to_rgb(_REGION_FILL), 1.0)
    return image.reshape(ny, nx, 4), (float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1]))


def _draw_route(
    ax: Axes,
    motion: Mapping[str, Any],
    poses: Array,
    upto: int | None,
    backdrop: tuple[Array, tuple[float, float, float, float]],
) -> list[Any]:
    """The region of the motion (pale), the path (grey, travelled part black), the
    posture changes (diamonds) and the asked poses, labelled X1..Xm."""
    image, extent = backdrop
    artists: list[Any] = [
        ax.imshow(
            image, origin="lower", extent=extent, interpolation="nearest", aspect="auto", zorder=0
        )
    ]
    artists += ax.plot(poses[:, 0], poses[:, 1], "-", color="#999999", lw=1.2, zorder=2)
    if upto is not None:
        artists += ax.plot(
            poses[: upto + 1, 0], poses[: upto + 1, 1], "-", color="black", lw=1.4, zorder=3
        )
    changes = _posture_changes(motion["path"])
    if changes:
        artists += ax.plot(
            poses[changes, 0], poses[changes, 1], "D", color="white", mec="black", ms=5, zorder=3
        )
    for i, k in enumerate(_waypoints(motion)):
        artists += ax.plot([poses[k, 0]], [poses[k, 1]], lw=0, zorder=7, **_ASKED)
        artists.append(
            ax.annotate(
                f"X{i + 1}",
                (poses[k, 0], poses[k, 1]),
                xytext=(5, 5),
                textcoords="offset points",
                fontsize=FONT["label"],
                fontweight="bold",
                zorder=8,
            )
        )
    return artists


def _path_handles(result: Analysis, motion: Mapping[str, Any]) -> list[Any]:
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    m = result.mechanism
    path = motion["path"]
    handles: list[Any] = [
        Patch(color=_REGION_FILL, label=f"W_N{motion['region']} (certified part)"),
        Line2D([], [], color="#999999", lw=1.2, label="planned path"),
        Line2D([], [], color="black", lw=1.4, label="path travelled"),
        Line2D([], [], lw=0, label="asked poses X1, X2, ...", **_ASKED),
    ]
    if _posture_changes(path):
        handles.append(
            Line2D(
                [], [], marker="D", color="white", mec="black", ms=5, lw=0, label="posture change"
            )
        )
    if _rails(m, np.zeros(len(m.pose_names))):
        handles.append(Line2D([], [], color="#999999", lw=5, label="slider strokes"))
    seen = []
    for c in path:
        if c["posture"] not in seen:
            seen.append(c["posture"])
    for name in seen:
        k = _posture_index(m, name)
        handles.append(
            Line2D(
                [],
                [],
                color=PALETTE[k % len(PALETTE)],
                lw=2,
                marker="o",
                ms=4,
                label=f"posture {name}",
            )
        )
    return handles


def plot_path(
    result: Analysis, motion: Mapping[str, Any], count: int = 6, axes: Sequence[Axes] | None = None
) -> Figure:
    """Snapshots of a planned motion, like the paper's strip (a), (b), ...

    The first and the last configuration always have a panel, and so has every
    posture change (at most :data:`MAX_POSTURE_CHANGES`; the title says when
    more are left out); the asked poses (``motion["waypoints"]``, else the ends)
    come next, then steps spread along the motion, ``count`` panels or more.
    Every panel marks the asked poses X1, ..., Xm on the path and frames the
    whole mechanism over the whole motion at one scale.
    """
    m = result.mechanism
    path = motion["path"]
    frames = _frames(motion, count)
    poses, joints = _motion_arrays(motion)
    box = _mechanism_box(m, poses, joints)
    cols = 3 if len(frames) <= 9 else 4
    if axes is None:
        axes = panels(len(frames), cols, 3.6, aspect=_box_aspect(*box))
    cols = min(len(frames), cols)
    fig = figure_of(axes[0])
    waypoints = _waypoints(motion)
    letters = "abcdefghijklmnopqrstuvwxyz"
    backdrop = _backdrop(result, motion["region"], box)
    for n, k in enumerate(frames):
        ax = axes[n]
        _draw_route(ax, motion, poses, k, backdrop)
        conf = path[k]
        posture = conf["posture"]
        index = _posture_index(m, posture)
        _draw_rails(ax, m, poses[k])
        _draw_mechanism(ax, m, poses[k], joints[k], PALETTE[index % len(PALETTE)])
        title = f"({letters[n % 26]}) step {k}, posture {posture}"
        at = [f"X{i + 1}" for i, w in enumerate(waypoints) if w == k]
        if at:
            title += f", at {' = '.join(at)}"
        if k > 0 and path[k - 1]["posture"] != posture:
            title += f"\nposture change from {path[k - 1]['posture']}"
        _pose_axes(ax, m, title, box)
    _outer_labels(axes, len(frames), cols)
    for ax in axes[len(frames) :]:
        ax.set_axis_off()
    changes = _posture_changes(path)
    shown = min(len(changes), MAX_POSTURE_CHANGES)
    asked = {1: "at X1", 2: "from X1 to X2"}.get(
        len(waypoints), f"through X1, ..., X{len(waypoints)}"
    )
    title = (
        f"Motion in region {motion['region']} {asked}: {len(path)} configurations, "
        f"{len(changes)} posture change{'' if len(changes) == 1 else 's'}"
    )
    if shown < len(changes):
        title += f" (the first {shown} shown)"
    fig.suptitle(title, fontsize=FONT["suptitle"])
    opaque_legend(fig, _path_handles(result, motion), loc="outside lower center", ncol=4)
    return fig


def animate_path(result: Analysis, motion: Mapping[str, Any], out: str, fps: int = 20) -> None:
    """Write a GIF of a planned motion.

    At most about 120 frames, spread along the motion, with the first and the
    last configuration, every posture change and every asked pose (X1, ...,
    marked on the path); the axes frame the whole mechanism over the whole motion.
    """
    plt = pyplot()
    from matplotlib.animation import PillowWriter

    m = result.mechanism
    path = motion["path"]
    poses, joints = _motion_arrays(motion)
    n = len(path)
    keep = set(np.linspace(0, n - 1, min(n, 120)).round().astype(int).tolist())
    keep.update(_posture_changes(path))
    keep.update(_waypoints(motion))
    frames = sorted(keep)
    box = _mechanism_box(m, poses, joints)
    aspect = _box_aspect(*box)
    fig, ax = plt.subplots(
        figsize=(5.5, 5.5 * min(max(aspect, 0.3), 1.6) + 0.6), layout="constrained"
    )
    _draw_route(ax, motion, poses, None, _backdrop(result, motion["region"], box, pixels=300))
    _draw_rails(ax, m, poses[0])
    (travelled,) = ax.plot([], [], "-", color="black", lw=1.4, zorder=3)
    _pose_axes(ax, m, "step", box)
    # lay the figure out once: every frame has the same frame of axes
    fig.canvas.draw()
    fig.set_layout_engine("none")
    moving: list[Any] = []

    writer = PillowWriter(fps=fps)
    # each frame drawn once, straight to the writer
    with writer.saving(fig, out, dpi=100):
        for k in frames:
            while moving:
                moving.pop().remove()
            conf = path[k]
            travelled.set_data(poses[: k + 1, 0], poses[: k + 1, 1])
            color = PALETTE[_posture_index(m, conf["posture"]) % len(PALETTE)]
            moving.extend(_draw_mechanism(ax, m, poses[k], joints[k], color))
            ax.set_title(
                f"region {motion['region']}: step {k} of {n - 1}, posture {conf['posture']}",
                fontsize=FONT["title"],
            )
            writer.grab_frame()
    plt.close(fig)


# ------------------------------------------------------------------ figure
def figures_for(result: Analysis) -> tuple[str, ...]:
    """The figures that apply to an analysis: :data:`FIGURES` for two pose axes,
    :data:`FIGURES_3D` for three.

    Examples
    --------
    >>> from moveability import analyze
    >>> from moveability.mechanisms import FiveBar
    >>> figures_for(analyze(FiveBar(), precision=0.5))
    ('workspace', 'postures', 'regions', 'joint-space', 'path')
    """
    return {2: FIGURES, 3: FIGURES_3D}.get(result.tree.ndim, ())


def figure(
    name: str,
    result: Analysis,
    *,
    pose: ArrayLike | None = None,
    motion: Mapping[str, Any] | None = None,
    phis: ArrayLike | None = None,
) -> Figure:
    """One of :data:`FIGURES` or :data:`FIGURES_3D` for an analysis.

    ``pose`` is for postures, ``motion`` (from :func:`moveability.plan_motion`) for
    path, ``phis`` (radians) for slices.
    Asking a figure of the other number of pose axes raises
    :class:`~moveability.errors.InvalidParameterError` naming ``figure``.
    """
    from ..errors import InvalidParameterError

    if name not in FIGURES + FIGURES_3D:
        raise InvalidParameterError("figure", f"one of {', '.join(FIGURES + FIGURES_3D)}", name)
    allowed = figures_for(result)
    if name not in allowed:
        k = result.tree.ndim
        raise InvalidParameterError(
            "figure",
            f"a figure of a mechanism with {k} pose axes ({', '.join(allowed) or 'none'})",
            name,
        )
    if name == "slices":
        from .plot3d import plot_slices

        return plot_slices(result, phis=phis)
    if name == "regions-3d":
        from .plot3d import plot_regions_3d

        return plot_regions_3d(result)
    if name == "workspace":
        return plot_workspace(result)
    if name == "postures":
        if pose is None:
            pose = _default_pose(result)
        return plot_postures(result.mechanism, pose)
    if name == "regions":
        return plot_regions(result)
    if name == "joint-space":
        return plot_joint_space(result)
    if motion is None:
        raise InvalidParameterError(
            "motion", "a motion planned by moveability.plan_motion, for the path figure", None
        )
    return plot_path(result, motion)


def _default_pose(result: Analysis) -> Array:
    """A pose of W where the most postures are within the limits."""
    leaves = result.tree.leaves()
    t = result.table
    score = (t.status == IN).sum(axis=1) + 1e-6 * (leaves.hi - leaves.lo).prod(axis=1)
    best = int(np.argmax(score))
    return 0.5 * (leaves.lo[best] + leaves.hi[best])
