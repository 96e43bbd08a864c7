"""Certified counts of regions: how often they are decided, and at what cost.

Prints, for random five-bars (seeded) at one precision, the time per design
with and without the resolution below the precision, and the share of designs
whose count and N-connectivity are decided; then the time to the certified
count of the issue's gap five-bar with a larger resolution budget.

Run: ``.venv/bin/python benchmarks/bench_counts.py [N_DESIGNS] [PRECISION]``
"""

from __future__ import annotations

import statistics
import sys
import time

import numpy as np

from moveability import analyze
from moveability.limits import JointLimit
from moveability.mechanisms import FiveBar


def random_five_bars(n: int, seed: int = 11) -> list[FiveBar]:
    rng = np.random.default_rng(seed)
    out: list[FiveBar] = []
    while len(out) < n:
        lengths = np.round(rng.uniform(2.0, 8.0, 5), 1)
        limits = []
        for _ in range(2):
            if rng.random() < 0.25:
                limits.append(JointLimit.unlimited())
            else:
                lo = float(np.round(rng.uniform(-np.pi, np.pi), 2))
                width = float(np.round(rng.uniform(1.0, 2 * np.pi - 0.01), 2))
                limits.append(JointLimit(lo, lo + width))
        try:
            out.append(FiveBar(*lengths, limits=(limits[0], limits[1])))
        except ValueError:
            continue
    return out


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 20
    eps = float(sys.argv[2]) if len(sys.argv) > 2 else 0.05
    designs = random_five_bars(n)
    analyze(designs[0], precision=0.5)  # compile the kernels first
    rows = {False: [], True: []}
    for m in designs:
        for resolve in (False, True):
            start = time.perf_counter()
            result = analyze(m, precision=eps, resolve=resolve)
            seconds = time.perf_counter() - start
            rows[resolve].append(
                (seconds, result.n_regions is not None, result.n_connected is not None)
            )
    print(f"{n} random five-bars at precision {eps}")
    print(f"{'':>12} {'median s':>9} {'max s':>7} {'count decided':>14} {'N-conn. decided':>16}")
    for resolve in (False, True):
        data = rows[resolve]
        times = [r[0] for r in data]
        counts = sum(r[1] for r in data) / len(data)
        nconn = sum(r[2] for r in data) / len(data)
        label = "resolved" if resolve else "plain pass"
        print(
            f"{label:>12} {statistics.median(times):9.2f} {max(times):7.2f} "
            f"{counts:14.0%} {nconn:16.0%}"
        )
    gap = FiveBar(
        6, 5, 6, 5, 6,
        limits=(
            JointLimit(1.3704384060045658, np.pi),
            JointLimit(-2.171858256624643, 1.9887034049203582),
        ),
    )
    for growth in (2.0, 12.0):
        start = time.perf_counter()
        result = analyze(gap, precision=0.05, resolve=True, resolve_growth=growth)
        print(
            f"gap five-bar at 0.05, resolve_growth={growth:g}: count {result.count} "
            f"in {time.perf_counter() - start:.1f} s, {len(result.tree)} leaves"
        )


if __name__ == "__main__":
    main()
