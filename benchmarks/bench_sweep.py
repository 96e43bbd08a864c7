"""Benchmark of design sweeps: one process, joblib workers, a Dask LocalCluster.

Sweeps the paper's five-bar over L2 and theta1.max (8 x 8 = 64 designs by
default) at precision 0.1 and prints, per way of running it: wall seconds,
designs per second, and the sum of the designs' own ``seconds`` (time spent in
the analyses, wherever they ran). The Dask cases compare workers started
without ``MALLOC_TRIM_THRESHOLD_`` (what :func:`moveability.sweep.local_cluster`
does), workers started with Dask's default ``MALLOC_TRIM_THRESHOLD_=65536``
with and without :func:`~moveability.sweep.restore_malloc_thresholds` (what
happens on an existing cluster). Every pool runs a small warm-up sweep first
(worker start and compiled-kernel loading are not timed).

Run: ``python benchmarks/bench_sweep.py [--count 8] [--precision 0.1]``.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path
from typing import Any

from moveability import load_spec
from moveability.sweep import local_cluster, read_table, run_sweep

SPEC = Path(__file__).resolve().parent.parent / "examples" / "five-bar-paper.toml"


def timed_sweep(
    spec: dict[str, Any], vary: list[str], eps: float, **how: Any
) -> tuple[float, float, int]:
    """Wall seconds, summed design seconds and failures of one fresh sweep."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "designs.csv")
        warm = os.path.join(tmp, "warm-up.csv")
        run_sweep(spec, ["L2=4.5:5.5:4"], warm, eps, **how)
        start = time.perf_counter()
        summary = run_sweep(spec, vary, out, eps, **how)
        wall = time.perf_counter() - start
        busy = sum(row["seconds"] for row in read_table(out)[1])
    return wall, busy, summary["failed"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--count", type=int, default=8, help="values per varied name")
    parser.add_argument("--precision", type=float, default=0.1)
    args = parser.parse_args()
    spec = load_spec(SPEC)
    n = args.count
    vary = [f"L2=4:6:{n}", f"theta1.max=pi/2:pi:{n}"]
    print(
        f"five-bar sweep: {n * n} designs ({' x '.join(vary)}), precision {args.precision}, "
        f"{os.cpu_count()} cores"
    )
    header = f"{'how':<52} {'seconds':>8} {'designs/s':>9} {'design s':>9} {'failed':>6}"
    print(header)
    print("-" * len(header))

    def show(name: str, wall: float, busy: float, failed: int) -> None:
        print(f"{name:<52} {wall:>8.2f} {n * n / wall:>9.2f} {busy:>9.2f} {failed:>6}")

    show("1 process", *timed_sweep(spec, vary, args.precision))
    show("joblib, 2 workers", *timed_sweep(spec, vary, args.precision, jobs=2))
    cases = [
        ("LocalCluster, 2 workers (no MALLOC_TRIM_THRESHOLD_)", False, True),
        ("LocalCluster, 2 workers, MALLOC_TRIM_THRESHOLD_ + fix", True, True),
        ("LocalCluster, 2 workers, MALLOC_TRIM_THRESHOLD_, no fix", True, False),
    ]
    for name, trim, fix in cases:
        with local_cluster(n_workers=2, malloc_trim=trim) as cluster:
            result = timed_sweep(
                spec, vary, args.precision, scheduler=cluster.scheduler_address, malloc_fix=fix
            )
        show(name, *result)
    print("design s: the designs' own seconds, summed (time inside the analyses)")


if __name__ == "__main__":
    main()
