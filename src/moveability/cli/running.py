"""How a command runs: logging and progress on stderr, the library's errors as one line,
and the calls into the library (imported when called, so that a command loads only
what it needs)."""

from __future__ import annotations

import logging
import sys
import time
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from typing import Any

import click
import numpy as np
from numpy.typing import NDArray

from ..errors import InputError, InvalidParameterError, MoveabilityError
from ..poses import read_points
from .options import resolve_growth, wants_resolution

__all__ = [
    "LoggedProgress",
    "Refused",
    "TerminalProgress",
    "analyse_poses",
    "analysis_options",
    "configure_logging",
    "is_saved",
    "load_mechanism",
    "make_mechanism",
    "open_analysis",
    "progress_reporter",
    "reporting_errors",
    "run_analysis",
    "status",
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


def progress_reporter() -> Any:
    """A progress display for the analysis, or ``None`` when nothing would show.

    With ``-v`` every level and phase is logged. Otherwise, when stderr is a
    terminal, a one-line display (:class:`TerminalProgress`) appears once the
    analysis has run for a second; nothing is written when stderr is not a
    terminal.

    Examples
    --------
    >>> configure_logging(0)
    >>> progress_reporter() is None  # stderr is not a terminal under the tests
    True
    """
    if logger.isEnabledFor(logging.INFO):
        return LoggedProgress()
    stream = sys.stderr
    if logger.isEnabledFor(logging.WARNING) and stream.isatty():
        return TerminalProgress(stream)
    return None


class LoggedProgress:
    """Progress as log lines (``-v``): one per level and one per phase."""

    def __call__(self, *args: Any, **kwargs: Any) -> None:
        # the analysis calls progress(level, n_split, n_leaves)
        if len(args) == 3 and not kwargs:
            logger.info("level %s: %s cells split, %s leaves", *args)
            return
        parts = [str(arg) for arg in args] + [f"{k}={v}" for k, v in kwargs.items()]
        logger.info("progress: %s", " ".join(parts))

    def phase(self, name: str, **info: int) -> None:
        details = ", ".join(f"{k} {v}" for k, v in info.items())
        logger.info("phase: %s%s", name, f" ({details})" if details else "")

    def close(self) -> None:
        """Nothing to clear."""


def status(message: str) -> None:
    """A one-line note of what a command is doing (drawing, writing): logged with
    ``-v``, on a terminal's stderr otherwise, nowhere when stderr is not one."""
    if logger.isEnabledFor(logging.INFO):
        logger.info("%s", message)
    elif logger.isEnabledFor(logging.WARNING) and sys.stderr.isatty():
        click.echo(f"{message} ...", err=True)


class TerminalProgress:
    """One updating line on a terminal, shown after the first second: the phase of
    the analysis, and while refining, a bar over the levels of the precision.

    Each update rewrites the whole line (``\\r`` and clear to its end), and
    :meth:`close` clears it, so that no old characters stay.
    """

    def __init__(self, stream: Any, delay: float = 1.0, width: int = 24) -> None:
        self.stream = stream
        self.start = time.monotonic()
        self.delay = delay
        self.width = width
        self.shown = False
        self.name = "refining"
        self.info: dict[str, int] = {}

    def _write(self, text: str) -> None:
        elapsed = time.monotonic() - self.start
        if elapsed < self.delay:
            return
        self.shown = True
        self.stream.write(f"\r\x1b[K{text}, {elapsed:.1f} s")
        self.stream.flush()

    def __call__(self, level: int, n_split: int, n_leaves: int) -> None:
        levels = self.info.get("levels")
        if self.name == "refining" and levels:
            done = min(int(level) + 1, levels)
            bar = "#" * (self.width * done // levels)
            text = f"refining [{bar:<{self.width}}] level {done}/{levels}"
        elif self.name == "resolving":
            text = f"resolving the open cells: round {self.info.get('round', '?')}, level {level}"
        else:
            text = f"{self.name}: level {level}"
        self._write(f"{text}, {n_leaves:,} cells, {n_split:,} split")

    def phase(self, name: str, **info: int) -> None:
        self.name, self.info = name, dict(info)
        if name == "resolving":
            text = f"resolving the open cells: round {info.get('round', '?')}"
        else:
            text = name
        self._write(text)

    def close(self) -> None:
        """Clear the line, if anything was shown."""
        if self.shown:
            self.stream.write("\r\x1b[K")
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
    mechanism: Any, precision: float | tuple[float, ...], progress: Any, **options: Any
) -> Any:
    """The analysis of ``mechanism`` (``moveability.analysis.result.analyze``), refined
    below the precision where the count is open unless the command was given
    ``--no-resolve`` (see :func:`resolve_option`)."""
    from ..analysis.result import analyze

    options.setdefault("resolve", wants_resolution())
    growth = resolve_growth()
    if growth is not None:
        options.setdefault("resolve_growth", growth)
    try:
        return analyze(mechanism, precision=precision, progress=progress, **options)
    finally:
        close = getattr(progress, "close", None)
        if callable(close):
            close()


def analyse_poses(
    source: str, points: str, precision: float, generalized_aspects: bool = False
) -> tuple[Any, NDArray[np.float64]]:
    """The analysis of a spec file or a saved analysis (see :func:`open_analysis`)
    and the poses of a CSV file, read before any computation.

    Call inside :func:`reporting_errors`.
    """
    if is_saved(source):
        result = open_analysis(source, precision, generalized_aspects)
        return result, read_points(points, result.mechanism.pose_names)
    mechanism = load_mechanism(source)
    poses = read_points(points, mechanism.pose_names)
    return open_analysis(source, precision, generalized_aspects, mechanism), poses


def is_saved(source: str) -> bool:
    """Whether a command's SPEC names a saved analysis (``.npz``) rather than a spec."""
    return source.lower().endswith(".npz")


def open_analysis(
    source: str,
    precision: float | tuple[float, ...],
    generalized_aspects: bool | None = None,
    mechanism: Any = None,
) -> Any:
    """The analysis a command answers from: read from a saved analysis (``.npz``,
    written by ``moveability analyze --out``), or computed from a spec file
    (``mechanism``, when given, is its mechanism, already built).

    With a saved analysis, a ``--precision`` given on the command line must be
    the saved one, and ``--generalized-aspects`` (for the commands that have
    it; ``None`` for the others) must agree with it: answers are never
    silently about another analysis.
    """
    if not is_saved(source):
        if mechanism is None:
            mechanism = load_mechanism(source)
        return run_analysis(
            mechanism,
            precision,
            progress_reporter(),
            **analysis_options(bool(generalized_aspects)),
        )
    from ..analysis.result import check_precision
    from ..analysis.saved import load_analysis

    started = time.monotonic()
    result = load_analysis(source)
    logger.info("read the analysis %s in %.1f s", source, time.monotonic() - started)
    context = click.get_current_context(silent=True)
    given = context is not None and context.get_parameter_source("precision") not in (
        None,
        click.core.ParameterSource.DEFAULT,
    )
    if given:
        asked = check_precision(precision, len(result.mechanism.pose_names))
        if not np.array_equal(asked, result.precisions):
            shown = (
                f"{asked[0]:g}" if (asked == asked[0]).all() else ", ".join(f"{v:g}" for v in asked)
            )
            raise InputError(
                f"invalid --precision: {source} was analysed at precision "
                f"{result.precision_text}, not {shown} "
                "(leave out --precision, or analyse the spec again)"
            )
    if generalized_aspects is not None and generalized_aspects != result.generalized_aspects:
        held = "the generalized aspects" if result.generalized_aspects else "the regions"
        raise InputError(
            f"invalid --generalized-aspects: {source} holds {held} "
            f"({'add' if result.generalized_aspects else 'leave out'} --generalized-aspects)"
        )
    return result


def analysis_options(generalized_aspects: bool) -> dict[str, Any]:
    """Keyword arguments of the analysis for the command-line flags that are set."""
    return {"generalized_aspects": True} if generalized_aspects else {}


def load_mechanism(spec_path: str) -> Any:
    """Read ``spec_path`` and build its mechanism; bad input raises the library's errors."""
    from ..mechanisms.registry import load_spec

    spec = load_spec(spec_path)
    logger.info("spec %s: %s", spec_path, spec["mechanism"])
    return make_mechanism(spec)
