"""``moveability report``: a self-contained HTML page of the analysis."""

from __future__ import annotations

import os

import click

from ..extras import require
from . import options, running
from .files import check_folder, folder_written_whole

__all__ = ["report_command"]


@click.command("report")
@options.spec_argument
@click.option(
    "--out",
    "out",
    required=True,
    help="Directory to write index.html into.",
)
@click.option("--overwrite", is_flag=True, help="Replace OUT/index.html if it exists.")
@options.precision_option
@options.resolve_option
def report_command(spec: str, out: str, overwrite: bool, precision: float) -> None:
    """Write OUT/index.html: the spec, the summary table and every figure.

    SPEC is a spec file, or an analysis saved by ``moveability analyze --out``.
    The page embeds its figures and opens in a browser without a server.
    """
    check_folder(out, "--out", overwrite, ("index.html",))
    with running.reporting_errors():
        require("matplotlib", "plot", "the report's figures")
        result = running.open_analysis(spec, precision)
        from ..analysis.planning import default_poses, plan_motion
        from ..errors import PlanningError
        from ..output.report import write_report

        try:
            motion, why = plan_motion(result, default_poses(result)), ""
        except PlanningError as error:
            motion, why = None, str(error)
        running.status(f"drawing the figures of {out}")
        with folder_written_whole(out) as temporary:
            written = write_report(result, temporary, motion, no_motion=why, spec_path=spec)
        path = os.path.join(out, os.path.basename(written))
    click.echo(path)
