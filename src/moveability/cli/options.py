"""The options and arguments the commands of ``moveability`` share (click decorators)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, TypeVar

import click

from ..errors import InputError

__all__ = [
    "DEFAULT_PRECISION",
    "aspects_option",
    "json_options",
    "points_argument",
    "precision_option",
    "resolve_flag_option",
    "resolve_growth",
    "resolve_option",
    "spec_argument",
    "wants_resolution",
]

#: size of the smallest cells of the analysis when ``--precision`` is not given
DEFAULT_PRECISION = 0.1

F = TypeVar("F", bound=Callable[..., Any])


class _Precision(click.ParamType):
    """A positive finite number, or one per pose axis separated by commas; a bad value
    is an :class:`~moveability.errors.InputError` (one line)."""

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


_RESOLVE = "moveability.resolve"
_GROWTH = "moveability.resolve_growth"


def wants_resolution() -> bool:
    """Whether the running command resolves the open answers (True outside a command)."""
    context = click.get_current_context(silent=True)
    return True if context is None else bool(context.meta.get(_RESOLVE, True))


def resolve_option(command: F) -> F:
    """``--resolve/--no-resolve`` (:func:`resolve_flag_option`) and ``--resolve-growth
    FACTOR``: the leaves the refinement may add, as a multiple of the plain pass's
    (``analyze``'s ``resolve_growth``; see :func:`resolve_growth`)."""

    def remember(context: click.Context, _param: click.Parameter, value: Any) -> Any:
        if value is not None:
            context.meta[_GROWTH] = value
        return value

    command = click.option(
        "--resolve-growth",
        type=_Growth(),
        default=None,
        expose_value=False,
        is_eager=True,
        callback=remember,
        help="Leaves the refinement below the precision may add, as a multiple of the "
        "leaves of the plain pass (at least 32768, within memory)  [default: 4]; a larger "
        "factor may decide a count or an N-connectivity the default leaves open.",
    )(command)
    return resolve_flag_option(command)


def resolve_growth() -> float | None:
    """The running command's ``--resolve-growth``; None where it was not given."""
    context = click.get_current_context(silent=True)
    return None if context is None else context.meta.get(_GROWTH)


class _Growth(click.ParamType):
    """A finite number >= 0; a bad value is an :class:`~moveability.errors.InputError`."""

    name = "FACTOR"

    def convert(
        self, value: Any, param: click.Parameter | None, ctx: click.Context | None
    ) -> float:
        try:
            growth = float(value)
        except (TypeError, ValueError):
            growth = math.nan
        if not (math.isfinite(growth) and growth >= 0):
            raise InputError(f"invalid --resolve-growth: expected a number >= 0, got {value!r}")
        return growth


def resolve_flag_option(command: F) -> F:
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
