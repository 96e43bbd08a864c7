"""Design studies: analyse many variants of a spec and tabulate what each one gives.

A sweep varies parameters (``L1``) and limit ends (``theta1.min``) over ranges
(:mod:`.designs`), analyses every design of their product in this process, on
local worker processes or on a Dask cluster (:mod:`.runner`), writes one row
per design as it finishes and resumes from what the table already holds
(:mod:`.table`), and maps the result over two varied names (:mod:`.figure`).

Examples
--------
>>> import pathlib, tempfile
>>> from moveability import load_spec
>>> from moveability.sweep import read_table, run_sweep
>>> spec = load_spec("examples/five-bar-paper.toml")
>>> with tempfile.TemporaryDirectory() as tmp:
...     out = pathlib.Path(tmp, "sweep.csv")
...     summary = run_sweep(spec, ["L2=4.5:5.5:2", "theta1.max=pi/2:pi:2"], out, precision=0.5)
...     columns, rows = read_table(out)
>>> summary
{'designs': 4, 'skipped': 0, 'computed': 4, 'failed': 0}
>>> columns[:3]
['L2', 'theta1.max', 'regions']
"""

from .designs import Vary, apply_design, check_varies, design_grid, parse_vary
from .figure import plot_sweep_map
from .progress import SweepProgress
from .runner import (
    design_row,
    local_cluster,
    restore_malloc_thresholds,
    run_designs,
    run_sweep,
    summarize,
)
from .table import RESULT_COLUMNS, SweepTable, read_table, table_columns

__all__ = [
    "RESULT_COLUMNS",
    "SweepProgress",
    "SweepTable",
    "Vary",
    "apply_design",
    "check_varies",
    "design_grid",
    "design_row",
    "local_cluster",
    "parse_vary",
    "plot_sweep_map",
    "read_table",
    "restore_malloc_thresholds",
    "run_designs",
    "run_sweep",
    "summarize",
    "table_columns",
]
