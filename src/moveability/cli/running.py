"""How a command runs: logging and progress on stderr, the library's errors as one line,
and the calls into the library (imported when called, so that a command loads only
what it needs)."""

from __future__ import annotations

import logging
import sys
import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from typing import Any

import click
import numpy as np
from numpy.typing import NDArray

from ..errors import InputError, InvalidParameterError, MoveabilityError
from ..poses import read_points
from .options import wants_resolution

__all__ = [
    "Refused",
    "TerminalProgress",
    "analyse_poses",
    "analysis_options",
    "configure_logging",
    "load_mechanism",
    "make_mechanism",
    "progress_reporter",
    "reporting_errors",
    "run_analysis",
]

logger = logging.getLogger("moveability")


class Refused(click.ClickException):
    """Bad input as click shows it: the one line ``Error: <message>`` on stderr, exit 2."""

    exit_code = 2

    def __init__(self, message: str) -> None:
        super().__init__(" ".join(str(message).splitlines()))


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
        return TerminalProgress(stream)
    return None


class TerminalProgress:
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


@contextmanager
def reporting_errors() -> Iterator[None]:
    """Turn the library's errors into one-line messages.

    Bad input (:class:`~moveability.errors.InvalidParameterError`, including a
    precision too fine for memory, and :class:`~moveability.errors.InputError`)
    exits with status 2; any other
    :class:`~moveability.errors.MoveabilityError` with status 1.
    """
    try:
        yield
    except (InvalidParameterError, InputError) as error:
        raise Refused(str(error)) from error
    except MoveabilityError as error:
        raise click.ClickException(" ".join(str(error).splitlines())) from error


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
    from ..mechanisms.registry import load_spec

    spec = load_spec(spec_path)
    logger.info("spec %s: %s", spec_path, spec["mechanism"])
    return make_mechanism(spec)
