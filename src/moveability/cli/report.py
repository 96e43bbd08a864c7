"""``moveability report``: a self-contained HTML page of the analysis."""

from __future__ import annotations

import click

from ..extras import require
from . import options, running

__all__ = ["report_command"]


@click.command("report")
@options.spec_argument
@click.option(
    "--out",
    "out",
    required=True,
    type=click.Path(file_okay=False),
    help="Directory to write index.html into.",
)
@options.precision_option
@options.resolve_option
def report_command(spec: str, out: str, precision: float) -> None:
    """Write OUT/index.html: the spec, the summary table and every figure.

    The page embeds its figures and opens in a browser without a server.
    """
    with running.reporting_errors():
        require("matplotlib", "plot", "the report's figures")
        mechanism = running.load_mechanism(spec)
        result = running.run_analysis(mechanism, precision, running.progress_reporter())
        from ..analysis.planning import default_poses, plan_motion
        from ..errors import PlanningError
        from ..output.report import write_report

        try:
            motion, why = plan_motion(result, default_poses(result)), ""
        except PlanningError as error:
            motion, why = None, str(error)
        path = write_report(result, out, motion, no_motion=why)
    click.echo(path)
