"""What a command prints: JSON (to stdout or a file), summaries and tables for people."""

from __future__ import annotations

import json
import logging
import os
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import click
import numpy as np

from ..errors import InputError
from .files import check_file, written_whole

__all__ = ["check_output", "format_table", "write_output"]

logger = logging.getLogger("moveability")


def check_output(json_out: str | None, overwrite: bool) -> None:
    """Refuse early, before any computation, a ``--json`` file that cannot be written."""
    if json_out is None or json_out == "-":
        return
    check_file(json_out, "--json", overwrite)


def _jsonable(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def write_output(
    data: Mapping[str, Any],
    json_out: str | None,
    overwrite: bool,
    summary: Callable[[Mapping[str, Any]], str],
) -> None:
    """Print ``summary(data)`` to stdout, or JSON to stdout, or both JSON to a file and summary.

    Parameters
    ----------
    data : mapping
        The JSON-ready result of the command.
    json_out : str or None
        ``None``: summary only; ``"-"``: JSON on stdout only; a path: JSON
        written there, summary on stdout.
    overwrite : bool
        Whether an existing ``json_out`` file may be replaced.
    summary : callable
        Formats ``data`` for people.
    """
    if json_out is not None:
        text = json.dumps(data, indent=2, allow_nan=False, default=_jsonable) + "\n"
        if json_out == "-":
            click.echo(text, nl=False)
            return
        if os.path.lexists(json_out) and not overwrite:
            raise InputError(f"refusing to overwrite {json_out}: it exists (use --overwrite)")
        try:
            with written_whole(json_out) as temporary:
                with open(temporary, "w", encoding="utf-8") as stream:
                    stream.write(text)
        except OSError as error:
            raise InputError(f"cannot write {json_out}: {error.strerror or error}") from None
        logger.info("wrote %s", json_out)
    shown = summary(data)
    if shown:
        click.echo(shown)


def format_table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """Columns aligned on their widths, first one left-aligned, others right-aligned.

    Examples
    --------
    >>> print(format_table(["x", "status"], [["1.5", "in"], ["-20.25", "unknown"]]))
    x       status
    1.5         in
    -20.25 unknown
    """
    widths = [max(len(str(cell)) for cell in column) for column in zip(header, *rows, strict=True)]

    def line(cells: Sequence[str]) -> str:
        first, *rest = (str(cell) for cell in cells)
        parts = [first.ljust(widths[0])]
        parts += [cell.rjust(width) for cell, width in zip(rest, widths[1:], strict=True)]
        return " ".join(parts).rstrip()

    return "\n".join(line(cells) for cells in [header, *rows])
