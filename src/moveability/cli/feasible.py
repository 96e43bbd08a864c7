"""``moveability feasible``: can the manipulator move through a list of poses?"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import click

from ..types import word
from . import options, printing, running

__all__ = ["feasible_command", "format_feasible"]


def format_feasible(data: Mapping[str, Any]) -> str:
    """A summary for people of the JSON of ``moveability feasible``.

    Examples
    --------
    >>> print(format_feasible({"feasible": True, "region": 1,
    ...                        "postures": [[0.5, 2.0], [0.25, 1.5]]}))
    feasible: yes (N-connected region 1)
    posture 1: 0.5, 2
    posture 2: 0.25, 1.5
    >>> print(format_feasible({"feasible": None, "region": None, "postures": None}))
    feasible: unknown
    """
    line = f"feasible: {word(data['feasible'])}"
    if data.get("region") is not None:
        line += f" (N-connected region {data['region']})"
    lines = [line]
    for number, posture in enumerate(data.get("postures") or [], start=1):
        lines.append(f"posture {number}: " + ", ".join(f"{angle:.6g}" for angle in posture))
    return "\n".join(lines)


@click.command("feasible")
@options.spec_argument
@options.points_argument
@options.precision_option
@options.json_options
@options.aspects_option
@options.resolve_option
def feasible_command(
    spec: str,
    points: str,
    precision: float,
    json_out: str | None,
    overwrite: bool,
    generalized_aspects: bool,
) -> None:
    """Whether the manipulator can move through every pose of POINTS without
    crossing a parallel singularity or a joint limit.

    SPEC is a TOML file describing the manipulator. POINTS is a CSV file ('-'
    for stdin) whose header names the pose coordinates (x,y for a five-bar).
    The answer is true, false or null (unknown at this precision); when true,
    the N-connected region and a posture (joint angles, radians) for each pose.
    """
    printing.check_output(json_out, overwrite)
    with running.reporting_errors():
        result, poses = running.analyse_poses(spec, points, precision, generalized_aspects)
        data = result.feasible(poses)
    printing.write_output(data, json_out, overwrite, format_feasible)
