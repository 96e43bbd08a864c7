"""``moveability analyze``: analyse once and save the analysis for the other commands."""

from __future__ import annotations

import click

from ..errors import InputError
from . import options, running
from .files import check_file
from .regions import format_regions

__all__ = ["analyze_command"]


@click.command("analyze")
@options.spec_argument
@click.option(
    "--out",
    "out",
    required=True,
    metavar="FILE.npz",
    help="Where to save the analysis (a .npz file).",
)
@click.option("--overwrite", is_flag=True, help="Replace --out if it exists.")
@options.precision_option
@options.aspects_option
@options.resolve_option
def analyze_command(
    spec: str, out: str, overwrite: bool, precision: float, generalized_aspects: bool
) -> None:
    """Analyse the manipulator of SPEC and save the analysis to FILE.npz.

    Every command that takes a SPEC (regions, locate, feasible, plan, plot,
    report, export) also takes FILE.npz in its place and answers from it
    without computing again; a --precision given with it must be the saved
    one. Prints the regions' summary.
    """
    check_file(out, "--out", overwrite, (".npz",))
    with running.reporting_errors():
        if running.is_saved(spec):
            raise InputError(f"invalid SPEC: expected a spec file (.toml), got the analysis {spec}")
        result = running.open_analysis(spec, precision, generalized_aspects)
        from ..analysis.saved import save_analysis

        # written under a temporary name and renamed: never half a file
        save_analysis(result, out)
    click.echo(format_regions(result.to_dict()))
    click.echo(f"saved {out}", err=True)
