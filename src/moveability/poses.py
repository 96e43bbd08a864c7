"""Point files: poses read from CSV text whose header names the pose coordinates."""

from __future__ import annotations

import csv
import math
import sys
from collections.abc import Iterable, Sequence

import numpy as np

from .errors import InvalidParameterError, Plain
from .types import Array

__all__ = ["parse_points", "read_points"]


def read_points(source: str, pose_names: Sequence[str], option: str = "POINTS") -> Array:
    """Read poses from a CSV file, or from stdin when ``source`` is ``-``.

    See :func:`parse_points` for the format. Errors name ``option``, the argument
    or option that gave ``source`` as the user typed it (``POINTS``, ``--points``);
    the errors of an option's file name the file too.

    Examples
    --------
    >>> read_points("no-such.csv", ("x", "y"), "--points")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
        ...
    moveability.errors.InvalidParameterError: invalid --points: expected an existing CSV file...
    """
    shown = "<stdin>" if source == "-" else source
    name = shown if option == "POINTS" else f"{option} ({shown})"
    if source == "-":
        return parse_points(sys.stdin, pose_names, name)
    try:
        with open(source, newline="", encoding="utf-8-sig") as stream:
            return parse_points(stream, pose_names, name)
    except FileNotFoundError:
        raise InvalidParameterError(
            option, "an existing CSV file or - for stdin", source
        ) from None
    except OSError as error:
        reason = error.strerror or type(error).__name__
        raise InvalidParameterError(option, f"a readable CSV file ({reason})", source) from None
    except UnicodeDecodeError:
        raise InvalidParameterError(option, "a UTF-8 CSV file", source) from None


def parse_points(
    lines: Iterable[str], pose_names: Sequence[str], name: str = "POINTS"
) -> Array:
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
