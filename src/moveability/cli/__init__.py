"""Command-line interface: ``moveability``.

One module per command (:mod:`.analyze`, :mod:`.regions`, :mod:`.locate`,
:mod:`.feasible`, :mod:`.plan`, :mod:`.plot`, :mod:`.report`, :mod:`.export`,
:mod:`.sweep`), shared options in :mod:`.options`, how a command runs (logging,
progress, errors) in :mod:`.running`, its output files in :mod:`.files`, what it
prints in :mod:`.printing`. Results go to stdout (a summary, or JSON with
``--json -``), logs to stderr. Bad input exits with status 2 and the one
line ``Error: <message>`` on stderr.

Examples
--------
>>> from click.testing import CliRunner
>>> result = CliRunner().invoke(main, ["regions", "missing.toml"])
>>> result.exit_code
2
>>> print(result.output)  # doctest: +ELLIPSIS
Error: invalid spec: expected an existing TOML file, got 'missing.toml'
"""

from __future__ import annotations

import os

# The package calls BLAS on small matrices only (a few rows): a command runs it on
# one thread and does not start OpenBLAS's pool of threads when numpy is first
# imported (below), which costs a short command most of its start on a busy
# machine. A value the user set is kept.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import importlib

import click

from .. import __version__
from . import process, running

__all__ = ["main", "run"]

#: each command's module and function: a command's module is imported when the
#: command runs (or the help lists it), so a command imports only its own
_COMMANDS = {
    "analyze": ("analyze", "analyze_command"),
    "export": ("export", "export_command"),
    "feasible": ("feasible", "feasible_command"),
    "locate": ("locate", "locate_command"),
    "plan": ("plan", "plan_command"),
    "plot": ("plot", "plot_command"),
    "regions": ("regions", "regions_command"),
    "report": ("report", "report_command"),
    "sweep": ("sweep", "sweep_command"),
}


class _Commands(click.Group):
    """The command group: the library's errors, wherever raised (an option's value
    included), become one line on stderr (:func:`.running.reporting_errors`); the
    commands' modules are imported on demand (``_COMMANDS``)."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(_COMMANDS)

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        if cmd_name not in _COMMANDS:
            return None
        module, name = _COMMANDS[cmd_name]
        command: click.Command = getattr(importlib.import_module(f".{module}", __name__), name)
        return command

    def invoke(self, ctx: click.Context) -> object:
        with running.reporting_errors():
            return super().invoke(ctx)


@click.group(cls=_Commands, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="moveability")
@click.option("-v", "--verbose", count=True, help="More messages on stderr (repeat for more).")
@click.option("-q", "--quiet", count=True, help="Fewer messages on stderr.")
@click.pass_context
def main(ctx: click.Context, verbose: int, quiet: int) -> None:
    """Regions of feasible point-to-point motions of fully-parallel manipulators."""
    ctx.obj = {"verbosity": verbose - quiet}
    running.configure_logging(verbose - quiet)


def run() -> None:
    """The ``moveability`` console script: :func:`main` in a process whose
    allocator keeps freed blocks for reuse, ended at once when the command is
    done (see :mod:`.process`). :func:`main` itself changes neither."""
    process.tune_allocator()
    try:
        main()  # click ends its standalone mode by raising SystemExit
    except SystemExit as exc:
        process.finish(exc.code)
    process.finish(0)
