"""Options and helpers shared by the commands of ``moveability``.

The library is reached through :func:`make_mechanism` and :func:`run_analysis`,
which import it when called: the CLI can be loaded (and tested with a stand-in
analysis) on its own.
"""

from __future__ import annotations

import csv
import json
import logging
import math
import os
import sys
import time
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from typing import Any, TypeVar

import click
import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError, MoveabilityError, Plain
from ..mechanisms.registry import load_spec

__all__ = [
    "DEFAULT_PRECISION",
    "InputError",
    "configure_logging",
    "json_options",
    "load_mechanism",
    "make_mechanism",
    "parse_points",
    "points_argument",
    "precision_option",
    "progress_reporter",
    "read_points",
    "reporting_errors",
    "resolve_option",
    "run_analysis",
    "spec_argument",
    "three_valued",
    "wants_resolution",
    "write_output",
]

#: size of the smallest cells of the analysis when ``--precision`` is not given
DEFAULT_PRECISION = 0.1

logger = logging.getLogger("moveability")

F = TypeVar("F", bound=Callable[..., Any])


class InputError(click.ClickException):
    """Bad input: printed as the one line ``Error: <message>`` on stderr, exit status 2."""

    exit_code = 2

    def __init__(self, message: str) -> None:
        super().__init__(" ".join(str(message).splitlines()))


# ------------------------------------------------------------------ options
class _Precision(click.ParamType):
    """A positive finite number, or one per pose axis separated by commas; a bad value
    is an :class:`InputError` (one line)."""

    name = "EPS"

    def convert(
        self, value: Any, param: click.Parameter | None, ctx: click.Context | None
    ) -> float | tuple[float, ...]:
        if isinstance(value, float | tuple):
            return value
        parts = str(value).split(",")
        try:
            eps = [float(v) for v in parts]
        except (TypeError, ValueError):
            eps = [math.nan]
        if not all(math.isfinite(e) and e > 0 for e in eps):
            raise InputError(
                "invalid --precision: expected a positive finite number, or one per pose "
                f"axis separated by commas, got {value!r}"
            )
        return eps[0] if len(eps) == 1 else tuple(eps)


def precision_option(command: F) -> F:
    """Add ``--precision EPS`` (default :data:`DEFAULT_PRECISION`)."""
    return click.option(
        "--precision",
        "-p",
        type=_Precision(),
        default=DEFAULT_PRECISION,
        show_default=True,
        help=(
            "Size of the smallest cells of the analysis (pose units: lengths and radians); "
            "one number, or one per pose axis separated by commas (0.1,0.1,0.02)."
        ),
    )(command)


def json_options(command: F) -> F:
    """Add ``--json OUT`` (``-`` for stdout) and ``--overwrite``."""
    command = click.option(
        "--overwrite",
        is_flag=True,
        help="Replace the --json file if it exists.",
    )(command)
    return click.option(
        "--json",
        "json_out",
        metavar="OUT",
        default=None,
        help="Write the result as JSON to OUT ('-' for stdout, with no summary).",
    )(command)


def spec_argument(command: F) -> F:
    """Add the ``SPEC`` argument: a TOML file (see :func:`~moveability.load_spec`)."""
    return click.argument("spec", metavar="SPEC")(command)


def points_argument(command: F) -> F:
    """Add the ``POINTS`` argument: a CSV file or ``-`` for stdin."""
    return click.argument("points", metavar="POINTS")(command)


# ------------------------------------------------------------------ logging
class _EchoHandler(logging.Handler):
    """Log records to the current stderr (looked up at each record, as click does)."""

    def emit(self, record: logging.LogRecord) -> None:
        try:
            click.echo(self.format(record), err=True)
        except Exception:  # pragma: no cover - logging must never raise
            self.handleError(record)


def configure_logging(verbosity: int) -> None:
    """Send the ``moveability`` logger to stderr: warnings at 0, info at 1, debug at 2."""
    for handler in list(logger.handlers):
        if isinstance(handler, _EchoHandler):
            logger.removeHandler(handler)
    handler = _EchoHandler()
    handler.setFormatter(logging.Formatter("%(levelname)s: %(message)s"))
    logger.addHandler(handler)
    logger.setLevel(max(logging.DEBUG, min(logging.CRITICAL, logging.WARNING - 10 * verbosity)))


def progress_reporter() -> Callable[..., None] | None:
    """A progress callback for the analysis, or ``None`` when nothing would show.

    With ``-v`` every level is logged. Otherwise, when stderr is a terminal, a
    one-line progress display appears once the analysis has run for a second
    (and is cleared at the end of each level display); nothing is written when
    stderr is not a terminal.

    Examples
    --------
    >>> configure_logging(0)
    >>> progress_reporter() is None  # stderr is not a terminal under the tests
    True
    """
    if logger.isEnabledFor(logging.INFO):

        def log_progress(*args: Any, **kwargs: Any) -> None:
            # the analysis calls progress(level, n_split, n_leaves)
            if len(args) == 3 and not kwargs:
                logger.info("level %s: %s cells split, %s leaves", *args)
                return
            parts = [str(arg) for arg in args] + [f"{k}={v}" for k, v in kwargs.items()]
            logger.info("progress: %s", " ".join(parts))

        return log_progress
    stream = sys.stderr
    if logger.isEnabledFor(logging.WARNING) and stream.isatty():
        return _TerminalProgress(stream)
    return None


class _TerminalProgress:
    """A single updating line on a terminal, shown after the first second."""

    def __init__(self, stream: Any, delay: float = 1.0) -> None:
        self.stream = stream
        self.start = time.monotonic()
        self.delay = delay
        self.shown = False

    def __call__(self, level: int, n_split: int, n_leaves: int) -> None:
        elapsed = time.monotonic() - self.start
        if elapsed < self.delay:
            return
        self.shown = True
        bar = "#" * min(int(level), 40)
        self.stream.write(
            f"\rrefining [{bar:<24.24}] level {level}, {n_leaves:,} cells, "
            f"{n_split:,} to split, {elapsed:.1f} s "
        )
        if n_split == 0:
            self.stream.write("\n")
        self.stream.flush()


# ------------------------------------------------------------------ errors
@contextmanager
def reporting_errors() -> Iterator[None]:
    """Turn the library's errors into one-line messages.

    Bad input (:class:`~moveability.errors.InvalidParameterError`, including a
    precision too fine for memory) exits with status 2; any other
    :class:`~moveability.errors.MoveabilityError` with status 1.
    """
    try:
        yield
    except InvalidParameterError as error:
        raise InputError(str(error)) from error
    except MoveabilityError as error:
        raise click.ClickException(" ".join(str(error).splitlines())) from error


# ------------------------------------------------------------------ library
def make_mechanism(spec: Mapping[str, Any]) -> Any:
    """The mechanism of a normalised spec (``moveability.mechanisms.from_spec``)."""
    from ..mechanisms import from_spec

    return from_spec(spec)


def run_analysis(
    mechanism: Any, precision: float, progress: Callable[..., None] | None, **options: Any
) -> Any:
    """The analysis of ``mechanism`` (``moveability.analysis.result.analyze``), refined
    below the precision where the count is open unless the command was given
    ``--no-resolve`` (see :func:`resolve_option`)."""
    from ..analysis.result import analyze

    options.setdefault("resolve", wants_resolution())
    return analyze(mechanism, precision=precision, progress=progress, **options)


_RESOLVE = "moveability.resolve"


def wants_resolution() -> bool:
    """Whether the running command resolves the open answers (True outside a command)."""
    context = click.get_current_context(silent=True)
    return True if context is None else bool(context.meta.get(_RESOLVE, True))


def resolve_option(command: F) -> F:
    """``--resolve/--no-resolve``: refine below the precision where the count is open."""

    def remember(context: click.Context, _param: click.Parameter, value: bool) -> bool:
        context.meta[_RESOLVE] = value
        return value

    return click.option(
        "--resolve/--no-resolve",
        default=True,
        show_default=True,
        expose_value=False,
        is_eager=True,
        callback=remember,
        help="Refine, below the precision, only the cells that keep the count of "
        "regions or N-connectivity open (within a deterministic budget); "
        "--no-resolve keeps the plain pass at the precision.",
    )(command)


def aspects_option(command: F) -> F:
    """``--generalized-aspects``: forbid serial singularities too (det B != 0)."""
    return click.option(
        "--generalized-aspects",
        "generalized_aspects",
        is_flag=True,
        help="Forbid serial singularities too: the regions become the generalized "
        "aspects (det A and det B of constant sign; the posture never changes).",
    )(command)


def analyse_poses(
    spec_path: str, points: str, precision: float, generalized_aspects: bool = False
) -> tuple[Any, NDArray[np.float64]]:
    """The analysis of the mechanism of a spec file and the poses of a CSV file.

    Call inside :func:`reporting_errors`.
    """
    mechanism = load_mechanism(spec_path)
    poses = read_points(points, mechanism.pose_names)
    result = run_analysis(
        mechanism, precision, progress_reporter(), **analysis_options(generalized_aspects)
    )
    return result, poses


def analysis_options(generalized_aspects: bool) -> dict[str, Any]:
    """Keyword arguments of the analysis for the command-line flags that are set."""
    return {"generalized_aspects": True} if generalized_aspects else {}


def load_mechanism(spec_path: str) -> Any:
    """Read ``spec_path`` and build its mechanism; bad input raises the library's errors."""
    spec = load_spec(spec_path)
    logger.info("spec %s: %s", spec_path, spec["mechanism"])
    return make_mechanism(spec)


# ------------------------------------------------------------------ points
def read_points(source: str, pose_names: Sequence[str]) -> NDArray[np.float64]:
    """Read poses from a CSV file, or from stdin when ``source`` is ``-``.

    See :func:`parse_points` for the format.
    """
    if source == "-":
        return parse_points(sys.stdin, pose_names, "<stdin>")
    try:
        with open(source, newline="", encoding="utf-8-sig") as stream:
            return parse_points(stream, pose_names, source)
    except FileNotFoundError:
        raise InvalidParameterError(
            "POINTS", "an existing CSV file or - for stdin", source
        ) from None
    except OSError as error:
        reason = error.strerror or type(error).__name__
        raise InvalidParameterError("POINTS", f"a readable CSV file ({reason})", source) from None
    except UnicodeDecodeError:
        raise InvalidParameterError("POINTS", "a UTF-8 CSV file", source) from None


def parse_points(
    lines: Iterable[str], pose_names: Sequence[str], name: str = "POINTS"
) -> NDArray[np.float64]:
    """Parse poses from CSV text whose header names the pose coordinates.

    Parameters
    ----------
    lines : iterable of str
        CSV text: a header holding exactly the names of ``pose_names`` in any
        order, then one row per pose. Spaces around names and values and
        blank lines are ignored.
    pose_names : sequence of str
        The coordinates of a pose, in the order of the columns returned.
    name : str, default "POINTS"
        How to name the input in an error message.

    Returns
    -------
    ndarray of float64, shape (m, k)
        The poses in input order, columns ordered as ``pose_names``.

    Raises
    ------
    moveability.errors.InvalidParameterError
        Naming the input: no header or no rows, a header that is not the pose
        names, a row of the wrong length, or a value that is not a finite
        number (naming the line, the row and the column).

    Examples
    --------
    >>> parse_points(["y, x", "2.0, 1.0", " 4 ,3"], ("x", "y")).tolist()
    [[1.0, 2.0], [3.0, 4.0]]
    >>> parse_points(["x,y", "1,2", "3,nan"], ("x", "y"), "pts.csv")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
        ...
    moveability.errors.InvalidParameterError: invalid pts.csv line 3 (row 2), column y: ...
    """
    k = len(pose_names)
    wanted = ", ".join(pose_names)
    reader = csv.reader(lines, skipinitialspace=True)
    columns: list[int] | None = None
    rows: list[list[float]] = []
    for record in reader:
        cells = [cell.strip() for cell in record]
        if not any(cells):
            continue
        line = reader.line_num
        if columns is None:
            if len(set(cells)) != len(cells) or set(cells) != set(pose_names):
                raise InvalidParameterError(
                    f"{name} header", f"the columns {wanted} in any order", ",".join(cells)
                )
            columns = [cells.index(pose) for pose in pose_names]
            continue
        where = f"{name} line {line} (row {len(rows) + 1})"
        if len(cells) != k:
            raise InvalidParameterError(where, f"{k} values ({wanted})", ",".join(cells))
        row = []
        for pose, column in zip(pose_names, columns, strict=True):
            try:
                value = float(cells[column])
            except ValueError:
                value = math.nan
            if not math.isfinite(value):
                raise InvalidParameterError(
                    f"{where}, column {pose}", "a finite number", cells[column]
                )
            row.append(value)
        rows.append(row)
    if not rows:
        got = "an empty file" if columns is None else "a header and no rows"
        raise InvalidParameterError(
            name, f"CSV with the header {','.join(pose_names)} and one pose per row", Plain(got)
        )
    return np.array(rows, dtype=np.float64).reshape(-1, k)


# ------------------------------------------------------------------ output
def three_valued(value: object) -> str:
    """``yes``, ``no`` or ``unknown`` for ``True``, ``False`` or ``None``.

    Examples
    --------
    >>> [three_valued(v) for v in (True, False, None)]
    ['yes', 'no', 'unknown']
    """
    if value is None:
        return "unknown"
    return "yes" if value else "no"


def check_output(json_out: str | None, overwrite: bool) -> None:
    """Refuse early, before any computation, a ``--json`` file that cannot be written."""
    if json_out is None or json_out == "-":
        return
    if os.path.exists(json_out) and not overwrite:
        raise InputError(f"refusing to overwrite {json_out}: it exists (use --overwrite)")
    parent = os.path.dirname(os.path.abspath(json_out))
    if not os.path.isdir(parent):
        raise InputError(f"cannot write {json_out}: no directory {parent}")


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
        try:
            with open(json_out, "w" if overwrite else "x", encoding="utf-8") as stream:
                stream.write(text)
        except FileExistsError:
            raise InputError(
                f"refusing to overwrite {json_out}: it exists (use --overwrite)"
            ) from None
        except OSError as error:
            raise InputError(f"cannot write {json_out}: {error.strerror or error}") from None
        logger.info("wrote %s", json_out)
    click.echo(summary(data))


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
