"""The table of a sweep: one row per design, written as designs finish, read back to resume.

Columns: the varied names as given, then :data:`RESULT_COLUMNS`. A row is
identified by its varied values; the file's format follows its extension:

- ``.csv``: each row is appended and flushed as its design finishes; floats
  are written with ``repr`` (they read back exactly), ``n_connected`` as
  ``true`` / ``false``, and unknown or missing values as empty cells. A last
  line cut short (a sweep killed while writing) is dropped when the sweep
  resumes.
- ``.parquet`` (or ``.pq``): a Parquet file cannot be appended to, so the whole
  table is written to a temporary file beside it and moved over it
  (``os.replace``, atomic) each time results arrive. The file on disk is thus
  always a complete table of the designs finished so far; the cost of each
  write grows with the table (CSV suits sweeps of very many designs better).
  Unknown values are nulls.
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from ..errors import InvalidParameterError, Plain
from ..extras import require

__all__ = [
    "RESULT_COLUMNS",
    "SweepTable",
    "decode_cell",
    "encode_cell",
    "read_table",
    "table_columns",
    "table_format",
]

#: the columns after the varied names, in order
RESULT_COLUMNS = (
    "regions",
    "regions_at_least",
    "regions_at_most",
    "workspace_inner",
    "workspace_outer",
    "largest_share",
    "n_connected",
    "seconds",
    "error",
)
_INTEGERS = {"regions", "regions_at_least", "regions_at_most"}
_BOOLEANS = {"n_connected"}
_TEXTS = {"error"}

Row = dict[str, Any]
Key = tuple[float, ...]


def table_columns(names: Sequence[str]) -> tuple[str, ...]:
    """The columns of a sweep over ``names``.

    Examples
    --------
    >>> table_columns(["L1", "theta1.min"])[:4]
    ('L1', 'theta1.min', 'regions', 'regions_at_least')
    """
    return (*names, *RESULT_COLUMNS)


def table_format(path: str | os.PathLike[str], name: str = "--out") -> str:
    """``"csv"`` or ``"parquet"``, from the file's extension.

    Examples
    --------
    >>> table_format("designs.csv"), table_format("designs.parquet")
    ('csv', 'parquet')
    >>> table_format("designs.xlsx")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
        ...
    moveability.errors.InvalidParameterError: invalid --out: expected a file name ending ...
    """
    suffix = os.path.splitext(os.fspath(path))[1].lower()
    if suffix == ".csv":
        return "csv"
    if suffix in (".parquet", ".pq"):
        require("pyarrow", "sweep", "Parquet tables")
        return "parquet"
    raise InvalidParameterError(
        name, "a file name ending in .csv, .parquet or .pq", os.fspath(path)
    )


def encode_cell(value: Any) -> str:
    """The CSV text of a value: ``repr`` for floats, ``true``/``false``, empty for None.

    Examples
    --------
    >>> [encode_cell(v) for v in (0.1, 3, True, None, "failed")]
    ['0.1', '3', 'true', '', 'failed']
    """
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(float(value))
    return str(value)


def decode_cell(column: str, text: str) -> Any:
    """The value of a CSV cell of ``column`` (inverse of :func:`encode_cell`).

    Examples
    --------
    >>> decode_cell("regions", "2"), decode_cell("n_connected", ""), decode_cell("L1", "0.1")
    (2, None, 0.1)
    """
    if column in _TEXTS:
        return text or None
    if text == "":
        return None
    if column in _INTEGERS:
        return int(text)
    if column in _BOOLEANS:
        if text not in ("true", "false"):
            raise ValueError(f"expected true, false or nothing, got {text!r}")
        return text == "true"
    return float(text)


def _key(row: Mapping[str, Any], names: Sequence[str]) -> Key:
    return tuple(float(row[name]) for name in names)


def _sweep_of(columns: Sequence[str]) -> str:
    if tuple(columns[-len(RESULT_COLUMNS) :]) == RESULT_COLUMNS:
        varied = ",".join(columns[: -len(RESULT_COLUMNS)])
        return f"a table of a sweep over {varied}"
    return "a table with the columns " + ",".join(columns)


def _other_table(
    path: str, header: Sequence[str], columns: Sequence[str], name: str
) -> InvalidParameterError:
    return InvalidParameterError(
        f"{name} {path}",
        _sweep_of(columns) + " (this sweep's), or a new file",
        Plain(_sweep_of(header)),
    )


def _read_csv(path: str, columns: Sequence[str] | None, name: str) -> tuple[list[str], list[Row]]:
    with open(path, newline="", encoding="utf-8") as stream:
        text = stream.read()
    if not text.endswith("\n"):
        text = text[: text.rfind("\n") + 1]  # a last line cut short is no row
    reader = csv.reader(io.StringIO(text))
    header = next(reader, None)
    if header is None:
        return [], []
    if columns is not None and tuple(header) != tuple(columns):
        raise _other_table(path, header, columns, name)
    rows = []
    for cells in reader:
        if not cells:
            continue
        where = f"{name} {path} line {reader.line_num}"
        if len(cells) != len(header):
            raise InvalidParameterError(where, f"{len(header)} cells", ",".join(cells))
        try:
            rows.append({c: decode_cell(c, cell) for c, cell in zip(header, cells, strict=True)})
        except ValueError as error:
            raise InvalidParameterError(where, "a row of this sweep", str(error)) from None
    return header, rows


def _read_parquet(
    path: str, columns: Sequence[str] | None, name: str
) -> tuple[list[str], list[Row]]:
    import pyarrow.parquet as pq

    try:
        table = pq.read_table(path)
    except Exception as error:  # pyarrow raises its own types for a file that is not Parquet
        raise InvalidParameterError(name, "a Parquet file", f"{path} ({error})") from None
    header = list(table.column_names)
    if columns is not None and tuple(header) != tuple(columns):
        raise _other_table(path, header, columns, name)
    rows = [{c: row[c] for c in header} for row in table.to_pylist()]
    return header, rows


def read_table(
    path: str | os.PathLike[str], columns: Sequence[str] | None = None, name: str = "--out"
) -> tuple[list[str], list[Row]]:
    """Read a sweep table (CSV or Parquet) as its columns and a list of row dicts.

    Parameters
    ----------
    path : str or os.PathLike
        The table.
    columns : sequence of str, optional
        When given, the columns the file must have, in order.
    name : str, default "--out"
        How to name the file in an error message.

    Returns
    -------
    (list of str, list of dict)
        Values are typed: floats, ``regions`` an int, ``n_connected`` a bool,
        ``error`` a str, and ``None`` where a value is unknown or missing.

    Raises
    ------
    moveability.errors.InvalidParameterError
        Named ``name``: the header is not ``columns``, a row is malformed, or
        the file is not in the format its extension says.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     path = pathlib.Path(tmp, "sweep.csv")
    ...     _ = path.write_text("L1,regions,n_connected,error\\n8.0,2,false,\\n")
    ...     read_table(path)
    (['L1', 'regions', 'n_connected', 'error'], [{'L1': 8.0, 'regions': 2, 'n_connected': False, 'error': None}])
    """  # noqa: E501
    shown = os.fspath(path)
    if table_format(shown, name) == "csv":
        return _read_csv(shown, columns, name)
    return _read_parquet(shown, columns, name)


def _parquet_schema(columns: Sequence[str]) -> Any:
    import pyarrow as pa

    def kind(column: str) -> Any:
        if column in _INTEGERS:
            return pa.int64()
        if column in _BOOLEANS:
            return pa.bool_()
        if column in _TEXTS:
            return pa.string()
        return pa.float64()

    return pa.schema([(column, kind(column)) for column in columns])


def _replace(path: str, write: Any) -> None:
    """Write through ``write(temporary_path)`` then move the result over ``path``."""
    tmp = f"{path}.{os.getpid()}.tmp"
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


class SweepTable:
    """The output table of a sweep, opened to resume and to add rows as designs finish.

    Parameters
    ----------
    path : str or os.PathLike
        ``.csv`` or ``.parquet`` / ``.pq`` file. An existing file must hold a
        table of the same columns (else :class:`InvalidParameterError` naming
        ``--out``); its rows count as done.
    names : sequence of str
        The varied names, in the order of the columns.
    retry_errors : bool, default False
        Drop the existing rows of failed designs (the file is rewritten), so
        that they are computed again.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     path = pathlib.Path(tmp, "sweep.csv")
    ...     with SweepTable(path, ["L1"]) as table:
    ...         table.append({"L1": 8.0, "regions": 2, "seconds": 0.5})
    ...     print(path.read_text().strip())
    ...     SweepTable(path, ["L1"]).is_done((8.0,))
    L1,regions,regions_at_least,regions_at_most,workspace_inner,workspace_outer,largest_share,n_connected,seconds,error
    8.0,2,,,,,,,0.5,
    True
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        names: Sequence[str],
        retry_errors: bool = False,
    ) -> None:
        self.path = os.fspath(path)
        self.names = tuple(names)
        self.columns = table_columns(self.names)
        self.format = table_format(self.path)
        self.rows: dict[Key, Row] = {}
        parent = os.path.dirname(os.path.abspath(self.path))
        if not os.path.isdir(parent):
            raise InvalidParameterError("--out", "a file in an existing directory", self.path)
        exists = os.path.exists(self.path) and os.path.getsize(self.path) > 0
        if exists:
            _, rows = read_table(self.path, self.columns, "--out")
            for row in rows:
                self.rows[_key(row, self.names)] = row
        dropped = False
        if retry_errors:
            failed = [key for key, row in self.rows.items() if row.get("error")]
            for key in failed:
                del self.rows[key]
            dropped = bool(failed)
        self._stream: Any = None
        if self.format == "csv":
            if not exists or dropped:
                self._rewrite_csv()
            else:
                self._truncate_partial_line()
        elif not exists or dropped:
            self._write_parquet()

    # ----------------------------------------------------------- queries
    def is_done(self, values: Sequence[float]) -> bool:
        """Whether the design of these varied values has a row."""
        return tuple(float(v) for v in values) in self.rows

    # ----------------------------------------------------------- writing
    def append(self, row: Mapping[str, Any]) -> None:
        """Add the row of one finished design (missing columns are unknown)."""
        self.extend([row])

    def extend(self, rows: Iterable[Mapping[str, Any]]) -> None:
        """Add the rows of finished designs and make them durable before returning."""
        full = [{c: row.get(c) for c in self.columns} for row in rows]
        for row in full:
            self.rows[_key(row, self.names)] = row
        if self.format == "csv":
            if self._stream is None:
                self._stream = open(self.path, "a", newline="", encoding="utf-8")
                self._writer = csv.writer(self._stream, lineterminator="\n")
            for row in full:
                self._writer.writerow([encode_cell(row[c]) for c in self.columns])
            self._stream.flush()
        elif full:
            self._write_parquet()

    def close(self) -> None:
        """Close the CSV stream, if open; the rows are already on disk."""
        if self._stream is not None:
            self._stream.close()
            self._stream = None

    def __enter__(self) -> SweepTable:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ----------------------------------------------------------- files
    def _truncate_partial_line(self) -> None:
        with open(self.path, "rb+") as stream:
            data = stream.read()
            if not data.endswith(b"\n"):
                stream.truncate(data.rfind(b"\n") + 1)
        if os.path.getsize(self.path) == 0:
            self._rewrite_csv()

    def _rewrite_csv(self) -> None:
        def write(tmp: str) -> None:
            with open(tmp, "w", newline="", encoding="utf-8") as stream:
                writer = csv.writer(stream, lineterminator="\n")
                writer.writerow(self.columns)
                for row in self.rows.values():
                    writer.writerow([encode_cell(row.get(c)) for c in self.columns])

        _replace(self.path, write)

    def _write_parquet(self) -> None:
        import pyarrow as pa
        import pyarrow.parquet as pq

        schema = _parquet_schema(self.columns)
        data = {
            c: [_finite_or_none(row.get(c)) for row in self.rows.values()] for c in self.columns
        }
        table = pa.table(data, schema=schema)
        _replace(self.path, lambda tmp: pq.write_table(table, tmp))


def _finite_or_none(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
