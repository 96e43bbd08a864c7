"""``moveability sweep``: analyse the product of parameter and limit ranges, one row per design."""

from __future__ import annotations

import logging
import sys
from typing import Any

import click

from ..errors import InputError
from ..extras import require
from . import options, running
from .files import check_file, written_whole

__all__ = ["sweep_command"]


class _LogProgress:
    """One log line per result (``-v`` when stderr is not a terminal)."""

    def __init__(self) -> None:
        from ..sweep.progress import SweepProgress

        self._format = SweepProgress(None, terminal=False)

    def __call__(self, done: int, total: int) -> None:
        import time

        if self._format.start is None:
            self._format.start, self._format.first_done = time.monotonic(), done
        running.logger.info(
            "%s", self._format.line(done, total, time.monotonic() - self._format.start)
        )


def sweep_progress() -> Any:
    """The sweep's progress display: a bar on a terminal, log lines with ``-v``, else none."""
    from ..sweep.progress import SweepProgress

    if sys.stderr.isatty() and running.logger.isEnabledFor(logging.WARNING):
        return SweepProgress(sys.stderr, terminal=True)
    if running.logger.isEnabledFor(logging.INFO):
        return _LogProgress()
    return None


class _Jobs(click.ParamType):
    """A positive integer; a bad value is an :class:`~.InputError` (one line)."""

    name = "N"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> int:
        try:
            jobs = int(value)
        except (TypeError, ValueError):
            jobs = 0
        if jobs < 1:
            raise InputError(f"invalid --jobs: expected a positive integer, got {value!r}")
        return jobs


def _check_jobs(jobs: int | None, scheduler: str | None) -> int:
    if jobs is not None and scheduler is not None:
        raise InputError(
            "invalid --jobs: expected nothing with --scheduler (the Dask cluster sets the "
            f"workers), got {jobs}"
        )
    return 1 if jobs is None else jobs


@click.command("sweep")
@options.spec_argument
@click.option(
    "--vary",
    "vary",
    metavar="NAME=START:STOP:COUNT",
    multiple=True,
    required=True,
    help="A parameter (L1) or a limit end (theta1.min, theta1.max) and COUNT values "
    "from START to STOP; angles may be written with pi (pi/2). Repeat for a product.",
)
@options.precision_option
@click.option(
    "--jobs", "-j", type=_Jobs(), default=None, help="Local worker processes (joblib). [default: 1]"
)
@click.option(
    "--scheduler",
    metavar="ADDRESS",
    default=None,
    help="Run on an existing Dask cluster (tcp://HOST:PORT) instead of local workers.",
)
@click.option(
    "--out",
    "out",
    metavar="FILE",
    required=True,
    help="The table: .csv, or .parquet / .pq. An existing table of the same sweep is resumed.",
)
@click.option("--retry-errors", is_flag=True, help="Compute again the designs that failed.")
@click.option(
    "--figure",
    "figure_out",
    metavar="PNG",
    default=None,
    help="Also draw the map of the number of regions over the two names that vary.",
)
@options.resolve_flag_option
def sweep_command(
    spec: str,
    vary: tuple[str, ...],
    precision: float,
    jobs: int | None,
    scheduler: str | None,
    out: str,
    retry_errors: bool,
    figure_out: str | None,
) -> None:
    """Analyse every design of the product of the --vary ranges; one row per design to FILE.

    Columns: the varied names, then regions (their number; empty when unknown
    at the precision), workspace_inner and workspace_outer (bounds on the area
    of W), largest_share (a certified lower bound on the share of W of the
    largest region), n_connected (true, false or empty when unknown), seconds
    and error (empty unless the design failed).

    Rows are written as designs finish; running the same command again skips
    the designs already in FILE (failed ones too, unless --retry-errors). FILE
    does not record the precision: resume with the same one. A progress bar
    shows on a terminal (log lines with `moveability -v sweep ...`).
    """
    n_jobs = _check_jobs(jobs, scheduler)
    with running.reporting_errors():
        from ..mechanisms.registry import load_spec
        from ..sweep import check_varies, parse_vary, run_sweep
        from ..sweep.table import table_format

        base = load_spec(spec)
        varies = [parse_vary(text, base) for text in vary]
        check_varies(varies)
        table_format(out)
        # the table is resumed and the map drawn again: both may exist already
        check_file(out, "--out", overwrite=True)
        if figure_out is not None:
            check_file(figure_out, "--figure", True, (".png", ".svg", ".pdf"))
            require("matplotlib", "plot", "the sweep figure (--figure)")
            several = [v.name for v in varies if len(set(v.values)) > 1]
            if len(several) != 2:
                raise InputError(
                    "invalid --figure: expected a sweep in which exactly two --vary names take "
                    f"several values, got {', '.join(several) or 'none'}"
                )
        summary = run_sweep(
            base,
            varies,
            out,
            precision,
            jobs=n_jobs,
            scheduler=scheduler,
            retry_errors=retry_errors,
            progress=sweep_progress(),
            resolve=options.wants_resolution(),
        )
        if figure_out is not None:
            from ..sweep import plot_sweep_map

            with written_whole(figure_out) as temporary:
                plot_sweep_map(out).savefig(temporary, dpi=150)
    click.echo(
        f"{summary['designs']} designs: {summary['computed']} computed, "
        f"{summary['skipped']} already in {out}, {summary['failed']} failed"
    )
    if figure_out is not None:
        click.echo(f"map: {figure_out}")
