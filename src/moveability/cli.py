"""Command-line interface: ``moveability``."""

from __future__ import annotations

import click

from . import __version__


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="moveability")
def main() -> None:
    """Regions of feasible point-to-point motions of fully-parallel manipulators."""
