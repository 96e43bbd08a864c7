"""``moveability plan``: a motion through a list of poses, inside one region."""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from typing import Any

import click

from . import options, printing, running

__all__ = ["format_plan", "plan_command"]

#: exit status when no certified motion joins the poses
NO_MOTION = 3


def format_plan(data: Mapping[str, Any]) -> str:
    """A summary for people of the JSON of ``moveability plan``.

    Examples
    --------
    >>> print(format_plan({"feasible": True, "region": 0, "path": [
    ...     {"pose": [1.0, 3.0], "joints": [1.5, 2.0], "posture": "+-"},
    ...     {"pose": [1.1, 3.0], "joints": [1.49, 1.98], "posture": "++"}],
    ...     "length": {"pose": {"before": 0.12, "after": 0.1},
    ...                "joints": {"before": 0.03, "after": 0.025}}}))
    motion in N-connected region 0: 2 configurations, 1 posture change(s)
    start  pose (1, 3) joints (1.5, 2) posture +-
    end    pose (1.1, 3) joints (1.49, 1.98) posture ++
    length in pose 0.12 -> 0.1, in the joints 0.03 -> 0.025 (the chain of cells -> smoothed)
    """
    path = data["path"]
    changes = sum(1 for a, b in itertools.pairwise(path) if a["posture"] != b["posture"])

    def show(c: Mapping[str, Any]) -> str:
        pose = ", ".join(f"{v:.6g}" for v in c["pose"])
        joints = ", ".join(f"{v:.6g}" for v in c["joints"])
        return f"pose ({pose}) joints ({joints}) posture {c['posture']}"

    lines = [
        f"motion in N-connected region {data['region']}: {len(path)} configurations, "
        f"{changes} posture change(s)",
        f"start  {show(path[0])}",
        f"end    {show(path[-1])}",
    ]
    length = data.get("length")
    if length:
        pose, joints = length["pose"], length["joints"]
        lines.append(
            f"length in pose {pose['before']:.4g} -> {pose['after']:.4g}, in the joints "
            f"{joints['before']:.4g} -> {joints['after']:.4g} (the chain of cells -> smoothed)"
        )
    return "\n".join(lines)


@click.command("plan")
@options.spec_argument
@options.points_argument
@options.precision_option
@options.json_options
@options.resolve_option
@click.option(
    "--smooth/--no-smooth",
    default=True,
    show_default=True,
    help="Shorten and smooth the chain of cells through certified shortcuts.",
)
def plan_command(
    spec: str, points: str, precision: float, json_out: str | None, overwrite: bool, smooth: bool
) -> None:
    """A continuous motion through the poses of POINTS, in order, inside one
    region (no parallel singularity, no joint limit crossed).

    The chain of certified cells is shortened and smoothed where every
    configuration of a shortcut is certified (valid, det A of the region's
    sign); --no-smooth keeps the chain. Consecutive configurations are at most
    the precision apart in pose and in each joint. Exits with status 3, saying
    which poses are apart, when no region is known to hold them all.
    """
    from ..analysis.planning import plan_motion
    from ..errors import PlanningError

    printing.check_output(json_out, overwrite)
    with running.reporting_errors():
        result, poses = running.analyse_poses(spec, points, precision)
        try:
            data = plan_motion(result, poses, smooth=smooth)
        except PlanningError as error:
            if json_out is not None:
                # the answer as feasible gives it, with the reason: JSON that pipes
                answer = result.feasible(poses)
                failed = {
                    "feasible": answer["feasible"],
                    "region": None,
                    "path": [],
                    "reason": str(error),
                }
                printing.write_output(failed, json_out, overwrite, lambda _: "")
            click.echo(f"Error: no motion: {error}", err=True)
            raise SystemExit(NO_MOTION) from None
    printing.write_output(data, json_out, overwrite, format_plan)
