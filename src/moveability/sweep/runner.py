"""Running the designs of a sweep: in this process, on local workers (joblib) or on Dask.

Each design is analysed by :func:`design_row`, which never raises for a design
that fails: the error's message goes in the row's ``error`` column. The rows
come back as designs finish (:func:`run_designs` yields them) and
:func:`run_sweep` writes each to the table before the next arrives.

Memory allocation on workers
----------------------------
Dask's nanny starts its workers with ``MALLOC_TRIM_THRESHOLD_=65536``. Setting
any such variable turns off glibc's dynamic mmap threshold: every allocation
above 128 KiB (most numpy temporaries of the analysis) is then mapped and
unmapped, its pages zeroed each time, which made the analysis about 3 times
slower. :func:`restore_malloc_thresholds` sets the trim and mmap thresholds
back to large values through ``mallopt``, once per process, before the first
design a process runs (whoever started its workers); clusters this package
starts (:func:`local_cluster`) leave the variable out altogether.
"""

from __future__ import annotations

import ctypes
import functools
import math
import os
import sys
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from typing import Any

from ..errors import InvalidParameterError, MoveabilityError
from ..extras import require
from .designs import Vary, check_varies, design_grid, parse_vary
from .table import SweepTable

__all__ = [
    "M_MMAP_THRESHOLD",
    "M_TRIM_THRESHOLD",
    "design_row",
    "local_cluster",
    "restore_malloc_thresholds",
    "run_chunk",
    "run_designs",
    "run_sweep",
    "summarize",
]

#: ``mallopt`` parameters, from glibc's malloc.h
M_TRIM_THRESHOLD = -1
M_MMAP_THRESHOLD = -3
#: free memory kept at the top of the heap before it is given back to the system
TRIM_THRESHOLD = 128 << 20
#: allocations from this size up are mapped; glibc's largest allowed value (32 MiB on 64 bits)
MMAP_THRESHOLD = 4 * 1024 * 1024 * ctypes.sizeof(ctypes.c_long)

_malloc_restored: bool | None = None

Row = dict[str, Any]


# ----------------------------------------------------------------- malloc
def _set_malloc_thresholds() -> bool:
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(None)
        libc.gnu_get_libc_version  # noqa: B018 - present in glibc only
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
    mallopt.restype = ctypes.c_int
    mmap_ok = mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD) == 1
    trim_ok = mallopt(M_TRIM_THRESHOLD, TRIM_THRESHOLD) == 1
    return mmap_ok and trim_ok


def restore_malloc_thresholds() -> bool:
    """Give glibc's allocator large trim and mmap thresholds, once per process.

    Undoes the effect of ``MALLOC_TRIM_THRESHOLD_`` (set by Dask's nanny on its
    workers), under which the numpy temporaries of the analysis are mapped and
    unmapped on every allocation. Does nothing but on Linux with glibc.

    Returns
    -------
    bool
        Whether the thresholds are set (the first call's answer, repeated).

    Examples
    --------
    >>> restore_malloc_thresholds() in (True, False)
    True
    """
    global _malloc_restored
    if _malloc_restored is None:
        _malloc_restored = _set_malloc_thresholds()
    return _malloc_restored


# ----------------------------------------------------------------- one design
def summarize(result: Any) -> Row:
    """The result columns of one analysis.

    ``regions`` is the number of regions where it is proved, else ``None``
    (unknown); ``regions_at_least`` and ``regions_at_most`` bound it
    (``regions_at_most`` is ``None`` while no upper bound is proved);
    ``largest_share`` is a certified lower bound on the share of W covered by
    the largest region: its inner area over the outer area of W (``None`` when
    there is no region); ``n_connected`` is ``True``, ``False`` or ``None``.

    Examples
    --------
    >>> from moveability import analyze, load_spec
    >>> spec = load_spec("examples/five-bar-paper.toml")
    >>> row = summarize(analyze(spec, precision=0.1))
    >>> row["regions"], row["n_connected"], round(row["largest_share"], 3)
    (2, False, 0.908)
    """
    # one entry, keyed by the measure's name (area in the plane)
    ((inner, outer),) = result.workspace.values()
    regions = result.regions
    share = None
    if regions and outer > 0:
        share = max(float(region.area[0]) for region in regions) / float(outer)
    return {
        "regions": result.n_regions,
        "regions_at_least": result.count[0],
        "regions_at_most": result.count[1],
        "workspace_inner": float(inner),
        "workspace_outer": float(outer),
        "largest_share": share,
        "n_connected": result.n_connected,
    }


def _message(error: BaseException) -> str:
    text = " ".join(str(error).split())
    if isinstance(error, MoveabilityError) and text:
        return text
    return f"{type(error).__name__}: {text}" if text else type(error).__name__


def design_row(
    spec: Mapping[str, Any],
    names: Sequence[str],
    values: Sequence[float],
    precision: float,
    analyze: Callable[..., Any] | None = None,
    resolve: bool = True,
) -> Row:
    """Analyse one design and return its row; a failure is recorded, not raised.

    Parameters
    ----------
    spec : mapping
        The base spec (see :func:`moveability.mechanisms.registry.load_spec`).
    names, values : sequences
        The varied names and this design's values.
    precision : float
        Precision of the analysis.
    analyze : callable, optional
        The analysis; by default ``moveability.analyze``.
    resolve : bool, default True
        Refine, below the precision, the cells that keep the count open (see
        :func:`moveability.analyze`); False keeps the plain pass.

    Examples
    --------
    >>> from moveability import load_spec
    >>> spec = load_spec("examples/five-bar-paper.toml")
    >>> row = design_row(spec, ["L2"], [-1.0], 0.5)
    >>> row["error"]
    'invalid parameters.L2: expected a positive finite length, got -1.0'
    >>> design_row(spec, ["L2"], [5.0], 0.5)["error"] is None
    True
    """
    from .designs import apply_design

    if analyze is None:
        from ..analysis.result import analyze as analysis

        run: Callable[..., Any] = functools.partial(analysis, resolve=resolve)
    else:
        run = analyze
    start = time.perf_counter()
    row: Row = dict(zip(names, (float(v) for v in values), strict=True))
    try:
        row.update(summarize(run(apply_design(spec, names, values), precision=precision)))
        row["error"] = None
    except Exception as error:  # any failure of one design is that design's result
        row["error"] = _message(error)
    row["seconds"] = time.perf_counter() - start
    return row


def run_chunk(
    spec: Mapping[str, Any],
    names: Sequence[str],
    chunk: Sequence[Sequence[float]],
    precision: float,
    malloc_fix: bool = True,
    resolve: bool = True,
) -> list[Row]:
    """The rows of several designs, run one after the other (the task sent to a worker)."""
    if malloc_fix:
        restore_malloc_thresholds()
    return [design_row(spec, names, values, precision, resolve=resolve) for values in chunk]


# ----------------------------------------------------------------- many designs
def _chunks(designs: Sequence[Sequence[float]], size: int) -> list[list[Sequence[float]]]:
    return [list(designs[i : i + size]) for i in range(0, len(designs), size)]


def _error_rows(
    names: Sequence[str], chunk: Sequence[Sequence[float]], error: BaseException
) -> list[Row]:
    message = _message(error)
    return [
        {**dict(zip(names, map(float, values), strict=True)), "error": message} for values in chunk
    ]


def run_designs(
    spec: Mapping[str, Any],
    names: Sequence[str],
    designs: Sequence[Sequence[float]],
    precision: float,
    *,
    jobs: int = 1,
    scheduler: str | None = None,
    chunk_size: int | None = None,
    malloc_fix: bool = True,
    resolve: bool = True,
) -> Iterator[list[Row]]:
    """Analyse designs and yield their rows as they finish (in any order).

    Parameters
    ----------
    spec : mapping
        The base spec.
    names : sequence of str
        The varied names.
    designs : sequence of value tuples
        The designs to run.
    precision : float
        Precision of every analysis.
    jobs : int, default 1
        Worker processes (joblib's loky backend); 1 runs in this process.
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://HOST:PORT``); excludes ``jobs``.
    chunk_size : int, optional
        Designs per Dask task; by default the designs are cut in about four
        tasks per worker thread.
    malloc_fix : bool, default True
        Call :func:`restore_malloc_thresholds` in each process before its first
        design (turned off only to measure what it saves).
    resolve : bool, default True
        Refine where the counts are open (see :func:`design_row`).

    Yields
    ------
    list of dict
        The rows of one finished task: one design locally, a chunk on Dask.
        A Dask task lost with its worker yields error rows for its designs.

    Examples
    --------
    >>> from moveability import load_spec
    >>> spec = load_spec("examples/five-bar-paper.toml")
    >>> rows = [r for rows in run_designs(spec, ["L2"], [(5.0,), (0.0,)], 0.5) for r in rows]
    >>> [(r["L2"], r["error"] is None) for r in rows]
    [(5.0, True), (0.0, False)]
    """
    jobs = _check_jobs(jobs)
    if scheduler is not None and jobs != 1:
        raise InvalidParameterError(
            "--jobs", "1 with --scheduler (the cluster sets the workers)", jobs
        )
    if not designs:
        return
    if scheduler is not None:
        yield from _run_dask(
            spec, names, designs, precision, scheduler, chunk_size, malloc_fix, resolve
        )
    elif jobs == 1:
        for values in designs:
            yield run_chunk(spec, names, [values], precision, malloc_fix, resolve)
    else:
        require("joblib", "sweep", "parallel sweeps (jobs > 1)")
        from joblib import Parallel, delayed

        parallel = Parallel(n_jobs=jobs, backend="loky", return_as="generator_unordered")
        yield from parallel(
            delayed(run_chunk)(spec, names, [values], precision, malloc_fix, resolve)
            for values in designs
        )


def _check_jobs(jobs: object) -> int:
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise InvalidParameterError("--jobs", "a positive integer", jobs)
    return jobs


def _run_dask(
    spec: Mapping[str, Any],
    names: Sequence[str],
    designs: Sequence[Sequence[float]],
    precision: float,
    address: str,
    chunk_size: int | None,
    malloc_fix: bool,
    resolve: bool = True,
) -> Iterator[list[Row]]:
    require("distributed", "sweep", "sweeps on Dask")
    from distributed import Client, as_completed

    try:
        client = Client(address, timeout="20s", set_as_default=False)
    except (OSError, ValueError, TypeError) as error:
        raise InvalidParameterError(
            "--scheduler",
            f"the address of a running Dask scheduler, tcp://HOST:PORT ({_message(error)})",
            address,
        ) from None
    with client:
        if chunk_size is None:
            slots = max(1, sum(client.nthreads().values()))
            chunk_size = max(1, math.ceil(len(designs) / (4 * slots)))
        chunks = _chunks(designs, chunk_size)
        futures = {
            client.submit(
                run_chunk,
                dict(spec),
                list(names),
                chunk,
                precision,
                malloc_fix,
                resolve,
                pure=False,
            ): chunk
            for chunk in chunks
        }
        for future in as_completed(list(futures), loop=client.loop):
            try:
                rows = future.result()
            except Exception as error:  # a worker lost: its designs are recorded as failed
                rows = _error_rows(names, futures[future], error)
            future.release()
            yield rows


def local_cluster(n_workers: int = 2, malloc_trim: bool = False, **kwargs: Any) -> Any:
    """A Dask ``LocalCluster`` on loopback whose workers keep glibc's default allocator.

    Parameters
    ----------
    n_workers : int, default 2
        Worker processes, one thread each.
    malloc_trim : bool, default False
        Keep Dask's ``MALLOC_TRIM_THRESHOLD_`` in the workers' environment (only
        to measure what it costs).
    **kwargs
        Passed to ``distributed.LocalCluster``.
    """
    require("distributed", "sweep", "a Dask cluster")
    import dask
    from distributed import LocalCluster

    environ = dict(dask.config.get("distributed.nanny.pre-spawn-environ", {}))
    if not malloc_trim:
        environ.pop("MALLOC_TRIM_THRESHOLD_", None)
    options: dict[str, Any] = {
        "n_workers": n_workers,
        "threads_per_worker": 1,
        "processes": True,
        "host": "127.0.0.1",
        "dashboard_address": ":0",  # any free port: never "port 8787 in use" warnings
    }
    options.update(kwargs)
    with dask.config.set({"distributed.nanny.pre-spawn-environ": environ}):
        return LocalCluster(**options)


# ----------------------------------------------------------------- a sweep
def run_sweep(
    spec: Mapping[str, Any],
    vary: Sequence[str | Vary],
    out: str | os.PathLike[str],
    precision: float = 0.1,
    *,
    jobs: int = 1,
    scheduler: str | None = None,
    retry_errors: bool = False,
    progress: Callable[[int, int], object] | None = None,
    malloc_fix: bool = True,
    resolve: bool = True,
) -> dict[str, int]:
    """Analyse the product of the ranges and write one row per design to ``out``.

    Designs already in ``out`` are skipped (failed ones too, unless
    ``retry_errors``); each row is on disk as soon as its design finishes (see
    :mod:`moveability.sweep.table`).

    Parameters
    ----------
    spec : mapping
        A spec as returned by :func:`moveability.mechanisms.registry.load_spec`.
    vary : sequence of str or Vary
        ``NAME=START:STOP:COUNT`` texts (see :func:`~moveability.sweep.parse_vary`).
    out : str or os.PathLike
        The table: ``.csv``, ``.parquet`` or ``.pq``.
    precision : float, default 0.1
        Precision of every analysis.
    jobs, scheduler
        Where the designs run (see :func:`run_designs`).
    retry_errors : bool, default False
        Compute again the designs whose row records an error.
    progress : callable, optional
        Called as ``progress(done, total)`` at the start and after each result.
    malloc_fix : bool, default True
        See :func:`run_designs`.
    resolve : bool, default True
        Refine, below the precision, where a design's count is open (see
        :func:`moveability.analyze`); False keeps the plain pass.

    Returns
    -------
    dict
        ``designs`` (all of the sweep), ``skipped`` (already in ``out``),
        ``computed`` (in this run) and ``failed`` (rows with an error in ``out``).

    Raises
    ------
    moveability.errors.InvalidParameterError
        Before any design runs: a bad ``--vary``, ``--jobs``, ``--scheduler`` or
        ``--out`` (an existing table of other columns).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from moveability import load_spec
    >>> spec = load_spec("examples/five-bar-paper.toml")
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     out = pathlib.Path(tmp, "sweep.csv")
    ...     first = run_sweep(spec, ["L2=4:6:3"], out, precision=0.5)
    ...     again = run_sweep(spec, ["L2=4:6:3"], out, precision=0.5)
    >>> first["computed"], again["computed"], again["skipped"]
    (3, 0, 3)
    """
    varies = [v if isinstance(v, Vary) else parse_vary(v, spec) for v in vary]
    if not varies:
        raise InvalidParameterError("--vary", "at least one NAME=START:STOP:COUNT", [])
    check_varies(varies)
    _check_jobs(jobs)
    if scheduler is not None and jobs != 1:
        raise InvalidParameterError(
            "--jobs", "1 with --scheduler (the cluster sets the workers)", jobs
        )
    names = [v.name for v in varies]
    grid = design_grid(varies)
    computed = 0
    with SweepTable(out, names, retry_errors=retry_errors) as table:
        todo = [values for values in dict.fromkeys(grid) if not table.is_done(values)]
        total = len(dict.fromkeys(grid))
        done = total - len(todo)
        if progress is not None:
            progress(done, total)
        for rows in run_designs(
            spec,
            names,
            todo,
            precision,
            jobs=jobs,
            scheduler=scheduler,
            malloc_fix=malloc_fix,
            resolve=resolve,
        ):
            table.extend(rows)
            computed += len(rows)
            if progress is not None:
                progress(done + computed, total)
        failed = sum(1 for values in dict.fromkeys(grid) if table.rows[_key(values)].get("error"))
    return {"designs": total, "skipped": total - len(todo), "computed": computed, "failed": failed}


def _key(values: Sequence[float]) -> tuple[float, ...]:
    return tuple(float(v) for v in values)
