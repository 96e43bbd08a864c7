"""``moveability regions``: the N-connected regions of the workspace."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import click

from ..types import word
from . import options, printing, running

__all__ = ["format_regions", "regions_command"]


def _area(value: Any) -> str:
    inner, outer = value
    return f"[{inner:.6g}, {outer:.6g}]"


def format_regions(data: Mapping[str, Any]) -> str:
    """A summary for people of the JSON of ``moveability regions``.

    Examples
    --------
    >>> print(format_regions({
    ...     "precision": 0.1,
    ...     "workspace": {"area": [10.0, 12.5]},
    ...     "regions": [{"id": 0, "area": [4.0, 5.0], "equals_workspace": False},
    ...                 {"id": 1, "area": [5.5, 7.0], "equals_workspace": None}],
    ...     "n_connected": None,
    ... }))
    precision: 0.1
    workspace area: [10, 12.5]
    N-connected regions: 2
    region      area equals workspace
    0       [4, 5]                 no
    1     [5.5, 7]            unknown
    workspace N-connected: unknown
    """
    measure = "volume" if "volume" in data["workspace"] else "area"
    eps = data["precision"]
    lines = [
        "precision: "
        + (", ".join(f"{v:g}" for v in eps) if isinstance(eps, list) else f"{eps:g}")
        + (f" (cells {' x '.join(f'{v:.4g}' for v in data['cell'])})" if "cell" in data else ""),
        f"workspace {measure}: {_area(data['workspace'][measure])}",
        (
            f"generalized aspects: {_count(data)}"
            if data.get("generalized_aspects")
            else f"N-connected regions: {_count(data)}"
        ),
    ]
    if data["regions"]:
        signed = all("sign" in region for region in data["regions"])
        rows = [
            [
                str(region["id"]),
                *([("det A > 0" if region["sign"] > 0 else "det A < 0")] if signed else []),
                _area(region[measure]),
                word(region["equals_workspace"]),
            ]
            for region in data["regions"]
        ]
        head = ["region", *(["sign"] if signed else []), measure, "equals workspace"]
        lines.append(printing.format_table(head, rows))
    lines.append(f"workspace N-connected: {word(data['n_connected'])}")
    undecided = data.get("undecided")
    if undecided:
        lines.append(
            f"undecided at this precision: {undecided[f'boundary_{measure}']:.6g} of {measure} in "
            f"undecided cells; {undecided['components']} possible region(s) without a "
            f"certified part, {undecided['detached']} certified part(s) of unknown region"
            + (
                f"; {undecided[f'open_{measure}']:.6g} of {measure} where a region may hide"
                if f"open_{measure}" in undecided
                else ""
            )
        )
        from ..analysis.open_parts import open_text

        still = open_text(undecided.get("open") or {}, data.get("pose") or (), measure)
        if still:
            lines.append(still)
    lines.extend(str(note) for note in data.get("notes") or ())
    return "\n".join(lines)


def _count(data: Mapping[str, Any]) -> str:
    """The count, definite only when proved; the listed regions otherwise."""
    count = data.get("count")
    if count is None or count["at_least"] == count["at_most"]:
        return str(len(data["regions"]))
    if count["at_most"] is None:
        return f"at least {count['at_least']} (no upper bound proved)"
    return f"at least {count['at_least']}, at most {count['at_most']}"


@click.command("regions")
@options.spec_argument
@options.precision_option
@options.json_options
@options.aspects_option
@options.resolve_option
def regions_command(
    spec: str,
    precision: float,
    json_out: str | None,
    overwrite: bool,
    generalized_aspects: bool,
) -> None:
    """The N-connected regions of the workspace of the manipulator of SPEC.

    SPEC is a TOML file naming the mechanism, its parameters and joint limits,
    or an analysis saved by ``moveability analyze --out``. Areas are given as
    [inner, outer] bounds; three-valued answers are true, false or null
    (unknown at this precision).
    """
    printing.check_output(json_out, overwrite)
    with running.reporting_errors():
        result = running.open_analysis(spec, precision, generalized_aspects)
        data = result.to_dict()
    printing.write_output(data, json_out, overwrite, format_regions)
