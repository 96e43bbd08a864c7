"""Benchmark of design sweeps: one process, joblib workers, a Dask LocalCluster.

Sweeps the paper's five-bar over L2 and theta1.max (8 x 8 = 64 designs by
default) at precision 0.1 and prints, per way of running it: wall seconds,
designs per second, and the sum of the designs' own ``seconds`` (time spent in
the analyses, wherever they ran). The Dask cases compare workers started
without ``MALLOC_TRIM_THRESHOLD_`` (what :func:`moveability.sweep.local_cluster`
does), workers started with Dask's default ``MALLOC_TRIM_THRESHOLD_=65536``
with and without :func:`~moveability.sweep.restore_malloc_thresholds` (what
happens on an existing cluster). All pools are started first and run a small
warm-up sweep (worker start and compiled-kernel loading are not timed); then
each round runs every case once, so that a change in the machine's speed
during the benchmark weighs on every case alike. Last, a paired measurement of
single analyses on one-worker clusters gives what the variable costs per
design, which other load on the machine blurs less than whole sweeps.

Run: ``python benchmarks/bench_sweep.py [--count 8] [--precision 0.1] [--repeat 3]``.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

from moveability import load_spec
from moveability.sweep import local_cluster, read_table, run_sweep
from moveability.sweep.runner import run_chunk

SPEC = Path(__file__).resolve().parent.parent / "examples" / "five-bar-paper.toml"


def timed_sweep(
    spec: dict[str, Any], vary: list[str], eps: float, **how: Any
) -> tuple[float, float, int]:
    """Wall seconds, summed design seconds and failures of one fresh sweep."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "designs.csv")
        start = time.perf_counter()
        summary = run_sweep(spec, vary, out, eps, **how)
        wall = time.perf_counter() - start
        busy = sum(row["seconds"] for row in read_table(out)[1])
    return wall, busy, summary["failed"]


def per_design(spec: dict[str, Any], eps: float, rounds: int = 6) -> dict[str, list[float]]:
    """Seconds of one analysis on a one-worker LocalCluster, per allocator setting.

    The three clusters run in turn, one task of 5 analyses each per round: a
    paired comparison that other load on the machine weighs on alike.
    """
    from distributed import Client

    settings = {
        "no MALLOC_TRIM_THRESHOLD_": (False, True),
        "MALLOC_TRIM_THRESHOLD_, fix": (True, True),
        "MALLOC_TRIM_THRESHOLD_, no fix": (True, False),
    }
    seconds: dict[str, list[float]] = {name: [] for name in settings}
    chunk = [(spec["parameters"]["L2"],)] * 5
    with contextlib.ExitStack() as stack:
        clients = {}
        for name, (trim, _) in settings.items():
            cluster = stack.enter_context(local_cluster(n_workers=1, malloc_trim=trim))
            clients[name] = stack.enter_context(Client(cluster, set_as_default=False))
        for i in range(rounds + 1):
            for name, (_, fix) in settings.items():
                task = clients[name].submit(run_chunk, spec, ["L2"], chunk, eps, fix, pure=False)
                if i:  # the first round is a warm-up
                    seconds[name].extend(row["seconds"] for row in task.result())
                else:
                    task.result()
    return seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--count", type=int, default=8, help="values per varied name")
    parser.add_argument("--precision", type=float, default=0.1)
    parser.add_argument("--repeat", type=int, default=3, help="rounds (each runs every case)")
    args = parser.parse_args()
    spec = load_spec(SPEC)
    n, eps = args.count, args.precision
    vary = [f"L2=4:6:{n}", f"theta1.max=pi/2:pi:{n}"]
    print(
        f"five-bar sweep: {n * n} designs ({' x '.join(vary)}), precision {eps}, "
        f"{os.cpu_count()} cores; {args.repeat} rounds, each running every case once"
    )
    with contextlib.ExitStack() as stack:
        cases: list[tuple[str, dict[str, Any]]] = [
            ("1 process", {}),
            ("joblib, 2 workers", {"jobs": 2}),
        ]
        for name, trim, fix in [
            ("LocalCluster 2 workers, no MALLOC_TRIM_THRESHOLD_", False, True),
            ("LocalCluster 2 workers, MALLOC_TRIM_THRESHOLD_, fix", True, True),
            ("LocalCluster 2 workers, MALLOC_TRIM_THRESHOLD_, no fix", True, False),
        ]:
            cluster = stack.enter_context(local_cluster(n_workers=2, malloc_trim=trim))
            cases.append((name, {"scheduler": cluster.scheduler_address, "malloc_fix": fix}))
        # warm-up: workers started, compiled kernels loaded, allocator settings applied
        for _, how in cases:
            timed_sweep(spec, ["L2=4.5:5.5:4"], eps, **how)
        results: dict[str, list[tuple[float, float, int]]] = {name: [] for name, _ in cases}
        load_start = os.getloadavg()
        for _ in range(args.repeat):
            for name, how in cases:
                results[name].append(timed_sweep(spec, vary, eps, **how))
        load_end = os.getloadavg()

    header = (
        f"{'how':<54} {'best s':>7} {'median s':>8} {'designs/s':>9} {'design s':>8} {'failed':>6}"
    )
    print(header)
    print("-" * len(header))
    for name, runs in results.items():
        walls = [run[0] for run in runs]
        median = statistics.median(walls)
        busy = statistics.median(run[1] for run in runs)
        failed = max(run[2] for run in runs)
        print(
            f"{name:<54} {min(walls):>7.2f} {median:>8.2f} {n * n / median:>9.2f} "
            f"{busy:>8.2f} {failed:>6}"
        )
    print("designs/s: from the median; design s: the designs' own seconds, summed (median)")
    print(
        f"load average (1 min) before and after the rounds: {load_start[0]:.1f}, {load_end[0]:.1f}"
    )

    print(f"\none analysis of the paper's five-bar at {eps} on a one-worker LocalCluster")
    per = per_design(spec, eps)
    base = min(per["no MALLOC_TRIM_THRESHOLD_"])
    for name, values in per.items():
        best, median = min(values), statistics.median(values)
        print(f"  {name:<32} best {best:.3f} s ({best / base:.2f} x), median {median:.3f} s")


if __name__ == "__main__":
    main()
