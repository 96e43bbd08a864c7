"""Figures of an analysis: workspace, postures, regions, joint space, planned motion.

Every ``plot_*`` function draws on the axes it is given (or new ones) and
returns the figure; matplotlib is imported here only. Colours follow the
Okabe-Ito palette, which stays distinct with colour-blind vision; lengths are
in the units of the mechanism's spec, angles in radians.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ..hypertree.status import IN, OUT
from ..types import Array
from .axes import PALETTE, UNDECIDED, draw_cells, figure_of, frame_axes, panels, pyplot

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from ..analysis.result import Analysis
    from ..mechanisms.base import Mechanism

__all__ = [
    "FIGURES",
    "FIGURES_3D",
    "PALETTE",
    "animate_path",
    "figure",
    "figures_for",
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


def _axes(ax: Axes | None, **kwargs: Any) -> tuple[Figure, Axes]:
    if ax is not None:
        return ax.figure, ax  # type: ignore[return-value]
    fig, ax = pyplot().subplots(**kwargs)
    return fig, ax


def _grid(mechanism: Mechanism, n: int = 400) -> tuple[Array, Array, Array]:
    lo, hi = mechanism.bounds
    xs = np.linspace(lo[0], hi[0], n)
    ys = np.linspace(lo[1], hi[1], n)
    gx, gy = np.meshgrid(xs, ys)
    return gx, gy, np.stack([gx.ravel(), gy.ravel()], axis=1)


# ---------------------------------------------------------------- workspace
def plot_workspace(result: Analysis, ax: Axes | None = None) -> Figure:
    """The workspace W (certain and undecided cells) with the singularity loci.

    Parallel singularities (det A = 0) are drawn per posture, serial ones (a
    leg's branches meeting) per leg.
    """
    fig, ax = _axes(ax, figsize=(7, 7))
    m = result.mechanism
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
    from matplotlib.patches import Patch

    handles = [
        Patch(color="#DDEEFF", label="W (certain)"),
        Patch(color=UNDECIDED, label="W undecided at this precision"),
        *handles,
    ]
    ax.legend(handles=handles, loc="upper right", fontsize=7)
    frame_axes(ax, m, f"Workspace W and singularity loci (precision {result.precision_text})")
    return fig


# ----------------------------------------------------------------- postures
def _draw_mechanism(
    ax: Axes,
    mechanism: Mechanism,
    pose: Array,
    joints: Array,
    color: str,
    alpha: float = 1.0,
    label: str | None = None,
) -> list[Any]:
    """Links of a mechanism: each leg's ``links`` (fixed joint, ..., platform point)."""
    artists = []
    for i, leg in enumerate(mechanism.legs):
        pts = leg.links(np.asarray(pose, dtype=np.float64), float(joints[i]))  # type: ignore[attr-defined]
        (line,) = ax.plot(
            pts[:, 0],
            pts[:, 1],
            "-o",
            color=color,
            alpha=alpha,
            lw=2,
            ms=4,
            label=label if i == 0 else None,
        )
        artists.append(line)
        ax.plot([pts[0, 0]], [pts[0, 1]], "s", color="black", ms=6)
    ax.plot([pose[0]], [pose[1]], "o", color="black", ms=5)
    return artists


def plot_postures(
    mechanism: Mechanism, pose: ArrayLike, axes: Sequence[Axes] | None = None
) -> Figure:
    """The mechanism at one pose in each of its postures.

    Postures beyond a joint limit are drawn faint and say so; singular ones
    (|det A| or a leg's serial term nearly zero) are marked.
    """
    p = np.asarray(pose, dtype=np.float64).reshape(1, -1)
    q = mechanism.joint_angles(p)[0]
    n = q.shape[0]
    if axes is None:
        axes = panels(n, 4, 4)
    fig = figure_of(axes[0])
    scale = float(np.abs(np.concatenate(mechanism.bounds)).max())
    for k in range(n):
        ax = axes[k]
        name = mechanism.posture_name(k)
        if not np.isfinite(q[k]).all():
            ax.set_title(f"posture {name}: unreachable")
            ax.set_axis_off()
            continue
        within = all(lim.contains(q[k, i]) for i, lim in enumerate(mechanism.limits))
        det = float(mechanism.det_a(p, q[k][None, :])[0])
        serial = [
            float(leg.serial_term(p, q[k][None, i])[0]) for i, leg in enumerate(mechanism.legs)
        ]
        singular = abs(det) < 1e-3 * scale**2 or min(abs(s) for s in serial) < 1e-3 * scale**2
        color = PALETTE[k % len(PALETTE)]
        _draw_mechanism(ax, mechanism, p[0], q[k], color, alpha=1.0 if within else 0.3)
        angles = ", ".join(f"{v:.3f}" for v in q[k])
        state = [] if within else ["beyond a joint limit"]
        if singular:
            state.append("singular")
        title = f"posture {name}: q = ({angles}) rad\ndet A = {det:.3g}"
        if state:
            title += " [" + ", ".join(state) + "]"
        ax.set_title(title, fontsize=8)
        frame_axes(ax, mechanism, ax.get_title())
        ax.set_title(title, fontsize=8)
    for ax in axes[n:]:
        ax.set_axis_off()
    fig.suptitle(f"Postures at pose ({', '.join(f'{v:g}' for v in p[0])})", y=1.04)
    return fig


# ------------------------------------------------------------------ regions
def plot_regions(result: Analysis, axes: Sequence[Axes] | None = None) -> Figure:
    """Each N-connected region W_Nj (one panel each) and an overlay.

    Dark: certified part of W_Nj; light: where W_Nj may extend (undecided band).
    """
    regions = result.regions
    n = len(regions) + 1
    if axes is None:
        axes = panels(n, 3, 5.5)
    fig = figure_of(axes[0])
    leaves = result.tree.leaves()
    overlay = axes[len(regions)]
    from matplotlib.patches import Patch

    overlay_handles = []
    for j, region in enumerate(regions):
        color = PALETTE[j % len(PALETTE)]
        sure, maybe = result.region_cells(j)
        ax = axes[j]
        draw_cells(ax, leaves.lo[sure], leaves.hi[sure], color)
        draw_cells(ax, leaves.lo[maybe], leaves.hi[maybe], color, alpha=0.3)
        label = (
            f"W_N{region.id}: area in [{region.area[0]:.3f}, {region.area[1]:.3f}], "
            f"det A {'>' if region.sign > 0 else '<'} 0"
        )
        ax.legend(
            handles=[
                Patch(color=color, label="certified"),
                Patch(color=color, alpha=0.3, label="undecided band"),
                Patch(color="white", label=label),
            ],
            loc="upper right",
            fontsize=7,
        )
        frame_axes(ax, result.mechanism, f"N-connected region {region.id}")
        draw_cells(overlay, leaves.lo[sure], leaves.hi[sure], color, alpha=0.45)
        overlay_handles.append(Patch(color=color, alpha=0.45, label=label))
    overlay.legend(handles=overlay_handles, loc="upper right", fontsize=7)
    frame_axes(overlay, result.mechanism, "All N-connected regions")
    for ax in axes[n:]:
        ax.set_axis_off()
    fig.suptitle(f"N-connected regions (precision {result.precision_text})")
    return fig


# -------------------------------------------------------------- joint space
def plot_joint_space(result: Analysis, ax: Axes | None = None, samples: int = 4) -> Figure:
    """The joint space Q: parallel-singularity curves and the traces of the regions.

    A region's trace is the set of joint vectors of its certified configurations.
    """
    fig, ax = _axes(ax, figsize=(7, 6))
    m = result.mechanism
    leaves = result.tree.leaves()
    g, t = result.graph, result.table
    rng = np.random.default_rng(0)
    for j, region in enumerate(result.regions):
        color = PALETTE[j % len(PALETTE)]
        nodes = np.argwhere((g.certain == region.certain) & (t.status == IN))
        if not nodes.size:
            continue
        lo, hi = leaves.lo[nodes[:, 0]], leaves.hi[nodes[:, 0]]
        pts = (
            lo[:, None, :] + rng.random((lo.shape[0], samples, lo.shape[1])) * (hi - lo)[:, None, :]
        ).reshape(-1, lo.shape[1])
        post = np.repeat(nodes[:, 1], samples)
        q = m.joint_angles(pts)[np.arange(pts.shape[0]), post]
        q = np.stack([lim.wrap(q[:, i]) for i, lim in enumerate(m.limits)], axis=1)
        ax.scatter(
            q[:, 0],
            q[:, 1],
            s=0.3,
            color=color,
            alpha=0.5,
            label=f"trace of region {region.id} (det A {'>' if region.sign > 0 else '<'} 0)",
        )
    from matplotlib.lines import Line2D

    from ..mechanisms import FiveBar

    lims = m.limits
    qs = [np.linspace(lim.lo, lim.lo + 2 * np.pi if lim.periodic else lim.hi, 400) for lim in lims]
    handles, _ = ax.get_legend_handles_labels()
    for h in handles:
        h.set_sizes([20])  # type: ignore[attr-defined]
    if isinstance(m, FiveBar):
        # parallel singularities: where the circles about C and D are tangent
        g1, g2 = np.meshgrid(qs[0], qs[1], indexing="ij")
        c = m.rr_legs[0].elbow(g1)
        d = m.rr_legs[1].elbow(g2)
        cd = np.hypot(*(c - d).transpose(2, 0, 1))
        b1, b2 = m.rr_legs[0].distal, m.rr_legs[1].distal
        for level, style in ((b1 + b2, "-"), (abs(b1 - b2), "--")):
            if cd.min() < level < cd.max():
                ax.contour(
                    g1, g2, cd, levels=[level], colors=["black"], linestyles=[style], linewidths=1.0
                )
        handles += [
            Line2D([], [], color="black", label="det A = 0: |CD| = L2 + L4"),
            Line2D([], [], color="black", linestyle="--", label="det A = 0: |CD| = |L2 - L4|"),
        ]
    ax.legend(handles=handles, loc="upper right", fontsize=7)
    ax.set_xlim(qs[0][0], qs[0][-1])
    ax.set_ylim(qs[1][0], qs[1][-1])
    ax.set_aspect("equal")
    units = ["" if lim.prismatic else " (rad)" for lim in lims]
    ax.set_xlabel(f"{m.joint_names[0]}{units[0]}")
    ax.set_ylabel(f"{m.joint_names[1]}{units[1]}")
    title = "singularity curves and region traces" if isinstance(m, FiveBar) else "region traces"
    ax.set_title(f"Joint space Q: {title}")
    return fig


# ---------------------------------------------------------------------- path
def _frames(motion: Mapping[str, Any], count: int) -> list[int]:
    path = motion["path"]
    changes = [k for k in range(1, len(path)) if path[k]["posture"] != path[k - 1]["posture"]]
    picks = set(np.linspace(0, len(path) - 1, count).round().astype(int).tolist())
    picks.update(changes[: max(0, count - 2)])
    return sorted(picks)[: max(count, len(changes) + 2)]


def plot_path(
    result: Analysis, motion: Mapping[str, Any], count: int = 6, axes: Sequence[Axes] | None = None
) -> Figure:
    """A strip of snapshots of a planned motion, posture changes marked."""
    m = result.mechanism
    path = motion["path"]
    frames = _frames(motion, count)
    if axes is None:
        axes = panels(len(frames), 3, 4.5)
    fig = figure_of(axes[0])
    poses = np.array([c["pose"] for c in path])
    letters = "abcdefghijklmnopqrstuvwxyz"
    for n, k in enumerate(frames):
        ax = axes[n]
        ax.plot(poses[:, 0], poses[:, 1], "-", color=UNDECIDED, lw=1)
        ax.plot(poses[: k + 1, 0], poses[: k + 1, 1], "-", color="black", lw=1)
        conf = path[k]
        posture = conf["posture"]
        index = next(i for i in range(len(m.postures)) if m.posture_name(i) == posture)
        _draw_mechanism(
            ax, m, np.array(conf["pose"]), np.array(conf["joints"]), PALETTE[index % len(PALETTE)]
        )
        changed = k > 0 and path[k - 1]["posture"] != posture
        title = f"({letters[n % 26]}) step {k}, posture {posture}"
        if changed:
            title += "  <- posture change"
        frame_axes(ax, m, title)
    for ax in axes[len(frames) :]:
        ax.set_axis_off()
    fig.suptitle(f"Motion in region {motion['region']}: {len(path)} configurations")
    return fig


def animate_path(result: Analysis, motion: Mapping[str, Any], out: str, fps: int = 20) -> None:
    """Write a GIF of a planned motion."""
    plt = pyplot()
    from matplotlib.animation import FuncAnimation, PillowWriter

    m = result.mechanism
    path = motion["path"]
    keep = np.unique(np.linspace(0, len(path) - 1, min(len(path), 120)).round().astype(int))
    fig, ax = plt.subplots(figsize=(5, 5))
    poses = np.array([c["pose"] for c in path])

    def draw(i: int) -> list[Any]:
        ax.clear()
        k = int(keep[i])
        conf = path[k]
        ax.plot(poses[:, 0], poses[:, 1], "-", color=UNDECIDED, lw=1)
        index = next(j for j in range(len(m.postures)) if m.posture_name(j) == conf["posture"])
        artists = _draw_mechanism(
            ax, m, np.array(conf["pose"]), np.array(conf["joints"]), PALETTE[index % len(PALETTE)]
        )
        frame_axes(ax, m, f"step {k}, posture {conf['posture']}")
        return artists

    anim = FuncAnimation(fig, draw, frames=len(keep), blit=False)
    anim.save(out, writer=PillowWriter(fps=fps))
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
