"""``moveability plot``: one figure of the analysis, as PNG or SVG."""

from __future__ import annotations

import os

import click
import numpy as np

from ..errors import InputError
from ..extras import require
from ..poses import read_points
from . import options, running

__all__ = ["plot_command"]


def _pose(text: str | None) -> np.ndarray | None:
    if text is None:
        return None
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise InputError(f"invalid --pose: expected x,y numbers, got {text!r}") from None
    if not np.isfinite(values).all():
        raise InputError(f"invalid --pose: expected finite numbers, got {text!r}")
    return np.array(values)


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
    type=click.Path(dir_okay=False),
    help="Output file: .png or .svg (.gif with --animate).",
)
@click.option("--pose", default=None, help="Pose x,y for the postures figure.")
@click.option(
    "--points",
    default=None,
    type=click.Path(dir_okay=False),
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
    animate: bool,
    overwrite: bool,
    precision: float,
) -> None:
    """Draw one figure of the analysis of the manipulator of SPEC."""
    from ..errors import PlanningError

    ext = os.path.splitext(out)[1].lower()
    allowed = (".gif",) if animate else (".png", ".svg")
    if ext not in allowed:
        raise InputError(
            f"invalid --out: expected a {' or '.join(allowed)} file, got {out!r}"
        )
    if animate and name != "path":
        raise InputError("invalid --animate: only the path figure is animated")
    if phis and name != "slices":
        raise InputError("invalid --phi: only the slices figure takes angles")
    if not all(np.isfinite(phis)):
        raise InputError(f"invalid --phi: expected finite angles, got {list(phis)!r}")
    if os.path.exists(out) and not overwrite:
        raise InputError(f"refusing to overwrite {out}: it exists (use --overwrite)")
    at = _pose(pose)
    with running.reporting_errors():
        require("matplotlib", "plot", "figures")
        mechanism = running.load_mechanism(spec)
        _check_figure(name, mechanism)
        poses = read_points(points, mechanism.pose_names) if points else None
        result = running.run_analysis(mechanism, precision, running.progress_reporter())
        from ..analysis.planning import default_poses, plan_motion
        from ..output.plot import animate_path, figure

        try:
            motion = None
            if name == "path":
                motion = plan_motion(result, poses if poses is not None else default_poses(result))
            if motion is not None and animate:
                animate_path(result, motion, out)
            else:
                angles = np.radians(phis) if phis else None
                fig = figure(name, result, pose=at, motion=motion, phis=angles)
                fig.savefig(out, dpi=110, bbox_inches="tight")
        except PlanningError as error:
            click.echo(f"Error: no motion: {error}", err=True)
            raise SystemExit(3) from None
    click.echo(f"wrote {out}", err=True)
