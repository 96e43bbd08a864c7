"""``moveability export``: the regions as VTK files for ParaView."""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import click

from ..errors import InputError
from . import options, printing, running
from .files import check_folder, folder_written_whole

__all__ = ["export_command", "format_export"]


def format_export(data: Mapping[str, Any]) -> str:
    """The paths written, one a line.

    Examples
    --------
    >>> print(format_export({"files": [{"path": "out/region-0.vtu"},
    ...                                {"path": "out/undecided.vtu"}]}))
    out/region-0.vtu
    out/undecided.vtu
    """
    return "\n".join(str(entry["path"]) for entry in data["files"])


@click.command("export")
@options.spec_argument
@click.option(
    "--out",
    "out",
    required=True,
    help="Directory to write region-<id>.vtu and undecided.vtu into (created if missing).",
)
@options.precision_option
@options.json_options
@options.resolve_option
def export_command(
    spec: str, out: str, precision: float, json_out: str | None, overwrite: bool
) -> None:
    """Write the regions of the manipulator of SPEC as VTK files (.vtu) for ParaView.

    One file per region: its leaves as cells, with the cell data ``certified``
    (1: certainly in the region, 0: the region may extend there) and
    ``leaf_level``; plus undecided.vtu, the leaves left undecided. Mechanisms
    with 2 pose axes give quads in the plane z = 0, with 3 hexahedra. Prints
    the paths written (a JSON list of files with --json -).
    """
    printing.check_output(json_out, overwrite)
    if os.path.isdir(out) and not overwrite:
        taken = sorted(name for name in os.listdir(out) if name.endswith(".vtu"))
        if taken:
            raise InputError(
                f"refusing to overwrite {os.path.join(out, taken[0])}: --out holds .vtu files "
                "(use --overwrite)"
            )
    check_folder(out, "--out", overwrite)
    with running.reporting_errors():
        result = running.open_analysis(spec, precision)
        from ..output.vtk import export_vtk, exported_files

        with folder_written_whole(out) as temporary:
            written = export_vtk(result, temporary)
        moved = [Path(out) / path.name for path in written]
        files = exported_files(result, moved)
        data = {
            "precision": result.precision,
            "pose": list(result.mechanism.pose_names),
            "files": files,
        }
    printing.write_output(data, json_out, overwrite, format_export)
