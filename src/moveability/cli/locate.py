"""``moveability locate``: the regions that hold each pose of a list."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import click

from ..types import word
from . import options, printing, running

__all__ = ["format_locate", "locate_command"]


def format_locate(data: Mapping[str, Any]) -> str:
    """A summary for people of the JSON of ``moveability locate``.

    Examples
    --------
    >>> print(format_locate({
    ...     "regions": [0, 1],
    ...     "points": [
    ...         {"pose": [1.0, 2.5], "workspace": True, "regions": {"0": True, "1": False}},
    ...         {"pose": [9.0, 0.0], "workspace": None, "regions": {"0": False, "1": None}},
    ...     ],
    ... }))
    pose     workspace region 0 region 1
    1, 2.5         yes      yes       no
    9, 0       unknown       no  unknown
    """
    ids = [str(region) for region in data["regions"]]
    header = ["pose", "workspace", *(f"region {region}" for region in ids)]
    rows = [
        [
            ", ".join(f"{coordinate:g}" for coordinate in point["pose"]),
            word(point["workspace"]),
            *(word(point["regions"][region]) for region in ids),
        ]
        for point in data["points"]
    ]
    return printing.format_table(header, rows)


@click.command("locate")
@options.spec_argument
@options.points_argument
@options.precision_option
@options.json_options
@options.aspects_option
@options.resolve_option
def locate_command(
    spec: str,
    points: str,
    precision: float,
    json_out: str | None,
    overwrite: bool,
    generalized_aspects: bool,
) -> None:
    """Whether each pose of POINTS is in the workspace and in each N-connected region.

    SPEC is a TOML file describing the manipulator. POINTS is a CSV file ('-'
    for stdin) whose header names the pose coordinates (x,y for a five-bar),
    one pose per row. Each answer is true, false or null in JSON (yes, no or
    unknown in the summary): null when undecided at this precision.
    """
    printing.check_output(json_out, overwrite)
    with running.reporting_errors():
        result, poses = running.analyse_poses(spec, points, precision, generalized_aspects)
        data = result.locate(poses)
    printing.write_output(data, json_out, overwrite, format_locate)
