"""Benchmark of the analysis of the mechanisms beyond the five-bar.

The 3-RPR of examples/three-rpr.toml at precisions of 1/32 .. 1/256 of the span
of each pose axis (x, y and phi), and the biglide of examples/biglide.toml.
Each case runs in a fresh process, so that the peak resident memory printed is
the case's own. Prints wall time (tree, then the whole analysis), peak resident
memory, leaves, undecided leaves, regions and the volume bounds of W.
Run: ``python benchmarks/bench_mechanisms.py [--quick]``.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def run_case(spec_file: str, divisions: int, precision: float) -> dict[str, object]:
    """One analysis, in this process: figures as a dict."""
    from moveability import analyze, load_spec
    from moveability.mechanisms import from_spec

    mechanism = from_spec(load_spec(EXAMPLES / spec_file))
    lo, hi = mechanism.bounds
    eps = tuple(float(v) for v in (hi - lo) / divisions) if divisions else precision
    built: list[float] = []
    start = time.perf_counter()

    def progress(level: int, n_split: int, n_leaves: int) -> None:
        built.append(time.perf_counter() - start)

    result = analyze(mechanism, precision=eps, progress=progress)
    seconds = time.perf_counter() - start
    measure = result.measure_name
    return {
        "seconds": seconds,
        "tree_seconds": built[-1] if built else seconds,
        "rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "leaves": len(result.tree),
        "undecided": result.tree.counts()["BOUNDARY"],
        "regions": len(result.regions),
        "unresolved": result.undecided["components"],
        "workspace": result.workspace[measure],
        "measure": measure,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="coarse precisions only")
    parser.add_argument("--case", nargs=3, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.case:
        spec_file, divisions, precision = args.case
        print(json.dumps(run_case(spec_file, int(divisions), float(precision))))
        return
    cases = [("three-rpr.toml", d, 0.0) for d in ((32, 64) if args.quick else (32, 64, 128, 256))]
    cases += [("biglide.toml", 0, eps) for eps in ((0.1,) if args.quick else (0.1, 0.02, 0.005))]
    header = (
        f"{'mechanism':<16} {'precision':>14} {'seconds':>8} {'tree s':>7} {'peak MiB':>8} "
        f"{'leaves':>9} {'undecided':>9} {'regions':>7} {'unres.':>6}  W bounds"
    )
    print(header)
    print("-" * len(header))
    for spec_file, divisions, precision in cases:
        out = subprocess.run(
            [sys.executable, __file__, "--case", spec_file, str(divisions), str(precision)],
            check=True,
            capture_output=True,
            text=True,
        )
        r = json.loads(out.stdout)
        shown = f"span/{divisions}" if divisions else f"{precision:g}"
        w = r["workspace"]
        print(
            f"{spec_file:<16} {shown:>14} {r['seconds']:>8.2f} {r['tree_seconds']:>7.2f} "
            f"{r['rss_mib']:>8.0f} {r['leaves']:>9} {r['undecided']:>9} {r['regions']:>7} "
            f"{r['unresolved']:>6}  {r['measure']} [{w[0]:.2f}, {w[1]:.2f}]"
        )


if __name__ == "__main__":
    main()
