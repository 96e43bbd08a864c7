"""Benchmark of the certified five-bar analysis at several precisions.

Prints, per case and precision: wall time of :func:`moveability.analyze` (best of
``--repeat`` runs), peak traced memory (numpy and Python allocations, from
tracemalloc in a separate run), the process' peak resident memory, the number
of leaves and of undecided (BOUNDARY) leaves, and the regions found.
Run: ``python benchmarks/bench_analysis.py [--quick]``.
"""

from __future__ import annotations

import argparse
import resource
import time
import tracemalloc
from pathlib import Path

from moveability import analyze, load_spec

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
CASES = [("[0, pi]", "five-bar-paper.toml"), ("[-pi, pi]", "five-bar-full-turn.toml")]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="coarse precisions only")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    precisions = [0.5, 0.1] if args.quick else [0.5, 0.1, 0.035, 0.01]
    analyze(load_spec(EXAMPLES / CASES[0][1]), precision=0.5)  # load compiled kernels
    print("five-bar L = 7, 8, 5, 8, 5 (the paper's), certified analysis")
    header = (
        f"{'limits':<10} {'eps':>6} {'seconds':>8} {'traced MiB':>10} {'leaves':>8} "
        f"{'undecided':>9} {'regions':>7}  W area bounds"
    )
    print(header)
    print("-" * len(header))
    for name, spec_file in CASES:
        spec = load_spec(EXAMPLES / spec_file)
        for eps in precisions:
            best = float("inf")
            for _ in range(args.repeat):
                start = time.perf_counter()
                result = analyze(spec, precision=eps)
                best = min(best, time.perf_counter() - start)
            tracemalloc.start()
            analyze(spec, precision=eps)
            _, peak = tracemalloc.get_traced_memory()
            tracemalloc.stop()
            counts = result.tree.counts()
            w = result.workspace["area"]
            print(
                f"{name:<10} {eps:>6g} {best:>8.3f} {peak / 2**20:>10.1f} {len(result.tree):>8} "
                f"{counts['BOUNDARY']:>9} {len(result.regions):>7}  [{w[0]:.3f}, {w[1]:.3f}]"
            )
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"process peak resident memory: {rss:.0f} MiB")


if __name__ == "__main__":
    main()
