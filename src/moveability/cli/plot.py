"""``moveability plot``: one figure of the analysis, as PNG or SVG."""

from __future__ import annotations

from typing import Any

import click
import numpy as np

from ..errors import InputError
from ..extras import require
from ..poses import read_points
from . import options, running
from .files import check_file, written_whole

__all__ = ["plot_command"]


def _pose(text: str | None) -> np.ndarray | None:
    if text is None:
        return None
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise InputError(
            f"invalid --pose: expected numbers separated by commas, got {text!r}"
        ) from None
    if not np.isfinite(values).all():
        raise InputError(f"invalid --pose: expected finite numbers, got {text!r}")
    return np.array(values)


def _check_pose(at: np.ndarray, mechanism: Any) -> None:
    """Refuse a ``--pose`` of the wrong length, or one that no posture reaches."""
    names = tuple(mechanism.pose_names)
    if at.shape != (len(names),):
        raise InputError(
            f"invalid --pose: expected {len(names)} numbers ({','.join(names)}), got {at.size}"
        )
    q = np.asarray(mechanism.joint_angles(at[None, :]))[0]
    shown = ", ".join(f"{v:g}" for v in at)
    reached = np.isfinite(q).all(axis=-1)
    if not reached.any():
        raise InputError(
            f"invalid --pose: no posture reaches ({shown}): it lies outside the workspace"
        )
    within = reached.copy()
    for i, lim in enumerate(mechanism.limits):
        within[reached] &= np.asarray(lim.contains(q[reached, i]), dtype=bool)
    if not within.any():
        raise InputError(
            f"invalid --pose: no posture within the joint limits reaches ({shown}): it lies "
            "outside the workspace"
        )


def _check_figure(name: str, mechanism: object) -> None:
    """Refuse, before the analysis, a figure drawn for the other number of pose axes."""
    from ..output.plot import FIGURES, FIGURES_3D

    axes = tuple(getattr(mechanism, "pose_names", ()))
    fitting = {2: FIGURES, 3: FIGURES_3D}.get(len(axes), ())
    if name not in fitting:
        use = f"use {' or '.join(fitting)}" if fitting else "no figure applies"
        raise InputError(
            f"invalid --figure: {name!r} does not apply to a mechanism with {len(axes)} pose "
            f"axes ({', '.join(axes)}); {use}"
        )


def _check_cuts(mechanism: Any, phis: tuple[float, ...], heights: tuple[float, ...]) -> None:
    """Refuse angles for slices across a height, and heights for slices across an angle."""
    angle = 2 in tuple(getattr(mechanism, "periodic_axes", ()))
    third = tuple(mechanism.pose_names)[2]
    if phis and not angle:
        raise InputError(f"invalid --phi: the slices cut {third}, a height: give --z")
    if heights and angle:
        raise InputError(f"invalid --z: the slices cut {third}, an angle: give --phi")


@click.command("plot")
@options.spec_argument
@click.option(
    "--figure",
    "name",
    required=True,
    type=click.Choice(
        ["workspace", "postures", "regions", "joint-space", "path", "slices", "regions-3d"]
    ),
    help="Which figure: slices and regions-3d for mechanisms with 3 pose axes (x, y, phi), "
    "the others for 2.",
)
@click.option(
    "--out",
    "out",
    required=True,
    help="Output file: .png or .svg (.gif with --animate).",
)
@click.option("--pose", default=None, help="Pose x,y for the postures figure.")
@click.option(
    "--points",
    default=None,
    help="CSV of poses for the path figure (default: two poses of the largest region).",
)
@click.option(
    "--phi",
    "phis",
    multiple=True,
    type=float,
    metavar="DEG",
    help="With --figure slices: an angle of the slices in degrees; repeat for several "
    "(default -135, -45, 45, 135).",
)
@click.option(
    "--z",
    "heights",
    multiple=True,
    type=float,
    metavar="Z",
    help="With --figure slices, for a mechanism whose third pose axis is a height (the "
    "Delta): a height of the slices in length units; repeat for several (default: four "
    "across the workspace).",
)
@click.option("--animate", is_flag=True, help="With --figure path: write an animated GIF.")
@click.option("--overwrite", is_flag=True, help="Replace --out if it exists.")
@options.precision_option
@options.resolve_option
def plot_command(
    spec: str,
    name: str,
    out: str,
    pose: str | None,
    points: str | None,
    phis: tuple[float, ...],
    heights: tuple[float, ...],
    animate: bool,
    overwrite: bool,
    precision: float,
) -> None:
    """Draw one figure of the analysis of the manipulator of SPEC (a spec file, or an
    analysis saved by ``moveability analyze --out``)."""
    from ..errors import PlanningError

    if animate and name != "path":
        raise InputError("invalid --animate: only the path figure is animated")
    if phis and name != "slices":
        raise InputError("invalid --phi: only the slices figure takes angles")
    if not all(np.isfinite(phis)):
        raise InputError(f"invalid --phi: expected finite angles, got {list(phis)!r}")
    if heights and name != "slices":
        raise InputError("invalid --z: only the slices figure takes heights")
    if not all(np.isfinite(heights)):
        raise InputError(f"invalid --z: expected finite heights, got {list(heights)!r}")
    if pose is not None and name != "postures":
        raise InputError("invalid --pose: only the postures figure takes a pose")
    if points is not None and name != "path":
        raise InputError("invalid --points: only the path figure takes poses")
    check_file(out, "--out", overwrite, (".gif",) if animate else (".png", ".svg"))
    at = _pose(pose)
    with running.reporting_errors():
        require("matplotlib", "plot", "figures")
        saved = running.open_analysis(spec, precision) if running.is_saved(spec) else None
        mechanism = saved.mechanism if saved is not None else running.load_mechanism(spec)
        _check_figure(name, mechanism)
        if name == "slices":
            _check_cuts(mechanism, phis, heights)
        if at is not None:
            _check_pose(at, mechanism)
        poses = None
        if points is not None:
            poses = read_points(points, mechanism.pose_names, "--points")
        from ..analysis.planning import default_poses, plan_motion
        from ..output.plot import animate_path, figure, plot_postures

        result: Any = None  # the postures at a given pose need no analysis
        if name != "postures" or at is None:
            result = saved
            if result is None:
                result = running.open_analysis(spec, precision, mechanism=mechanism)
        try:
            with written_whole(out) as temporary:
                if result is None and at is not None:
                    fig = plot_postures(mechanism, at)
                    fig.savefig(temporary, dpi=110, bbox_inches="tight")
                elif name == "path":
                    motion = plan_motion(
                        result, poses if poses is not None else default_poses(result)
                    )
                    if animate:
                        running.status(f"drawing the animation of {out}")
                        animate_path(result, motion, temporary)
                    else:
                        figure(name, result, motion=motion).savefig(
                            temporary, dpi=110, bbox_inches="tight"
                        )
                else:
                    cuts = np.radians(phis) if phis else (np.array(heights) if heights else None)
                    fig = figure(name, result, pose=at, phis=cuts)
                    fig.savefig(temporary, dpi=110, bbox_inches="tight")
        except PlanningError as error:
            click.echo(f"Error: no motion: {error}", err=True)
            raise SystemExit(3) from None
    click.echo(f"wrote {out}", err=True)
